"""Every file format of uasnav: IMU logs, flight telemetry and numeric tables.

Any log → :func:`open_log` (:mod:`uasnav.io.logfile`): one :class:`LogFile` whose typed views
(IMUs, GNSS, barometer, magnetometer, the autopilot's estimate, plan, parameters, limits, modes,
identity) are decoded in one pass per command.

IMU logs → :class:`~uasnav.imu.ImuLog`; :func:`read_log` (``open_log(path).imu``) picks the
reader from the extension.

========== ================================ ===========================================
extension  reader                           notes
========== ================================ ===========================================
.csv .txt  :func:`read_csv_v1` / x-io CSV   x-io layout recognised by its header
.npz       :func:`read_npz`                 uasnav layout or the ADIS reference layout
.ulg       :func:`read_ulog`                PX4, primary IMU (sensor_combined)
.bin       :func:`read_dataflash`           ArduPilot; ``read_log`` returns the first IMU
.tlog      :func:`read_tlog`                MAVLink; ``read_log`` returns the first stream
========== ================================ ===========================================

One flight → :class:`~uasnav.io.flight.Flight`: :func:`read_nav` (``open_log(path).nav``: the
sensors and the autopilot's estimate, for :func:`uasnav.ins.run`) and :func:`read_flight`
(``open_log(path).flight``: the telemetry track and the mission's events, ``.csv`` flight CSV,
``.tlog``, ``.bin``, ``.ulg``).

Writers are atomic: :func:`write_log` by extension (``.csv`` → CSV v1, ``.npz``) for IMU logs,
:func:`write_csv_table` for any other numeric table (:mod:`uasnav.io.table`).

One class per log format in :mod:`uasnav.io.formats` reads that format, and only there: which
message types each view needs, the record decoders, and the format's rules (GNSS delay, EKF
origin, height datums, declination parameter, field layouts across firmware versions):
:mod:`~uasnav.io.formats.ulog` (PX4 ULog), :mod:`~uasnav.io.formats.dataflash`,
:mod:`~uasnav.io.formats.tlog`, :mod:`~uasnav.io.formats.alfa`,
:mod:`~uasnav.io.formats.csv_v1` (+ :mod:`~uasnav.io.formats.gnss_csv`),
:mod:`~uasnav.io.formats.xio`, :mod:`~uasnav.io.formats.flight_csv` and
:mod:`~uasnav.io.formats.npz`. Every numeric CSV is read in chunks of whole lines through
numpy's C reader (:mod:`uasnav.io._csvstream`: bounded memory, no pyarrow). The functions
``read_ulog``, ``read_dataflash``, ``read_tlog``, ``read_*_flight`` and
``read_dataflash_messages`` exported here are those decoders (each reads its file in one pass,
or replays the active pass of a :class:`LogFile`). Nothing here imports from the rest of uasnav
except :mod:`uasnav.imu`, :mod:`uasnav.errors`, :mod:`uasnav.units`, :mod:`uasnav.limits`,
:mod:`uasnav.geo`, :mod:`uasnav.httpfetch` and :mod:`uasnav.atomicfile`.

Hostile files: every reader gives one :class:`~uasnav.errors.DataFormatError` naming the file
(and for text the line and column) for malformed content: a stray ``"``, an over-long cell, NUL
bytes, text that is not UTF-8 (a UTF-8 byte-order mark is accepted), npz object arrays (never
unpickled) or arrays whose declared size exceeds the memory limit (checked before inflating).
Text is read bounded (:mod:`uasnav.limits`, ``UASNAV_MAX_MEMORY``). Corrupt binary logs
(DataFlash, ULog without checksums; ``.tlog`` checksum failures) are read as far as they are
valid: the decoders' own output is silenced, corrupt records are dropped and counted, one
:class:`~uasnav.errors.CorruptDataWarning` gives the counts, and a reader fails only when nothing
valid is left.
"""

from __future__ import annotations

import os
from pathlib import Path

from uasnav.errors import DataFormatError, InputError, ResourceLimitError
from uasnav.imu import ImuLog, require_log
from uasnav.io.flight import Flight
from uasnav.io.formats.csv_v1 import read_csv_v1, write_csv_v1
from uasnav.io.formats.dataflash import read_dataflash, read_dataflash_flight, read_dataflash_messages
from uasnav.io.formats.flight_csv import read_flight_csv
from uasnav.io.formats.gnss_csv import read_gnss_csv, write_gnss_csv
from uasnav.io.formats.npz import read_npz, write_npz
from uasnav.io.formats.tlog import read_tlog, read_tlog_flight
from uasnav.io.formats.ulog import read_ulog, read_ulog_flight
from uasnav.io.formats.xio import read_xio_csv
from uasnav.io.logfile import LogFile, open_log
from uasnav.io.table import read_csv_table, write_csv_table

