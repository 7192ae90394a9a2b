"""Compliance matrices: missions × features (Table 18), features × equipment (Table 19,
reconstructed) and the derived missions × equipment matrix compared with Table 20.

Derivation rule (the thesis' step 4, made explicit because §5.2.2.4 gives none): a mission
feature may span several levels (e.g. range "<1 km to >5 km"). For one equipment item and one
feature, the item is *necessary* if any of the mission's levels makes it necessary (the hardest
case sets the requirement) and *incompatible* only if every level is incompatible (the mission
can be flown in a compatible case). Across features, necessary wins over incompatible (a
requirement cannot be waived), incompatible over optional.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

from uasnav.errors import DataFormatError, InputError
from uasnav.mission.loading import load_document

NECESSARY, OPTIONAL, INCOMPATIBLE = "necessary", "optional", "incompatible"
_SYMBOL = {"N": NECESSARY, "o": OPTIONAL, "-": INCOMPATIBLE}


@dataclass(frozen=True)
class Equipment:
    """One equipment item of Table 19 with its reconstructed rules."""

    id: str
    name: str
    group: str
    necessary_when: frozenset[tuple[str, str]]
    incompatible_when: frozenset[tuple[str, str]]
    always_necessary: bool
    note: str
    table20_name: str | None = None
    #: Operation rules: (facts, reason) — necessary when the operation has any of the facts.
    operation_rules: tuple[tuple[frozenset[str], str], ...] = ()
    #: Database token of the per-UAS equipment that provides this item (None: not recorded).
    onboard: str | None = None
    #: Whether the item can be fitted to a UAS that lacks it (a module, not a design feature).
    retrofit: bool = False


@dataclass(frozen=True)
class EquipmentStatus:
    """The status of one item for one mission flown as one operation, and why."""

    id: str
    status: str
    reason: str


@dataclass(frozen=True)
class Mission:
    """One mission of Table 18: feature id → tuple of levels."""

    id: str
    name: str
    features: dict[str, tuple[str, ...]]


@dataclass(frozen=True)
class Table20Row:
    """One printed row of Table 20: status per mission id."""

    label: str
    equipment: str | None
    status: dict[str, str]


@dataclass
class Matrices:
    """The three matrices as loaded from ``matrices.xml``."""

    features: dict[str, tuple[str, ...]]
    feature_names: dict[str, str]
    missions: dict[str, Mission]
    equipment: dict[str, Equipment]
    table20: list[Table20Row] = field(default_factory=list)
    source: str = ""

    def mission(self, mission_id: str) -> Mission:
        """The mission ``mission_id`` or an InputError listing the known ones."""
        try:
            return self.missions[mission_id]
        except KeyError:
            raise InputError(f"unknown mission {mission_id!r}; known: {', '.join(self.missions)}") from None

    def equipment_status(self, mission_id: str, equipment_id: str) -> str:
        """Derived status (necessary / optional / incompatible) of one item for one mission."""
        mission = self.mission(mission_id)
        item = self.equipment[equipment_id]
        if item.always_necessary:
            return NECESSARY
        incompatible = False
        for feat, levels in mission.features.items():
            cells = [(feat, lv) for lv in levels]
            if any(c in item.necessary_when for c in cells):
                return NECESSARY
            if cells and all(c in item.incompatible_when for c in cells):
                incompatible = True
        return INCOMPATIBLE if incompatible else OPTIONAL

    def status_for(
        self,
        equipment_id: str,
        features: dict[str, tuple[str, ...]],
        facts: frozenset[str] = frozenset(),
    ) -> EquipmentStatus:
        """Status of one item for a mission's ``features`` (Table 18 levels, possibly narrowed
        to the operation) and the operation's ``facts``, with the rule that decided it.

        The Table 19 rule of the module docstring, then the operation rules: an operation rule
        makes an item necessary even where a feature level alone would exclude it (the
        operation is what is flown; e.g. a BLOS link for a BVLOS flight).
        """
        item = self.equipment[equipment_id]
        if item.always_necessary:
            return EquipmentStatus(item.id, NECESSARY, "always necessary (" + item.note + ")")
        for tokens, reason in item.operation_rules:
            if tokens & facts:
                return EquipmentStatus(item.id, NECESSARY, "operation " + reason)
        incompatible = None
        for feat, levels in features.items():
            cells = [(feat, lv) for lv in levels]
            hit = next((c for c in cells if c in item.necessary_when), None)
            if hit is not None:
                return EquipmentStatus(
                    item.id, NECESSARY, f"Table 19: {self.feature_names.get(feat, feat)} {hit[1]} needs it"
                )
            if cells and all(c in item.incompatible_when for c in cells) and incompatible is None:
                incompatible = (
                    f"Table 19: not used at {self.feature_names.get(feat, feat)} {' '.join(levels)}"
                )
        if incompatible is not None:
            return EquipmentStatus(item.id, INCOMPATIBLE, incompatible)
        return EquipmentStatus(item.id, OPTIONAL, "no rule of Table 19 or of the operation needs it")

    def derive(self, mission_id: str) -> dict[str, str]:
        """Missions × equipment for one mission: equipment id → status (thesis step 4)."""
        return {eid: self.equipment_status(mission_id, eid) for eid in self.equipment}

    def compare_table20(self) -> list[dict]:
        """Every cell where the derivation and the printed Table 20 disagree.

        Returns a list of ``{"equipment", "label", "mission", "derived", "table20"}``.
        """
        out = []
        for row in self.table20:
            if row.equipment is None:
                continue
            for mid, printed in row.status.items():
                derived = self.equipment_status(mid, row.equipment)
                if derived != printed:
                    out.append(
                        {
                            "equipment": row.equipment,
                            "label": row.label,
                            "mission": mid,
                            "derived": derived,
                            "table20": printed,
                        }
                    )
        return out


def explain_table20(mx: Matrices) -> list[dict]:
    """Every cell where the derivation and the printed Table 20 disagree, each with the reason.

    Kinds: ``blank-is-not-relevant`` (we derive optional, Table 20 leaves it blank: Table 20 uses
    blank for "not relevant", Table 19 allows the item); ``mission-objective`` (Table 20 asks
    for an item that no feature rule of Table 19 / §5.2.2.3 asks for — §5.2.2.4 motivates such
    items by the mission's objective, which the features cannot express); ``rule-applied`` (a
    rule of §5.2.2.3, named by its Table 19 cell, makes the item necessary where Table 20 does
    not; we follow the stated rule); ``incompatible-cell`` (a Table 19 incompatibility with a
    physical reason excludes an item Table 20 lists).
    """
    out = []
    for d in mx.compare_table20():
        mission = mx.mission(d["mission"])
        st = mx.status_for(d["equipment"], dict(mission.features))
        derived, printed = d["derived"], d["table20"]
        if derived == OPTIONAL and printed == INCOMPATIBLE:
            kind = "blank-is-not-relevant"
            why = "Table 20 leaves blank (not relevant) what Table 19 allows; no feature excludes it"
        elif printed == NECESSARY:
            kind = "mission-objective"
            why = (
                "Table 20 requires it but no rule of §5.2.2.3 names a feature level of this mission "
                "(objective-driven, §5.2.2.4)"
            )
        elif derived == NECESSARY:
            kind = "rule-applied"
            why = f"{st.reason}; Table 20 does not apply this rule"
            span = [
                f
                for f, lv in mission.features.items()
                if len(lv) > 1 and mx.feature_names.get(f, f) in st.reason
            ]
            if span:
                f = span[0]
                why += (
                    f" (the mission spans {f} {' '.join(mission.features[f])}: with the operation known, "
                    "only the flown level counts — uasnav.mission.operation)"
                )
        else:
            kind = "incompatible-cell"
            why = f"{st.reason} (Table 19 blank kept for its physical reason: see the item's note)"
        out.append({**d, "kind": kind, "reason": why})
    return out


def _cells(text: str, features: dict[str, tuple[str, ...]], where: str, line: int | None) -> frozenset:
    cells = set()
    for tok in text.split():
        feat, _, level = tok.partition(":")
        if feat not in features or level not in features[feat]:
            raise DataFormatError(f"unknown feature cell {tok!r}", path=where, line=line)
        cells.add((feat, level))
    return frozenset(cells)


def load_matrices(source: str | os.PathLike | None = None, **fetch_kw) -> Matrices:
    """Load the compliance matrices (default: the copy shipped in the package).

    Beyond the XSD, checks the cross-references: feature ids and levels used by missions and
    rules exist, Table 20 rows have one symbol per mission and name known equipment.
    """
    tree, where = load_document(source, "matrices", default="matrices.xml", **fetch_kw)
    root = tree.getroot()
    features, names = {}, {}
    for f in root.iterfind("features/feature"):
        features[f.get("id")] = tuple(f.get("levels").split())
        names[f.get("id")] = (f.text or "").strip()
    missions = {}
    for m in root.iterfind("missions/mission"):
        feats = {}
        for v in m.iterfind("value"):
            fid = v.get("feature")
            levels = tuple(v.get("levels").split())
            if fid not in features or any(lv not in features[fid] for lv in levels):
                raise DataFormatError(
                    f"mission {m.get('id')}: unknown feature/level {fid}:{levels}",
                    path=where,
                    line=v.sourceline,
                )
            feats[fid] = levels
        missions[m.get("id")] = Mission(m.get("id"), m.get("name"), feats)
    equipment = {}
    for it in root.iterfind("equipment/item"):
        nec, inc = it.find("necessary"), it.find("incompatible")
        equipment[it.get("id")] = Equipment(
            id=it.get("id"),
            name=it.get("name"),
            group=it.get("group"),
            necessary_when=_cells(nec.get("when"), features, where, nec.sourceline)
            if nec is not None
            else frozenset(),
            incompatible_when=_cells(inc.get("when"), features, where, inc.sourceline)
            if inc is not None
            else frozenset(),
            always_necessary=it.get("always") == "necessary",
            note=(it.findtext("note") or "").strip(),
            table20_name=it.get("table20"),
            operation_rules=tuple(
                (frozenset(op.get("necessary").split()), op.get("reason")) for op in it.iterfind("operation")
            ),
            onboard=it.get("onboard"),
            retrofit=it.get("retrofit") in ("true", "1"),
        )
    order = list(missions)
    rows = []
    for r in root.iterfind("table20/row"):
        sym = (r.text or "").strip()
        if len(sym) != len(order):
            raise DataFormatError(
                f"Table 20 row {r.get('label')!r} has {len(sym)} symbols for {len(order)} missions",
                path=where,
                line=r.sourceline,
            )
        eq = r.get("equipment")
        if eq is not None and eq not in equipment:
            raise DataFormatError(
                f"Table 20 row names unknown equipment {eq!r}", path=where, line=r.sourceline
            )
        rows.append(
            Table20Row(r.get("label"), eq, {mid: _SYMBOL[s] for mid, s in zip(order, sym, strict=True)})
        )
    return Matrices(features, names, missions, equipment, rows, (root.findtext("source") or "").strip())
