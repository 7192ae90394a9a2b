"""What the GNSS/INS filter flies on: IMU, GNSS, barometer, magnetometer, and the references
to compare with (the autopilot's own estimate, or the truth of a simulated flight).

Every series has its own time stamps (s, one clock per flight). Units are SI; latitude and
longitude in degrees; heights are WGS-84 ellipsoidal (m) for GNSS and references, any datum for
the barometer (the filter tracks the offset). Frames: body FRD, navigation NED. The
constructors check shapes, finiteness and strictly increasing time and name what is wrong.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav.errors import InputError
from uasnav.imu import ImuLog, check_time

FloatArray = NDArray[np.float64]


def _arr(owner: str, name: str, value: ArrayLike, shape_tail: tuple[int, ...], n: int | None) -> FloatArray:
    try:
        a = np.ascontiguousarray(np.asarray(value, dtype=np.float64))
    except (TypeError, ValueError):
        raise InputError(f"{owner}.{name}: expected numbers, got {type(value).__name__}") from None
    want_ndim = 1 + len(shape_tail)
    if a.ndim != want_ndim or a.shape[1:] != shape_tail or (n is not None and a.shape[0] != n):
        want = ("n" if n is None else str(n),) + tuple(str(k) for k in shape_tail)
        raise InputError(f"{owner}.{name}: expected shape ({', '.join(want)}), got {a.shape}")
    bad = np.flatnonzero(~np.all(np.isfinite(a.reshape(a.shape[0], -1)), axis=1))
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
        Ellipsoidal height, m.
    vel : ndarray, shape (m, 3)
        Velocity north, east, down, m/s.
    h_acc, v_acc : ndarray, shape (m,)
        Reported 1σ horizontal and vertical position accuracy, m (> 0).
    s_acc : ndarray, shape (m,)
        Reported 1σ speed accuracy, m/s (> 0).
    """

    t: FloatArray
    lat: FloatArray
    lon: FloatArray
    alt: FloatArray
    vel: FloatArray
    h_acc: FloatArray
    v_acc: FloatArray
    s_acc: FloatArray

    def __post_init__(self) -> None:
        t = _time("gnss", self.t)
        n = t.size
        object.__setattr__(self, "t", t)
        for k in ("lat", "lon", "alt", "h_acc", "v_acc", "s_acc"):
            object.__setattr__(self, k, _arr("gnss", k, getattr(self, k), (), n))
        object.__setattr__(self, "vel", _arr("gnss", "vel", self.vel, (3,), n))
        if np.any(np.abs(self.lat) > 90.0):
            raise InputError(f"gnss.lat: outside ±90° at row {int(np.argmax(np.abs(self.lat) > 90))}")
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
            *(getattr(self, k)[keep] for k in ("t", "lat", "lon", "alt", "vel", "h_acc", "v_acc", "s_acc"))
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
        Degrees, degrees, m (ellipsoidal for truth; the autopilot's datum for references,
        see ``alt_datum``).
    vel : ndarray, shape (k, 3) or None
        NED velocity, m/s.
    euler_deg : ndarray, shape (k, 3) or None
        Roll, pitch, yaw (3-2-1), degrees.
    name : str
        Where it comes from (e.g. ``"ArduPilot EKF (NKF1/AHR2)"``, ``"truth"``).
    alt_datum : str
        ``"ellipsoid"`` or ``"amsl"`` (vertical differences are then only meaningful after
        removing the mean).
    """

    t: FloatArray
    lat: FloatArray
    lon: FloatArray
    alt: FloatArray
    vel: FloatArray | None = None
    euler_deg: FloatArray | None = None
    name: str = "reference"
    alt_datum: str = "ellipsoid"
    extra: dict[str, FloatArray] = field(default_factory=dict)

    def __post_init__(self) -> None:
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


# ---------------------------------------------------------------------------------------------
# Per-format extraction


#: ArduPilot's GPS message has no accuracy fields in older logs: σ_H = HDOP × this UERE (m),
#: σ_V = 1.5 σ_H, and the speed accuracy below. Stated, not measured: a u-blox receiver with
#: HDOP ≈ 1.5 typically reaches 1–3 m.
ARDUPILOT_UERE_M = 1.0
ARDUPILOT_SPEED_ACC_M_S = 0.3
#: ArduPilot logs a GPS message when it arrives; the fix is valid this long before (s): the
#: autopilot's own default ``EKF_GPS_DELAY`` / ``GPS_DELAY_MS`` of 220 ms.
ARDUPILOT_GPS_DELAY_S = 0.22


def _pick(
    tables: dict[str, dict[str, FloatArray]], names: tuple[str, ...]
) -> tuple[str, dict[str, FloatArray]] | None:
    for n in names:
        if n in tables and tables[n]["t"].size >= 2:
            return n, tables[n]
    return None


def _strictly_increasing(t: FloatArray) -> NDArray[np.bool_]:
    """Keep the first of repeated/decreasing time stamps."""
    keep = np.ones(t.size, dtype=bool)
    last = -np.inf
    for i, x in enumerate(t):
        if x > last:
            last = x
        else:
            keep[i] = False
    return keep


def _dataflash_declination_meta(path: Any, gp: dict[str, FloatArray], first: int) -> dict[str, Any]:
    """``declination_deg``/``declination_source`` from ``PARM`` ``COMPASS_DEC`` (radians) when
    the autopilot used it (``COMPASS_AUTODEC`` 0: with auto-declination on it takes its own
    table's value at run time and the logged parameter is not that value), and ``utc_year``
    (decimal year) from the ``GPS`` week and time of week of fix ``first``."""
    from pathlib import Path

    from uasnav.io._mavlink import messages, reading
    from uasnav.io.gpstime import decimal_year, gps_week_ms_to_utc

    p = Path(path)
    params: dict[str, float] = {}
    with reading(p) as (conn, _):
        for m in messages(conn, ["PARM"], p, "DataFlash"):
            name = str(m.Name).rstrip("\x00")
            if name in ("COMPASS_DEC", "COMPASS_AUTODEC"):
                params[name] = float(m.Value)  # the last value logged wins
    meta: dict[str, Any] = {}
    dec = params.get("COMPASS_DEC")
    if dec is not None and math.isfinite(dec) and params.get("COMPASS_AUTODEC", 0.0) == 0.0:
        meta["declination_deg"] = math.degrees(dec)
        meta["declination_source"] = "log: PARM COMPASS_DEC (COMPASS_AUTODEC = 0)"
    week = gp.get("GWk", gp.get("Week"))
    tow = gp.get("GMS", gp.get("TimeMS"))
    if week is not None and tow is not None:
        w, ms = float(week[first]), float(tow[first])
        if math.isfinite(w) and math.isfinite(ms) and 1000 < w < 10000 and 0 <= ms < 604_800_000:
            meta["utc_year"] = decimal_year(gps_week_ms_to_utc(w, ms))
    return meta


def read_dataflash_nav(path: str | Any, imu: str | None = None) -> Flight:
    """Navigation data of an ArduPilot DataFlash log: every IMU (``IMU``/``IMU2``/``IMU3``
    with temperature), ``GPS`` (fixes with ``Status`` ≥ 3; time from its ``T`` field, the
    log clock, when ``TimeMS`` is GPS time of week), ``BARO`` (``Alt``), ``MAG`` (field minus
    nothing: the logged ``MagX/Y/Z`` are already offset-corrected), and the autopilot's
    estimate from ``XKF1``/``NKF1``/``EKF1`` (``PN/PE/PD`` from the origin, taken as the first
    3-D fix, ``VN/VE/VD``, ``Roll/Pitch/Yaw``), else ``AHR2``.

    Heights are the GPS ``Alt`` (above mean sea level: older logs carry no ellipsoidal height;
    the filter only needs one consistent datum). Accuracies from HDOP (see
    :data:`ARDUPILOT_UERE_M`); fix times moved back by the GPS delay
    (:data:`ARDUPILOT_GPS_DELAY_S`).

    Raises
    ------
    DataFormatError
        No IMU, no GPS message, or fewer than 2 fixes with ``Status`` ≥ 3 (named).
    """
    from uasnav.errors import DataFormatError
    from uasnav.io.dataflash import read_dataflash, read_dataflash_messages

    imus = read_dataflash(path)
    tables = read_dataflash_messages(path, ["GPS", "BARO", "MAG", "XKF1", "NKF1", "EKF1", "AHR2", "ATT"])
    if "GPS" not in tables:
        raise DataFormatError(
            "no GPS message: the GNSS/INS filter needs GNSS fixes", path=str(path), column="GPS"
        )
    gp = tables["GPS"]
    t_field = "T" if "T" in gp and np.all(np.isfinite(gp["T"])) and gp["T"].max() > 0 else None
    t = gp["T"] * 1e-3 if t_field else gp["t"]
    status = gp.get("Status", np.full(t.size, 3.0))
    ok = (status >= 3) & np.isfinite(gp["Lat"]) & np.isfinite(gp["Lng"]) & (np.abs(gp["Lat"]) > 1e-6)
    t, ok = t[ok], np.flatnonzero(ok)
    keep = _strictly_increasing(t)
    t, ok = t[keep], ok[keep]
    if t.size < 2:
        raise DataFormatError(
            "GPS: fewer than 2 fixes with Status >= 3 (3-D fix)", path=str(path), column="GPS.Status"
        )
    spd, crs = gp["Spd"][ok], np.radians(gp["GCrs"][ok])
    vz = gp["VZ"][ok] if "VZ" in gp else np.zeros(t.size)
    hdop = gp["HDop"][ok] if "HDop" in gp else np.full(t.size, 1.5)
    h_acc = np.maximum(np.nan_to_num(hdop, nan=5.0), 0.5) * ARDUPILOT_UERE_M
    gnss = GnssData(
        t - ARDUPILOT_GPS_DELAY_S,
        gp["Lat"][ok],
        gp["Lng"][ok],
        gp["Alt"][ok],
        np.column_stack([spd * np.cos(crs), spd * np.sin(crs), vz]),
        h_acc,
        1.5 * h_acc,
        np.full(t.size, ARDUPILOT_SPEED_ACC_M_S),
    )
    baro = None
    if "BARO" in tables and tables["BARO"]["t"].size >= 2:
        b = tables["BARO"]
        k = _strictly_increasing(b["t"]) & np.isfinite(b["Alt"])
        baro = BaroData(b["t"][k], b["Alt"][k])
    mag = None
    if "MAG" in tables and tables["MAG"]["t"].size >= 2:
        m = tables["MAG"]
        k = _strictly_increasing(m["t"])
        fld = np.column_stack([m["MagX"], m["MagY"], m["MagZ"]])[k]
        k2 = np.all(np.isfinite(fld), axis=1) & (np.linalg.norm(fld, axis=1) > 0)
        mag = MagData(m["t"][k][k2], fld[k2])
    ref = None
    ekf = _pick(tables, ("XKF1", "NKF1", "EKF1"))
    if ekf is not None:
        name, e = ekf
        lat0, lon0, alt0 = float(gnss.lat[0]), float(gnss.lon[0]), float(gnss.alt[0])
        s2 = math.sin(math.radians(lat0)) ** 2
        d = 1.0 - 6.69437999014e-3 * s2
        re = 6378137.0 / math.sqrt(d)
        rn = re * (1.0 - 6.69437999014e-3) / d
        k = _strictly_increasing(e["t"])
        ref = Trajectory(
            e["t"][k],
            lat0 + np.degrees(e["PN"][k] / rn),
            lon0 + np.degrees(e["PE"][k] / (re * math.cos(math.radians(lat0)))),
            alt0 - e["PD"][k],
            np.column_stack([e["VN"], e["VE"], e["VD"]])[k],
            np.column_stack([e["Roll"], e["Pitch"], e["Yaw"]])[k],
            name=f"ArduPilot EKF ({name}; origin = first 3-D fix)",
            alt_datum="origin-relative",
        )
    elif "AHR2" in tables:
        a = tables["AHR2"]
        k = _strictly_increasing(a["t"]) & (np.abs(a["Lat"]) > 1e-6)
        if k.sum() >= 2:
            ref = Trajectory(
                a["t"][k],
                a["Lat"][k],
                a["Lng"][k],
                a["Alt"][k],
                None,
                np.column_stack([a["Roll"], a["Pitch"], a["Yaw"]])[k],
                name="ArduPilot AHR2",
                alt_datum="amsl",
            )
    key = imu or next(iter(imus))
    if key not in imus:
        from uasnav.errors import InputError

        raise InputError(f"imu: {key!r} not in the log (has {', '.join(imus)})")
    return Flight(
        imus[key],
        gnss,
        baro,
        mag,
        reference=ref,
        imus=imus,
        meta={
            "source": str(path),
            "format": "ardupilot-dataflash",
            "imu": key,
            **_dataflash_declination_meta(path, gp, int(ok[0])),
        },
    )


def read_ulog_nav(path: str | Any) -> Flight:
    """Navigation data of a PX4 ULog: the primary IMU (:func:`uasnav.io.px4.read_ulog`:
    ``sensor_combined`` or ``sensor_gyro``/``sensor_accel``, with temperature),
    ``vehicle_gps_position`` or ``sensor_gps`` (``alt_ellipsoid``, ``eph``/``epv``/
    ``s_variance_m_s`` as accuracies, fixes with ``fix_type`` ≥ 3), ``vehicle_air_data``
    (``baro_alt_meter``), ``vehicle_magnetometer``, and the reference from
    ``vehicle_global_position`` or ``vehicle_local_position`` (``ref_lat/ref_lon/ref_alt`` +
    ``x/y/z``, ``vx/vy/vz``) with ``vehicle_attitude``.

    Raises
    ------
    DataFormatError
        No GNSS topic, fewer than 2 3-D fixes, or the IMU reader's errors.
    """
    from pathlib import Path

    from uasnav.errors import DataFormatError
    from uasnav.io.px4 import _dataset, _open, read_ulog

    p = Path(path)
    imu = read_ulog(p)
    ulog, _ = _open(p)

    def topic(*names: str) -> dict[str, Any] | None:
        for n in names:
            d = _dataset(ulog, n)
            if d is not None and len(d.data["timestamp"]) >= 2:
                return {k: np.asarray(v, dtype=np.float64) for k, v in d.data.items()}
        return None

    g = topic("vehicle_gps_position", "sensor_gps")
    if g is None:
        raise DataFormatError(
            "no vehicle_gps_position / sensor_gps topic: the GNSS/INS filter needs GNSS fixes", path=str(p)
        )
    ok = g.get("fix_type", np.full(g["timestamp"].size, 3.0)) >= 3
    t = g["timestamp"][ok] * 1e-6
    keep = _strictly_increasing(t)
    sel = np.flatnonzero(ok)[keep]
    if sel.size < 2:
        raise DataFormatError(
            "vehicle_gps_position: fewer than 2 fixes with fix_type >= 3",
            path=str(p),
            column="vehicle_gps_position.fix_type",
        )
    alt = g["alt_ellipsoid"] if "alt_ellipsoid" in g and np.any(g["alt_ellipsoid"] != 0) else g["alt"]
    gnss = GnssData(
        g["timestamp"][sel] * 1e-6,
        g["lat"][sel] * 1e-7,
        g["lon"][sel] * 1e-7,
        alt[sel] * 1e-3,
        np.column_stack([g["vel_n_m_s"], g["vel_e_m_s"], g["vel_d_m_s"]])[sel],
        np.maximum(g.get("eph", np.full(g["timestamp"].size, 2.0))[sel], 0.1),
        np.maximum(g.get("epv", np.full(g["timestamp"].size, 3.0))[sel], 0.1),
        np.maximum(g.get("s_variance_m_s", np.full(g["timestamp"].size, 0.3))[sel], 0.05),
    )
    baro = None
    b = topic("vehicle_air_data")
    if b is not None:
        k = _strictly_increasing(b["timestamp"])
        baro = BaroData(b["timestamp"][k] * 1e-6, b["baro_alt_meter"][k])
    mag = None
    m = topic("vehicle_magnetometer")
    if m is not None and "magnetometer_ga[0]" in m:
        k = _strictly_increasing(m["timestamp"])
        mag = MagData(
            m["timestamp"][k] * 1e-6, np.column_stack([m[f"magnetometer_ga[{i}]"] for i in range(3)])[k]
        )
    ref = None
    att = topic("vehicle_attitude")
    lp = topic("vehicle_local_position")
    if lp is not None and "ref_lat" in lp:
        k = _strictly_increasing(lp["timestamp"])
        tt = lp["timestamp"][k] * 1e-6
        lat0, lon0, alt0 = (
            float(lp["ref_lat"][k][-1]),
            float(lp["ref_lon"][k][-1]),
            float(lp["ref_alt"][k][-1]),
        )
        origin = "ref_lat/ref_lon/ref_alt"
        if lat0 == 0.0 and lon0 == 0.0:
            # No global reference in the log (e.g. an excerpt): the EKF origin is taken as the
            # first 3-D fix, its height as that fix's (ellipsoidal) height.
            lat0, lon0, alt0 = float(gnss.lat[0]), float(gnss.lon[0]), float(gnss.alt[0])
            origin = "first 3-D fix"
            z0 = float(np.interp(gnss.t[0], lp["timestamp"][k] * 1e-6, lp["z"][k]))
            alt0 += z0
        s2 = math.sin(math.radians(lat0)) ** 2
        d = 1.0 - 6.69437999014e-3 * s2
        re = 6378137.0 / math.sqrt(d)
        rn = re * (1.0 - 6.69437999014e-3) / d
        eul = None
        if att is not None:
            from scipy.spatial.transform import Rotation

            q = np.column_stack([att[f"q[{i}]"] for i in (1, 2, 3, 0)])
            e = Rotation.from_quat(q).as_euler("ZYX")[:, ::-1]
            ta = att["timestamp"] * 1e-6
            eul = np.column_stack(
                [
                    np.degrees(
                        np.arctan2(np.interp(tt, ta, np.sin(e[:, i])), np.interp(tt, ta, np.cos(e[:, i])))
                    )
                    for i in range(3)
                ]
            )
        ref = Trajectory(
            tt,
            lat0
            + np.degrees(
                (
                    lp["x"][k]
                    - (
                        float(np.interp(gnss.t[0], tt, lp["x"][k]))
                        if origin != "ref_lat/ref_lon/ref_alt"
                        else 0.0
                    )
                )
                / rn
            ),
            lon0
            + np.degrees(
                (
                    lp["y"][k]
                    - (
                        float(np.interp(gnss.t[0], tt, lp["y"][k]))
                        if origin != "ref_lat/ref_lon/ref_alt"
                        else 0.0
                    )
                )
                / (re * math.cos(math.radians(lat0)))
            ),
            alt0 - lp["z"][k],
            np.column_stack([lp["vx"], lp["vy"], lp["vz"]])[k],
            eul,
            name=f"PX4 EKF2 (vehicle_local_position + vehicle_attitude; origin = {origin})",
            alt_datum="origin-relative",
        )
    return Flight(
        imu,
        gnss,
        baro,
        mag,
        reference=ref,
        imus={"IMU": imu},
        meta={"source": str(p), "format": "px4-ulog", "imu": "IMU", **_ulog_declination_meta(ulog, g, sel)},
    )


def _ulog_declination_meta(ulog: Any, g: dict[str, FloatArray], sel: NDArray[np.intp]) -> dict[str, Any]:
    """``declination_deg`` from the parameter ``EKF2_MAG_DECL`` (degrees) when non-zero (PX4
    saves the declination it used there), and ``utc_year`` from the GNSS ``time_utc_usec``."""
    import datetime as _dt

    from uasnav.io.gpstime import decimal_year

    meta: dict[str, Any] = {}
    dec = ulog.initial_parameters.get("EKF2_MAG_DECL")
    if dec is not None and math.isfinite(float(dec)) and float(dec) != 0.0:
        meta["declination_deg"] = float(dec)
        meta["declination_source"] = "log: parameter EKF2_MAG_DECL"
    utc = g.get("time_utc_usec")
    if utc is not None:
        u = utc[sel]
        u = u[np.isfinite(u) & (u > 1e15)]  # after 2001: a real UTC time
        if u.size:
            meta["utc_year"] = decimal_year(
                _dt.datetime(1970, 1, 1) + _dt.timedelta(microseconds=float(u[0]))
            )
    return meta


def read_csv_nav(path: str | Any, gnss: GnssData) -> Flight:
    """A CSV v1 IMU log (``mx my mz`` as magnetometer if present) with a separate GNSS CSV."""
    from uasnav.io.csv_v1 import read_csv_v1

    imu = read_csv_v1(path)
    mag = MagData(imu.t, imu.mag) if imu.mag is not None else None
    return Flight(
        imu, gnss, None, mag, imus={"IMU": imu}, meta={"source": str(path), "format": "csv-v1", "imu": "IMU"}
    )
