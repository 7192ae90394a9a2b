"""Mission selector (thesis §5.2): matrices, database and the precision-agriculture case.

The shipped compliance matrices are compared with the printed Table 20, and the thesis' case
(Tables 22–23, eq. 61) is run on the shipped UAS/camera database: feasible aircraft and cameras,
our ranking, and the thesis' Table-24 pairs scored with our database values. Nothing here is
random; ``seed`` and ``quick`` exist for the common ``run`` signature.

>>> from uasnav.experiments import mission
>>> res = mission.run()
>>> res.table20.cells, res.table20.agree
(300, 167)
>>> [(r.uas, r.camera, round(r.score, 3)) for r in res.table24 if r.score is not None]
[('Phantom 4', 'Micro ADC', 1.426), ('Phantom 3', 'Micro ADC', 1.274)]
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from uasnav.experiments.thesis import TABLE24
from uasnav.mission import (
    Database,
    Matrices,
    RankedPair,
    Requirements,
    Selection,
    Targets,
    Weights,
    load_database,
    load_matrices,
    select,
)
from uasnav.mission.matrices import NECESSARY, Mission, explain_table20
from uasnav.mission.scoring import transfer

#: Thesis (Table 24) names → our database ids; None where the thesis' product cannot be
#: identified as a public one.
TABLE24_IDS: dict[str, str | None] = {
    "Phantom 4": "dji-phantom-4",
    "Phantom 3": "dji-phantom-3-professional",
    "Hexacopter Hawk": None,
    "Based 1": None,
    "Micro ADC": "tetracam-adc-micro",
    "Snap ADC": "tetracam-adc-snap",
}


@dataclass(frozen=True)
class Table20Row:
    """One printed row of Table 20 beside our derivation, per mission (in ``missions`` order).

    ``derived`` is None for a printed row with no Table-19 equipment item. Statuses are
    ``"necessary"``, ``"optional"`` or ``"incompatible"`` (printed: blank, not listed).
    """

    label: str
    equipment: str | None
    derived: tuple[str, ...] | None
    printed: tuple[str, ...]


@dataclass(frozen=True)
class Table20Comparison:
    """Derived missions × equipment against the printed Table 20.

    Attributes
    ----------
    rows : tuple of Table20Row
    cells : int
        Cells of the rows that have an equipment item.
    agree : int
        Cells where derived and printed status are equal.
    agree_necessary : int
        Cells that agree on necessary vs not.
    kinds : tuple of (derived, printed, count)
        Disagreements by kind, most frequent first.
    """

    rows: tuple[Table20Row, ...]
    cells: int
    agree: int
    agree_necessary: int
    kinds: tuple[tuple[str, str, int], ...]


@dataclass(frozen=True)
class Table24Row:
    """One thesis Table-24 pair scored with our database.

    ``score`` is our Score_Total (eq. 61) when the pair is feasible, else None and ``reason``
    says why (not in our database, or the failed feasibility tests).
    """

    uas: str
    camera: str
    thesis_score: float
    score: float | None
    pair: RankedPair | None
    reason: str | None


@dataclass(frozen=True)
class Figure74:
    """The scoring transfer functions of Figure 74 (dimensionless scores)."""

    weight_g: NDArray[np.float64]
    weight_score: NDArray[np.float64]
    range_m: NDArray[np.float64]
    range_score: NDArray[np.float64]


@dataclass(frozen=True)
class MissionResult:
    """Everything chapter 5.2 shows (see :func:`run`).

    Attributes
    ----------
    matrices : Matrices
        Tables 18, 19 (reconstructed) and the printed Table 20, as shipped.
    missions : tuple of Mission
        The missions of Table 18, in document order.
    table20 : Table20Comparison
    database : Database
        The UAS and camera database (Table 21, extended).
    requirements, targets, weights : Requirements, Targets, Weights
        The precision-agriculture case (Tables 22–23, eq. 61).
    selection : Selection
        Its selection over the whole database (top 500).
    table24 : tuple of Table24Row
        The thesis' five pairs scored with our database.
    top5 : tuple of RankedPair
        Our five best configurations.
    figure74 : Figure74
    """

    matrices: Matrices
    missions: tuple[Mission, ...]
    table20: Table20Comparison
    database: Database
    requirements: Requirements
    targets: Targets
    weights: Weights
    selection: Selection
    table24: tuple[Table24Row, ...]
    top5: tuple[RankedPair, ...]
    figure74: Figure74
    #: Every Table 20 disagreement with its kind and reason (:func:`explain_table20`).
    table20_explained: tuple[dict, ...] = ()
    #: The thesis' own case: necessary items from the mission type alone.
    before_necessary: tuple[str, ...] = ()
    #: The thesis' requirements flown at 300 m: VLOS, open category.
    vlos: Selection | None = None


def compare_table20(mx: Matrices) -> Table20Comparison:
    """Our derivation (thesis step 4) against the printed Table 20, cell by cell."""
    missions = list(mx.missions.values())
    rows = []
    for r in mx.table20:
        derived = (
            None if r.equipment is None else tuple(mx.equipment_status(m.id, r.equipment) for m in missions)
        )
        rows.append(Table20Row(r.label, r.equipment, derived, tuple(r.status[m.id] for m in missions)))
    diffs = mx.compare_table20()
    n_cells = sum(len(r.status) for r in mx.table20 if r.equipment)
    nec = [d for d in diffs if (d["derived"] == "necessary") != (d["table20"] == "necessary")]
    kinds: dict[tuple[str, str], int] = {}
    for d in diffs:
        kinds[(d["derived"], d["table20"])] = kinds.get((d["derived"], d["table20"]), 0) + 1
    return Table20Comparison(
        tuple(rows),
        n_cells,
        n_cells - len(diffs),
        n_cells - len(nec),
        tuple((a, b, n) for (a, b), n in sorted(kinds.items(), key=lambda kv: -kv[1])),
    )


def score_thesis_pairs(sel: Selection) -> tuple[Table24Row, ...]:
    """The thesis' Table-24 pairs looked up in our ranking ``sel`` (which must hold every pair)."""
    by_pair = {(cf.uas_id, cf.camera_id): cf for cf in sel.ranking}
    rej: dict[str, list[str]] = {}
    for r in sel.rejections:
        rej.setdefault(r.item, []).append(r.message)
    rows = []
    for uas, cam, score in TABLE24:
        ui, ci = TABLE24_IDS[uas], TABLE24_IDS[cam]
        if ui is None or ci is None:
            rows.append(
                Table24Row(
                    uas, cam, score, None, None, "not identifiable as a public product; not in our database"
                )
            )
            continue
        cf = by_pair.get((ui, ci))
        if cf is not None:
            rows.append(Table24Row(uas, cam, score, cf.score, cf, None))
        else:
            reason = "; ".join(rej.get(ci, []) + rej.get(ui, [])) or "infeasible"
            rows.append(Table24Row(uas, cam, score, None, None, reason))
    return tuple(rows)


