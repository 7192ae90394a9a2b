"""Report sections; one module per capability, each defining ``SECTION``."""
