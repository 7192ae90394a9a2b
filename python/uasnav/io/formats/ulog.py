"""PX4 ULog (``.ulg``) through pyulog: one parse per command for the topics its views need.

Views and their topics (:attr:`UlogFormat.SOURCES`):

- ``imus``/``imu`` (:func:`read_ulog_imus` / :func:`read_ulog`): ``sensor_combined`` (rad/s,
  m/s², gauss → µT) or ``vehicle_imu`` (delta angles/velocities over their intervals), body FRD;
  each ``sensor_gyro``/``sensor_accel`` pair as ``sensor_imu[N]``; temperature from
  ``sensor_gyro``/``sensor_accel``, else ``sensor_combined.baro_temp_celcius``.
- ``nav`` (``gnss``, ``baro``, ``mag``, ``autopilot_estimate``): :func:`read_ulog_nav`.
- ``flight`` (:func:`read_ulog_flight`): ``vehicle_global_position`` (or ``…gps_position``),
  ``mission_result`` reached events, ``wind_estimate``; no waypoints (they live in dataman).
- ``plan``: :func:`uasnav.io.plan_formats.ulog.ulog_plan` (``navigator_mission_item``: PX4 ≥ 1.13
  logs ``altitude_is_relative``, older ones the MAV_FRAME ``frame``).
- ``params`` (initial parameters), ``limits``, ``modes`` (``vehicle_status.nav_state``),
  ``identity`` (``ver_sw_release``, ``ver_hw``, ``sys_uuid``; UTC from the receiver's
  ``time_utc_usec``).
Time is ``timestamp`` (µs since boot) in seconds.

Height datums (the rule that makes ``nav`` agree with EKF2 vertically): ``vehicle_gps_position``
carries both the ellipsoidal height ``alt_ellipsoid`` and the AMSL height ``alt`` of the
receiver's own geoid model; EKF2's origin height ``vehicle_local_position.ref_alt`` is AMSL.
GNSS fixes are read ellipsoidal and the estimate is moved onto the ellipsoid with the
receiver's own undulation N = median(``alt_ellipsoid`` − ``alt``). A receiver that reports no
ellipsoidal height leaves both in AMSL. The telemetry track (``flight``) stays AMSL as logged.

Errors: a missing file or one pyulog cannot parse is a :class:`~uasnav.errors.DataFormatError`
naming the file. ULog records carry no checksum: the readers drop corrupt records (time out of
order, non-finite or implausible values), silence pyulog's notices (it prints them to stdout)
and warn once with the counts (:class:`~uasnav.errors.CorruptDataWarning`).
"""

from __future__ import annotations

import datetime as dt
import math
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from uasnav.errors import DataFormatError, InputError
from uasnav.geo.datum import HeightDatum, receiver_undulation
from uasnav.geo.frames import ned_to_geodetic
from uasnav.imu import ImuLog
from uasnav.io._common import (
    TEMP_RANGE_C,
    build_log,
    corruption_meta,
    imu_limits,
    nothing_valid,
    report_corruption,
    salvage,
)
from uasnav.io._quiet import LibraryOutput
from uasnav.io.autopilot_params import PX4_PARAMS
from uasnav.io.flight import (
    BaroData,
    Flight,
    GnssData,
    MagData,
    Trajectory,
    flight_from_fixes,
    strictly_increasing,
)
from uasnav.io.formats._scan import ULogScan, _open
from uasnav.io.formats.base import ScannedFormat
from uasnav.io.mission_plan import MissionPlan
from uasnav.io.plan_formats.ulog import TOPICS as PLAN_TOPICS
from uasnav.io.plan_formats.ulog import ulog_plan
from uasnav.io.views import Identity, ModeTimeline, changes

FloatArray = NDArray[np.float64]

#: |magnetic field| above which a record is corrupt, µT (sensors saturate near ±5000 µT).
MAX_MAG_UT = 10_000.0
#: Wind estimates above this (m/s) are corrupt records.
MAX_WIND_M_S = 100.0


