"""One log, decoded once: :func:`open_log` and :class:`LogFile`.

``open_log(path)`` recognises the format (``.ulg`` PX4 ULog, ``.bin`` ArduPilot DataFlash,
``.tlog`` MAVLink telemetry, ``.csv``/``.txt`` CSV v1 / x-io / flight CSV by the header,
``.npz``, or an ALFA ROS-topic CSV folder) and returns a :class:`LogFile` whose views are
decoded on first access and cached:

===================== ============================================== =========================
view                  type                                           units, frames, datums
===================== ============================================== =========================
``imus`` / ``imu``    dict of :class:`~uasnav.imu.ImuLog` / primary  body FRD; rad/s, m/s², °C
``gnss``              :class:`~uasnav.io.flight.GnssData`           deg, NED m/s; ``alt_datum``
``baro``              :class:`~uasnav.io.flight.BaroData`           m, datum unknown
``mag``               :class:`~uasnav.io.flight.MagData`            body FRD, unit as logged
``autopilot_estimate`` :class:`~uasnav.io.flight.Trajectory`        deg; NED m/s; deg 3-2-1;
                                                                     in the GNSS fixes' datum
``nav``               :class:`~uasnav.io.flight.Flight`             all of the above together
``flight``            :class:`~uasnav.io.flight.Flight`           telemetry for trajectory
``plan``              :class:`~uasnav.io.mission_plan.MissionPlan`   items with altitude frames
``params``            dict name → float                              as the autopilot stores
``limits``            :class:`~uasnav.io.autopilot_limits.AutopilotLimits` SI
``modes``             :class:`~uasnav.io.views.ModeTimeline`          log time
``identity``          :class:`~uasnav.io.views.Identity`              UTC at log time 0
===================== ============================================== =========================

One decoding pass serves a whole command: declare the views up front
(``open_log(p, need={"imus", "gnss"})`` or :meth:`LogFile.need`); the first access decodes
the union of the message types they need in one pass (pymavlink with a ``type`` filter, pyulog
with ``message_name_filter_list``). A view asked for later that needs other types costs one
more pass, for those types only (DataFlash, tlog) or for the union (ULog).
Every time is log time (:mod:`uasnav.io.views`). Format rules live in the format classes
(:mod:`uasnav.io.formats`).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from uasnav.errors import DataFormatError, InputError
from uasnav.io._active import active
from uasnav.io.formats.alfa import AlfaFormat
from uasnav.io.formats.base import VIEWS, LogFormat
from uasnav.io.formats.csv_v1 import CsvV1Format
from uasnav.io.formats.dataflash import DataflashFormat
from uasnav.io.formats.flight_csv import FlightCsvFormat, is_flight_csv
from uasnav.io.formats.npz import NpzFormat
from uasnav.io.formats.tlog import TlogFormat
from uasnav.io.formats.ulog import UlogFormat
from uasnav.io.formats.xio import XioFormat, is_xio_csv

#: Format classes by extension (CSV by header, see :func:`format_class`).
BY_EXTENSION: dict[str, type[LogFormat]] = {
    ".ulg": UlogFormat,
    ".bin": DataflashFormat,
    ".tlog": TlogFormat,
    ".npz": NpzFormat,
}
_CSV = {"csv-v1": CsvV1Format, "xio-csv": XioFormat, "flight-csv": FlightCsvFormat}
EXTENSIONS = (".ulg", ".bin", ".tlog", ".csv", ".txt", ".npz")


def csv_kind(path: str | os.PathLike[str]) -> str:
    """``csv-v1``, ``xio-csv`` or ``flight-csv`` from the first non-comment line of a CSV file.

    Raises
    ------
    DataFormatError
        Missing file, a directory, or unreadable.
    """
    p = Path(path)
    try:
        with open(p, "rb") as fh:
            for _ in range(1000):
                raw = fh.readline(4096)  # a bounded peek, whatever the file
                if not raw:
                    break
                line = raw.decode("utf-8", errors="replace").lstrip("\ufeff").strip()
                if not line or line.startswith("#"):
                    continue
                if is_xio_csv(line):
                    return XioFormat.name
                if is_flight_csv([c.strip() for c in line.split(",")]):
                    return FlightCsvFormat.name
                return CsvV1Format.name
    except FileNotFoundError:
        raise DataFormatError("no such file", path=str(p)) from None
    except IsADirectoryError:
        raise DataFormatError("is a directory, not a file", path=str(p)) from None
    except OSError as e:
        raise DataFormatError(f"cannot read ({e.strerror or e})", path=str(p)) from None
    return CsvV1Format.name


def format_class(path: str | os.PathLike[str]) -> type[LogFormat]:
    """The format class of ``path``.

    Raises
    ------
    InputError
        Unknown extension (naming the supported ones).
    DataFormatError
        A CSV that cannot be read to tell its layout.
    """
    p = Path(path)
    if p.is_dir():
        return AlfaFormat
    ext = p.suffix.lower()
    if ext in (".csv", ".txt"):
        return _CSV[csv_kind(p)]
    if ext in BY_EXTENSION:
        return BY_EXTENSION[ext]
    raise InputError(f"{p}: unknown log type {ext!r} (expected {', '.join(EXTENSIONS)} or an ALFA folder)")


class LogFile:
    """A log file and its views (see the module docs). Views raise the format's
    :class:`~uasnav.errors.DataFormatError` when the log lacks what they need."""

    def __init__(self, fmt: LogFormat, need: Iterable[str] = ()) -> None:
        self.format = fmt
        self._need: set[str] = set()
        self._cache: dict[str, Any] = {}
        self._scan: Any | None = None
        self._download: Any = None  # the temporary folder of a log fetched by URL
        self.need(*need)

    @property
    def path(self) -> Path:
        """The file (or folder) read."""
        return self.format.path

    @property
    def format_name(self) -> str:
        """``px4-ulog``, ``ardupilot-dataflash``, ``mavlink-tlog``, ``csv-v1`` …"""
        return self.format.name

    def carries(self, view: str) -> bool:
        """Whether the format can have ``view`` at all (the log may still lack it)."""
        return self.format.carries(view)

    def need(self, *views: str) -> LogFile:
        """Declare views the command will read, so that the first decoding pass covers them."""
        for v in views:
            if v not in VIEWS:
                raise InputError(f"open_log: unknown view {v!r} (views: {', '.join(VIEWS)})")
            self._need.add(v)
        return self

    def view(self, name: str) -> Any:
        """The view ``name`` (decoded on first access, then cached)."""
        if name in self._cache:
            return self._cache[name]
        self.need(name)
        types = self.format.types_for(v for v in self._need if self.format.carries(v))
        self._scan = self.format.scan(types, self._scan)
        if self._scan is None:
            value = self.format.build(name, self._cache)
        else:
            with active(self._scan):
                value = self.format.build(name, self._cache)
        self._cache[name] = value
        return value

    # the views, typed for readers of the code (see the module table)
    @property
    def imus(self) -> Any:
        """Every IMU, keyed by stream name."""
        return self.view("imus")

    @property
    def imu(self) -> Any:
        """The primary IMU (what :func:`uasnav.io.read_log` returns)."""
        return self.view("imu")

    @property
    def nav(self) -> Any:
        """The navigation data (:class:`~uasnav.io.flight.Flight`)."""
        return self.view("nav")

    @property
    def gnss(self) -> Any:
        """GNSS fixes."""
        return self.view("gnss")

    @property
    def baro(self) -> Any:
        """Barometric altitude (None when not logged)."""
        return self.view("baro")

    @property
    def mag(self) -> Any:
        """Magnetometer (None when not logged)."""
        return self.view("mag")

    @property
    def autopilot_estimate(self) -> Any:
        """The autopilot's own estimate (None when not logged)."""
        return self.view("autopilot_estimate")

    @property
    def flight(self) -> Any:
        """Flight telemetry (:class:`~uasnav.io.flight.Flight`)."""
        return self.view("flight")

    @property
    def plan(self) -> Any:
        """The mission plan the log carries."""
        return self.view("plan")

    @property
    def params(self) -> Any:
        """Autopilot parameters."""
        return self.view("params")

    @property
    def limits(self) -> Any:
        """The navigation limits configured (:class:`~uasnav.io.autopilot_limits.AutopilotLimits`)."""
        return self.view("limits")

    @property
    def modes(self) -> Any:
        """Flight-mode timeline."""
        return self.view("modes")

    @property
    def identity(self) -> Any:
        """Vehicle, firmware, board and clock."""
        return self.view("identity")


