"""The operation a mission's requirements describe, each fact with the requirement and the rule
that produced it (VLOS/BVLOS, height, people, urban/rural, day/night, airspace), the category
it falls in and its legal basis, and the checks of the EU standard scenarios and PDRAs and of
FAA Part 107 (over people under Subpart D, night, waivers).

>>> op = derive_operation(Requirements(range_m=300.0))
>>> op.visibility, op.category, op.range_level
('VLOS', 'open', 'lt1km')
>>> derive_operation(Requirements()).visibility   # the thesis' 1500 m
'BVLOS'
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from uasnav.errors import InputError
from uasnav.mission.feasibility import Requirements
from uasnav.mission.sora import DENSITY_CLASSES, density_class

#: Default distance (m) at which a small UA is kept in unaided sight when the user gives none.
#: UK CAA CAP 722 (Unmanned Aircraft System Operations in UK Airspace) treats operations within
#: 500 m horizontally and 400 ft vertically of the remote pilot as normally VLOS; EASA's
#: GM1 Article 2(7) of (EU) 2019/947 gives no distance (it depends on UA size, light,
#: weather). We use 500 m for every UA and say so: no primary document we could check gives a
#: size-to-distance formula, so the default is not derived from the UA's dimension.
DEFAULT_VLOS_DISTANCE_M = 500.0
VLOS_SOURCE = "UK CAA CAP 722 (500 m horizontally normally VLOS); give --vlos-distance for this UA"
#: 120 m above ground: the EU open-category limit (2019/947 Art. 4(1)(e)).
EU_MAX_HEIGHT_M = 120.0
#: Eurostat degree of urbanisation (DEGURBA): urban centres are grid cells of at least
#: 1500 inhabitants/km²; we call an area urban from that density on.
URBAN_DENSITY = 1500.0
#: The three Table 18 range levels (m).
RANGE_LEVELS = (("lt1km", 1000.0), ("1to5km", 5000.0), ("gt5km", math.inf))
OVER_PEOPLE = ("none", "uninvolved", "assemblies")
#: Default population when none is given: an agricultural area (thesis §5.2.3 case).
DEFAULT_POPULATION = "lightly"


@dataclass(frozen=True)
class Fact:
    """One derived fact: ``name`` = ``value``, from ``requirement`` by ``rule``."""

    name: str
    value: str
    requirement: str
    rule: str


@dataclass(frozen=True)
class ScenarioCheck:
    """Whether a standard scenario / PDRA / waiver applies, with the unmet conditions."""

    id: str
    applies: bool
    reasons: tuple[str, ...]
    source: str


@dataclass(frozen=True)
class Operation:
    """The operation derived from the requirements (:func:`derive_operation`).

    Distances and heights in m (height above ground), population density in ppl/km².
    ``category`` is the operational category the operation needs (``open``/``specific`` for
    EASA, ``part107`` for the FAA) and ``legal_basis`` the article that puts it there;
    ``facts`` are the strings the equipment rules read (``bvlos``, ``urban`` …).
    """

    jurisdiction: str
    visibility: str
    max_distance_m: float
    vlos_distance_m: float
    height_m: float
    over_people: str
    population: str
    population_density: float
    urban: bool
    night: bool
    airspace: str
    range_level: str
    category: str
    legal_basis: str
    facts: frozenset[str]
    derivation: tuple[Fact, ...]
    notes: tuple[str, ...] = field(default_factory=tuple)
    observers: int = 0

    @property
    def bvlos(self) -> bool:
        """Beyond the remote pilot's own sight (BVLOS or EVLOS)."""
        return self.visibility != "VLOS"

    def to_dict(self) -> dict:
        """Plain JSON."""
        return {
            "jurisdiction": self.jurisdiction,
            "visibility": self.visibility,
            "max_distance_m": self.max_distance_m,
            "vlos_distance_m": self.vlos_distance_m,
            "height_m": self.height_m,
            "over_people": self.over_people,
            "population": self.population,
            "population_density": self.population_density,
            "environment": "urban" if self.urban else "rural",
            "night": self.night,
            "airspace": self.airspace,
            "range_level": self.range_level,
            "category": self.category,
            "legal_basis": self.legal_basis,
            "facts": sorted(self.facts),
            "derivation": [f.__dict__ for f in self.derivation],
            "notes": list(self.notes),
            "observers": self.observers,
        }


