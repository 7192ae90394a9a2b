"""The base of the log format classes: which message types each view needs, one decoding pass
for the union of them, and the view builders. Each format's rules (time fields, GNSS delay,
EKF origin, height datums, field layouts across firmware versions) live in its own class."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any, ClassVar

from uasnav.errors import DataFormatError
from uasnav.imu import ImuLog
from uasnav.io.views import Identity

#: Every view a :class:`~uasnav.io.logfile.LogFile` can offer.
VIEWS = (
    "imus",
    "imu",
    "nav",
    "gnss",
    "baro",
    "mag",
    "autopilot_estimate",
    "flight",
    "plan",
    "params",
    "limits",
    "modes",
    "identity",
)
#: Views taken from the navigation data (:class:`~uasnav.io.flight.Flight`).
NAV_PARTS = {"gnss": "gnss", "baro": "baro", "mag": "mag", "autopilot_estimate": "reference"}


class LogFormat(ABC):
    """One log format. A subclass sets :attr:`name` and :attr:`SOURCES` (view → message types or
    topics it decodes), implements :meth:`scan` (through :class:`ScannedFormat` for binary logs,
    :class:`WholeFileFormat` for files read whole) and :meth:`build_identity`, and builds every
    other view of :attr:`SOURCES` with a ``build_<view>`` method or a :attr:`READERS` entry."""

    name: ClassVar[str] = ""
    #: The message types / topics each view needs.
    SOURCES: ClassVar[dict[str, tuple[str, ...]]] = {}

    def __init__(self, path: Path, **options: Any) -> None:
        self.path = Path(path)
        self.options = options

    @classmethod
    def carries(cls, view: str) -> bool:
        """Whether this format can have the view at all."""
        if view in NAV_PARTS:
            return "nav" in cls.SOURCES
        return view in cls.SOURCES

    def types_for(self, views: Iterable[str]) -> set[str]:
        """The union of the message types the ``views`` need."""
        out: set[str] = set()
        for v in views:
            out.update(self.SOURCES.get("nav" if v in NAV_PARTS else v, ()))
        return out

    #: Views read by one reader function of the path (called with the scan active).
    READERS: ClassVar[dict[str, Callable[[Path], Any]]] = {}

    @abstractmethod
    def scan(self, types: set[str], previous: Any | None) -> Any | None:
        """The decoding pass that covers the message types ``types`` (``previous``, the pass
        made so far, when it does), or None for a format read whole."""

    @abstractmethod
    def build_identity(self) -> Any:
        """Who wrote the log (:class:`~uasnav.io.views.Identity`)."""

    def build(self, view: str, cache: dict[str, Any]) -> Any:
        """The view ``view`` (called with the scan active; ``cache`` holds views already built)."""
        if view in NAV_PARTS:
            nav = cache.get("nav")
            if nav is None:
                nav = cache["nav"] = self.build("nav", cache)
            return getattr(nav, NAV_PARTS[view])
        if view not in self.SOURCES:
            raise DataFormatError(
                f"a {self.name} log carries no {view.replace('_', ' ')}", path=str(self.path)
            )
        if view in self.READERS:
            value = self.READERS[view](self.path)
        else:
            value = getattr(self, f"build_{view}")()
        if view == "nav" and self.options.get("gnss") is not None and self.name != "csv-v1":
            value = self._with_gnss(value)  # the fixes of a GNSS CSV replace the log's own
        return value

    def build_imu(self) -> Any:
        """The primary IMU: the first stream by name."""
        logs = self.build("imus", {})
        return logs[sorted(logs)[0]]

    def limit_parameters(self, params: dict[str, float]) -> dict[str, tuple[str, float]]:
        """The parameter table of :mod:`uasnav.io.autopilot_params` the limits are read with."""
        from uasnav.io.autopilot_params import ARDUPILOT_PARAMS

        return ARDUPILOT_PARAMS

    def build_limits(self) -> Any:
        """The navigation limits from the parameters
        (:func:`~uasnav.io.autopilot_params.limits_from_params`)."""
        from uasnav.io.autopilot_params import limits_from_params

        params = self.build("params", {})
        return limits_from_params(params, self.limit_parameters(params))

    def _with_gnss(self, nav: Any) -> Any:
        """``nav`` with the GNSS fixes of the option ``gnss`` (a GNSS CSV path or GnssData)."""
        from dataclasses import replace

        from uasnav.io.flight import GnssData

        gnss = self.options["gnss"]
        if not isinstance(gnss, GnssData):
            from uasnav.io.formats.gnss_csv import read_gnss_csv

            gnss = read_gnss_csv(gnss)
        return replace(nav, gnss=gnss)


class ScannedFormat(LogFormat):
    """A binary log decoded in passes of :attr:`SCANNER` (:mod:`uasnav.io.formats._scan`) for
    the union of the message types the views need."""

    #: The decoding pass and its options.
    SCANNER: ClassVar[Callable[..., Any]]
    SCAN_OPTIONS: ClassVar[dict[str, Any]] = {}

    def scan(self, types: set[str], previous: Any | None) -> Any:
        """``previous`` when it covers ``types``, else one new pass for ``types`` and what
        ``previous`` held."""
        if previous is not None and previous.covers(types):
            return previous
        union = set(types) | (set(previous.types) if previous is not None else set())
        return self.SCANNER(self.path, union, **self.SCAN_OPTIONS)


class WholeFileFormat(LogFormat):
    """A file (or folder) read whole by its views' builders: no decoding pass to share."""

    def scan(self, types: set[str], previous: Any | None) -> None:
        return None


class ImuFileFormat(WholeFileFormat):
    """An IMU log read whole by one reader (:meth:`read_imu`), once, then cached."""

    @abstractmethod
    def read_imu(self) -> ImuLog:
        """The file's IMU log."""

    def build_imu(self) -> ImuLog:
        cached = self.options.get("_imu")
        if cached is None:
            cached = self.options["_imu"] = self.read_imu()
        return cached  # type: ignore[no-any-return]

    def build_imus(self) -> dict[str, Any]:
        return {"imu0": self.build_imu()}

    def build_identity(self) -> Identity:
        meta = self.build_imu().meta
        return Identity(vehicle_id=meta.get("vehicle"), board=meta.get("hardware"), clock="file")


__all__ = ["NAV_PARTS", "VIEWS", "ImuFileFormat", "LogFormat", "ScannedFormat", "WholeFileFormat"]
