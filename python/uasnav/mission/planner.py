"""From a field to a filed authorisation: one request through every part (``uasnav plan``).

Pipeline: the selection ranks UAS + camera for this area (:func:`uasnav.mission.selection.select`,
pilot distance from the area and the pilot's position) → a survey plan for the chosen pair
(:mod:`uasnav.mission.survey`: height, lines, triggers, speed, flights) → each flight's time
predicted with its calibrated bounds (:func:`uasnav.trajectory.route3d.predict_route` through
:func:`uasnav.utm.intent.build_intent`) → one ASTM F3548 operational intent per flight → the
ED-269 zones over the flight window the prediction gives, and strategic deconfliction against
the given intents (with the departure delay that clears each conflict) → the authorisation
summary.

:func:`plan` returns a :class:`PlanResult`: ``result`` is the ``result.json`` document and
``files`` every file ``uasnav plan --out DIR`` writes (name → bytes), written all or nothing
by :func:`write_outputs`.
"""

from __future__ import annotations

import datetime as dt
import functools
import json
import math
import os
import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from uasnav.errors import InputError
from uasnav.jsonable import to_jsonable
from uasnav.mission.request import OptionError, Upload, parse_select_options
from uasnav.mission.survey import Camera, SurveyPlan, flight_plan, plan_survey

#: Time between two flights of a survey (land, change the battery, take off), s.
DEFAULT_TURNAROUND_S = 600.0
#: Coverage of the time bounds of the intents.
COVERAGE = 0.95
#: Simulated 3D runs the built-in predictor's time bounds are calibrated on (≥ 19 for 95 %).
CALIBRATION_RUNS = 40
#: Ground elevation taken when none is given, m AMSL (stated in the output).
DEFAULT_GROUND_ELEVATION_M = 0.0
#: Farthest a plan's home position may be from the take-off point (m) for its altitude to be
#: taken as the take-off ground's.
HOME_AS_TAKEOFF_M = 100.0
#: Spread of an area's ground heights (m) beyond which the flat-field assumption is flagged.
FLAT_SPREAD_M = 10.0
#: Files written per flight (``{k:02d}`` is the flight number).
FLIGHT_FILES = ("flight-{k:02d}.plan", "flight-{k:02d}.waypoints", "flight-{k:02d}.intent.json")

#: Options of ``uasnav plan`` besides the selector's (:data:`SELECT_OPTIONS`): name → help.
PLAN_OPTIONS: dict[str, str] = {
    "overlap": "Front and side overlap of the photos, FRONT,SIDE in % or fractions (default 75,65).",
    "intents": "Operational intents of other operators to deconflict with (F3548 JSON or InterUSS "
    "flight-intent YAML).",
    "start": "Take-off time of the first flight, ISO 8601 with a zone (2026-05-01T10:00Z).",
    "turnaround": "Time between two flights (landing, battery change, take-off), s.",
}


@dataclass
class FlightResult:
    """One flight of the survey: its plan, prediction and intent."""

    number: int
    plan: Any  # MissionPlan
    intent: Any  # IntentBuild
    start: dt.datetime
    photos: int
    lines: int
    estimated_s: float

    @property
    def name(self) -> str:
        return f"flight-{self.number:02d}"

    def to_dict(self) -> dict[str, Any]:
        b = self.intent
        return {
            "name": self.name,
            "start": b.start.isoformat(),
            "eta_s": b.eta_s,
            "eta_bounds_s": list(b.eta_bounds_s),
            "end_latest": (b.start + dt.timedelta(seconds=b.eta_bounds_s[1])).isoformat(),
            "photos": self.photos,
            "lines": self.lines,
            "volumes": len(b.details.volumes),
            "files": [f.format(k=self.number) for f in FLIGHT_FILES],
        }


@dataclass
class PlanResult:
    """What :func:`plan` returns: ``result`` (the ``result.json`` document), ``files`` (name →
    bytes, every file of the output directory), the selection, the survey and the flights."""

    result: dict[str, Any]
    files: dict[str, bytes]
    selection: Any
    survey: SurveyPlan | None
    flights: list[FlightResult] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """The ``result.json`` document."""
        return self.result

    def __getitem__(self, key: str) -> Any:
        return self.result[key]

    def keys(self):
        return self.result.keys()


_LOCK = threading.Lock()


