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


SOURCE = (
    "5 AUTO runs of the vehicle (phoenix_mission1_arducopter.tlog): Student-t prediction bounds of each "
    "run's slowest and fastest log pace (T + 10 s)/(T̂ + 10 s), assuming they scatter normally from run "
    "to run; "
    "leave-one-run-out: {k}/5 runs within the bounds of the others"
)


def test_bounds_from_the_vehicles_own_runs(phoenix: dict[str, Path]) -> None:
    # the --limits-from log's five runs are enough for any coverage: no simulation
    code, out = _intent(phoenix, "--limits-from", str(phoenix["tlog"]))
    assert code == 0, out
    d = _json(out)
    assert d["time_bounds_source"] == SOURCE.format(k=5)
    # every route point of the whole plan, the 2.8 m first leg included
    assert len(d["waypoint_times_s"]) == 5
    lo, hi = d["eta_bounds_s"]
    # the five real runs last 56–62 s from AUTO against a predicted 51 s: the band follows the
    # vehicle's own pace (it is not centred on the prediction)
    assert lo < 56.0 < 61.6 < hi < 70.0 and hi - d["eta_s"] > 2 * (d["eta_s"] - lo)
    # at 80 % the held-out check misses one run (its bounds from the four others)
    code, out = _intent(phoenix, "--limits-from", str(phoenix["tlog"]), "--coverage", "0.8")
    assert code == 0, out
    d80 = _json(out)
    assert d80["time_bounds_source"] == SOURCE.format(k=4)
    assert d80["eta_bounds_s"][0] > lo and d80["eta_bounds_s"][1] < hi


def test_runs_that_cannot_give_bounds(phoenix: dict[str, Path], shared_data: Path) -> None:
    ulg = str(shared_data / "flights" / "px4_s500_mission_land.ulg")
    # implicitly (--limits-from): simulation, and the intent says why the runs were not used
    code, out = _intent(phoenix, "--limits-from", ulg)
    assert code == 0, out
    src = _json(out)["time_bounds_source"]
    assert src.startswith("20 simulated runs") and "own runs in px4_s500_mission_land.ulg not used" in src
    # explicitly (--flights): refused with one line
    code, out = _intent(phoenix, "--flights", ulg)
    assert code != 0 and out.strip().count("\n") == 0 and out.startswith("error: --flights: "), out


def test_run_paces_are_the_extreme_log_ratios(phoenix: dict[str, Path]) -> None:
    from uasnav.io import open_log
    from uasnav.io.mission_plan import ItemKind
    from uasnav.trajectory.mission_runs import MISSION_VIEWS, mission_runs
    from uasnav.trajectory.models import load_model
    from uasnav.trajectory.route3d import vertical_limits
    from uasnav.trajectory.timebounds import leave_one_run_out
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
    for j, run in enumerate(runs):
        pairs = [(t, first[i]) for i, t in run.reached] + ([(run.duration_s, eta)] if run.landed else [])
        r = [np.log((t + tau) / (q + tau)) for t, q in pairs]
        assert b.upper_log[j] == pytest.approx(max(r)) and b.lower_log[j] == pytest.approx(min(r))
    # the real runs take 56–62 s against the kinematic model's 51 s: every run ends late
    assert np.all(b.upper_log > 0.05)
    # every run lies within the 95 % bounds of the other four
    assert leave_one_run_out(list(b.runs), 0.95, tau) == [True] * 5


def test_pace_bounds_are_the_student_t_prediction_bounds() -> None:
    from scipy import stats

    from uasnav.errors import InputError
    from uasnav.trajectory.timebounds import PaceBounds

    u, lo = np.array([0.10, 0.15, 0.12, 0.20]), np.array([-0.05, 0.0, -0.02, 0.01])
    b = PaceBounds(u, lo, 10.0)
    k = stats.t.ppf(0.95, 3) * np.sqrt(1 + 1 / 4)  # coverage 0.9: each side at 0.95
    L, U = b.limits(0.9)
    assert U == pytest.approx(u.mean() + k * u.std(ddof=1))
    assert L == pytest.approx(lo.mean() - k * lo.std(ddof=1))
    t_lo, t_hi = b.band(np.array([0.0, 50.0]), 0.0, 0.9)
    assert t_hi[1] == pytest.approx(60.0 * np.exp(U) - 10.0)
    assert t_lo[0] == pytest.approx(10.0 * np.exp(L) - 10.0) and t_lo[0] < 0  # opens before the start
    with pytest.raises(InputError, match="at least 3 runs"):
        PaceBounds(u[:2], lo[:2]).limits(0.9)
    with pytest.raises(InputError, match="coverage"):
        b.limits(1.0)


def test_pace_bounds_hold_their_coverage_under_their_assumption() -> None:
    """Runs whose paces scatter log-normally (a run's own pace plus waypoint noise): the bounds
    of 5 runs cover a sixth as often as stated (binomial 99.9 % band over 2000 trials)."""
    from uasnav.trajectory.timebounds import PaceBounds, log_pace

    rng = np.random.default_rng(7)
    t_pred = np.array([10.0, 12.0, 36.0, 51.0])

    def run() -> tuple[np.ndarray, np.ndarray]:
        pace = rng.normal(0.12, 0.04) + rng.normal(0.0, 0.02, t_pred.size)
        return (t_pred + 10.0) * np.exp(pace) - 10.0, t_pred

    for c in (0.8, 0.95):
        hits = 0
        for _ in range(2000):
            b = PaceBounds.of_runs([run() for _ in range(5)], 10.0)
            hits += b.covers(*run(), coverage=c)
        sd = np.sqrt(c * (1 - c) / 2000)
        assert hits / 2000 > c - 3.3 * sd, (c, hits)
    assert log_pace(np.array([0.0]), np.array([0.0])) == (0.0, 0.0)
