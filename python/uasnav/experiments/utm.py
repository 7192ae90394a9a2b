"""UTM experiment: calibrated time bounds, an operational intent of a 3D mission, and
a deconfliction example with a resolved conflict.

1. **Time bounds.** The trajectory predictor of the Phantom-4 experiment is calibrated by
   split-conformal on ``n_cal`` simulated runs (random plans and winds,
   :mod:`uasnav.trajectory.calibration`); coverage is then counted on ``n_test`` held-out
   simulated runs (every element boundary at once) with a Clopper–Pearson interval.
2. **Intent.** A 3D mission (take-off, a survey pattern with a climb and a hold, return and
   landing) at a fictional site becomes an F3548 intent; the 3D truth is simulated
   (:func:`uasnav.trajectory.route_sim.simulate_route`) and checked against the volumes.
3. **Deconfliction.** A second mission crossing the first departs a little later; the index
   finds the conflict and the smallest departure delay that clears it, and the delayed
   intent is checked conflict-free.

:func:`real_coverage` counts, on real flights (a telemetry log with its mission), how many
runs the simulated calibration covers (k of n, Clopper–Pearson): the guarantee is for runs
like the calibration runs, real flights are a separate check.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime, timedelta, timezone

import numpy as np

from uasnav.io.mission_plan import HomePosition, MissionItem, MissionPlan, route_points
from uasnav.io.operational_intent import NamedIntent
from uasnav.trajectory.calibration import (
    SimulatedRouteRun,
    calibrate,
    covered,
    simulated_route_runs,
    simulated_runs,
)
from uasnav.trajectory.features import wind_vector
from uasnav.trajectory.models import Predictor
from uasnav.trajectory.route3d import Route3D, vertical_limits
from uasnav.trajectory.route_sim import simulate_route
from uasnav.trajectory.simulator import MultirotorParams, VerticalLimits, WindModel
from uasnav.trajectory.timebounds import clopper_pearson
from uasnav.utm.deconflict import Conflict, deconflict
from uasnav.utm.intent import IntentBuild, build_intent
from uasnav.utm.volumes import volume_arrays

#: The fictional site: 47.0° N, 8.0° E, home 450 m AMSL, geoid height 47.3 m.
SITE = (47.0, 8.0, 450.0)
GEOID_HEIGHT_M = 47.3
START = datetime(2026, 6, 1, 9, 0, tzinfo=timezone.utc)
WIND = (3.0, 60.0)  # m/s from 60°


@dataclass(frozen=True)
class Coverage:
    """Coverage of the time bounds on held-out runs.

    Attributes
    ----------
    coverage : float — nominal coverage.
    n_cal : int — calibration runs.
    k, n : int — held-out runs covered (every element boundary) and run.
    ci : (float, float) — Clopper–Pearson 95 % interval of k/n.
    quantile : float — the conformal quantile r₍ₖ₎ (relative half-width).
    eta_halfwidth_pct : float — median half-width of the ETA bound, % of the ETA.
    """

    coverage: float
    n_cal: int
    k: int
    n: int
    ci: tuple[float, float]
    quantile: float
    eta_halfwidth_pct: float


@dataclass(frozen=True)
class UtmResult:
    """Everything the report's UTM section shows."""

    coverage: Coverage
    mission: MissionPlan
    intent: IntentBuild
    truth_en: np.ndarray
    truth_t: np.ndarray
    contained: bool
    other_intent: IntentBuild
    conflict: Conflict | None
    conflicts_after_delay: int
    n_volumes: int
    truth_alt_w84: np.ndarray | None = None


def _item(cmd: int, e: float, n: float, alt: float, hold: float = 0.0) -> MissionItem:
    from uasnav.geo import frames

    lat, lon, _ = frames.enu_to_geodetic(e, n, 0.0, SITE[0], SITE[1], 0.0)
    return MissionItem(
        command=cmd, frame=3, params=(hold, 0.0, 0.0, 0.0), lat_deg=float(lat), lon_deg=float(lon), alt_m=alt
    )


def survey_mission() -> MissionPlan:
    """Take-off to 40 m, a four-leg survey (one leg climbing to 60 m, a 10 s hold), RTL."""
    items = (
        MissionItem(command=22, frame=3, alt_m=40.0),
        _item(16, 0.0, 120.0, 40.0),
        _item(16, 150.0, 120.0, 40.0, hold=10.0),
        _item(16, 150.0, 200.0, 60.0),
        _item(16, 0.0, 200.0, 60.0),
        MissionItem(command=20, frame=2),
    )
    return MissionPlan(
        items=items,
        home=HomePosition(SITE[0], SITE[1], SITE[2]),
        source="survey mission",
        hover_speed_ms=3.33,
    )


def crossing_mission() -> MissionPlan:
    """A transit crossing the survey east–west at 50 m, from a home 300 m east of it."""
    from uasnav.geo import frames

    lat, lon, _ = frames.enu_to_geodetic(300.0, 160.0, 0.0, SITE[0], SITE[1], 0.0)
    items = (
        MissionItem(command=22, frame=3, alt_m=50.0),
        _item(16, -150.0, 160.0, 50.0),
        _item(21, -150.0, 160.0, 0.0),
    )
    return MissionPlan(
        items=items,
        home=HomePosition(float(lat), float(lon), SITE[2]),
        source="crossing mission",
        hover_speed_ms=3.33,
    )


