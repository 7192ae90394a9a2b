"""Mission execution models per autopilot family: closed forms against numerical simulation,
the parameter defaults against their cited firmware sources, and the real flights."""

from __future__ import annotations

import dataclasses
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.io.mission_plan import HomePosition, MissionItem, MissionPlan
from uasnav.trajectory import autopilot as ap
from uasnav.trajectory.geometry import merge_short_legs


# --- closed forms ---------------------------------------------------------------------------
def _simulate_1d(d: float, v_max: float, a: float, decel: float, dt: float = 1e-4) -> float:
    """Rest-to-rest point mass under a speed and acceleration limit, braking as late as it can
    (the time-optimal bang-bang profile), integrated numerically."""
    x = v = t = 0.0
    while x < d - 1e-9:
        brake = v * v / (2 * decel) >= d - x
        acc = -decel if brake else (a if v < v_max else 0.0)
        v = min(max(v + acc * dt, 0.0), v_max)
        x += v * dt
        t += dt
        if brake and v <= 0.0:
            break
    return t


@pytest.mark.parametrize(
    ("d", "v", "a", "dec"), [(100.0, 5.0, 1.0, 1.0), (3.0, 5.0, 1.0, 1.0), (50.0, 5.0, 1.0, 2.0)]
)
def test_leg_time_is_the_time_optimal_profile(d: float, v: float, a: float, dec: float) -> None:
    t, v_end = ap.leg_time(d, v, a, decel=dec)
    assert v_end == 0.0
    assert t == pytest.approx(_simulate_1d(d, v, a, dec), rel=0.01)
    if d >= v * v / (2 * a) + v * v / (2 * dec):  # trapezoid: d/v + v/(2a) + v/(2·dec)
        assert t == pytest.approx(d / v + v / (2 * a) + v / (2 * dec))
    else:  # triangle
        vp = math.sqrt(2 * d * a * dec / (a + dec))
        assert t == pytest.approx(vp / a + vp / dec)


def test_jerk_limited_speed_change() -> None:
    # Δv ≥ a²/j: Δv/a + a/j; below it the acceleration never saturates: 2·√(Δv/j)
    assert ap.speed_change_time(5.0, 1.0, 1.0) == pytest.approx(6.0)
    assert ap.speed_change_time(0.5, 1.0, 1.0) == pytest.approx(2 * math.sqrt(0.5))
    # numerically: jerk ±j up to a, the distance covered equals (v0 + v1)/2 · T
    j, a, dv, dt = 2.0, 1.5, 4.0, 1e-5
    t_ramp = a / j
    t_total = ap.speed_change_time(dv, a, j)
    ts = np.arange(0.0, t_total, dt)
    acc = np.minimum(np.minimum(j * ts, a), j * (t_total - ts))
    assert np.sum(acc) * dt == pytest.approx(dv, rel=1e-3)
    assert t_ramp < t_total / 2


def test_px4_braking_law_closed_form() -> None:
    a, j = 3.0, 4.0
    # computeMaxSpeedFromDistance: v = ½(−b + √(b² + 8ad + 4v_f²)), b = 4a²/j
    b = 4 * a * a / j
    for d, vf in ((4.4, 0.0), (20.0, 1.0)):
        assert ap.px4_max_speed_from_distance(d, a, j, vf) == pytest.approx(
            0.5 * (-b + math.sqrt(b * b + 8 * a * d + 4 * vf * vf))
        )
    # the time along the law equals ∫ dd / v(d), numerically
    d1, d2 = 10.0, 1.0
    dd = np.linspace(d2, d1, 200_001)
    v = np.array([ap.px4_max_speed_from_distance(x, a, j) for x in dd[::100]])
    t_num = np.trapezoid(1.0 / v, dd[::100])
    assert ap.px4_braking_time(d1, d2, a, j) == pytest.approx(t_num, rel=1e-4)


def test_landing_speed_profiles() -> None:
    # ArduCopter: 10 m at WPNAV_SPEED_DN above LAND_ALT_LOW, the rest at LAND_SPEED
    assert ap.banded_descent_time(20.0, 1.5, 0.5, 10.0) == pytest.approx(10 / 1.5 + 10 / 0.5)
    assert ap.banded_descent_time(5.0, 1.5, 0.5, 10.0) == pytest.approx(10.0)
    # PX4: linear blend between MPC_LAND_ALT1 and ALT2, integrated numerically
    h, vdn, vl, a1, a2 = 30.0, 1.5, 0.7, 10.0, 5.0
    z = np.linspace(0.0, h, 300_001)
    v = np.where(z > a1, vdn, np.where(z < a2, vl, vl + (vdn - vl) * (z - a2) / (a1 - a2)))
    assert ap.px4_land_time(h, vdn, vl, a1, a2) == pytest.approx(np.trapezoid(1 / v, z), rel=1e-5)


