"""An ASTM F3548 operational intent from a mission plan and a calibrated trajectory prediction.

Steps:

1. The plan's 3D route (:func:`uasnav.io.mission_plan.route_points`): take-off climb, waypoints
   with hold times, landing descent; altitudes converted to WGS-84 ellipsoidal heights
   (:func:`uasnav.utm.altitude.w84_altitudes`).
2. Times: the route's 3D elements by :func:`uasnav.trajectory.route3d.predict_route` —
   horizontal legs and turns by the trajectory predictor (kinematic point mass by default, or
   LVQ), climbs and descents with the vertical limits (the kinematic model's own, from the
   vehicle's log, else ArduPilot's defaults ``WPNAV_SPEED_UP`` 2.5 m/s, ``WPNAV_SPEED_DN``
   1.5 m/s), a sloped leg no faster than its vertical limit allows, hovers for their hold
   time, ``DO_CHANGE_SPEED`` legs at their own speed.
3. Time bounds at the requested coverage (:mod:`uasnav.trajectory.timebounds`), widened by the
   predictor's flagged elements: the model's calibrated split-conformal band, or, from the
   vehicle's own runs (:func:`vehicle_run_bounds`), the Student-t prediction band of their log
   pace, which may open the first volume before the filed start.
4. Volumes: each leg is cut into pieces of at most ``piece_m`` metres; a piece's volume is the
   piece's segment grown by the lateral buffer (a polygon with round caps; a circle for a
   vertical-only piece), between its lowest and highest altitude ∓ the vertical buffer, alive
   from the lower time bound at its start to the upper bound at its end (holds included). A
   vehicle whose arrival times lie within the band and whose path stays within the lateral
   buffer of the plan is therefore inside some volume at every instant.

The default buffers come from navigation accuracy: lateral 15 m (GNSS 95 % horizontal
≈ 5 m plus a multirotor's flight technical error ≈ 10 m), vertical 10 m (barometric/GNSS
altitude hold). The conformal guarantee covers the horizontal timing as calibrated; climb,
descent and hold times are predicted deterministically and carried inside the same band.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime, timedelta
from typing import Any

import numpy as np

from uasnav.errors import InputError
from uasnav.io.mission_plan import ItemKind, MissionPlan, RoutePoint, plan_cruise_speed, route_points
from uasnav.io.operational_intent import parse_details, rfc3339
from uasnav.trajectory.models import Predictor
from uasnav.trajectory.route3d import Route3D, RoutePrediction, predict_route, vertical_limits
from uasnav.trajectory.timebounds import DEFAULT_COVERAGE, DEFAULT_TAU_S, PaceBounds
from uasnav.utm.altitude import w84_altitudes

DEFAULT_LATERAL_BUFFER_M = 15.0
DEFAULT_VERTICAL_BUFFER_M = 10.0
DEFAULT_PIECE_M = 100.0
#: Shortest volume, s (a volume must end after it starts).
MIN_VOLUME_S = 1.0
#: Horizontal distance (m) below which two route points are one place.
SAME_PLACE_M = 0.01


@dataclass(frozen=True)
class IntentBuild:
    """An operational intent and the prediction it was made from.

    Attributes
    ----------
    details : uas_standards OperationalIntentDetails — the intent (checked).
    start : datetime — departure time (UTC).
    origin : (lat_deg, lon_deg) — the local ENU plane of the arrays below.
    route_en : ndarray, shape (n, 2) — route points, east/north m.
    route_alt_w84 : ndarray, shape (n,) — their altitudes, m W84.
    t_arrive_s, t_lo_s, t_hi_s : ndarray, shape (n,) — predicted arrival at each point and its
        bounds, s after ``start`` (the bounds of the departure after a hold for ``t_hi_s``).
    eta_s : float — predicted mission time, s; ``eta_bounds_s`` its bounds.
    volume_outline_en : list of ndarray (k, 2) — each volume's outline, east/north m.
    volume_alt_w84, volume_time_s : ndarray, shape (v, 2) — altitude (m W84) and time (s after
        ``start``) ranges of each volume.
    coverage : float
    flags : list of list of str — the predictor's flags per horizontal element.
    route_prediction : RoutePrediction or None — the 3D elements (legs, turns, climbs,
        descents, hovers) and their times.
    time_bounds_source : str — what calibrated the time bounds: the vehicle's own flights
        (``trajectory calibrate --flights``) or simulated runs.
    """

    details: Any
    start: datetime
    origin: tuple[float, float]
    route_en: np.ndarray
    route_alt_w84: np.ndarray
    t_arrive_s: np.ndarray
    t_lo_s: np.ndarray
    t_hi_s: np.ndarray
    eta_s: float
    eta_bounds_s: tuple[float, float]
    volume_outline_en: list[np.ndarray]
    volume_alt_w84: np.ndarray
    volume_time_s: np.ndarray
    coverage: float
    flags: list[list[str]]
    route_prediction: RoutePrediction | None = None
    time_bounds_source: str = ""


def _positive(x: float, name: str) -> float:
    if not (math.isfinite(x) and x > 0):
        raise InputError(f"{name} must be finite and > 0, got {x!r}")
    return float(x)


def _predict_plan(
    plan: MissionPlan,
    predictor: Predictor,
    wind_ne: np.ndarray,
    *,
    geoid_height_m: float | None,
    home_amsl_m: float | None,
    climb_ms: float,
    descent_ms: float,
    accel_z_ms2: float,
    cruise_ms: float | None,
) -> tuple[list[RoutePoint], np.ndarray, np.ndarray, RoutePrediction]:
    """The plan's route points, their east/north (m, from the first point) and W84 heights,
    and the predictor's times along the route."""
    from uasnav.geo import frames

    pts: list[RoutePoint] = route_points(plan)
    for p in pts:
        if not math.isfinite(p.hold_s):
            what = "an unlimited loiter" if p.hold_s == math.inf else "a loiter of N turns (time unknown)"
            raise InputError(f"{plan.source}: item {p.item}: {what} has no predictable end")
    home = (
        home_amsl_m if home_amsl_m is not None else (plan.home.alt_amsl_m if plan.home is not None else None)
    )
    z = w84_altitudes(pts, home_amsl_m=home, geoid_height_m=geoid_height_m, source=plan.source)
    lat = np.array([p.lat_deg for p in pts])
    lon = np.array([p.lon_deg for p in pts])
    e, n, _ = frames.geodetic_to_enu(lat, lon, 0.0, float(lat[0]), float(lon[0]), 0.0)
    en = np.column_stack([e, n])
    v_ref = float(cruise_ms or plan_cruise_speed(plan) or predictor.cruise_ms_)
    # DO_CHANGE_SPEED: the leg into a point flies the latest speed set before that point,
    # unless the caller fixed the speed (cruise_ms)
    speeds = np.full(len(pts), np.nan)
    if cruise_ms is None:
        v = np.nan
        for i, p in enumerate(pts):
            v = p.speed_ms if p.speed_ms is not None and i > 0 else v
            speeds[i] = v
    route = Route3D(en[:, ::-1], z, np.array([p.hold_s for p in pts]), speeds)
    rp = predict_route(
        predictor,
        route,
        np.asarray(wind_ne, dtype=float),
        v_ref,
        climb_ms=climb_ms,
        descent_ms=descent_ms,
        accel_z_ms2=accel_z_ms2,
    )
    return pts, en, z, rp


