"""The selector: requirements → equipment, feasible UAS and cameras, ranked configurations
(thesis Figure 66 steps 1–6)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from uasnav.mission.database import Database, load_database
from uasnav.mission.feasibility import (
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
from uasnav.mission.regulations import Regulations, load_regulations
from uasnav.mission.scoring import ScoreMatrix, Targets, Weights, rank, score_matrix
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


@dataclass
class Selection:
    """Everything the output interface of Figure 70 shows."""

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

    @property
    def authorisation(self) -> dict:
        """The verdict an operator files against: ``authorisable`` (False when a PROHIBITED zone
        is entered or nothing is feasible), the ``blocking`` reasons and the ``requirements``
        (the category's authorisation, STS/PDRA or FAA waivers that apply, zone authorisations
        and conditions)."""
        op, req = self.operation, self.requirements
        blocking = [r.message for r in self.rejections if r.test == "zone-prohibited"]
        needs: list[str] = []
        if op is not None and req.jurisdiction == "easa":
            if op.category == "open":
                sub = self.chosen.open_subcategory if self.chosen else None
                where = f"open category {sub}" if sub else "open category"
                needs.append(f"{where}: no operational authorisation ({op.legal_basis})")
            elif op.category == "specific":
                sail = (
                    f", SORA {self.sora.edition} SAIL {self.sora.sail}"
                    if self.sora and self.sora.sail
                    else ""
                )
                needs.append(
                    f"operational authorisation from the competent authority ((EU) 2019/947 Art. 12{sail})"
                )
                for x in self.scenarios:
                    if x.applies:
                        how = "declaration" if x.id.startswith("STS") else "authorisation"
                        needs.append(f"or {how} under {x.id} ({x.source})")
        else:
            needs += [f"{x.id}: {'; '.join(x.reasons)} ({x.source})" for x in self.scenarios if x.applies]
        if self.sora is not None and self.sora.certified:
            blocking.append("outside the SORA: certified category")
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
            verdict = "no feasible configuration"
        elif len(needs) > 1 or (needs and not needs[0].startswith("open category")):
            verdict = "authorisable with the requirements listed"
        else:
            verdict = "no authorisation needed (open category)" if needs else "authorisable"
        return {
            "authorisable": not blocking and bool(self.ranking),
            "verdict": verdict,
            "blocking": blocking,
            "requirements": needs,
        }

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
            "feasible_uas": self.feasible_uas,
            "feasible_cameras": self.feasible_cameras,
            "rejections": [x.__dict__ for x in self.rejections],
            "ranking": [c.__dict__ for c in self.ranking],
            "weights": self.scores.weights.__dict__,
            "notes": self.notes,
            "operation": self.operation.to_dict() if self.operation else None,
            "sora": self.sora.to_dict() if self.sora else None,
            "zones": self.zones.to_dict() if self.zones else None,
            "scenarios": [x.__dict__ | {"reasons": list(x.reasons)} for x in self.scenarios],
            "chosen_equipment": self.equipment_on(self.chosen.uas_id) if self.chosen else [],
            "authorisation": self.authorisation,
            "withheld_ranking": [c.__dict__ for c in self.withheld],
            "flight_window": self.flight_window,
        }


def equipment_tests(u, req: Requirements, equipment: list[EquipmentNeed]) -> list[TestResult]:
    """Equipment tests on the UAS: the GNSS autopilot when required (thesis Table 22) and every
    necessary item that is a design feature of the aircraft (not a module that can be fitted)."""
    need = [(e.onboard, e.name) for e in equipment if e.necessary and e.onboard and not e.retrofit]
    return _equipment_tests(u, req.gnss_autopilot, need)


def _flight_duration(u, req: Requirements, ranking: list[RankedPair]) -> tuple[float, str]:
    """(duration s, how it was obtained) of the flight: ``req.flight_duration_s`` when given,
    else the mission time (out and back over the range against the wind at the cruise airspeed,
    :func:`mission_time_s`) of the best-ranked UAS, else the longest finite one in the database."""
    if req.flight_duration_s is not None:
        return float(req.flight_duration_s), "--flight-duration"
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


def _vlos_defaults(
    u, req: Requirements, regs: Regulations
) -> tuple[np.ndarray | None, tuple[float, str] | None]:
    """Each UAS's VLOS distance from its size (:func:`~uasnav.mission.operation.vlos_distance_of`)
    and the operation's default: the largest over the UAS that pass the aircraft tests of the
    category a flight in sight would be in (a flight is VLOS when at least one candidate UA can be
    kept in sight; the others are then rejected by the ``vlos-distance`` test). (None, None) when
    the user gives ``--vlos-distance``."""
    if req.vlos_distance_m is not None or len(u) == 0:
        return None, None
    per = np.asarray(vlos_distance_of(u.span_m, list(u.types)), dtype=float)
    in_sight = derive_operation(req, vlos_default=(np.inf, ""))
    lim = regs.category(req.jurisdiction, in_sight.category).limit("mtom")
    ok = np.ones(len(u), dtype=bool)
    for t in uas_tests(u, req, lim.value_si if lim is not None else np.inf) + _equipment_tests(
        u, req.gnss_autopilot, []
    ):
        ok &= t.ok
    pool = np.flatnonzero(ok) if ok.any() else np.arange(len(u))
    k = int(pool[np.argmax(per[pool])])
    src = (
        f"{VLOS_SOURCE}; the largest of the candidate UAS: {u.label(k)}, {float(u.span_m[k]):g} m "
        f"{u.types[k]}; each UAS is held to its own distance"
    )
    return per, (float(per[k]), src)


def _reject(tests: list[TestResult], kind: str, labels, ids) -> tuple[np.ndarray, list[Rejection]]:
    ok = np.ones(len(ids), dtype=bool)
    out = []
    for t in tests:
        for i in np.flatnonzero(~t.ok):
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
    per_ua_vlos, vlos_default = _vlos_defaults(u, req, regs)
    op = derive_operation(req, vlos_default=vlos_default)
    feats = narrowed_features(dict(mission.features), op)
    equipment = []
    for e in mx.equipment.values():
        st = mx.status_for(e.id, feats, op.facts)
        if st.status != INCOMPATIBLE:
            equipment.append(
                EquipmentNeed(e.id, e.name, e.group, st.status == NECESSARY, st.reason, e.onboard, e.retrofit)
            )
    category = op.category
    cat = regs.category(req.jurisdiction, category)
    h_reg = regs.max_height_m(req.jurisdiction, category)
    mtom_lim = cat.limit("mtom")
    max_mtom = mtom_lim.value_si if mtom_lim is not None else np.inf
    notes = []
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
                f"{op.max_distance_m:g} m exceeds the {op.vlos_distance_m:g} m kept in sight",
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
                    f"required altitude {req.altitude_m:g} m exceeds {chk.limit.describe()}",
                )
            )
    if cat.vlos_required and not op.bvlos:
        notes.append(
            f"{req.jurisdiction}/{category}: VLOS required ({cat.source}); "
            f"{op.max_distance_m:g} m from the pilot, within the {op.vlos_distance_m:g} m kept in sight"
        )
    # eq. 60 at the highest height the regulations allow (thesis §5.2.3.4); if the category sets
    # no height limit the required altitude is used instead.
    h_cam = h_reg if np.isfinite(h_reg) else req.altitude_m
    sight = []
    if per_ua_vlos is not None and op.visibility != "BVLOS":
        # The operation is flown in sight (of the pilot, or of an observer each): a UA too small
        # to be kept in sight at the pilot distance cannot fly it.
        reach = per_ua_vlos * (op.observers + 1)
        sight.append(
            TestResult(
                "vlos-distance",
                reach >= op.max_distance_m,
                reach,
                np.full(len(u), op.max_distance_m),
                "m",
                ">=",
            )
        )
    uas_ok, rej = _reject(
        uas_tests(u, req, max_mtom) + sight + equipment_tests(u, req, equipment), "uas", u.label, u.ids
    )
    rejections += rej
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
    scores = score_matrix(
        u.max_range_m, u.mass_g, u.cost_usd, c.mass_g, c.cost_usd, c.ifov_deg, targets, weights, pair_ok
    )
    is_open = req.jurisdiction == "easa" and category == "open"
    if is_open:
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
    is_specific = req.jurisdiction == "easa" and category == "specific"

    def sora_of(i: int, m: float, quantitative: bool = False) -> SoraResult:
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

    ranking = []
    for i, j in rank(scores.total, top):
        m = float(scores.mass_g[i, j])
        ranking.append(
            RankedPair(
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
                regs.open_subcategory(m, u.eu_class[i], over_people=op.over_people, urban=op.urban)
                if "easa" in regs.jurisdictions
                else None,
                sora_of(i, m).sail if is_specific else None,
            )
        )
    sora = None
    scenarios: tuple[ScenarioCheck, ...] = ()
    if ranking:
        best = ranking[0]
        bi = u.ids.index(best.uas_id)
        if is_specific:
            sora = sora_of(bi, best.mass_g, quantitative=True)
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
            duration, how = _flight_duration(u, req, ranking)
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
        req,
        mission.name,
        dict(mission.features),
        equipment,
        h_reg,
        required_hfov_deg(req.image_size_m[0], h_cam),
        cat.vlos_required,
        uas_ok,
        cam_ok,
        pair_ok,
        rejections,
        ranking,
        scores,
        db,
        notes,
        op,
        sora,
        zone_check,
        scenarios,
        withheld,
        window,
    )
