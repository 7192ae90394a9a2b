"""Real telemetry: the ArduCopter tlog (mission, reached events, 1 Hz positions), PX4 ULog, CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.errors import InputError
from uasnav.io import read_flight
from uasnav.trajectory.runs import flown_runs, run_samples
from uasnav.trajectory.samples import ElementSamples

TLOG = "flights/phoenix_mission1_arducopter.tlog"


@pytest.fixture(scope="module")
def tlog(shared_data):
    return read_flight(shared_data / TLOG)


def test_tlog_mission_runs(tlog):
    assert sorted(tlog.waypoints) == [2, 3]
    assert tlog.cruise_ms == pytest.approx(5.0)  # WPNAV_SPEED 500 cm/s
    assert tlog.wind_ne is None
    runs = flown_runs(tlog)
    assert len(runs) == 5
    for r in runs:
        assert r.seqs == [2, 3]
        assert np.hypot(*np.diff(r.plan_ne, axis=0)[0]) == pytest.approx(100.5, abs=0.5)
        assert 19.0 < r.reached_t[1] - r.reached_t[0] < 23.0


def test_tlog_elements_and_leave_one_out_beats_distance_over_speed(tlog):
    from uasnav.trajectory.baselines import evaluate_methods

    _runs, samples = run_samples(tlog)
    assert [len(s) for s in samples] == [5] * 5
    # Straight middle elements are flown at about the 5 m/s waypoint speed.
    mid = np.concatenate([s.t_real_s[1:4] for s in samples])
    assert 3.4 < np.median(20.0 / mid) < 5.5
    leg_lvq, leg_ds = [], []
    for k in range(5):
        train = ElementSamples.concat([s for i, s in enumerate(samples) if i != k])
        res = {m.name: m for m in evaluate_methods(train, samples[k])}
        real = samples[k].t_real_s.sum()
        leg_lvq.append(abs(res["LVQ (thesis)"].time_s.sum() - real) / real)
        leg_ds.append(abs(res["distance ÷ speed"].time_s.sum() - real) / real)
    assert np.mean(leg_lvq) < np.mean(leg_ds)


def test_ulog_has_wind_but_no_mission(shared_data):
    log = read_flight(shared_data / "logs/px4_sample_log_small.ulg")
    assert log.wind_ne is not None and np.isfinite(log.wind_ne).all()
    with pytest.raises(InputError, match="no mission waypoints"):
        flown_runs(log)


def test_unknown_extension(tmp_path):
    p = tmp_path / "x.txt"
    p.write_text("1")
    with pytest.raises(InputError, match="unknown telemetry format"):
        read_flight(p)


def test_cli_train_predict_evaluate(shared_data, tmp_path):
    model = tmp_path / "m.json"
    r = CliRunner().invoke(main, ["trajectory", "train", str(shared_data / TLOG), "--out", str(model)])
    assert r.exit_code == 0, r.output
    assert "25 elements of 5 run(s)" in r.output
    # every limit of the kinematic default comes from the log's parameters (WPNAV_ACCEL_Z included)
    params = json.loads(model.read_text())["params"]
    assert params["accel_z_ms2"] == pytest.approx(1.0) and "accel_z_ms2" in params["limits_source"]
    assert params["limits_source"].endswith("from phoenix_mission1_arducopter.tlog")
    plan = tmp_path / "plan.csv"
    plan.write_text("north,east\n0,0\n0,40\n40,40\n")
    r = CliRunner().invoke(
        main, ["trajectory", "predict", "--model", str(model), "--plan", str(plan), "--wind", "0@0", "--json"]
    )
    assert r.exit_code == 0, r.output
    out = json.loads(r.output)
    assert out["eta_s"] == pytest.approx(sum(e["time_s"] for e in out["elements"]))
    assert len(out["waypoint_times_s"]) == 3
    # The corner was never flown in training: flagged, not silent.
    assert any(e["low_confidence"] for e in out["elements"] if e["kind"] == "corner")
    r = CliRunner().invoke(main, ["trajectory", "evaluate", str(shared_data / TLOG), "--json"])
    assert r.exit_code == 0, r.output
    ev = json.loads(r.output)
    assert ev["n_runs"] == 5 and "distance ÷ speed" in ev["methods"]
    # the kinematic models use the log's WPNAV_ACCEL (100 cm/s²), and the learned residual is
    # evaluated beside the plain point mass (issue 17 follow-up)
    assert ev["limits"] == {"accel_ms2": 1.0, "from_log": True}
    assert ev["methods"]["kinematic + residual"]["applicable"]
    assert len(ev["methods"]["kinematic + residual"]["run_e_pct"]) == 5
    # 4D feasibility: the predicted times themselves are feasible, half of them are not.
    times = ",".join(f"{x:.3f}" for x in out["waypoint_times_s"])
    half = ",".join(f"{x / 2:.3f}" for x in out["waypoint_times_s"])
    base = ["trajectory", "predict", "--model", str(model), "--plan", str(plan), "--wind", "0@0", "--json"]
    r = CliRunner().invoke(main, [*base, "--required", times, "--tolerance", "0.5"])
    assert r.exit_code == 0 and json.loads(r.output)["feasible"] is True
    r = CliRunner().invoke(main, [*base, "--required", half, "--tolerance", "0.5"])
    assert r.exit_code == 0 and json.loads(r.output)["waypoint_ok"] == [True, False, False]
    r = CliRunner().invoke(main, [*base, "--required", "0,1"])
    assert r.exit_code == 1 and "one finite required time per waypoint" in r.output
    # bad input: one-waypoint plan, bad wind syntax
    plan.write_text("north,east\n0,0\n")
    r = CliRunner().invoke(
        main, ["trajectory", "predict", "--model", str(model), "--plan", str(plan), "--wind", "3@0"]
    )
    assert r.exit_code == 1 and "at least two waypoints" in r.output
    r = CliRunner().invoke(
        main, ["trajectory", "predict", "--model", str(model), "--plan", str(plan), "--wind", "3"]
    )
    assert r.exit_code == 1 and "SPEED@DIR" in r.output


def test_trajectory_experiment_quick():
    # What the report's quick trajectory section shows (uasnav.experiments.trajectory.run).
    from uasnav.experiments import trajectory

    res = trajectory.run(quick=True)
    assert (res.n_flights, res.n_train) == (5, 3)
    assert len(res.phantom4.table17) == 2
    means = {m.name: m.mean_pct for m in res.methods}
    assert means["LVQ (thesis)"] < means["distance ÷ speed"]


def test_dataflash_without_mission(shared_data):
    log = read_flight(shared_data / "logs/ardupilot_log171.bin")
    assert log.t.size > 1000 and np.all(np.diff(log.t) > 0)
    assert -35.4 < np.median(log.lat) < -35.3  # CMAC, Canberra
    with pytest.raises(InputError, match="no mission waypoints"):
        flown_runs(log)


def test_cli_csv_flight_with_plan(tmp_path):
    import pymap3d

    from uasnav.trajectory.simulator import phantom4_plans, simulate_flight

    plan = phantom4_plans()["A"]
    lat0, lon0, h0 = 40.85, 14.27, 12.0
    tel = simulate_flight(plan, seed=5)
    lat, lon, h = pymap3d.ned2geodetic(tel.pos_ne[:, 0], tel.pos_ne[:, 1], 0 * tel.t, lat0, lon0, h0)
    flight = tmp_path / "f.csv"
    rows = ["t,lat,lon,alt,v_N,v_E,v_D"] + [
        f"{a},{b:.9f},{c:.9f},{d:.3f},{e},{f},0"
        for a, b, c, d, e, f in zip(tel.t, lat, lon, h, *tel.vel_ne.T, strict=True)
    ]
    flight.write_text("\n".join(rows) + "\n")
    plat, plon, ph = pymap3d.ned2geodetic(plan[:, 0], plan[:, 1], 0 * plan[:, 0], lat0, lon0, h0)
    plan_csv = tmp_path / "plan.csv"
    plan_csv.write_text(
        "lat,lon,alt\n"
        + "".join(f"{a:.9f},{b:.9f},{c:.3f}\n" for a, b, c in zip(plat, plon, ph, strict=True))
    )
    model = tmp_path / "m.json"
    args = [
        "trajectory",
        "train",
        str(flight),
        "--plan",
        str(plan_csv),
        "--speed",
        "3.33",
        "--wind",
        "2.78@22.5",
    ]
    # the default method is the kinematic point mass: no classifier, so no warning
    r = CliRunner().invoke(main, [*args, "--out", str(model), "--json"])
    assert r.exit_code == 0 and r.stderr == "", r.output
    info = json.loads(r.stdout)
    assert info["method"] == "kinematic" and info["limits"]["source"] == "defaults"
    r = CliRunner().invoke(
        main,
        ["trajectory", "predict", "--model", str(model), "--plan", str(plan_csv), "--wind", "0@0", "--json"],
    )
    assert r.exit_code == 0 and json.loads(r.output)["method"] == "kinematic", r.output
    # the LVQ network's options select it; with the kinematic method named they are refused
    r = CliRunner().invoke(main, [*args, "--prototypes", "16", "--out", str(model), "--json"])
    assert r.exit_code == 0 and json.loads(r.stdout)["method"] == "lvq", r.output
    r = CliRunner().invoke(main, [*args, "--method", "kinematic", "--algorithm", "glvq", "--out", str(model)])
    assert r.exit_code == 2 and "--algorithm apply to --method lvq only" in r.output
    # the thesis' LVQ, selected by name
    args += ["--method", "lvq"]
    r = CliRunner().invoke(main, [*args, "--out", str(model), "--json"])
    assert r.exit_code == 0, r.output
    from uasnav.trajectory.geometry import discretise

    # JSON on stdout; 9 elements in 8 feature cells is too few for a classifier: one warning line.
    assert json.loads(r.stdout)["n_elements"] == len(discretise(plan)) == 9
    assert r.stderr.count("\n") == 1 and r.stderr.startswith("warning: 8 populated feature cells")
    r = CliRunner().invoke(
        main,
        [
            "trajectory",
            "predict",
            "--model",
            str(model),
            "--plan",
            str(plan_csv),
            "--wind",
            "2.78@22.5",
            "--json",
        ],
    )
    assert r.exit_code == 0, r.output
    out = json.loads(r.output)
    # Predicting the very flight it was trained on: the 4D times of the interior waypoints are
    # those at which the flown track passed them, within 2 %.
    from uasnav.trajectory.geometry import arc_length_along
    from uasnav.trajectory.samples import crossing_times

    s_wp = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(plan, axis=0).T))])
    flown = crossing_times(tel.t, arc_length_along(plan, tel.pos_ne), s_wp[1:-1])
    np.testing.assert_allclose(out["waypoint_times_s"][1:-1], flown, rtol=0.02)
    # The ETA is to the end of the last element (the waypoint); the simulated vehicle then
    # settles onto it for a few seconds more.
    assert tel.t[-1] - 8.0 < out["eta_s"] < tel.t[-1]
    assert not any(e["low_confidence"] for e in out["elements"])
    # No --plan for a CSV flight: a clear error.
    r = CliRunner().invoke(main, ["trajectory", "train", str(flight), "--out", str(model)])
    assert r.exit_code == 1 and "give --plan" in r.output


def test_one_flight_reader_for_every_format(shared_data):
    # read_flight is open_log's flight view: the same telemetry, no second reader
    import importlib.util

    from uasnav.io import open_log

    assert importlib.util.find_spec("uasnav.trajectory.telemetry") is None
    a = read_flight(shared_data / TLOG)
    b = open_log(shared_data / TLOG).flight
    assert np.array_equal(a.t, b.t) and a.waypoints == b.waypoints and a.reached == b.reached
