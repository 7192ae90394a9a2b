"""What the GNSS/INS filter flies on: IMU, GNSS, barometer, magnetometer, and the references
to compare with (the autopilot's own estimate, or the truth of a simulated flight).

Every series has its own time stamps (s, one clock per flight). Units are SI; latitude and
longitude in degrees; heights in metres with their datum (``alt_datum``, :mod:`uasnav.geo.datum`:
the readers give GNSS fixes and the autopilot's estimate in one datum, ellipsoidal where the
log allows), any datum for the barometer (the filter tracks the offset). Frames: body FRD, navigation NED. The
constructors check shapes, finiteness and strictly increasing time and name what is wrong.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav.errors import InputError
from uasnav.geo.datum import HeightDatum
from uasnav.imu import ImuLog, check_time

FloatArray = NDArray[np.float64]
#: Largest |height| of a GNSS fix (m) taken as data: the nav filter's own bound (no UAS flies
#: 100 km above or below the ellipsoid; 1e308 m is a corrupt cell).
MAX_GNSS_HEIGHT_M = 1e5


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
    """One flight for :func:`uasnav.ins.run`.

    Attributes
    ----------
    imu : ImuLog
        The IMU the filter integrates (body FRD; gyro rad/s, accel m/s², temp °C).
    gnss : GnssData
        GNSS fixes.
    baro, mag : BaroData, MagData or None
        Barometer and magnetometer, if logged.
    reference : Trajectory or None
        The autopilot's own estimate in the same log.
    truth : Trajectory or None
        Ground truth (simulated flights).
    imus : dict of str to ImuLog
        Every IMU of the log (for redundant-IMU fusion), including ``imu``.
    airborne : (float, float) or None
        The airborne interval (s) when known.
    meta : dict
        Source, format, notes (e.g. the IMU rate's limits).
    """

    imu: ImuLog
    gnss: GnssData
    baro: BaroData | None = None
    mag: MagData | None = None
    reference: Trajectory | None = None
    truth: Trajectory | None = None
    imus: dict[str, ImuLog] = field(default_factory=dict)
    airborne: tuple[float, float] | None = None
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not isinstance(self.imu, ImuLog):
            raise InputError(f"flight.imu: expected an ImuLog, got {type(self.imu).__name__}")
        if not isinstance(self.gnss, GnssData):
            raise InputError(f"flight.gnss: expected GnssData, got {type(self.gnss).__name__}")

    def with_imu(self, imu: ImuLog, name: str | None = None) -> Flight:
        """The same flight integrating another IMU (e.g. a redundant-IMU fusion)."""
        meta = dict(self.meta)
        if name:
            meta["imu"] = name
        return Flight(
            imu, self.gnss, self.baro, self.mag, self.reference, self.truth, self.imus, self.airborne, meta
        )

    def between(self, t0: float, t1: float) -> Flight:
        """The flight cut to ``t0 ≤ t ≤ t1`` (every stream)."""

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
        return Flight(
            self.imu.between(t0, t1),
            g,
            baro,
            mag,
            _cut_traj(self.reference, t0, t1),
            _cut_traj(self.truth, t0, t1),
            {k: v.between(t0, t1) for k, v in self.imus.items()},
            self.airborne,
            dict(self.meta),
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
