"""3D routes: element kinds and climb rate, the vertical closed form, the 3D simulator's truth,
and operational intents that contain the simulated 3D flight (take-off, sloped legs, holds,
landing) — with checks that the containment can fail."""

from __future__ import annotations

from datetime import datetime, timezone

import numpy as np
import pymap3d
import pytest
import shapely
from scipy.stats import binom

from uasnav.errors import InputError
from uasnav.io.mission_plan import HomePosition, MissionItem, MissionPlan, route_points
from uasnav.trajectory.calibration import calibrate, covered, simulated_route_runs
from uasnav.trajectory.route3d import ELEMENT_KINDS, Route3D, predict_route, vertical_time
from uasnav.trajectory.route_sim import _vertical, simulate_route
from uasnav.trajectory.simulator import VerticalLimits, phantom4_plans, simulate_flight
from uasnav.trajectory.timebounds import TimeBounds
from uasnav.utm.intent import build_intent

T0 = datetime(2026, 11, 24, 12, 0, tzinfo=timezone.utc)
HOME = (47.0, 8.0, 400.0)
N = 47.0  # geoid height, m


@pytest.fixture(scope="module")
def model():
    """The default (kinematic) model, calibrated on 40 simulated 3D runs."""
    from uasnav.experiments.trajectory import run_phantom4
    from uasnav.trajectory.models import DEFAULT_METHOD, make_predictor

    m = make_predictor(DEFAULT_METHOD).fit(run_phantom4(n_flights=4, n_train=3).train)
    m.time_bounds_ = calibrate(simulated_route_runs(m, 40, seed=21))
    return m


def test_vertical_time_closed_form_and_simulated_move():
    # trapezoid: 50 m at 2.5 m/s, 1 m/s² → 50/2.5 + 2.5 s; triangle: 2 m < v²/a → 2·√(2/1)
    np.testing.assert_allclose(vertical_time([50.0, -2.0], 2.5, 1.0), [22.5, 2 * np.sqrt(2.0)])
    with pytest.raises(InputError, match="> 0"):
        vertical_time(1.0, 0.0, 1.0)
    # the simulator's vertical move (acceleration-limited command, 0.3 s velocity loop) takes
    # the closed-form time plus about one loop time constant
    for dz, v in ((50.0, 2.5), (-30.0, 1.5)):
        t, z = _vertical(0.0, dz, VerticalLimits(), 1.0, 0.02, 5)
        assert z[-1] == dz
        assert 0.0 < t[-1] - float(vertical_time(dz, v, 1.0)) < 1.5


def _route() -> Route3D:
    ne = np.array([[0, 0], [0, 0], [100, 0], [100, 80], [0, 80], [0, 80]], dtype=float)
    alt = np.array([0, 30, 30, 50, 50, 0.0])
    hold = np.array([0, 0, 10, 0, 5, 0.0])
    return Route3D(ne, alt, hold, np.array([np.nan, np.nan, np.nan, 5.0, np.nan, np.nan]))


def test_route_elements_kinds_climb_rate_and_times(model):
    r = _route()
    p = predict_route(model, r, np.zeros(2), 3.33)
    el = p.elements
    assert set(el.kind) == set(ELEMENT_KINDS)
    # take-off and landing: the vertical closed form with the model's limits
    assert el.kind[0] == "climb" and el.time_s[0] == pytest.approx(float(vertical_time(30, 2.5, 1.0)))
    assert el.kind[-1] == "descent" and el.time_s[-1] == pytest.approx(float(vertical_time(50, 1.5, 1.0)))
    # hovers last their hold time; arrival + hold = departure
    np.testing.assert_allclose(el.time_s[el.kind == "hover"], [10.0, 5.0])
    np.testing.assert_allclose(p.t_depart_s - p.t_arrive_s, r.hold_s)
    # the sloped leg (20 m up over 80 m at 5 m/s) is capped by the climb limit: the climb-rate
    # feature never exceeds 2.5 m/s, and the leg lasts at least the vertical move
    sloped = (el.segment == 2) & (el.kind != "hover")
    assert np.all(el.climb_rate_ms[sloped] <= 2.5 + 1e-9) and np.all(el.climb_rate_ms[sloped] > 0)
    assert el.time_s[sloped].sum() >= float(vertical_time(20, 2.5, 1.0)) - 1e-9
    assert el.dz_m[sloped].sum() == pytest.approx(20.0)
    # element times add up to the ETA
    assert el.time_s.sum() == pytest.approx(p.eta_s)
    # the LVQ model times the same route's horizontal stretches with its own network
    from uasnav.experiments.trajectory import run_phantom4

    q = predict_route(run_phantom4(n_flights=4, n_train=3).predictor, r, np.zeros(2), 3.33)
    assert set(q.elements.kind) == set(ELEMENT_KINDS) and q.eta_s == pytest.approx(p.eta_s, rel=0.1)