def time_bound_coverage(
    model: Predictor,
    n_cal: int,
    n_test: int,
    coverage: float = 0.95,
    seed: int = 0,
    progress: Callable[[int, int], None] | None = None,
) -> tuple[Coverage, list[SimulatedRouteRun]]:
    """Calibrate ``model.time_bounds_`` on ``n_cal`` simulated 3D runs (take-off, sloped legs,
    holds, landing: :func:`~uasnav.trajectory.calibration.simulated_route_runs`) and count
    coverage on ``n_test`` held-out ones."""
    cal = simulated_route_runs(model, n_cal, seed=2 * seed + 1, progress=progress)
    test = simulated_route_runs(model, n_test, seed=2 * seed + 2)
    model.time_bounds_ = calibrate(cal, source=f"{n_cal} simulated runs, seed {seed}")
    k = sum(covered(model.time_bounds_, r, coverage) for r in test)
    half = []
    for r in test:
        lo, hi = model.time_bounds_.band(r.t_pred_s[-1:], r.widening_s[-1:], coverage)
        half.append(50.0 * (hi[0] - lo[0]) / r.t_pred_s[-1])
    q = model.time_bounds_.quantile(coverage)
    cov = Coverage(
        coverage, n_cal, int(k), n_test, clopper_pearson(int(k), n_test), q, float(np.median(half))
    )
    return cov, test


def real_coverage(
    model: Predictor, path: str, coverage: float = 0.95, n_cal: int = 200, seed: int = 0
) -> tuple[int, int, tuple[float, float]]:
    """Runs of a real telemetry log (with its mission) whose element-boundary times all lie in
    bounds calibrated on ``n_cal`` simulated runs at the log's commanded speed: (k, n,
    Clopper–Pearson 95 %). Wind calm (the log has none). Boundaries beyond where the autopilot
    declared the last waypoint reached (it lands short) are not counted."""
    from uasnav.io import read_flight
    from uasnav.trajectory.geometry import arc_length_along
    from uasnav.trajectory.runs import flown_runs
    from uasnav.trajectory.samples import crossing_times
    from uasnav.trajectory.timebounds import widening

    log = read_flight(path)
    bounds = calibrate(simulated_runs(model, n_cal, seed=seed, cruise_ms=log.cruise_ms))
    k = n = 0
    for r in flown_runs(log):
        pred = model.predict(r.plan_ne, np.zeros(2), log.cruise_ms)
        el = pred.elements
        s_knots = np.concatenate([[el.s_start_m[0]], el.s_end_m])
        t_pred = np.concatenate([[0.0], np.cumsum(pred.time_s)])
        s = arc_length_along(r.plan_ne, r.pos_ne)
        s_end = float(np.interp(r.reached_t[-1], r.t, s))
        use = s_knots <= s_end
        t_true = crossing_times(r.t, s, s_knots[use]) - r.reached_t[0]
        lo, hi = bounds.band(t_pred[use], widening(pred.time_s, pred.low_confidence)[use], coverage)
        n += 1
        k += bool(np.all((t_true >= lo) & (t_true <= hi)))
    return k, n, clopper_pearson(k, n)


def _contained(b: IntentBuild, t: np.ndarray, en: np.ndarray, alt_w84: np.ndarray) -> bool:
    """Every sample (time s after start, east/north m, altitude m W84) inside a live volume."""
    import shapely

    polys = [shapely.Polygon(o) for o in b.volume_outline_en]
    for ti, p, z in zip(t, en, alt_w84, strict=True):
        pt = shapely.Point(p)
        if not any(
            lo <= ti <= hi and za <= z <= zb and poly.covers(pt)
            for poly, (lo, hi), (za, zb) in zip(polys, b.volume_time_s, b.volume_alt_w84, strict=True)
        ):
            return False
    return True


def run(
    model: Predictor,
    seed: int = 0,
    quick: bool = False,
    progress: Callable[[int, int], None] | None = None,
) -> UtmResult:
    """The experiment (see module); ``model`` gets calibrated time bounds."""
    n_cal, n_test = (25, 10) if quick else (200, 60)
    cov, _ = time_bound_coverage(model, n_cal, n_test, seed=seed, progress=progress)
    wind = wind_vector(*WIND)
    mission = survey_mission()
    b = build_intent(mission, model, wind, START, geoid_height_m=GEOID_HEIGHT_M)
    # truth: the survey flown in 3D by the simulator (take-off, legs, the climb, the hold,
    # return, landing) with the model's vertical limits
    pts = route_points(mission)
    route = Route3D(
        b.route_en[:, ::-1], b.route_alt_w84, np.array([p.hold_s for p in pts]), np.full(len(pts), np.nan)
    )
    # the same vertical limits as the intent's prediction (the model's own, else the defaults)
    up, down, a_z = vertical_limits(model)
    vl = VerticalLimits(climb_ms=up, descent_ms=down, accel_z_ms2=a_z)
    tr = simulate_route(
        route, params=MultirotorParams(cruise_ms=3.33), wind=WindModel(*WIND), vertical=vl, seed=seed
    )
    t_truth, truth_en, z_truth = tr.t, tr.pos_ne[:, ::-1], tr.alt_m
    contained = _contained(b, t_truth, truth_en, z_truth)
    other = crossing_mission()
    ob = build_intent(other, model, wind, START + timedelta(seconds=30), geoid_height_m=GEOID_HEIGHT_M)
    intents = [NamedIntent("survey", b.details), NamedIntent("crossing", ob.details)]
    res = deconflict(intents)
    conflict = res.conflicts[0] if res.conflicts else None
    after = 0
    if conflict is not None and conflict.delay_s is not None:
        v = volume_arrays(intents)
        later = v.names.index(conflict.later)
        after = len(deconflict(v.shifted(later, conflict.delay_s + 1e-3)).conflicts)
    return UtmResult(
        cov, mission, b, truth_en, t_truth, contained, ob, conflict, after, res.n_volumes, z_truth
    )


__all__ = [
    "Coverage",
    "UtmResult",
    "crossing_mission",
    "real_coverage",
    "run",
    "survey_mission",
    "time_bound_coverage",
]