def vehicle_run_bounds(
    logs: Sequence[Any],
    predictor: Predictor,
    wind_ne: np.ndarray,
    *,
    climb_ms: float | None = None,
    descent_ms: float | None = None,
    accel_z_ms2: float | None = None,
    cruise_ms: float | None = None,
    tau_s: float = DEFAULT_TAU_S,
) -> PaceBounds:
    """Time bounds of ``predictor`` from the vehicle's own earlier flights: for every AUTO run
    of each log (:func:`uasnav.trajectory.mission_runs.mission_runs`), its true and predicted
    times (s from the run's start) at the items it reached and at its touch-down (a land item
    counts at the touch-down), with the predictor's times for the log's own plan (``runs`` of
    the result); the bounds are the Student-t prediction bounds of each run's slowest and
    fastest log pace ratio (:class:`uasnav.trajectory.timebounds.PaceBounds`), which follow the
    vehicle's own bias and hold from few runs under their stated assumption; ``describe`` adds
    the leave-one-run-out check.

    Raises
    ------
    InputError
        A log without a mission or without an AUTO run that reaches an item; fewer runs than
        :data:`uasnav.trajectory.timebounds.MIN_PACE_RUNS` at the first use of the bounds.
    """
    from pathlib import Path

    from uasnav.io.logfile import LogFile, open_log
    from uasnav.trajectory.mission_runs import MISSION_VIEWS, mission_runs

    up, down, a_z = vertical_limits(predictor, climb_ms, descent_ms, accel_z_ms2)
    runs: list[tuple[np.ndarray, np.ndarray]] = []
    names: list[str] = []
    for item in logs:
        log = item if isinstance(item, LogFile) else open_log(item, need=MISSION_VIEWS)
        plan = log.plan
        pts, _, _, rp = _predict_plan(
            plan, predictor, wind_ne, geoid_height_m=0.0, home_amsl_m=None, climb_ms=up, descent_ms=down,
            accel_z_ms2=a_z, cruise_ms=cruise_ms,
        )  # fmt: skip
        eta = float(rp.t_depart_s[-1])
        pred: dict[int, float] = {}
        for k, p in enumerate(pts):
            if p.item is not None and p.item not in pred:
                pred[p.item] = eta if p.kind is ItemKind.LAND else float(rp.t_arrive_s[k])
        for run in mission_runs(log, plan):
            pairs = [(t, pred[i]) for i, t in run.reached if i in pred]
            if run.landed:
                pairs.append((run.duration_s, eta))
            if pairs:
                runs.append((np.array([t for t, _ in pairs]), np.array([p for _, p in pairs])))
        names.append(Path(str(log.path)).name)
    if not runs:
        raise InputError("no AUTO run of the vehicle reaches an item of its mission")
    return PaceBounds.of_runs(runs, tau_s, f"{len(runs)} AUTO runs of the vehicle ({', '.join(names)})")


