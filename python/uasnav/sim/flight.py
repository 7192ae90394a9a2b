"""Simulated flights with ground truth for the GNSS/INS filter: waypoints → smooth kinematics →
IMU with thermal errors, GNSS, barometer and magnetometer, with GNSS dropouts.

Kinematics: the vehicle rests on the ground for ``static_s`` seconds, then follows a C²
cubic spline through the waypoints (local north, east, up in metres from the start; times from
the leg lengths at ``speed_m_s``, clamped to zero velocity at both ends). The attitude is that
of a multirotor (differential flatness): the body down axis is opposite to the specific force
``a − g``, the yaw follows the course (held below 1 m/s, smoothed over 1 s).

IMU (the sample at ``t_k`` holds over ``(t_{k−1}, t_k]``, as the filter reads it):
``ω̃ = rotvec(C_{k−1}ᵀ C_k)/Ts + Cᵀω_in + b_g + b_T(T) + n_g`` and
``f̃ = C_midᵀ(Δv/Ts − g + (2ω_ie + ω_en) × v) + b_a + n_a``, with turn-on biases, the
preset's thermal gyro-bias curve ``b_T`` (heating branch; zero at the start temperature) on a die
temperature that warms exponentially, white noise (ARW, VRW), rotor vibration while airborne
(white) and bias random walks. GNSS:
antenna position/velocity with white errors of exactly the reported σ (the filter's model; real
receivers have time-correlated errors). Barometer: height minus a constant datum offset plus
white noise. Magnetometer: a fixed NED field (declination 0 plus a per-flight heading error)
resolved in the body plus noise.

Position: the north/east of the path are distances flown over the WGS-84 ellipsoid at the
vehicle's height, so latitude and longitude are integrated with the radii of curvature where the
vehicle is (:func:`uasnav.geo.frames.radii_of_curvature`):
``φ̇ = v_N/(R_N(φ)+h)``, ``λ̇ = v_E/((R_E(φ)+h) cos φ)``, the same transport rate ``ω_en`` the
simulated gyro carries (a constant course is a rhumb line). Gravity at the start latitude with
its exact height dependence (the latitude term changes it by < 1e-5 m/s² per km).

Deterministic from ``seed``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import CubicHermiteSpline, CubicSpline
from scipy.ndimage import gaussian_filter1d
from scipy.spatial.transform import Rotation

from uasnav import earth
from uasnav.errors import InputError
from uasnav.geo.frames import radii_of_curvature
from uasnav.imu import ImuLog
from uasnav.io.flight import BaroData, Flight, GnssData, MagData, Trajectory
from uasnav.limits import check_memory
from uasnav.sim.core import thermal_model
from uasnav.sim.model import SensorModel

FloatArray = NDArray[np.float64]

#: A 400 m × 300 m circuit at 50–70 m (north, east, up; m), flown after a vertical climb.
DEFAULT_CIRCUIT = ((400.0, 0.0, 50.0), (400.0, 300.0, 70.0), (0.0, 300.0, 60.0), (0.0, 0.0, 50.0))


@dataclass(frozen=True)
class FlightErrors:
    """Sensor error parameters of :func:`simulate_flight` (SI units in every name)."""

    gyro_turn_on_rad_s: float = math.radians(0.05)
    accel_turn_on_m_s2: float = 0.03
    arw_rad_sqrt_s: float = math.radians(0.3) / 60.0
    vrw_m_s_sqrt_s: float = 0.004
    gyro_rw_rad_s_sqrt_s: float = 1e-5
    accel_rw_m_s2_sqrt_s: float = 1e-4
    gnss_h_std_m: float = 1.5
    gnss_v_std_m: float = 2.5
    gnss_vel_std_m_s: float = 0.15
    baro_std_m: float = 0.5
    baro_offset_m: float = -30.0
    mag_std_ut: float = 0.3
    #: Heading error of the magnetometer common to a whole flight (unknown declination and
    #: iron effects), drawn once per flight, σ in rad.
    mag_heading_bias_std_rad: float = math.radians(2.0)
    #: Rotor vibration while airborne, white, σ per sample (m/s², rad/s): what tells hovering
    #: from standing on the ground.
    vibration_accel_m_s2: float = 0.1
    vibration_gyro_rad_s: float = 0.002
    temp_start_c: float = 20.0
    temp_rise_c: float = 20.0
    temp_tau_s: float = 300.0


def _gravity(lat0: float, h: FloatArray) -> FloatArray:
    # normal_gravity is exactly quadratic in h: three evaluations fix the polynomial.
    g = [earth.normal_gravity(lat0, x) for x in (0.0, 1000.0, 2000.0)]
    c = np.polyfit([0.0, 1000.0, 2000.0], g, 2)
    return np.polyval(c, h)


def _geodetic(
    t: FloatArray, vel: FloatArray, h: FloatArray, lat0: float, lon0: float
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Latitude and longitude (rad) along the path and their rates (rad/s): the NED velocity
    ``vel`` at height ``h`` integrated with the radii of curvature at the current latitude
    (trapezoid rule on the sample times; the radii depend on the latitude being integrated, so
    three fixed-point passes, each shrinking the radii's error by ~1e-5)."""
    lat = np.full(t.size, lat0)
    dt = np.diff(t)
    for _ in range(3):
        rn, re = radii_of_curvature(lat, degrees=False)
        lat_rate = vel[:, 0] / (rn + h)
        lat = lat0 + np.concatenate([[0.0], np.cumsum(0.5 * (lat_rate[1:] + lat_rate[:-1]) * dt)])
    rn, re = radii_of_curvature(lat, degrees=False)
    lat_rate = vel[:, 0] / (rn + h)
    lon_rate = vel[:, 1] / ((re + h) * np.cos(lat))
    lon = lon0 + np.concatenate([[0.0], np.cumsum(0.5 * (lon_rate[1:] + lon_rate[:-1]) * dt)])
    return lat, lon, lat_rate, lon_rate


