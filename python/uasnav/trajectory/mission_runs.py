"""AUTO executions of a mission in a flight log, and how well a mission execution model
(:mod:`uasnav.trajectory.autopilot`) and the baselines predict them.

A **run** is one AUTO execution: from the moment the autopilot enters its mission mode
(ArduPilot ``AUTO``; PX4 ``AUTO_MISSION``, continuing through ``AUTO_LAND``/``AUTO_RTL``) —
or, when the vehicle is on the ground then, from its lift-off (ArduCopter waits for the pilot's
throttle, PX4 spools its motors up first) — to touch-down, or to the pilot leaving AUTO.
A run cut short (the pilot took over before touch-down) is scored up to the cut, on the
waypoints it reached. Runs that reach no mission item are left out.

Truth: the autopilot's own waypoint-reached events (``MISSION_ITEM_REACHED``, PX4
``mission_result.seq_reached``) and the touch-down seen in the altitude (the first time after
the last item the altitude is within :data:`TOUCHDOWN_M` of the ground it ends on).
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
from uasnav.io.mission_plan import MissionPlan
from uasnav.trajectory.autopilot import (
    MissionParams,
    distance_over_speed_time,
    family_of,
    mission_params,
    predict_mission,
    qgc_mission_time,
)
from uasnav.trajectory.timebounds import DEFAULT_TAU_S, TimeBounds

#: Mode names that run a mission, and those that continue a run once started.
MISSION_MODES = frozenset({"AUTO", "AUTO_MISSION"})
CONTINUING_MODES = frozenset({"AUTO", "AUTO_MISSION", "AUTO_LAND", "AUTO_RTL", "AUTO_TAKEOFF", "LAND", "RTL"})
#: Simulated runs that calibrate each log's time bounds, and their coverage.
SIM_RUNS = 200
COVERAGE = 0.95
#: The views of a log the mission evaluation reads.
MISSION_VIEWS = ("flight", "plan", "params", "modes", "identity")
#: Height above the ground (m) that counts as lift-off / touch-down.
LIFTOFF_M = 0.3
TOUCHDOWN_M = 0.3


@dataclass(frozen=True)
class MissionRun:
    """One AUTO execution (see the module docs).

    Attributes
    ----------
    source : str
        The log.
    start_t, end_t : float
        Start and end (s, log time).
    landed : bool
        Whether the run ends in a touch-down (else the pilot left AUTO: a cut run).
    reached : tuple of (int, float)
        Mission item index reached and its time (s from ``start_t``), in order.
    start_height_m : float
        Height above home at the start (0 on the ground).
    start_ne : tuple of float
        North, east (m) from home at the start.
    start_heading_deg : float or None
        The autopilot's heading (degrees from true north) at the start, taken as the heading it
        was armed at (ArduCopter turns back to it over home in RTL); None when the log has no
        attitude.
    """

    source: str
    start_t: float
    end_t: float
    landed: bool
    reached: tuple[tuple[int, float], ...]
    start_height_m: float
    start_ne: tuple[float, float]
    start_heading_deg: float | None = None

    @property
    def duration_s(self) -> float:
        """Start to end (s)."""
        return self.end_t - self.start_t


def _ground_level(alt: np.ndarray) -> float:
    return float(np.percentile(alt, 2)) if alt.size else math.nan


def _touchdown(t: np.ndarray, alt: np.ndarray, after: float, until: float, ground0: float) -> float | None:
    """The touch-down after ``after`` (s), or None when the vehicle is still flying at
    ``until``. The ground is where the altitude settles at the end (the take-off ground when
    the telemetry stops while still descending). Telemetry is sparse (1–4 Hz, with gaps): the
    touch-down is extrapolated at the last observed descent rate from the last sample above
    the ground."""
    idx = np.flatnonzero((t >= after) & (t <= until))
    if idx.size < 3:
        return None
    rate_end = (alt[idx[-1]] - alt[idx[-2]]) / max(t[idx[-1]] - t[idx[-2]], 1e-3)
    ground = float(np.min(alt[idx])) if abs(rate_end) < 0.15 else ground0
    if float(alt[idx[-1]]) - ground > 3.0:
        return None  # still flying when AUTO ended
    below = idx[alt[idx] <= ground + TOUCHDOWN_M]
    if below.size:
        j = int(below[0])
        prior = idx[idx < j]
        if prior.size < 2:
            return float(t[j])
        k, prev = int(prior[-1]), int(prior[-2])
    else:
        j = -1
        k, prev = int(idx[-1]), int(idx[-2])
    rate = (alt[prev] - alt[k]) / max(t[k] - t[prev], 1e-3)
    if rate <= 0.05:
        return float(t[j]) if j >= 0 else None
    t_td = float(t[k]) + float(alt[k] - ground) / rate
    if j >= 0:
        t_td = min(t_td, float(t[j]))
    return t_td if t_td <= until + 1e-9 else None


def _heading_at(fl: Any, t: float) -> float | None:
    """The autopilot's yaw (degrees) at the sample nearest ``t`` (no interpolation across the
    ±180° wrap), or None without an attitude."""
    ref = getattr(fl, "reference", None)
    euler = getattr(ref, "euler_deg", None) if ref is not None else None
    if euler is None or len(ref.t) == 0:
        return None
    k = int(np.argmin(np.abs(np.asarray(ref.t) - t)))
    yaw = float(euler[k, 2])
    return yaw if math.isfinite(yaw) else None


def mission_runs(log: Any, plan: MissionPlan | None = None) -> list[MissionRun]:
    """The AUTO runs of an opened log (:func:`uasnav.io.open_log`; its ``modes``, ``flight``
    and ``plan`` views).

    Raises
    ------
    InputError
        No mission mode in the log, or no run reaching a mission item.
    """
    plan = plan if plan is not None else log.plan
    modes = log.modes
    fl = log.flight
    src = str(getattr(log, "path", fl.source))
    spans: list[tuple[float, float]] = []
    t_end_log = float(fl.t[-1])
    start: float | None = None
    for k, name in enumerate(modes.names):
        t = float(modes.t[k])
        if start is None and name in MISSION_MODES:
            start = t
        elif start is not None and name not in CONTINUING_MODES:
            spans.append((start, t))
            start = None
    if start is not None:
        spans.append((start, t_end_log))
    if not spans:
        raise InputError(f"{src}: no mission (AUTO) mode in the log")
    seq_to_item = {it.jump_id if it.jump_id is not None else i: i for i, it in enumerate(plan.items)}
    home = plan.home
    from uasnav.trajectory.geometry import geodetic_to_local

    origin = (
        (home.lat_deg, home.lon_deg, 0.0) if home is not None else (float(fl.lat[0]), float(fl.lon[0]), 0.0)
    )
    runs = []
    for t0, t1 in spans:
        sel = (fl.t >= t0 - 2.0) & (fl.t <= t1)
        if sel.sum() < 3:
            continue
        tt, alt = fl.t[sel], fl.alt[sel]
        events = [(t, s) for t, s in fl.reached if t0 <= t <= t1 and s in seq_to_item]
        # the ground: the lowest altitude around the run (before it and at its end)
        before = fl.alt[(fl.t >= t0 - 30.0) & (fl.t <= t0)]
        ground0 = _ground_level(before) if before.size else float(alt[0])
        a0 = float(np.interp(t0, tt, alt))
        on_ground = a0 - ground0 < 1.0
        start_t = t0
        if not events:
            continue
        # the end: the autopilot's own "reached" of a final land item (ArduCopter reports its
        # landing complete so), else the touch-down seen in the altitude after the last item
        # reached, while still in AUTO
        last = events[-1][0]
        landed = False
        end_t = t1
        final = plan.items[seq_to_item[events[-1][1]]].command
        if final in (21, 85, 20):
            end_t, landed = float(last), True
        else:
            landed_t = _touchdown(tt, alt, last, t1, ground0)
            if landed_t is not None:
                end_t, landed = landed_t, True
        p0 = geodetic_to_local(
            np.array([np.interp(start_t, fl.t, fl.lat)]), np.array([np.interp(start_t, fl.t, fl.lon)]),
            np.zeros(1), origin=origin,
        )[0]  # fmt: skip
        ground_ref = ground0
        runs.append(
            MissionRun(
                source=src,
                start_t=start_t,
                end_t=end_t,
                landed=landed,
                reached=tuple((seq_to_item[s], t - start_t) for t, s in events if t >= start_t),
                start_height_m=0.0 if on_ground else float(a0 - ground_ref),
                start_ne=(float(p0[0]), float(p0[1])),
                start_heading_deg=_heading_at(fl, start_t),
            )
        )
    if not runs:
        raise InputError(f"{src}: no AUTO run reaches a mission item")
    return runs


@dataclass(frozen=True)
class RunScore:
    """How each method predicted one run.

    Attributes
    ----------
    run : MissionRun
    eta_real_s : float
        The run's time to its end (touch-down; for a cut run, to the last item reached).
    eta_pred_s : dict of str → float
        Each method's predicted time to the same point.
    waypoint_errors_s : list of dict
        Per item reached: ``item``, ``real_s``, ``pred_s``, ``error_s`` of the default model.
    """

    run: MissionRun
    eta_real_s: float
    eta_pred_s: dict[str, float]
    waypoint_errors_s: list[dict[str, float]]

    def e_pct(self, method: str) -> float:
        """Signed ETA error of ``method`` (%): (predicted − real)/real·100."""
        return (self.eta_pred_s[method] - self.eta_real_s) / self.eta_real_s * 100.0


#: The method names of :func:`score_runs`.
MODEL = "autopilot model"
QGC = "QGroundControl estimate"
NAIVE = "plan length ÷ speed"


def log_mission_params(log: Any) -> MissionParams:
    """The mission execution parameters of an opened log (its parameters, else the firmware
    defaults of its family and version)."""
    params = log.params
    ident = log.identity
    fam = family_of(ident, params)
    return mission_params(fam, getattr(ident, "firmware_version", None), params)


def score_runs(log: Any, params: MissionParams | None = None) -> list[RunScore]:
    """Predict every AUTO run of ``log`` (an opened log) with the mission execution model, the
    QGroundControl estimate and distance ÷ speed, and score them against the log."""
    plan = log.plan
    p = params or log_mission_params(log)
    home_amsl = plan.home.alt_amsl_m if plan.home is not None else None
    out = []
    for run in mission_runs(log, plan):
        pred = predict_mission(
            plan, p, home_amsl_m=home_amsl, start_ne=run.start_ne if run.start_height_m > 0.5 else None,
            start_height_m=run.start_height_m, armed_heading_deg=run.start_heading_deg,
        )  # fmt: skip
        qgc = qgc_mission_time(plan, p.cruise_ms, home_amsl)
        naive = distance_over_speed_time(plan, p.cruise_ms, home_amsl)
        wps = []
        for item, t_real in run.reached:
            t_pred = pred.arrival_of(item)
            if t_pred is not None:
                wps.append(
                    {"item": int(item), "real_s": float(t_real), "pred_s": t_pred, "error_s": t_pred - t_real}
                )
        if run.landed and pred.landed:
            real, model = run.duration_s, pred.eta_s
            frac = 1.0
        else:
            # a cut run: scored up to the last item it reached
            if not wps:
                continue
            real, model = wps[-1]["real_s"], wps[-1]["pred_s"]
            frac = model / pred.eta_s if pred.eta_s > 0 else 1.0
        out.append(RunScore(run, real, {MODEL: model, QGC: qgc * frac, NAIVE: naive * frac}, wps))
    return out


def evaluate_logs(logs: Sequence[Any]) -> dict[str, Any]:
    """Score every AUTO run of every log (physics with each log's own parameters: no training),
    per method: per-run ETA errors, their median and worst, and per-waypoint errors.

    ``logs`` are paths or logs opened with :func:`uasnav.io.open_log` (declare the views
    ``flight``, ``plan``, ``params``, ``modes``, ``identity`` so that one pass decodes them).
    """
    from uasnav.io.logfile import LogFile, open_log

    scores: list[tuple[str, RunScore]] = []
    stacks: dict[str, str] = {}
    sources: dict[str, Any] = {}
    covered: list[bool] = []
    for item in logs:
        log = item if isinstance(item, LogFile) else open_log(item, need=MISSION_VIEWS)
        path = str(log.path)
        log.plan  # noqa: B018 - a log without a mission is refused for that, before its parameters
        p = log_mission_params(log)
        stacks[path] = f"{p.family} {p.version or ''}".strip()
        sources[path] = {k: {"value": p.values[k], "source": p.sources[k]} for k in p.values}
        log_scores = score_runs(log, p)
        scores += [(path, s) for s in log_scores]
        # time bounds calibrated on simulated executions of this log's mission (the vehicle's
        # own earlier flights calibrate them with `trajectory calibrate --flights`)
        bounds = TimeBounds(
            simulated_scores(log.plan, p, SIM_RUNS), DEFAULT_TAU_S, f"{SIM_RUNS} simulated runs"
        )
        covered += [covered_run(bounds, s, COVERAGE) for s in log_scores]
    if not scores:
        raise InputError("no scorable AUTO run in the logs")
    methods: dict[str, Any] = {}
    for m in (MODEL, QGC, NAIVE):
        e = np.array([s.e_pct(m) for _, s in scores])
        methods[m] = {
            "applicable": True,
            "run_e_pct": e.tolist(),
            "run_abs_e_pct_median": float(np.median(np.abs(e))),
            "run_abs_e_pct_p95": float(np.percentile(np.abs(e), 95)),
            "run_abs_e_pct_worst": float(np.max(np.abs(e))),
            "run_e_pct_mean": float(np.mean(e)),
        }
    runs: list[dict[str, Any]] = [
        {
            "log": path,
            "stack": stacks[path],
            "start_s": s.run.start_t,
            "landed": s.run.landed,
            "eta_real_s": s.eta_real_s,
            "eta_pred_s": dict(s.eta_pred_s),
            "waypoint_errors": s.waypoint_errors_s,
        }
        for path, s in scores
    ]
    per_stack: dict[str, Any] = {}
    for r in runs:
        per_stack.setdefault(r["stack"].split()[0], []).append(
            (r["eta_pred_s"][MODEL] - r["eta_real_s"]) / r["eta_real_s"] * 100.0
        )
    stack_table = {
        k: {"n_runs": len(v), "run_abs_e_pct_median": float(np.median(np.abs(v))),
            "run_abs_e_pct_worst": float(np.max(np.abs(v)))}
        for k, v in per_stack.items()
    }  # fmt: skip
    from uasnav.trajectory.timebounds import clopper_pearson

    k = int(sum(covered))
    lo, hi = clopper_pearson(k, len(covered))
    bounds_report = {
        "coverage": COVERAGE,
        "source": f"{SIM_RUNS} simulated runs of each log's mission (perturbed parameters)",
        "covered": k,
        "n_runs": len(covered),
        "covered_ci95": [lo, hi],
    }
    for r, c in zip(runs, covered, strict=True):
        r["within_time_bounds"] = c
    return {
        "methods": methods,
        "runs": runs,
        "per_stack": stack_table,
        "parameters": sources,
        "time_bounds": bounds_report,
    }


__all__ = [
    "MISSION_VIEWS",
    "MODEL",
    "NAIVE",
    "QGC",
    "SIM_SPREAD",
    "MissionRun",
    "RunScore",
    "calibrate_from_flights",
    "covered_run",
    "evaluate_logs",
    "log_mission_params",
    "mission_runs",
    "run_nonconformity",
    "score_runs",
    "simulated_scores",
]


# --------------------------------------------------------------------------- time bounds
def run_nonconformity(s: RunScore, tau_s: float = DEFAULT_TAU_S) -> float:
    """The score r of a real run for the mission model (the form of
    :func:`uasnav.trajectory.timebounds.score`): max over its waypoint arrivals and its end of
    |T − T̂| / (T̂ + τ)."""
    pairs = [(w["real_s"], w["pred_s"]) for w in s.waypoint_errors_s]
    pairs.append((s.eta_real_s, s.eta_pred_s[MODEL]))
    return max(abs(t - p) / (p + tau_s) for t, p in pairs)


#: The perturbations of the simulated runs that calibrate the mission model's time bounds
#: when the vehicle has no flights of its own: each parameter of the firmware's waypoint,
#: climb and landing control scaled by a uniform factor in [1 − x, 1 + x] (speeds 10 %,
#: accelerations and jerk 30 %, acceptance radii and land altitudes 50 %), and a start delay
#: uniform in [0, 2] s (the pilot's throttle, the motors spooling up).
SIM_SPREAD = {"speed": 0.10, "accel": 0.30, "radius": 0.50}
SIM_START_DELAY_S = 2.0


def _spread_of(name: str) -> float:
    if any(k in name for k in ("ACC", "JERK")):
        return SIM_SPREAD["accel"]
    if any(k in name for k in ("RAD", "ALT", "LOIT")):
        return SIM_SPREAD["radius"]
    if any(k in name for k in ("SPEED", "CRUISE", "V_AUTO", "VEL", "ARSPD", "CLMB", "SINK")):
        return SIM_SPREAD["speed"]
    return 0.0


def simulated_scores(
    plan: MissionPlan, params: MissionParams, n_runs: int = 200, seed: int = 0, tau_s: float = DEFAULT_TAU_S
) -> np.ndarray:
    """Scores r of ``n_runs`` simulated executions of ``plan`` (truth: the model with perturbed
    parameters, :data:`SIM_SPREAD`; prediction: the nominal parameters)."""
    rng = np.random.default_rng(seed)
    nominal = predict_mission(plan, params)
    out = np.empty(n_runs)
    for k in range(n_runs):
        vals = {n: v * (1.0 + _spread_of(n) * rng.uniform(-1.0, 1.0)) for n, v in params.values.items()}
        truth = predict_mission(plan, dataclasses.replace(params, values=vals))
        delay = rng.uniform(0.0, SIM_START_DELAY_S)
        t_true = np.r_[truth.arrive_s, truth.eta_s] + delay
        t_pred = np.r_[nominal.arrive_s, nominal.eta_s]
        m = min(t_true.size, t_pred.size)
        out[k] = float(np.max(np.abs(t_true[:m] - t_pred[:m]) / (t_pred[:m] + tau_s)))
    return out


def calibrate_from_flights(logs: Sequence[Any], tau_s: float = DEFAULT_TAU_S) -> TimeBounds:
    """Time bounds of the mission model from the vehicle's own flights: one score per AUTO run
    (:func:`run_nonconformity`)."""
    from uasnav.io.logfile import LogFile, open_log

    scores: list[float] = []
    names = []
    for item in logs:
        log = item if isinstance(item, LogFile) else open_log(item, need=MISSION_VIEWS)
        names.append(Path(str(log.path)).name)
        scores += [run_nonconformity(s, tau_s) for s in score_runs(log)]
    if not scores:
        raise InputError("no scorable AUTO run in the flights")
    return TimeBounds(np.array(scores), tau_s, f"{len(scores)} AUTO runs of the vehicle ({', '.join(names)})")


def covered_run(bounds: TimeBounds, s: RunScore, coverage: float) -> bool:
    """Whether every waypoint arrival and the end of a real run lie within the bounds."""
    q = bounds.quantile(coverage)
    pairs = [(w["real_s"], w["pred_s"]) for w in s.waypoint_errors_s]
    pairs.append((s.eta_real_s, s.eta_pred_s[MODEL]))
    return all(abs(t - p) <= q * (p + bounds.tau_s) for t, p in pairs)
