"""Plan files: CSV with header ``lat,lon,alt`` (WGS-84 deg, m) or ``north,east`` (local m)."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from uasnav.errors import DataFormatError, InputError
from uasnav.trajectory.geometry import geodetic_to_local


def read_plan(path: str | Path) -> tuple[np.ndarray, tuple[float, float, float] | None]:
    """Read a plan CSV. Returns (waypoints north/east m, geodetic origin or None)."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"no such plan file: {p}")
    with open(p, newline="") as fh:
        rows = [r for r in csv.reader(fh) if r and not r[0].lstrip().startswith("#")]
    if not rows:
        raise DataFormatError("empty plan", path=str(p))
    head = [h.strip().lower() for h in rows[0]]
    if {"lat", "lon"} <= set(head):
        cols = ["lat", "lon", "alt"] if "alt" in head else ["lat", "lon"]
    elif {"north", "east"} <= set(head):
        cols = ["north", "east"]
    else:
        raise DataFormatError("header must name lat,lon[,alt] or north,east", path=str(p), line=1)
    idx = [head.index(c) for c in cols]
    vals = np.empty((len(rows) - 1, len(cols)))
    for i, r in enumerate(rows[1:]):
        for j, k in enumerate(idx):
            try:
                vals[i, j] = float(r[k])
            except (ValueError, IndexError):
                raise DataFormatError("not a number", path=str(p), line=i + 2, column=cols[j]) from None
    if not np.isfinite(vals).all():
        i, j = np.argwhere(~np.isfinite(vals))[0]
        raise DataFormatError("NaN coordinate", path=str(p), line=int(i) + 2, column=cols[j])
    if cols[0] == "north":
        return vals, None
    alt = vals[:, 2] if vals.shape[1] == 3 else np.zeros(vals.shape[0])
    if vals.shape[0] == 0:
        raise DataFormatError("plan has no waypoints", path=str(p))
    origin = (float(vals[0, 0]), float(vals[0, 1]), float(alt[0]))
    return geodetic_to_local(vals[:, 0], vals[:, 1], alt, origin=origin)[:, :2], origin


__all__ = ["read_plan"]
