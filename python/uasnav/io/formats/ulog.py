"""PX4 ULog (``.ulg``): one pyulog parse per command for the topics its views need.

Views and their topics (:attr:`UlogFormat.SOURCES`):

- ``imus``/``imu``: :func:`uasnav.io.px4.read_ulog_imus` / :func:`~uasnav.io.px4.read_ulog`.
- ``nav`` (``gnss``, ``baro``, ``mag``, ``autopilot_estimate``): :func:`read_ulog_nav`.
- ``flight``: :func:`uasnav.io.px4.read_ulog_flight`; ``plan``:
  :func:`uasnav.io.plan_formats.ulog.read_ulog_plan` (``navigator_mission_item``: PX4 ≥ 1.13
  logs ``altitude_is_relative``, older ones the MAV_FRAME ``frame``).
- ``params`` (initial parameters), ``limits``, ``modes`` (``vehicle_status.nav_state``),
  ``identity`` (``ver_sw_release``, ``ver_hw``, ``sys_uuid``; UTC from the receiver's
  ``time_utc_usec``).

Height datums (the rule that makes ``nav`` agree with EKF2 vertically): ``vehicle_gps_position``
carries both the ellipsoidal height ``alt_ellipsoid`` and the AMSL height ``alt`` of the
receiver's own geoid model; EKF2's origin height ``vehicle_local_position.ref_alt`` is AMSL.
GNSS fixes are read ellipsoidal and the estimate is moved onto the ellipsoid with the
receiver's own undulation N = median(``alt_ellipsoid`` − ``alt``). A receiver that reports no
ellipsoidal height leaves both in AMSL.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from uasnav.errors import DataFormatError
from uasnav.geo.datum import HeightDatum, receiver_undulation
from uasnav.geo.frames import ned_to_geodetic
from uasnav.io.autopilot_params import PX4_PARAMS
from uasnav.io.flight import BaroData, Flight, GnssData, MagData, Trajectory, strictly_increasing
from uasnav.io.formats._scan import ULogScan
from uasnav.io.formats.base import LogFormat
from uasnav.io.plan_formats.ulog import read_ulog_plan
from uasnav.io.px4 import _open, _start_utc, read_ulog, read_ulog_flight, read_ulog_imus
from uasnav.io.views import Identity, ModeTimeline, changes

FloatArray = NDArray[np.float64]

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
    """Navigation data of a PX4 ULog: the primary IMU (:func:`uasnav.io.px4.read_ulog`),
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


class UlogFormat(LogFormat):
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
        "plan": read_ulog_plan,
    }

    def _ulog(self) -> Any:
        return _open(self.path)[0]

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
            import datetime as dt

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


__all__ = ["NAV_STATES", "UlogFormat", "read_ulog_nav"]