def build_intent(
    plan: MissionPlan,
    predictor: Predictor,
    wind_ne: np.ndarray,
    start: datetime,
    *,
    coverage: float = DEFAULT_COVERAGE,
    lateral_buffer_m: float = DEFAULT_LATERAL_BUFFER_M,
    vertical_buffer_m: float = DEFAULT_VERTICAL_BUFFER_M,
    geoid_height_m: float | None = None,
    home_amsl_m: float | None = None,
    climb_ms: float | None = None,
    descent_ms: float | None = None,
    accel_z_ms2: float | None = None,
    piece_m: float = DEFAULT_PIECE_M,
    cruise_ms: float | None = None,
    priority: int = 0,
) -> IntentBuild:
    """The operational intent of ``plan`` departing at ``start`` (see module).

    Parameters
    ----------
    plan : MissionPlan
    predictor : KinematicPredictor or TrajectoryPredictor — fitted, with calibrated ``time_bounds_``.
    wind_ne : ndarray, shape (2,) — wind velocity (m/s, toward north/east).
    start : datetime — departure, time-zone aware.
    coverage : float — coverage of the time bounds.
    lateral_buffer_m, vertical_buffer_m : float — buffers around the path, m.
    geoid_height_m : float — geoid height N at the site, m (W84 = AMSL + N); required.
    home_amsl_m : float, optional — home altitude AMSL, m (default the plan's).
    climb_ms, descent_ms, accel_z_ms2 : float, optional
        Vertical speed (m/s) and acceleration (m/s²) limits; default the predictor's own (a
        kinematic model's, from the vehicle's log), else ArduPilot's defaults
        (:func:`uasnav.trajectory.route3d.vertical_limits`).
    piece_m : float — longest piece of a leg per volume, m.
    cruise_ms : float, optional — horizontal speed (default the plan's, else the model's).
    priority : int — F3548 priority.
    """
    import shapely

    from uasnav.geo import frames

    bounds = getattr(predictor, "time_bounds_", None)
    if bounds is None:
        raise InputError(
            "the model has no calibrated time bounds: run `uasnav trajectory calibrate` on it first"
        )
    if start.tzinfo is None:
        raise InputError("start time needs a time zone")
    for name, x in (("lateral buffer", lateral_buffer_m), ("piece length", piece_m)):
        _positive(x, name)
    up, down, a_z = vertical_limits(predictor, climb_ms, descent_ms, accel_z_ms2)
    if not (math.isfinite(vertical_buffer_m) and vertical_buffer_m >= 0):
        raise InputError(f"vertical buffer must be finite and ≥ 0, got {vertical_buffer_m!r}")
    bounds.quantile(coverage)  # refuses a coverage the calibration cannot give
    pts, en, z, rp = _predict_plan(
        plan, predictor, wind_ne, geoid_height_m=geoid_height_m, home_amsl_m=home_amsl_m, climb_ms=up,
        descent_ms=down, accel_z_ms2=a_z, cruise_ms=cruise_ms,
    )  # fmt: skip
    lat0, lon0 = float(pts[0].lat_deg), float(pts[0].lon_deg)
    step = np.hypot(*np.diff(en, axis=0).T)
    flags = [f for f, k in zip(rp.elements.flags, rp.elements.kind, strict=True) if k in ("leg", "turn")]
    m = len(pts)
    t_arr, t_dep, w = rp.t_arrive_s, rp.t_depart_s, rp.w_arrive_s
    lo_arr, _ = bounds.band(t_arr, w, coverage)
    _, hi_dep = bounds.band(t_dep, rp.w_depart_s, coverage)
    outlines: list[np.ndarray] = []
    alts, times, vols = [], [], []
    for i in range(m - 1):
        dh = float(step[i])
        seg = t_arr[i + 1] - t_dep[i]
        k = max(1, math.ceil(dh / piece_m))
        for j in range(k):
            a, b = j / k, (j + 1) / k
            pa, pb = en[i] + a * (en[i + 1] - en[i]), en[i] + b * (en[i + 1] - en[i])
            za, zb = z[i] + a * (z[i + 1] - z[i]), z[i] + b * (z[i + 1] - z[i])
            wa, wb = w[i] + a * (w[i + 1] - w[i]), w[i] + b * (w[i + 1] - w[i])
            ta = t_arr[i] if j == 0 else t_dep[i] + a * seg
            tb = t_dep[i + 1] if j == k - 1 else t_dep[i] + b * seg
            t_lo = float(bounds.band(np.array([ta]), wa, coverage)[0][0])
            t_hi = float(bounds.band(np.array([tb]), wb, coverage)[1][0])
            t_hi = max(t_hi, t_lo + MIN_VOLUME_S)
            alt = (min(za, zb) - vertical_buffer_m, max(za, zb) + vertical_buffer_m)
            if dh > SAME_PLACE_M:
                poly = shapely.LineString([pa, pb]).buffer(lateral_buffer_m, quad_segs=4)
                ring = np.asarray(poly.exterior.coords)[:-1]
                la, lo_, _ = frames.enu_to_geodetic(ring[:, 0], ring[:, 1], 0.0, lat0, lon0, 0.0)
                outline: dict[str, Any] = {
                    "outline_polygon": {
                        "vertices": [{"lat": float(x), "lng": float(y)} for x, y in zip(la, lo_, strict=True)]
                    }
                }
                outlines.append(ring)
            else:
                la, lo_, _ = frames.enu_to_geodetic(pa[0], pa[1], 0.0, lat0, lon0, 0.0)
                outline = {
                    "outline_circle": {
                        "center": {"lat": float(la), "lng": float(lo_)},
                        "radius": {"value": float(lateral_buffer_m), "units": "M"},
                    }
                }
                ang = np.linspace(0, 2 * np.pi, 33)[:-1]
                outlines.append(pa + lateral_buffer_m * np.column_stack([np.cos(ang), np.sin(ang)]))
            vols.append(
                {
                    "volume": {
                        **outline,
                        "altitude_lower": {"value": float(alt[0]), "reference": "W84", "units": "M"},
                        "altitude_upper": {"value": float(alt[1]), "reference": "W84", "units": "M"},
                    },
                    "time_start": {"value": rfc3339(start + timedelta(seconds=t_lo)), "format": "RFC3339"},
                    "time_end": {"value": rfc3339(start + timedelta(seconds=t_hi)), "format": "RFC3339"},
                }
            )
            alts.append(alt)
            times.append((t_lo, t_hi))
    details = parse_details({"volumes": vols, "off_nominal_volumes": [], "priority": int(priority)}, "intent")
    eta = float(t_dep[-1])
    eta_lo, eta_hi = bounds.band(np.array([eta]), rp.w_depart_s[-1], coverage)
    return IntentBuild(
        details=details,
        start=start,
        origin=(lat0, lon0),
        route_en=en,
        route_alt_w84=z,
        t_arrive_s=t_arr,
        t_lo_s=lo_arr,
        t_hi_s=hi_dep,
        eta_s=eta,
        eta_bounds_s=(float(eta_lo[0]), float(eta_hi[0])),
        volume_outline_en=outlines,
        volume_alt_w84=np.array(alts).reshape(-1, 2),
        volume_time_s=np.array(times).reshape(-1, 2),
        coverage=coverage,
        flags=flags,
        route_prediction=rp,
        time_bounds_source=bounds.describe(coverage),
    )


__all__ = [
    "DEFAULT_LATERAL_BUFFER_M",
    "DEFAULT_PIECE_M",
    "DEFAULT_VERTICAL_BUFFER_M",
    "IntentBuild",
    "build_intent",
    "vehicle_run_bounds",
]