def test_bad_routes():
    with pytest.raises(InputError, match="at least 2 points"):
        Route3D.flat(np.zeros((1, 2)))
    ok = _route()
    with pytest.raises(InputError, match="hold times"):
        Route3D(ok.ne, ok.alt_m, -ok.hold_s - 1, ok.speed_ms)
    with pytest.raises(InputError, match="speeds"):
        Route3D(ok.ne, ok.alt_m, ok.hold_s, np.zeros(len(ok)))
    with pytest.raises(InputError, match="shape"):
        Route3D(ok.ne, ok.alt_m[:2], ok.hold_s, ok.speed_ms)


def test_simulator_altitude_channel():
    plan = phantom4_plans()["A"]
    flat = simulate_flight(plan, seed=3)
    # a level flight with an altitude profile is the 2D flight (no extra random draws)
    level = simulate_flight(plan, seed=3, alt_m=np.full(plan.shape[0], 12.0))
    np.testing.assert_array_equal(level.pos_ne, flat.pos_ne)
    np.testing.assert_allclose(level.alt_m, 12.0)
    # a steep climb: the vertical speed stays within the limit and the altitude is reached
    alt = np.array([10.0, 10.0, 40.0, 40.0, 10.0])
    vl = VerticalLimits(climb_ms=1.0, descent_ms=0.8)
    up = simulate_flight(plan, seed=3, alt_m=alt, vertical=vl)
    assert up.vz_ms.max() <= 1.0 + 1e-9 and up.vz_ms.min() >= -0.8 - 1e-9
    assert abs(up.alt_m[-1] - 10.0) < 0.1 and up.alt_m.max() == pytest.approx(40.0, abs=0.5)
    # the 30 m climb at ≤ 1 m/s makes that leg (45 m) slower than the level flight
    assert up.t[-1] > flat.t[-1] + 10.0


def _mission(rng: np.random.Generator) -> MissionPlan:
    """Take-off, 2–4 waypoints (legs 40–150 m, altitude changes ±20 m, some holds), land."""
    h = float(rng.uniform(20, 60))
    items = [MissionItem(command=22, frame=3, alt_m=h)]
    e = n = 0.0
    heading = rng.uniform(0, 2 * np.pi)
    for _ in range(int(rng.integers(2, 5))):
        d = rng.uniform(40, 150)
        e, n = e + d * np.sin(heading), n + d * np.cos(heading)
        heading += np.radians(rng.uniform(-150, 150))
        h = float(np.clip(h + rng.uniform(-20, 20), 15, 90))
        lat, lon, _ = pymap3d.enu2geodetic(e, n, 0.0, HOME[0], HOME[1], 0.0)
        hold = float(rng.choice([0.0, 0.0, rng.uniform(3, 15)]))
        if rng.random() < 0.3:  # DO_CHANGE_SPEED before this waypoint
            items.append(MissionItem(178, 2, params=(1.0, float(rng.uniform(2.0, 6.0)), -1.0, 0.0)))
        items.append(
            MissionItem(16, 3, params=(hold, 0, 0, 0), lat_deg=float(lat), lon_deg=float(lon), alt_m=h)
        )
    items.append(MissionItem(command=21, frame=3, lat_deg=items[-1].lat_deg, lon_deg=items[-1].lon_deg))
    return MissionPlan(items=tuple(items), home=HomePosition(*HOME), source="random 3D mission")


