"""A multirotor waypoint-flight simulator with wind, for the thesis' Phantom-4 experiment (§5.1.4).

Horizontal point-mass model in NED (the altitude is held by the autopilot and ignored):

* guidance: along-track speed command limited by the cruise speed and by a braking curve
  v ≤ √(v_c² + 2 a_brake d) toward each waypoint, where d is the remaining distance and
  v_c = V_cruise · max(cos(θ/2), 0.1) the corner speed for a turn of θ (a stop at the last
  waypoint); cross-track error fed back with gain ``k_xtrack``; the next leg is taken when the
  vehicle passes the waypoint's bisector plane or comes within ``accept_m``;
* velocity loop: PI on ground velocity, its output (the horizontal specific force of the tilted
  thrust) limited by the maximum tilt, a = g·tan(tilt_max) (Table 16, P-mode 15°);
* aerodynamic drag on the air-relative velocity, −k_drag |v − w|(v − w), with k_drag chosen so
  that the drag balances the S-mode tilt (42°) at the maximum speed of 20 m/s (Table 16);
* wind: the mean vector plus Ornstein–Uhlenbeck gusts (σ, τ per axis), and a per-flight
  variation of the mean speed.

Telemetry is sampled at ``rate_hz`` with GNSS-like position/velocity noise. Everything is
deterministic from the seed.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from uasnav.errors import InputError
from uasnav.trajectory.features import wind_vector
from uasnav.trajectory.geometry import check_plan, signed_angle_deg
from uasnav.units import STANDARD_GRAVITY


@dataclass(frozen=True)
class MultirotorParams:
    """Phantom-4-like parameters (Table 16 and the experiment of §5.1.4.1).

    Attributes
    ----------
    cruise_ms : commanded ground speed (m/s), 3.33 in the thesis.
    altitude_m : flight altitude (m), 12.
    tilt_max_deg : tilt limit of the velocity loop (deg), P-mode 15°.
    k_drag_per_m : quadratic drag coefficient (1/m): g·tan(42°)/20² by default.
    kp_vel_per_s, ki_vel_per_s2 : velocity-loop gains (1/s, 1/s²).
    a_brake_ms2 : planned braking deceleration toward corners (m/s²).
    k_xtrack_per_s : cross-track feedback gain (1/s).
    accept_m : waypoint acceptance radius (m).
    speed_sigma_frac : flight-to-flight relative spread of the speed actually tracked (a
        random scale per flight, e.g. battery state, speed-controller calibration): effects the
        features cannot explain. 3 % makes the spread of t_Real over repeated flights match
        Table 17 (24.5–28.2 s, about ±4 %).
    """

    cruise_ms: float = 3.33
    altitude_m: float = 12.0
    tilt_max_deg: float = 15.0
    k_drag_per_m: float = STANDARD_GRAVITY * np.tan(np.radians(42.0)) / 20.0**2
    kp_vel_per_s: float = 1.2
    ki_vel_per_s2: float = 0.25
    a_brake_ms2: float = 0.8
    k_xtrack_per_s: float = 0.6
    accept_m: float = 0.5
    speed_sigma_frac: float = 0.03


@dataclass(frozen=True)
class WindModel:
    """Mean wind (speed m/s, from-direction deg) with Ornstein–Uhlenbeck gusts.

    The thesis' experiment: 2.78 m/s from NNE (22.5°).
    """

    speed_ms: float = 2.78
    from_deg: float = 22.5
    gust_sigma_ms: float = 0.5
    gust_tau_s: float = 3.0
    flight_speed_sigma_ms: float = 0.25


@dataclass
class Telemetry:
    """One simulated (or read) flight: time (s), position (n, 2) and velocity (n, 2) north/east.

    ``wind_ne`` is the mean wind velocity of the flight (m/s, toward), ``cruise_ms`` the
    commanded speed, ``plan_ne`` the waypoints flown.
    """

    t: np.ndarray
    pos_ne: np.ndarray
    vel_ne: np.ndarray
    plan_ne: np.ndarray
    wind_ne: np.ndarray
    cruise_ms: float
    meta: dict = field(default_factory=dict)
    #: Altitude (m, up, the plan's vertical frame) and vertical speed (m/s, up) of each sample,
    #: for a flight with an altitude profile (``alt_m`` given to :func:`simulate_flight`).
    alt_m: np.ndarray | None = None
    vz_ms: np.ndarray | None = None


@dataclass(frozen=True)
class VerticalLimits:
    """The autopilot's vertical limits (ArduPilot ``WPNAV_SPEED_UP``, ``WPNAV_SPEED_DN``,
    ``WPNAV_ACCEL_Z``; PX4 ``MPC_Z_VEL_MAX_UP/DN``, ``MPC_ACC_UP/DOWN_MAX``), defaults ArduPilot's.

    Attributes
    ----------
    climb_ms, descent_ms : vertical speed limits up / down (> 0), m/s.
    accel_z_ms2 : vertical acceleration limit, m/s².
    kp_z_per_s : altitude-error gain of the vertical velocity command, 1/s.
    tau_z_s : time constant of the vertical velocity loop, s.
    """

    climb_ms: float = 2.5
    descent_ms: float = 1.5
    accel_z_ms2: float = 1.0
    kp_z_per_s: float = 1.0
    tau_z_s: float = 0.3


def _corner_speed(cruise: float, turn_deg: float) -> float:
    return cruise * max(np.cos(np.radians(abs(turn_deg)) / 2.0), 0.1)


def simulate_flight(
    plan_ne: np.ndarray,
    params: MultirotorParams | None = None,
    wind: WindModel | None = None,
    seed: int = 0,
    dt: float = 0.02,
    rate_hz: float = 10.0,
    pos_noise_m: float = 0.05,
    vel_noise_ms: float = 0.03,
    max_time_s: float | None = None,
    alt_m: np.ndarray | None = None,
    leg_speed_ms: np.ndarray | None = None,
    vertical: VerticalLimits | None = None,
) -> Telemetry:
    """Fly ``plan_ne`` (north/east m) from rest at its first waypoint to rest at its last.

    Returns the telemetry sampled at ``rate_hz``. Raises :class:`InputError` for a bad plan
    and :class:`~uasnav.errors.NumericalError` if the vehicle does not arrive in time.

    With ``alt_m`` (shape (n,), m up) the vehicle also flies the altitude profile, as
    ArduPilot's waypoint controller does on a sloped leg: the altitude target moves along the
    leg with the along-track progress, the vertical velocity command (slope × along-track speed
    plus ``kp_z``·altitude error) is limited to ``vertical.climb_ms``/``descent_ms`` and its
    change to ``vertical.accel_z_ms2``, and the along-track speed is capped so that the leg's
    slope never asks for more than the vertical limit. ``leg_speed_ms`` (shape (n − 1,), m/s)
    sets each leg's commanded speed (``DO_CHANGE_SPEED``; NaN = the cruise speed). Neither
    draws random numbers: without them a flight is identical to the 2D one.
    """
    from uasnav.errors import NumericalError

    prm = params or MultirotorParams()
    wm = wind or WindModel()
    p_plan = check_plan(plan_ne)
    rng = np.random.default_rng(seed)
    n_wp = p_plan.shape[0]
    d = np.diff(p_plan, axis=0)
    seg_len = np.hypot(d[:, 0], d[:, 1])
    tang = d / seg_len[:, None]
    turns = [0.0] + [float(signed_angle_deg(d[k - 1], d[k])) for k in range(1, n_wp - 1)] + [180.0]
    speed_this_flight = max(wm.speed_ms + rng.normal(0.0, wm.flight_speed_sigma_ms), 0.0)
    scale = float(np.clip(1.0 + rng.normal(0.0, prm.speed_sigma_frac), 0.5, 1.5))
    cruise = prm.cruise_ms * scale
    # per-leg commanded speed (the flight's spread applies to every leg)
    v_leg = np.full(n_wp - 1, cruise)
    if leg_speed_ms is not None:
        ls = np.asarray(leg_speed_ms, dtype=float)
        if ls.shape != (n_wp - 1,) or np.any(ls[np.isfinite(ls)] <= 0):
            raise InputError(f"leg_speed_ms needs {n_wp - 1} speeds > 0 (NaN = cruise), got {ls}")
        v_leg = np.where(np.isfinite(ls), ls * scale, cruise)
    vl = vertical or VerticalLimits()
    z_wp = None
    if alt_m is not None:
        z_wp = np.asarray(alt_m, dtype=float)
        if z_wp.shape != (n_wp,) or not np.isfinite(z_wp).all():
            raise InputError(f"alt_m needs {n_wp} finite altitudes, got shape {z_wp.shape}")
        slope = np.diff(z_wp) / seg_len
        # the along-track speed at which the leg's slope asks for exactly the vertical limit
        v_slope = np.where(slope > 0, vl.climb_ms, vl.descent_ms) / np.maximum(np.abs(slope), 1e-12)
        v_leg = np.minimum(v_leg, v_slope)
    v_corner = [
        _corner_speed(min(v_leg[k - 1], v_leg[k]), turns[k]) if 0 < k < n_wp - 1 else 0.0 for k in range(n_wp)
    ]
    if leg_speed_ms is None and z_wp is None:
        v_corner = [_corner_speed(cruise, turns[k]) if k < n_wp - 1 else 0.0 for k in range(n_wp)]
    w_mean = wind_vector(speed_this_flight, wm.from_deg)
    a_max = STANDARD_GRAVITY * np.tan(np.radians(prm.tilt_max_deg))
    total = seg_len.sum()
    t_end = max_time_s or 20.0 + 4.0 * total / prm.cruise_ms
    n_steps = int(t_end / dt)
    every = max(round(1.0 / (rate_hz * dt)), 1)
    pos = p_plan[0].copy()
    vel = np.zeros(2)
    integ = np.zeros(2)
    gust = rng.normal(0.0, wm.gust_sigma_ms, 2)
    phi = np.exp(-dt / wm.gust_tau_s)
    k = 0
    out_t, out_p, out_v, out_z, out_vz = [], [], [], [], []
    arrived = False
    z = float(z_wp[0]) if z_wp is not None else 0.0
    vz = 0.0
    vz_cmd_prev = 0.0
    for step in range(n_steps):
        t = step * dt
        a_pt = p_plan[k]
        rel = pos - a_pt
        along = float(rel @ tang[k])
        cross = rel - along * tang[k]
        remaining = seg_len[k] - along
        if k < n_wp - 2:
            # Bisector plane of the corner: switch legs once past it (or within accept_m).
            bis = tang[k] + tang[k + 1]
            past = float((pos - p_plan[k + 1]) @ bis) >= 0.0 if np.linalg.norm(bis) > 1e-9 else remaining <= 0
            if past or np.hypot(*(pos - p_plan[k + 1])) < prm.accept_m:
                k += 1
                continue
        elif remaining < 0.05 and np.hypot(*vel) < 0.05:
            arrived = True
        v_lim = np.sqrt(v_corner[k + 1] ** 2 + 2.0 * prm.a_brake_ms2 * max(remaining, 0.0))
        v_along = min(v_leg[k], v_lim)
        if k == n_wp - 2 and remaining < 0:
            v_along = prm.k_xtrack_per_s * remaining
        v_cmd = v_along * tang[k] - prm.k_xtrack_per_s * cross
        err = v_cmd - vel
        a_cmd = prm.kp_vel_per_s * err + integ
        na = np.hypot(*a_cmd)
        if na > a_max:
            a_cmd *= a_max / na
        else:
            integ += prm.ki_vel_per_s2 * err * dt
        gust = phi * gust + np.sqrt(1 - phi**2) * wm.gust_sigma_ms * rng.normal(size=2)
        va = vel - (w_mean + gust)
        acc = a_cmd - prm.k_drag_per_m * np.hypot(*va) * va
        if z_wp is not None:
            frac = float(np.clip(along / seg_len[k], 0.0, 1.0))
            z_target = z_wp[k] + frac * (z_wp[k + 1] - z_wp[k])
            vz_cmd = slope[k] * max(v_along, 0.0) + vl.kp_z_per_s * (z_target - z)
            vz_cmd = float(np.clip(vz_cmd, -vl.descent_ms, vl.climb_ms))
            # acceleration-limited command (WPNAV_ACCEL_Z), then a first-order velocity loop
            dv_max = vl.accel_z_ms2 * dt
            vz_cmd = float(np.clip(vz_cmd, vz_cmd_prev - dv_max, vz_cmd_prev + dv_max))
            vz_cmd_prev = vz_cmd
            if arrived and abs(z_wp[-1] - z) > 0.05:
                arrived = False  # a stop is a stop in altitude too
        if step % every == 0:
            out_t.append(t)
            out_p.append(pos.copy())
            out_v.append(vel.copy())
            out_z.append(z)
            out_vz.append(vz)
            if arrived:
                break
        vel = vel + acc * dt
        pos = pos + vel * dt
        if z_wp is not None:
            vz += (vz_cmd - vz) * dt / vl.tau_z_s
            z += vz * dt
    if not arrived:
        raise NumericalError(f"simulated vehicle did not reach the last waypoint within {t_end:.0f} s")
    t_arr = np.array(out_t)
    p_arr = np.array(out_p) + rng.normal(0.0, pos_noise_m, (len(out_t), 2))
    v_arr = np.array(out_v) + rng.normal(0.0, vel_noise_ms, (len(out_t), 2))
    return Telemetry(
        t=t_arr,
        pos_ne=p_arr,
        vel_ne=v_arr,
        plan_ne=p_plan,
        wind_ne=w_mean,
        cruise_ms=prm.cruise_ms,
        meta={
            "seed": seed,
            "wind_speed_ms": speed_this_flight,
            "wind_from_deg": wm.from_deg,
            "speed_tracked_ms": cruise,
        },
        alt_m=np.array(out_z) if z_wp is not None else None,
        vz_ms=np.array(out_vz) if z_wp is not None else None,
    )


def _plan_from_headings(headings_deg: list[float], legs_m: list[float]) -> np.ndarray:
    pts = [np.zeros(2)]
    for h, length in zip(headings_deg, legs_m, strict=True):
        r = np.radians(h)
        pts.append(pts[-1] + length * np.array([np.cos(r), np.sin(r)]))
    return np.array(pts)


def phantom4_plans() -> dict[str, np.ndarray]:
    """The two test trajectories (Figure 57 analogue), north/east m.

    Their corners reproduce the four training elements of §5.1.4.2 in the thesis' wind
    (2.78 m/s from 22.5°, blowing toward 202.5°): (θ, θ_w) = (72°, 64°) and (105°, 140°, a
    left turn folded by the mirror symmetry) on trajectory A, (80°, 90°) and (130°, 170°) on
    trajectory B, with further corners (132°, 352°), (97.5°, 10°), (102.5°, 272.5°) in between.
    A right turn of θ whose first segment has course h has θ_w = 202.5° − h.
    """
    plan_a = _plan_from_headings([138.5, 210.5, 342.5, 237.5], [45.0, 45.0, 45.0, 40.0])
    plan_b = _plan_from_headings([112.5, 192.5, 290.0, 32.5, 162.5], [45.0, 40.0, 40.0, 45.0, 40.0])
    return {"A": plan_a, "B": plan_b}


def phantom4_experiment(
    n_flights: int = 10, seed: int = 0, wind: WindModel | None = None
) -> dict[str, list[Telemetry]]:
    """Both trajectories flown ``n_flights`` times each (thesis: 10; 7 train, 3 test)."""
    if n_flights < 1:
        raise InputError(f"n_flights must be ≥ 1, got {n_flights}")
    out: dict[str, list[Telemetry]] = {}
    for j, (name, plan) in enumerate(phantom4_plans().items()):
        out[name] = [
            simulate_flight(plan, wind=wind, seed=seed * 1000 + 100 * j + i) for i in range(n_flights)
        ]
    return out


__all__ = [
    "MultirotorParams",
    "Telemetry",
    "VerticalLimits",
    "WindModel",
    "phantom4_experiment",
    "phantom4_plans",
    "simulate_flight",
]
