"""x-io Technologies CSV (x-IMU / Fusion example data).

Header ``Time (s), Gyroscope X (deg/s), Gyroscope Y (deg/s), Gyroscope Z (deg/s),
Accelerometer X (g), …, Magnetometer X (uT), …``; converted to rad/s, m/s² and µT. The axes
are kept as the sensor defines them (x-IMU: z up, so a level unit reads +1 g on z; uasnav's
simulator uses FRD with −g on z) and ``meta["frame"] = "sensor (z up)"`` says so.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from uasnav.errors import DataFormatError
from uasnav.imu import ImuLog
from uasnav.io._text import csv_rows, numeric_rows, read_text, split_lines
from uasnav.units import convert

HEADER_PREFIX = "Time (s)"
_COLS = {
    "Time (s)": ("t", 1.0),
    "Gyroscope X (deg/s)": ("g0", "deg/s"),
    "Gyroscope Y (deg/s)": ("g1", "deg/s"),
    "Gyroscope Z (deg/s)": ("g2", "deg/s"),
    "Accelerometer X (g)": ("a0", "g"),
    "Accelerometer Y (g)": ("a1", "g"),
    "Accelerometer Z (g)": ("a2", "g"),
}
_MAG = ("Magnetometer X (uT)", "Magnetometer Y (uT)", "Magnetometer Z (uT)")


def is_xio_csv(first_line: str) -> bool:
    """True if a CSV header line is the x-io layout."""
    return first_line.lstrip("\ufeff").startswith(HEADER_PREFIX)


def read_xio_csv(path: str | os.PathLike[str]) -> ImuLog:
    """Read an x-io CSV (see module docs).

    Raises
    ------
    DataFormatError
        Missing file or column, a non-numeric, missing or non-finite cell, non-increasing time,
        malformed CSV or text that is not UTF-8 (names the file, line and column).
    """
    p = Path(path)
    source = str(p)
    lines = split_lines(read_text(p))
    first = next(csv_rows(lines, 0, source), None)
    if first is None:
        raise DataFormatError("empty file", path=source)
    header_line, cells = first
    header = [h.strip() for h in cells]
    missing = [c for c in _COLS if c not in header]
    if missing:
        raise DataFormatError(
            f"missing column(s) {missing}", path=source, line=header_line, column=missing[0]
        )
    want = list(_COLS) + [c for c in _MAG if c in header]
    data, row_lines = numeric_rows(lines, header_line, source, header, want)
    t = data[:, 0]
    d = np.diff(t)
    if np.any(d <= 0):
        i = int(np.flatnonzero(d <= 0)[0]) + 1
        raise DataFormatError(
            f"time stamp not increasing ({float(t[i - 1])!r} then {float(t[i])!r})",
            path=source,
            line=row_lines[i],
            column="Time (s)",
        )
    mag = data[:, 7:10] if data.shape[1] >= 10 else None
    return ImuLog(
        t=t,
        gyro=np.asarray(convert(data[:, 1:4], "deg/s", "rad/s")),
        accel=np.asarray(convert(data[:, 4:7], "g", "m/s^2")),
        mag=mag,
        meta={"source": str(p), "format": "xio-csv", "frame": "sensor (z up)"},
    )


__all__ = ["is_xio_csv", "read_xio_csv"]