def _path(
    waypoints: Sequence[tuple[float, float, float]], speed: float, static_s: float, duration_s: float | None
) -> CubicSpline:
    pts = [np.zeros(3)]
    wps = [np.asarray(w, dtype=np.float64) for w in waypoints]
    if not wps:
        raise InputError("waypoints: need at least one waypoint")
    for w in wps:
        if w.shape != (3,) or not np.isfinite(w).all():
            raise InputError(f"waypoints: expected finite (north, east, up) triples, got {w!r}")
    # Vertical climb above the start, then the circuit (repeated to fill the duration).
    pts.append(np.array([0.0, 0.0, wps[0][2] if len(wps) else 30.0]))
    times = [static_s, static_s + max(pts[1][2] / 2.0, 4.0)]
    while True:
        for w in wps:
            leg = float(np.linalg.norm(w - pts[-1]))
            if leg < 1e-6:
                continue
            pts.append(w)
            times.append(times[-1] + max(leg / speed, 4.0))
        if duration_s is None or times[-1] >= duration_s or len(pts) > 100_000:
            break
    p = np.array(pts)
    # NED with the "up" column turned into down.
    ned = np.column_stack([p[:, 0], p[:, 1], -p[:, 2]])
    return CubicSpline(np.array(times), ned, bc_type=((1, np.zeros(3)), (1, np.zeros(3))))


