"""The selector: requirements → equipment, feasible UAS and cameras, ranked configurations
(thesis Figure 66 steps 1–6)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from uasnav.mission.database import Database, load_database
from uasnav.mission.feasibility import (
    Rejection,
    Requirements,
    TestResult,
    camera_tests,
    describe,
    pair_tests,
    required_hfov_deg,
    uas_tests,
)
from uasnav.mission.matrices import INCOMPATIBLE, Matrices, load_matrices
from uasnav.mission.regulations import Regulations, load_regulations
from uasnav.mission.scoring import ScoreMatrix, Targets, Weights, rank, score_matrix


@dataclass(frozen=True)
class EquipmentNeed:
    """One equipment item suggested for the mission."""

    id: str
    name: str
    group: str
    necessary: bool


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
                "category": r.category,
                "max_height_m": self.regulatory_height_m,
                "vlos_required": self.vlos_required,
            },
            "required_hfov_deg": self.required_hfov_deg,
            "feasible_uas": self.feasible_uas,
            "feasible_cameras": self.feasible_cameras,
            "rejections": [x.__dict__ for x in self.rejections],
            "ranking": [c.__dict__ for c in self.ranking],
            "weights": self.scores.weights.__dict__,
            "notes": self.notes,
        }


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
    status = mx.derive(req.mission)
    equipment = [
        EquipmentNeed(e.id, e.name, e.group, status[e.id] == "necessary")
        for e in mx.equipment.values()
        if status[e.id] != INCOMPATIBLE
    ]
    cat = regs.category(req.jurisdiction, req.category)
    h_reg = regs.max_height_m(req.jurisdiction, req.category)
    mtom_lim = cat.limit("mtom")
    max_mtom = mtom_lim.value_si if mtom_lim is not None else np.inf
    notes = []
    rejections: list[Rejection] = []
    height_checks = regs.check(req.jurisdiction, req.category, height_m=req.altitude_m)
    mission_ok = all(c.ok for c in height_checks)
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
    if cat.vlos_required:
        notes.append(
            f"{req.jurisdiction}/{req.category}: VLOS required ({cat.source}); "
            f"range {req.range_m:g} m must stay in sight"
        )
    # eq. 60 at the highest height the regulations allow (thesis §5.2.3.4); if the category sets
    # no height limit the required altitude is used instead.
    h_cam = h_reg if np.isfinite(h_reg) else req.altitude_m
    u, c = db.uas, db.cameras
    uas_ok, rej = _reject(uas_tests(u, req, max_mtom), "uas", u.label, u.ids)
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
                regs.open_subcategory(m, u.eu_class[i]) if "easa" in regs.jurisdictions else None,
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
    )