#: Speeds (m/s) the shipped survey models are calibrated at (``data/survey_models.json``).
MODEL_SPEEDS = (3.0, 5.0, 7.0, 9.0, 11.0, 13.0, 15.0)
#: The shipped survey models: the built-in kinematic predictor with its time bounds calibrated
#: at each of :data:`MODEL_SPEEDS` (regenerate with ``scripts/make_survey_models.py``).
MODELS_FILE = Path(__file__).parent / "data" / "survey_models.json"


def build_predictor(speed_ms: float, runs: int = CALIBRATION_RUNS) -> Any:
    """The built-in survey predictor at ``speed_ms``: the kinematic point mass (the default
    method) fitted on the thesis' two Phantom-4 trajectories simulated in calm air and in a
    5 m/s wind, its time bounds calibrated (split-conformal) on ``runs`` simulated 3D runs
    (take-off, sloped legs, holds, landing) flown at ``speed_ms``. Deterministic."""
    import warnings

    from uasnav.trajectory.calibration import calibrate, simulated_route_runs
    from uasnav.trajectory.models import make_predictor
    from uasnav.trajectory.samples import ElementSamples, measure_elements
    from uasnav.trajectory.simulator import MultirotorParams, WindModel, phantom4_plans, simulate_flight

    parts = []
    for k, plan_ne in enumerate(phantom4_plans().values()):
        for w, (speed, from_deg) in enumerate(((0.0, 0.0), (5.0, 200.0))):
            tel = simulate_flight(
                plan_ne,
                params=MultirotorParams(cruise_ms=speed_ms),
                wind=WindModel(speed_ms=speed, from_deg=from_deg),
                seed=10 * k + w,
            )
            _, s = measure_elements(
                tel.plan_ne, tel.t, tel.pos_ne, tel.vel_ne, tel.wind_ne, tel.cruise_ms, flight=2 * k + w
            )
            parts.append(s)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=UserWarning)
        model = make_predictor("kinematic").fit(ElementSamples.concat(parts))
    cal = simulated_route_runs(model, runs, seed=0, cruise_ms=speed_ms)
    model.time_bounds_ = calibrate(cal, source=f"{runs} simulated 3D runs at {speed_ms:g} m/s, seed 0")
    return model


@functools.lru_cache(maxsize=1)
def _shipped() -> dict[str, Any]:
    from uasnav import jsoncheck as jc

    with jc.reraise_in(str(MODELS_FILE)):
        return jc.obj(jc.parse(MODELS_FILE.read_text(), "invalid JSON"), "")


@functools.lru_cache(maxsize=16)
def _predictor_at(speed_key: float) -> Any:
    from uasnav.trajectory.models import model_from_dict

    if MODELS_FILE.exists():
        models = _shipped()["models"]
        nearest = min(models, key=lambda k: abs(float(k) - speed_key))
        return model_from_dict(models[nearest], source=f"{MODELS_FILE.name}[{nearest}]")
    return build_predictor(speed_key)


def survey_predictor(speed_ms: float) -> Any:
    """The trajectory model a survey flown at ``speed_ms`` is timed with: the shipped model
    calibrated at the nearest of :data:`MODEL_SPEEDS` (:func:`build_predictor`)."""
    with _LOCK:
        return _predictor_at(round(float(speed_ms), 1))


def parse_overlap(value: Any) -> tuple[float, float]:
    """``"75,65"`` (percent), ``"0.75,0.65"`` or a pair → (front, side) fractions in [0, 0.95]."""
    if value is None or value == "":
        from uasnav.mission.survey import DEFAULT_OVERLAP

        return DEFAULT_OVERLAP
    parts: Any = value.split(",") if isinstance(value, str) else value
    try:
        if not isinstance(parts, list | tuple) or len(parts) != 2:
            raise ValueError
        f, s = float(parts[0]), float(parts[1])
    except (TypeError, ValueError):
        raise OptionError("overlap", f"overlap: expected FRONT,SIDE (e.g. 75,65), got {value!r}") from None
    if f > 1.0 or s > 1.0:
        f, s = f / 100.0, s / 100.0
    if not (math.isfinite(f) and math.isfinite(s) and 0.0 <= f <= 0.95 and 0.0 <= s <= 0.95):
        raise OptionError("overlap", f"overlap: each must be within 0–95 %, got {value!r}")
    return f, s


