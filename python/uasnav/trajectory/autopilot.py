"""Mission execution models per autopilot family: when the vehicle reaches each item of a
mission plan, and when it touches down, as ArduCopter, PX4 multicopter or ArduPlane/QuadPlane
fly it, with the parameters of the vehicle's log or the firmware's defaults.

Every time is seconds from the start of the mission (lift-off, or the moment AUTO was entered
when the vehicle was already flying).

Kinematics (closed forms, one leg at a time)
--------------------------------------------
A leg of length d flown from speed v₀ to speed v₁ under the speed limit v and the acceleration
limit a (and jerk limit j where the firmware has one) takes

* speed change Δv: T(Δv) = Δv/a + a/j if Δv ≥ a²/j, else 2·√(Δv/j) (jerk-limited, symmetric
  S-curve; without a jerk limit T = Δv/a), covering (v₀ + v₁)/2 · T; ArduCopter 4.x's
  ``SCurve`` shapes the jerk itself as a raised cosine of duration t_j, adding t_j
  (:func:`speed_change_time`, :func:`arducopter_jerk_time`);
* the peak speed v_p ≤ v is the largest one whose speed-up and slow-down fit in d; the rest is
  flown at v_p.

Vertical legs and climbs use the vertical limits the same way; a 3-D leg takes the longer of its
horizontal and vertical times (both controllers run at once).

Family rules
------------
ArduCopter (``AC_WPNav``): ``WPNAV_SPEED/ACCEL/SPEED_UP/SPEED_DN/ACCEL_Z``; firmware 3.x flies
straight lines (no jerk limit; its target slows down at 2·``WPNAV_ACCEL``, the
``get_slow_down_speed`` √(4·a·d) law; a waypoint followed by another waypoint without a delay is
a "fast waypoint" passed at full speed); 4.x plans S-curves (``WPNAV_JERK``) and rounds corners
within ``WPNAV_RADIUS`` at the lateral acceleration ``WPNAV_ACCEL_C`` (0: 2·``WPNAV_ACCEL``).
Take-off climbs vertically; LAND descends at ``LAND_SPEED_HIGH`` (0: ``WPNAV_SPEED_DN``) down
to ``LAND_ALT_LOW`` and at ``LAND_SPEED`` below; RTL climbs to ``RTL_ALT`` limited by the
cone ``RTL_CONE_SLOPE`` (:func:`arducopter_rtl_altitude`), returns at ``RTL_SPEED``
(0: ``WPNAV_SPEED``), loiters ``RTL_LOIT_TIME`` — longer when ``WP_YAW_BEHAVIOR`` 1 or 3 turned
the nose home and it must turn back to the armed heading (:func:`arducopter_rtl_yaw_wait`) —
and lands (or descends to ``RTL_ALT_FINAL`` and hovers when it is non-zero). ArduCopter never
waits for its heading before or along a leg: ``ModeAuto::wp_run`` flies the waypoint
controller and points the nose at the same time, and ``verify_nav_wp`` completes on
``reached_wp_destination`` and the hold alone (``ArduCopter/mode_auto.cpp`` at ArduPilot
00132531; ``AC_WPNav::advance_wp_target_along_track`` of 3.x reaches a waypoint on the track
and ``WPNAV_RADIUS`` alone), so ``WP_YAW_BEHAVIOR`` costs no time in AUTO.

PX4 multicopter (``FlightTaskAuto`` + ``PositionSmoothing``): ``MPC_XY_CRUISE``,
``MPC_ACC_HOR``, ``MPC_JERK_AUTO``, ``MPC_Z_V_AUTO_UP/DN`` (before 1.12: ``MPC_Z_VEL_MAX_UP/DN``),
corner speed √(a·R·tan(α/2)) with R = ``NAV_ACC_RAD`` and α the angle between the legs
(``computeMaxSpeedInWaypoint``); with ``MPC_YAW_MODE`` 4 ("yaw first") the vehicle stops at
each corner and turns at ``MPC_YAWRAUTO_MAX`` before the next leg; take-off at
``MPC_TKO_SPEED`` after a ``MPC_TKO_RAMP_T`` ramp; landing at ``MPC_Z_V_AUTO_DN`` above
``MPC_LAND_ALT1``, blending linearly to ``MPC_LAND_SPEED`` at ``MPC_LAND_ALT2`` and below.

Fixed wing and QuadPlane (ArduPlane): legs at the cruise airspeed (``AIRSPEED_CRUISE``, before
4.5 ``TRIM_ARSPD_CM``), corners as circular arcs of radius v²/(g·tan φ) with φ = ``ROLL_LIMIT_DEG``
(before 4.5 ``LIM_ROLL_CD``); VTOL take-off and landing climb and descend at
``Q_WP_SPEED_UP/DN`` (the last ``Q_LAND_FINAL_ALT`` at ``Q_LAND_SPEED``) plus a transition of
``Q_TRANSITION_MS``.

Waypoints closer together than the corner geometry needs (a VTOL landing 1.85 m from the last
waypoint, PX4 waypoints metres apart) are flown as short legs: each leg's own speed profile
never exceeds what its length allows, so no leg is merged or refused.

Terrain frames (``MAV_FRAME`` 10/11) are taken as relative to home (flat ground): the models
know no terrain.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from uasnav.errors import InputError
from uasnav.io.mission_plan import (
    MAV_CMD_DO_CHANGE_SPEED,
    MAV_CMD_NAV_LAND,
    MAV_CMD_NAV_LOITER_TIME,
    MAV_CMD_NAV_LOITER_TURNS,
    MAV_CMD_NAV_LOITER_UNLIM,
    MAV_CMD_NAV_RETURN_TO_LAUNCH,
    MAV_CMD_NAV_SPLINE_WAYPOINT,
    MAV_CMD_NAV_TAKEOFF,
    MAV_CMD_NAV_VTOL_LAND,
    MAV_CMD_NAV_VTOL_TAKEOFF,
    MAV_CMD_NAV_WAYPOINT,
    AltitudeFrame,
    MissionPlan,
    flight_sequence,
)

G0 = 9.80665
MAV_CMD_NAV_DELAY = 93
#: Families :func:`predict_mission` knows.
FAMILIES = ("arducopter", "px4-mc", "plane")


# --------------------------------------------------------------------------- kinematics
def speed_change_time(dv: float, accel: float, jerk: float | None = None, jerk_time: float = 0.0) -> float:
    """Time (s) to change speed by ``dv`` (m/s) at acceleration limit ``accel`` (m/s²) and, when
    given, jerk limit ``jerk`` (m/s³): Δv/a + a/j when the acceleration limit is reached
    (Δv ≥ a²/j), else 2·√(Δv/j); Δv/a without a jerk limit.

    With ``jerk_time`` t_j > 0 the jerk itself rises and falls as a raised cosine over t_j
    (ArduPilot's ``SCurve``: the snap limit), so the acceleration ramps take t₂ + 2·t_j with
    t₂ = a/j − t_j at constant jerk: T = Δv/a + a/j + t_j when a is reached
    (Δv ≥ a·(a/j + t_j)); below, the peak acceleration A solves A²/j + A·t_j = Δv and
    T = 2·(A/j + t_j); below Δv = 2·j·t_j² the jerk is lowered at fixed t_j and T = 4·t_j.
    Every profile is point-symmetric about its middle, so it covers (v₀ + v₁)/2 · T.

    >>> speed_change_time(5.0, 1.0)
    5.0
    >>> speed_change_time(5.0, 1.0, 1.0)
    6.0
    >>> speed_change_time(5.0, 1.0, 1.0, 0.3)
    6.3
    """
    dv = abs(dv)
    if dv == 0.0:
        return 0.0
    if jerk is None or not math.isfinite(jerk) or jerk <= 0:
        return dv / accel
    tj = max(jerk_time, 0.0) if math.isfinite(jerk_time) else 0.0
    if tj > 0.0:
        if accel < jerk * tj:
            # the raised cosine alone would exceed the acceleration limit: SCurve shortens it
            # to t_j' = √(a·t_j/j) at the same snap (j' = j·t_j'/t_j), so that a = j'·t_j'
            tj_short = math.sqrt(accel * tj / jerk)
            jerk, tj = jerk * tj_short / tj, tj_short
        if dv >= accel * (accel / jerk + tj):
            return dv / accel + accel / jerk + tj
        if dv >= 2.0 * jerk * tj * tj:
            a_peak = 0.5 * jerk * (-tj + math.sqrt(tj * tj + 4.0 * dv / jerk))
            return 2.0 * (a_peak / jerk + tj)
        return 4.0 * tj
    if dv >= accel * accel / jerk:
        return dv / accel + accel / jerk
    return 2.0 * math.sqrt(dv / jerk)


def _change(
    v0: float, v1: float, accel: float, jerk: float | None, jerk_time: float = 0.0
) -> tuple[float, float]:
    t = speed_change_time(v1 - v0, accel, jerk, jerk_time)
    return t, 0.5 * (v0 + v1) * t


def leg_time(
    d: float,
    v_max: float,
    accel: float,
    jerk: float | None = None,
    v0: float = 0.0,
    v1: float = 0.0,
    decel: float | None = None,
    jerk_time: float = 0.0,
) -> tuple[float, float]:
    """Time (s) to fly ``d`` m from speed ``v0`` to ``v1`` under ``v_max``, the acceleration
    ``accel`` (``decel`` for slowing down, default the same), the jerk limit and the raised-cosine
    jerk time ``jerk_time`` (:func:`speed_change_time`); and the speed the leg actually ends at
    (lower than ``v1`` when the leg is too short to reach it).

    >>> leg_time(100.0, 5.0, 1.0)  # trapezoid: 100/5 + 5/1
    (25.0, 0.0)
    """
    if d <= 0.0:
        return 0.0, v0
    dec = decel or accel
    v0 = min(v0, v_max)
    v1 = min(v1, v_max)
    # the end speed reachable from v0 within d
    _, d01 = _change(v0, v1, accel if v1 > v0 else dec, jerk, jerk_time)
    if d01 > d:
        if v1 > v0:  # cannot reach v1: accelerate all the way
            vb = math.sqrt(v0 * v0 + 2.0 * accel * d)
        else:  # cannot slow down to v1: arrive faster (the autopilot would overshoot the corner)
            vb = math.sqrt(max(v0 * v0 - 2.0 * dec * d, 0.0))
        vb = min(vb, v_max)
        return 2.0 * d / max(v0 + vb, 1e-9), vb

    def dist(vp: float) -> tuple[float, float]:
        ta, da = _change(v0, vp, accel, jerk, jerk_time)
        tb, db = _change(vp, v1, dec, jerk, jerk_time)
        return ta + tb, da + db

    lo, hi = max(v0, v1), v_max
    t_lh, d_lh = dist(hi)
    if d_lh <= d:
        return t_lh + (d - d_lh) / hi, v1
    for _ in range(60):  # bisection on the peak speed
        mid = 0.5 * (lo + hi)
        if dist(mid)[1] > d:
            hi = mid
        else:
            lo = mid
    t_p, d_p = dist(lo)
    return t_p + (d - d_p) / max(lo, 1e-9), v1


def banded_descent_time(h: float, v_high: float, v_low: float, alt_low: float) -> float:
    """Time (s) to descend ``h`` m at ``v_high`` down to ``alt_low`` m and ``v_low`` below
    (ArduCopter LAND; accelerations neglected, the land controller's are fast)."""
    if h <= 0:
        return 0.0
    low = min(h, alt_low)
    return (h - low) / v_high + low / v_low


def px4_land_time(h: float, v_dn: float, v_land: float, alt1: float, alt2: float) -> float:
    """Time (s) to land from ``h`` m with PX4's landing speed: ``v_dn`` above ``alt1``, linear
    in height from ``v_dn`` to ``v_land`` between ``alt1`` and ``alt2``, ``v_land`` below.
    In the blend v(z) = v_land + (v_dn − v_land)·(z − alt2)/(alt1 − alt2), so the time across
    it is (alt1 − alt2)·ln(v_dn/v_land)/(v_dn − v_land)."""
    if h <= 0:
        return 0.0
    t = 0.0
    if h > alt1:
        t += (h - alt1) / v_dn
    lo, hi = alt2, min(h, alt1)
    if hi > lo and alt1 > alt2:
        k = (v_dn - v_land) / (alt1 - alt2)
        if abs(k) < 1e-12:
            t += (hi - lo) / v_land
        else:
            t += (math.log(v_land + k * (hi - lo)) - math.log(v_land)) / k
    t += min(h, alt2) / v_land
    return t


def px4_max_speed_from_distance(d: float, accel: float, jerk: float, v_final: float = 0.0) -> float:
    """PX4's speed limit at distance ``d`` (m) from a waypoint to be passed at ``v_final``
    (``math::trajectory::computeMaxSpeedFromDistance``):
    v = ½·(−b + √(b² + 8·a·d + 4·v_f²)) with b = 4·a²/j.

    >>> round(px4_max_speed_from_distance(4.4, 3.0, 4.0), 3)
    2.33
    """
    b = 4.0 * accel * accel / jerk
    return 0.5 * (-b + math.sqrt(b * b + 8.0 * accel * max(d, 0.0) + 4.0 * v_final * v_final))


def px4_braking_time(d1: float, d2: float, accel: float, jerk: float, v_final: float = 0.0) -> float:
    """Time (s) to go from ``d1`` to ``d2`` m before the waypoint following PX4's speed limit
    (:func:`px4_max_speed_from_distance`). With w = √(b² + 8·a·d + 4·v_f²), dd = w·dw/(4a) and
    v = (w − b)/2, so t = [w + b·ln(w − b)] / (2a) between the two ends."""
    if d1 <= d2:
        return 0.0
    b = 4.0 * accel * accel / jerk

    def w(d: float) -> float:
        return math.sqrt(b * b + 8.0 * accel * d + 4.0 * v_final * v_final)

    w1, w2 = w(d1), w(d2)
    return ((w1 - w2) + b * math.log((w1 - b) / max(w2 - b, 1e-12))) / (2.0 * accel)


def px4_leg_time(
    d: float,
    v_max: float,
    accel: float,
    jerk: float,
    v0: float,
    v_final: float,
    accept_m: float,
    lag_s: float,
) -> tuple[float, float]:
    """Time (s) until PX4 accepts a waypoint ``d`` m away, and the speed then: speeding up
    (jerk-limited) from ``v0`` until the speed meets the braking limit
    (:func:`px4_max_speed_from_distance`, or ``v_max``), then following it down to where the
    vehicle — ``lag_s``·v behind its trajectory (1/``MPC_XY_P``) — is ``accept_m`` from the
    waypoint."""

    def v_lim(x: float) -> float:
        return min(v_max, px4_max_speed_from_distance(x, accel, jerk, v_final))

    # where the acceptance happens on the trajectory: d_a + lag·v(d_a) = accept
    lo, hi = 0.0, max(accept_m, 0.0)
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        if mid + lag_s * v_lim(mid) > accept_m:
            hi = mid
        else:
            lo = mid
    d_acc = lo
    if d <= d_acc:
        return 0.0, min(v0, v_lim(d))
    v0 = min(v0, v_max)
    if v0 >= v_lim(d):  # already at the limit: follow it
        return _braking_with_cruise(d, d_acc, v_max, accel, jerk, v_final), v_lim(d_acc)
    # meet the limit: bisection on the speed reached by speeding up
    a_lo, a_hi = v0, v_lim(d)
    for _ in range(50):
        vm = 0.5 * (a_lo + a_hi)
        t_a, x_a = _change(v0, vm, accel, jerk)
        if x_a > d - d_acc or vm > v_lim(d - x_a):
            a_hi = vm
        else:
            a_lo = vm
    t_a, x_a = _change(v0, a_lo, accel, jerk)
    return t_a + _braking_with_cruise(d - x_a, d_acc, v_max, accel, jerk, v_final), v_lim(d_acc)


def _braking_with_cruise(
    d1: float, d2: float, v_max: float, accel: float, jerk: float, v_final: float
) -> float:
    """Time from ``d1`` to ``d2`` before the waypoint at min(``v_max``, the braking limit)."""
    b = 4.0 * accel * accel / jerk
    # the distance where the braking limit equals v_max: v_max² + b·v_max = 2a·d + v_f²
    d_c = max((v_max * v_max + b * v_max - v_final * v_final) / (2.0 * accel), 0.0)
    t = 0.0
    if d1 > d_c:
        t += (d1 - max(d_c, d2)) / v_max
        d1 = max(d_c, d2)
    return t + px4_braking_time(d1, d2, accel, jerk, v_final)


# --------------------------------------------------------------------------- parameters
@dataclass(frozen=True)
class Default:
    """A firmware default and where it is defined.

    Attributes
    ----------
    value : float
        The default in SI units (m, m/s, m/s², m/s³, s, deg).
    source : str
        ``"<file> <version>: <NAME> <number> <unit>"``, the number in the firmware's own unit.
    verified : str
        Where the number was read in the public source: the file as stored at a commit, or the
        layout of the file that identifies the release (names the commit when known).
    """

    value: float
    source: str
    verified: str = ""


# Stored versions of the firmware sources the defaults below were read in (public GitHub):
_AC3_WPNAV = "AC_WPNav.h of Copter 3.x (WPNAV_ACCELERATION 100, WPNAV_WP_SPEED 500 in the header)"
_AC4_WPNAV = "AC_WPNav.cpp with ACCEL_C and the SCurve legs (Copter 4.x var_info)"
_AC_CONFIG = "ArduCopter/config.h (LAND_SPEED 50, RTL_ALT 1500, RTL_LOITER_TIME 5000, RTL_ALT_FINAL 0)"
_AC36_PARAMS = "ArduCopter/Parameters.cpp with Copter::ModeFlowHold (3.6): ParametersG2 LAND_ALT_LOW 1000"
_AC45_PARAMS = "ArduCopter/Parameters.cpp with rtl_speed_cms/land_speed_high_cms (4.5+)"
_AC45_CONFIG = (
    "ArduCopter/config.h at HoodTechMech/ardupilot_4p5 0c1b263c (Copter 4.5: RTL_CONE_SLOPE_DEFAULT 3.0, "
    "RTL_MIN_CONE_SLOPE 0.5, RTL_ALT_MIN 30, RTL_CLIMB_MIN_DEFAULT 0, "
    "WP_YAW_BEHAVIOR_DEFAULT LOOK_AT_NEXT_WP_EXCEPT_RTL)"
)
_AC36_RTL = (
    "ArduCopter/control_rtl.cpp of the 3.5–3.6 layout (Location_Class): rtl_compute_return_target "
    "applies RTL_CONE_SLOPE with RTL_ABS_MIN_CLIMB"
)
_AC3_CONFIG_YAW = (
    "ArduCopter/config.h of Copter 3.x (AUTO_YAW_SLEW_RATE 60 deg/s, "
    "WP_YAW_BEHAVIOR_DEFAULT LOOK_AT_NEXT_WP_EXCEPT_RTL)"
)
_ATC_TC = (
    "libraries/AC_AttitudeControl/AC_AttitudeControl.cpp (Copter and Sub: "
    "AC_ATTITUDE_CONTROL_INPUT_TC_DEFAULT 0.15f 'Medium'); AC_WPNav.cpp calc_scurve_jerk_and_snap"
)
_ATC_SLEW = (
    "libraries/AC_AttitudeControl/AC_AttitudeControl.h (AC_ATTITUDE_CONTROL_SLEW_YAW_DEFAULT_CDS 6000 "
    "→ ATC_SLEW_YAW)"
)
_PX4_111 = "mc_pos_control_params.c of the v1.11 layout (defines MPC_SPOOLUP_TIME; no MPC_Z_V_AUTO_*)"
_PX4_112 = "mc_pos_control_params.c of the v1.12–1.13 layout (defines MPC_Z_V_AUTO_*, SYS_VEHICLE_RESP)"
_PX4_114 = "multicopter_autonomous_params.c at 456c5516 (v1.14 split layout)"
_PX4_MAIN = "multicopter_*_params.yaml at 6ffdc936 (main; MPC_YAWRAUTO_MAX is 60 there)"
_PX4_NAV = "navigator_params.c (NAV_ACC_RAD 10, NAV_MC_ALT_RAD 0.8)"
_PX4_MIS = "mission_params.c and mission_params.yaml at 4631d99a (MIS_YAW_ERR 12, MIS_YAW_TMT −1)"
_PX4_RTL = (
    "rtl_params.c: RTL_RETURN_ALT 60, RTL_DESCEND_ALT 30 in every layout; RTL_LAND_DELAY −1 (old) / 0 (new)"
)
_PLANE_CONFIG = "ArduPlane/config.h (AIRSPEED_CRUISE 12, ROLL_LIMIT_DEG 45, WP_RADIUS_DEFAULT 90)"
_QPLANE = "ArduPlane/quadplane.cpp var_info (TRANSITION_MS 5000, LAND_SPEED 50, LAND_FINAL_ALT 6)"
_TECS = "libraries/AP_TECS/AP_TECS.cpp var_info (CLMB_MAX 5.0, SINK_MAX 5.0)"

#: ArduCopter defaults, SI units, by major version. 3.x keeps the ``WPNAV_*`` defaults in
#: ``libraries/AC_WPNav/AC_WPNav.h``, 4.x in ``AC_WPNav.cpp`` (``WPNAV_ACCELERATION`` in the
#: header); ``LAND_SPEED``, ``RTL_ALT``, ``RTL_LOIT_TIME``, ``RTL_ALT_FINAL`` are ``config.h``
#: macros used by ``ArduCopter/Parameters.cpp``, which defines ``LAND_SPEED_HIGH``, ``RTL_SPEED``
#: and ``LAND_ALT_LOW`` (``ParametersG2``) itself.
ARDUCOPTER_DEFAULTS: dict[str, dict[str, Default]] = {
    "3": {
        "WPNAV_SPEED": Default(5.0, "AC_WPNav.h Copter-3.6: WPNAV_WP_SPEED 500 cm/s", _AC3_WPNAV),
        "WPNAV_ACCEL": Default(1.0, "AC_WPNav.h Copter-3.6: WPNAV_ACCELERATION 100 cm/s²", _AC3_WPNAV),
        "WPNAV_SPEED_UP": Default(2.5, "AC_WPNav.h Copter-3.6: WPNAV_WP_SPEED_UP 250 cm/s", _AC3_WPNAV),
        "WPNAV_SPEED_DN": Default(1.5, "AC_WPNav.h Copter-3.6: WPNAV_WP_SPEED_DOWN 150 cm/s", _AC3_WPNAV),
        "WPNAV_ACCEL_Z": Default(
            1.0, "AC_WPNav.h Copter-3.6: WPNAV_WP_ACCEL_Z_DEFAULT 100 cm/s²", _AC3_WPNAV
        ),
        "WPNAV_RADIUS": Default(2.0, "AC_WPNav.h Copter-3.6: WPNAV_WP_RADIUS 200 cm", _AC3_WPNAV),
        "LAND_SPEED": Default(0.5, "ArduCopter/config.h Copter-3.6: LAND_SPEED 50 cm/s", _AC_CONFIG),
        "LAND_SPEED_HIGH": Default(
            0.0, "ArduCopter/Parameters.cpp Copter-3.6: LAND_SPEED_HIGH 0", _AC36_PARAMS
        ),
        "LAND_ALT_LOW": Default(
            10.0, "ArduCopter/Parameters.cpp Copter-3.6: LAND_ALT_LOW 1000 cm", _AC36_PARAMS
        ),
        "RTL_ALT": Default(15.0, "ArduCopter/config.h Copter-3.6: RTL_ALT 1500 cm", _AC_CONFIG),
        "RTL_SPEED": Default(
            0.0, "ArduCopter/Parameters.cpp Copter-3.6: RTL_SPEED 0 (WPNAV_SPEED)", _AC36_PARAMS
        ),
        "RTL_LOIT_TIME": Default(5.0, "ArduCopter/config.h Copter-3.6: RTL_LOITER_TIME 5000 ms", _AC_CONFIG),
        "RTL_ALT_FINAL": Default(0.0, "ArduCopter/config.h Copter-3.6: RTL_ALT_FINAL 0", _AC_CONFIG),
        "RTL_CONE_SLOPE": Default(
            3.0, "ArduCopter/config.h Copter-3.6: RTL_CONE_SLOPE_DEFAULT 3.0", f"{_AC36_RTL}; {_AC45_CONFIG}"
        ),
        "RTL_CLIMB_MIN": Default(
            0.0, "ArduCopter/config.h Copter-3.6: RTL_CLIMB_MIN_DEFAULT 0 cm", f"{_AC36_RTL}; {_AC45_CONFIG}"
        ),
        "WP_YAW_BEHAVIOR": Default(
            2.0, "ArduCopter/config.h Copter-3.6: WP_YAW_BEHAVIOR_DEFAULT 2 (except RTL)", _AC3_CONFIG_YAW
        ),
        "ATC_SLEW_YAW": Default(
            60.0, "ArduCopter/config.h Copter-3.6: AUTO_YAW_SLEW_RATE 60 °/s", _AC3_CONFIG_YAW
        ),
    },
    "4": {
        "WPNAV_SPEED": Default(10.0, "AC_WPNav.cpp Copter-4.5: WPNAV_WP_SPEED 1000 cm/s", _AC4_WPNAV),
        "WPNAV_ACCEL": Default(2.5, "AC_WPNav.h Copter-4.5: WPNAV_ACCELERATION 250 cm/s²", _AC4_WPNAV),
        "WPNAV_SPEED_UP": Default(2.5, "AC_WPNav.cpp Copter-4.5: WPNAV_WP_SPEED_UP 250 cm/s", _AC4_WPNAV),
        "WPNAV_SPEED_DN": Default(1.5, "AC_WPNav.cpp Copter-4.5: WPNAV_WP_SPEED_DOWN 150 cm/s", _AC4_WPNAV),
        "WPNAV_ACCEL_Z": Default(
            1.0, "AC_WPNav.cpp Copter-4.5: WPNAV_WP_ACCEL_Z_DEFAULT 100 cm/s²", _AC4_WPNAV
        ),
        "WPNAV_RADIUS": Default(2.0, "AC_WPNav.cpp Copter-4.5: WPNAV_WP_RADIUS 200 cm", _AC4_WPNAV),
        "WPNAV_JERK": Default(1.0, "AC_WPNav.cpp Copter-4.5: JERK 1 m/s³", _AC4_WPNAV),
        "WPNAV_ACCEL_C": Default(0.0, "AC_WPNav.cpp Copter-4.5: ACCEL_C 0 (2×WPNAV_ACCEL)", _AC4_WPNAV),
        "ATC_INPUT_TC": Default(
            0.15, "AC_AttitudeControl.cpp Copter-4.5: AC_ATTITUDE_CONTROL_INPUT_TC_DEFAULT 0.15 s", _ATC_TC
        ),
        "LAND_SPEED": Default(0.5, "ArduCopter/config.h Copter-4.5: LAND_SPEED 50 cm/s", _AC_CONFIG),
        "LAND_SPEED_HIGH": Default(
            0.0, "ArduCopter/Parameters.cpp Copter-4.5: LAND_SPEED_HIGH 0", _AC45_PARAMS
        ),
        "LAND_ALT_LOW": Default(
            10.0, "ArduCopter/Parameters.cpp Copter-4.5: LAND_ALT_LOW 1000 cm", _AC45_PARAMS
        ),
        "RTL_ALT": Default(15.0, "ArduCopter/config.h Copter-4.5: RTL_ALT 1500 cm", _AC_CONFIG),
        "RTL_SPEED": Default(
            0.0, "ArduCopter/Parameters.cpp Copter-4.5: RTL_SPEED 0 (WPNAV_SPEED)", _AC45_PARAMS
        ),
        "RTL_LOIT_TIME": Default(5.0, "ArduCopter/config.h Copter-4.5: RTL_LOITER_TIME 5000 ms", _AC_CONFIG),
        "RTL_ALT_FINAL": Default(0.0, "ArduCopter/config.h Copter-4.5: RTL_ALT_FINAL 0", _AC_CONFIG),
        "RTL_CONE_SLOPE": Default(
            3.0, "ArduCopter/config.h Copter-4.5: RTL_CONE_SLOPE_DEFAULT 3.0", _AC45_CONFIG
        ),
        "RTL_CLIMB_MIN": Default(
            0.0, "ArduCopter/config.h Copter-4.5: RTL_CLIMB_MIN_DEFAULT 0 cm", _AC45_CONFIG
        ),
        "WP_YAW_BEHAVIOR": Default(
            2.0, "ArduCopter/config.h Copter-4.5: WP_YAW_BEHAVIOR_DEFAULT 2 (except RTL)", _AC45_CONFIG
        ),
        "ATC_SLEW_YAW": Default(
            60.0, "AC_AttitudeControl.h Copter-4.5: SLEW_YAW_DEFAULT_CDS 6000 cd/s", _ATC_SLEW
        ),
    },
}
#: ArduCopter parameters logged in cm, cm/s, cm/s² or ms (→ SI by these factors).
_AC_SCALE = {
    "WPNAV_SPEED": 0.01, "WPNAV_ACCEL": 0.01, "WPNAV_SPEED_UP": 0.01, "WPNAV_SPEED_DN": 0.01,
    "WPNAV_ACCEL_Z": 0.01, "WPNAV_RADIUS": 0.01, "WPNAV_ACCEL_C": 0.01, "LAND_SPEED": 0.01,
    "LAND_SPEED_HIGH": 0.01, "LAND_ALT_LOW": 0.01, "RTL_ALT": 0.01, "RTL_SPEED": 0.01,
    "RTL_LOIT_TIME": 0.001, "RTL_ALT_FINAL": 0.01, "WPNAV_JERK": 1.0, "RTL_CONE_SLOPE": 1.0,
    "RTL_CLIMB_MIN": 0.01, "WP_YAW_BEHAVIOR": 1.0, "ATC_SLEW_YAW": 0.01, "ATC_INPUT_TC": 1.0,
}  # fmt: skip

#: PX4 multicopter defaults (SI). Sources: PX4-Autopilot
#: ``src/modules/mc_pos_control/mc_pos_control_params.c`` (one file up to 1.13; split into
#: ``multicopter_*_params.c`` in 1.14 and into ``.yaml`` later), ``navigator_params.c``,
#: ``mission_params.c``, ``rtl_params.c``. Every value is the same from 1.11 to 1.14 unless
#: its citation names a range; ``MPC_YAWRAUTO_MAX`` is 60 °/s on PX4 main after 1.14.
PX4_MC_DEFAULTS: dict[str, Default] = {
    "MPC_XY_CRUISE": Default(
        5.0, "mc_pos_control_params.c v1.11–1.14: MPC_XY_CRUISE 5 m/s", f"{_PX4_111}; {_PX4_114}"
    ),
    "MPC_ACC_HOR": Default(
        3.0, "mc_pos_control_params.c v1.11–1.14: MPC_ACC_HOR 3 m/s²", f"{_PX4_111}; {_PX4_114}"
    ),
    "MPC_JERK_AUTO": Default(
        4.0, "mc_pos_control_params.c v1.11–1.14: MPC_JERK_AUTO 4 m/s³", f"{_PX4_111}; {_PX4_114}"
    ),
    "MPC_Z_V_AUTO_UP": Default(
        3.0, "mc_pos_control_params.c v1.12–1.14: MPC_Z_V_AUTO_UP 3 m/s", f"{_PX4_112}; {_PX4_114}"
    ),
    "MPC_Z_V_AUTO_DN": Default(
        1.5, "mc_pos_control_params.c v1.12–1.14: MPC_Z_V_AUTO_DN 1.5 m/s", f"{_PX4_112}; {_PX4_114}"
    ),
    "MPC_Z_VEL_MAX_UP": Default(3.0, "mc_pos_control_params.c v1.11: MPC_Z_VEL_MAX_UP 3 m/s", _PX4_111),
    "MPC_Z_VEL_MAX_DN": Default(1.0, "mc_pos_control_params.c v1.11: MPC_Z_VEL_MAX_DN 1 m/s", _PX4_111),
    "MPC_ACC_UP_MAX": Default(
        4.0, "mc_pos_control_params.c v1.11–1.14: MPC_ACC_UP_MAX 4 m/s²", f"{_PX4_111}; {_PX4_112}"
    ),
    "MPC_TKO_SPEED": Default(
        1.5, "mc_pos_control_params.c v1.11–1.14: MPC_TKO_SPEED 1.5 m/s", f"{_PX4_111}; {_PX4_MAIN}"
    ),
    "MPC_TKO_RAMP_T": Default(
        3.0, "mc_pos_control_params.c v1.11–1.14: MPC_TKO_RAMP_T 3 s", f"{_PX4_111}; {_PX4_MAIN}"
    ),
    "MPC_LAND_SPEED": Default(
        0.7, "mc_pos_control_params.c v1.11–1.14: MPC_LAND_SPEED 0.7 m/s", f"{_PX4_111}; {_PX4_MAIN}"
    ),
    "MPC_LAND_ALT1": Default(
        10.0, "mc_pos_control_params.c v1.11–1.14: MPC_LAND_ALT1 10 m", f"{_PX4_111}; {_PX4_MAIN}"
    ),
    "MPC_LAND_ALT2": Default(
        5.0, "mc_pos_control_params.c v1.11–1.14: MPC_LAND_ALT2 5 m", f"{_PX4_111}; {_PX4_MAIN}"
    ),
    "NAV_ACC_RAD": Default(10.0, "navigator_params.c v1.11–1.14: NAV_ACC_RAD 10 m", _PX4_NAV),
    "NAV_MC_ALT_RAD": Default(0.8, "navigator_params.c v1.11–1.14: NAV_MC_ALT_RAD 0.8 m", _PX4_NAV),
    "MIS_YAW_ERR": Default(12.0, "mission_params.c v1.11–1.14: MIS_YAW_ERR 12°", _PX4_MIS),
    "MIS_YAW_TMT": Default(-1.0, "mission_params.c v1.11–1.14: MIS_YAW_TMT −1 (no timeout)", _PX4_MIS),
    "MPC_YAWRAUTO_MAX": Default(
        45.0,
        "mc_pos_control_params.c v1.11–1.14: MPC_YAWRAUTO_MAX 45°/s",
        f"{_PX4_111}; {_PX4_112}; {_PX4_114}",
    ),
    "MPC_YAW_MODE": Default(
        0.0,
        "mc_pos_control_params.c v1.11–1.14: MPC_YAW_MODE 0 (towards waypoint)",
        f"{_PX4_111}; {_PX4_114}",
    ),
    "MPC_XY_TRAJ_P": Default(
        0.5, "mc_pos_control_params.c v1.11–1.14: MPC_XY_TRAJ_P 0.5", f"{_PX4_111}; {_PX4_114}"
    ),
    "MPC_XY_P": Default(0.95, "mc_pos_control_params.c v1.11–1.13: MPC_XY_P 0.95", f"{_PX4_111}; {_PX4_112}"),
    "MPC_SPOOLUP_TIME": Default(
        1.0, "mc_pos_control_params.c v1.11: MPC_SPOOLUP_TIME 1 s (COM_SPOOLUP_TIME from 1.12)", _PX4_111
    ),
    "RTL_RETURN_ALT": Default(60.0, "rtl_params.c v1.11–1.14: RTL_RETURN_ALT 60 m", _PX4_RTL),
    "RTL_DESCEND_ALT": Default(30.0, "rtl_params.c v1.11–1.14: RTL_DESCEND_ALT 30 m", _PX4_RTL),
    "RTL_LAND_DELAY": Default(
        0.0, "rtl_params.c v1.13–1.14: RTL_LAND_DELAY 0 s (−1 before: hover)", _PX4_RTL
    ),
}

#: ArduPlane / QuadPlane defaults (SI). Sources: ArduPilot ``ArduPlane/config.h`` (used by
#: ``Parameters.cpp``: ``TRIM_ARSPD_CM``/``AIRSPEED_CRUISE``, ``LIM_ROLL_CD``/``ROLL_LIMIT_DEG``,
#: ``WP_RADIUS``), ``ArduPlane/quadplane.cpp`` (``Q_TRANSITION_MS``, ``Q_LAND_SPEED``,
#: ``Q_LAND_FINAL_ALT``; ``Q_WP_SPEED_UP/DN`` are the ``AC_WPNav`` defaults), ``AP_TECS.cpp``.
PLANE_DEFAULTS: dict[str, Default] = {
    "AIRSPEED_CRUISE": Default(12.0, "ArduPlane/config.h Plane-4.5: AIRSPEED_CRUISE 12 m/s", _PLANE_CONFIG),
    "ROLL_LIMIT_DEG": Default(45.0, "ArduPlane/config.h Plane-4.5: ROLL_LIMIT_DEG 45°", _PLANE_CONFIG),
    "WP_RADIUS": Default(90.0, "ArduPlane/config.h Plane-4.5: WP_RADIUS_DEFAULT 90 m", _PLANE_CONFIG),
    "Q_WP_SPEED_UP": Default(2.5, "AC_WPNav.cpp Plane-4.5 (Q_WP_): WPNAV_WP_SPEED_UP 250 cm/s", _AC4_WPNAV),
    "Q_WP_SPEED_DN": Default(1.5, "AC_WPNav.cpp Plane-4.5 (Q_WP_): WPNAV_WP_SPEED_DOWN 150 cm/s", _AC4_WPNAV),
    "Q_WP_ACCEL_Z": Default(
        1.0, "AC_WPNav.cpp Plane-4.5 (Q_WP_): WPNAV_WP_ACCEL_Z_DEFAULT 100 cm/s²", _AC4_WPNAV
    ),
    "Q_LAND_SPEED": Default(0.5, "ArduPlane/quadplane.cpp Plane-4.5: Q_LAND_SPEED 50 cm/s", _QPLANE),
    "Q_LAND_FINAL_ALT": Default(6.0, "ArduPlane/quadplane.cpp Plane-4.5: Q_LAND_FINAL_ALT 6 m", _QPLANE),
    "Q_TRANSITION_MS": Default(5.0, "ArduPlane/quadplane.cpp Plane-4.5: Q_TRANSITION_MS 5000 ms", _QPLANE),
    "TECS_CLMB_MAX": Default(5.0, "libraries/AP_TECS/AP_TECS.cpp Plane-4.5: TECS_CLMB_MAX 5 m/s", _TECS),
    "TECS_SINK_MAX": Default(5.0, "libraries/AP_TECS/AP_TECS.cpp Plane-4.5: TECS_SINK_MAX 5 m/s", _TECS),
}
#: Older ArduPlane names in their logged units → the names above (SI).
_PLANE_ALIASES = {"TRIM_ARSPD_CM": ("AIRSPEED_CRUISE", 0.01), "LIM_ROLL_CD": ("ROLL_LIMIT_DEG", 0.01),
                  "Q_WP_SPEED_UP": ("Q_WP_SPEED_UP", 0.01), "Q_WP_SPEED_DN": ("Q_WP_SPEED_DN", 0.01),
                  "Q_WP_ACCEL_Z": ("Q_WP_ACCEL_Z", 0.01), "Q_LAND_SPEED": ("Q_LAND_SPEED", 0.01),
                  "Q_TRANSITION_MS": ("Q_TRANSITION_MS", 0.001)}  # fmt: skip


@dataclass(frozen=True)
class ModelOptions:
    """The modelling choices of the mission execution models that are not a firmware
    parameter: how the vehicle follows what the firmware commands. The defaults are what the
    firmware source implies; :mod:`uasnav.trajectory.holdout` re-chooses them on held-out
    flights.

    Attributes
    ----------
    ac3_slowdown_factor : float
        ArduCopter 3.x: the waypoint target slows down at this multiple of ``WPNAV_ACCEL``
        (``AC_WPNav::get_slow_down_speed`` v = √(4·a·d) is a deceleration of 2·a).
    px4_tracking_lag : bool
        PX4: the vehicle trails its smoothed trajectory by 1/``MPC_XY_P`` seconds of speed when
        the navigator checks the acceptance radius.
    px4_takeoff_lead : bool
        PX4: a take-off from the ground first spools the motors up
        (``MPC_SPOOLUP_TIME``/``COM_SPOOLUP_TIME``) and ramps the climb setpoint
        (``MPC_TKO_RAMP_T``).
    px4_yaw_acceptance : bool
        PX4: a waypoint with a heading is accepted only once the heading is within
        ``MIS_YAW_ERR`` (``Mission::is_mission_item_reached``).
    yaw_before_move : bool
        Turn to face the next leg before flying it where the firmware waits for the heading:
        PX4 with ``MPC_YAW_MODE`` 4 ("towards waypoint, yaw first"); ArduCopter never waits
        (``ModeAuto::wp_run``/``verify_nav_wp`` have no heading condition).
    """

    ac3_slowdown_factor: float = 2.0
    px4_tracking_lag: bool = True
    px4_takeoff_lead: bool = True
    px4_yaw_acceptance: bool = True
    yaw_before_move: bool = True


@dataclass(frozen=True)
class MissionParams:
    """The parameters a mission execution model flies with (SI units).

    Attributes
    ----------
    family : str
        ``"arducopter"``, ``"px4-mc"`` or ``"plane"``.
    version : str or None
        Firmware version (decides 3.x vs 4.x behaviour for ArduCopter, the PX4 vertical speeds).
    values : dict of str → float
        Parameter name → value in SI units (m, m/s, m/s², m/s³, s, deg).
    sources : dict of str → str
        Parameter name → ``"log"`` or the firmware default's citation.
    options : ModelOptions
        The modelling choices that are not firmware parameters.
    """

    family: str
    version: str | None
    values: dict[str, float]
    sources: dict[str, str] = field(default_factory=dict)
    options: ModelOptions = field(default_factory=ModelOptions)

    def __getitem__(self, name: str) -> float:
        return self.values[name]

    @property
    def major(self) -> int | None:
        """The firmware's major version number, when known."""
        try:
            return int(str(self.version).split(".")[0])
        except ValueError:
            return None

    @property
    def minor(self) -> int:
        """The firmware's minor version number (0 when unknown)."""
        try:
            return int(str(self.version).split(".")[1])
        except (ValueError, IndexError):
            return 0

    @property
    def cruise_ms(self) -> float:
        """The horizontal mission speed (m/s)."""
        return self.values[
            {"arducopter": "WPNAV_SPEED", "px4-mc": "MPC_XY_CRUISE", "plane": "AIRSPEED_CRUISE"}[self.family]
        ]


def family_of(identity: object | None, params: dict[str, float]) -> str:
    """The model family of a log: from its identity (autopilot, vehicle type) and, failing
    that, from which parameters it carries."""
    auto = str(getattr(identity, "autopilot", "") or "").lower()
    vtype = str(getattr(identity, "vehicle_type", "") or "").lower()
    if "plane" in vtype or "fixed" in vtype or "Q_ENABLE" in params or "TRIM_ARSPD_CM" in params:
        return "plane"
    if "px4" in auto or any(k.startswith("MPC_") for k in params):
        return "px4-mc"
    return "arducopter"


def plan_family(plan: object) -> str:
    """The family a mission plan is flown with when neither the user nor a log names one: a plan
    with VTOL items (``MAV_CMD_NAV_VTOL_TAKEOFF``/``LAND``, 84/85) or made for a fixed wing
    (``MAV_TYPE`` 1) is a plane, any other an ArduCopter."""
    items = getattr(plan, "items", ())
    if any(it.command in (84, 85) for it in items) or getattr(plan, "vehicle_type", None) == 1:
        return "plane"
    return "arducopter"


def mission_params(
    family: str,
    version: str | None = None,
    log_params: dict[str, float] | None = None,
) -> MissionParams:
    """The parameters of ``family`` at firmware ``version``: the log's where it has them, the
    firmware defaults (:data:`ARDUCOPTER_DEFAULTS`, :data:`PX4_MC_DEFAULTS`,
    :data:`PLANE_DEFAULTS`) otherwise; :attr:`MissionParams.sources` says which.

    Raises
    ------
    InputError
        Unknown family, or a parameter that is not finite or not positive where it must be.
    """
    lp = dict(log_params or {})
    values: dict[str, float] = {}
    sources: dict[str, str] = {}
    if family == "arducopter":
        major = "4"
        try:
            major = "3" if version is not None and int(str(version).split(".")[0]) <= 3 else "4"
        except ValueError:
            pass
        for k, d in ARDUCOPTER_DEFAULTS[major].items():
            if k in lp and math.isfinite(lp[k]):
                values[k], sources[k] = lp[k] * _AC_SCALE[k], "log"
            else:
                values[k], sources[k] = d.value, d.source
        version = version or ("3.6" if major == "3" else "4.5")
    elif family == "px4-mc":
        for k, d in PX4_MC_DEFAULTS.items():
            if k in lp and math.isfinite(lp[k]):
                values[k], sources[k] = float(lp[k]), "log"
            elif (
                k == "MPC_SPOOLUP_TIME" and "COM_SPOOLUP_TIME" in lp and math.isfinite(lp["COM_SPOOLUP_TIME"])
            ):
                values[k], sources[k] = float(lp["COM_SPOOLUP_TIME"]), "log: COM_SPOOLUP_TIME"
            else:
                values[k], sources[k] = d.value, d.source
    elif family == "plane":
        for k, d in PLANE_DEFAULTS.items():
            values[k], sources[k] = d.value, d.source
        for k, v in lp.items():
            if k in _PLANE_ALIASES and math.isfinite(v):
                name, scale = _PLANE_ALIASES[k]
                values[name], sources[name] = v * scale, "log"
            elif k in PLANE_DEFAULTS and math.isfinite(v):
                values[k], sources[k] = float(v), "log"
    else:
        raise InputError(f"unknown autopilot family {family!r} (known: {', '.join(FAMILIES)})")
    for k, v in values.items():
        if not math.isfinite(v) or (v < 0 and k not in ("MIS_YAW_TMT", "RTL_LAND_DELAY")):
            raise InputError(f"parameter {k} = {v}: must be finite and ≥ 0")
    return MissionParams(family, version, values, sources)


# --------------------------------------------------------------------------- prediction
@dataclass(frozen=True)
class MissionPrediction:
    """When a mission's items are reached.

    Attributes
    ----------
    items : tuple of int
        Mission item index (in :attr:`MissionPlan.items`) of each event, flown order.
    commands : tuple of int
        Their ``MAV_CMD``.
    arrive_s : ndarray
        Time each item is reached (s from the mission start).
    eta_s : float
        Time the mission ends (touch-down, or the last item reached when it does not land).
    landed : bool
        Whether the mission ends on the ground.
    params : MissionParams
        The parameters used.
    """

    items: tuple[int, ...]
    commands: tuple[int, ...]
    arrive_s: np.ndarray
    eta_s: float
    landed: bool
    params: MissionParams

    def arrival_of(self, item: int) -> float | None:
        """The first time item ``item`` is reached (None when the prediction never reaches it)."""
        for i, t in zip(self.items, self.arrive_s, strict=True):
            if i == item:
                return float(t)
        return None


@dataclass
class _State:
    ne: np.ndarray  # north, east (m) from the origin
    h: float  # height above home (m)
    v: float = 0.0  # horizontal speed at the current point (m/s)
    t: float = 0.0
    airborne: bool = False
    heading: float = math.nan  # rad from north (NaN: unknown)
    vdir: np.ndarray | None = None  # unit vector of the horizontal motion (north, east)
    armed_heading: float = math.nan  # rad from north at arming (NaN: unknown)


def _local(plan: MissionPlan, origin: tuple[float, float]) -> dict[int, np.ndarray]:
    from uasnav.trajectory.geometry import geodetic_to_local

    idx = [i for i, it in enumerate(plan.items) if it.has_position]
    if not idx:
        return {}
    lat = np.array([plan.items[i].lat_deg for i in idx])
    lon = np.array([plan.items[i].lon_deg for i in idx])
    ned = geodetic_to_local(lat, lon, np.zeros(len(idx)), origin=(origin[0], origin[1], 0.0))
    return {i: ned[k, :2] for k, i in enumerate(idx)}


def _height(plan: MissionPlan, i: int, home_amsl: float | None, current: float) -> float:
    """Height above home (m) of item ``i`` (its current height when it has no altitude)."""
    it = plan.items[i]
    if not math.isfinite(it.alt_m):
        return current
    try:
        frame = it.altitude_frame
    except InputError:
        return current
    if frame is AltitudeFrame.AMSL:
        if home_amsl is None or not math.isfinite(home_amsl):
            return current
        return it.alt_m - home_amsl
    return it.alt_m  # relative to home; terrain frames taken as relative (flat ground)


def _turn_angle(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> float:
    """The heading change (rad, 0 … π) at b between the legs a→b and b→c."""
    u, w = b - a, c - b
    nu, nw = float(np.hypot(*u)), float(np.hypot(*w))
    if nu < 1e-6 or nw < 1e-6:
        return math.pi
    cos = float(np.clip(np.dot(u, w) / (nu * nw), -1.0, 1.0))
    return math.acos(cos)


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def corner_speed(p: MissionParams, theta: float, v: float) -> float:
    """Speed (m/s) a multicopter passes a waypoint at whose legs turn by ``theta`` rad.

    * PX4: √(a·R·tan(α/2)) with α = π − θ the angle between the legs, R = ``NAV_ACC_RAD``,
      a = ``MPC_ACC_HOR``·``MPC_XY_TRAJ_P`` (``computeMaxSpeedInWaypoint``);
    * ArduCopter 4.x: the arc that stays within R = ``WPNAV_RADIUS`` of the corner has radius
      r = R/(1/cos(θ/2) − 1); speed √(a_c·r) with a_c = ``WPNAV_ACCEL_C`` (0: 2·``WPNAV_ACCEL``);
    * ArduCopter 3.x passes a fast waypoint at full speed.
    """
    if theta < 1e-6:
        return v
    if theta >= math.pi - 1e-6:
        return 0.0
    if p.family == "px4-mc":
        a = p["MPC_ACC_HOR"] * p["MPC_XY_TRAJ_P"]  # max_acc_xy_radius_scale
        return min(v, math.sqrt(a * p["NAV_ACC_RAD"] * math.tan((math.pi - theta) / 2)))
    if p.family == "arducopter":
        if (p.major or 4) <= 3:
            return v
        a_c = p["WPNAV_ACCEL_C"] or 2.0 * p["WPNAV_ACCEL"]
        r = p["WPNAV_RADIUS"] / (1.0 / math.cos(theta / 2) - 1.0)
        return min(v, math.sqrt(a_c * r))
    return v


def arducopter_jerk_time(p: MissionParams) -> float:
    """The raised-cosine jerk time t_j (s) of ArduCopter 4.x's S-curves: ``SCurve`` takes
    t_j = j·π/(2·S) with the snap S = ½·j·π/(2·max(``ATC_INPUT_TC``, 0.1 s))
    (``AC_WPNav::calc_scurve_jerk_and_snap``; the attitude controller's own acceleration limit
    ``ATC_ACCEL_R/P_MAX`` binds only far below its defaults), so t_j = 2·max(``ATC_INPUT_TC``,
    0.1 s): 0.3 s by default. 3.x has no S-curve (0).
    """
    if p.family != "arducopter" or (p.major or 4) <= 3:
        return 0.0
    return 2.0 * max(p.values.get("ATC_INPUT_TC", 0.15), 0.1)


def predict_mission(
    plan: MissionPlan,
    params: MissionParams,
    *,
    home_amsl_m: float | None = None,
    start_ne: tuple[float, float] | None = None,
    start_height_m: float = 0.0,
    origin: tuple[float, float] | None = None,
    armed_heading_deg: float | None = None,
) -> MissionPrediction:
    """When each item of ``plan`` is reached and when the mission ends, as the autopilot
    family of ``params`` flies it (see the module docs).

    Parameters
    ----------
    plan : MissionPlan
        The mission (``DO_JUMP`` expanded, ``DO_CHANGE_SPEED`` applied).
    params : MissionParams
        From :func:`mission_params`.
    home_amsl_m : float, optional
        Home altitude AMSL (m), for items in AMSL; default the plan's home.
    start_ne, start_height_m : the vehicle's position at the start, north/east m from
        ``origin`` and height above home (default: at home, on the ground).
    origin : (lat, lon), optional
        The local frame's origin (default home, else the first positioned item).
    armed_heading_deg : float, optional
        The vehicle's heading at arming and at the start (degrees from true north); ArduCopter
        turns back to it over home in RTL when ``WP_YAW_BEHAVIOR`` is 1 or 3. Unknown: no
        turn is timed.

    Raises
    ------
    InputError
        A plan without positioned items, or an unlimited loiter (the mission has no end time).
    """
    p = params
    home = plan.home
    if home_amsl_m is None and home is not None and math.isfinite(home.alt_amsl_m):
        home_amsl_m = home.alt_amsl_m
    seq = flight_sequence(plan)
    first = next((i for i in seq if plan.items[i].has_position), None)
    if origin is None:
        if home is not None:
            origin = (home.lat_deg, home.lon_deg)
        elif first is not None:
            origin = (plan.items[first].lat_deg, plan.items[first].lon_deg)
        else:
            raise InputError(f"{plan.source}: no item with a position")
    pos = _local(plan, origin)
    home_ne = np.zeros(2) if home is not None else (pos[first] if first is not None else np.zeros(2))
    s = _State(np.array(start_ne if start_ne is not None else home_ne, dtype=float), float(start_height_m))
    s.airborne = start_height_m > 0.5
    if armed_heading_deg is not None and math.isfinite(armed_heading_deg):
        s.heading = s.armed_heading = math.radians(armed_heading_deg)
    cruise = p.cruise_ms
    out_items: list[int] = []
    out_cmds: list[int] = []
    out_t: list[float] = []
    landed = False

    def next_nav_after(k: int) -> int | None:
        later = [j for j in seq[k + 1 :] if plan.items[j].command < 95]
        return later[0] if later else None

    for k, i in enumerate(seq):
        it = plan.items[i]
        cmd = it.command
        if cmd == MAV_CMD_DO_CHANGE_SPEED:
            if it.speed_ms is not None:
                cruise = it.speed_ms
            continue
        if cmd >= 95 and cmd != MAV_CMD_NAV_DELAY:
            continue  # other DO_/CONDITION_ items run alongside the navigation
        if cmd == MAV_CMD_NAV_DELAY:
            s.t += max(it.params[0], 0.0) if math.isfinite(it.params[0]) else 0.0
        elif cmd in (MAV_CMD_NAV_TAKEOFF, MAV_CMD_NAV_VTOL_TAKEOFF):
            h1 = _height(plan, i, home_amsl_m, s.h)
            if i in pos and p.family != "plane":
                s.ne = pos[i]
            s.t += _climb_time(
                p, max(h1 - s.h, 0.0), vtol=cmd == MAV_CMD_NAV_VTOL_TAKEOFF, ground=not s.airborne
            )
            s.h, s.v, s.airborne = max(h1, s.h), 0.0, True
        elif cmd in (MAV_CMD_NAV_WAYPOINT, MAV_CMD_NAV_SPLINE_WAYPOINT, MAV_CMD_NAV_LOITER_TIME,
                     MAV_CMD_NAV_LOITER_TURNS, MAV_CMD_NAV_LOITER_UNLIM):  # fmt: skip
            if cmd == MAV_CMD_NAV_LOITER_UNLIM:
                raise InputError(
                    f"{plan.source}: item {i} loiters without limit: the mission has no end time"
                )
            target = pos.get(i, s.ne)
            h1 = _height(plan, i, home_amsl_m, s.h)
            if p.family == "px4-mc" and not s.airborne:
                # PX4's navigator inserts a take-off to the first waypoint's altitude when the
                # mission starts on the ground (Mission::do_need_vertical_takeoff)
                s.t += _climb_time(p, max(h1 - s.h, 0.0), vtol=False, ground=True)
                s.h, s.airborne = h1, True
            hold = it.hold_s if cmd != MAV_CMD_NAV_LOITER_TURNS else 0.0
            nxt = next_nav_after(k)
            v_out = 0.0
            if p.family == "plane":
                v_out = cruise
            elif nxt is not None and hold == 0.0 and cmd == MAV_CMD_NAV_WAYPOINT and not _yaw_first(p):
                nc = plan.items[nxt].command
                if nc in (MAV_CMD_NAV_WAYPOINT, MAV_CMD_NAV_SPLINE_WAYPOINT) and nxt in pos:
                    theta = _turn_angle(s.ne, target, pos[nxt])
                    v_out = corner_speed(p, theta, cruise)
            if _yaw_first(p):
                _turn_before_leg(p, s, target)
            _leg(p, s, target, h1, cruise, v_out)
            if p.family == "px4-mc" and p.options.px4_yaw_acceptance:
                _px4_yaw(p, s, it.params[3])
            if cmd == MAV_CMD_NAV_LOITER_TURNS:
                turns = it.params[0] if math.isfinite(it.params[0]) else 1.0
                radius = abs(it.params[2]) if math.isfinite(it.params[2]) and it.params[2] != 0 else 60.0
                s.t += abs(turns) * 2 * math.pi * radius / max(cruise, 0.1)
            out_items.append(i)
            out_cmds.append(cmd)
            out_t.append(s.t)
            s.t += hold if math.isfinite(hold) else 0.0
            if hold > 0:
                s.v = 0.0
            continue
        elif cmd in (MAV_CMD_NAV_LAND, MAV_CMD_NAV_VTOL_LAND):
            target = pos.get(i, s.ne)
            # PX4 starts the descent once within NAV_ACC_RAD of the landing point
            _leg(p, s, target, s.h, cruise, 0.0, accept=p.family == "px4-mc")
            s.v = 0.0
            if p.family == "plane":
                s.t += p["Q_TRANSITION_MS"]
            s.t += _land_time(p, s.h, vtol=cmd == MAV_CMD_NAV_VTOL_LAND)
            s.h, landed = 0.0, True
        elif cmd == MAV_CMD_NAV_RETURN_TO_LAUNCH:
            landed = _rtl(p, s, home_ne, cruise)
        else:
            continue
        out_items.append(i)
        out_cmds.append(cmd)
        out_t.append(s.t)
        if landed and any(plan.items[j].command in (MAV_CMD_NAV_VTOL_TAKEOFF, MAV_CMD_NAV_TAKEOFF)
                          for j in seq[k + 1:]):  # fmt: skip
            landed, s.airborne = False, False  # the mission takes off again
        elif landed:
            break
    return MissionPrediction(
        tuple(out_items), tuple(out_cmds), np.asarray(out_t, dtype=float), float(s.t), landed, p
    )


def _yaw_first(p: MissionParams) -> bool:
    """Whether the firmware holds the vehicle until it faces the next waypoint: PX4 with
    ``MPC_YAW_MODE`` 4 (``FlightTaskAuto``: ``should_wait_for_yaw_align`` zeroes the velocity
    setpoint while the rate-limited yaw setpoint is not aligned). ArduCopter turns while it
    flies (``WP_YAW_BEHAVIOR`` only chooses where the nose points): ``ModeAuto::wp_run``
    runs ``update_wpnav`` and the heading together and ``verify_nav_wp`` waits for
    ``reached_wp_destination`` and the hold only (``mode_auto.cpp`` at ArduPilot 00132531),
    so it never waits."""
    return p.family == "px4-mc" and p.options.yaw_before_move and p.values.get("MPC_YAW_MODE", 0.0) == 4.0


def _turn_before_leg(p: MissionParams, s: _State, target: np.ndarray) -> None:
    """Turn on the spot to face ``target`` at ``MPC_YAWRAUTO_MAX`` (the heading is unknown
    before the first leg: no wait then)."""
    u = np.asarray(target, dtype=float) - s.ne
    if float(np.hypot(*u)) < 1e-6 or not math.isfinite(s.heading):
        return
    want = math.atan2(u[1], u[0])
    s.t += abs(_wrap(want - s.heading)) / math.radians(p["MPC_YAWRAUTO_MAX"])
    s.heading, s.v = want, 0.0


def _px4_yaw(p: MissionParams, s: _State, yaw_deg: float) -> None:
    """PX4 accepts a waypoint with a heading only once the heading is within ``MIS_YAW_ERR``
    (or after ``MIS_YAW_TMT`` when ≥ 0); the heading turns at ``MPC_YAWRAUTO_MAX``."""
    if not math.isfinite(yaw_deg):
        return
    want = math.radians(yaw_deg)
    if math.isfinite(s.heading):
        err = abs(_wrap(want - s.heading)) - math.radians(p["MIS_YAW_ERR"])
        if err > 0:
            wait = err / math.radians(p["MPC_YAWRAUTO_MAX"])
            if p["MIS_YAW_TMT"] >= 0:
                wait = min(wait, p["MIS_YAW_TMT"])
            s.t += wait
    s.heading = want


def _tail_time(r: float, v_end: float, v_peak: float, decel: float) -> float:
    """Time (s) a speed profile that slows to ``v_end`` at ``decel`` spends on its last ``r`` m."""
    if r <= 0:
        return 0.0
    v_r = min(math.sqrt(v_end * v_end + 2.0 * decel * r), max(v_peak, v_end))
    d_dec = (v_r * v_r - v_end * v_end) / (2.0 * decel)
    return (v_r - v_end) / decel + max(r - d_dec, 0.0) / max(v_r, 1e-9)


def _leg(
    p: MissionParams, s: _State, target: np.ndarray, h1: float, cruise: float, v_out: float,
    accept: bool = True,
) -> None:  # fmt: skip
    """Fly the state to (``target``, ``h1``): the time of the leg up to the moment the
    autopilot accepts the waypoint, and the state there.

    PX4 accepts within ``NAV_ACC_RAD`` horizontally and ``NAV_MC_ALT_RAD`` vertically and goes
    on from there; ArduCopter's waypoint controller moves a target that reaches the waypoint
    first (its acceptance is the target's arrival); a plane accepts within ``WP_RADIUS``."""
    u = np.asarray(target, dtype=float) - s.ne
    d = float(np.hypot(*u))
    dz = h1 - s.h
    up, dn, az = _vertical_limits(p)
    vz = up if dz > 0 else dn
    t_v = leg_time(abs(dz), vz, az)[0] if abs(dz) > 0 else 0.0
    r_h = r_v = 0.0
    if (
        accept and p.family == "px4-mc"
        and d <= p["NAV_ACC_RAD"] and abs(dz) <= p["NAV_MC_ALT_RAD"]
    ):  # fmt: skip
        return  # already within the acceptance radius: accepted at once
    # the speed carried into the leg is the part along it; motion against it is stopped first
    t_stop = 0.0
    v0 = s.v
    if v0 > 0 and s.vdir is not None and d > 1e-6:
        along = v0 * float(np.dot(s.vdir, u / d))
        a_stop = (
            p["MPC_ACC_HOR"]
            if p.family == "px4-mc"
            else p["WPNAV_ACCEL"]
            if p.family == "arducopter"
            else 1.0
        )
        j_stop = p["MPC_JERK_AUTO"] if p.family == "px4-mc" else None
        if along < 0:
            t_stop = speed_change_time(-along, a_stop, j_stop)
            d += 0.5 * (-along) * t_stop  # the overshoot flown back
            v0 = 0.0
        else:
            v0 = along
    if p.family == "plane":
        a = 1.0
        r_h = min(p["WP_RADIUS"], d) if accept else 0.0
        t_h, v_end = d / max(cruise, 0.1), cruise
        t_h -= r_h / max(cruise, 0.1)
    elif p.family == "arducopter":
        a = p["WPNAV_ACCEL"]
        if (p.major or 4) <= 3:
            # the 3.x target slows down at twice WPNAV_ACCEL (get_slow_down_speed)
            a = p.options.ac3_slowdown_factor * a
            t_h, v_end = leg_time(d, cruise, p["WPNAV_ACCEL"], None, v0, v_out, decel=a)
        else:
            t_h, v_end = leg_time(d, cruise, a, p["WPNAV_JERK"], v0, v_out, jerk_time=arducopter_jerk_time(p))
    else:
        a, j = p["MPC_ACC_HOR"], p["MPC_JERK_AUTO"]
        if accept:
            r_h = min(p["NAV_ACC_RAD"], d)
            r_v = min(p["NAV_MC_ALT_RAD"], abs(dz))
            lag = 1.0 / p["MPC_XY_P"] if p.options.px4_tracking_lag else 0.0
            t_h, v_end = px4_leg_time(d, cruise, a, j, v0, v_out, p["NAV_ACC_RAD"], lag)
            t_v -= _tail_time(r_v, 0.0, vz, az)
        else:
            # to the point itself: the braking limit approaches it exponentially, so the leg
            # ends 0.1 m before it
            t_h, v_end = px4_leg_time(d, cruise, a, j, v0, 0.0, 0.1, 0.0)
    t_h += t_stop
    t = max(t_h, t_v, 0.0)
    if d > 1e-6:
        s.ne = s.ne + u * (1.0 - r_h / d)
        s.vdir = u / d
        if d > r_h:
            s.heading = math.atan2(u[1], u[0])
    s.h = h1 - math.copysign(r_v, dz) if r_v > 0 else h1
    s.t += t
    s.v = v_end


def _vertical_limits(p: MissionParams) -> tuple[float, float, float]:
    """Climb speed, descent speed (m/s), vertical acceleration (m/s²) for waypoint legs."""
    if p.family == "arducopter":
        return p["WPNAV_SPEED_UP"], p["WPNAV_SPEED_DN"], p["WPNAV_ACCEL_Z"]
    if p.family == "px4-mc":
        if p.sources.get("MPC_Z_V_AUTO_UP") == "log" or (p.major or 1) > 1 or p.minor >= 12:
            return p["MPC_Z_V_AUTO_UP"], p["MPC_Z_V_AUTO_DN"], p["MPC_ACC_UP_MAX"]
        return p["MPC_Z_VEL_MAX_UP"], p["MPC_Z_VEL_MAX_DN"], p["MPC_ACC_UP_MAX"]
    return p["TECS_CLMB_MAX"], p["TECS_SINK_MAX"], 1.0


def _climb_time(p: MissionParams, dz: float, *, vtol: bool, ground: bool) -> float:
    if dz <= 0:
        return 0.0
    if p.family == "px4-mc":
        # the take-off ramp raises the speed setpoint linearly over MPC_TKO_RAMP_T: half of it
        # is lost against climbing at MPC_TKO_SPEED throughout
        # on the ground: the motors spool up, then the take-off ramp raises the climb-speed
        # setpoint over MPC_TKO_RAMP_T from the one that holds the vehicle down; the
        # take-off is accepted within NAV_MC_ALT_RAD
        lead = p["MPC_SPOOLUP_TIME"] + p["MPC_TKO_RAMP_T"] if ground and p.options.px4_takeoff_lead else 0.0
        return lead + max(dz - p["NAV_MC_ALT_RAD"], 0.0) / p["MPC_TKO_SPEED"]
    if p.family == "plane":
        if vtol:
            t, _ = leg_time(dz, p["Q_WP_SPEED_UP"], p["Q_WP_ACCEL_Z"])
            return t + p["Q_TRANSITION_MS"]
        return dz / p["TECS_CLMB_MAX"]
    up, _, az = _vertical_limits(p)
    return leg_time(dz, up, az)[0]


def _land_time(p: MissionParams, h: float, *, vtol: bool) -> float:
    if p.family == "arducopter":
        high = p["LAND_SPEED_HIGH"] or p["WPNAV_SPEED_DN"]
        return banded_descent_time(h, high, p["LAND_SPEED"], p["LAND_ALT_LOW"])
    if p.family == "px4-mc":
        _, dn, _ = _vertical_limits(p)
        return px4_land_time(h, dn, p["MPC_LAND_SPEED"], p["MPC_LAND_ALT1"], p["MPC_LAND_ALT2"])
    return banded_descent_time(h, p["Q_WP_SPEED_DN"], p["Q_LAND_SPEED"], p["Q_LAND_FINAL_ALT"])


#: ArduCopter RTL constants (``ArduCopter/config.h``): the lowest return altitude
#: ``RTL_ALT_MIN`` (30 cm in 4.5), the shallowest cone that is applied ``RTL_MIN_CONE_SLOPE``
#: (0.5), and the 3.5–4.x cone's minimum climb ``RTL_ABS_MIN_CLIMB`` (250 cm).
AC_RTL_ALT_MIN_M = 0.3
AC_RTL_MIN_CONE_SLOPE = 0.5
AC_RTL_ABS_MIN_CLIMB_M = 2.5
#: ArduCopter's ``RESET_TO_ARMED_YAW`` ends the loiter at home once the heading is within 2°
#: of the heading at arming (``ModeRTL::loiterathome_run``).
AC_RTL_YAW_TOLERANCE_DEG = 2.0


def arducopter_rtl_altitude(p: MissionParams, height_m: float, distance_m: float) -> float:
    """The height above home (m) ArduCopter returns at from ``height_m`` m, ``distance_m`` m
    (horizontal) from home (``ModeRTL::compute_return_target``).

    With h the current height, d the distance, s = ``RTL_CONE_SLOPE``, c = ``RTL_CLIMB_MIN``:

    * 4.x: m = max(``RTL_ALT_MIN``, h + c); H = max(``RTL_ALT``, m); when s ≥ 0.5,
      H = min(H, max(d·s, m)); never below h;
    * 3.5–3.6: H = max(h + c, ``RTL_ALT``); when s ≥ 0.5,
      H = max(h, min(H, max(d·s, h + ``RTL_ABS_MIN_CLIMB``)));
    * before 3.5 (no cone): max(h + c, ``RTL_ALT``).

    ``RTL_ALT`` 0 keeps the current height.

    >>> p = mission_params("arducopter", "4.5.7")
    >>> arducopter_rtl_altitude(p, 5.0, 100.0), arducopter_rtl_altitude(p, 5.0, 3.0)
    (15.0, 9.0)
    """
    h, d = max(height_m, 0.0), max(distance_m, 0.0)
    rtl_alt = p["RTL_ALT"] if p["RTL_ALT"] > 0 else h
    climb_min = max(p.values.get("RTL_CLIMB_MIN", 0.0), 0.0)
    slope = p.values.get("RTL_CONE_SLOPE", 0.0)
    major, minor = p.major or 4, p.minor
    if major >= 4:
        m = max(AC_RTL_ALT_MIN_M, h + climb_min)
        target = max(rtl_alt, m)
        if slope >= AC_RTL_MIN_CONE_SLOPE:
            target = min(target, max(d * slope, m))
        return max(target, h)
    target = max(h + climb_min, rtl_alt)
    if (major, minor) >= (3, 5) and slope >= AC_RTL_MIN_CONE_SLOPE:
        target = max(h, min(target, max(d * slope, h + AC_RTL_ABS_MIN_CLIMB_M)))
    return max(target, h)


def arducopter_rtl_yaw_wait(p: MissionParams, heading_rad: float, armed_heading_rad: float) -> float:
    """Extra time (s) beyond ``RTL_LOIT_TIME`` ArduCopter loiters at home to turn back to the
    heading it was armed at: only when ``WP_YAW_BEHAVIOR`` points the nose on the way home
    (1 "next waypoint" or 3 "ground course"; 0 and 2 hold the heading in RTL, so
    ``loiterathome_start`` chooses ``HOLD``). The turn runs at ``ATC_SLEW_YAW`` (3.x:
    ``AUTO_YAW_SLEW_RATE``) from the start of the loiter and ends within 2°, so the wait is
    max(0, (|Δψ| − 2°)/rate − ``RTL_LOIT_TIME``). An unknown heading waits nothing.

    >>> p = mission_params("arducopter", "4.5.7", {"WP_YAW_BEHAVIOR": 1, "RTL_LOIT_TIME": 0})
    >>> round(arducopter_rtl_yaw_wait(p, math.pi, 0.0), 3)  # (180° − 2°) at 60°/s
    2.967
    """
    if int(p.values.get("WP_YAW_BEHAVIOR", 2.0)) not in (1, 3):
        return 0.0
    if not (math.isfinite(heading_rad) and math.isfinite(armed_heading_rad)):
        return 0.0
    err = abs(_wrap(armed_heading_rad - heading_rad)) - math.radians(AC_RTL_YAW_TOLERANCE_DEG)
    rate = math.radians(max(p.values.get("ATC_SLEW_YAW", 60.0), 1e-3))
    return max(err / rate - p["RTL_LOIT_TIME"], 0.0)


def _rtl(p: MissionParams, s: _State, home_ne: np.ndarray, cruise: float) -> bool:
    """Return to launch from the state (updating it); whether it ends on the ground."""
    up, _, az = _vertical_limits(p)
    if p.family == "arducopter":
        rtl_alt = arducopter_rtl_altitude(p, s.h, float(np.hypot(*(np.asarray(home_ne) - s.ne))))
        v = p["RTL_SPEED"] or p["WPNAV_SPEED"]
        loiter, final = p["RTL_LOIT_TIME"], p["RTL_ALT_FINAL"]
    elif p.family == "px4-mc":
        rtl_alt, v = p["RTL_RETURN_ALT"], cruise
        # RTL_LAND_DELAY < 0: hover at RTL_DESCEND_ALT instead of landing
        loiter = max(p["RTL_LAND_DELAY"], 0.0)
        final = p["RTL_DESCEND_ALT"] if p["RTL_LAND_DELAY"] < 0 else 0.0
    else:
        rtl_alt, v, loiter, final = s.h, cruise, 0.0, 0.0
    if s.h < rtl_alt:
        s.t += leg_time(rtl_alt - s.h, up, az)[0]
        s.h = rtl_alt
    s.v = 0.0
    heading_before = s.heading
    _leg(p, s, home_ne, s.h, v, 0.0, accept=False)
    if p.family == "arducopter":
        if int(p.values.get("WP_YAW_BEHAVIOR", 2.0)) in (1, 3):
            # the nose points home on the way (LOOK_AT_NEXT_WP / LOOK_AHEAD) and turns back
            # to the armed heading over home
            loiter += arducopter_rtl_yaw_wait(p, s.heading, s.armed_heading)
            if math.isfinite(s.armed_heading):
                s.heading = s.armed_heading
        else:
            s.heading = heading_before  # HOLD: the heading the vehicle had when RTL began
    s.t += loiter
    s.ne, s.v = home_ne.copy(), 0.0
    if p.family == "px4-mc" and s.h > p["RTL_DESCEND_ALT"]:
        _, dn, _ = _vertical_limits(p)
        s.t += (s.h - p["RTL_DESCEND_ALT"]) / dn
        s.h = p["RTL_DESCEND_ALT"]
    if final > 0:
        _, dn, _ = _vertical_limits(p)
        s.t += max(s.h - final, 0.0) / dn
        s.h = final
        return False
    s.t += _land_time(p, s.h, vtol=p.family == "plane")
    s.h = 0.0
    return True


# --------------------------------------------------------------------------- baselines
#: QGroundControl's offline-editing ascent and descent speeds (m/s): ``AppSettings.json``
#: ``offlineEditingAscentSpeed`` 5, ``offlineEditingDescentSpeed`` 3.
QGC_ASCENT_MS = 5.0
QGC_DESCENT_MS = 3.0


def qgc_mission_time(plan: MissionPlan, hover_speed_ms: float, home_amsl_m: float | None = None) -> float:
    """QGroundControl's mission time (s) as ``MissionController::_recalcMissionFlightStatus``
    computes it for a multicopter: a take-off first item climbs |Δalt| at the ascent speed
    (:data:`QGC_ASCENT_MS`); every item with a coordinate adds its horizontal distance from the
    previous one ÷ the hover speed (``DO_CHANGE_SPEED`` replaces it); every item adds its
    ``additionalTimeDelay`` (a waypoint's or a timed loiter's hold); after an RTL item no more
    items count and the way home adds its distance ÷ speed and |Δalt| ÷ the descent speed
    (:data:`QGC_DESCENT_MS`). A land item adds no descent time.
    """
    from uasnav.trajectory.geometry import geodetic_to_local

    speed = hover_speed_ms
    t = 0.0
    prev: tuple[float, float, float] | None = None
    home = plan.home
    first = True
    home_h = 0.0
    rtl = False
    for i in flight_sequence(plan):
        it = plan.items[i]
        if it.speed_ms is not None:
            speed = it.speed_ms
            continue
        if it.command == MAV_CMD_NAV_RETURN_TO_LAUNCH:
            rtl = True
            break
        hold = it.hold_s
        if math.isfinite(hold):
            t += hold
        if not it.has_position:
            if first and it.command in (MAV_CMD_NAV_TAKEOFF, MAV_CMD_NAV_VTOL_TAKEOFF) and home is not None:
                h = _height(plan, i, home_amsl_m, 0.0)
                t += abs(h - home_h) / QGC_ASCENT_MS
                prev = (home.lat_deg, home.lon_deg, h)
                first = False
            continue
        h = _height(plan, i, home_amsl_m, prev[2] if prev else 0.0)
        if first and it.command in (MAV_CMD_NAV_TAKEOFF, MAV_CMD_NAV_VTOL_TAKEOFF) and home is not None:
            t += abs(h - home_h) / QGC_ASCENT_MS
            prev = (home.lat_deg, home.lon_deg, home_h)
        first = False
        if prev is not None:
            ne = geodetic_to_local(
                np.array([it.lat_deg]), np.array([it.lon_deg]), np.zeros(1), origin=(prev[0], prev[1], 0.0)
            )[0, :2]
            t += float(np.hypot(*ne)) / speed
        prev = (it.lat_deg, it.lon_deg, h)
    if rtl and prev is not None and home is not None:
        ne = geodetic_to_local(
            np.array([home.lat_deg]), np.array([home.lon_deg]), np.zeros(1), origin=(prev[0], prev[1], 0.0)
        )[0, :2]
        t += float(np.hypot(*ne)) / speed + abs(prev[2]) / QGC_DESCENT_MS
    return t


def distance_over_speed_time(plan: MissionPlan, speed_ms: float, home_amsl_m: float | None = None) -> float:
    """The naive estimate (s): the 3-D path length through the plan's items ÷ ``speed_ms``."""
    params = MissionParams("plane", None, {**{k: d.value for k, d in PLANE_DEFAULTS.items()},
                                           "AIRSPEED_CRUISE": speed_ms, "TECS_CLMB_MAX": speed_ms,
                                           "TECS_SINK_MAX": speed_ms, "Q_WP_SPEED_UP": speed_ms,
                                           "Q_WP_SPEED_DN": speed_ms, "Q_LAND_SPEED": speed_ms,
                                           "Q_TRANSITION_MS": 0.0, "Q_WP_ACCEL_Z": 1e9,
                                           "WP_RADIUS": 0.0})  # fmt: skip
    try:
        return predict_mission(plan, params, home_amsl_m=home_amsl_m).eta_s
    except InputError:
        return math.nan


__all__ = [
    "ARDUCOPTER_DEFAULTS",
    "FAMILIES",
    "PLANE_DEFAULTS",
    "PX4_MC_DEFAULTS",
    "Default",
    "MissionParams",
    "MissionPrediction",
    "ModelOptions",
    "arducopter_jerk_time",
    "arducopter_rtl_altitude",
    "arducopter_rtl_yaw_wait",
    "banded_descent_time",
    "corner_speed",
    "distance_over_speed_time",
    "family_of",
    "leg_time",
    "mission_params",
    "predict_mission",
    "px4_land_time",
    "qgc_mission_time",
    "speed_change_time",
]