#: How long (s) and how large (bytes) a log fetched by URL may be.
FETCH_TIMEOUT_S = 600.0
FETCH_MAX_BYTES = 4 * 1024**3


def open_log(path: str | os.PathLike[str], *, need: Iterable[str] = (), **options: Any) -> LogFile:
    """Open the log ``path`` — a file, an ALFA folder or an ``http(s)://`` URL, fetched first
    into a temporary folder that lives as long as the :class:`LogFile` — (see the module docs);
    ``need`` declares the views to decode in the first pass. ``gnss=`` (a GNSS CSV path or
    :class:`~uasnav.io.flight.GnssData`) gives a CSV v1 log its fixes, or replaces a log's own.

    Raises
    ------
    InputError
        Unknown format or view; a URL that cannot be fetched (:class:`~uasnav.httpfetch.FetchError`).
    DataFormatError
        A missing or unreadable file (when a view is read; a CSV's layout at once).
    """
    from uasnav.httpfetch import is_url

    keep: Any = None
    if is_url(str(path)):
        keep, path = _fetch(str(path))
    p = Path(path)
    fmt = format_class(p)(p, **options)
    log = LogFile(fmt, need)
    log._download = keep
    return log


def _fetch(url: str) -> tuple[Any, Path]:
    """The log at ``url`` downloaded into a new temporary folder (kept with its extension: the
    format follows it); the folder object (removed when collected) and the file."""
    import re
    import tempfile
    from urllib.parse import unquote, urlsplit

    from uasnav.httpfetch import download

    tmp = tempfile.TemporaryDirectory(prefix="uasnav-log-")
    name = re.sub(r"[^A-Za-z0-9._-]", "_", os.path.basename(unquote(urlsplit(url).path))).lstrip(".")
    local = Path(tmp.name) / (name[-120:] or "log")
    with open(local, "wb") as fh:
        download(url, fh, timeout_s=FETCH_TIMEOUT_S, max_bytes=FETCH_MAX_BYTES)
    return tmp, local


__all__ = [
    "EXTENSIONS",
    "FETCH_MAX_BYTES",
    "FETCH_TIMEOUT_S",
    "LogFile",
    "csv_kind",
    "format_class",
    "open_log",
]