def _read_intents(items: Sequence[Any], now: dt.datetime) -> list[Any]:
    """Intents of other operators: paths, or :class:`Upload` documents (JSON, or InterUSS
    flight-intent YAML whose times are resolved at ``now``). Volumes that ended before the
    survey are not refused: they cannot conflict with it."""
    from uasnav import jsoncheck as jc
    from uasnav.io.interuss import read_flight_intents, resolve_flight_intents
    from uasnav.io.operational_intent import parse_intents, read_intents

    found = []
    for it in items:
        if isinstance(it, Upload):
            name = it.name
            if name.lower().endswith((".yaml", ".yml")):
                import yaml

                try:
                    data = yaml.safe_load(it.data.decode("utf-8"))
                except (yaml.YAMLError, UnicodeDecodeError) as e:
                    raise InputError(f"{name}: not a flight-intent YAML document ({e})") from None
                found += resolve_flight_intents(data, name, now)
            else:
                with jc.reraise_in(name):
                    d = jc.parse(
                        it.data.decode("utf-8", "replace"), "not an operational intent: not valid JSON"
                    )
                found += parse_intents(d, name, os.path.splitext(os.path.basename(name))[0])
        else:
            p = os.fspath(it)
            found += read_flight_intents(p, now) if p.lower().endswith((".yaml", ".yml")) else read_intents(p)
    return found


def _field_polygon(area: Any, lat0: float, lon0: float) -> Any:
    """The field to photograph in the local east/north frame about the take-off point: the
    area's polygons (a plan's route: its convex hull)."""
    g = area.local(lon0, lat0)
    if g.geom_type not in ("Polygon", "MultiPolygon") or g.area <= 0:
        g = g.convex_hull
    if g.geom_type == "MultiPolygon":
        g = g.convex_hull
    if g.geom_type != "Polygon" or g.area <= 0:
        raise InputError(f"{area.where}: the survey area needs a surface (a polygon, or a plan with an area)")
    return g