def range_level(distance_m: float) -> str:
    """Table 18's range level of a distance (m): < 1 km, 1–5 km, > 5 km (1000 m is 1to5km)."""
    return next(name for name, upper in RANGE_LEVELS if distance_m < upper)


def population_of(req: Requirements) -> tuple[str, float]:
    """SORA 2.5 population class and density (ppl/km²) of the requirements."""
    if req.population_density is not None:
        return density_class(req.population_density), req.population_density
    name = req.population_class or DEFAULT_POPULATION
    if name not in DENSITY_CLASSES:
        raise InputError(f"unknown population class {name!r}; known: {', '.join(DENSITY_CLASSES)}")
    return name, DENSITY_CLASSES[name]


def derive_operation(req: Requirements) -> Operation:
    """Derive the operation from ``req``; see :class:`Operation`."""
    facts: list[Fact] = []
    dist = req.max_distance_m if req.max_distance_m is not None else req.range_m
    dist_req = "--max-distance" if req.max_distance_m is not None else "--range (no --max-distance given)"
    if req.vlos_distance_m is not None:
        vlos_d, vlos_src = req.vlos_distance_m, "--vlos-distance"
    else:
        vlos_d, vlos_src = DEFAULT_VLOS_DISTANCE_M, VLOS_SOURCE
    if dist <= vlos_d:
        vis = "VLOS"
    elif req.observers > 0 and dist <= vlos_d * (req.observers + 1):
        # Observers posted along the route each keep the UA in sight over the same distance.
        vis = "EVLOS"
    else:
        vis = "BVLOS"
    facts.append(
        Fact(
            "visibility",
            vis,
            f"{dist_req} = {dist:g} m, --observers = {req.observers}",
            f"kept in sight up to {vlos_d:g} m ({vlos_src}); "
            "VLOS per (EU) 2019/947 Art. 2(7), 14 CFR §107.31; EVLOS: kept in sight by airspace "
            "observers posted along the route, each over the same distance (JARUS SORA glossary)",
        )
    )
    lvl = range_level(dist)
    facts.append(
        Fact("range level", lvl, f"{dist_req} = {dist:g} m", "thesis Table 18 levels <1 km, 1–5 km, >5 km")
    )
    facts.append(
        Fact(
            "height",
            f"{req.altitude_m:g} m AGL",
            f"--altitude = {req.altitude_m:g} m",
            "(EU) 2019/947 Art. 4(1)(e) 120 m; 14 CFR §107.51(b) 400 ft",
        )
    )
    if req.over_people not in OVER_PEOPLE:
        raise InputError(f"over_people {req.over_people!r}: expected one of {', '.join(OVER_PEOPLE)}")
    facts.append(
        Fact(
            "over people",
            req.over_people,
            f"--over-people = {req.over_people}",
            "(EU) 2019/947 Art. 4(1)(c) (never over assemblies in the open category), UAS.OPEN.020–040; "
            "14 CFR §107.39 and Subpart D",
        )
    )
    pop, density = population_of(req)
    facts.append(
        Fact(
            "population",
            f"{pop} ({density:g} ppl/km²)",
            "--population-density"
            if req.population_density is not None or req.population_class
            else f"default ({DEFAULT_POPULATION}: agricultural area)",
            "JARUS SORA 2.5 Main Body Table 2 rows (< 5, < 50, < 500, < 5000, < 50000 ppl/km²)",
        )
    )
    urban = density >= URBAN_DENSITY or pop == "assemblies"
    facts.append(
        Fact(
            "environment",
            "urban" if urban else "rural",
            f"population density {density:g} ppl/km²",
            f"Eurostat DEGURBA urban centre >= {URBAN_DENSITY:g} inhabitants/km²",
        )
    )
    facts.append(
        Fact(
            "time of day",
            "night" if req.night else "day",
            f"--night = {'yes' if req.night else 'no'}",
            "14 CFR §107.29 (2021 rule); (EU) 2019/947 UAS.OPEN.060 (lights at night)",
        )
    )
    controlled = req.airspace not in ("uncontrolled", "atypical")
    facts.append(
        Fact(
            "airspace",
            req.airspace,
            f"--airspace = {req.airspace}",
            "JARUS SORA initial ARC decision tree (2.5 Figure 6, 2.0 Figure 4); 14 CFR §107.41",
        )
    )
    tokens = {vis.lower()}
    if controlled:
        tokens.add("controlled-airspace")
    if req.night:
        tokens.add("night")
    if req.over_people != "none":
        tokens.add("over-people")
    if urban:
        tokens.add("urban")
    if req.altitude_m > EU_MAX_HEIGHT_M:
        tokens.add("above-120m")
    notes: list[str] = []
    if req.jurisdiction == "easa":
        why_not = []
        if vis != "VLOS":
            why_not.append(
                f"{vis} (open category requires the remote pilot's own VLOS: Art. 4(1)(d), Art. 2(7))"
            )
        if req.altitude_m > EU_MAX_HEIGHT_M:
            why_not.append(f"{req.altitude_m:g} m above 120 m (Art. 4(1)(e))")
        if req.over_people == "assemblies":
            why_not.append("over assemblies of people (Art. 4(1)(c))")
        derived = "open" if not why_not else "specific"
        basis = (
            "(EU) 2019/947 Art. 4 (open category: VLOS, <= 120 m, < 25 kg, not over assemblies)"
            if derived == "open"
            else "(EU) 2019/947 Art. 5 (specific category: " + "; ".join(why_not) + ")"
        )
        category = req.category if req.category is not None else derived
        if req.category is not None and req.category != derived:
            notes.append(f"category {req.category} was given; the operation derives {derived}: {basis}")
        if req.night:
            notes.append(
                "night: the UA's green flashing light must be on ((EU) 2019/947 UAS.OPEN.060, as amended)"
            )
    elif req.jurisdiction == "faa":
        category = req.category if req.category is not None else "part107"
        basis = "14 CFR Part 107 (small UAS < 55 lb)"
        derived = category
    else:
        if req.category is None:
            raise InputError(f"jurisdiction {req.jurisdiction!r}: give the category too")
        category, basis, derived = req.category, f"{req.jurisdiction} {req.category}", req.category
    facts.append(Fact("category", category, "the facts above", basis))
    return Operation(
        req.jurisdiction,
        vis,
        float(dist),
        float(vlos_d),
        float(req.altitude_m),
        req.over_people,
        pop,
        float(density),
        urban,
        req.night,
        req.airspace,
        lvl,
        category,
        basis,
        frozenset(tokens),
        tuple(facts),
        tuple(notes),
        req.observers,
    )


