"""The flight model: :class:`Flight`, what one log tells about one flight, and the sensor series
it is made of.

A :class:`Flight` holds the sensors the GNSS/INS filter integrates (IMU, GNSS, barometer,
magnetometer), the references to compare with (the autopilot's own estimate, the truth of a
simulated flight), the position telemetry the autopilot logged (``track``) and the mission's
events (navigation waypoints, waypoint-reached events, wind, cruise speed). A log's
:class:`~uasnav.io.logfile.LogFile` gives two of them, each decoding only what it needs:
``nav`` (the sensors and the estimate, for :func:`uasnav.ins.run`) and ``flight`` (the telemetry
and the mission, for :mod:`uasnav.trajectory`).

Every series has its own time stamps (s, one clock per flight). Units are SI; latitude and
longitude in degrees; heights in metres with their datum (``alt_datum``, :mod:`uasnav.geo.datum`:
the readers give GNSS fixes and the autopilot's estimate in one datum, ellipsoidal where the
log allows; the telemetry track in the datum the autopilot logged, AMSL), any datum for the
barometer (the filter tracks the offset). Frames: body FRD, navigation NED. The constructors
check shapes, finiteness and strictly increasing time and name what is wrong.

This module imports no format reader (the readers of :mod:`uasnav.io.formats` import it), so it
cannot close an import circle. The readers of binary logs salvage what is valid from a corrupt
log (see :func:`valid_fixes`).
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav.errors import DataFormatError, InputError
from uasnav.geo.datum import HeightDatum
from uasnav.imu import ImuLog, check_time
from uasnav.io._common import nothing_valid, report_corruption, salvage
from uasnav.io._quiet import LibraryOutput

FloatArray = NDArray[np.float64]
#: Largest |height| of a GNSS fix (m) taken as data: the nav filter's own bound (no UAS flies
#: 100 km above or below the ellipsoid; 1e308 m is a corrupt cell).
MAX_GNSS_HEIGHT_M = 1e5

_TRACK_FIELDS = ("t", "lat", "lon", "alt", "vel_ned")


def _arr(owner: str, name: str, value: ArrayLike, shape_tail: tuple[int, ...], n: int | None) -> FloatArray:
    try:
        a = np.ascontiguousarray(np.asarray(value, dtype=np.float64))
    except (TypeError, ValueError):
        raise InputError(f"{owner}.{name}: expected numbers, got {type(value).__name__}") from None
    want_ndim = 1 + len(shape_tail)
    if a.ndim != want_ndim or a.shape[1:] != shape_tail or (n is not None and a.shape[0] != n):
        want = ("n" if n is None else str(n),) + tuple(str(k) for k in shape_tail)
        raise InputError(f"{owner}.{name}: expected shape ({', '.join(want)}), got {a.shape}")
    bad = np.flatnonzero(~np.all(np.isfinite(a.reshape(a.shape[0], math.prod(shape_tail))), axis=1))
    if bad.size:
        raise InputError(f"{owner}.{name}: non-finite value at row {int(bad[0])}")
    return a


def _time(owner: str, value: ArrayLike, min_len: int = 1) -> FloatArray:
    t = _arr(owner, "t", value, (), None)
    if t.size < min_len:
        raise InputError(f"{owner}.t: need at least {min_len} samples, got {t.size}")
    check_time(t, f"{owner}.t")
    return t


@dataclass(frozen=True)
class GnssData:
    """GNSS position/velocity fixes (the GNSS CSV layout ``t,lat,lon,alt,vn,ve,vd,h_acc,v_acc,s_acc``).

    Attributes
    ----------
    t : ndarray, shape (m,)
        Fix time, s.
    lat, lon : ndarray, shape (m,)
        Latitude, longitude, degrees (WGS-84).
    alt : ndarray, shape (m,)
        Height, m, in the datum ``alt_datum`` (ellipsoidal when the receiver reports it).
    vel : ndarray, shape (m, 3)
        Velocity north, east, down, m/s.
    h_acc, v_acc : ndarray, shape (m,)
        Reported 1σ horizontal and vertical position accuracy, m (> 0).
    s_acc : ndarray, shape (m,)
        Reported 1σ speed accuracy, m/s (> 0).
    alt_datum : HeightDatum
        What ``alt`` is measured from (:mod:`uasnav.geo.datum`); ``geoid_undulation_m`` the
        receiver's own geoid undulation N = ellipsoidal − AMSL height (m) when it reports both.
    """

    t: FloatArray
    lat: FloatArray
    lon: FloatArray
    alt: FloatArray
    vel: FloatArray
    h_acc: FloatArray
    v_acc: FloatArray
    s_acc: FloatArray
    alt_datum: HeightDatum = HeightDatum.ELLIPSOID
    geoid_undulation_m: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "alt_datum", HeightDatum(self.alt_datum))
        t = _time("gnss", self.t)
        n = t.size
        object.__setattr__(self, "t", t)
        for k in ("lat", "lon", "alt", "h_acc", "v_acc", "s_acc"):
            object.__setattr__(self, k, _arr("gnss", k, getattr(self, k), (), n))
        object.__setattr__(self, "vel", _arr("gnss", "vel", self.vel, (3,), n))
        if np.any(np.abs(self.lat) > 90.0):
            raise InputError(f"gnss.lat: outside ±90° at row {int(np.argmax(np.abs(self.lat) > 90))}")
        bad_lon = (self.lon < -180.0) | (self.lon > 360.0)  # 0…360° east is a convention too
        if np.any(bad_lon):
            row = int(np.argmax(bad_lon))
            raise InputError(f"gnss.lon: {self.lon[row]:g}° is outside -180…360° at row {row}")
        if np.any(np.abs(self.alt) > MAX_GNSS_HEIGHT_M):
            row = int(np.argmax(np.abs(self.alt) > MAX_GNSS_HEIGHT_M))
            raise InputError(f"gnss.alt: {self.alt[row]:g} m is beyond ±{MAX_GNSS_HEIGHT_M:g} m at row {row}")
        for k in ("h_acc", "v_acc", "s_acc"):
            a = getattr(self, k)
            if np.any(a <= 0):
                raise InputError(f"gnss.{k}: accuracy must be > 0 (row {int(np.argmax(a <= 0))})")

    @property
    def n(self) -> int:
        """Number of fixes."""
        return int(self.t.size)

    def select(self, keep: NDArray[np.bool_]) -> GnssData:
        """The fixes where ``keep`` is true."""
        return GnssData(
            *(getattr(self, k)[keep] for k in ("t", "lat", "lon", "alt", "vel", "h_acc", "v_acc", "s_acc")),
            alt_datum=self.alt_datum,
            geoid_undulation_m=self.geoid_undulation_m,
        )


@dataclass(frozen=True)
class BaroData:
    """Barometric altitude: ``t`` (s), ``alt`` (m, any datum)."""

    t: FloatArray
    alt: FloatArray

    def __post_init__(self) -> None:
        t = _time("baro", self.t)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "alt", _arr("baro", "alt", self.alt, (), t.size))


@dataclass(frozen=True)
class MagData:
    """Magnetometer: ``t`` (s), ``field`` (k, 3) in the body frame (any unit)."""

    t: FloatArray
    field: FloatArray

    def __post_init__(self) -> None:
        t = _time("mag", self.t)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "field", _arr("mag", "field", self.field, (3,), t.size))


@dataclass(frozen=True)
class Trajectory:
    """A navigation solution to compare with: the autopilot's estimate or a simulation's truth.

    Attributes
    ----------
    t : ndarray, shape (k,)
        Time, s.
    lat, lon, alt : ndarray, shape (k,)
        Degrees, degrees, m (WGS-84; the height in the datum ``alt_datum``).
    vel : ndarray, shape (k, 3) or None
        NED velocity, m/s.
    euler_deg : ndarray, shape (k, 3) or None
        Roll, pitch, yaw (3-2-1), degrees.
    name : str
        Where it comes from (e.g. ``"ArduPilot EKF (NKF1/AHR2)"``, ``"truth"``).
    alt_datum : HeightDatum
        What ``alt`` is measured from (:mod:`uasnav.geo.datum`). A reader gives the autopilot's
        estimate in the datum of its GNSS fixes, so that the two compare directly.
    """

    t: FloatArray
    lat: FloatArray
    lon: FloatArray
    alt: FloatArray
    vel: FloatArray | None = None
    euler_deg: FloatArray | None = None
    name: str = "reference"
    alt_datum: HeightDatum = HeightDatum.ELLIPSOID
    extra: dict[str, FloatArray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "alt_datum", HeightDatum(self.alt_datum))
        t = _time(self.name, self.t, 2)
        n = t.size
        object.__setattr__(self, "t", t)
        for k in ("lat", "lon", "alt"):
            object.__setattr__(self, k, _arr(self.name, k, getattr(self, k), (), n))
        if self.vel is not None:
            object.__setattr__(self, "vel", _arr(self.name, "vel", self.vel, (3,), n))
        if self.euler_deg is not None:
            object.__setattr__(self, "euler_deg", _arr(self.name, "euler_deg", self.euler_deg, (3,), n))


@dataclass(frozen=True)
class Flight:
    """One flight (see the module docs): the parts a log carries, the others None or empty.

    Attributes
    ----------
    imu : ImuLog or None
        The IMU the filter integrates (body FRD; gyro rad/s, accel m/s², temp °C).
    gnss : GnssData or None
        GNSS fixes.
    baro, mag : BaroData, MagData or None
        Barometer and magnetometer, if logged.
    reference : Trajectory or None
        The autopilot's own estimate, in the datum of the GNSS fixes.
    truth : Trajectory or None
        Ground truth (simulated flights).
    imus : dict of str to ImuLog
        Every IMU of the log (for redundant-IMU fusion), including ``imu``.
    airborne : (float, float) or None
        The airborne interval (s) when known.
    meta : dict
        Source, format, notes (e.g. the IMU rate's limits).
    track : Trajectory or None
        The position telemetry as logged (ULog ``vehicle_global_position``, DataFlash ``GPS``,
        ``GLOBAL_POSITION_INT``, a flight CSV), time in the log's own clock (wall clock for
        .tlog), NED ground velocity ``vel``; its datum ``track.alt_datum`` (AMSL for the log
        readers, ``unknown`` for a flight CSV). :attr:`t`, :attr:`lat`, :attr:`lon`,
        :attr:`alt`, :attr:`vel_ned` and :attr:`alt_datum` read it.
    waypoints : dict seq → (lat, lon, alt)
        Mission navigation waypoints (deg, deg, m).
    reached : list of (t, seq)
        Waypoint-reached events (s, sequence number), sorted.
    wind_ne : ndarray, shape (2,) or None
        Mean wind velocity (north, east; m/s, toward), if logged.
    cruise_ms : float or None
        Mission/waypoint speed (m/s), if logged.
    source : str
        The file read (``meta["source"]`` when not given).
    """

    imu: ImuLog | None = None
    gnss: GnssData | None = None
    baro: BaroData | None = None
    mag: MagData | None = None
    reference: Trajectory | None = None
    truth: Trajectory | None = None
    imus: dict[str, ImuLog] = field(default_factory=dict)
    airborne: tuple[float, float] | None = None
    meta: dict[str, Any] = field(default_factory=dict)
    track: Trajectory | None = None
    waypoints: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    reached: list[tuple[float, int]] = field(default_factory=list)
    wind_ne: FloatArray | None = None
    cruise_ms: float | None = None
    source: str = ""

    def __post_init__(self) -> None:
        if self.imu is not None and not isinstance(self.imu, ImuLog):
            raise InputError(f"flight.imu: expected an ImuLog, got {type(self.imu).__name__}")
        if self.gnss is not None and not isinstance(self.gnss, GnssData):
            raise InputError(f"flight.gnss: expected GnssData, got {type(self.gnss).__name__}")
        if self.track is not None and not isinstance(self.track, Trajectory):
            raise InputError(f"flight.track: expected a Trajectory, got {type(self.track).__name__}")
        if not self.source and isinstance(self.meta, Mapping):
            object.__setattr__(self, "source", str(self.meta.get("source", "")))
        src = self.source or "flight log"
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

    @classmethod
    def from_track(
        cls,
        t: ArrayLike,
        lat: ArrayLike,
        lon: ArrayLike,
        alt: ArrayLike,
        vel_ned: ArrayLike,
        *,
        alt_datum: HeightDatum = HeightDatum.UNKNOWN,
        source: str = "",
        **parts: Any,
    ) -> Flight:
        """A flight from its position telemetry: time (s), latitude, longitude (deg), height
        (m, in ``alt_datum``) and NED ground velocity (k, 3) m/s; ``parts`` are the other fields
        (``waypoints``, ``reached``, ``wind_ne``, ``cruise_ms`` …).

        The samples are sorted by time and repeated time stamps dropped (the first sample of each
        time stamp is kept), so the track's ``t`` is strictly increasing.

        Raises
        ------
        InputError
            A field that is not numeric, of the wrong shape or not finite (naming the field and
            sample); fewer than 2 samples.
        """
        src = source or "flight log"
        arrays: dict[str, FloatArray] = {}
        for k, v in zip(_TRACK_FIELDS, (t, lat, lon, alt, vel_ned), strict=True):
            try:
                arrays[k] = np.asarray(v, dtype=np.float64)
            except (TypeError, ValueError):
                raise InputError(f"{src}: {k} is not numeric ({type(v).__name__})") from None
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
        keep = np.concatenate([[True], np.diff(arrays["t"][order]) > 0])
        a = {k: v[order][keep] for k, v in arrays.items()}
        track = Trajectory(
            a["t"],
            a["lat"],
            a["lon"],
            a["alt"],
            a["vel_ned"],
            name="telemetry",
            alt_datum=HeightDatum(alt_datum),
        )
        return cls(track=track, source=source, **parts)

    def _track(self) -> Trajectory:
        if self.track is None:
            raise InputError(f"{self.source or 'flight'}: no position telemetry (read the log's flight view)")
        return self.track

    @property
    def t(self) -> FloatArray:
        """Telemetry time, s (strictly increasing)."""
        return self._track().t

    @property
    def lat(self) -> FloatArray:
        """Telemetry latitude, deg."""
        return self._track().lat

    @property
    def lon(self) -> FloatArray:
        """Telemetry longitude, deg."""
        return self._track().lon

    @property
    def alt(self) -> FloatArray:
        """Telemetry height, m, in :attr:`alt_datum`."""
        return self._track().alt

    @property
    def vel_ned(self) -> FloatArray:
        """Telemetry ground velocity (k, 3), NED m/s."""
        vel = self._track().vel
        assert vel is not None  # from_track always sets it
        return vel

    @property
    def alt_datum(self) -> HeightDatum:
        """What the telemetry's :attr:`alt` is measured from."""
        return self._track().alt_datum

    def with_imu(self, imu: ImuLog, name: str | None = None) -> Flight:
        """The same flight integrating another IMU (e.g. a redundant-IMU fusion)."""
        meta = dict(self.meta)
        if name:
            meta["imu"] = name
        return replace(self, imu=imu, meta=meta)

    def between(self, t0: float, t1: float) -> Flight:
        """The flight cut to ``t0 ≤ t ≤ t1`` (every sensor stream and reference; the telemetry
        track and the mission events are kept whole)."""
        if self.imu is None or self.gnss is None:
            raise InputError(f"flight.between({t0}, {t1}): the flight has no IMU and GNSS to cut")

        def cut(t: FloatArray) -> NDArray[np.bool_]:
            return (t >= t0) & (t <= t1)

        g = self.gnss.select(cut(self.gnss.t))
        if g.n == 0:
            raise InputError(f"flight.between({t0}, {t1}): no GNSS fix in that interval")
        baro = BaroData(self.baro.t[cut(self.baro.t)], self.baro.alt[cut(self.baro.t)]) if self.baro else None
        mag = MagData(self.mag.t[cut(self.mag.t)], self.mag.field[cut(self.mag.t)]) if self.mag else None
        if baro is not None and baro.t.size == 0:
            baro = None
        if mag is not None and mag.t.size == 0:
            mag = None
        return replace(
            self,
            imu=self.imu.between(t0, t1),
            gnss=g,
            baro=baro,
            mag=mag,
            reference=_cut_traj(self.reference, t0, t1),
            truth=_cut_traj(self.truth, t0, t1),
            imus={k: v.between(t0, t1) for k, v in self.imus.items()},
            meta=dict(self.meta),
        )


