"""Simulated runs with ground truth for calibrating and checking the time bounds.

Each run is a random plan (3–6 waypoints, legs 40–150 m, turns up to ±150°) flown by the
simulator (:func:`~uasnav.trajectory.simulator.simulate_flight`) in a random wind (0–8 m/s from
any direction; the simulator adds gusts and a per-flight speed spread), with the predictor's
commanded speed. The prediction uses the run's *nominal* wind (what a planner knows from a
forecast), the truth is the simulated flight: the time its arc length along the plan first
reaches each element boundary. Everything is deterministic from the seed.

3D runs (:func:`simulated_route_runs`, what ``uasnav trajectory calibrate`` and the intents
use): a random route with a take-off, sloped legs, holds, speed changes and a landing
(:func:`random_route`), flown by :func:`uasnav.trajectory.route_sim.simulate_route` with the
predictor's vertical limits, scored at every 3D element boundary — so the calibrated bounds
cover climbs, descents and hovers as well as the horizontal elements.

The simulator steps at ``dt`` = 0.05 s here (the experiments use 0.02 s): calibration needs
hundreds of runs, and the timing difference between the two steps (a few tenths of a percent)
is far below the spread the bounds cover.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from uasnav.trajectory.features import wind_vector
from uasnav.trajectory.geometry import arc_length_along
from uasnav.trajectory.models import Predictor
from uasnav.trajectory.predictor import PlanPrediction
from uasnav.trajectory.route3d import Route3D, RoutePrediction, predict_route, vertical_limits
from uasnav.trajectory.route_sim import RouteTruth, simulate_route
from uasnav.trajectory.samples import crossing_times
from uasnav.trajectory.simulator import (
    MultirotorParams,
    Telemetry,
    VerticalLimits,
    WindModel,
    simulate_flight,
)
from uasnav.trajectory.timebounds import DEFAULT_TAU_S, TimeBounds, score, widening

#: Simulator step of the calibration runs, s.
CALIBRATION_DT_S = 0.1


@dataclass(frozen=True)
class SimulatedRun:
    """One run: the plan, its prediction and the truth at the element boundaries.

    Attributes
    ----------
    plan_ne : ndarray, shape (n, 2) — waypoints, north/east m.
    wind_ne : ndarray, shape (2,) — nominal wind (m/s, toward).
    prediction : PlanPrediction
    s_knots_m, t_pred_s, t_true_s, widening_s : ndarray, shape (m + 1,)
        Element boundaries (arc length, m), predicted and true times there (s), widening w (s).
    telemetry : Telemetry — the simulated flight (truth positions).
    """

    plan_ne: np.ndarray
    wind_ne: np.ndarray
    prediction: PlanPrediction
    s_knots_m: np.ndarray
    t_pred_s: np.ndarray
    t_true_s: np.ndarray
    widening_s: np.ndarray
    telemetry: Telemetry


def random_plan(rng: np.random.Generator) -> np.ndarray:
    """A random waypoint plan (see module), north/east m, starting at the origin."""
    n_legs = int(rng.integers(2, 6))
    heading = rng.uniform(0, 2 * np.pi)
    pts = [np.zeros(2)]
    for _ in range(n_legs):
        length = rng.uniform(40.0, 150.0)
        pts.append(pts[-1] + length * np.array([np.cos(heading), np.sin(heading)]))
        heading += np.radians(rng.uniform(-150.0, 150.0))
    return np.array(pts)


def simulate_run(predictor: Predictor, seed: int, cruise_ms: float | None = None) -> SimulatedRun:
    """One simulated run with its prediction (see module), at ``cruise_ms`` (default the
    model's speed): calibrate at the speed the missions will fly."""
    v = predictor.cruise_ms_ if cruise_ms is None else float(cruise_ms)
    rng = np.random.default_rng(seed)
    plan = random_plan(rng)
    speed, from_deg = float(rng.uniform(0.0, 8.0)), float(rng.uniform(0.0, 360.0))
    wind = WindModel(speed_ms=speed, from_deg=from_deg)
    tel = simulate_flight(
        plan,
        params=MultirotorParams(cruise_ms=v),
        wind=wind,
        seed=int(rng.integers(2**31)),
        dt=CALIBRATION_DT_S,
    )
    w_ne = wind_vector(speed, from_deg)
    pred = predictor.predict(plan, w_ne, v)
    el = pred.elements
    s_knots = np.concatenate([[el.s_start_m[0]], el.s_end_m])
    t_pred = np.concatenate([[0.0], np.cumsum(pred.time_s)])
    s_true = arc_length_along(plan, tel.pos_ne)
    # the vehicle stops at the last waypoint: "reached" within 0.5 m of it (position noise)
    targets = np.minimum(s_knots, s_knots[-1] - 0.5)
    t_true = crossing_times(tel.t, s_true, targets)
    return SimulatedRun(
        plan, w_ne, pred, s_knots, t_pred, t_true, widening(pred.time_s, pred.low_confidence), tel
    )


#: Elementary operations of one simulated calibration run (≈ 36 ms of one core: a simulated
#: flight of a few minutes at the simulator step, plus its prediction).
OPS_PER_SIMULATED_RUN = 4e7


def check_runs(n_runs: int, option: str = "n_runs") -> None:
    """Refuse, up front, more simulated runs than the work limit allows (with the estimate).

    Raises
    ------
    ResourceLimitError
        ``n_runs`` × :data:`OPS_PER_SIMULATED_RUN` beyond :func:`uasnav.limits.max_work`.
    """
    from uasnav.limits import check_work

    check_work(float(n_runs) * OPS_PER_SIMULATED_RUN, f"{n_runs} simulated calibration runs", option=option)


def simulated_runs(
    predictor: Predictor,
    n_runs: int,
    seed: int = 0,
    progress: Callable[[int, int], None] | None = None,
    cruise_ms: float | None = None,
) -> list[SimulatedRun]:
    """``n_runs`` runs, run i from seed ``seed·100003 + i`` (distinct seeds → independent sets).
    More runs than the work limit allows are refused up front (:func:`check_runs`)."""
    check_runs(n_runs)
    out = []
    for i in range(n_runs):
        out.append(simulate_run(predictor, seed * 100_003 + i, cruise_ms))
        if progress is not None:
            progress(i + 1, n_runs)
    return out


@dataclass(frozen=True)
class SimulatedRouteRun:
    """One 3D run: a random route (take-off, sloped legs, holds, landing), its prediction and
    the truth at every element boundary (:mod:`uasnav.trajectory.route3d`).

    Attributes
    ----------
    route : Route3D
    wind_ne : ndarray, shape (2,) — nominal wind (m/s, toward).
    prediction : RoutePrediction
    t_pred_s, t_true_s, widening_s : ndarray, shape (m + 1,)
        Predicted and true times (s) at the start and at each element's end, widening w (s).
    truth : RouteTruth — the simulated flight.
    """

    route: Route3D
    wind_ne: np.ndarray
    prediction: RoutePrediction
    t_pred_s: np.ndarray
    t_true_s: np.ndarray
    widening_s: np.ndarray
    truth: RouteTruth


def random_route(rng: np.random.Generator, cruise_ms: float = MultirotorParams.cruise_ms) -> Route3D:
    """A random 3D route (north/east m, altitude m above the take-off point): a vertical
    take-off to 15–60 m, a :func:`random_plan` whose waypoints change altitude by up to ±15 m
    (half of them) and are held 3–15 s (one in three), a ``DO_CHANGE_SPEED`` to 0.5–2 ×
    ``cruise_ms`` (m/s) before one leg in three, held until the next change (the bounds
    calibrated on these routes cover speed changes), and a vertical landing at the end."""
    plan = random_plan(rng)
    h = float(rng.uniform(15.0, 60.0))
    alt = [h]
    for _ in range(plan.shape[0] - 1):
        step = float(rng.uniform(-15.0, 15.0)) if rng.random() < 0.5 else 0.0
        alt.append(float(np.clip(alt[-1] + step, 10.0, 90.0)))
    hold = np.where(rng.random(plan.shape[0]) < 1 / 3, rng.uniform(3.0, 15.0, plan.shape[0]), 0.0)
    hold[0] = 0.0
    ne = np.vstack([plan[:1], plan, plan[-1:]])
    # the speed of the leg into each plan point: a change before one leg in three, then held
    speeds, v = [], np.nan
    for _ in range(plan.shape[0] - 1):
        if rng.random() < 1 / 3:
            v = float(cruise_ms * rng.uniform(0.5, 2.0))
        speeds.append(v)
    speed = np.array([np.nan, np.nan, *speeds, np.nan])
    return Route3D(ne, np.array([0.0, *alt, 0.0]), np.array([0.0, *hold, 0.0]), speed)


def simulate_route_run(predictor: Predictor, seed: int, cruise_ms: float | None = None) -> SimulatedRouteRun:
    """One simulated 3D run (see :class:`SimulatedRouteRun`), at ``cruise_ms`` (default the
    model's speed) with the predictor's vertical limits (a kinematic model's own, else
    ArduPilot's defaults) flown by the simulator too."""
    v = predictor.cruise_ms_ if cruise_ms is None else float(cruise_ms)
    rng = np.random.default_rng(seed)
    route = random_route(rng, v)
    speed, from_deg = float(rng.uniform(0.0, 8.0)), float(rng.uniform(0.0, 360.0))
    up, down, a_z = vertical_limits(predictor)
    vl = VerticalLimits(climb_ms=up, descent_ms=down, accel_z_ms2=a_z)
    truth = simulate_route(
        route,
        params=MultirotorParams(cruise_ms=v),
        wind=WindModel(speed_ms=speed, from_deg=from_deg),
        vertical=vl,
        seed=int(rng.integers(2**31)),
        dt=CALIBRATION_DT_S,
    )
    w_ne = wind_vector(speed, from_deg)
    pred = predict_route(predictor, route, w_ne, v)
    el = pred.elements
    # the truth at each element's end: crossing times of the horizontal stretches' arc length,
    # arrival at the top/bottom of a vertical move, departure after a hold
    stretch_of = {}
    for i, j, t0, tel in truth.stretches:
        s_true = arc_length_along(route.ne[i : j + 1], tel.pos_ne)
        total = float(np.hypot(*np.diff(route.ne[i : j + 1], axis=0).T).sum())
        for g in range(i, j):
            stretch_of[g] = (tel, s_true, t0, total)
    t_true = [0.0]
    for e in range(len(el)):
        g = int(el.segment[e])
        if el.kind[e] in ("leg", "turn"):
            tel, s_true, t0, total = stretch_of[g]
            # the vehicle stops at the stretch's end: "reached" within 0.5 m (position noise)
            target = min(float(el.stretch_s_end_m[e]), total - 0.5)
            t_true.append(t0 + float(crossing_times(tel.t, s_true, np.array([target]))[0]))
        elif el.kind[e] == "hover":
            t_true.append(float(truth.t_reached_s[g] + route.hold_s[g]))
        else:
            t_true.append(float(truth.t_reached_s[g + 1]))
    t_pred = np.concatenate([[0.0], np.cumsum(el.time_s)])
    return SimulatedRouteRun(
        route, w_ne, pred, t_pred, np.array(t_true), widening(el.time_s, el.flagged), truth
    )


def simulated_route_runs(
    predictor: Predictor,
    n_runs: int,
    seed: int = 0,
    progress: Callable[[int, int], None] | None = None,
    cruise_ms: float | None = None,
) -> list[SimulatedRouteRun]:
    """``n_runs`` 3D runs, run i from seed ``seed·100003 + i``. More runs than the work limit
    allows are refused up front (:func:`check_runs`)."""
    check_runs(n_runs)
    out = []
    for i in range(n_runs):
        out.append(simulate_route_run(predictor, seed * 100_003 + i, cruise_ms))
        if progress is not None:
            progress(i + 1, n_runs)
    return out


def calibrate(
    runs: Sequence[SimulatedRun | SimulatedRouteRun], tau_s: float = DEFAULT_TAU_S, source: str = ""
) -> TimeBounds:
    """Time bounds from calibration runs (one score per run)."""
    scores = np.array([score(r.t_true_s, r.t_pred_s, r.widening_s, tau_s) for r in runs])
    return TimeBounds(scores, tau_s, source or f"{len(runs)} simulated runs")


def covered(bounds: TimeBounds, run: SimulatedRun | SimulatedRouteRun, coverage: float) -> bool:
    """Whether the run's true times lie within the bounds at every element boundary."""
    lo, hi = bounds.band(run.t_pred_s, run.widening_s, coverage)
    return bool(np.all((run.t_true_s >= lo) & (run.t_true_s <= hi)))


__all__ = [
    "CALIBRATION_DT_S",
    "SimulatedRouteRun",
    "SimulatedRun",
    "calibrate",
    "covered",
    "random_plan",
    "random_route",
    "simulate_route_run",
    "simulate_run",
    "simulated_route_runs",
    "simulated_runs",
]