def _truth_route(plan: MissionPlan, b) -> Route3D:
    """The route the vehicle flies: the plan's points, holds and speeds (a DO_CHANGE_SPEED holds
    from the leg into the next point on)."""
    pts = route_points(plan)
    speeds, v = [], np.nan
    for i, p in enumerate(pts):
        v = p.speed_ms if p.speed_ms is not None and i > 0 else v
        speeds.append(v)
    return Route3D(b.route_en[:, ::-1], b.route_alt_w84, np.array([p.hold_s for p in pts]), np.array(speeds))


def _contained(b, t: np.ndarray, ne: np.ndarray, alt: np.ndarray) -> bool:
    polys = [shapely.Polygon(o) for o in b.volume_outline_en]
    live = [(lo, hi, za, zb) for (lo, hi), (za, zb) in zip(b.volume_time_s, b.volume_alt_w84, strict=True)]
    for ti, p, z in zip(t, ne[:, ::-1], alt, strict=True):
        pt = shapely.Point(p)
        if not any(
            lo <= ti <= hi and za <= z <= zb and poly.covers(pt)
            for poly, (lo, hi, za, zb) in zip(polys, live, strict=True)
        ):
            return False
    return True


def test_intent_contains_the_simulated_3d_flight(model):
    rng = np.random.default_rng(5)
    n_runs, k = 60, 0
    err = []
    n_speed = 0
    for i in range(n_runs):
        plan = _mission(rng)
        b = build_intent(plan, model, np.zeros(2), T0, geoid_height_m=N)
        route = _truth_route(plan, b)
        n_speed += bool(np.isfinite(route.speed_ms).any())
        tr = simulate_route(route, seed=100 + i, dt=0.05, rate_hz=5.0)
        k += _contained(b, tr.t, tr.pos_ne, tr.alt_m)
        err.append(abs(tr.t_reached_s[-1] - b.t_arrive_s[-1]) / tr.t_reached_s[-1])
    # calibrated at 95 %: 60 runs consistent with ≥ 95 % (1 % binomial test)
    assert binom.cdf(k, n_runs, 0.95) > 0.01, f"{k}/{n_runs} simulated 3D flights contained"
    print(
        f"3D containment {k}/{n_runs}, median ETA error {100 * np.median(err):.2f} %, {n_speed} speed changes"
    )
    assert n_speed >= 10  # the missions exercise DO_CHANGE_SPEED
    assert np.median(err) < 0.06  # the 3D prediction itself: median mission-time error
    # the check can fail: with near-zero bounds a plan flown much faster than predicted...
    plan = _mission(np.random.default_rng(1))
    keep, model.time_bounds_ = model.time_bounds_, TimeBounds(np.zeros(3) + 1e-6, tau_s=0.0)
    try:
        fast = build_intent(
            plan, model, np.zeros(2), T0, geoid_height_m=N, coverage=0.5, cruise_ms=3 * model.cruise_ms_
        )
        # ...and climbs predicted four times faster than the vehicle climbs
        quick = build_intent(
            plan, model, np.zeros(2), T0, geoid_height_m=N, coverage=0.5, climb_ms=10.0, descent_ms=6.0
        )
    finally:
        model.time_bounds_ = keep
    b = build_intent(plan, model, np.zeros(2), T0, geoid_height_m=N)
    tr = simulate_route(_truth_route(plan, b), seed=7, dt=0.05, rate_hz=5.0)
    assert _contained(b, tr.t, tr.pos_ne, tr.alt_m)
    assert not _contained(fast, tr.t, tr.pos_ne, tr.alt_m)
    assert not _contained(quick, tr.t, tr.pos_ne, tr.alt_m)
    # and the vertical check does not pass blindly: the flight 30 m higher is outside
    assert not _contained(b, tr.t, tr.pos_ne, tr.alt_m + 30.0)