def plan(options: Mapping[str, Any] | None = None, /, **kw: Any) -> PlanResult:
    """Plan a survey of an area and everything its authorisation needs (see module).

    Parameters
    ----------
    options, **kw
        Options by snake_case name: every selector option (:data:`SELECT_OPTIONS`; ``area`` is
        required: GeoJSON, KML or a mission plan, as a path, its text/bytes, a parsed object or
        an :class:`~uasnav.mission.request.Upload`) plus ``overlap`` (``"75,65"``), ``intents``
        (paths or uploads), ``start`` (ISO 8601, or a datetime; default: the next full hour)
        and ``turnaround`` (s between flights). ``altitude`` is an upper bound on the survey
        height (the resolution sets it otherwise).

    Returns
    -------
    PlanResult

    Raises
    ------
    OptionError
        A bad option (``.option`` names it).
    InputError
        Nothing can fly it, or an input file is unreadable.
    """
    values: dict[str, Any] = {**(options or {}), **kw}
    overlap = parse_overlap(values.pop("overlap", None))
    intents_in = values.pop("intents", None) or ()
    if isinstance(intents_in, str | os.PathLike | Upload):
        intents_in = (intents_in,)
    start_v = values.pop("start", None)
    turnaround = values.pop("turnaround", None)
    turnaround = DEFAULT_TURNAROUND_S if turnaround in (None, "") else float(turnaround)
    if not (math.isfinite(turnaround) and turnaround >= 0):
        raise OptionError(
            "turnaround", f"turnaround: must be a finite number of seconds >= 0, got {turnaround!r}"
        )
    if values.get("area") is None:
        raise OptionError("area", "area: give the field to survey (GeoJSON, KML or a plan)")
    altitude_given = values.get("altitude") not in (None, "")
    for name in ("area", "zones"):
        v = values.get(name)
        if isinstance(v, os.PathLike) or (isinstance(v, str) and not v.lstrip().startswith(("{", "<"))):
            from uasnav.mission.request import read_file_option

            values[name] = read_file_option(name, os.fspath(v))
    if start_v is None or start_v == "":
        start_v = values.get("flight_time")
    if isinstance(start_v, dt.datetime):
        if start_v.tzinfo is None:
            raise OptionError("start", "start: the take-off time needs a time zone")
        start = start_v.astimezone(dt.timezone.utc)
    elif start_v is None or start_v == "":
        now = dt.datetime.now(dt.timezone.utc)
        start = (now + dt.timedelta(hours=1)).replace(minute=0, second=0, microsecond=0)
    else:
        from uasnav.mission.zones import parse_when

        try:
            start = parse_when(str(start_v))
        except InputError as e:
            raise OptionError("start", f"start: {e}") from None
    values["flight_time"] = start.isoformat()
    request = parse_select_options({k: v for k, v in values.items() if k != "altitude" or v is not None})
    req = request.requirements
    from uasnav.mission.regulations import load_regulations
    from uasnav.mission.selection import select

    regs = load_regulations()
    # A survey is a mosaic: the resolution is reached by flying at the height that gives it;
    # the height checked by the regulations is the operator's ceiling or the legal maximum.
    legal = _legal_height(regs, req)
    req = replace(req, mosaic=True, altitude_m=req.altitude_m if altitude_given else legal)
    assert request.area is not None and request.takeoff is not None and request.pilot is not None
    area = request.area
    lat0, lon0 = request.takeoff
    sel_kw = dict(targets=request.targets, weights=request.weights, top=request.top, regulations=regs)
    sel = select(req, **sel_kw)
    if sel.chosen is None:
        return _no_plan(sel, request)
    best = sel.chosen
    u = sel.database.uas
    i = u.ids.index(best.uas_id)
    j = sel.database.cameras.ids.index(best.camera_id)
    camera = Camera.from_table(sel.database.cameras, j)
    cruise = req.cruise_fraction * float(u.max_speed_ms[i])
    endurance = float(u.endurance_min[i]) * 60.0 * (1.0 - req.reserve)
    field_en = _field_polygon(area, lat0, lon0)
    sp = plan_survey(
        field_en,
        camera,
        resolution_m=req.resolution_m,
        origin=(lat0, lon0),
        altitude_m=req.altitude_m if altitude_given else None,
        legal_max_m=legal,
        overlap=overlap,
        cruise_ms=cruise,
        endurance_s=endurance,
    )
    ground_info = ground_datum(req.ground_elevation_m, area, lat0, lon0)
    ground = ground_info["elevation_m"]
    if ground_info["assumed"]:
        sp.assumptions.append(
            f"ground elevation not known ({ground_info['source'].removeprefix('assumed: ')}): the take-off "
            f"point is taken at {ground:g} m AMSL, so the intents' WGS-84 altitudes are {ground:g} m + "
            f"height + geoid height ({ground_info['geoid_height_m']:.1f} m here); give --ground-elevation "
            "(m AMSL) before filing"
        )
    if ground_info.get("spread_m", 0.0) > FLAT_SPREAD_M:
        sp.assumptions.append(
            f"the area's heights span {ground_info['spread_m']:.0f} m: the survey's heights are above the "
            f"take-off point and the ground is taken at their mean, {ground:.0f} m AMSL; on ground this "
            "uneven the resolution and the overlaps vary with it"
        )
    model = survey_predictor(sp.speed_ms)
    from uasnav.trajectory.features import wind_vector
    from uasnav.utm.intent import build_intent

    wind_from = request.wind_from_deg
    if wind_from is None:
        wind_from = 0.0
        sp.assumptions.append("wind direction not given: taken from the north (the time bounds cover it)")
    wind = wind_vector(req.wind_ms, wind_from)
    flights: list[FlightResult] = []
    t = start
    for k in range(len(sp.flights)):
        mp = flight_plan(sp, k, home_amsl_m=ground, name="survey")
        b = build_intent(mp, model, wind, t, coverage=COVERAGE, priority=0)
        flights.append(
            FlightResult(
                k + 1,
                mp,
                b,
                t,
                sum(ln.photos for ln in sp.flights[k]),
                len(sp.flights[k]),
                sp.estimated_time_s[k],
            )
        )
        t = t + dt.timedelta(seconds=b.eta_bounds_s[1] + turnaround)
    end_latest = t - dt.timedelta(seconds=turnaround)
    total_s = (end_latest - start).total_seconds()
    # The answer at the height the survey flies (operation, SORA, zones' vertical band) and over
    # the predicted window (take-off of the first flight to the latest end of the last); kept
    # only if the same configuration still ranks first, else the first pass's heights stand.
    zone_kw: dict[str, Any] = (
        dict(area=area, zones=request.zones, zones_source=request.zones_source, when=start)
        if request.zones is not None
        else {}
    )
    # The UA flies past the area on its run-ins and run-outs: the operation's distances are the
    # route's when it reaches farther than the area (unless the operator typed them).
    assert request.distances is not None
    distances, farther = route_distances(sp, request.distances, lat0, lon0)
    if "max_distance_m" in farther and req.max_distance_m == request.distances["pilot_distance_m"]:
        req = replace(req, max_distance_m=farther["max_distance_m"], max_distance_source=ROUTE_DISTANCE_WORDS)
    if "range_m" in farther and req.range_m == request.distances["range_m"]:
        req = replace(req, range_m=farther["range_m"])
    flown = replace(
        req, altitude_m=math.ceil(sp.altitude_m * 10.0) / 10.0, flight_duration_s=max(total_s, 1.0)
    )
    again = select(flown, **sel_kw, **zone_kw)
    pick = again.chosen or (again.withheld[0] if again.withheld else None)
    if pick is None or (pick.uas_id, pick.camera_id) != (best.uas_id, best.camera_id):
        again = select(replace(req, flight_duration_s=max(total_s, 1.0)), **sel_kw, **zone_kw)
    sel = again
    if sel.chosen is None:
        # the zones over the flight's window leave nothing to rank (a PROHIBITED zone withholds
        # every configuration): no flight is planned, and none of its files is offered
        return _no_plan(sel, request)
    if sel.flight_window is not None:
        sel.flight_window["from"] = "predicted flight time of the survey (upper bounds, turnarounds included)"
    conflicts = _deconflict(flights, _read_intents(list(intents_in), dt.datetime.now(dt.timezone.utc)))
    result = _result(sel, best, sp, flights, conflicts, request, start, total_s, overlap, ground_info)
    result["distances"] = distances
    files = _files(sel, sp, flights, result)
    return PlanResult(result, files, sel, sp, flights)