def test_corner_speeds() -> None:
    px4 = ap.mission_params("px4-mc", "1.14.0", {"NAV_ACC_RAD": 2.0})
    # √(a·TRAJ_P·R·tan(α/2)), α = π − θ: a 90° turn gives tan(45°) = 1
    assert ap.corner_speed(px4, math.pi / 2, 10.0) == pytest.approx(math.sqrt(3.0 * 0.5 * 2.0))
    assert ap.corner_speed(px4, 0.0, 5.0) == 5.0 and ap.corner_speed(px4, math.pi, 5.0) == 0.0
    ac4 = ap.mission_params("arducopter", "4.5.7")
    r = 2.0 / (1 / math.cos(math.pi / 4) - 1)  # the arc within WPNAV_RADIUS of the corner
    assert ap.corner_speed(ac4, math.pi / 2, 10.0) == pytest.approx(math.sqrt(2 * 2.5 * r))
    ac3 = ap.mission_params("arducopter", "3.6.12")
    assert ap.corner_speed(ac3, math.pi / 2, 5.0) == 5.0  # a 3.x fast waypoint


# --- ArduCopter 4.x S-curve against the firmware's own segment equations ---------------------
def _raised_cosine_speed_change(
    dv: float, a_max: float, j_max: float, tj: float, dt: float = 2e-5
) -> tuple[float, float, float]:
    """Integrate SCurve's jerk profile numerically from rest: a raised-cosine jerk rise over
    tj (J = ½·Jm·(1 − cos(π·t/tj))), constant jerk Jm for t2 = Am/Jm − tj, a raised-cosine
    fall, constant acceleration, and the mirror image down to zero acceleration at v = Δv
    (``SCurve::add_segments_jerk``). Returns (duration, speed reached, distance)."""
    t2 = a_max / j_max - tj
    a_ramp_dv = a_max * (t2 + 2 * tj)  # speed gained by the rise and the fall of the acceleration
    t4 = (dv - a_ramp_dv) / a_max
    assert t2 >= 0 and t4 >= 0

    def jerk_up(t: float) -> float:  # one rise of the acceleration from 0 to Am
        if t < tj:
            return 0.5 * j_max * (1 - math.cos(math.pi * t / tj))
        if t < tj + t2:
            return j_max
        if t < 2 * tj + t2:
            return 0.5 * j_max * (1 - math.cos(math.pi * (t - tj - t2) / tj + math.pi))
        return 0.0

    t_rise = 2 * tj + t2
    total = 2 * t_rise + t4
    ts = np.arange(0.0, total, dt)
    jerk = np.array(
        [jerk_up(t) if t < t_rise else (0.0 if t < t_rise + t4 else -jerk_up(t - t_rise - t4)) for t in ts]
    )
    acc = np.cumsum(jerk) * dt
    vel = np.cumsum(acc) * dt
    return total, float(vel[-1]), float(np.sum(vel) * dt)


def test_scurve_raised_cosine_segment_matches_the_firmware_closed_forms() -> None:
    """``SCurve::add_segment_incr_jerk`` ends a raised-cosine jerk segment of length tj at
    A = Jm·tj/2, V = Jm/2·(tj²/2 − 2·tj²/π²), P = Jm/2·(tj³/6 − tj³/π²) (from rest): the same
    numbers as integrating the jerk numerically."""
    jm, tj, dt = 1.0, 0.3, 1e-6
    ts = np.arange(0.0, tj, dt)
    acc = np.cumsum(0.5 * jm * (1 - np.cos(np.pi * ts / tj))) * dt
    vel = np.cumsum(acc) * dt
    pos = np.sum(vel) * dt
    beta = math.pi / tj
    assert acc[-1] == pytest.approx(0.5 * jm * tj, rel=1e-4)
    assert vel[-1] == pytest.approx(0.5 * jm * (tj * tj / 2 - 2 / beta**2), rel=1e-3)
    assert pos == pytest.approx(0.5 * jm * (-tj / beta**2 + tj**3 / 6), rel=2e-3)


@pytest.mark.parametrize(
    ("dv", "a_max", "j_max", "tc"), [(10.0, 2.5, 1.0, 0.15), (5.0, 1.0, 1.0, 0.15), (8.0, 2.0, 2.5, 0.3)]
)
def test_arducopter_4x_speed_change_is_the_scurve_profile(
    dv: float, a_max: float, j_max: float, tc: float
) -> None:
    """The 4.x speed change (:func:`speed_change_time` with t_j = 2·ATC_INPUT_TC) equals the
    duration of SCurve's 7-segment raised-cosine profile, and covers (v₀ + v₁)/2 · T."""
    p = ap.mission_params(
        "arducopter", "4.5.7", {"ATC_INPUT_TC": tc, "WPNAV_ACCEL": a_max * 100, "WPNAV_JERK": j_max}
    )
    tj = ap.arducopter_jerk_time(p)
    assert tj == pytest.approx(2 * tc)
    # AC_WPNav::calc_scurve_jerk_and_snap: S = ½·j·π/(2·tc); SCurve::calculate_path: tj = j·π/(2·S)
    snap = 0.5 * j_max * math.pi / (2 * max(tc, 0.1))
    assert tj == pytest.approx(j_max * math.pi / (2 * snap))
    total, v_end, dist = _raised_cosine_speed_change(dv, a_max, j_max, tj)
    assert v_end == pytest.approx(dv, rel=1e-3)
    assert ap.speed_change_time(dv, a_max, j_max, tj) == pytest.approx(total, rel=1e-6)
    assert dist == pytest.approx(0.5 * dv * total, rel=1e-3)
    # a whole rest-to-rest leg long enough to cruise: two such changes and the cruise between
    d = 200.0
    t_leg, _ = ap.leg_time(d, dv, a_max, j_max, jerk_time=tj)
    assert t_leg == pytest.approx(2 * total + (d - dv * total) / dv, rel=1e-6)
    # 3.x has no S-curve
    assert ap.arducopter_jerk_time(ap.mission_params("arducopter", "3.6.12")) == 0.0