def _dataset(ulog: Any, name: str, multi: int = 0) -> Any | None:
    for d in ulog.data_list:
        if d.name == name and d.multi_id == multi:
            return d
    return None


def _cols(d: Any, stem: str, path: str) -> np.ndarray:
    try:
        return np.column_stack([np.asarray(d.data[f"{stem}[{i}]"], dtype=np.float64) for i in range(3)])
    except KeyError as e:
        raise DataFormatError(
            f"{d.name}: missing field {e.args[0]!r}", path=path, column=f"{d.name}.{stem}"
        ) from None


def _no_topic(ulog: Any, decoder: LibraryOutput, what: str, sp: str) -> DataFormatError:
    names = sorted({d.name for d in ulog.data_list})
    if not names and decoder.problems:
        return DataFormatError(f"corrupt ULog: no topic could be read ({decoder.summary()})", path=sp)
    return DataFormatError(f"no {what} topic (topics: {', '.join(names) or 'none'})", path=sp)


def _temperature(
    ulog: Any, sc: Any | None, t: np.ndarray, meta: dict[str, Any]
) -> tuple[np.ndarray | None, int]:
    """Temperature (°C) on the IMU time stamps ``t`` (see the module docs), and the number of
    corrupt temperature records dropped."""
    lo, hi = TEMP_RANGE_C
    for name, field in (("sensor_gyro", "temperature"), ("sensor_accel", "temperature")):
        d = _dataset(ulog, name)
        if d is not None and field in d.data:
            temp_t = np.asarray(d.data["timestamp"], dtype=np.float64) * 1e-6
            temp = np.asarray(d.data[field], dtype=np.float64)
            keep = salvage(temp_t, {"temp": temp}, {"temp": (lo, hi)})
            if keep.sum() < 2:
                continue  # nothing valid: try the next source
            meta["temperature_source"] = f"{name}.{field}"
            return np.interp(t, temp_t[keep], temp[keep]), int((~keep).sum())
    if sc is not None and np.any(np.asarray(sc.data.get("baro_temp_celcius", [0.0])) != 0):
        # logged as exactly 0 when the barometer did not report: treat as absent
        meta["temperature_source"] = "sensor_combined.baro_temp_celcius"
        return np.asarray(sc.data["baro_temp_celcius"], dtype=np.float64), 0
    return None, 0


