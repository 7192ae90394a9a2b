"""Calibrated time bounds (split-conformal) and operational intents that contain the true
trajectory, on simulated runs with ground truth."""

from __future__ import annotations

import json
from datetime import datetime, timedelta, timezone

import numpy as np
import pymap3d
import pytest
import shapely
from click.testing import CliRunner
from scipy.stats import binom, binomtest

from uasnav.cli import main
from uasnav.errors import InputError
from uasnav.io.mission_plan import HomePosition, MissionItem, MissionPlan
from uasnav.io.operational_intent import read_intents
from uasnav.trajectory.calibration import calibrate, covered, simulated_runs
from uasnav.trajectory.predictor import TrajectoryPredictor
from uasnav.trajectory.timebounds import TimeBounds, clopper_pearson
from uasnav.utm.intent import build_intent

T0 = datetime(2026, 11, 24, 12, 0, tzinfo=timezone.utc)
N_CAL, N_TEST, COVERAGE = 40, 30, 0.95


@pytest.fixture(scope="module")
def model() -> TrajectoryPredictor:
    from uasnav.experiments.trajectory import run_phantom4

    return run_phantom4(n_flights=6, n_train=4).predictor


def run_phantom4_train():
    from uasnav.experiments.trajectory import run_phantom4

    return run_phantom4(n_flights=4, n_train=3).train


@pytest.fixture(scope="module")
def runs(model):
    cal = simulated_runs(model, N_CAL, seed=11)
    test = simulated_runs(model, N_TEST, seed=12)
    model.time_bounds_ = calibrate(cal)
    return cal, test


def _consistent_with(k: int, n: int, p: float) -> bool:
    """k successes of n are not significantly (1 %) fewer than a rate p would give."""
    return binom.cdf(k, n, p) > 0.01


def test_conformal_quantile_by_hand():
    b = TimeBounds(np.array([0.5, 0.1, 0.3, 0.2]), tau_s=0.0)
    # n = 4, coverage 0.6: k = ceil(5·0.6) = 3 → the third smallest score
    assert b.quantile(0.6) == 0.3
    assert b.quantile(0.8) == 0.5  # k = ceil(5·0.8) = 4 ≤ n
    with pytest.raises(InputError, match="needs at least 5 calibration runs"):
        b.quantile(0.81)  # k = ceil(4.05) = 5 > n
    lo, hi = b.band(np.array([10.0]), 0.0, 0.6)
    assert (lo[0], hi[0]) == pytest.approx((7.0, 13.0))


def test_clopper_pearson_matches_scipy():
    for k, n in ((0, 10), (7, 10), (10, 10), (190, 200)):
        ci = binomtest(k, n).proportion_ci(0.95, method="exact")
        assert clopper_pearson(k, n) == pytest.approx((ci.low, ci.high), abs=1e-9)


def test_coverage_on_held_out_simulated_runs(model, runs):
    """Split-conformal: held-out runs drawn like the calibration runs are covered (every element
    boundary at once) at least at the nominal rate; a narrower band covers fewer."""
    _, test = runs
    k = sum(covered(model.time_bounds_, r, COVERAGE) for r in test)
    assert _consistent_with(k, N_TEST, COVERAGE), f"{k}/{N_TEST} covered"
    k50 = sum(covered(model.time_bounds_, r, 0.5) for r in test)
    assert k50 < k and _consistent_with(k50, N_TEST, 0.5)
    assert not _consistent_with(k50, N_TEST, 0.99)  # the test can tell a too-narrow band


def test_model_file_keeps_the_bounds(model, runs, tmp_path):
    model.save(tmp_path / "m.json")
    back = TrajectoryPredictor.load(tmp_path / "m.json")
    np.testing.assert_array_equal(back.time_bounds_.scores, model.time_bounds_.scores)
    d = json.loads((tmp_path / "m.json").read_text())
    d["time_bounds"]["scores"][0] = -1.0
    (tmp_path / "bad.json").write_text(json.dumps(d))
    with pytest.raises(InputError, match=r"time_bounds\.scores\[0\]"):
        TrajectoryPredictor.load(tmp_path / "bad.json")


def _geodetic_plan(plan_ne: np.ndarray, alt_rel: float = 30.0) -> MissionPlan:
    lat, lon, _ = pymap3d.enu2geodetic(plan_ne[:, 1], plan_ne[:, 0], 0.0, 47.0, 8.0, 0.0)
    items = tuple(
        MissionItem(command=16, frame=3, lat_deg=float(a), lon_deg=float(b), alt_m=alt_rel)
        for a, b in zip(lat, lon, strict=True)
    )
    return MissionPlan(items=items, home=HomePosition(47.0, 8.0, 400.0), source="sim")