def test_3d_time_bounds_cover_held_out_3d_runs(model):
    test = simulated_route_runs(model, 40, seed=22)
    # every run has every element kind's truth: vertical moves end at the reached altitude
    # (truth within a few seconds of the closed form), a hover ends its hold after the vehicle
    # reached the point
    r = next(x for x in test if "hover" in set(x.prediction.elements.kind))
    el = r.prediction.elements
    assert {"climb", "descent", "leg", "hover"} <= set(el.kind)
    dt_true = np.diff(r.t_true_s)
    hov = el.kind == "hover"
    at = el.segment[hov]
    np.testing.assert_allclose(r.t_true_s[1:][hov], r.truth.t_reached_s[at] + r.route.hold_s[at])
    vert = np.isin(el.kind, ["climb", "descent"])
    assert np.all(np.abs(dt_true[vert] - el.time_s[vert]) < 3.0)
    k = sum(covered(model.time_bounds_, x, 0.95) for x in test)
    assert binom.cdf(k, 40, 0.95) > 0.01, f"{k}/40 held-out 3D runs covered"
    # and coverage can fail: bounds of (almost) zero width cover no run
    assert sum(covered(TimeBounds(np.zeros(3) + 1e-6, tau_s=0.0), x, 0.5) for x in test) == 0


def test_measured_climb_rate_and_element_table_columns():
    import pyarrow as pa

    from uasnav.trajectory.element_table import ELEMENT_SCHEMA, from_table, to_rows
    from uasnav.trajectory.samples import measure_elements

    # a straight 200 m leg climbing 20 m: the simulated truth climbs 0.1 m per metre flown
    plan = np.array([[0.0, 0.0], [200.0, 0.0]])
    tel = simulate_flight(plan, seed=4, alt_m=np.array([10.0, 30.0]))
    _, s = measure_elements(plan, tel.t, tel.pos_ne, tel.vel_ne, np.zeros(2), 3.33, alt_m=tel.alt_m)
    speed = s.length_m / s.t_real_s
    inner = slice(2, -2)  # away from the ends, where the altitude loop lags the ramp
    np.testing.assert_allclose(s.climb_rate_ms[inner], 0.1 * speed[inner], rtol=0.1)
    with pytest.raises(InputError, match="altitude shape"):
        measure_elements(plan, tel.t, tel.pos_ne, tel.vel_ne, np.zeros(2), 3.33, alt_m=tel.alt_m[:-1])
    # the element table carries the kind and the climb rate, and reads back exactly
    table = pa.Table.from_pylist(to_rows(s, 10.0), schema=ELEMENT_SCHEMA)
    assert set(table.column("element_kind").to_pylist()) == {"leg"}
    back, _ = from_table(table)
    np.testing.assert_array_equal(back.climb_rate_ms, s.climb_rate_ms)
    # corners are turns; a flight without altitude has NaN climb rates
    tel2 = simulate_flight(phantom4_plans()["A"], seed=4)
    _, s2 = measure_elements(tel2.plan_ne, tel2.t, tel2.pos_ne, tel2.vel_ne, np.zeros(2), 3.33)
    rows = to_rows(s2, 10.0)
    assert {r["element_kind"] for r in rows} == {"leg", "turn"} and all(
        np.isnan(r["climb_rate_ms"]) for r in rows
    )
    # tables written before the two columns existed still read
    old = table.drop_columns(["element_kind", "climb_rate_ms"])
    assert from_table(old)[0].climb_rate_ms is None