#: Where the operation's pilot distance comes from when the flown route reaches past the area.
ROUTE_DISTANCE_WORDS = "the planned route's farthest point from the pilot position"


def route_distances(
    sp: SurveyPlan, area_distances: dict[str, Any], lat0: float, lon0: float
) -> tuple[dict[str, Any], dict[str, float]]:
    """The distances of the flown survey: the farthest any line point (run-in and run-out ends
    included) is from the pilot and from the take-off point (``lat0``, ``lon0``, the survey's
    origin), against the area's (:func:`uasnav.mission.request.area_distances`).

    Returns the ``distances`` block of the result — the area's, with ``route_pilot_distance_m``,
    ``route_range_m``, ``area_pilot_distance_m``, and ``pilot_distance_m``/``range_m`` the larger
    of the two, ``pilot_distance_on`` naming which — and the requirement changes
    (``max_distance_m``, ``range_m``) where the route reaches farther than the area.
    """
    from uasnav.geo import frames

    pts = np.array([p for ln in sp.lines for p in (ln.run_in_en, ln.start_en, ln.end_en, ln.run_out_en)])
    pe, pn, _ = frames.geodetic_to_enu(
        area_distances["pilot"][0], area_distances["pilot"][1], 0.0, lat0, lon0, 0.0
    )
    to_pilot = float(np.hypot(pts[:, 0] - float(pe), pts[:, 1] - float(pn)).max()) if len(pts) else 0.0
    to_takeoff = float(np.hypot(pts[:, 0], pts[:, 1]).max()) if len(pts) else 0.0
    out = dict(area_distances)
    out["area_pilot_distance_m"] = area_distances["pilot_distance_m"]
    out["route_pilot_distance_m"] = to_pilot
    out["route_range_m"] = to_takeoff
    changes: dict[str, float] = {}
    on_route = to_pilot > area_distances["pilot_distance_m"]
    out["pilot_distance_on"] = "the planned route (run-ins and run-outs included)" if on_route else "the area"
    if on_route:
        out["pilot_distance_m"] = changes["max_distance_m"] = to_pilot
    if to_takeoff > area_distances["range_m"]:
        out["range_m"] = changes["range_m"] = to_takeoff
    return out, changes