def _contained(b, run, alt_w84: float) -> bool:
    """Every truth sample inside a volume alive at that time (outline, altitude, time)."""
    polys = [shapely.Polygon(o) for o in b.volume_outline_en]
    en = run.telemetry.pos_ne[:, ::-1]
    for t, p in zip(run.telemetry.t, en, strict=True):
        pt = shapely.Point(p)
        ok = any(
            lo <= t <= hi and za <= alt_w84 <= zb and poly.covers(pt)
            for poly, (lo, hi), (za, zb) in zip(polys, b.volume_time_s, b.volume_alt_w84, strict=True)
        )
        if not ok:
            return False
    return True


def test_intent_contains_the_true_trajectory(model, runs):
    _, test = runs
    k = 0
    for r in test:
        plan = _geodetic_plan(r.plan_ne)
        b = build_intent(plan, model, r.wind_ne, T0, geoid_height_m=47.0, cruise_ms=model.cruise_ms_)
        # the intent's local frame is the plan's first point: the simulator's origin
        np.testing.assert_allclose(b.route_en[:, ::-1], r.plan_ne, atol=1e-3)
        assert b.volume_alt_w84.min() <= 477.0 <= b.volume_alt_w84.max()
        k += _contained(b, r, 400.0 + 30.0 + 47.0)
    assert _consistent_with(k, N_TEST, COVERAGE), f"{k}/{N_TEST} runs contained"
    # and the check can fail: a prediction three times too fast without the bounds' width
    r = test[0]
    narrow = TimeBounds(np.zeros(3) + 1e-6, tau_s=0.0)
    keep, model.time_bounds_ = model.time_bounds_, narrow
    try:
        plan = _geodetic_plan(r.plan_ne)
        b = build_intent(
            plan, model, r.wind_ne, T0, geoid_height_m=47.0, coverage=0.5, cruise_ms=3 * model.cruise_ms_
        )
    finally:
        model.time_bounds_ = keep
    assert not _contained(b, r, 477.0)
    # nor does the vertical check pass blindly: the truth 100 m higher is outside
    b = build_intent(
        _geodetic_plan(r.plan_ne), model, r.wind_ne, T0, geoid_height_m=47.0, cruise_ms=model.cruise_ms_
    )
    assert not _contained(b, r, 577.0)


def test_intent_altitudes_and_refusals(model, runs, shared_data, monkeypatch):
    from uasnav.io.plans import read_plan

    plan = read_plan(shared_data / "missions" / "mavsdk_qgroundcontrol_sample.plan")
    b = build_intent(plan, model, np.zeros(2), T0, geoid_height_m=47.4)
    home = 488.93101752001763
    # W84 = AMSL + N: relative 0 (ground) and 50 m ± the 10 m vertical buffer
    assert b.volume_alt_w84.min() == pytest.approx(home + 47.4 - 10)
    assert b.volume_alt_w84.max() == pytest.approx(home + 50 + 47.4 + 10)
    # take-off at 2.5 m/s with 1 m/s² (trapezoid): 50 m in 50/2.5 + 2.5/1 s; the landing
    # descends 50 m at 1.5 m/s in 50/1.5 + 1.5/1 s
    assert b.t_arrive_s[1] == pytest.approx(50 / 2.5 + 2.5)
    assert b.t_arrive_s[-1] - b.t_arrive_s[-2] == pytest.approx(50 / 1.5 + 1.5)
    assert b.eta_bounds_s[0] < b.eta_s < b.eta_bounds_s[1]
    t0 = min(v.time_start.value.datetime for v in b.details.volumes)
    t1 = max(v.time_end.value.datetime for v in b.details.volumes)
    assert t0 == T0 and abs(t1 - (T0 + timedelta(seconds=b.eta_bounds_s[1]))) < timedelta(milliseconds=1)
    # N of the EGM96 grid when not given; refused (never N = 0) when no geoid grid is installed
    from uasnav.utm import altitude

    egm = build_intent(plan, model, np.zeros(2), T0)
    n = altitude.geoid_heights(np.array([plan.home.lat_deg]), np.array([plan.home.lon_deg]))[0]
    assert egm.volume_alt_w84.min() == pytest.approx(home + n - 10, abs=0.02)
    with monkeypatch.context() as m:
        m.setattr(altitude, "geoid_grid_path", lambda: None)
        with pytest.raises(InputError, match="never assumes N = 0"):
            build_intent(plan, model, np.zeros(2), T0)
    no_home = MissionPlan(items=plan.items, home=None, source="x")
    with pytest.raises(InputError, match="return to launch but the plan has no home"):
        build_intent(no_home, model, np.zeros(2), T0, geoid_height_m=47.4)
    terrain = MissionPlan(
        items=tuple(MissionItem(16, 10, lat_deg=47 + i * 1e-3, lon_deg=8, alt_m=20) for i in range(2)),
        source="t",
    )
    with pytest.raises(InputError, match="above terrain"):
        build_intent(terrain, model, np.zeros(2), T0, geoid_height_m=47.4)
    loiter = MissionPlan(
        items=(*terrain.items[:1], MissionItem(17, 3, lat_deg=47.01, lon_deg=8, alt_m=20)), source="l"
    )
    with pytest.raises(InputError, match="unlimited loiter"):
        build_intent(loiter, model, np.zeros(2), T0, geoid_height_m=47.4)