def test_short_scurve_speed_changes_are_continuous() -> None:
    # across the branches (acceleration limit reached / not reached / jerk lowered) the time
    # grows continuously with Δv and reduces to the constant-jerk law when t_j = 0
    a, j, tj = 2.5, 1.0, 0.3
    dvs = np.linspace(1e-4, 12.0, 4001)
    ts = np.array([ap.speed_change_time(x, a, j, tj) for x in dvs])
    assert np.all(np.diff(ts) >= -1e-12) and np.max(np.abs(np.diff(ts))) < 0.05
    for x in (0.05, 1.0, 7.0):
        assert ap.speed_change_time(x, a, j, 0.0) == ap.speed_change_time(x, a, j)


# --- PX4 jerk-limited speed changes against VelocitySmoothing's own durations ----------------
def _px4_velocity_smoothing(v0: float, v1: float, a_max: float, j_max: float) -> tuple[float, float]:
    """PX4 ``VelocitySmoothing::updateDurationsMinimizeTotalTime`` from zero acceleration:
    T1 = (½·√(4·j·Δv))/j saturated so that j·T1 ≤ a_max (``computeT1``,
    ``saturateT1ForAccel``), T3 = T1 (``computeT3`` with a₀ = 0), T2 =
    (Δv − j·T1² ·½ − j·T1·T3 + j·T3²·½)/(j·T1) (``computeT2``); the distance from
    ``evaluatePoly`` over the three phases. Returns (T1 + T2 + T3, distance)."""
    dv = v1 - v0
    t1 = min(0.5 * math.sqrt(4 * j_max * dv) / j_max, a_max / j_max)
    t3 = t1
    t2 = max((-0.5 * t1 * t1 * j_max - t1 * t3 * j_max + 0.5 * t3 * t3 * j_max + dv) / (j_max * t1), 0.0)

    def poly(j: float, a: float, v: float, x: float, t: float) -> tuple[float, float, float]:
        return a + j * t, v + a * t + 0.5 * j * t * t, x + v * t + 0.5 * a * t * t + j * t**3 / 6

    a, v, x = poly(j_max, 0.0, v0, 0.0, t1)
    a, v, x = poly(0.0, a, v, x, t2)
    a, v, x = poly(-j_max, a, v, x, t3)
    assert v == pytest.approx(v1, abs=1e-9) and a == pytest.approx(0.0, abs=1e-9)
    return t1 + t2 + t3, x


@pytest.mark.parametrize(("v0", "v1"), [(0.0, 5.0), (0.0, 1.0), (2.0, 12.0), (1.0, 1.5)])
def test_px4_speed_change_is_velocity_smoothing(v0: float, v1: float) -> None:
    a, j = 3.0, 4.0  # MPC_ACC_HOR, MPC_JERK_AUTO defaults
    total, dist = _px4_velocity_smoothing(v0, v1, a, j)
    assert ap.speed_change_time(v1 - v0, a, j) == pytest.approx(total, rel=1e-9)
    assert ap._change(v0, v1, a, j)[1] == pytest.approx(dist, rel=1e-9)


# --- defaults against their citations -------------------------------------------------------
_UNIT_SCALE = {"cm/s²": 0.01, "cm/s": 0.01, "cm": 0.01, "ms": 0.001, "cd/s": 0.01}


@pytest.mark.parametrize(
    "table", [ap.ARDUCOPTER_DEFAULTS["3"], ap.ARDUCOPTER_DEFAULTS["4"], ap.PX4_MC_DEFAULTS, ap.PLANE_DEFAULTS]
)
def test_defaults_match_their_cited_source(table: dict[str, ap.Default]) -> None:
    for name, d in table.items():
        # "<file> <version>: <NAME> <number> <unit>": the number, in the firmware's unit, is the value
        m = re.search(
            r":\s*[A-Z_0-9]+ (−?[\d.]+)\s*(cm/s²|cm/s|cm|ms|cd/s|m/s³|m/s²|m/s|m|s|°/s|°)?", d.source
        )
        assert m is not None, d.source
        number = float(m.group(1).replace("−", "-"))
        assert d.value == pytest.approx(number * _UNIT_SCALE.get(m.group(2) or "", 1.0)), (name, d.source)
        assert re.search(r"\.(cpp|c|h)\b", d.source) and re.search(r"\d\.\d", d.source), d.source
        # read in the public source: the stored file and the layout or commit that dates it
        assert re.search(r"\.(cpp|c|h|yaml)\b", d.verified), (name, d.verified)


