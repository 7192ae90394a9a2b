"""Reading and writing IMU logs. :func:`read_log` picks the reader from the file extension.

========== ================================ ===========================================
extension  reader                           notes
========== ================================ ===========================================
.csv .txt  :func:`read_csv_v1` / x-io CSV   x-io layout recognised by its header
.npz       :func:`read_npz`                 uasnav layout or the ADIS reference layout
.ulg       :func:`read_ulog`                PX4, primary IMU (sensor_combined)
.bin       :func:`read_dataflash`           ArduPilot; ``read_log`` returns the first IMU
.tlog      :func:`read_tlog`                MAVLink; ``read_log`` returns the first stream
========== ================================ ===========================================

Writers (:func:`write_log` by extension: ``.csv`` → CSV v1, ``.npz``) are atomic.
"""

from __future__ import annotations

import os
from pathlib import Path

from uasnav.errors import DataFormatError, InputError
from uasnav.imu import ImuLog
from uasnav.io.ardupilot import read_dataflash, read_tlog
from uasnav.io.csv_v1 import read_csv_v1, write_csv_v1
from uasnav.io.npz import read_npz, write_npz
from uasnav.io.px4 import read_ulog
from uasnav.io.xio import is_xio_csv, read_xio_csv

READ_EXTENSIONS = (".csv", ".txt", ".npz", ".ulg", ".bin", ".tlog")
WRITE_EXTENSIONS = (".csv", ".npz")


def read_log(path: str | os.PathLike[str]) -> ImuLog:
    """Read an IMU log; the format follows the extension (see the module table)."""
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix in (".csv", ".txt"):
        try:
            with open(p, encoding="utf-8-sig") as fh:
                first = fh.readline()
        except FileNotFoundError:
            raise DataFormatError("no such file", path=str(p)) from None
        except UnicodeDecodeError:
            return read_csv_v1(p)  # reports the decoding error with its position
        return read_xio_csv(p) if is_xio_csv(first) else read_csv_v1(p)
    if suffix == ".npz":
        return read_npz(p)
    if suffix == ".ulg":
        return read_ulog(p)
    if suffix == ".bin":
        logs = read_dataflash(p)
        return logs[sorted(logs)[0]]
    if suffix == ".tlog":
        logs = read_tlog(p)
        return logs[sorted(logs)[0]]
    raise InputError(f"{p}: unknown log format {suffix!r} (supported: {', '.join(READ_EXTENSIONS)})")


def write_log(log: ImuLog, path: str | os.PathLike[str]) -> None:
    """Write ``log`` atomically; ``.csv`` → CSV v1 (with truth columns), ``.npz``."""
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == ".csv":
        write_csv_v1(log, p)
    elif suffix == ".npz":
        write_npz(log, p)
    else:
        raise InputError(f"{p}: cannot write format {suffix!r} (supported: {', '.join(WRITE_EXTENSIONS)})")


__all__ = [
    "READ_EXTENSIONS",
    "WRITE_EXTENSIONS",
    "read_csv_v1",
    "read_dataflash",
    "read_log",
    "read_npz",
    "read_tlog",
    "read_ulog",
    "read_xio_csv",
    "write_csv_v1",
    "write_log",
    "write_npz",
]
