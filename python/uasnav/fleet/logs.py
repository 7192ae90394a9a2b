"""One log of a fleet, read once through :mod:`uasnav.io`: its format, IMUs and identity.

The fleet never parses a format itself: every log is opened with :func:`uasnav.io.open_log`
(one decoding pass). This module names the format (by extension, and for ``.csv`` by the
header: CSV v1, x-io or the flight CSV) and gathers what every analysis needs: the IMU
instances as :class:`~uasnav.imu.ImuLog` (the ``imus`` view) and the vehicle identity written
in the log (CSV v1 ``# vehicle:``, ``# autopilot:``, ``# start_time:`` comments; a ULog's
flight-controller UUID and GNSS UTC time; a DataFlash log's board identity line and GPS
week/time (the ``identity`` view); a ``.tlog``'s wall-clock time stamps; else ``unknown``). A
ULog's IMUs are the primary one and every ``sensor_gyro``/``sensor_accel`` instance. A CSV v1 log ``X.csv``
with ``X_gnss.csv`` beside it is one log of the GNSS/INS flight format (:func:`gnss_companion`);
a ``.tlog`` without IMU streams is telemetry only.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from uasnav.errors import DataFormatError, InputError
from uasnav.imu import ImuLog
from uasnav.io.logfile import LogFile

#: Format names of the inventory (``format`` column) by reader.
FORMATS = ("csv-v1", "xio-csv", "flight-csv", "npz", "px4-ulog", "ardupilot-dataflash", "mavlink-tlog")
_AUTOPILOT = {"px4-ulog": "PX4", "ardupilot-dataflash": "ArduPilot"}


@dataclass(frozen=True)
class FleetLog:
    """What the fleet knows of one log after reading it once.

    Attributes
    ----------
    path : str
    format : str
        One of :data:`FORMATS`.
    imus : dict of str → ImuLog
        IMU instances by name (empty for a flight CSV).
    vehicle, autopilot : str or None
        Identifiers written in the log, if any.
    start_time : datetime or None
        Start of the recording (UTC), if the log says.
    file : LogFile or None
        The opened log, for further views from the same decoding pass.
    """

    path: str
    format: str
    imus: dict[str, ImuLog]
    vehicle: str | None = None
    autopilot: str | None = None
    start_time: dt.datetime | None = None
    file: LogFile | None = field(default=None, compare=False, repr=False)

    @property
    def day(self) -> str | None:
        """``YYYY-MM-DD`` of the start (UTC), or None."""
        return None if self.start_time is None else self.start_time.date().isoformat()


def csv_kind(path: str) -> str:
    """``csv-v1``, ``xio-csv`` or ``flight-csv`` from the header
    (:func:`uasnav.io.logfile.csv_kind`)."""
    from uasnav.io.logfile import csv_kind as kind

    return kind(path)


#: Suffix of the GNSS CSV that goes with a CSV v1 IMU log (``X.csv`` + ``X_gnss.csv``, the
#: flight format of ``uasnav simulate --profile flight`` and ``uasnav nav --gnss``).
GNSS_SUFFIX = "_gnss.csv"


def gnss_companion(path: str) -> str | None:
    """The GNSS CSV of the CSV IMU log ``path`` (``X_gnss.csv`` beside ``X.csv``), if it exists."""
    p = Path(path)
    if p.suffix.lower() != ".csv" or p.name.endswith(GNSS_SUFFIX):
        return None
    g = p.with_name(p.stem + GNSS_SUFFIX)
    return str(g) if g.is_file() else None


def is_gnss_companion(path: str) -> bool:
    """``path`` is ``X_gnss.csv`` with an ``X.csv`` beside it (part of that log)."""
    p = Path(path)
    if not p.name.endswith(GNSS_SUFFIX):
        return False
    return p.with_name(p.name[: -len(GNSS_SUFFIX)] + ".csv").is_file()


def format_of(path: str) -> str:
    """The format of ``path`` (see :data:`FORMATS`); InputError for an unknown extension."""
    ext = Path(path).suffix.lower()
    if ext in (".csv", ".txt"):
        return csv_kind(path)
    known = {".npz": "npz", ".ulg": "px4-ulog", ".bin": "ardupilot-dataflash", ".tlog": "mavlink-tlog"}
    if ext not in known:
        raise InputError(f"{path}: unknown log format {ext!r}")
    return known[ext]


def _start_time(meta: dict[str, Any]) -> dt.datetime | None:
    text = meta.get("start_time")
    if not text:
        return None
    try:
        t = dt.datetime.fromisoformat(str(text).replace("Z", "+00:00"))
    except ValueError:
        raise DataFormatError(
            f"start_time: not an ISO 8601 time: {text!r}", path=meta.get("source")
        ) from None
    return t.replace(tzinfo=dt.timezone.utc) if t.tzinfo is None else t.astimezone(dt.timezone.utc)


def _tlog_start(log: LogFile) -> dt.datetime | None:
    """A .tlog's telemetry is stamped with the ground station's wall clock (UTC, s): its first
    GNSS sample dates the log. None without one (or before 2000: not a wall clock)."""
    from uasnav.errors import UasnavError

    try:
        t0 = float(log.flight.t[0])
    except (UasnavError, IndexError):
        return None
    if t0 < 946_684_800:  # 2000-01-01
        return None
    return dt.datetime.fromtimestamp(t0, tz=dt.timezone.utc)


def read_fleet_log(path: str, need: tuple[str, ...] = (), **options: Any) -> FleetLog:
    """Read ``path`` once (:func:`uasnav.io.open_log`, with its ``options``: one decoding pass
    for the IMUs, the identity and the views ``need`` that the caller reads next from
    ``FleetLog.file``)."""
    from uasnav.io.logfile import open_log

    fmt = format_of(path)
    imus: dict[str, ImuLog]
    vehicle = None
    boot_utc = None
    if fmt in ("csv-v1", "xio-csv", "npz"):
        log = open_log(path, need=("imu", *need), **options)
        imus = {"imu0": log.imu}
    elif fmt in ("px4-ulog", "ardupilot-dataflash"):
        log = open_log(path, need=("imus", "identity", *need), **options)
        imus = dict(log.imus)
        if fmt == "ardupilot-dataflash":
            ident = log.identity
            if ident.board and ident.vehicle_id:
                vehicle = f"{ident.board} {ident.vehicle_id}"  # the board identity line of MSG
            boot_utc = ident.utc_at_zero
    elif fmt == "mavlink-tlog":
        log = open_log(path, need=("imus", "flight", *need), **options)
        try:
            imus = dict(log.imus)
        except DataFormatError as imu_error:
            # a ground station's telemetry often streams no IMU: then it is telemetry only
            # (like a flight CSV) if it has position fixes, else the reader's error stands
            try:
                log.view("flight")
            except DataFormatError:
                raise imu_error from None
            imus = {}
    else:  # flight CSV: telemetry only
        log = open_log(path, need=("flight", *need), **options)
        log.view("flight")
        imus = {}
    meta = dict(next(iter(imus.values())).meta) if imus else {}
    if vehicle is not None:
        meta["vehicle"] = vehicle
    start = _start_time(meta)
    if start is None and boot_utc is not None and imus:
        start = boot_utc + dt.timedelta(seconds=min(float(m.t[0]) for m in imus.values()))
    if start is None and fmt == "mavlink-tlog":
        start = _tlog_start(log)
    return FleetLog(
        path=path,
        format=fmt,
        imus=imus,
        vehicle=meta.get("vehicle"),
        autopilot=meta.get("autopilot") or _AUTOPILOT.get(fmt),
        start_time=start,
        file=log,
    )


__all__ = ["FORMATS", "FleetLog", "csv_kind", "format_of", "read_fleet_log"]