def narrowed_features(features: dict[str, tuple[str, ...]], op: Operation) -> dict[str, tuple[str, ...]]:
    """A mission's Table 18 levels narrowed to the flown operation: ``operations`` to VLOS or
    BVLOS and ``range`` to the level of the maximum distance (the other features stay)."""
    out = dict(features)
    # Table 18 knows VLOS, BVLOS and BLOS: an EVLOS flight is beyond the pilot's own sight.
    out["operations"] = ("vlos",) if op.visibility == "VLOS" else ("bvlos",)
    out["range"] = (op.range_level,)
    return out


# --- EU standard scenarios and PDRAs ------------------------------------------------------


def eu_scenarios(
    op: Operation, *, eu_class: str | None, mtom_g: float, dimension_m: float, speed_ms: float
) -> tuple[ScenarioCheck, ...]:
    """Which EU standard scenarios (STS-01, STS-02) and PDRAs (G01) fit the operation with one UA.

    Sources: (EU) 2019/947 Appendix 1 as inserted by (EU) 2020/639 (UAS.STS-01.010/020,
    UAS.STS-02.010/020); AMC2 Article 11 PDRA-G01 v1.3 (EASA ED Decision 2023/012/R), scope (a).
    The controlled ground area the STSs need is not an input: it is listed as a condition.
    """
    ke = 0.5 * mtom_g / 1000.0 * speed_ms**2
    out = []
    why = []
    if op.visibility != "VLOS":
        why.append("STS-01 is VLOS")
    if eu_class != "C5":
        why.append(f"UA class {eu_class or 'none'}, STS-01 needs C5")
    if op.height_m > EU_MAX_HEIGHT_M:
        why.append("above 120 m")
    if op.over_people == "assemblies":
        why.append("over assemblies")
    out.append(
        ScenarioCheck(
            "STS-01",
            not why,
            (*why, "needs a controlled ground area under the UA"),
            "(EU) 2019/947 Appendix 1 UAS.STS-01.010/020 ((EU) 2020/639)",
        )
    )
    why = []
    if op.visibility == "VLOS":
        why.append("STS-02 is BVLOS (a VLOS flight needs none)")
    if eu_class != "C6":
        why.append(f"UA class {eu_class or 'none'}, STS-02 needs C6")
    if op.max_distance_m > (2000.0 if op.observers > 0 else 1000.0):
        why.append(
            f"{op.max_distance_m:g} m from the pilot, STS-02 allows 1 km (2 km with airspace observers)"
        )
    if DENSITY_CLASSES[op.population] >= 500.0:
        why.append("not a sparsely populated area")
    if op.height_m > EU_MAX_HEIGHT_M:
        why.append("above 120 m")
    out.append(
        ScenarioCheck(
            "STS-02",
            not why,
            (*why, "needs a controlled ground area under the UA"),
            "(EU) 2019/947 Appendix 1 UAS.STS-02.010/020 ((EU) 2020/639)",
        )
    )
    why = []
    if op.visibility == "VLOS":
        why.append("PDRA-G01 is BVLOS")
    if dimension_m > 3.0:
        why.append(f"dimension {dimension_m:g} m > 3 m")
    if ke > 34e3:
        why.append(f"kinetic energy {ke / 1e3:.1f} kJ > 34 kJ")
    if DENSITY_CLASSES[op.population] >= 500.0:
        why.append("not a sparsely populated area")
    if op.height_m >= 150.0:
        why.append("not below 150 m")
    if op.airspace not in ("uncontrolled", "atypical"):
        why.append("not in uncontrolled airspace")
    out.append(
        ScenarioCheck(
            "PDRA-G01",
            not why,
            tuple(why),
            "AMC2 Article 11 (EU) 2019/947, PDRA-G01 v1.3 scope (a)(1)-(5) (ED Decision 2023/012/R)",
        )
    )
    return tuple(out)