def test_cli_predict_route_matches_the_intent(model, shared_data, tmp_path):
    import json

    from click.testing import CliRunner

    from uasnav.cli import main

    mpath = tmp_path / "m.json"
    model.save(mpath)
    plan = str(shared_data / "missions" / "mavsdk_qgroundcontrol_sample.plan")
    base = ["trajectory", "predict", "--model", str(mpath), "--plan", plan, "--wind", "3@45", "--route"]
    r = CliRunner().invoke(main, [*base, "--json"])
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    kinds = [e["kind"] for e in out["elements"]]
    assert out["method"] == "kinematic" and kinds[0] == "climb" and kinds[-1] == "descent" and "leg" in kinds
    assert out["elements"][0]["climb_rate_ms"] == pytest.approx(50 / (50 / 2.5 + 2.5))
    assert sum(e["time_s"] for e in out["elements"]) == pytest.approx(out["eta_s"])
    # the same route timing as the operational intent's
    i = CliRunner().invoke(
        main,
        ["trajectory", "intent", "--model", str(mpath), "--plan", plan, "--wind", "3@45", "--start",
         "2026-11-24T12:00:00Z", "--geoid-height", "47.4", "--out", str(tmp_path / "i.json"), "--json"],
    )  # fmt: skip
    assert i.exit_code == 0, i.output
    intent = json.loads(i.stdout)
    assert intent["eta_s"] == pytest.approx(out["eta_s"])
    np.testing.assert_allclose(intent["waypoint_times_s"], out["arrive_s"])
    text = CliRunner().invoke(main, base)
    assert text.exit_code == 0 and "climb" in text.output and "ETA" in text.output
    bad = CliRunner().invoke(main, [*base, "--required", "0,1"])
    assert bad.exit_code == 2 and "--required" in bad.output
    # a local (north/east) plan has no geodetic route
    csv = tmp_path / "p.csv"
    csv.write_text("north,east\n0,0\n100,0\n")
    r = CliRunner().invoke(
        main, ["trajectory", "predict", "--model", str(mpath), "--plan", str(csv), "--wind", "0@0", "--route"]
    )
    assert r.exit_code == 1 and "no geodetic route" in r.output


def test_route_from_plan_frames_and_refusals():
    from uasnav.trajectory.route3d import route_from_plan

    def wp(n: float, alt: float, frame: int = 3, cmd: int = 16, hold: float = 0.0) -> MissionItem:
        lat, lon, _ = pymap3d.enu2geodetic(0.0, n, 0.0, HOME[0], HOME[1], 0.0)
        return MissionItem(
            cmd, frame, params=(hold, 0, 0, 0), lat_deg=float(lat), lon_deg=float(lon), alt_m=alt
        )

    # relative 30 m then AMSL 450 m at a home 400 m AMSL: a 20 m climb on the second leg
    mixed = MissionPlan(items=(wp(0, 30.0), wp(100, 450.0, frame=0)), home=HomePosition(*HOME), source="m")
    r = route_from_plan(mixed)
    np.testing.assert_allclose(r.alt_m, [430.0, 450.0])
    np.testing.assert_allclose(r.ne[-1], [100.0, 0.0], atol=0.01)
    with pytest.raises(InputError, match="mixed and no home altitude"):
        route_from_plan(MissionPlan(items=mixed.items, home=None, source="m"))
    with pytest.raises(InputError, match="terrain"):
        route_from_plan(MissionPlan(items=(wp(0, 30.0, frame=10), wp(100, 30.0, frame=10)), source="t"))
    with pytest.raises(InputError, match="unlimited loiter"):
        route_from_plan(MissionPlan(items=(wp(0, 30.0), wp(100, 30.0, cmd=17)), source="l"))


def _slow_vertical_model(**limits):
    """A kinematic model with its own vertical limits (as a log gives them), time bounds set."""
    from uasnav.experiments.trajectory import run_phantom4
    from uasnav.trajectory.kinematic import KinematicPredictor

    m = KinematicPredictor(**limits).fit(run_phantom4(n_flights=2, n_train=1).train)
    m.time_bounds_ = TimeBounds(np.full(20, 0.05), tau_s=5.0)
    return m


