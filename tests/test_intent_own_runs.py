"""Operational intents whose time bounds come from the vehicle's own AUTO runs."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.io.plans import read_plan, write_plan

TLOG = "flights/phoenix_mission1_arducopter.tlog"


@pytest.fixture(scope="module")
def phoenix(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("own_runs")
    tlog = shared_data / TLOG
    plan = d / "phoenix.plan"
    write_plan(read_plan(tlog), plan)  # the whole plan: its first waypoint is 2.8 m from home
    model = d / "model.json"
    r = CliRunner().invoke(main, ["trajectory", "train", str(tlog), "--out", str(model)])
    assert r.exit_code == 0, r.output
    return {"tlog": tlog, "plan": plan, "model": model, "dir": d}


def _json(out: str) -> dict:
    """The JSON summary in the output (a progress line may come before it, a warning after)."""
    return json.JSONDecoder().raw_decode(out[out.index("{") :])[0]


def _intent(phoenix: dict[str, Path], *extra: str) -> tuple[int, str]:
    r = CliRunner().invoke(
        main,
        ["trajectory", "intent", "--model", str(phoenix["model"]), "--plan", str(phoenix["plan"]),
         "--wind", "0@0", "--start", "2018-09-17T23:50:00Z", "--calibration-runs", "20",
         "--out", str(phoenix["dir"] / "intent.json"), "--json", *extra],
    )  # fmt: skip
    return r.exit_code, r.output


def test_bounds_from_the_vehicles_own_runs(phoenix: dict[str, Path]) -> None:
    code, out = _intent(phoenix, "--limits-from", str(phoenix["tlog"]), "--coverage", "0.8")
    assert code == 0, out
    d = _json(out)
    assert d["time_bounds_source"] == "5 AUTO runs of the vehicle (phoenix_mission1_arducopter.tlog)"
    # every route point of the whole plan, the 2.8 m first leg included
    assert len(d["waypoint_times_s"]) == 5
    lo, hi = d["eta_bounds_s"]
    # the five real runs last 56–62 s from AUTO: the 80 % band of their own scores holds them
    assert lo < 56.0 and hi > 59.0


def test_too_few_runs_for_the_coverage(phoenix: dict[str, Path]) -> None:
    # implicitly (--limits-from): simulation, and the intent says why the runs were not used
    code, out = _intent(phoenix, "--limits-from", str(phoenix["tlog"]))
    assert code == 0, out
    src = _json(out)["time_bounds_source"]
    assert src.startswith("20 simulated runs") and "needs at least 19 calibration runs" in src
    # explicitly (--flights): refused with one line
    code, out = _intent(phoenix, "--flights", str(phoenix["tlog"]))
    assert code != 0 and out.strip().count("\n") == 0 and out.startswith("error: --flights: coverage 0.95")


def test_run_scores_are_the_largest_relative_miss(phoenix: dict[str, Path]) -> None:
    from uasnav.io import open_log
    from uasnav.io.mission_plan import ItemKind
    from uasnav.trajectory.mission_runs import MISSION_VIEWS, mission_runs
    from uasnav.trajectory.models import load_model
    from uasnav.trajectory.route3d import vertical_limits
    from uasnav.utm.intent import _predict_plan, vehicle_run_bounds

    model = load_model(phoenix["model"])
    log = open_log(phoenix["tlog"], need=MISSION_VIEWS)
    tau = 10.0
    b = vehicle_run_bounds([log], model, np.zeros(2), tau_s=tau)
    up, down, a_z = vertical_limits(model, None, None, None)
    pts, _, _, rp = _predict_plan(
        log.plan, model, np.zeros(2), geoid_height_m=0.0, home_amsl_m=None, climb_ms=up, descent_ms=down,
        accel_z_ms2=a_z, cruise_ms=None,
    )  # fmt: skip
    eta = float(rp.t_depart_s[-1])
    first = {}
    for k, p in enumerate(pts):
        if p.item is not None and p.item not in first:
            first[p.item] = eta if p.kind is ItemKind.LAND else float(rp.t_arrive_s[k])
    runs = mission_runs(log)
    assert b.n_runs == len(runs) == 5 and b.tau_s == tau
    want = []
    for run in runs:
        pairs = [(t, first[i]) for i, t in run.reached] + ([(run.duration_s, eta)] if run.landed else [])
        want.append(max(abs(t - q) / (q + tau) for t, q in pairs))
    assert np.sort(b.scores) == pytest.approx(np.sort(want))  # the bounds keep their scores sorted
    # the real runs take 56–62 s against the kinematic model's 51 s: every score is a miss
    assert np.all(b.scores > 0.05)
