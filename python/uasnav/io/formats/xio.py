"""x-io Technologies CSV (x-IMU / Fusion example data).

Header ``Time (s), Gyroscope X (deg/s), Gyroscope Y (deg/s), Gyroscope Z (deg/s),
Accelerometer X (g), …, Magnetometer X (uT), …``; converted to rad/s, m/s² and µT. The axes
are kept as the sensor defines them (x-IMU: z up, so a level unit reads +1 g on z; uasnav's
simulator uses FRD with −g on z) and ``meta["frame"] = "sensor (z up)"`` says so.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import ClassVar

import numpy as np

from uasnav.errors import DataFormatError
from uasnav.imu import ImuLog
from uasnav.io._csvstream import read_table
from uasnav.io.formats.base import ImuFileFormat
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
    """Read an x-io CSV (see module docs), in chunks by the CSV engine
    (:mod:`uasnav.io._csvstream`).

    Raises
    ------
    DataFormatError
        Missing file or column, a non-numeric, missing or non-finite cell, non-increasing time,
        malformed CSV or text that is not UTF-8 (names the file, line and column).
    ResourceLimitError
        If the log would need more memory than the limit (``UASNAV_MAX_MEMORY``).
    """
    p = Path(path)
    source = str(p)

    def select(header: list[str], header_line: int) -> list[str]:
        missing = [c for c in _COLS if c not in header]
        if missing:
            raise DataFormatError(
                f"missing column(s) {missing}", path=source, line=header_line, column=missing[0]
            )
        return list(_COLS) + [c for c in _MAG if c in header]

    table = read_table(p, select, what="x-io CSV", empty="empty file", min_rows=2)
    data = np.column_stack(list(table.columns.values()))
    t = data[:, 0]
    d = np.diff(t)
    if np.any(d <= 0):
        i = int(np.flatnonzero(d <= 0)[0]) + 1
        raise DataFormatError(
            f"time stamp not increasing ({float(t[i - 1])!r} then {float(t[i])!r})",
            path=source,
            line=table.row_line(i),
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


class XioFormat(ImuFileFormat):
    """x-io Technologies CSV (:func:`read_xio_csv`)."""

    name = "xio-csv"
    SOURCES: ClassVar[dict[str, tuple[str, ...]]] = {"imus": (), "imu": (), "identity": ()}

    def read_imu(self) -> ImuLog:
        return read_xio_csv(self.path)


__all__ = ["XioFormat", "is_xio_csv", "read_xio_csv"]
