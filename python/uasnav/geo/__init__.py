"""Geodesy and datums: WGS-84, coordinate frames and heights with their datum."""
