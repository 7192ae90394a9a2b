"""Trajectory prediction for small UAS with LVQ networks (thesis §5.1)."""
