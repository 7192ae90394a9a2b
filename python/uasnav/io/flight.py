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
The flight readers of binary logs salvage what is valid from a corrupt log (see
:func:`valid_fixes`).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from uasnav.errors import DataFormatError, InputError
from uasnav.geo.datum import HeightDatum
from uasnav.io._common import nothing_valid, report_corruption, salvage
from uasnav.io._quiet import LibraryOutput
from uasnav.io._text import csv_rows, numeric_rows, read_text, split_lines

FloatArray = NDArray[np.float64]

#: Columns of the flight CSV (s, deg, deg, m, then the NED ground velocity in m/s).
FLIGHT_CSV_COLUMNS = ("t", "lat", "lon", "alt", "v_N", "v_E", "v_D")

_SAMPLE_FIELDS = ("t", "lat", "lon", "alt", "vel_ned")


@dataclass(frozen=True)
class FlightLog:
    """Telemetry of one log.

    The constructor checks shapes and finiteness (:class:`~uasnav.errors.InputError` naming the
    field and sample), sorts the samples by time and drops repeated time stamps (the first
    sample of each time stamp is kept), so ``t`` is strictly increasing.

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
    alt_datum : HeightDatum
        What ``alt`` is measured from: AMSL for the log readers (ULog ``vehicle_global_position``
        / ``vehicle_gps_position.alt``, DataFlash ``GPS.Alt``, ``GLOBAL_POSITION_INT.alt``), not
        stated by a flight CSV (``unknown``).
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
    alt_datum: HeightDatum = HeightDatum.UNKNOWN

    def __post_init__(self) -> None:
        object.__setattr__(self, "alt_datum", HeightDatum(self.alt_datum))
        src = self.source or "flight log"
        arrays: dict[str, FloatArray] = {}
        for k in _SAMPLE_FIELDS:
            try:
                arrays[k] = np.asarray(getattr(self, k), dtype=np.float64)
            except (TypeError, ValueError):
                raise InputError(f"{src}: {k} is not numeric ({type(getattr(self, k)).__name__})") from None
        n = arrays["t"].size
        if n < 2:
            raise InputError(f"{src}: fewer than 2 position samples")
        for k, a in arrays.items():
            want = (n, 3) if k == "vel_ned" else (n,)
            if a.shape != want:
                raise InputError(f"{src}: {k} has shape {a.shape}, expected {want}")
            bad = np.flatnonzero(~np.all(np.isfinite(a.reshape(n, -1)), axis=1))
            if bad.size:
                raise InputError(f"{src}: non-finite {k} at sample {int(bad[0])}")
        order = np.argsort(arrays["t"], kind="stable")
        arrays = {k: a[order] for k, a in arrays.items()}
        keep = np.concatenate([[True], np.diff(arrays["t"]) > 0])
        for k, a in arrays.items():
            object.__setattr__(self, k, a[keep])
        if not isinstance(self.waypoints, Mapping):
            raise InputError(
                f"{src}: waypoints must map seq → (lat, lon, alt), got {type(self.waypoints).__name__}"
            )
        for seq, wp in self.waypoints.items():
            try:
                wpa = np.asarray(wp, dtype=np.float64)
            except (TypeError, ValueError):
                wpa = np.full(1, np.nan)
            if wpa.shape != (3,) or not np.all(np.isfinite(wpa)):
                raise InputError(f"{src}: waypoint {seq} is not a finite (lat, lon, alt): {wp}")
        if self.wind_ne is not None:
            try:
                w = np.asarray(self.wind_ne, dtype=np.float64)
            except (TypeError, ValueError):
                w = np.full(1, np.nan)
            if w.shape != (2,) or not np.all(np.isfinite(w)):
                raise InputError(f"{src}: wind_ne must be a finite (north, east) pair, got {self.wind_ne!r}")
            object.__setattr__(self, "wind_ne", w)
        if self.cruise_ms is not None:
            ok = isinstance(self.cruise_ms, int | float | np.number) and not isinstance(self.cruise_ms, bool)
            if not (ok and np.isfinite(self.cruise_ms) and self.cruise_ms >= 0):
                shown = float(self.cruise_ms) if ok else self.cruise_ms
                raise InputError(f"{src}: cruise speed must be a finite number ≥ 0 m/s, got {shown!r}")


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


#: Bounds of a plausible position fix (deg, deg, m, m/s); a fix outside is a corrupt record.
FIX_LIMITS = {"lat": (-90.0, 90.0), "lon": (-180.0, 180.0), "alt": (-1e3, 1e5), "vel": (-1e3, 1e3)}


def valid_fixes(a: FloatArray) -> NDArray[np.bool_]:
    """Mask of the valid rows of fixes ``(t, lat, lon, alt, v_N, v_E, v_D)`` (k, 7) of a log
    without checksums: finite, within :data:`FIX_LIMITS`, and in time order (the longest run
    of rows in time order is kept; see :func:`uasnav.io._common.salvage`)."""
    return salvage(
        a[:, 0],
        {"lat": a[:, 1], "lon": a[:, 2], "alt": a[:, 3], "vel": a[:, 4:7]},
        FIX_LIMITS,
    )


def flight_from_fixes(
    fixes: Sequence[tuple[float, ...]] | FloatArray,
    path: str | os.PathLike[str],
    *,
    waypoints: dict[int, tuple[float, float, float]],
    reached: list[tuple[float, int]],
    wind: Sequence[FloatArray | tuple[float, float]],
    cruise_ms: float | None = None,
    decoder: LibraryOutput | None = None,
    alt_datum: HeightDatum = HeightDatum.AMSL,
) -> FlightLog:
    """A :class:`FlightLog` from position fixes ``(t, lat, lon, alt, v_N, v_E, v_D)`` (rows of a
    sequence or an array (k, 7)) and events.

    ``alt_datum`` is the heights' datum (the log readers': AMSL). ``wind`` holds the log's wind
    estimates (north, east; m/s): their mean becomes ``wind_ne``.
    Corrupt fixes (:func:`valid_fixes`) are dropped; if any were, or the ``decoder`` reported
    problems, one :class:`~uasnav.errors.CorruptDataWarning` says so.

    Raises
    ------
    DataFormatError
        If there is no fix, or fewer than 2 valid ones.
    """
    src = str(path)
    if len(fixes) == 0:
        raise DataFormatError("no position fixes", path=src)
    a = np.array(fixes, dtype=np.float64)
    keep = valid_fixes(a)
    if keep.sum() < 2:
        raise nothing_valid(src, "position fix", a.shape[0], decoder)
    report_corruption(src, decoder, int((~keep).sum()), a.shape[0], "position fix")
    a = a[keep]
    try:
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
            source=src,
            alt_datum=alt_datum,
        )
    except InputError as e:
        raise DataFormatError(str(e).removeprefix(f"{src}: "), path=src) from None


def read_flight_csv(path: str | os.PathLike[str]) -> FlightLog:
    """Read a flight CSV: header ``t,lat,lon,alt,v_N,v_E,v_D`` (s, deg, deg, m, m/s NED), no mission.

    Other columns are ignored.

    Raises
    ------
    DataFormatError
        Empty file, missing column, fewer than 2 rows, a non-numeric, missing or non-finite
        cell, a latitude/longitude/altitude outside :data:`FIX_LIMITS`, malformed CSV or text
        that is not UTF-8 (names line and column).
    """
    source = str(path)
    lines = split_lines(read_text(path))
    first = next(csv_rows(lines, 0, source), None)
    if first is None:
        raise DataFormatError("empty file", path=source)
    header_line, cells = first
    head = [h.strip() for h in cells]
    missing = [c for c in FLIGHT_CSV_COLUMNS if c not in head]
    if missing:
        raise DataFormatError(
            f"missing column(s) {missing}; need {FLIGHT_CSV_COLUMNS}", path=source, line=header_line
        )
    data, row_lines = numeric_rows(lines, header_line, source, head, FLIGHT_CSV_COLUMNS)
    for j, name in enumerate(FLIGHT_CSV_COLUMNS[1:4], start=1):
        lo, hi = FIX_LIMITS[name]
        out = np.flatnonzero((data[:, j] < lo) | (data[:, j] > hi))
        if out.size:
            raise DataFormatError(
                f"{float(data[out[0], j])!r} is outside [{lo:g}, {hi:g}]",
                path=source,
                line=row_lines[out[0]],
                column=name,
            )
    return FlightLog(
        t=data[:, 0], lat=data[:, 1], lon=data[:, 2], alt=data[:, 3], vel_ned=data[:, 4:7], source=str(path)
    )


__all__ = [
    "FIX_LIMITS",
    "FLIGHT_CSV_COLUMNS",
    "FlightLog",
    "flight_from_fixes",
    "read_flight_csv",
    "valid_fixes",
    "wind_from",
]