def test_corrected_citations() -> None:
    # 3.x keeps the WPNAV defaults in the header; LAND_ALT_LOW is a parameter from 3.6 on
    assert ap.ARDUCOPTER_DEFAULTS["3"]["WPNAV_ACCEL"].source.startswith("AC_WPNav.h Copter-3.6")
    assert "LAND_ALT_LOW 1000 cm" in ap.ARDUCOPTER_DEFAULTS["3"]["LAND_ALT_LOW"].source
    assert ap.ARDUCOPTER_DEFAULTS["4"]["LAND_ALT_LOW"].source.startswith("ArduCopter/Parameters.cpp")
    # PX4 1.11 descends at MPC_Z_VEL_MAX_DN 1 m/s; 1.12+ in AUTO at MPC_Z_V_AUTO_DN 1.5 m/s
    assert ap.PX4_MC_DEFAULTS["MPC_Z_VEL_MAX_DN"].value == 1.0
    assert ap.PX4_MC_DEFAULTS["MPC_Z_V_AUTO_DN"].value == 1.5


_NO_YAW = (0.0, 0.0, 0.0, math.nan)


def test_px4_yaw_first_waits_for_the_heading() -> None:
    # MPC_YAW_MODE 4: stop at the corner, turn at MPC_YAWRAUTO_MAX, then fly the next leg (the
    # items leave the heading to the yaw mode: param 4 NaN)
    items = [
        MissionItem(22, 3, alt_m=10.0),
        MissionItem(16, 3, _NO_YAW, lat_deg=_north(50.0), lon_deg=8.0, alt_m=10.0),
        MissionItem(16, 3, _NO_YAW, lat_deg=_north(50.0), lon_deg=8.0 + 50.0 / 75_800.0, alt_m=10.0),
        MissionItem(16, 3, _NO_YAW, lat_deg=_north(100.0), lon_deg=8.0 + 50.0 / 75_800.0, alt_m=10.0),
    ]
    base = ap.mission_params("px4-mc", "1.14.0", {"MPC_YAW_MODE": 4.0, "NAV_ACC_RAD": 1.0})
    no_wait = ap.mission_params("px4-mc", "1.14.0", {"MPC_YAW_MODE": 0.0, "NAV_ACC_RAD": 1.0})
    r4, r0 = ap.predict_mission(_plan(items), base), ap.predict_mission(_plan(items), no_wait)
    # two turns of atan(50/1) ≈ 88.9° at 45°/s on top of the legs (and the stops at the corners)
    turn_s = math.degrees(math.atan2(50.0, 1.0)) / 45.0
    assert r4.eta_s - r0.eta_s >= 2 * turn_s
    no_option = dataclasses.replace(base, options=ap.ModelOptions(yaw_before_move=False))
    assert ap.predict_mission(_plan(items), no_option).eta_s == pytest.approx(r0.eta_s)
    # ArduCopter turns while it flies: WP_YAW_BEHAVIOR changes nothing in the time
    ac = ap.mission_params("arducopter", "4.5.7")
    assert ap.predict_mission(_plan(items), ac).eta_s == pytest.approx(
        ap.predict_mission(
            _plan(items), dataclasses.replace(ac, options=ap.ModelOptions(yaw_before_move=False))
        ).eta_s
    )


def test_log_parameters_win_and_are_converted() -> None:
    p = ap.mission_params("arducopter", "3.5.7", {"WPNAV_SPEED": 500.0, "WPNAV_ACCEL": 100.0})
    assert p["WPNAV_SPEED"] == 5.0 and p.sources["WPNAV_SPEED"] == "log"
    # LAND_SPEED's default is the config.h macro Parameters.cpp refers to
    assert p.sources["LAND_SPEED"].startswith("ArduCopter/config.h Copter-3.6")
    # PX4 before 1.12 climbs at MPC_Z_VEL_MAX_UP in AUTO, from 1.12 at MPC_Z_V_AUTO_UP
    old = ap.mission_params("px4-mc", "1.11.0", {"MPC_Z_VEL_MAX_DN": 1.0})
    new = ap.mission_params("px4-mc", "1.14.0", {"MPC_Z_V_AUTO_DN": 2.0})
    assert ap._vertical_limits(old)[1] == 1.0 and ap._vertical_limits(new)[1] == 2.0
    with pytest.raises(Exception, match="unknown autopilot family"):
        ap.mission_params("betaflight")


# --- whole missions, simulated --------------------------------------------------------------
def _plan(items: list[MissionItem]) -> MissionPlan:
    return MissionPlan(items=tuple(items), home=HomePosition(47.0, 8.0, 400.0))


def _north(m: float) -> float:
    return 47.0 + m / 111_195.0  # about a metre of latitude


