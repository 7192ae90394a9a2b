"""The typed views of a log that :class:`~uasnav.io.logfile.LogFile` offers besides the sensor
and estimate data types of :mod:`uasnav.io.flight` (IMU, GNSS, barometer, magnetometer,
autopilot estimate) and the plan (:class:`~uasnav.io.mission_plan.MissionPlan`).

Time base: every time in every view is the log's own clock in seconds — time since boot for
ULog and DataFlash, the ground station's UTC wall clock (s since 1970) for ``.tlog``, the file's
``t`` column for CSV. :attr:`Identity.utc_at_zero` gives UTC at log time 0 where the log says
(from GNSS week and time of week minus the GPS − UTC leap seconds, or the receiver's UTC).
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from uasnav.errors import InputError

#: GPS − UTC (s) from the given UTC date on (leap seconds; IERS bulletin C).
GPS_UTC_LEAP_S = ((dt.datetime(2012, 7, 1, tzinfo=dt.timezone.utc), 16),
                  (dt.datetime(2015, 7, 1, tzinfo=dt.timezone.utc), 17),
                  (dt.datetime(2017, 1, 1, tzinfo=dt.timezone.utc), 18))  # fmt: skip
GPS_EPOCH = dt.datetime(1980, 1, 6, tzinfo=dt.timezone.utc)


def gps_to_utc(week: int, time_of_week_ms: float) -> tuple[dt.datetime, int]:
    """UTC of a GPS week and time of week (ms), and the GPS − UTC leap seconds applied.

    Examples
    --------
    >>> gps_to_utc(2000, 0.0)
    (datetime.datetime(2018, 5, 5, 23, 59, 42, tzinfo=datetime.timezone.utc), 18)
    """
    gps = GPS_EPOCH + dt.timedelta(weeks=int(week), milliseconds=float(time_of_week_ms))
    leap = max([s for since, s in GPS_UTC_LEAP_S if gps >= since], default=15)
    return gps - dt.timedelta(seconds=leap), leap


@dataclass(frozen=True)
class Identity:
    """Who wrote the log.

    Attributes
    ----------
    autopilot : str or None
        ``"PX4"``, ``"ArduPilot"`` … (None when the log does not say).
    vehicle_type : str or None
        E.g. ``"multirotor"``, ``"fixed-wing"``, ``"ArduCopter"``.
    firmware_version : str or None
        E.g. ``"1.11.0"``, ``"4.0.3"``.
    firmware_git : str or None
        The firmware's source revision when logged.
    board : str or None
        The flight-controller hardware (``ver_hw``, the board line of ``MSG``).
    vehicle_id : str or None
        A unique id of the flight controller (``sys_uuid``; the processor id of the board line).
    utc_at_zero : datetime or None
        UTC at log time 0 (see the module docs).
    leap_seconds : int or None
        GPS − UTC applied to get ``utc_at_zero`` from GPS time (None when not from GPS time).
    clock : str
        What log time is: ``"boot"``, ``"wall"`` (UTC s since 1970) or ``"file"`` (CSV ``t``).
    """

    autopilot: str | None = None
    vehicle_type: str | None = None
    firmware_version: str | None = None
    firmware_git: str | None = None
    board: str | None = None
    vehicle_id: str | None = None
    utc_at_zero: dt.datetime | None = None
    leap_seconds: int | None = None
    clock: str = "boot"

    @property
    def date(self) -> dt.date | None:
        """The UTC date of log time 0, when known."""
        return None if self.utc_at_zero is None else self.utc_at_zero.date()


@dataclass(frozen=True)
class ModeTimeline:
    """Flight modes over time: mode ``names[i]`` from ``t[i]`` (s, log time) until ``t[i+1]``
    (the last until the end of the log). Names as the autopilot calls them (``"AUTO"``,
    ``"LOITER"``, PX4's ``"AUTO_MISSION"`` …)."""

    t: NDArray[np.float64]
    names: tuple[str, ...]
    source: str = ""
    extra: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=np.float64)
        if t.ndim != 1 or t.size != len(self.names):
            raise InputError(f"modes: {t.size} times for {len(self.names)} names")
        if t.size and (not np.all(np.isfinite(t)) or np.any(np.diff(t) < 0)):
            raise InputError("modes: times must be finite and non-decreasing")
        object.__setattr__(self, "t", t)

    def at(self, t: float) -> str | None:
        """The mode at log time ``t`` (None before the first change)."""
        i = int(np.searchsorted(self.t, t, side="right")) - 1
        return None if i < 0 else self.names[i]


def changes(t: NDArray[np.float64], names: list[str], source: str) -> ModeTimeline:
    """The timeline of the samples (``t``, ``names``) keeping only the changes."""
    keep_t: list[float] = []
    keep_n: list[str] = []
    for ti, n in zip(t, names, strict=True):
        if not keep_n or n != keep_n[-1]:
            keep_t.append(float(ti))
            keep_n.append(n)
    return ModeTimeline(np.asarray(keep_t, dtype=np.float64), tuple(keep_n), source)


__all__ = ["GPS_EPOCH", "GPS_UTC_LEAP_S", "Identity", "ModeTimeline", "changes", "gps_to_utc"]