def test_cli_intent_then_deconflict(model, runs, shared_data, tmp_path):
    mpath = tmp_path / "m.json"
    model.save(mpath)
    plan = shared_data / "missions" / "mavsdk_qgroundcontrol_sample.plan"
    base = ["trajectory", "intent", "--model", str(mpath), "--plan", str(plan), "--wind", "3@45"]
    r = CliRunner().invoke(
        main, [*base, "--start", "2026-11-24T12:00:00Z", "--out", str(tmp_path / "a.json"), "--json"]
    )
    # without --geoid-height: N of the EGM96 grid at each point (tests/test_geoid.py checks the grid)
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout)["geoid"].startswith("EGM96")
    egm = json.loads((tmp_path / "a.json").read_text())
    for name, start in (("a", "2026-11-24T12:00:00Z"), ("b", "2026-11-24T12:01:00Z")):
        r = CliRunner().invoke(
            main,
            [
                *base,
                "--start",
                start,
                "--geoid-height",
                "47.4",
                "--out",
                str(tmp_path / f"{name}.json"),
                "--geojson",
                str(tmp_path / f"{name}.geojson"),
                "--json",
            ],
        )
        assert r.exit_code == 0, r.output
    s = json.loads(r.stdout)
    assert s["geoid"] == "given"
    assert s["eta_bounds_s"][0] < s["eta_s"] < s["eta_bounds_s"][1] and len(s["waypoint_bounds_s"]) == len(
        s["waypoint_times_s"]
    )
    (a,) = read_intents(tmp_path / "a.json")
    assert all(v.volume.altitude_lower.reference == "W84" for v in a.details.volumes)
    from uasnav.utm.altitude import geoid_heights

    for ve, v47 in zip(egm["volumes"], a.details.volumes, strict=True):
        vol = ve["volume"]
        pts = (
            vol["outline_polygon"]["vertices"]
            if "outline_polygon" in vol
            else [vol["outline_circle"]["center"]]
        )
        n = geoid_heights(
            np.array([np.mean([p["lat"] for p in pts])]), np.array([np.mean([p["lng"] for p in pts])])
        )
        for k in ("altitude_lower", "altitude_upper"):
            assert vol[k]["value"] - v47.volume[k].value == pytest.approx(n[0] - 47.4, abs=0.02)
    gj = json.loads((tmp_path / "a.geojson").read_text())
    assert len(gj["features"]) == len(a.details.volumes) + 1
    # the same mission one minute later conflicts with itself; the delay frees it
    r = CliRunner().invoke(
        main,
        [
            "utm",
            "deconflict",
            str(tmp_path / "a.json"),
            str(tmp_path / "b.json"),
            "--now",
            "2026-11-24T11:00:00Z",
            "--json",
        ],
    )
    assert r.exit_code == 0, r.output
    (c,) = json.loads(r.output)["conflicts"]
    assert c["later"] == "b" and c["delay_s"] > 0
    # b delayed by delay_s no longer conflicts with a (and by a little less it still does)
    (bb,) = read_intents(tmp_path / "b.json")
    from uasnav.io.operational_intent import NamedIntent
    from uasnav.utm import deconflict, volume_arrays

    v = volume_arrays([a, NamedIntent("b", bb.details)])
    assert not deconflict(v.shifted(1, c["delay_s"] + 1e-3)).conflicts
    assert deconflict(v.shifted(1, c["delay_s"] - 1.0)).conflicts


def test_cli_intent_calibrates_a_model_without_bounds(model, runs, shared_data, tmp_path):
    keep, model.time_bounds_ = model.time_bounds_, None
    try:
        model.save(tmp_path / "raw.json")
    finally:
        model.time_bounds_ = keep
    assert "time_bounds" not in json.loads((tmp_path / "raw.json").read_text())
    plan = shared_data / "missions" / "mavsdk_qgroundcontrol_sample.plan"
    argv = [
        "trajectory",
        "intent",
        "--model",
        str(tmp_path / "raw.json"),
        "--plan",
        str(plan),
        "--wind",
        "0@0",
    ]
    argv += ["--start", "2026-11-24T12:00:00Z", "--geoid-height", "47.4", "--calibration-runs", "20"]
    r = CliRunner().invoke(main, [*argv, "--out", str(tmp_path / "i.json")])
    assert r.exit_code == 0, r.output
    assert len(read_intents(tmp_path / "i.json")[0].details.volumes) > 0
    # calibrate writes a model whose bounds the intent then uses as they are
    cal = [
        "trajectory",
        "calibrate",
        "--model",
        str(tmp_path / "raw.json"),
        "--out",
        str(tmp_path / "cal.json"),
    ]
    r = CliRunner().invoke(main, [*cal, "--runs", "20", "--test-runs", "5", "--json"])
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    assert out["runs"] == 20 and 0 <= out["covered"] <= 5
    assert TrajectoryPredictor.load(tmp_path / "cal.json").time_bounds_.n_runs == 20