def read_ulog(path: str | os.PathLike[str]) -> ImuLog:
    """Read the primary IMU of a PX4 ULog (see the module docs for topics and units).

    A corrupt log (ULog records carry no checksum) is read as far as it is valid: records with
    time out of order, non-finite or implausible values are dropped, pyulog's notices are
    silenced, and one :class:`~uasnav.errors.CorruptDataWarning` gives the counts (also in
    ``meta["corrupt_records_dropped"]``, ``meta["corruption"]``).

    Raises
    ------
    DataFormatError
        Missing/unreadable file, no IMU topic, a missing field, or fewer than 2 valid records.
    """
    p = Path(path)
    ulog, decoder = _open(p)
    sp = str(p)
    meta: dict[str, Any] = {"source": sp, "format": "px4-ulog", "frame": "FRD"}
    # the flight controller's identity when the log records it (uasnav.fleet partitions by it)
    info = getattr(ulog, "msg_info_dict", None) or {}
    meta.update(
        {k: str(info[i]) for k, i in (("vehicle", "sys_uuid"), ("hardware", "ver_hw")) if info.get(i)}
    )
    start = _start_utc(ulog)
    if start is not None:
        meta["start_time"] = start
    sc = _dataset(ulog, "sensor_combined")
    mag = None
    if sc is not None:
        t = np.asarray(sc.data["timestamp"], dtype=np.float64) * 1e-6
        gyro = _cols(sc, "gyro_rad", sp)
        accel = _cols(sc, "accelerometer_m_s2", sp)
        if "magnetometer_ga[0]" in sc.data:
            mag = _cols(sc, "magnetometer_ga", sp) * 100.0  # gauss → µT
        topic = "sensor_combined"
    else:
        vi = _dataset(ulog, "vehicle_imu")
        if vi is None:
            raise _no_topic(ulog, decoder, "sensor_combined or vehicle_imu", sp)
        t = np.asarray(vi.data["timestamp"], dtype=np.float64) * 1e-6
        dt_a = np.asarray(vi.data["delta_angle_dt"], dtype=np.float64) * 1e-6
        dt_v = np.asarray(vi.data["delta_velocity_dt"], dtype=np.float64) * 1e-6
        with np.errstate(divide="ignore", invalid="ignore"):
            # a non-positive integration interval is a corrupt record: NaN, dropped below
            gyro = _cols(vi, "delta_angle", sp) / np.where(dt_a > 0, dt_a, np.nan)[:, None]
            accel = _cols(vi, "delta_velocity", sp) / np.where(dt_v > 0, dt_v, np.nan)[:, None]
        topic = "vehicle_imu"
    values = {"gyro": gyro, "accel": accel}
    limits = imu_limits(False)
    if mag is not None:
        values["mag"] = mag
        limits["mag"] = (-MAX_MAG_UT, MAX_MAG_UT)
    keep = salvage(t, values, limits)
    if keep.sum() < 2:
        raise nothing_valid(sp, topic, t.size, decoder)
    dropped = int((~keep).sum())
    t, gyro, accel = t[keep], gyro[keep], accel[keep]
    mag = None if mag is None else mag[keep]
    temp, temp_dropped = _temperature(ulog, sc, t, meta)
    if temp is not None and temp.shape != t.shape:  # baro_temp_celcius: one per IMU record
        temp = temp[keep]
    if temp is not None and not np.all(np.isfinite(temp)):
        temp, _ = None, meta.pop("temperature_source", None)
    report_corruption(sp, decoder, dropped + temp_dropped, keep.size, topic)
    meta["topic"] = topic
    meta.update(corruption_meta(decoder, dropped + temp_dropped))
    return build_log(sp, topic, t, gyro, accel, temp, meta, mag=mag)


def _start_utc(ulog: Any) -> str | None:
    """UTC (ISO 8601) of the log's start from the first GNSS record with a UTC time, or None."""
    g = _dataset(ulog, "vehicle_gps_position") or _dataset(ulog, "sensor_gps")
    if g is None or "time_utc_usec" not in g.data:
        return None
    utc = np.asarray(g.data["time_utc_usec"], dtype=np.float64)
    k = np.flatnonzero(utc > 946_684_800e6)  # after 2000: a real UTC time
    if not k.size:
        return None
    i = int(k[0])
    t0 = float(utc[i] - (float(g.data["timestamp"][i]) - float(ulog.start_timestamp))) * 1e-6
    return dt.datetime.fromtimestamp(t0, tz=dt.timezone.utc).isoformat(timespec="milliseconds")


def read_ulog_imus(path: str | os.PathLike[str]) -> dict[str, ImuLog]:
    """Every IMU of a PX4 ULog: the primary (:func:`read_ulog`, keyed by its topic) and each
    ``sensor_gyro``/``sensor_accel`` instance pair N logged, keyed ``sensor_imu[N]`` (the
    accelerometer interpolated to the gyro's sample times, both FRD in rad/s and m/s²; the
    gyro's temperature, °C). An instance with fewer than 2 valid records is left out.

    Raises
    ------
    DataFormatError
        As :func:`read_ulog` (the primary IMU is required).
    """
    p = Path(path)
    primary = read_ulog(p)
    out = {str(primary.meta["topic"]): primary}
    ulog, _ = _open(p)
    sp = str(p)
    for g in [d for d in ulog.data_list if d.name == "sensor_gyro"]:
        a = _dataset(ulog, "sensor_accel", g.multi_id)
        if a is None or not {"x", "y", "z"} <= set(g.data) or not {"x", "y", "z"} <= set(a.data):
            continue
        tg = np.asarray(g.data["timestamp"], dtype=np.float64) * 1e-6
        ta = np.asarray(a.data["timestamp"], dtype=np.float64) * 1e-6
        if tg.size < 2 or ta.size < 2 or np.any(np.diff(ta) <= 0):
            continue
        gyro = np.column_stack([np.asarray(g.data[c], dtype=np.float64) for c in "xyz"])
        accel = np.column_stack([np.interp(tg, ta, np.asarray(a.data[c], dtype=np.float64)) for c in "xyz"])
        temp = np.asarray(g.data["temperature"], dtype=np.float64) if "temperature" in g.data else None
        values = {"gyro": gyro, "accel": accel}
        keep = salvage(tg, values, imu_limits(False))
        keep &= (tg >= ta[0]) & (tg <= ta[-1])  # no extrapolated accelerometer samples
        if keep.sum() < 2:
            continue
        if temp is not None and not np.all(np.isfinite(temp[keep])):
            temp = None
        name = f"sensor_imu[{g.multi_id}]"
        meta = {"source": sp, "format": "px4-ulog", "frame": "FRD", "topic": name}
        meta.update({k: primary.meta[k] for k in ("vehicle", "hardware", "start_time") if k in primary.meta})
        if "device_id" in g.data:
            meta["device_id"] = str(int(g.data["device_id"][0]))
        out[name] = build_log(
            sp, name, tg[keep], gyro[keep], accel[keep], None if temp is None else temp[keep], meta
        )
    return out