def test_arducopter_3x_mission_is_the_sum_of_its_closed_forms() -> None:
    p = ap.mission_params("arducopter", "3.6.0")  # defaults: 5 m/s, 1 m/s², up 2.5, dn 1.5
    plan = _plan(
        [
            MissionItem(22, 3, alt_m=20.0),
            MissionItem(16, 3, lat_deg=_north(100.0), lon_deg=8.0, alt_m=20.0),
            MissionItem(21, 3, alt_m=0.0),
        ]
    )
    r = ap.predict_mission(plan, p)
    t_takeoff = ap.leg_time(20.0, 2.5, 1.0)[0]
    t_leg = ap.leg_time(100.0, 5.0, 1.0, decel=2.0)[0]
    t_land = 10 / 1.5 + 10 / 0.5
    assert r.arrive_s == pytest.approx([t_takeoff, t_takeoff + t_leg, t_takeoff + t_leg + t_land], rel=2e-3)
    assert r.landed and r.eta_s == pytest.approx(r.arrive_s[-1])


def test_px4_mission_simulated_point_mass() -> None:
    """A PX4 leg against a numerical point mass that follows the braking law with the
    acceleration limit, accepted NAV_ACC_RAD before the waypoint."""
    p = ap.mission_params("px4-mc", "1.14.0", {"NAV_ACC_RAD": 2.0, "MPC_XY_P": 1e9})
    d, a, j, v_max = 60.0, 3.0, 4.0, 5.0
    x = v = t = 0.0
    dt = 1e-4
    acc = 0.0
    while d - x > 2.0:
        lim = min(v_max, ap.px4_max_speed_from_distance(d - x, a, j))
        want = min(v + a * dt, lim)
        acc_new = (want - v) / dt
        acc = min(acc_new, acc + j * dt) if acc_new > acc else acc_new  # jerk while speeding up
        v += acc * dt
        x += v * dt
        t += dt
    plan = _plan([MissionItem(16, 3, lat_deg=_north(d), lon_deg=8.0, alt_m=10.0)])
    r = ap.predict_mission(plan, p, start_height_m=10.0)
    assert r.arrive_s[0] == pytest.approx(t, rel=0.02)


def test_quadplane_dalby_plan_predicts(shared_data: Path) -> None:
    plan = shared_data / "missions" / "ardupilot_autotest_dalby_obc2016.waypoints"
    r = CliRunner().invoke(main, ["trajectory", "mission", str(plan), "--json"])
    assert r.exit_code == 0, r.output
    out = json.loads(r.output)
    assert out["autopilot"] == "plane" and out["landed"]
    # km-long legs at 12–24 m/s with a DO_JUMP loop repeated four times: most of an hour
    assert 1800 < out["eta_s"] < 7200
    # the default is the config.h macro ArduPlane/Parameters.cpp refers to
    assert out["parameters"]["AIRSPEED_CRUISE"]["source"].startswith("ArduPlane/config.h")
    # VTOL take-off (84) and landing (85) are items with times
    assert {84, 85} <= {i["command"] for i in out["items"]}


def test_short_legs_merge() -> None:
    plan = np.array([[0.0, 0.0], [100.0, 0.0], [100.0, 1.85], [200.0, 1.85], [201.0, 1.85]])
    merged, idx = merge_short_legs(plan, 10.0)
    assert merged.tolist() == [[0.0, 0.0], [100.0, 0.0], [201.0, 1.85]]
    assert idx.tolist() == [0, 1, 2, 2, 2]


# --- real flights ---------------------------------------------------------------------------
def test_real_px4_mission_evaluates_without_options(shared_data: Path) -> None:
    from uasnav.trajectory.mission_runs import MODEL, QGC, evaluate_logs

    r = evaluate_logs([shared_data / "flights" / "px4_s500_mission_land.ulg"])
    (run,) = r["runs"]
    assert run["stack"].startswith("px4-mc 1.11") and run["landed"]
    assert len(run["waypoint_errors"]) == 11  # navigator_mission_item v1.11 layout read
    e = abs(run["eta_pred_s"][MODEL] - run["eta_real_s"]) / run["eta_real_s"]
    e_qgc = abs(run["eta_pred_s"][QGC] - run["eta_real_s"]) / run["eta_real_s"]
    assert e <= 0.15 and e_qgc >= 2 * e
    assert r["parameters"][str(shared_data / "flights" / "px4_s500_mission_land.ulg")]["NAV_ACC_RAD"] == {
        "value": 2.0,
        "source": "log",
    }