def test_intent_and_cli_route_use_the_models_vertical_limits(shared_data, tmp_path):
    import json

    from click.testing import CliRunner

    from uasnav.cli import main
    from uasnav.io.plans import read_plan

    plan_path = shared_data / "missions" / "mavsdk_qgroundcontrol_sample.plan"
    plan = read_plan(plan_path)
    model = _slow_vertical_model(climb_ms=1.0, descent_ms=0.5, accel_z_ms2=0.5)
    b = build_intent(plan, model, np.zeros(2), T0, geoid_height_m=N)
    el = b.route_prediction.elements
    up, down = el.kind == "climb", el.kind == "descent"
    assert up.sum() == 1 and down.sum() == 1
    # the closed form with the model's limits: |Δz|/v + v/a (take-off 50 m: 50/1 + 1/0.5 = 52 s)
    want_up = float(vertical_time(el.dz_m[up][0], 1.0, 0.5))
    want_down = float(vertical_time(el.dz_m[down][0], 0.5, 0.5))
    assert el.dz_m[up][0] == pytest.approx(50.0) and want_up == pytest.approx(52.0)
    np.testing.assert_allclose([el.time_s[up][0], el.time_s[down][0]], [want_up, want_down])
    assert b.t_arrive_s[1] == pytest.approx(want_up)
    # `trajectory predict --route` times the same route the same way
    mpath = tmp_path / "m.json"
    model.save(mpath)
    r = CliRunner().invoke(
        main,
        ["trajectory", "predict", "--model", str(mpath), "--plan", str(plan_path), "--wind", "0@0",
         "--route", "--json"],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    rows = json.loads(r.stdout)["elements"]
    t_cli = {e["kind"]: e["time_s"] for e in rows if e["kind"] in ("climb", "descent")}
    assert t_cli == pytest.approx({"climb": want_up, "descent": want_down})
    # explicit limits still win, in the API and the CLI
    fast = build_intent(plan, model, np.zeros(2), T0, geoid_height_m=N, climb_ms=2.0, accel_z_ms2=2.0)
    assert fast.t_arrive_s[1] == pytest.approx(float(vertical_time(50.0, 2.0, 2.0)))
    base = ["trajectory", "intent", "--model", str(mpath), "--plan", str(plan_path), "--wind", "0@0",
            "--start", "2026-11-24T12:00:00Z", "--geoid-height", "47.4", "--out", str(tmp_path / "i.json"),
            "--json"]  # fmt: skip
    i = CliRunner().invoke(main, base)
    assert i.exit_code == 0, i.output
    s = json.loads(i.stdout)
    assert (s["climb_ms"], s["descent_ms"], s["accel_z_ms2"]) == (1.0, 0.5, 0.5)
    assert s["elements"]["climb"]["time_s"] == pytest.approx(want_up)
    # --limits-from: the log's vertical speeds and acceleration (PX4 MPC_Z_VEL_MAX_UP/DN,
    # MPC_ACC_UP_MAX = 4 m/s²) replace the model's; an explicit --climb-rate beats the log
    from uasnav.io.autopilot_limits import read_autopilot_limits

    ulg = shared_data / "logs" / "px4_sample_log_small.ulg"
    lim = read_autopilot_limits(ulg)
    i = CliRunner().invoke(main, [*base, "--limits-from", str(ulg), "--climb-rate", "3"])
    assert i.exit_code == 0, i.output
    s = json.loads(i.stdout)
    assert (s["climb_ms"], s["descent_ms"], s["accel_z_ms2"]) == (3.0, lim.descent_ms, 4.0)
    assert {"descent_ms", "accel_z_ms2"} <= set(s["limits_from_log"]) and "climb_ms" not in s[
        "limits_from_log"
    ]
    assert s["elements"]["climb"]["time_s"] == pytest.approx(float(vertical_time(50.0, 3.0, 4.0)))


def test_speed_changes_fly_each_leg_at_its_own_speed():
    from uasnav.experiments.trajectory import run_phantom4
    from uasnav.trajectory.kinematic import KinematicPredictor
    from uasnav.trajectory.simulator import MultirotorParams, WindModel

    # a = 1.2 m/s²: between the simulator's tilt-limited acceleration and its 0.8 m/s² braking
    a = 1.2
    model = KinematicPredictor(accel_ms2=a).fit(run_phantom4(n_flights=2, n_train=1).train)
    calm = WindModel(speed_ms=0.0, gust_sigma_ms=0.0, flight_speed_sigma_ms=0.0)
    line = np.array([[0.0, 0.0], [200.0, 0.0]])
    for v in (2.0, 5.0, 10.0):
        # a 200 m leg from rest to rest after DO_CHANGE_SPEED v, predicted with a default of 5 m/s
        r = Route3D(line, np.zeros(2), np.zeros(2), np.array([np.nan, v]))
        t = predict_route(model, r, np.zeros(2), 5.0).eta_s
        assert t == pytest.approx(200.0 / v + v / a, rel=1e-3)  # closed form L/V + V/a
        sim = np.median(
            [simulate_route(r, params=MultirotorParams(cruise_ms=5.0), wind=calm, seed=s).t_reached_s[-1]
             for s in range(3)]
        )  # fmt: skip
        # (scaling the 5 m/s time by 5/v, as before, was 19 % short at 10 m/s, 10 % long at 2 m/s)
        assert abs(t - sim) / sim < 0.06, (v, t, sim)
    # two straight legs, 200 m at 10 m/s then 200 m at 2 m/s (a = 1 m/s²): accelerate 10 s
    # (50 m), cruise 102 m (10.2 s), brake to 2 m/s at the change 8 s (48 m), cruise 198 m
    # (99 s), brake 2 s (2 m) = 129.2 s
    m1 = KinematicPredictor(accel_ms2=1.0).fit(run_phantom4(n_flights=2, n_train=1).train)
    two = Route3D(
        np.array([[0.0, 0], [200, 0], [400, 0]]), np.zeros(3), np.zeros(3), np.array([np.nan, 10, 2])
    )
    p = predict_route(m1, two, np.zeros(2), 5.0)
    assert p.eta_s == pytest.approx(129.2, rel=1e-3)
    # (the waypoint time is interpolated inside the 10 m element that holds it: ≈ 1 s here)
    assert p.t_arrive_s[1] == pytest.approx(10 + 10.2 + 8, abs=1.5)
    # the LVQ keeps its documented approximation: its times scaled by cruise ÷ leg speed
    from uasnav.trajectory.predictor import TrajectoryPredictor

    lvq = TrajectoryPredictor(random_state=0).fit(run_phantom4(n_flights=2, n_train=1).train)
    slow = Route3D(line, np.zeros(2), np.zeros(2), np.array([np.nan, 2.5]))
    base = predict_route(lvq, Route3D.flat(line), np.zeros(2), 5.0).eta_s
    assert predict_route(lvq, slow, np.zeros(2), 5.0).eta_s == pytest.approx(2.0 * base)


def test_amsl_plan_without_home_names_what_is_missing(model, tmp_path):
    """An all-AMSL plan with a take-off and a landing: the ground points the route adds are
    relative to home, so without a home altitude the take-off height is unknown — refused
    naming that, and timed once the home altitude is given (API and ``predict --route
    --home-alt``)."""
    import json

    from click.testing import CliRunner

    from uasnav.cli import main
    from uasnav.io.plans import read_plan, write_plan
    from uasnav.trajectory.route3d import route_from_plan

    def item(n: float, cmd: int) -> MissionItem:
        lat, lon, _ = pymap3d.enu2geodetic(0.0, n, 0.0, HOME[0], HOME[1], 0.0)
        return MissionItem(cmd, 0, params=(0.0,) * 4, lat_deg=float(lat), lon_deg=float(lon), alt_m=450.0)

    path = tmp_path / "amsl.waypoints"
    write_plan(MissionPlan(items=(item(0, 22), item(100, 16), item(200, 21)), source="a"), path)
    plan = read_plan(path)
    assert plan.home is None
    with pytest.raises(
        InputError, match=r"altitudes are AMSL but its take-off/landing on the ground is relative"
    ):
        route_from_plan(plan)
    r = route_from_plan(plan, home_amsl_m=400.0)
    np.testing.assert_allclose(r.alt_m[[0, 1, -1]], [400.0, 450.0, 400.0])
    mpath = tmp_path / "m.json"
    model.save(mpath)
    base = ["trajectory", "predict", "--model", str(mpath), "--plan", str(path), "--wind", "0@0", "--route"]
    bad = CliRunner().invoke(main, base)
    assert bad.exit_code == 1 and "take-off/landing on the ground is relative to home" in bad.output
    assert "mixed" not in bad.output
    ok = CliRunner().invoke(main, [*base, "--home-alt", "400", "--json"])
    assert ok.exit_code == 0, ok.output
    el = json.loads(ok.stdout)["elements"]
    assert el[0]["kind"] == "climb" and el[0]["dz_m"] == pytest.approx(50.0)
    assert el[-1]["kind"] == "descent" and el[-1]["dz_m"] == pytest.approx(-50.0)
    # --home-alt belongs to the 3D route
    misuse = CliRunner().invoke(main, base[:-1] + ["--home-alt", "400"])
    assert misuse.exit_code == 2 and "--route" in misuse.output