def read_ulog_flight(path: str | os.PathLike[str]) -> Flight:
    """The flight telemetry of a PX4 ULog (see the module docs for the topics).

    Corrupt position records are dropped (:func:`uasnav.io.flight.valid_fixes`; one
    :class:`~uasnav.errors.CorruptDataWarning` gives the counts).

    Raises
    ------
    DataFormatError
        Missing/unreadable file, neither vehicle_global_position nor vehicle_gps_position, or
        fewer than 2 valid position records.
    """
    p = Path(path)
    ulog, decoder = _open(p)

    def topic(name: str) -> dict[str, np.ndarray] | None:
        d = _dataset(ulog, name)
        return None if d is None else d.data

    g = topic("vehicle_global_position")
    if g is not None and "vel_n" in g:
        t = g["timestamp"] * 1e-6
        lat, lon, alt = g["lat"], g["lon"], g["alt"]
        vel = np.column_stack([g["vel_n"], g["vel_e"], g["vel_d"]])
    else:
        g = topic("vehicle_gps_position")
        if g is None:
            raise _no_topic(ulog, decoder, "vehicle_global_position / vehicle_gps_position", str(p))
        t = g["timestamp"] * 1e-6
        lat, lon, alt = g["lat"] * 1e-7, g["lon"] * 1e-7, g["alt"] * 1e-3
        vel = np.column_stack([g["vel_n_m_s"], g["vel_e_m_s"], g["vel_d_m_s"]])
    reached: list[tuple[float, int]] = []
    mr = topic("mission_result")
    if mr is not None and "seq_reached" in mr:
        last = -1
        for ts, s in zip(mr["timestamp"], mr["seq_reached"], strict=True):
            if s >= 0 and s != last:
                reached.append((ts * 1e-6, int(s)))
            last = s
    w = topic("wind_estimate")
    wind = []
    if w is not None:
        wn = np.asarray(w["windspeed_north"], dtype=np.float64)
        we = np.asarray(w["windspeed_east"], dtype=np.float64)
        ok = np.isfinite(wn) & np.isfinite(we) & (np.hypot(wn, we) <= MAX_WIND_M_S)
        if ok.any():
            wind = [(wn[ok].mean(), we[ok].mean())]
    fixes = np.column_stack([t, lat, lon, alt, vel]).astype(np.float64)
    return flight_from_fixes(fixes, p, waypoints={}, reached=reached, wind=wind, decoder=decoder)