def _legal_height(regs: Any, req: Any) -> float:
    """Highest height (m above ground) the applicable category allows (open if unset)."""
    from uasnav.mission.regulations import DEFAULT_CATEGORY

    cat = req.category or DEFAULT_CATEGORY.get(req.jurisdiction)
    try:
        h = float(regs.max_height_m(req.jurisdiction, cat))
    except Exception:
        h = math.inf
    return h if math.isfinite(h) else 120.0


def _deconflict(flights: list[FlightResult], others: list[Any]) -> list[dict[str, Any]]:
    """Conflicts of each survey flight with the given intents, and the delay of our flight
    that clears it (None: none within a day)."""
    if not others or not flights:
        return []
    from uasnav.io.operational_intent import NamedIntent
    from uasnav.utm.deconflict import deconflict, earliest_delays
    from uasnav.utm.volumes import volume_arrays

    ours = [NamedIntent(f.name, f.intent.details, f.name) for f in flights]
    names = {x.name for x in ours}
    clash = [x for x in others if x.name in names]
    if clash:
        raise InputError(
            f"an intent given with --intents is named {clash[0].name!r}, like a flight of this plan"
        )
    allv = ours + list(others)
    res = deconflict(allv)
    v = volume_arrays(allv)
    out = []
    mine = [k for k, x in enumerate(allv) if x.name in names]
    delays = dict(zip(mine, earliest_delays(v, mine), strict=True))
    for c in res.conflicts:
        if not (set(c.intents) & names):
            continue
        own = c.intents[0] if c.intents[0] in names else c.intents[1]
        other = c.intents[1] if own == c.intents[0] else c.intents[0]
        d = float(delays[[x.name for x in allv].index(own)])
        out.append(
            {
                "flight": own,
                "intent": other,
                "overlap_start": c.overlap[0].isoformat(),
                "overlap_end": c.overlap[1].isoformat(),
                "volumes": [list(p) for p in c.volumes],
                "delay_s": None if math.isnan(d) else d,
                "resolution": (
                    f"delay {own} by {d:.0f} s" if not math.isnan(d) else "no delay within a day clears it"
                ),
            }
        )
    return out


def ground_datum(elevation_m: float | None, area: Any, lat_deg: float, lon_deg: float) -> dict[str, Any]:
    """The ground under the take-off point (``lat_deg``, ``lon_deg``) that every height of the
    plan stands on, with its datum and where it comes from.

    The survey flies at heights above this point (flat field); an F3548 intent needs WGS-84
    ellipsoidal altitudes: h_W84 = H_AMSL(ground) + height + N, with N the EGM96 geoid height
    (:func:`uasnav.geo.geoid.geoid_height`, evaluated at each point of the intent). The ground's
    AMSL elevation is, in this order:

    1. the operator's (``elevation_m``, ``--ground-elevation``);
    2. the home altitude (AMSL) of a mission plan given as the area, when its home is within
       :data:`HOME_AS_TAKEOFF_M` of the take-off point. A home altitude of exactly 0 m or none
       is no elevation: QGroundControl starts the planned home at 0 m and replaces it only with
       the terrain height (when its terrain query answers) or the vehicle's home, and writes
       ``null`` for an unknown altitude — so 0 means it had neither (the plans in
       ``../shared/data/missions`` carry 343, 483–489 and 5.2 m, or ``null``);
    3. the heights of a GeoJSON area (the third coordinate of its positions: metres above the
       WGS-84 ellipsoid, RFC 7946 §4), each less its EGM96 geoid height, averaged, when the
       take-off point is within :data:`HOME_AS_TAKEOFF_M` of the area. Heights that are all 0
       are taken as unset (a placeholder many tools write);
    4. else :data:`DEFAULT_GROUND_ELEVATION_M`, flagged ``assumed`` (uasnav carries no terrain
       model: the geoid gives ellipsoid ↔ AMSL, not the ground); ``source`` says why.

    Returns
    -------
    dict
        ``elevation_m`` (m AMSL), ``datum`` ("AMSL"), ``source``, ``assumed``, ``at`` ([lat, lon]
        of the take-off point), ``geoid`` (model), ``geoid_height_m`` (N at the take-off point),
        ``ellipsoidal_height_m`` (the ground's h_W84 there) and, from area heights, ``spread_m``
        (highest less lowest AMSL elevation of the area's positions).
    """
    from uasnav.geo.geoid import GEOID_MODEL, geoid_height

    extra: dict[str, Any] = {}
    if elevation_m is not None:
        ground, source, assumed = float(elevation_m), "the operator (--ground-elevation)", False
    else:
        ground, source, assumed = _ground_of_area(area, lat_deg, lon_deg, extra)
    n_m = float(geoid_height(lat_deg, lon_deg))
    return {
        "elevation_m": ground,
        "datum": "AMSL",
        "source": source,
        "assumed": assumed,
        "at": [float(lat_deg), float(lon_deg)],
        "geoid": GEOID_MODEL,
        "geoid_height_m": n_m,
        "ellipsoidal_height_m": ground + n_m,
        **extra,
    }


