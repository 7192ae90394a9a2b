"""Reading and writing IMU logs. :func:`read_log` picks the reader from the file extension."""

from __future__ import annotations

import os
from pathlib import Path

from uasnav.errors import InputError
from uasnav.imu import ImuLog
from uasnav.io.csv_v1 import read_csv_v1, write_csv_v1


def read_log(path: str | os.PathLike[str]) -> ImuLog:
    """Read an IMU log; the format follows the extension (``.csv`` → CSV v1)."""
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix in (".csv", ".txt"):
        return read_csv_v1(p)
    raise InputError(f"{p}: unknown log format {suffix!r} (supported: .csv)")


__all__ = ["read_csv_v1", "read_log", "write_csv_v1"]