def test_arducopter_4x_rtl_closed_form_and_final_altitude_hover() -> None:
    items = [
        MissionItem(22, 3, alt_m=20.0),
        MissionItem(16, 3, lat_deg=_north(100.0), lon_deg=8.0, alt_m=20.0),
        MissionItem(20, 2),
    ]
    p = ap.mission_params("arducopter", "4.5.7")  # 10 m/s, 2.5 m/s², jerk 1 m/s³; RTL_ALT 15 m
    r = ap.predict_mission(_plan(items), p)
    # the S-curve's raised-cosine jerk lasts 2·ATC_INPUT_TC = 0.3 s
    t_leg = ap.leg_time(100.0, 10.0, 2.5, 1.0, jerk_time=0.3)[0]
    # already above RTL_ALT: back at WPNAV_SPEED, RTL_LOIT_TIME 5 s, land 10 m at 1.5 + 10 m at 0.5
    assert r.eta_s - r.arrive_s[1] == pytest.approx(t_leg + 5.0 + 10 / 1.5 + 10 / 0.5, rel=2e-3)
    assert r.landed
    hover = ap.mission_params("arducopter", "4.5.7", {"RTL_ALT_FINAL": 500.0})
    h = ap.predict_mission(_plan(items), hover)
    assert not h.landed and h.eta_s - h.arrive_s[1] == pytest.approx(t_leg + 5.0 + 15 / 1.5, rel=2e-3)


def test_arducopter_rtl_cone_closed_form() -> None:
    """``ModeRTL::compute_return_target``: the return height is RTL_ALT limited by the cone
    d·RTL_CONE_SLOPE around home, never below the current height."""
    p4 = ap.mission_params("arducopter", "4.5.7")  # RTL_ALT 15 m, slope 3, RTL_CLIMB_MIN 0
    assert ap.arducopter_rtl_altitude(p4, 5.0, 100.0) == 15.0  # far: RTL_ALT
    assert ap.arducopter_rtl_altitude(p4, 5.0, 3.0) == pytest.approx(9.0)  # 3 m × 3
    assert ap.arducopter_rtl_altitude(p4, 5.0, 1.0) == 5.0  # inside the cone: no climb
    assert ap.arducopter_rtl_altitude(p4, 20.0, 1.0) == 20.0  # never descends
    flat = ap.mission_params("arducopter", "4.5.7", {"RTL_CONE_SLOPE": 0.4})  # below 0.5: off
    assert ap.arducopter_rtl_altitude(flat, 5.0, 1.0) == 15.0
    climb = ap.mission_params("arducopter", "4.5.7", {"RTL_CLIMB_MIN": 300.0})  # 3 m, in cm
    assert ap.arducopter_rtl_altitude(climb, 5.0, 1.0) == pytest.approx(8.0)
    # 3.5–3.6: inside the cone it still climbs RTL_ABS_MIN_CLIMB (2.5 m) up to RTL_ALT
    p3 = ap.mission_params("arducopter", "3.6.12")
    assert ap.arducopter_rtl_altitude(p3, 5.0, 1.0) == pytest.approx(7.5)
    assert ap.arducopter_rtl_altitude(p3, 5.0, 3.0) == pytest.approx(9.0)
    assert ap.arducopter_rtl_altitude(p3, 14.0, 1.0) == pytest.approx(15.0)
    # 3.3 has no cone: up to RTL_ALT
    assert ap.arducopter_rtl_altitude(ap.mission_params("arducopter", "3.3.3"), 5.0, 1.0) == 15.0


def test_arducopter_rtl_near_home_climbs_only_to_the_cone() -> None:
    # RTL 3 m from home at 5 m: climbs 4 m (to 3 m × 3) instead of 10 m, then returns
    items = [
        MissionItem(22, 3, alt_m=5.0),
        MissionItem(16, 3, lat_deg=_north(3.0), lon_deg=8.0, alt_m=5.0),
        MissionItem(20, 2),
    ]
    p = ap.mission_params("arducopter", "4.5.7")
    r = ap.predict_mission(_plan(items), p)
    t_climb = ap.leg_time(4.0, 2.5, 1.0)[0]
    t_back = ap.leg_time(3.0, 10.0, 2.5, 1.0, jerk_time=0.3)[0]
    t_land = 9.0 / 0.5  # all of it below LAND_ALT_LOW
    assert r.eta_s - r.arrive_s[1] == pytest.approx(t_climb + t_back + 5.0 + t_land, rel=2e-3)
    no_cone = ap.mission_params("arducopter", "4.5.7", {"RTL_CONE_SLOPE": 0.0})
    r0 = ap.predict_mission(_plan(items), no_cone)
    t_climb0 = ap.leg_time(10.0, 2.5, 1.0)[0]
    t_land0 = 5.0 / 1.5 + 10.0 / 0.5
    assert r0.eta_s - r0.arrive_s[1] == pytest.approx(t_climb0 + t_back + 5.0 + t_land0, rel=2e-3)