def simulate_flight(
    *,
    waypoints: Sequence[tuple[float, float, float]] = DEFAULT_CIRCUIT,
    duration_s: float | None = None,
    speed_m_s: float = 10.0,
    rate_hz: float = 100.0,
    gnss_rate_hz: float = 5.0,
    static_s: float = 20.0,
    latitude_deg: float = 45.0,
    longitude_deg: float = 7.0,
    height_m: float = 300.0,
    preset: str | SensorModel = "lsm6dsm",
    errors: FlightErrors | None = None,
    gnss_dropouts: Sequence[tuple[float, float]] = (),
    seed: int = 0,
) -> Flight:
    """Simulate a flight with truth (see the module docs).

    Parameters
    ----------
    waypoints : sequence of (north, east, up)
        Circuit in metres from the start point; repeated until ``duration_s``.
    duration_s : float, optional
        Length (s); default one circuit.
    speed_m_s : float
        Cruise speed (m/s).
    rate_hz, gnss_rate_hz : float
        IMU and GNSS rates (Hz).
    static_s : float
        Time at rest on the ground before take-off (s).
    latitude_deg, longitude_deg, height_m : float
        Start point (deg, deg, m ellipsoidal).
    preset : str or SensorModel
        Simulator preset (or model) whose thermal gyro-bias curve the IMU carries.
    errors : FlightErrors, optional
        Sensor errors.
    gnss_dropouts : sequence of (start_s, duration_s)
        Intervals without GNSS fixes.
    seed : int
        Random seed.

    Returns
    -------
    Flight
        With ``truth`` (position, velocity, attitude; ``extra["gyro_bias"]``,
        ``extra["accel_bias"]`` the true total biases, rad/s and m/s²).
    """
    e = errors or FlightErrors()
    for name, v in (("speed_m_s", speed_m_s), ("rate_hz", rate_hz), ("gnss_rate_hz", gnss_rate_hz)):
        if not (math.isfinite(v) and v > 0):
            raise InputError(f"{name}: must be a positive number, got {v!r}")
    if not (math.isfinite(static_s) and static_s >= 1.0):
        raise InputError(f"static_s: must be ≥ 1 s (levelling), got {static_s!r}")
    if not -80.0 <= latitude_deg <= 80.0:
        raise InputError(f"latitude_deg: must be within ±80°, got {latitude_deg!r}")
    preset_name = preset if isinstance(preset, str) else preset.name
    spline = _path(waypoints, speed_m_s, static_s, duration_s)
    t_end = float(spline.x[-1]) if duration_s is None else float(duration_s)
    if duration_s is not None and not (math.isfinite(t_end) and t_end > static_s):
        raise InputError(f"duration_s: must exceed static_s ({static_s} s), got {duration_s!r}")
    # estimated before round(): a duration of 1e308 s is refused, not an OverflowError
    check_memory((t_end * rate_hz + 1) * 8 * 60, "simulated flight", option="duration_s or rate_hz")
    n = round(t_end * rate_hz) + 1
    rng = np.random.default_rng(seed)
    dt = 1.0 / rate_hz
    t = np.arange(n) * dt

    def kin(tt: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        tc = np.clip(tt, static_s, spline.x[-1])
        moving = ((tt >= static_s) & (tt <= spline.x[-1]))[:, None]
        return spline(tc), spline(tc, 1) * moving, spline(tc, 2) * moving

    pos, vel, acc = kin(t)
    lat0, lon0 = math.radians(latitude_deg), math.radians(longitude_deg)
    h = height_m - pos[:, 2]
    lat, lon, lat_rate, lon_rate = _geodetic(t, vel, h, lat0, lon0)
    g = _gravity(lat0, h)

    # Yaw: the course where moving, held below 1 m/s, smoothed over 1 s.
    sp = np.hypot(vel[:, 0], vel[:, 1])
    course = np.arctan2(vel[:, 1], vel[:, 0])
    ok = sp > 1.0
    if ok.any():
        idx = np.flatnonzero(ok)
        yaw = np.unwrap(course[idx])
        yaw = np.interp(np.arange(n), idx, yaw)
    else:
        yaw = np.zeros(n)
    yaw = gaussian_filter1d(yaw, sigma=rate_hz, mode="nearest")

    def dcm(acc_: FloatArray, yaw_: FloatArray, g_: FloatArray) -> FloatArray:
        f = acc_ - np.column_stack([np.zeros_like(g_), np.zeros_like(g_), g_])
        zb = -f / np.linalg.norm(f, axis=1, keepdims=True)
        xc = np.column_stack([np.cos(yaw_), np.sin(yaw_), np.zeros_like(yaw_)])
        yb = np.cross(zb, xc)
        yb /= np.linalg.norm(yb, axis=1, keepdims=True)
        xb = np.cross(yb, zb)
        return np.stack([xb, yb, zb], axis=2)  # columns: body axes in NED

    c = dcm(acc, yaw, g)
    rot = Rotation.from_matrix(c)
    # Body rotation over each interval (sample k holds over (t_{k-1}, t_k]).
    rel = (rot[:-1].inv() * rot[1:]).as_rotvec() / dt
    w_nb = np.vstack([rel[:1] * 0.0, rel])
    # Mid-interval quantities.
    tm = t - dt / 2
    _, vel_m, _ = kin(tm)
    dv = np.vstack([np.zeros((1, 3)), np.diff(vel, axis=0)]) / dt
    c_mid = (rot[:-1] * Rotation.from_rotvec(rel * dt / 2)).as_matrix()
    c_mid = np.concatenate([c[:1], c_mid])
    lat_m = np.r_[lat[:1], 0.5 * (lat[1:] + lat[:-1])]
    h_m = np.r_[h[:1], 0.5 * (h[1:] + h[:-1])]
    w_ie = earth.OMEGA_IE * np.column_stack([np.cos(lat_m), np.zeros(n), -np.sin(lat_m)])
    rn, re = radii_of_curvature(lat_m, degrees=False)
    w_en = np.column_stack(
        [vel_m[:, 1] / (re + h_m), -vel_m[:, 0] / (rn + h_m), -vel_m[:, 1] * np.tan(lat_m) / (re + h_m)]
    )
    g_m = _gravity(lat0, h_m)
    f_n = dv - np.column_stack([np.zeros(n), np.zeros(n), g_m]) + np.cross(2 * w_ie + w_en, vel_m)
    f_true = np.einsum("nji,nj->ni", c_mid, f_n)
    w_true = w_nb + np.einsum("nji,nj->ni", c_mid, w_ie + w_en)

    # Sensor errors.
    temp = e.temp_start_c + e.temp_rise_c * (1.0 - np.exp(-t / e.temp_tau_s))
    th = thermal_model(preset, "gyro")
    b_t = (
        np.zeros((n, 3))
        if th is None
        else th.branch_bias(temp, "heating") - th.branch_bias(temp[:1], "heating")
    )
    bg = (
        rng.normal(0.0, e.gyro_turn_on_rad_s, 3)
        + np.cumsum(rng.normal(0.0, e.gyro_rw_rad_s_sqrt_s * math.sqrt(dt), (n, 3)), axis=0)
        + b_t
    )
    ba = rng.normal(0.0, e.accel_turn_on_m_s2, 3) + np.cumsum(
        rng.normal(0.0, e.accel_rw_m_s2_sqrt_s * math.sqrt(dt), (n, 3)), axis=0
    )
    airborne = ((t >= static_s) & (t <= spline.x[-1]))[:, None]
    gyro = w_true + bg + rng.normal(0.0, e.arw_rad_sqrt_s / math.sqrt(dt), (n, 3))
    gyro += airborne * rng.normal(0.0, e.vibration_gyro_rad_s, (n, 3))
    accel = f_true + ba + rng.normal(0.0, e.vrw_m_s_sqrt_s / math.sqrt(dt), (n, 3))
    accel += airborne * rng.normal(0.0, e.vibration_accel_m_s2, (n, 3))
    # The bias the filter can see is b_T relative to its own start; the model file knows b_T(T)
    # absolutely, so the absolute curve is kept in truth for TCZUPT.
    truth_extra = {"gyro_bias": bg, "accel_bias": ba, "temp": temp}
    imu = ImuLog(
        t,
        gyro,
        accel,
        temp,
        truth={},
        meta={
            "source": "simulated flight",
            "format": "simulated",
            "rate_hz": rate_hz,
            "seed": seed,
            "preset": preset_name,
        },
    )

    # GNSS at its own rate, with dropouts.
    tg = np.arange(0.0, t_end + 1e-9, 1.0 / gnss_rate_hz)
    keep = np.ones(tg.size, dtype=bool)
    for start, dur in gnss_dropouts:
        keep &= ~((tg >= start) & (tg < start + dur))
    tg = tg[keep]
    pg, vg, _ = kin(tg)
    hg = height_m - pg[:, 2]
    m = tg.size
    n_err = rng.normal(0.0, e.gnss_h_std_m, (m, 2))
    v_err = rng.normal(0.0, e.gnss_v_std_m, m)
    lat_g = CubicHermiteSpline(t, lat, lat_rate)(tg)
    lon_g = CubicHermiteSpline(t, lon, lon_rate)(tg)
    rn_g, re_g = radii_of_curvature(lat_g, degrees=False)
    gnss = GnssData(
        t=tg,
        lat=np.degrees(lat_g + n_err[:, 0] / (rn_g + hg)),
        lon=np.degrees(lon_g + n_err[:, 1] / ((re_g + hg) * np.cos(lat_g))),
        alt=hg + v_err,
        vel=vg + rng.normal(0.0, e.gnss_vel_std_m_s, (m, 3)),
        h_acc=np.full(m, e.gnss_h_std_m),
        v_acc=np.full(m, e.gnss_v_std_m),
        s_acc=np.full(m, e.gnss_vel_std_m_s),
    )
    tb = np.arange(0.0, t_end + 1e-9, 0.1)
    pb, _, _ = kin(tb)
    baro = BaroData(tb, height_m - pb[:, 2] + e.baro_offset_m + rng.normal(0.0, e.baro_std_m, tb.size))
    dec_err = rng.normal(0.0, e.mag_heading_bias_std_rad)
    m_n = np.array([20.0 * math.cos(dec_err), 20.0 * math.sin(dec_err), 45.0])
    tm_ = np.arange(0.0, t_end + 1e-9, 0.05)
    im = np.clip(np.round(tm_ * rate_hz).astype(int), 0, n - 1)
    mag_field = np.einsum("nji,j->ni", c[im], m_n) + rng.normal(0.0, e.mag_std_ut, (im.size, 3))
    mag = MagData(tm_, mag_field)
    euler = np.degrees(rot.as_euler("ZYX")[:, ::-1])
    truth = Trajectory(
        t,
        np.degrees(lat),
        np.degrees(lon),
        h,
        vel,
        euler,
        name="truth",
        extra=truth_extra | {"quat": _quat(rot)},
    )
    return Flight(
        imu,
        gnss,
        baro,
        mag,
        reference=None,
        truth=truth,
        imus={"IMU": imu},
        airborne=(static_s, float(spline.x[-1])),
        meta={"source": "simulated flight", "seed": seed, "preset": preset_name, "errors": e},
    )


def _quat(rot: Rotation) -> FloatArray:
    q = rot.as_quat()  # scalar last
    return np.column_stack([q[:, 3], q[:, :3]])


def imu_log_with_truth(flight: Flight) -> ImuLog:
    """The IMU log of a simulated ``flight`` as log format v1 carries it: the magnetometer
    interpolated to the IMU times (µT) and the truth as ``truth_*`` channels (lat, lon in deg,
    alt in m, NED velocity m/s, roll/pitch/yaw deg, gyro bias rad/s, accel bias m/s²) — what
    ``uasnav simulate --profile flight`` and the synthetic fleet write beside the GNSS CSV."""
    tr = flight.truth
    if tr is None or tr.vel is None or tr.euler_deg is None or flight.mag is None:
        raise InputError("flight: a simulated flight with truth and magnetometer is needed")
    t = flight.imu.t
    mag = np.column_stack([np.interp(t, flight.mag.t, flight.mag.field[:, i]) for i in range(3)])
    truth = {
        "lat": tr.lat,
        "lon": tr.lon,
        "alt": tr.alt,
        "vel": tr.vel,
        "euler_deg": tr.euler_deg,
        "gyro_bias": tr.extra["gyro_bias"],
        "accel_bias": tr.extra["accel_bias"],
    }
    return dataclasses.replace(flight.imu, mag=mag, truth=truth)


def matched_config_values(errors: FlightErrors | None = None) -> dict[str, float]:
    """nav-core settings matching :class:`FlightErrors` (noise densities including vibration,
    barometer and magnetometer σ): what a filter tuned to this simulator's sensors uses, for
    consistency (NEES) tests. Keys are those of :class:`uasnav.ins.InsConfig` fields and its
    ``extra`` dict (``mag_heading_std_rad``, ``baro_std_m``)."""
    e = errors or FlightErrors()
    rate = 100.0  # vibration σ per sample is given at the default IMU rate
    return {
        "sigma_vrw_m_s_sqrt_s": math.hypot(e.vrw_m_s_sqrt_s, e.vibration_accel_m_s2 / math.sqrt(rate)),
        "sigma_arw_rad_sqrt_s": math.hypot(e.arw_rad_sqrt_s, e.vibration_gyro_rad_s / math.sqrt(rate)),
        "sigma_abi_m_s2": e.accel_rw_m_s2_sqrt_s,
        "sigma_gbi_rad_s": e.gyro_rw_rad_s_sqrt_s,
        "mag_heading_std_rad": math.hypot(e.mag_heading_bias_std_rad, math.atan2(e.mag_std_ut, 20.0)),
        "baro_std_m": e.baro_std_m,
    }