READ_EXTENSIONS = (".csv", ".txt", ".npz", ".ulg", ".bin", ".tlog")
WRITE_EXTENSIONS = (".csv", ".npz")
FLIGHT_EXTENSIONS = (".csv", ".tlog", ".bin", ".ulg")


def read_log(path: str | os.PathLike[str]) -> ImuLog:
    """Read an IMU log (``open_log(path).imu``; the format follows the extension and, for CSV,
    the header: see the module table)."""
    p = Path(path)
    if p.suffix.lower() not in READ_EXTENSIONS:
        suffix = p.suffix.lower()
        raise InputError(f"{p}: unknown log format {suffix!r} (supported: {', '.join(READ_EXTENSIONS)})")
    if p.is_dir():
        raise DataFormatError("is a directory, not a file", path=str(p))
    log = open_log(p, need=("imu",))
    if log.format_name == "flight-csv":
        return read_csv_v1(p)  # a flight CSV is no IMU log: the CSV v1 reader says what is missing
    try:
        return log.imu  # type: ignore[no-any-return]
    except (DataFormatError, ResourceLimitError):
        raise
    except InputError as e:  # ImuLog's own checks (e.g. a temperature below absolute zero): name the file
        raise DataFormatError(str(e), path=str(p)) from None


def read_flight(path: str | os.PathLike[str]) -> Flight:
    """Read the flight telemetry of a log (``open_log(path).flight``: .csv, .tlog, .bin, .ulg).

    Raises
    ------
    InputError
        If ``path`` does not exist, is not a regular file or has another extension.
    DataFormatError
        If the file is malformed (names the file, and the line and column for CSV).
    """
    p = Path(path)
    if not p.exists():
        raise InputError(f"no such telemetry file: {p}")
    if not p.is_file():
        raise InputError(f"{p}: not a regular file (a directory, device or FIFO)")
    ext = p.suffix.lower()
    if ext not in FLIGHT_EXTENSIONS:
        raise InputError(f"{p}: unknown telemetry format {ext!r} (expected .csv, .tlog, .bin, .ulg)")
    if ext == ".csv":
        return read_flight_csv(p)  # any CSV: the flight CSV reader names missing columns
    return open_log(p, need=("flight",)).flight  # type: ignore[no-any-return]


def read_nav(path: str | os.PathLike[str], *, gnss_csv: str | os.PathLike[str] | None = None) -> Flight:
    """The navigation data of a log (``open_log(path, gnss=gnss_csv).nav``): ``.bin``, ``.ulg``,
    ``.tlog``, ``.csv`` (CSV v1, with ``gnss_csv`` required) or an ALFA ROS-topic CSV folder;
    ``gnss_csv`` replaces the log's own GNSS when given.

    Raises
    ------
    InputError
        Unknown extension, or a CSV log without ``gnss_csv``.
    DataFormatError
        The format reader's errors.
    """
    return open_log(path, need=("nav",), gnss=gnss_csv).nav  # type: ignore[no-any-return]


def write_log(log: ImuLog, path: str | os.PathLike[str]) -> None:
    """Write ``log`` atomically; ``.csv`` → CSV v1 (with truth columns), ``.npz``."""
    require_log(log)
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == ".csv":
        write_csv_v1(log, p)
    elif suffix == ".npz":
        write_npz(log, p)
    else:
        raise InputError(f"{p}: cannot write format {suffix!r} (supported: {', '.join(WRITE_EXTENSIONS)})")


__all__ = [
    "FLIGHT_EXTENSIONS",
    "READ_EXTENSIONS",
    "WRITE_EXTENSIONS",
    "Flight",
    "LogFile",
    "open_log",
    "read_csv_table",
    "read_csv_v1",
    "read_dataflash",
    "read_dataflash_flight",
    "read_dataflash_messages",
    "read_flight",
    "read_flight_csv",
    "read_gnss_csv",
    "read_log",
    "read_nav",
    "read_npz",
    "read_tlog",
    "read_tlog_flight",
    "read_ulog",
    "read_ulog_flight",
    "read_xio_csv",
    "write_csv_table",
    "write_csv_v1",
    "write_gnss_csv",
    "write_log",
    "write_npz",
]
