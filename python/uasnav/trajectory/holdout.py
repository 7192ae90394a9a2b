"""Held-out evaluation of the mission execution model's defaults: every choice that is not a
firmware parameter is made on some flights and scored on the others.

The choices
-----------
A **candidate** is one way to predict a run: the mission execution model with one set of
:class:`~uasnav.trajectory.autopilot.ModelOptions` (the firmware-implied options first, then
each option turned the other way), the same model times a learned scale factor (a residual
correction: the median of real ÷ predicted mission time over the training runs), or a baseline
(QGroundControl's estimate, plan length ÷ speed). :data:`CANDIDATES` lists them; the first is
the **prior**, what the package uses when it has no flights to choose with.

The procedure
-------------
For each held-out group of runs (one run: leave-one-run-out; all runs of one log, i.e. one
vehicle and stack: leave-one-log-out):

1. score every candidate on the remaining runs by the median of its per-run |ETA e%|, ties
   broken by the worst |e%| and then by the order of :data:`CANDIDATES` (the prior wins a tie).
   A learned scale is fitted inside this step too: its training error on each training run
   uses the factor fitted on the other training runs (inner leave-one-out), so it is not
   favoured by being scored on the runs that fitted it;
2. refit the chosen candidate's scale (if any) on all training runs;
3. predict the held-out runs with it and record their e%.

With no training runs left (one log only) the prior is chosen. The held-out errors are the
evidence for "defaults chosen without the flights they are scored on"; the errors of the prior
on all runs are not, when the prior itself was written while looking at those flights (say so
where they are reported).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from uasnav.errors import InputError
from uasnav.trajectory.autopilot import ModelOptions
from uasnav.trajectory.mission_runs import MISSION_VIEWS, MODEL, NAIVE, QGC, log_mission_params, score_runs


@dataclass(frozen=True)
class Candidate:
    """One way to predict a run.

    Attributes
    ----------
    name : str
    method : str
        Which prediction of :func:`~uasnav.trajectory.mission_runs.score_runs` (the model,
        QGroundControl's estimate, plan length ÷ speed).
    options : ModelOptions
        The model's options (ignored by the baselines).
    scaled : bool
        Multiplied by a scale factor learned on the training runs.
    """

    name: str
    method: str = MODEL
    options: ModelOptions = dataclasses.field(default_factory=ModelOptions)
    scaled: bool = False


_P = ModelOptions()
#: The candidates, the prior first.
_swap = dataclasses.replace
CANDIDATES: tuple[Candidate, ...] = (
    Candidate(MODEL),
    Candidate(f"{MODEL}, ArduCopter 3.x slowing at WPNAV_ACCEL", options=_swap(_P, ac3_slowdown_factor=1.0)),
    Candidate(f"{MODEL}, no PX4 tracking lag", options=_swap(_P, px4_tracking_lag=False)),
    Candidate(f"{MODEL}, no PX4 spool-up/ramp", options=_swap(_P, px4_takeoff_lead=False)),
    Candidate(f"{MODEL}, no PX4 yaw acceptance", options=_swap(_P, px4_yaw_acceptance=False)),
    Candidate(f"{MODEL} × learned scale", scaled=True),
    Candidate(QGC, method=QGC),
    Candidate(NAIVE, method=NAIVE),
)  # fmt: skip


@dataclass(frozen=True)
class RunTable:
    """Every candidate's prediction of every run.

    Attributes
    ----------
    logs : list of str
        The log of each run.
    start_s : ndarray, shape (n,)
        Each run's start (s, log clock).
    real_s : ndarray, shape (n,)
        Each run's real time (touch-down, or the last item reached for a cut run).
    pred_s : dict of str → ndarray, shape (n,)
        Candidate name → its unscaled prediction of each run.
    stacks : list of str
        The autopilot family and version of each run.
    """

    logs: list[str]
    start_s: np.ndarray
    real_s: np.ndarray
    pred_s: dict[str, np.ndarray]
    stacks: list[str]


def run_table(logs: Sequence[Any], candidates: Sequence[Candidate] = CANDIDATES) -> RunTable:
    """Predict every AUTO run of ``logs`` (paths or opened logs) with every candidate."""
    from uasnav.io.logfile import LogFile, open_log

    names: list[str] = []
    start: list[float] = []
    real: list[float] = []
    stacks: list[str] = []
    pred: dict[str, list[float]] = {c.name: [] for c in candidates}
    for item in logs:
        log = item if isinstance(item, LogFile) else open_log(item, need=MISSION_VIEWS)
        p = log_mission_params(log)
        base = score_runs(log, p)
        by_options: dict[ModelOptions, list[Any]] = {p.options: base}
        for c in candidates:
            if c.options not in by_options:
                by_options[c.options] = score_runs(log, dataclasses.replace(p, options=c.options))
            scores = by_options[c.options] if c.method == MODEL else base
            if len(scores) != len(base):
                raise InputError(f"{log.path}: the options change which runs are scored")
            pred[c.name] += [s.eta_pred_s[c.method] for s in scores]
        names += [str(log.path)] * len(base)
        start += [s.run.start_t for s in base]
        real += [s.eta_real_s for s in base]
        stacks += [f"{p.family} {p.version or ''}".strip()] * len(base)
    if not real:
        raise InputError("no scorable AUTO run in the logs")
    return RunTable(names, np.array(start), np.array(real), {k: np.array(v) for k, v in pred.items()}, stacks)


def fit_scale(real_s: np.ndarray, pred_s: np.ndarray) -> float:
    """The learned correction: median of real ÷ predicted time (1 without runs)."""
    return float(np.median(real_s / pred_s)) if real_s.size else 1.0


def _e_pct(pred: np.ndarray, real: np.ndarray) -> np.ndarray:
    return (pred - real) / real * 100.0


def training_errors(c: Candidate, real_s: np.ndarray, pred_s: np.ndarray) -> np.ndarray:
    """Per-run e% of a candidate on training runs; a learned scale is fitted, for each run, on
    the other training runs (inner leave-one-out)."""
    if not c.scaled:
        return _e_pct(pred_s, real_s)
    n = real_s.size
    k = np.array([fit_scale(np.delete(real_s, i), np.delete(pred_s, i)) for i in range(n)])
    return _e_pct(pred_s * k, real_s)


def choose(
    table: RunTable, train: np.ndarray, candidates: Sequence[Candidate] = CANDIDATES
) -> tuple[Candidate, float]:
    """The candidate chosen on the runs where ``train`` (bool mask) is true, and its scale
    factor fitted on them (1 when unscaled). The prior when no run trains."""
    if not train.any():
        return candidates[0], 1.0
    real = table.real_s[train]
    best: tuple[float, float, int] | None = None
    chosen = candidates[0]
    for order, c in enumerate(candidates):
        e = np.abs(training_errors(c, real, table.pred_s[c.name][train]))
        key = (float(np.median(e)), float(np.max(e)), order)
        if best is None or key < best:
            best, chosen = key, c
    scale = fit_scale(real, table.pred_s[chosen.name][train]) if chosen.scaled else 1.0
    return chosen, scale


def held_out(
    table: RunTable, groups: Sequence[str], candidates: Sequence[Candidate] = CANDIDATES
) -> dict[str, Any]:
    """Held-out errors: each group of runs (same label in ``groups``) predicted by the candidate
    chosen on all other groups (see the module docs)."""
    g = np.asarray(groups)
    n = table.real_s.size
    e = np.full(n, math.nan)
    rows: list[dict[str, Any]] = []
    chosen_by_run: list[tuple[str, float, int]] = [("", 1.0, 0)] * n
    for label in dict.fromkeys(g.tolist()):
        test = g == label
        c, k = choose(table, ~test, candidates)
        e[test] = _e_pct(table.pred_s[c.name][test] * k, table.real_s[test])
        for j in np.flatnonzero(test).tolist():
            chosen_by_run[j] = (c.name, k, int((~test).sum()))
    for i in range(n):
        name, k, n_train = chosen_by_run[i]
        rows.append(
            {
                "log": table.logs[i],
                "stack": table.stacks[i],
                "start_s": float(table.start_s[i]),
                "eta_real_s": float(table.real_s[i]),
                "chosen": name,
                "scale": k,
                "n_training_runs": n_train,
                "e_pct": float(e[i]),
            }
        )
    a = np.abs(e)
    qgc = np.abs(_e_pct(table.pred_s[QGC], table.real_s)) if QGC in table.pred_s else None
    out: dict[str, Any] = {
        "runs": rows,
        "run_abs_e_pct_median": float(np.median(a)),
        "run_abs_e_pct_worst": float(np.max(a)),
        "prior_chosen": sum(r["chosen"] == candidates[0].name for r in rows),
    }
    if qgc is not None:
        out["qgc_abs_e_pct_median"] = float(np.median(qgc))
        out["qgc_over_held_out"] = float(np.median(qgc) / max(float(np.median(a)), 1e-12))
    return out


def held_out_report(table: RunTable, candidates: Sequence[Candidate] = CANDIDATES) -> dict[str, Any]:
    """Leave-one-run-out and leave-one-log-out held-out errors of :func:`held_out`, the
    candidates and each candidate's in-sample errors on all runs."""
    in_sample = {}
    for c in candidates:
        e = np.abs(training_errors(c, table.real_s, table.pred_s[c.name]))
        in_sample[c.name] = {
            "run_abs_e_pct_median": float(np.median(e)),
            "run_abs_e_pct_worst": float(np.max(e)),
        }
    by_run = [f"{lg}@{t}" for lg, t in zip(table.logs, table.start_s, strict=True)]
    return {
        "prior": candidates[0].name,
        "candidates": [c.name for c in candidates],
        "criterion": "median |ETA e%| on the training runs, then the worst, then the candidate order",
        "in_sample": in_sample,
        "leave_one_run_out": held_out(table, by_run, candidates),
        "leave_one_log_out": held_out(table, [Path(lg).name for lg in table.logs], candidates),
    }


__all__ = [
    "CANDIDATES",
    "Candidate",
    "RunTable",
    "choose",
    "fit_scale",
    "held_out",
    "held_out_report",
    "run_table",
    "training_errors",
]