def _cut_traj(tr: Trajectory | None, t0: float, t1: float) -> Trajectory | None:
    if tr is None:
        return None
    k = (tr.t >= t0) & (tr.t <= t1)
    if k.sum() < 2:
        return None
    return Trajectory(
        tr.t[k],
        tr.lat[k],
        tr.lon[k],
        tr.alt[k],
        None if tr.vel is None else tr.vel[k],
        None if tr.euler_deg is None else tr.euler_deg[k],
        tr.name,
        tr.alt_datum,
        {n: v[k] for n, v in tr.extra.items()},
    )


def strictly_increasing(t: FloatArray) -> NDArray[np.bool_]:
    """Keep the first of repeated/decreasing time stamps."""
    keep = np.ones(t.size, dtype=bool)
    last = -np.inf
    for i, x in enumerate(t):
        if x > last:
            last = x
        else:
            keep[i] = False
    return keep


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
) -> Flight:
    """A :class:`Flight` (its telemetry track and mission events) from position fixes
    ``(t, lat, lon, alt, v_N, v_E, v_D)`` (rows of a sequence or an array (k, 7)) and events.

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
        return Flight.from_track(
            a[:, 0],
            a[:, 1],
            a[:, 2],
            a[:, 3],
            a[:, 4:7],
            waypoints=waypoints,
            reached=sorted(reached),
            wind_ne=np.mean(np.asarray(wind, dtype=np.float64), axis=0) if wind else None,
            cruise_ms=cruise_ms,
            source=src,
            alt_datum=alt_datum,
        )
    except InputError as e:
        raise DataFormatError(str(e).removeprefix(f"{src}: "), path=src) from None


__all__ = [
    "FIX_LIMITS",
    "BaroData",
    "Flight",
    "GnssData",
    "MagData",
    "Trajectory",
    "flight_from_fixes",
    "strictly_increasing",
    "valid_fixes",
    "wind_from",
]