_GNSS = ("vehicle_gps_position", "sensor_gps")
_IMU = ("sensor_combined", "vehicle_imu", "sensor_gyro", "sensor_accel", *_GNSS)
#: PX4 ``vehicle_status.nav_state`` numbers → names (``vehicle_status.msg``).
NAV_STATES = {
    0: "MANUAL", 1: "ALTCTL", 2: "POSCTL", 3: "AUTO_MISSION", 4: "AUTO_LOITER", 5: "AUTO_RTL",
    6: "AUTO_RCRECOVER", 7: "AUTO_RTGS", 8: "AUTO_LANDENGFAIL", 9: "AUTO_LANDGPSFAIL", 10: "ACRO",
    12: "DESCEND", 13: "TERMINATION", 14: "OFFBOARD", 15: "STAB", 17: "AUTO_TAKEOFF",
    18: "AUTO_LAND", 19: "AUTO_FOLLOW_TARGET", 20: "AUTO_PRECLAND", 21: "ORBIT", 22: "AUTO_VTOL_TAKEOFF",
}  # fmt: skip
#: PX4 ``vehicle_status.vehicle_type``.
VEHICLE_TYPES = {0: "unknown", 1: "multirotor", 2: "fixed-wing", 3: "rover", 4: "airship"}
_RELEASE_TYPES = {0: "dev", 64: "alpha", 128: "beta", 192: "rc", 255: ""}


def _topic(ulog: Any, *names: str) -> dict[str, FloatArray] | None:
    for n in names:
        for d in ulog.data_list:
            if d.name == n and d.multi_id == 0 and len(d.data["timestamp"]) >= 2:
                return {k: np.asarray(v, dtype=np.float64) for k, v in d.data.items()}
    return None


def _euler_at(att: dict[str, FloatArray], tt: FloatArray) -> FloatArray:
    from scipy.spatial.transform import Rotation

    q = np.column_stack([att[f"q[{i}]"] for i in (1, 2, 3, 0)])
    e = Rotation.from_quat(q).as_euler("ZYX")[:, ::-1]
    ta = att["timestamp"] * 1e-6
    return np.column_stack(
        [
            np.degrees(np.arctan2(np.interp(tt, ta, np.sin(e[:, i])), np.interp(tt, ta, np.cos(e[:, i]))))
            for i in range(3)
        ]
    )


def read_ulog_nav(path: str | Path) -> Flight:
    """Navigation data of a PX4 ULog: the primary IMU (:func:`read_ulog`),
    ``vehicle_gps_position``/``sensor_gps`` fixes with ``fix_type`` ≥ 3 (``eph``/``epv``/
    ``s_variance_m_s`` as accuracies), ``vehicle_air_data.baro_alt_meter``,
    ``vehicle_magnetometer``, and EKF2's estimate from ``vehicle_local_position`` (``x/y/z`` NED
    from ``ref_lat/ref_lon/ref_alt``, ``vx/vy/vz``) with ``vehicle_attitude``. Heights: see the
    module docs.

    Raises
    ------
    DataFormatError
        No GNSS topic, fewer than 2 3-D fixes, or the IMU reader's errors.
    """
    p = Path(path)
    imu = read_ulog(p)
    ulog, _ = _open(p)
    g = _topic(ulog, *_GNSS)
    if g is None:
        raise DataFormatError(
            "no vehicle_gps_position / sensor_gps topic: the GNSS/INS filter needs GNSS fixes", path=str(p)
        )
    ok = g.get("fix_type", np.full(g["timestamp"].size, 3.0)) >= 3
    t = g["timestamp"][ok] * 1e-6
    sel = np.flatnonzero(ok)[strictly_increasing(t)]
    if sel.size < 2:
        raise DataFormatError(
            "vehicle_gps_position: fewer than 2 fixes with fix_type >= 3",
            path=str(p),
            column="vehicle_gps_position.fix_type",
        )
    n_geoid = None
    if "alt_ellipsoid" in g and np.any(g["alt_ellipsoid"][sel] != 0):
        alt, datum = g["alt_ellipsoid"], HeightDatum.ELLIPSOID
        n_geoid = receiver_undulation(g["alt_ellipsoid"][sel] * 1e-3, g["alt"][sel] * 1e-3)
    else:
        alt, datum = g["alt"], HeightDatum.AMSL
    n = g["timestamp"].size
    gnss = GnssData(
        g["timestamp"][sel] * 1e-6,
        g["lat"][sel] * 1e-7,
        g["lon"][sel] * 1e-7,
        alt[sel] * 1e-3,
        np.column_stack([g["vel_n_m_s"], g["vel_e_m_s"], g["vel_d_m_s"]])[sel],
        np.maximum(g.get("eph", np.full(n, 2.0))[sel], 0.1),
        np.maximum(g.get("epv", np.full(n, 3.0))[sel], 0.1),
        np.maximum(g.get("s_variance_m_s", np.full(n, 0.3))[sel], 0.05),
        alt_datum=datum,
        geoid_undulation_m=n_geoid,
    )
    baro = None
    b = _topic(ulog, "vehicle_air_data")
    if b is not None:
        k = strictly_increasing(b["timestamp"])
        baro = BaroData(b["timestamp"][k] * 1e-6, b["baro_alt_meter"][k])
    mag = None
    m = _topic(ulog, "vehicle_magnetometer")
    if m is not None and "magnetometer_ga[0]" in m:
        k = strictly_increasing(m["timestamp"])
        mag = MagData(
            m["timestamp"][k] * 1e-6, np.column_stack([m[f"magnetometer_ga[{i}]"] for i in range(3)])[k]
        )
    lp = _topic(ulog, "vehicle_local_position")
    ref = None
    if lp is not None and "ref_lat" in lp:
        ref = _ekf2_estimate(lp, _topic(ulog, "vehicle_attitude"), gnss)
    meta = {"source": str(p), "format": "px4-ulog", "imu": "IMU", **_declination_meta(ulog, g, sel)}
    return Flight(imu, gnss, baro, mag, reference=ref, imus={"IMU": imu}, meta=meta)


