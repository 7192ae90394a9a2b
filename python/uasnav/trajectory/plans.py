"""Plan files: CSV with header ``lat,lon,alt`` (WGS-84 deg, m) or ``north,east`` (local m)."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from uasnav.errors import DataFormatError, InputError
from uasnav.limits import read_file_limited
from uasnav.trajectory.geometry import geodetic_to_local

#: Largest plan file read (bytes): a plan of 100 000 waypoints is about 4 MB.
MAX_PLAN_BYTES = 16 * 2**20


def read_plan(path: str | Path) -> tuple[np.ndarray, tuple[float, float, float] | None]:
    """Read a plan CSV. Returns (waypoints north/east m, geodetic origin or None).

    At most :data:`MAX_PLAN_BYTES` are read (whatever size the file reports); a UTF-8 byte-order
    mark is accepted. Raises :class:`DataFormatError` naming the line for malformed content.
    """
    p = Path(path)
    if not p.exists():
        raise InputError(f"no such plan file: {p}")
    if p.is_dir():
        raise InputError(f"{p}: is a directory, not a plan file")
    raw = read_file_limited(p, MAX_PLAN_BYTES)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        raise DataFormatError("not UTF-8 text", path=str(p), line=line) from None
    reader = csv.reader(io.StringIO(text, newline=""))
    try:
        rows = [r for r in reader if r and not r[0].lstrip().startswith("#")]
    except csv.Error as exc:
        raise DataFormatError(f"malformed CSV ({exc})", path=str(p), line=reader.line_num) from None
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


__all__ = ["MAX_PLAN_BYTES", "read_plan"]