def _ground_of_area(
    area: Any, lat_deg: float, lon_deg: float, extra: dict[str, Any]
) -> tuple[float, str, bool]:
    """(elevation m AMSL, source, assumed) of the take-off ground from the area document (steps
    2–4 of :func:`ground_datum`); ``extra`` receives ``spread_m`` for area heights."""
    from shapely import geometry as sg

    from uasnav.geo import frames
    from uasnav.geo.geoid import geoid_height

    fallback = "assumed: no ground elevation given and no terrain model"
    home = getattr(area, "home", None)
    if home is not None:
        e, n, _ = frames.geodetic_to_enu(home[0], home[1], 0.0, lat_deg, lon_deg, 0.0)
        d = math.hypot(float(e), float(n))
        if d <= HOME_AS_TAKEOFF_M:
            where = f"the home position of the plan {area.where} ({d:.0f} m from the take-off point)"
            alt = float(home[2])
            if math.isfinite(alt) and alt != 0.0:
                return alt, where, False
            said = "no altitude" if not math.isfinite(alt) else "altitude 0 m"
            return (
                DEFAULT_GROUND_ELEVATION_M,
                f"assumed: {where} has {said}, which QGroundControl writes when it had neither terrain "
                "data nor a vehicle's home; no terrain model",
                True,
            )
    heights = getattr(area, "heights", ())
    if heights:
        h = np.asarray(heights, dtype=float)
        if not np.any(h[:, 2] != 0.0):
            return (
                DEFAULT_GROUND_ELEVATION_M,
                f"{fallback} (the heights of {area.where} are all 0: unset)",
                True,
            )
        near = area.local(lon_deg, lat_deg).distance(sg.Point(0.0, 0.0))
        if near > HOME_AS_TAKEOFF_M:
            return (
                DEFAULT_GROUND_ELEVATION_M,
                f"{fallback} (the take-off point is {near:.0f} m from {area.where}, whose heights "
                "are not its ground)",
                True,
            )
        amsl = h[:, 2] - np.asarray(geoid_height(h[:, 1], h[:, 0]), dtype=float)
        extra["spread_m"] = float(amsl.max() - amsl.min())
        return (
            float(amsl.mean()),
            f"the heights of {area.where}: mean of {len(amsl)} positions' WGS-84 ellipsoidal heights "
            "(RFC 7946) less the EGM96 geoid height at each",
            False,
        )
    return DEFAULT_GROUND_ELEVATION_M, fallback, True


def _no_plan(sel: Any, request: Any) -> PlanResult:
    """The answer when no configuration ranks (none meets the requirements, or a zone withholds
    them all): the selection's verdict, no survey and no flight; ``result.json`` only."""
    base = {
        "configuration": None,
        "operation": None,
        "survey": None,
        "flights": [],
        "eta_s": None,
        "zones": sel.zones.to_dict() if sel.zones else None,
        "conflicts": [],
        "authorisation": sel.authorisation,
        "distances": request.distances,
        "selection": sel.to_dict(),
    }
    return PlanResult(to_jsonable(base), {"result.json": _json(base)}, sel, None)


