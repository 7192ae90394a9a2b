"""The held-out procedure of the mission execution model's defaults (trajectory.holdout)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from uasnav.trajectory import holdout as ho
from uasnav.trajectory.autopilot import ModelOptions
from uasnav.trajectory.mission_runs import MODEL, QGC

_CANDS = (ho.Candidate("prior"), ho.Candidate("other", options=ModelOptions(px4_tracking_lag=False)),
          ho.Candidate("scaled", scaled=True))  # fmt: skip


def _table(real: list[float], **pred: list[float]) -> ho.RunTable:
    n = len(real)
    return ho.RunTable(
        [f"log{i // 2}.tlog" for i in range(n)], np.arange(n, dtype=float), np.array(real),
        {k: np.array(v) for k, v in pred.items()}, ["arducopter 3.6"] * n,
    )  # fmt: skip


def test_a_held_out_run_never_influences_its_own_choice() -> None:
    # "other" is perfect on run 0 only and far off elsewhere: it must not be chosen for run 0
    real = [100.0, 100.0, 100.0, 100.0]
    t = _table(real, prior=[110.0, 103.0, 97.0, 102.0], other=[100.0, 150.0, 150.0, 150.0],
               scaled=[110.0, 103.0, 97.0, 102.0])  # fmt: skip
    r = ho.held_out(t, [str(i) for i in range(4)], _CANDS)
    assert r["runs"][0]["chosen"] == "prior" and r["runs"][0]["e_pct"] == pytest.approx(10.0)
    # the held-out run's own prediction can be anything: its choice does not change
    t2 = _table(real, prior=[500.0, 103.0, 97.0, 102.0], other=[100.0, 150.0, 150.0, 150.0],
                scaled=[500.0, 103.0, 97.0, 102.0])  # fmt: skip
    assert ho.held_out(t2, [str(i) for i in range(4)], _CANDS)["runs"][0]["chosen"] == "prior"
    assert all(row["n_training_runs"] == 3 for row in r["runs"])


def test_learned_scale_is_fitted_on_the_training_runs_only() -> None:
    # every run 20 % slower than predicted except the held-out one: the scale comes from the others
    real = [120.0, 120.0, 120.0, 100.0]
    pred = [100.0, 100.0, 100.0, 100.0]
    t = _table(real, prior=pred, other=pred, scaled=pred)
    r = ho.held_out(t, ["a", "b", "c", "d"], _CANDS)
    last = r["runs"][3]
    assert last["chosen"] == "scaled" and last["scale"] == pytest.approx(1.2)
    assert last["e_pct"] == pytest.approx(20.0)  # scored against its own real time, not refitted
    # the inner leave-one-out: with two training runs the scale of each comes from the other
    e = ho.training_errors(_CANDS[2], np.array([100.0, 200.0]), np.array([100.0, 100.0]))
    assert e.tolist() == pytest.approx([100.0, -50.0])


def test_no_training_run_keeps_the_prior_and_groups_leave_together() -> None:
    t = _table([100.0, 100.0], prior=[104.0, 96.0], other=[100.0, 100.0], scaled=[104.0, 96.0])
    r = ho.held_out(t, ["one log", "one log"], _CANDS)
    assert [row["chosen"] for row in r["runs"]] == ["prior", "prior"] and r["prior_chosen"] == 2
    assert r["run_abs_e_pct_median"] == pytest.approx(4.0)
    assert all(row["n_training_runs"] == 0 for row in r["runs"])


def test_real_flights_held_out(shared_data: Path) -> None:
    flights = shared_data / "flights"
    t = ho.run_table([flights / "phoenix_mission1_arducopter.tlog", flights / "px4_s500_mission_land.ulg"])
    assert t.real_s.size == 6 and set(t.pred_s) == {c.name for c in ho.CANDIDATES}
    r = ho.held_out_report(t)
    assert r["prior"] == MODEL and QGC in r["candidates"]
    for key in ("leave_one_run_out", "leave_one_log_out"):
        h = r[key]
        assert len(h["runs"]) == 6
        # the Done-when figures, held out: median ≤ 5 %, worst ≤ 15 %, ≥ 2× better than QGC
        assert h["run_abs_e_pct_median"] <= 5.0 and h["run_abs_e_pct_worst"] <= 15.0, h
        assert h["qgc_over_held_out"] >= 2.0
    # leave-one-log-out: the PX4 run is chosen for on the ArduCopter runs only (5 of them)
    px4 = [row for row in r["leave_one_log_out"]["runs"] if row["stack"].startswith("px4")]
    assert len(px4) == 1 and px4[0]["n_training_runs"] == 5
