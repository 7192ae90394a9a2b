"""Mission selector (thesis §5.2)."""