def test_arducopter_rtl_turns_back_to_the_armed_heading() -> None:
    """WP_YAW_BEHAVIOR 1/3 point the nose home on the way back; over home the loiter ends
    once RTL_LOIT_TIME has passed and the heading is within 2° of the armed heading."""
    items = [
        MissionItem(22, 3, alt_m=20.0),
        MissionItem(16, 3, lat_deg=_north(100.0), lon_deg=8.0, alt_m=20.0),
        MissionItem(20, 2),
    ]
    # armed facing north; the way home is south: a 180° turn at ATC_SLEW_YAW 60°/s = 2.97 s
    p_hold = ap.mission_params("arducopter", "4.5.7", {"RTL_LOIT_TIME": 1000.0})  # 1 s
    p_look = ap.mission_params("arducopter", "4.5.7", {"RTL_LOIT_TIME": 1000.0, "WP_YAW_BEHAVIOR": 1})
    r_hold = ap.predict_mission(_plan(items), p_hold, armed_heading_deg=0.0)
    r_look = ap.predict_mission(_plan(items), p_look, armed_heading_deg=0.0)
    assert r_look.eta_s - r_hold.eta_s == pytest.approx((180.0 - 2.0) / 60.0 - 1.0, abs=1e-6)
    # a loiter longer than the turn hides it; WP_YAW_BEHAVIOR 2 (the default) holds the heading
    p_long = ap.mission_params("arducopter", "4.5.7", {"WP_YAW_BEHAVIOR": 3})
    base = ap.predict_mission(_plan(items), ap.mission_params("arducopter", "4.5.7"), armed_heading_deg=0.0)
    assert ap.predict_mission(_plan(items), p_long, armed_heading_deg=0.0).eta_s == pytest.approx(base.eta_s)
    # unknown armed heading: no turn is timed
    assert ap.predict_mission(_plan(items), p_look).eta_s == pytest.approx(r_hold.eta_s)
    # armed facing south (the way home): nothing to turn
    assert ap.predict_mission(_plan(items), p_look, armed_heading_deg=180.0).eta_s == pytest.approx(
        r_hold.eta_s
    )


def test_arducopter_yaw_behaviour_costs_no_time_in_auto() -> None:
    """ModeAuto::wp_run points the nose while it flies; verify_nav_wp has no heading
    condition: a square flown with any WP_YAW_BEHAVIOR takes the same time."""
    items = [
        MissionItem(22, 3, alt_m=10.0),
        MissionItem(16, 3, lat_deg=_north(50.0), lon_deg=8.0, alt_m=10.0),
        MissionItem(16, 3, lat_deg=_north(50.0), lon_deg=8.0 + 50.0 / 75_800.0, alt_m=10.0),
        MissionItem(16, 3, lat_deg=_north(0.0), lon_deg=8.0 + 50.0 / 75_800.0, alt_m=10.0),
        MissionItem(21, 3, alt_m=0.0),
    ]
    times = {
        b: ap.predict_mission(
            _plan(items),
            ap.mission_params("arducopter", "4.5.7", {"WP_YAW_BEHAVIOR": b}),
            armed_heading_deg=90.0,
        ).eta_s
        for b in (0, 1, 2, 3)
    }
    assert max(times.values()) == pytest.approx(min(times.values()))


def test_time_bounds_from_the_vehicles_own_flights(shared_data: Path) -> None:
    from uasnav.errors import InputError
    from uasnav.trajectory.mission_runs import calibrate_from_flights, simulated_scores

    ulg = shared_data / "flights" / "px4_s500_mission_land.ulg"
    b = calibrate_from_flights([ulg])
    assert b.n_runs == 1 and "1 AUTO runs of the vehicle (px4_s500_mission_land.ulg)" == b.source
    # one run cannot give 95 % coverage (19 are needed): refused, not a silent band
    with pytest.raises(InputError, match="at least 19 calibration runs"):
        b.quantile(0.95)
    assert b.quantile(0.5) == b.scores[0]
    # without flights: simulated executions of the plan; the nominal parameters score 0
    p = ap.mission_params("arducopter", "4.5.7")
    plan = _plan([MissionItem(22, 3, alt_m=20.0), MissionItem(21, 3, alt_m=0.0)])
    s = simulated_scores(plan, p, n_runs=50, seed=1)
    assert s.shape == (50,) and np.all(s >= 0) and np.all(s < 1.0) and s.max() > 0


def test_px4_auto_vertical_speeds_win_in_the_limits() -> None:
    from uasnav.io.autopilot_params import PX4_PARAMS, limits_from_params

    lim = limits_from_params(
        {"MPC_Z_V_AUTO_UP": 2.0, "MPC_Z_VEL_MAX_UP": 3.0, "MPC_Z_VEL_MAX_DN": 1.0}, PX4_PARAMS
    )
    assert lim.climb_ms == 2.0 and lim.descent_ms == 1.0  # 1.11 logs have only the _VEL_MAX_ pair