def _ekf2_estimate(
    lp: dict[str, FloatArray], att: dict[str, FloatArray] | None, gnss: GnssData
) -> Trajectory:
    """EKF2's position (geodetic, in the GNSS fixes' datum), velocity and attitude."""
    k = strictly_increasing(lp["timestamp"])
    tt = lp["timestamp"][k] * 1e-6
    x, y, z = lp["x"][k], lp["y"][k], lp["z"][k]
    lat0, lon0, alt0 = (float(lp[f][k][-1]) for f in ("ref_lat", "ref_lon", "ref_alt"))
    if lat0 == 0.0 and lon0 == 0.0:
        # No global reference in the log (e.g. an excerpt): the EKF origin is taken as the first
        # 3-D fix, already in the fixes' datum.
        x0, y0, z0 = (float(np.interp(gnss.t[0], tt, v)) for v in (x, y, z))
        lat0, lon0, alt0 = float(gnss.lat[0]), float(gnss.lon[0]), float(gnss.alt[0])
        x, y, z = x - x0, y - y0, z - z0
        origin = "first 3-D fix"
    else:
        origin = "ref_lat/ref_lon/ref_alt"
        if gnss.alt_datum is HeightDatum.ELLIPSOID and gnss.geoid_undulation_m is not None:
            alt0 += gnss.geoid_undulation_m  # ref_alt is AMSL: onto the ellipsoid with the receiver's N
            origin += f" + receiver geoid undulation {gnss.geoid_undulation_m:+.2f} m"
    lat, lon, alt = ned_to_geodetic(x, y, z, lat0, lon0, alt0)
    return Trajectory(
        tt,
        np.asarray(lat, dtype=np.float64),
        np.asarray(lon, dtype=np.float64),
        np.asarray(alt, dtype=np.float64),
        np.column_stack([lp["vx"], lp["vy"], lp["vz"]])[k],
        None if att is None else _euler_at(att, tt),
        name=f"PX4 EKF2 (vehicle_local_position + vehicle_attitude; origin = {origin})",
        alt_datum=gnss.alt_datum,
    )


def _declination_meta(ulog: Any, g: dict[str, FloatArray], sel: NDArray[np.intp]) -> dict[str, Any]:
    """``declination_deg`` from the parameter ``EKF2_MAG_DECL`` (degrees) when non-zero (PX4
    saves the declination it used there), and ``utc_year`` from the GNSS ``time_utc_usec``."""
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
            meta["utc_year"] = decimal_year(dt.datetime(1970, 1, 1) + dt.timedelta(microseconds=float(u[0])))
    return meta


