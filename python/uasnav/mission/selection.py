"""The selector: requirements → equipment, feasible UAS and cameras, ranked configurations
(thesis Figure 66 steps 1–6)."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from uasnav.mission.database import Database, load_database
from uasnav.mission.feasibility import (
    MIN_SURVEY_HEIGHT_M,
    Rejection,
    Requirements,
    TestResult,
    camera_tests,
    describe,
    mission_time_s,
    pair_tests,
    required_hfov_deg,
    uas_tests,
)
from uasnav.mission.feasibility import equipment_tests as _equipment_tests
from uasnav.mission.matrices import INCOMPATIBLE, NECESSARY, Matrices, load_matrices
from uasnav.mission.operation import (
    VLOS_SOURCE,
    Operation,
    ScenarioCheck,
    derive_operation,
    eu_scenarios,
    faa_checks,
    narrowed_features,
    vlos_distance_of,
)
from uasnav.mission.readable import metres
from uasnav.mission.regulations import Regulations, load_regulations
from uasnav.mission.scoring import ScoreMatrix, Targets, Weights, explain, rank, score_matrix
from uasnav.mission.sora import SoraResult, assess

if TYPE_CHECKING:
    import datetime as dt

    from uasnav.io.ed269 import Zone
    from uasnav.mission.zones import MissionArea, ZoneCheck


@dataclass(frozen=True)
class EquipmentNeed:
    """One equipment item for the mission flown as the derived operation.

    ``reason`` names the Table 19 cell or the operation rule that set the status;
    ``onboard`` is the database token that provides it on a UAS (None: not recorded per UAS)
    and ``retrofit`` whether it can be fitted to a UAS that lacks it.
    """

    id: str
    name: str
    group: str
    necessary: bool
    reason: str = ""
    onboard: str | None = None
    retrofit: bool = False


@dataclass(frozen=True)
class RankedPair:
    """One ranked UAS/camera pair (a configuration of Table 24) with its partial scores (eq. 61).

    Scores are dimensionless (0 inside the target, 1 at the limit; lower is better); ``mass_g``
    is the take-off mass of UAS + camera (g), ``cost_usd`` their cost (USD) and
    ``open_subcategory`` the EASA open subcategory of that mass (None outside the EASA rules).
    """

    uas_id: str
    uas: str
    camera_id: str
    camera: str
    score: float
    score_range: float
    score_weight: float
    score_cost: float
    score_resolution: float
    mass_g: float
    cost_usd: float
    open_subcategory: str | None
    #: SORA SAIL of this configuration in the specific category (None elsewhere, or certified).
    sail: str | None = None
    #: The operation this configuration implies: VLOS/EVLOS/BVLOS (from the distance at which
    #: this UA can be kept in sight) and its category.
    visibility: str | None = None
    category: str | None = None


@dataclass(kw_only=True)
class Selection:
    """Everything the output interface of Figure 70 shows (built from keywords)."""

    requirements: Requirements
    mission_name: str
    features: dict[str, tuple[str, ...]]
    equipment: list[EquipmentNeed]
    regulatory_height_m: float
    required_hfov_deg: float
    vlos_required: bool
    uas_ok: np.ndarray
    camera_ok: np.ndarray
    pair_ok: np.ndarray
    rejections: list[Rejection]
    ranking: list[RankedPair]
    scores: ScoreMatrix
    database: Database
    notes: list[str] = field(default_factory=list)
    #: The derived operation (visibility, height, people, category …) with its derivation.
    operation: Operation | None = None
    #: SORA of the best configuration (EASA specific category), else None.
    sora: SoraResult | None = None
    #: Geographical zones the mission area enters (when an area and zones were given).
    zones: ZoneCheck | None = None
    #: EU STS/PDRA checks or FAA waivers/authorisations for the best configuration.
    scenarios: tuple[ScenarioCheck, ...] = ()
    #: Configurations that would rank but are withheld: the area enters a PROHIBITED zone
    #: (``ranking`` is then empty — nothing is presented as flyable).
    withheld: list[RankedPair] = field(default_factory=list)
    #: The flight window the zone schedules were checked over (start, end, duration_s, from).
    flight_window: dict | None = None
    #: Every operation the candidate UAS imply (one per VLOS/EVLOS/BVLOS present), least
    #: demanding first, each with its best configuration; ``operation`` is the chosen one's.
    operations: list[OperationChoice] = field(default_factory=list)
    #: Height (m above ground) the cameras' field of view and resolution were tested at, and
    #: the rule that chose it (``planned`` or ``regulatory-max``, :attr:`Requirements.camera_height`).
    camera_height_m: float | None = None
    #: The scoring's targets and limits (Table 23), for the explanation shown with the ranking.
    targets: Targets | None = None

    @property
    def authorisation(self) -> dict:
        """The verdict an operator files against: ``authorisable`` (False when a PROHIBITED zone
        is entered or nothing is feasible), the ``blocking`` reasons, the ``requirements``
        (the category's authorisation, STS/PDRA or FAA waivers that apply, zone authorisations
        and conditions) and ``route``: the category that authorises it, falling back open →
        STS → PDRA → SORA → certified (EASA); "not authorisable" only when none can."""
        op, req = self.operation, self.requirements
        blocking = [r.message for r in self.rejections if r.test == "zone-prohibited"]
        needs: list[str] = []
        route = None
        if op is not None and req.jurisdiction == "easa":
            if op.category == "open":
                sub = self.chosen.open_subcategory if self.chosen else None
                where = f"open category {sub}" if sub else "open category"
                needs.append(f"{where}: no operational authorisation ({op.legal_basis})")
                route = where
            elif op.category == "specific":
                sts = [x for x in self.scenarios if x.applies and x.id.startswith("STS")]
                pdra = [x for x in self.scenarios if x.applies and x.id.startswith("PDRA")]
                if self.sora is not None and self.sora.certified and not sts and not pdra:
                    route = "certified category"
                    needs.append(
                        "certified category ((EU) 2019/947 Art. 6): the SORA puts this operation "
                        "beyond the specific category — a certified UAS, a licensed remote pilot and "
                        "an operator certificate"
                    )
                else:
                    for x in sts:
                        needs.append(f"declaration under {x.id} ({x.source})")
                    for x in pdra:
                        needs.append(f"operational authorisation under {x.id} ({x.source})")
                    sail = (
                        f", SORA {self.sora.edition} SAIL {self.sora.sail}"
                        if self.sora and self.sora.sail
                        else ""
                    )
                    needs.append(
                        ("or " if sts or pdra else "")
                        + "operational authorisation from the competent authority "
                        + f"((EU) 2019/947 Art. 12{sail})"
                    )
                    route = (
                        f"specific category, {sts[0].id} declaration"
                        if sts
                        else f"specific category, {pdra[0].id}"
                        if pdra
                        else "specific category, SORA"
                        + (f" SAIL {self.sora.sail}" if self.sora and self.sora.sail else "")
                    )
        else:
            needs += [f"{x.id}: {'; '.join(x.reasons)} ({x.source})" for x in self.scenarios if x.applies]
        for h in self.zones.hits if self.zones else ():
            if h.restriction in ("REQ_AUTHORISATION", "CONDITIONAL"):
                what = (
                    "authorisation from the zone authority"
                    if h.restriction == "REQ_AUTHORISATION"
                    else "conditions"
                )
                needs.append(
                    f"zone {h.identifier} {h.name} ({h.restriction}): {what}"
                    + (f" — {h.message}" if h.message else "")
                    + ("" if h.certain else f" [uncertain: {'; '.join(h.why)}]")
                )
        if blocking:
            verdict = "not authorisable: " + "; ".join(blocking)
        elif not self.ranking:
            verdict = self.unmet
        elif route == "certified category":
            verdict = "authorisable only in the certified category"
        elif len(needs) > 1 or (needs and not needs[0].startswith("open category")):
            verdict = "authorisable with the requirements listed" + (f" ({route})" if route else "")
        else:
            verdict = "no authorisation needed (open category)" if needs else "authorisable"
        return {
            "authorisable": not blocking and bool(self.ranking),
            "verdict": verdict,
            "route": route,
            "blocking": blocking,
            "requirements": needs,
        }

    def _resolution_unmet(self, finest: Rejection) -> str:
        """The resolution no camera reaches, in the units and words it was asked in (m/px, by
        --resolution), against the finest camera at the height it was tested at and why."""
        r = self.requirements
        if r.mosaic:
            where = f"{metres(MIN_SURVEY_HEIGHT_M)}, the lowest height a survey flies"
        elif r.camera_height == "regulatory-max":
            where = f"{metres(self.camera_height_m or r.altitude_m)}, the highest the category allows"
        else:
            where = f"{metres(self.camera_height_m or r.altitude_m)}, the planned height (--altitude)"
        cams = self.database.cameras
        name = cams.label(cams.ids.index(finest.item)) if finest.item in cams.ids else finest.item
        return (
            f"resolution: --resolution {r.resolution_m:g} m/px ({_per_pixel(r.resolution_m)}) asked; "
            f"the finest, {name}, gives {finest.value:.3g} m/px ({_per_pixel(finest.value)}) "
            f"at {where}"
        )

    @property
    def unmet(self) -> str:
        """What no configuration meets, said as what it is ("no camera meets the resolution
        …") rather than as a flight that cannot be flown."""
        tests_of: dict[str, set[str]] = {"uas": set(), "camera": set(), "pair": set(), "mission": set()}
        for r in self.rejections:
            tests_of.setdefault(r.kind, set()).add(r.test)
        parts = []
        if len(self.database.cameras) and not self.camera_ok.any():
            # the tests that alone keep some camera out (a camera failing only them), else all
            fails: dict[str, set[str]] = {}
            for r in self.rejections:
                if r.kind == "camera":
                    fails.setdefault(r.item, set()).add(r.test)
            binding = {next(iter(t)) for t in fails.values() if len(t) == 1}
            if binding:
                tests_of["camera"] = binding
            finest = min(
                (r for r in self.rejections if r.kind == "camera" and r.test == "resolution"),
                key=lambda r: r.value,
                default=None,
            )
            why = sorted(tests_of["camera"])
            if finest is not None and np.isfinite(finest.value):
                why = [w if w != "resolution" else self._resolution_unmet(finest) for w in why]
            parts.append("no camera in the database meets " + ", ".join(why))
        if len(self.database.uas) and not self.uas_ok.any():
            parts.append("no UAS in the database meets " + ", ".join(sorted(tests_of["uas"])))
        if not parts and tests_of["mission"]:
            parts.append("the mission fails " + ", ".join(sorted(tests_of["mission"])))
        if not parts:
            parts.append("no UAS/camera pair meets " + (", ".join(sorted(tests_of["pair"])) or "the tests"))
        return "; ".join(parts)

    @property
    def chosen(self) -> RankedPair | None:
        """The best-ranked configuration, if any."""
        return self.ranking[0] if self.ranking else None

    def equipment_on(self, uas_id: str) -> list[dict]:
        """Each necessary item against the equipment record of UAS ``uas_id``: ``present``,
        ``missing`` (``to be fitted`` when it is a module) or ``not recorded``."""
        u = self.database.uas
        i = u.ids.index(uas_id)
        rec = u.equipment[i] if u.equipment else None
        out = []
        for e in self.equipment:
            if not e.necessary:
                continue
            if e.onboard is None:
                state = "not recorded per UAS"
            elif rec is not None and e.onboard in rec:
                state = "present"
            elif e.retrofit:
                state = "missing: to be fitted"
            else:
                state = "missing"
            out.append({"id": e.id, "name": e.name, "state": state, "reason": e.reason})
        return out

    @property
    def feasible_uas(self) -> list[str]:
        """Labels of the UAS passing every aircraft test."""
        u = self.database.uas
        return [u.label(int(i)) for i in np.flatnonzero(self.uas_ok)]

    @property
    def feasible_cameras(self) -> list[str]:
        """Labels of the cameras passing every camera test."""
        c = self.database.cameras
        return [c.label(int(i)) for i in np.flatnonzero(self.camera_ok)]

    def to_dict(self) -> dict:
        """Plain-JSON view (used by ``uasnav select --json``)."""
        r = self.requirements
        return {
            "mission": r.mission,
            "mission_name": self.mission_name,
            "requirements": r.__dict__,
            "features": {k: list(v) for k, v in self.features.items()},
            "equipment": [e.__dict__ for e in self.equipment],
            "regulations": {
                "jurisdiction": r.jurisdiction,
                "category": self.operation.category if self.operation else r.category,
                "max_height_m": self.regulatory_height_m,
                "vlos_required": self.vlos_required,
                "legal_basis": self.operation.legal_basis if self.operation else None,
            },
            "required_hfov_deg": self.required_hfov_deg,
            "camera_height": {
                "rule": r.camera_height,
                "height_m": self.camera_height_m,
                "explained": (
                    "a survey: no field-of-view test; the resolution is reachable at or above "
                    f"{MIN_SURVEY_HEIGHT_M:g} m (the survey flies at the height that gives it)"
                    if r.mosaic
                    else "field of view and resolution tested at the planned height (--altitude)"
                    if r.camera_height == "planned"
                    else "field of view and resolution tested at the highest height the category "
                    "allows (thesis §5.2.3.4)"
                ),
            },
            "feasible_uas": self.feasible_uas,
            "feasible_cameras": self.feasible_cameras,
            "rejections": [x.__dict__ for x in self.rejections],
            "ranking": [c.__dict__ for c in self.ranking],
            "weights": self.scores.weights.__dict__,
            "scoring": {
                "weights": self.scores.weights.__dict__,
                "targets": (self.targets or Targets()).__dict__,
                "explained": explain(self.targets or Targets(), self.scores.weights),
            },
            "notes": self.notes,
            "operation": self.operation.to_dict() if self.operation else None,
            "sora": self.sora.to_dict() if self.sora else None,
            "zones": self.zones.to_dict() if self.zones else None,
            "scenarios": [x.__dict__ | {"reasons": list(x.reasons)} for x in self.scenarios],
            "chosen_equipment": self.equipment_on(self.chosen.uas_id) if self.chosen else [],
            "authorisation": self.authorisation,
            "withheld_ranking": [c.__dict__ for c in self.withheld],
            "flight_window": self.flight_window,
            "operations": [o.to_dict() for o in self.operations],
        }


def equipment_tests(u, req: Requirements, equipment: list[EquipmentNeed]) -> list[TestResult]:
    """Equipment tests on the UAS: the GNSS autopilot when required (thesis Table 22) and every
    necessary item that is a design feature of the aircraft (not a module that can be fitted)."""
    need = [(e.onboard, e.name) for e in equipment if e.necessary and e.onboard and not e.retrofit]
    return _equipment_tests(u, req.gnss_autopilot, need)


def _survey_duration(db: Database, req: Requirements, best: RankedPair, area) -> tuple[float, str] | None:
    """(duration s, how) of a survey of the polygon ``area`` by ``best`` at the resolution, from
    the take-off point at the area's centroid: the survey planner's flight-time estimate of
    every flight plus the turnarounds between them; None if no survey can be laid out."""
    from uasnav.errors import UasnavError
    from uasnav.mission.survey import Camera, plan_survey

    u, c = db.uas, db.cameras
    i, j = u.ids.index(best.uas_id), c.ids.index(best.camera_id)
    lon0, lat0 = area.centre()
    g = area.local(lon0, lat0)
    if g.geom_type != "Polygon":
        g = g.convex_hull
    try:
        sp = plan_survey(
            g,
            Camera.from_table(c, j),
            resolution_m=req.resolution_m,
            origin=(lat0, lon0),
            takeoff_en=(g.centroid.x, g.centroid.y),
            altitude_m=req.altitude_m,
            cruise_ms=req.cruise_fraction * float(u.max_speed_ms[i]),
            endurance_s=float(u.endurance_min[i]) * 60.0 * (1.0 - req.reserve),
        )
    except UasnavError:
        return None
    n = len(sp.flights)
    total = sum(sp.estimated_time_s) + SURVEY_TURNAROUND_S * (n - 1)
    return float(total), (
        f"survey of the area by {best.uas} + {best.camera}: {len(sp.lines)} lines, {n} flight(s) "
        f"at {sp.speed_ms:.1f} m/s (conservative estimate; `uasnav plan` predicts it with bounds)"
    )


#: Time between two flights of a survey (landing, battery change, take-off), s.
SURVEY_TURNAROUND_S = 600.0


def _flight_duration(
    u, req: Requirements, ranking: list[RankedPair], area=None, db: Database | None = None
) -> tuple[float, str]:
    """(duration s, how it was obtained) of the flight: ``req.flight_duration_s`` when given,
    else the mission time (out and back over the range against the wind at the cruise airspeed,
    :func:`mission_time_s`) of the best-ranked UAS, else the longest finite one in the database."""
    if req.flight_duration_s is not None:
        return float(req.flight_duration_s), "--flight-duration"
    if ranking and area is not None and db is not None and any(k == "poly" for k, _ in area.parts):
        got = _survey_duration(db, req, ranking[0], area)
        if got is not None:
            return got
    t = mission_time_s(req.range_m, req.cruise_fraction * u.max_speed_ms, req.wind_ms)
    if ranking:
        i = u.ids.index(ranking[0].uas_id)
        return float(
            t[i]
        ), f"mission time estimate of {u.label(i)} (range {req.range_m:g} m, wind {req.wind_ms:g} m/s)"
    finite = t[np.isfinite(t)]
    if finite.size == 0:
        return 0.0, "no UAS can fly the range: take-off instant only"
    return float(finite.max()), "longest mission time estimate in the database (no configuration ranked)"


#: Order of the operations by what they ask of the operator: a flight in the remote pilot's
#: own sight before one with observers before one beyond sight, and a category that needs no
#: operational authorisation (EASA open) before one that does.
_VISIBILITY_ORDER = {"VLOS": 0, "EVLOS": 1, "BVLOS": 2}
_CATEGORY_ORDER = {"open": 0}


def _burden(op: Operation) -> tuple[int, int]:
    """Sort key of an operation: (needs an authorisation, how far beyond the pilot's sight)."""
    return (_CATEGORY_ORDER.get(op.category, 1), _VISIBILITY_ORDER[op.visibility])


def _visibility_of(dist: float, reach: np.ndarray, observers: int) -> np.ndarray:
    """VLOS / EVLOS / BVLOS of each UA kept in sight up to ``reach`` (m) at pilot distance
    ``dist`` (m), the same rule as :func:`~uasnav.mission.operation.derive_operation`."""
    out = np.full(reach.shape, "BVLOS", dtype=object)
    if observers > 0:
        out[dist <= reach * (observers + 1)] = "EVLOS"
    out[dist <= reach] = "VLOS"
    return out


def _operations_per_uas(u, req: Requirements, regs: Regulations) -> list[tuple[Operation, np.ndarray]]:
    """The operations the candidate UAS imply, each with its member UAS (bool mask).

    The operation follows from the distance at which *this* UA can be kept in sight (its
    :func:`~uasnav.mission.operation.vlos_distance_of`): at the same pilot distance a large UA
    may be flown VLOS in the open category while a small one is flown BVLOS in the specific
    category; both are evaluated. Each operation reports as its VLOS distance the largest of
    its member UAS that pass the aircraft tests of its category (else of all its members).
    One operation for every UAS when ``--vlos-distance`` is given or the database is empty.
    """
    dist = req.max_distance_m if req.max_distance_m is not None else req.range_m
    if req.vlos_distance_m is not None or len(u) == 0:
        return [(derive_operation(req), np.ones(len(u), dtype=bool))]
    per = np.asarray(vlos_distance_of(u.span_m, list(u.types)), dtype=float)
    vis = _visibility_of(float(dist), per, req.observers)
    present = [v for v in ("VLOS", "EVLOS", "BVLOS") if (vis == v).any()]
    out = []
    for v in present:
        members = vis == v
        k = int(np.flatnonzero(members)[np.argmax(per[members])])
        op = derive_operation(req, vlos_default=(float(per[k]), ""))
        lim = regs.category(req.jurisdiction, op.category).limit("mtom")
        ok = members.copy()
        for t in uas_tests(u, req, lim.value_si if lim is not None else np.inf) + _equipment_tests(
            u, req.gnss_autopilot, []
        ):
            ok &= t.ok
        pool = np.flatnonzero(ok) if ok.any() else np.flatnonzero(members)
        k = int(pool[np.argmax(per[pool])])
        src = (
            f"{VLOS_SOURCE}; the largest of the candidate UAS"
            + (f" flown {v} ({int(members.sum())} of {len(u)} UAS)" if len(present) > 1 else "")
            + f": {u.label(k)}, {float(u.span_m[k]):g} m {u.types[k]}; each UAS is held to its own distance"
        )
        out.append((derive_operation(req, vlos_default=(float(per[k]), src)), members))
    return sorted(out, key=lambda x: _burden(x[0]))


#: Farthest pilot–UA distance a direct radio C2 link of a small UAS covers with radio line of
#: sight (m): manufacturers' direct links reach 5–15 km unobstructed; beyond this distance the
#: C2 link is a network (cellular) or SATCOM link.
DIRECT_C2_RANGE_M = 5000.0


def _per_pixel(m_per_px: float) -> str:
    """A ground resolution as people say it: "0.5 mm per pixel", "2 cm per pixel"."""
    if m_per_px < 0.01:
        return f"{m_per_px * 1000:.2g} mm per pixel"
    return f"{m_per_px * 100:.3g} cm per pixel"


def c2_name(item_id: str, name: str, distance_m: float) -> str:
    """The beyond-sight C2 link named by the range it must cover (``distance_m`` from the
    pilot): a network or SATCOM link only beyond :data:`DIRECT_C2_RANGE_M`."""
    if item_id != "blos-c2":
        return name
    if distance_m <= DIRECT_C2_RANGE_M:
        return (
            f"BLOS C2 data link covering {metres(distance_m)} from the pilot: a direct radio link with radio "
            "line of sight over the whole area (raised antenna), or a communication network link"
        )
    return (
        f"BLOS C2 data link covering {metres(distance_m)} from the pilot: communication network or SATCOM "
        "(beyond direct radio range)"
    )


def _reject(
    tests: list[TestResult], kind: str, labels, ids, rows: np.ndarray | None = None
) -> tuple[np.ndarray, list[Rejection]]:
    """Combine ``tests``; rejections only for the items in ``rows`` (all when None)."""
    rows = np.ones(len(ids), dtype=bool) if rows is None else rows
    ok = rows.copy()
    out = []
    for t in tests:
        for i in np.flatnonzero(~t.ok & rows):
            out.append(
                Rejection(
                    kind,
                    ids[i],
                    t.name,
                    float(t.value[i]),
                    float(t.limit[i]),
                    t.unit,
                    describe(t, i, labels(i)),
                )
            )
        ok &= t.ok
    return ok, out


def _plan_altitude(req: Requirements, area: MissionArea) -> tuple[Requirements, str | None]:
    """``req`` with the height the plan ``area`` flies when it is above ``--altitude`` (the
    height checks use the higher), and the note saying which was used."""
    from uasnav.mission.zones import plan_height

    got = plan_height(area, ground_elevation_m=req.ground_elevation_m)
    if got is None:
        return req, None
    h, how = got
    if h > req.altitude_m:
        note = (
            f"the plan flies up to {metres(h, against=req.altitude_m)} above ground ({how}), above "
            f"--altitude {metres(req.altitude_m)}: the height checks use {metres(h, against=req.altitude_m)}"
        )
        return replace(req, altitude_m=h, altitude_source=f"plan, highest item ({how})"), note
    note = (
        f"the plan's highest item is {metres(h, against=req.altitude_m)} above ground ({how}), within "
        f"--altitude {metres(req.altitude_m)}"
    )
    return req, note


def _sora_of(op: Operation, req: Requirements, u, i: int, m: float, quantitative: bool = False) -> SoraResult:
    """SORA of UAS ``i`` at take-off mass ``m`` (g) flown as ``op``."""
    return assess(
        dimension_m=float(u.span_m[i]),
        speed_ms=float(u.max_speed_ms[i]),
        population=op.population,
        # SORA treats EVLOS like VLOS: the observers give the see-and-avoid (TMPR)
        bvlos=op.visibility == "BVLOS",
        mass_g=m,
        height_m=req.altitude_m,
        airspace=req.airspace,
        urban=op.urban,
        mitigations=dict(req.mitigations),
        residual_arc=req.residual_arc,
        edition=req.sora_edition,
        density_ppl_km2=op.population_density,
        quantitative=quantitative,
    )


@dataclass(frozen=True)
class OperationChoice:
    """One operation the candidate UAS imply (see :func:`select`): the operation, the UAS that
    imply it, its necessary equipment and its best configuration (None if none is feasible)."""

    visibility: str
    category: str
    legal_basis: str
    vlos_distance_m: float
    uas: tuple[str, ...]
    feasible_pairs: int
    necessary_equipment: tuple[str, ...]
    best: RankedPair | None
    #: Rank (1-based) of ``best`` in the selection's ranking, None when beyond ``top`` or when
    #: the ranking is withheld (PROHIBITED zone).
    rank: int | None

    def to_dict(self) -> dict:
        """Plain JSON."""
        d = dict(self.__dict__)
        d["uas"] = list(self.uas)
        d["necessary_equipment"] = list(self.necessary_equipment)
        d["best"] = self.best.__dict__ if self.best else None
        return d


@dataclass
class _Branch:
    """The selection steps run for one operation over the UAS (``members``) that imply it."""

    op: Operation
    members: np.ndarray
    equipment: list[EquipmentNeed]
    h_reg: float
    h_cam: float
    vlos_required: bool
    uas_ok: np.ndarray
    cam_ok: np.ndarray
    pair_ok: np.ndarray
    rejections: list[Rejection]
    notes: list[str]
    scores: ScoreMatrix
    best: RankedPair | None = None
    uas_ids: tuple[str, ...] = ()

    def choice(self, ranking: list[RankedPair], of_branch: list[int], index: int) -> OperationChoice:
        """This branch as an :class:`OperationChoice`."""
        rank_no = next((k + 1 for k, b in enumerate(of_branch) if b == index), None)
        return OperationChoice(
            self.op.visibility,
            self.op.category,
            self.op.legal_basis,
            self.op.vlos_distance_m,
            tuple(self.uas_ids),
            int(np.count_nonzero(self.pair_ok)),
            tuple(e.id for e in self.equipment if e.necessary),
            self.best,
            rank_no,
        )


def _evaluate(op, members, req, mission, mx, regs, u, c, targets, weights) -> _Branch:
    """Equipment, regulation checks, feasibility tests and scores for operation ``op`` flown by
    the UAS in ``members`` (thesis Figure 66 steps 1–5)."""
    feats = narrowed_features(dict(mission.features), op)
    equipment = []
    for e in mx.equipment.values():
        st = mx.status_for(e.id, feats, op.facts)
        if st.status != INCOMPATIBLE:
            equipment.append(
                EquipmentNeed(
                    e.id, c2_name(e.id, e.name, op.max_distance_m), e.group, st.status == NECESSARY,
                    st.reason, e.onboard, e.retrofit,
                )
            )  # fmt: skip
    category = op.category
    cat = regs.category(req.jurisdiction, category)
    h_reg = regs.max_height_m(req.jurisdiction, category)
    mtom_lim = cat.limit("mtom")
    max_mtom = mtom_lim.value_si if mtom_lim is not None else np.inf
    notes: list[str] = []
    rejections: list[Rejection] = []
    height_checks = regs.check(req.jurisdiction, category, height_m=req.altitude_m)
    mission_ok = all(c.ok for c in height_checks)
    notes += list(op.notes)
    if cat.vlos_required and op.bvlos and req.jurisdiction == "faa":
        # Part 107's VLOS rule is waivable (§107.205): the flight needs a waiver, listed with
        # the FAA checks, it is not refused.
        notes.append(f"faa/{category}: BVLOS needs a waiver of 14 CFR §107.31 (§107.205)")
    elif cat.vlos_required and op.bvlos:
        mission_ok = False
        rejections.append(
            Rejection(
                "mission",
                req.mission,
                "regulation-vlos",
                op.max_distance_m,
                op.vlos_distance_m,
                "m",
                f"{req.jurisdiction}/{category} requires VLOS ({cat.source}); the pilot-UA distance "
                f"{metres(op.max_distance_m, against=op.vlos_distance_m)} exceeds the "
                f"{metres(op.vlos_distance_m)} kept in sight",
            )
        )
    for chk in height_checks:
        if not chk.ok:
            rejections.append(
                Rejection(
                    "mission",
                    req.mission,
                    "regulation-height",
                    req.altitude_m,
                    chk.limit.value_si,
                    "m",
                    f"required altitude {metres(req.altitude_m, against=chk.limit.value_si)} exceeds "
                    f"{chk.limit.describe()}",
                )
            )
    if cat.vlos_required and not op.bvlos:
        notes.append(
            f"{req.jurisdiction}/{category}: VLOS required ({cat.source}); "
            f"{metres(op.max_distance_m, against=op.vlos_distance_m)} from the pilot, within the "
            f"{metres(op.vlos_distance_m)} kept in sight"
        )
    # eq. 60 at the planned height, or at the highest height the regulations allow (the
    # thesis' rule, §5.2.3.4; the required altitude when the category sets no limit)
    if req.mosaic:  # a survey: the resolution is tested at the lowest survey height
        h_cam = MIN_SURVEY_HEIGHT_M
    elif req.camera_height == "regulatory-max":
        h_cam = h_reg if np.isfinite(h_reg) else req.altitude_m
    else:
        h_cam = req.altitude_m
    uas_ok, rej = _reject(
        uas_tests(u, req, max_mtom) + equipment_tests(u, req, equipment), "uas", u.label, u.ids, members
    )
    rejections += rej
    if req.mosaic:
        # UAS kept out of a survey by its pattern alone: said once, beside the ranking
        failed: dict[str, set[str]] = {}
        for r in rej:
            failed.setdefault(r.item, set()).add(r.test)
        only = [u.label(k) for k, uid in enumerate(u.ids) if failed.get(uid) == {"survey-pattern"}]
        if only:
            notes.append(
                f"survey: {', '.join(only)} would qualify but cannot hover; the survey's lines are a "
                "rotorcraft pattern (stop and turn at each line's end), so they are not ranked for it"
            )
    cam_ok, rej = _reject(camera_tests(c, req, h_cam), "camera", c.label, c.ids)
    rejections += rej
    pair_ok = uas_ok[:, None] & cam_ok[None, :] & mission_ok
    for t in pair_tests(u, c, max_mtom):
        bad = pair_ok & ~t.ok
        for i, j in zip(*np.nonzero(bad), strict=True):
            rejections.append(
                Rejection(
                    "pair",
                    f"{u.ids[i]}+{c.ids[j]}",
                    t.name,
                    float(t.value[i, j]),
                    float(t.limit[i, j]),
                    t.unit,
                    describe(t, (i, j), f"{u.label(i)} + {c.label(j)}"),
                )
            )
        pair_ok &= t.ok
    if req.jurisdiction == "easa" and category == "open":
        # The open subcategory follows the class label, the mass and the distances to people;
        # a pair the open category cannot admit under this operation is rejected.
        for i, j in zip(*np.nonzero(pair_ok), strict=True):
            m = float(u.mass_g[i] + c.mass_g[j])
            if regs.open_subcategory(m, u.eu_class[i], over_people=op.over_people, urban=op.urban) is None:
                pair_ok[i, j] = False
                rejections.append(
                    Rejection(
                        "pair",
                        f"{u.ids[i]}+{c.ids[j]}",
                        "open-subcategory",
                        m,
                        float("nan"),
                        "g",
                        f"{u.label(i)} + {c.label(j)}: no open subcategory (A1/A2/A3) admits class "
                        f"{u.eu_class[i] or 'none'} at {m:.0f} g over people '{op.over_people}'"
                        f"{' in an urban area' if op.urban else ''}",
                    )
                )
    scores = score_matrix(
        u.max_range_m, u.mass_g, u.cost_usd, c.mass_g, c.cost_usd, c.ifov_deg, targets, weights, pair_ok
    )
    return _Branch(
        op,
        members,
        equipment,
        h_reg,
        h_cam,
        cat.vlos_required,
        uas_ok,
        cam_ok,
        pair_ok,
        rejections,
        notes,
        scores,
        uas_ids=tuple(u.ids[i] for i in np.flatnonzero(members)),
    )


def _merge_rankings(branches: list[_Branch], req, regs, u, c, top: int) -> tuple[list[RankedPair], list[int]]:
    """The ``top`` configurations over all branches, ranked by the operation they need
    (:func:`_burden`: the branches' order), then by score; with the branch of each. Sets each
    branch's ``best``."""
    cands = []
    for k, br in enumerate(branches):
        for i, j in rank(br.scores.total, top):
            cands.append((k, i, j))
            if br.best is None:
                br.best = _ranked(br, req, regs, u, c, i, j)
    # Branches are already in burden order and rank() returns each branch's pairs best first
    # with reproducible ties, so a stable sort by branch keeps both orders.
    cands.sort(key=lambda x: x[0])
    chosen = cands[:top]
    return [_ranked(branches[k], req, regs, u, c, i, j) for k, i, j in chosen], [k for k, _, _ in chosen]


def _ranked(br: _Branch, req, regs, u, c, i: int, j: int) -> RankedPair:
    """The :class:`RankedPair` of UAS ``i`` and camera ``j`` in branch ``br``."""
    op, scores = br.op, br.scores
    m = float(scores.mass_g[i, j])
    return RankedPair(
        u.ids[i],
        u.label(i),
        c.ids[j],
        c.label(j),
        float(scores.total[i, j]),
        float(scores.range[i, 0]),
        float(scores.weight[i, j]),
        float(scores.cost[i, j]),
        float(scores.resolution[0, j]),
        m,
        float(scores.cost_usd[i, j]),
        # an open subcategory only on a row flown in the open category (a BVLOS or specific
        # operation has none, whatever the mass)
        regs.open_subcategory(m, u.eu_class[i], over_people=op.over_people, urban=op.urban)
        if req.jurisdiction == "easa" and op.category == "open" and "easa" in regs.jurisdictions
        else None,
        _sora_of(op, req, u, i, m).sail if req.jurisdiction == "easa" and op.category == "specific" else None,
        op.visibility,
        op.category,
    )


def select(
    req: Requirements,
    *,
    database: Database | None = None,
    matrices: Matrices | None = None,
    regulations: Regulations | None = None,
    targets: Targets | None = None,
    weights: Weights | None = None,
    top: int = 10,
    area: MissionArea | None = None,
    zones: tuple[Zone, ...] | None = None,
    zones_source: str = "zones",
    when: dt.datetime | None = None,
) -> Selection:
    """Run the whole selection for ``req``.

    Parameters
    ----------
    req : Requirements
    database, matrices, regulations : optional
        Loaded documents; default to the copies shipped in the package.
    targets, weights : Targets, Weights
        Scoring parameters (Table 23, eq. 61 by default).
    top : int
        Number of ranked configurations returned.
    area, zones : optional
        Mission area (:func:`uasnav.mission.zones.parse_area`) and ED-269 zones: the zones the
        area enters are reported (both needed).
    zones_source : str
        Name of the zone file in the output.
    when : datetime, optional
        Take-off time (aware) for the zones' schedules.

    Returns
    -------
    Selection
    """
    targets = targets if targets is not None else Targets()
    weights = weights if weights is not None else Weights()
    db = database if database is not None else load_database()
    mx = matrices if matrices is not None else load_matrices()
    regs = regulations if regulations is not None else load_regulations()
    mission = mx.mission(req.mission)
    u, c = db.uas, db.cameras
    plan_note = None
    if area is not None and area.plan_altitudes:
        req, plan_note = _plan_altitude(req, area)
    branches = [
        _evaluate(op, members, req, mission, mx, regs, u, c, targets, weights)
        for op, members in _operations_per_uas(u, req, regs)
    ]
    ranking, of_branch = _merge_rankings(branches, req, regs, u, c, top)
    # The output describes the operation of the configuration ranked first; when nothing
    # ranks, the least demanding operation (the branches are sorted by _burden).
    main = branches[of_branch[0]] if ranking else branches[0]
    op, equipment = main.op, main.equipment
    notes = list(main.notes) + ([plan_note] if plan_note else [])
    rejections = list(main.rejections)
    for br in branches:
        if br is main:
            continue
        tag = f"[{br.op.visibility}/{br.op.category}] "
        seen = {(r.kind, r.item, r.test, r.message) for r in rejections}
        for r in br.rejections:
            if r.kind == "uas" or (r.kind, r.item, r.test, r.message) not in seen:
                rejections.append(r if r.kind == "uas" else replace(r, message=tag + r.message))
    if len(branches) > 1:
        notes.append(
            "operation per UA (each UAS is held to the distance at which it can be kept in sight): "
            + "; ".join(
                f"{int(br.members.sum())} UAS {br.op.visibility} ({br.op.category})" for br in branches
            )
            + "; configurations ranked by the operation they need (no authorisation first, then "
            "the pilot's own sight before observers before BVLOS), then by score"
        )
    uas_ok = np.zeros(len(u), dtype=bool)
    cam_ok = np.zeros(len(c), dtype=bool)
    pair_ok = np.zeros((len(u), len(c)), dtype=bool)
    total = np.full((len(u), len(c)), np.inf)
    for br in branches:
        uas_ok |= br.uas_ok
        cam_ok |= br.cam_ok
        pair_ok |= br.pair_ok
        total[br.members] = br.scores.total[br.members]
    scores = replace(main.scores, total=total)
    operations = [br.choice(ranking, of_branch, i) for i, br in enumerate(branches)]
    is_specific = req.jurisdiction == "easa" and op.category == "specific"
    sora = None
    scenarios: tuple[ScenarioCheck, ...] = ()
    if ranking:
        best = ranking[0]
        bi = u.ids.index(best.uas_id)
        if is_specific:
            sora = _sora_of(op, req, u, bi, best.mass_g, quantitative=True)
        if req.jurisdiction == "easa":
            scenarios = eu_scenarios(
                op,
                eu_class=u.eu_class[bi],
                mtom_g=best.mass_g,
                dimension_m=float(u.span_m[bi]),
                speed_ms=float(u.max_speed_ms[bi]),
            )
        elif req.jurisdiction == "faa":
            scenarios = faa_checks(op, mtom_g=best.mass_g)
    elif req.jurisdiction == "faa":
        scenarios = faa_checks(op, mtom_g=None)
    zone_check = None
    window = None
    withheld: list[RankedPair] = []
    if area is not None and zones is not None:
        import datetime as _dt

        from uasnav.mission.zones import check_zones

        until = None
        if when is not None:
            duration, how = _flight_duration(u, req, ranking, area, db)
            until = when + _dt.timedelta(seconds=duration)
            window = {
                "start": when.isoformat(),
                "end": until.isoformat(),
                "duration_s": duration,
                "from": how,
            }
        zone_check = check_zones(
            zones,
            area,
            height_m=req.altitude_m,
            ground_elevation_m=req.ground_elevation_m,
            when=when,
            until=until,
            source=zones_source,
        )
        for h in zone_check.hits:
            notes.append(f"zone {h.identifier} ({h.restriction}): {h.requires}")
        banned = [h for h in zone_check.hits if h.restriction == "PROHIBITED"]
        if banned:
            # Nothing is presented as flyable: the configurations are withheld (kept for an
            # exemption request to the zone authority) and the mission is rejected by zone.
            withheld, ranking = ranking, []
            # the operations' best configurations are withheld too: no rank in an empty ranking
            operations = [replace(o, rank=None) for o in operations]
            for h in banned:
                rejections.append(
                    Rejection(
                        "mission",
                        req.mission,
                        "zone-prohibited",
                        float("nan"),
                        float("nan"),
                        "",
                        f"the area enters PROHIBITED zone {h.identifier} {h.name}"
                        + ("" if h.certain else f" (counted as entered: {'; '.join(h.why)})")
                        + (f": {h.message}" if h.message else ""),
                    )
                )
    return Selection(
        requirements=req,
        mission_name=mission.name,
        features=dict(mission.features),
        equipment=equipment,
        regulatory_height_m=main.h_reg,
        required_hfov_deg=required_hfov_deg(req.image_size_m[0], main.h_cam),
        vlos_required=main.vlos_required,
        uas_ok=uas_ok,
        camera_ok=cam_ok,
        pair_ok=pair_ok,
        rejections=rejections,
        ranking=ranking,
        scores=scores,
        database=db,
        notes=notes,
        operation=op,
        sora=sora,
        zones=zone_check,
        scenarios=scenarios,
        withheld=withheld,
        flight_window=window,
        operations=operations,
        camera_height_m=float(main.h_cam),
        targets=targets,
    )