def test_speed_change_shortens_the_following_legs(model, runs):
    """A DO_CHANGE_SPEED to twice the speed halves the predicted time of the legs after it."""
    import pymap3d

    def wp(n: float) -> MissionItem:
        lat, lon, _ = pymap3d.enu2geodetic(0.0, n, 0.0, 47.0, 8.0, 0.0)
        return MissionItem(16, 3, lat_deg=float(lat), lon_deg=float(lon), alt_m=30.0)

    legs = (wp(0), wp(100), wp(200), wp(300))
    home = HomePosition(47.0, 8.0, 400.0)
    v0 = model.cruise_ms_
    change = MissionItem(178, 2, params=(1.0, 2 * v0, -1.0, 0.0))
    plain = build_intent(MissionPlan(items=legs, home=home), model, np.zeros(2), T0, geoid_height_m=47.0)
    faster = build_intent(
        MissionPlan(items=(*legs[:2], change, *legs[2:]), home=home),
        model,
        np.zeros(2),
        T0,
        geoid_height_m=47.0,
    )
    d0, d1 = np.diff(plain.t_arrive_s), np.diff(faster.t_arrive_s)
    assert d1[0] == pytest.approx(d0[0])  # the leg before the change
    np.testing.assert_allclose(d1[1:], d0[1:] / 2)  # the legs into and after it


def test_cli_intent_limits_from_log(model, shared_data, tmp_path):
    """--limits-from: the log's WPNAV_SPEED_UP/DN (log171: 400/300 cm/s) replace the default
    climb/descent rates unless given explicitly; faster vertical limits shorten the intent."""
    mpath = tmp_path / "m.json"
    model.save(mpath)
    plan = shared_data / "missions" / "mavsdk_qgroundcontrol_sample.plan"
    base = ["trajectory", "intent", "--model", str(mpath), "--plan", str(plan), "--wind", "3@45"]
    base += ["--start", "2026-11-24T12:00:00Z", "--geoid-height", "47.4", "--json"]
    log = str(shared_data / "logs" / "ardupilot_log171.bin")

    def run(*extra):
        r = CliRunner().invoke(main, [*base, "--out", str(tmp_path / "i.json"), *extra])
        assert r.exit_code == 0, r.output
        return json.loads(r.stdout)

    default = run()
    assert (default["climb_ms"], default["descent_ms"], default["limits_from_log"]) == (2.5, 1.5, [])
    # the 3D elements by kind: the take-off climbs 50 m, the landing descends 50 m
    assert default["method"] == "lvq" and default["elements"]["leg"]["count"] > 0
    assert default["elements"]["climb"] == {"count": 1, "time_s": pytest.approx(50 / 2.5 + 2.5)}
    assert default["elements"]["descent"] == {"count": 1, "time_s": pytest.approx(50 / 1.5 + 1.5)}
    logged = run("--limits-from", log)
    assert (logged["climb_ms"], logged["descent_ms"]) == (4.0, 3.0)
    assert {"climb_ms", "descent_ms"} <= set(logged["limits_from_log"])
    assert logged["eta_s"] < default["eta_s"]
    explicit = run("--limits-from", log, "--climb-rate", "1.0")
    assert explicit["climb_ms"] == 1.0 and "climb_ms" not in explicit["limits_from_log"]
    r = CliRunner().invoke(main, [*base, "--out", str(tmp_path / "j.json"), "--limits-from", str(plan)])
    assert r.exit_code == 1 and "no autopilot parameters" in r.output
    # a kinematic model carries its vehicle's vertical limits into the intent
    from uasnav.trajectory.kinematic import KinematicPredictor

    kin = KinematicPredictor(climb_ms=1.0, descent_ms=0.5).fit(run_phantom4_train())
    kin.time_bounds_ = model.time_bounds_
    kin.save(mpath)
    k = run()
    assert (k["method"], k["climb_ms"], k["descent_ms"]) == ("kinematic", 1.0, 0.5)
    assert k["elements"]["climb"]["time_s"] == pytest.approx(50 / 1.0 + 1.0)
