"""The mission planner's local web application (``uasnav serve``).

Mission selection (thesis §5.2, Figures 69–70 and 75–76) and trajectory prediction (§5.1) as
pages and as a JSON API on the same functions; see :mod:`uasnav.web.app`.
"""

from uasnav.web.app import Documents, create_app, load_documents

__all__ = ["Documents", "create_app", "load_documents"]