def test_evaluate_cli_on_a_px4_log_keeps_the_keys_and_adds_waypoints(shared_data: Path) -> None:
    ulg = shared_data / "flights" / "px4_s500_mission_land.ulg"
    r = CliRunner().invoke(main, ["trajectory", "evaluate", str(ulg), "--json"])
    assert r.exit_code == 0, r.output
    out = json.loads(r.output)
    assert out["default_method"] == "autopilot model"
    m = out["methods"]["autopilot model"]
    assert m["applicable"] and m["run_abs_e_pct_median"] <= 15.0 and len(m["run_e_pct"]) == 1
    assert out["methods"]["QGroundControl estimate"]["run_abs_e_pct_median"] >= 2 * m["run_abs_e_pct_median"]
    (run,) = out["runs"]
    assert [w["item"] for w in run["waypoint_errors"]] == list(range(11))
    assert all(abs(w["error_s"]) < 5.0 for w in run["waypoint_errors"])
    tb = out["time_bounds"]
    assert tb["n_runs"] == 1 and 0.0 <= tb["covered_ci95"][0] < tb["covered_ci95"][1] <= 1.0
    # the element methods need waypoints in the telemetry, which a PX4 log keeps out of it
    assert "no waypoints in the telemetry" in out["element_methods"]
    r = CliRunner().invoke(main, ["trajectory", "evaluate", str(ulg)])
    assert r.exit_code == 0 and "autopilot model" in r.output and "Clopper–Pearson" in r.output


def test_web_prediction_takes_the_dalby_plan_with_its_short_vtol_leg(shared_data: Path) -> None:
    from uasnav.web.default_model import default_model
    from uasnav.web.prediction import predict_plan, read_uploaded_plan

    data = (shared_data / "missions" / "ardupilot_autotest_dalby_obc2016.waypoints").read_bytes()
    up = read_uploaded_plan("dalby.waypoints", data)
    legs = np.hypot(*np.diff(up.route_ne, axis=0).T)
    assert legs.min() < 10.0  # the VTOL landing's 1.85 m leg, shorter than L
    r = predict_plan(default_model(), up.route_ne, up.origin, 3.0, 0.0, 20.0, "default")
    times = [w["time_s"] for w in r.waypoints]
    assert len(times) == len(up.route_ne) and np.all(np.diff(times) >= 0) and r.eta_s > 0


@pytest.mark.parametrize(
    ("log", "why"),
    [
        ("flights/alfa_carbonz_engine_failure", "carries no plan"),
        ("logs/ardupilot_log171.bin", "only a home position"),
        ("logs/px4_sample_log_small.ulg", "empty mission"),
    ],
)
def test_evaluate_names_why_a_log_without_a_mission_cannot_be_scored(
    shared_data: Path, log: str, why: str
) -> None:
    # an ALFA folder is a log like any other; each evaluation says why it does not apply
    r = CliRunner().invoke(main, ["trajectory", "evaluate", str(shared_data / log)])
    assert r.exit_code == 1
    lines = r.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: mission model: ") and why in lines[0], r.output
    assert "element methods: " in lines[0] and "Traceback" not in r.output


def test_web_page_predicts_the_dalby_plan(shared_data: Path) -> None:
    """The trajectory page itself (form post, no JavaScript) takes the real QuadPlane plan
    with its 1.85 m VTOL landing leg and draws every waypoint."""
    import warnings

    from uasnav.web import create_app

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from fastapi.testclient import TestClient

    data = (shared_data / "missions" / "ardupilot_autotest_dalby_obc2016.waypoints").read_bytes()
    client = TestClient(create_app(), base_url="http://127.0.0.1:8000", raise_server_exceptions=False)
    r = client.post("/trajectory", files={"plan": ("dalby.waypoints", data)})
    assert r.status_code == 200 and 'id="prediction"' in r.text, r.text[-2000:]
    assert "shorter than" not in r.text
    # every distinct waypoint of the route is drawn (the start marked apart)
    assert r.text.count('<circle class="wp') >= 29


def test_run_start_heading_is_the_nearest_attitude_sample() -> None:
    from types import SimpleNamespace

    from uasnav.trajectory.mission_runs import _heading_at

    ref = SimpleNamespace(
        t=np.array([0.0, 1.0, 2.0]), euler_deg=np.array([[0, 0, 179.0], [0, 0, -179.0], [0, 0, 10.0]])
    )
    # nearest sample, never an interpolation through 0° across the ±180° wrap
    assert _heading_at(SimpleNamespace(reference=ref), 0.6) == -179.0
    assert _heading_at(SimpleNamespace(reference=None), 0.6) is None
    assert _heading_at(SimpleNamespace(reference=SimpleNamespace(t=ref.t, euler_deg=None)), 0.6) is None


def test_plan_family_is_the_rule_the_cli_and_the_page_share(shared_data: Path) -> None:
    """VTOL items or a fixed-wing plan fly as a plane; anything else as an ArduCopter."""
    from uasnav.io.plans import read_plan

    dalby = read_plan(shared_data / "missions" / "ardupilot_autotest_dalby_obc2016.waypoints")
    assert any(it.command in (84, 85) for it in dalby.items)
    assert ap.plan_family(dalby) == "plane"
    copter = MissionPlan(items=(MissionItem(22, 3, alt_m=10.0),), home=HomePosition(47.0, 8.0, 400.0))
    assert ap.plan_family(copter) == "arducopter"
    assert ap.plan_family(dataclasses.replace(copter, vehicle_type=1)) == "plane"
    vtol_land = MissionItem(85, 3, lat_deg=47.0, lon_deg=8.0, alt_m=0.0)
    assert ap.plan_family(dataclasses.replace(copter, items=(*copter.items, vtol_land))) == "plane"