# --- FAA Part 107 ---------------------------------------------------------------------------

#: 14 CFR §107.39 / Subpart D categories for operations over people.
FAA_CAT1_LB = 0.55


def faa_checks(op: Operation, *, mtom_g: float | None) -> tuple[ScenarioCheck, ...]:
    """Waivers and authorisations a Part 107 operation needs, and its Subpart D category.

    Sources: 14 CFR §107.31 (VLOS), §107.29 (night, as amended 2021: anti-collision lighting
    visible 3 statute miles, pilot night training), §107.39 and §§107.105–107.140 (operations
    over people, categories 1–4), §107.41 (controlled airspace: ATC authorisation, not a
    waiver), §107.51(b) (400 ft), §107.205 (waivable sections).
    """
    out = []
    if op.bvlos:
        # Observers posted away from the remote pilot (daisy-chained) are not §107.33 visual
        # observers: EVLOS needs the waiver too.
        out.append(
            ScenarioCheck("waiver §107.31", True, (op.visibility,), "14 CFR §107.31, §107.33, §107.205(b)")
        )
    if op.height_m > 121.92:
        out.append(
            ScenarioCheck("waiver §107.51(b)", True, ("above 400 ft AGL",), "14 CFR §107.51(b), §107.205")
        )
    if op.night:
        out.append(
            ScenarioCheck(
                "night §107.29",
                True,
                ("anti-collision lighting visible 3 statute miles; remote pilot night training",),
                "14 CFR §107.29 (2021 rule, no waiver needed)",
            )
        )
    if op.airspace != "uncontrolled":
        out.append(
            ScenarioCheck(
                "ATC authorisation §107.41",
                True,
                (f"airspace {op.airspace}",),
                "14 CFR §107.41 (LAANC / DroneZone)",
            )
        )
    if op.over_people != "none":
        lb = math.inf if mtom_g is None else mtom_g / 453.59237
        if op.over_people == "assemblies":
            cat = (
                "category 4 (airworthiness certificate) or waiver §107.39; categories 1–2 allow "
                "open-air assemblies only with Remote ID, category 3 never"
            )
        elif lb <= FAA_CAT1_LB:
            cat = "category 1 (≤ 0.55 lb, no exposed rotating parts that could lacerate)"
        else:
            cat = (
                "category 2 or 3 (manufacturer's declaration of compliance, §107.120/§107.130) or category 4"
            )
        out.append(ScenarioCheck("over people Subpart D", True, (cat,), "14 CFR §107.39, §§107.105–107.140"))
    return tuple(out)
