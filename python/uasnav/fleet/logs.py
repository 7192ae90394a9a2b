"""One log of a fleet, read once through :mod:`uasnav.io`: its format, IMUs and identity.

The fleet never parses a format itself: every reader is :mod:`uasnav.io`'s. This module only
says which reader a file needs (by extension, and for ``.csv`` by the header: CSV v1, x-io or
the flight CSV) and gathers what every analysis needs: the IMU instances as
:class:`~uasnav.imu.ImuLog` (``read_dataflash``/``read_tlog`` give every instance, ``read_ulog``
the primary one) and the vehicle identity written in the log (CSV v1 ``# vehicle:``,
``# autopilot:``, ``# start_time:`` comments; a ULog's flight-controller UUID and GNSS UTC time;
a DataFlash log's board identity line and GPS week/time (:func:`uasnav.io.dataflash.read_dataflash_identity`);
a ``.tlog``'s wall-clock time stamps; else ``unknown``). A ULog's IMUs are the primary one and
every ``sensor_gyro``/``sensor_accel`` instance (:func:`uasnav.io.px4.read_ulog_imus`). A CSV v1 log ``X.csv``
with ``X_gnss.csv`` beside it is one log of the GNSS/INS flight format (:func:`gnss_companion`);
a ``.tlog`` without IMU streams is telemetry only.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from uasnav.errors import DataFormatError, InputError
from uasnav.imu import ImuLog
from uasnav.io.flight import FLIGHT_CSV_COLUMNS

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
    """

    path: str
    format: str
    imus: dict[str, ImuLog]
    vehicle: str | None = None
    autopilot: str | None = None
    start_time: dt.datetime | None = None

    @property
    def day(self) -> str | None:
        """``YYYY-MM-DD`` of the start (UTC), or None."""
        return None if self.start_time is None else self.start_time.date().isoformat()


def csv_kind(path: str) -> str:
    """``csv-v1``, ``xio-csv`` or ``flight-csv`` from the first non-comment line of a CSV file."""
    from uasnav.io import is_xio_csv

    with open(path, "rb") as fh:
        for _ in range(1000):
            raw = fh.readline(4096)
            if not raw:
                break
            line = raw.decode("utf-8", errors="replace").lstrip("\ufeff").strip()
            if not line or line.startswith("#"):
                continue
            if is_xio_csv(line):
                return "xio-csv"
            cols = [c.strip() for c in line.split(",")]
            if cols[: len(FLIGHT_CSV_COLUMNS)] == list(FLIGHT_CSV_COLUMNS) or {"lat", "lon"} <= set(cols):
                return "flight-csv"
            return "csv-v1"
    return "csv-v1"


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


def _tlog_start(path: str) -> dt.datetime | None:
    """A .tlog's telemetry is stamped with the ground station's wall clock (UTC, s): its first
    GNSS sample dates the log. None without one (or before 2000: not a wall clock)."""
    from uasnav.errors import UasnavError
    from uasnav.io import read_flight

    try:
        t0 = float(read_flight(path).t[0])
    except (UasnavError, IndexError):
        return None
    if t0 < 946_684_800:  # 2000-01-01
        return None
    return dt.datetime.fromtimestamp(t0, tz=dt.timezone.utc)


def read_fleet_log(path: str) -> FleetLog:
    """Read ``path`` once with the reader its format needs (module docs)."""
    from uasnav import io

    fmt = format_of(path)
    imus: dict[str, ImuLog]
    identity: dict[str, Any] = {}
    if fmt in ("csv-v1", "xio-csv", "npz"):
        imus = {"imu0": io.read_log(path)}
    elif fmt == "px4-ulog":
        from uasnav.io.px4 import read_ulog_imus

        imus = read_ulog_imus(path)
    elif fmt == "ardupilot-dataflash":
        from uasnav.io.dataflash import read_dataflash_identity

        imus = io.read_dataflash(path)
        identity = read_dataflash_identity(path)
    elif fmt == "mavlink-tlog":
        try:
            imus = io.read_tlog(path)
        except DataFormatError as imu_error:
            # a ground station's telemetry often streams no IMU: then it is telemetry only
            # (like a flight CSV) if it has position fixes, else the reader's error stands
            try:
                io.read_flight(path)
            except DataFormatError:
                raise imu_error from None
            imus = {}
    else:  # flight CSV: telemetry only
        io.read_flight(path)
        imus = {}
    meta = dict(next(iter(imus.values())).meta) if imus else {}
    if "vehicle" in identity:
        meta["vehicle"] = identity["vehicle"]
    start = _start_time(meta)
    if start is None and "boot_utc" in identity and imus:
        start = identity["boot_utc"] + dt.timedelta(seconds=min(float(m.t[0]) for m in imus.values()))
    if start is None and fmt == "mavlink-tlog":
        start = _tlog_start(path)
    return FleetLog(
        path=path,
        format=fmt,
        imus=imus,
        vehicle=meta.get("vehicle"),
        autopilot=meta.get("autopilot") or _AUTOPILOT.get(fmt),
        start_time=start,
    )


__all__ = ["FORMATS", "FleetLog", "csv_kind", "format_of", "read_fleet_log"]