class UlogFormat(ScannedFormat):
    """PX4 ULog (see the module docs)."""

    name = "px4-ulog"
    SCANNER = ULogScan
    SOURCES: ClassVar[dict[str, tuple[str, ...]]] = {
        "imus": _IMU,
        "imu": _IMU,
        "nav": (
            *_IMU,
            "vehicle_air_data",
            "vehicle_magnetometer",
            "vehicle_attitude",
            "vehicle_local_position",
        ),
        "flight": ("vehicle_global_position", "vehicle_gps_position", "mission_result", "wind_estimate"),
        "plan": ("navigator_mission_item", "home_position", "mission", "mission_result"),
        "params": (),
        "limits": (),
        "modes": ("vehicle_status",),
        "identity": (*_GNSS, "vehicle_status"),
    }
    READERS: ClassVar[dict[str, Callable[[Path], Any]]] = {
        "imus": read_ulog_imus,
        "imu": read_ulog,
        "nav": read_ulog_nav,
        "flight": read_ulog_flight,
    }

    def _ulog(self) -> Any:
        return _open(self.path)[0]

    def build_plan(self) -> MissionPlan:
        if not self.path.is_file():
            raise InputError(f"{self.path}: no such file")
        ulog, _ = _open(self.path, list(PLAN_TOPICS))  # pyulog's notices stay off stdout
        return ulog_plan(ulog, str(self.path))

    def build_params(self) -> dict[str, float]:
        out = {}
        for k, v in self._ulog().initial_parameters.items():
            try:
                out[str(k)] = float(v)
            except (TypeError, ValueError):
                continue
        return out

    def limit_parameters(self, params: dict[str, float]) -> dict[str, tuple[str, float]]:
        return PX4_PARAMS

    def build_modes(self) -> ModeTimeline:
        vs = _topic(self._ulog(), "vehicle_status")
        if vs is None or "nav_state" not in vs:
            return ModeTimeline(np.zeros(0), (), "vehicle_status.nav_state")
        names = [NAV_STATES.get(int(s), f"NAV_STATE_{int(s)}") for s in vs["nav_state"]]
        return changes(vs["timestamp"] * 1e-6, names, "vehicle_status.nav_state")

    def build_identity(self) -> Identity:
        ulog = self._ulog()
        info = getattr(ulog, "msg_info_dict", None) or {}
        version = None
        rel = info.get("ver_sw_release")
        if isinstance(rel, int) and rel > 0:
            kind = _RELEASE_TYPES.get(rel & 0xFF, str(rel & 0xFF))
            version = f"{(rel >> 24) & 0xFF}.{(rel >> 16) & 0xFF}.{(rel >> 8) & 0xFF}" + (
                f"-{kind}" if kind else ""
            )
        vs = _topic(ulog, "vehicle_status")
        vtype = None
        if vs is not None and "vehicle_type" in vs:
            vtype = VEHICLE_TYPES.get(int(vs["vehicle_type"][-1]), str(int(vs["vehicle_type"][-1])))
        start = _start_utc(ulog)
        utc0 = None
        if start is not None:
            utc0 = dt.datetime.fromisoformat(start) - dt.timedelta(seconds=float(ulog.start_timestamp) * 1e-6)
        return Identity(
            autopilot=str(info.get("sys_name") or "PX4"),
            vehicle_type=vtype,
            firmware_version=version,
            firmware_git=str(info["ver_sw"]) if info.get("ver_sw") else None,
            board=str(info["ver_hw"]) if info.get("ver_hw") else None,
            vehicle_id=str(info["sys_uuid"]) if info.get("sys_uuid") else None,
            utc_at_zero=utc0,
            leap_seconds=None,
            clock="boot",
        )


__all__ = [
    "NAV_STATES",
    "UlogFormat",
    "read_ulog",
    "read_ulog_flight",
    "read_ulog_imus",
    "read_ulog_nav",
]
