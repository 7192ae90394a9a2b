"""The in-memory flight telemetry type :class:`FlightLog`, and the flight CSV format.

A :class:`FlightLog` is what the flight readers of each log format return (time, WGS-84
position, NED ground velocity, the mission's navigation waypoints, waypoint-reached events and
the wind estimate when the log has them); :func:`uasnav.io.read_flight` picks the reader from
the file extension:

========= =========================================== =============================================
extension reader                                      messages
========= =========================================== =============================================
.csv      :func:`read_flight_csv`                     header ``t,lat,lon,alt,v_N,v_E,v_D``
.tlog     :func:`uasnav.io.tlog.read_tlog_flight`     GLOBAL_POSITION_INT, MISSION_ITEM(_INT), …
.bin      :func:`uasnav.io.dataflash.read_dataflash_flight` GPS, CMD, MSG, XKF2/NKF2/EKF2
.ulg      :func:`uasnav.io.px4.read_ulog_flight`      vehicle_global_position, mission_result, …
========= =========================================== =============================================

This module imports no format reader (they import it), so it cannot close an import circle.
"""

from __future__ import annotations

import csv
import os
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from uasnav.errors import DataFormatError, InputError

FloatArray = NDArray[np.float64]

#: Columns of the flight CSV (s, deg, deg, m, then the NED ground velocity in m/s).
FLIGHT_CSV_COLUMNS = ("t", "lat", "lon", "alt", "v_N", "v_E", "v_D")

_SAMPLE_FIELDS = ("t", "lat", "lon", "alt", "vel_ned")


@dataclass(frozen=True)
class FlightLog:
    """Telemetry of one log.

    The constructor sorts the samples by time and drops repeated time stamps (the first sample
    of each time stamp is kept), so ``t`` is strictly increasing.

    Attributes
    ----------
    t : ndarray, shape (k,)
        Time, s (wall clock for .tlog, the log's own clock otherwise).
    lat, lon, alt : ndarray, shape (k,)
        Degrees, degrees, m.
    vel_ned : ndarray, shape (k, 3)
        Ground velocity, m/s.
    waypoints : dict seq → (lat, lon, alt)
        Mission navigation waypoints (deg, deg, m).
    reached : list of (t, seq)
        Waypoint-reached events (s, sequence number), sorted.
    wind_ne : ndarray, shape (2,) or None
        Mean wind velocity (north, east; m/s, toward), if logged.
    cruise_ms : float or None
        Mission/waypoint speed (m/s), if logged.
    source : str
        The file read.
    """

    t: FloatArray
    lat: FloatArray
    lon: FloatArray
    alt: FloatArray
    vel_ned: FloatArray
    waypoints: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    reached: list[tuple[float, int]] = field(default_factory=list)
    wind_ne: FloatArray | None = None
    cruise_ms: float | None = None
    source: str = ""

    def __post_init__(self) -> None:
        n = np.asarray(self.t).size
        if n < 2:
            raise InputError(f"{self.source}: fewer than 2 position samples")
        order = np.argsort(self.t, kind="stable")
        arrays = {k: np.asarray(getattr(self, k), dtype=float)[order] for k in _SAMPLE_FIELDS}
        keep = np.concatenate([[True], np.diff(arrays["t"]) > 0])
        for k, a in arrays.items():
            object.__setattr__(self, k, a[keep])


def wind_from(speed_ms: float, from_deg: float) -> FloatArray:
    """Wind velocity (north, east) m/s of a wind of ``speed_ms`` blowing *from* ``from_deg``.

    The same arithmetic and check as :func:`uasnav.trajectory.features.wind_vector`; here the
    values come from a log's WIND message.

    Raises
    ------
    InputError
        If the speed is negative or either value is not finite.

    Examples
    --------
    >>> wind_from(2.0, 90.0).round(12).tolist()  # from the east: blows toward the west
    [-0.0, -2.0]
    """
    if not (np.isfinite(speed_ms) and np.isfinite(from_deg)) or speed_ms < 0:
        raise InputError(f"wind must be a finite speed ≥ 0 and direction, got {speed_ms}@{from_deg}")
    to = np.radians(from_deg + 180.0)
    return np.array([speed_ms * np.cos(to), speed_ms * np.sin(to)])


def flight_from_fixes(
    fixes: Sequence[tuple[float, ...]],
    path: str | os.PathLike[str],
    *,
    waypoints: dict[int, tuple[float, float, float]],
    reached: list[tuple[float, int]],
    wind: Sequence[FloatArray | tuple[float, float]],
    cruise_ms: float | None = None,
) -> FlightLog:
    """A :class:`FlightLog` from position fixes ``(t, lat, lon, alt, v_N, v_E, v_D)`` and events.

    ``wind`` holds the log's wind estimates (north, east; m/s): their mean becomes ``wind_ne``.

    Raises
    ------
    DataFormatError
        If there is no fix.
    """
    if not fixes:
        raise DataFormatError("no position fixes", path=str(path))
    a = np.array(fixes, dtype=np.float64)
    return FlightLog(
        t=a[:, 0],
        lat=a[:, 1],
        lon=a[:, 2],
        alt=a[:, 3],
        vel_ned=a[:, 4:7],
        waypoints=waypoints,
        reached=sorted(reached),
        wind_ne=np.mean(np.asarray(wind, dtype=np.float64), axis=0) if wind else None,
        cruise_ms=cruise_ms,
        source=str(path),
    )


def read_flight_csv(path: str | os.PathLike[str]) -> FlightLog:
    """Read a flight CSV: header ``t,lat,lon,alt,v_N,v_E,v_D`` (s, deg, deg, m, m/s NED), no mission.

    Other columns are ignored.

    Raises
    ------
    DataFormatError
        Empty file, missing column, a non-numeric or non-finite cell (names line and column).
    """
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    if not rows:
        raise DataFormatError("empty file", path=str(path))
    head = [h.strip() for h in rows[0]]
    missing = [c for c in FLIGHT_CSV_COLUMNS if c not in head]
    if missing:
        raise DataFormatError(
            f"missing column(s) {missing}; need {FLIGHT_CSV_COLUMNS}", path=str(path), line=1
        )
    idx = [head.index(c) for c in FLIGHT_CSV_COLUMNS]
    data = np.empty((len(rows) - 1, len(FLIGHT_CSV_COLUMNS)))
    for i, r in enumerate(rows[1:]):
        for j, k in enumerate(idx):
            try:
                data[i, j] = float(r[k])
            except (ValueError, IndexError):
                raise DataFormatError(
                    "not a number", path=str(path), line=i + 2, column=FLIGHT_CSV_COLUMNS[j]
                ) from None
    bad = ~np.isfinite(data)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise DataFormatError("NaN/inf", path=str(path), line=int(i) + 2, column=FLIGHT_CSV_COLUMNS[j])
    return FlightLog(
        t=data[:, 0], lat=data[:, 1], lon=data[:, 2], alt=data[:, 3], vel_ned=data[:, 4:7], source=str(path)
    )


__all__ = ["FLIGHT_CSV_COLUMNS", "FlightLog", "flight_from_fixes", "read_flight_csv", "wind_from"]