def run(
    *, seed: int = 2024, quick: bool = False, progress: Callable[[str], None] | None = None
) -> MissionResult:
    """Matrices against Table 20 and the precision-agriculture selection (Tables 22–24).

    Parameters
    ----------
    seed, quick : int, bool
        Unused: the selector is deterministic and fast.
    progress : callable, optional
        Receives one-line progress messages.
    """
    del seed, quick
    say = progress or (lambda _msg: None)
    say("mission selector: precision agriculture")
    mx = load_matrices()
    db = load_database()
    # the thesis' rule: cameras tested at the highest height the category allows (§5.2.3.4)
    thesis = "regulatory-max"
    req, t, wts = Requirements(camera_height=thesis), Targets(), Weights()
    sel = select(req, database=db, matrices=mx, top=500)
    say("mission selector: VLOS variant (300 m)")
    vlos = select(Requirements(range_m=300.0, camera_height=thesis), database=db, matrices=mx, top=5)
    status = mx.derive(req.mission)
    before = tuple(e.name for e in mx.equipment.values() if status[e.id] == NECESSARY)
    x = np.linspace(0, 2400, 400)
    r = np.linspace(0, 7000, 400)
    fig74 = Figure74(x, transfer(x, *t.weight_g), r, transfer(r, *t.range_m))
    return MissionResult(
        mx,
        tuple(mx.missions.values()),
        compare_table20(mx),
        db,
        req,
        t,
        wts,
        sel,
        score_thesis_pairs(sel),
        tuple(sel.ranking[:5]),
        fig74,
        tuple(explain_table20(mx)),
        before,
        vlos,
    )


__all__ = [
    "TABLE24_IDS",
    "Figure74",
    "MissionResult",
    "Table20Comparison",
    "Table20Row",
    "Table24Row",
    "compare_table20",
    "run",
    "score_thesis_pairs",
]