def _result(sel, best, sp, flights, conflicts, request, start, total_s, overlap, ground) -> dict[str, Any]:
    op = sel.operation
    etas = [f.intent.eta_s for f in flights]
    lo = [f.intent.eta_bounds_s[0] for f in flights]
    hi = [f.intent.eta_bounds_s[1] for f in flights]
    auth = sel.authorisation
    if conflicts:
        auth = dict(auth)
        auth["requirements"] = list(auth["requirements"]) + [
            f"strategic conflict of {c['flight']} with {c['intent']}: {c['resolution']}" for c in conflicts
        ]
    d = {
        "configuration": {
            "uas_id": best.uas_id,
            "uas": best.uas,
            "camera_id": best.camera_id,
            "camera": best.camera,
            "score": best.score,
            "mass_g": best.mass_g,
            "cost_usd": best.cost_usd,
        },
        "operation": op.to_dict() if op else None,
        "distances": request.distances,
        "survey": {
            "altitude_m": sp.altitude_m,
            "altitude_datum": "above the take-off point (flat field)",
            "height_reason": sp.height_reason,
            "gsd_m": sp.gsd_m,
            "footprint_m": list(sp.footprint_m),
            "overlap": {"front": overlap[0], "side": overlap[1]},
            "line_spacing_m": sp.spacing_m,
            "trigger_distance_m": sp.trigger_m,
            "speed_ms": sp.speed_ms,
            "speed_reason": sp.speed_reason,
            "heading_deg": sp.heading_deg,
            "photos": sp.photos,
            "lines": len(sp.lines),
            "length_m": sp.length_m,
            "flights": len(sp.flights),
            "endurance_s": sp.endurance_s,
            "estimated_time_s": sp.estimated_time_s,
            "assumptions": sp.assumptions,
        },
        "ground": ground,
        "flights": [f.to_dict() for f in flights],
        "eta_s": {
            "total": float(sum(etas)),
            "lower": float(sum(lo)),
            "upper": float(sum(hi)),
            "coverage": COVERAGE,
            "per_flight": [
                {"eta_s": e, "lower": a, "upper": b} for e, a, b in zip(etas, lo, hi, strict=True)
            ],
            "window": {
                "start": start.isoformat(),
                "end": (start + dt.timedelta(seconds=total_s)).isoformat(),
                "duration_s": total_s,
            },
        },
        "zones": sel.zones.to_dict() if sel.zones else None,
        "flight_window": sel.flight_window,
        "conflicts": conflicts,
        "authorisation": auth,
        "sora": sel.sora.to_dict() if sel.sora else None,
        "scenarios": [x.__dict__ | {"reasons": list(x.reasons)} for x in sel.scenarios],
        "notes": list(sel.notes),
        "files": ["summary.html", "summary.json", "result.json"]
        + [n.format(k=f.number) for f in flights for n in FLIGHT_FILES],
    }
    return to_jsonable(d)


def _json(d: Any) -> bytes:
    return (json.dumps(to_jsonable(d), indent=2, ensure_ascii=False, allow_nan=False) + "\n").encode()


def _files(sel, sp, flights, result) -> dict[str, bytes]:
    from uasnav.io.operational_intent import to_json
    from uasnav.io.plan_formats.qgc import qgc_plan_dict
    from uasnav.io.plan_formats.wpl import wpl_text
    from uasnav.mission.summary import summary_dict, summary_html

    files: dict[str, bytes] = {}
    for f in flights:
        k = f.number
        files[f"flight-{k:02d}.plan"] = (
            json.dumps(qgc_plan_dict(f.plan), indent=4, allow_nan=False) + "\n"
        ).encode()
        files[f"flight-{k:02d}.waypoints"] = wpl_text(f.plan).encode()
        files[f"flight-{k:02d}.intent.json"] = (
            json.dumps(to_json(f.intent.details), indent=1, allow_nan=False) + "\n"
        ).encode()
    summ = summary_dict(sel)
    summ["plan"] = {k: result[k] for k in ("survey", "ground", "flights", "eta_s", "conflicts", "distances")}
    summ["authorisation"] = result["authorisation"]
    files["summary.json"] = _json(summ)
    files["summary.html"] = summary_html(sel, plan=result).encode()
    files["result.json"] = _json(result)
    return files


def write_outputs(result: PlanResult, out_dir: str | os.PathLike[str]) -> list[str]:
    """Write every file of ``result`` into ``out_dir`` (created if missing), all or nothing."""
    from uasnav.atomicfile import output_set

    d = Path(out_dir)
    if d.exists() and not d.is_dir():
        raise InputError(f"{d}: exists and is not a directory")
    with output_set() as out:
        for name, data in result.files.items():
            out.write_bytes(d / name, data)
    return [str(d / n) for n in result.files]


__all__ = [
    "PLAN_OPTIONS",
    "FlightResult",
    "PlanResult",
    "parse_overlap",
    "plan",
    "survey_predictor",
    "write_outputs",
]
