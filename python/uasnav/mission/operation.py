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
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from uasnav.errors import InputError
from uasnav.mission.feasibility import Requirements
from uasnav.mission.readable import metres
from uasnav.mission.sora import DENSITY_CLASSES, density_class

#: The distance (m) up to which a UA is kept in unaided sight, from its size, when the user gives
#: none: EASA AMC1 Article 11 Annex A §A.5.2.5 (Annex to ED Decision 2025/018/R, AMC & GM to
#: (EU) 2019/947 Issue 1 Amendment 3, pp. 79–80; worked table §A.5.2.6, p. 81). The VLOS
#: distance is the smaller of the attitude line of sight ALOS (the distance up to which the
#: remote pilot can see the UA's position and orientation, "determined in practical tests"):
#: ALOS = 327·CD + 20 m for rotorcraft and multirotors, 490·CD + 30 m for fixed wing, CD the
#: maximum characteristic dimension (m); and the detection line of sight DLOS = 0.3·GV, the
#: ground visibility GV being at most 5 km (so DLOS ≤ 1500 m). VTOL fixed wings take the
#: rotorcraft line (the smaller: they hover near the pilot). Independent field data agree in
#: order: Li et al. (Applied Ergonomics 81, a Phantom 4 seen by 50 % of observers at 245 m) and
#: Li, Sun & Li (Appl. Sci. 10(16) 5501, 2020, doi:10.3390/app10165501, a Mavic Air at 307 m,
#: visual angle 0.065°) — detection distances, longer than the ALOS of a 0.35 m UA (134 m),
#: which asks for the attitude too.
ALOS_ROTORCRAFT = (327.0, 20.0)
ALOS_FIXED_WING = (490.0, 30.0)
DLOS_FRACTION = 0.3
MAX_GROUND_VISIBILITY_M = 5000.0
VLOS_SOURCE = "EASA AMC1 Art. 11 Annex A §A.5.2.5 (ED Decision 2025/018/R, pp. 79-80): min(ALOS, DLOS)"
#: The UA assumed when none is known (``derive_operation`` alone): a 1 m multirotor, the first
#: row of EASA's worked table (347 m). The selector uses each UA's own size instead.
REFERENCE_UA = (1.0, "multirotor")


def vlos_distance_of(dimension_m, kind="multirotor", ground_visibility_m: float = MAX_GROUND_VISIBILITY_M):
    """VLOS distance (m) of a UA of maximum characteristic dimension ``dimension_m`` (m, scalar or
    array) and ``kind`` (``fixed-wing``, else rotorcraft; scalar or sequence): min(ALOS, DLOS),
    see :data:`ALOS_ROTORCRAFT`.

    >>> float(vlos_distance_of(1.0)), float(vlos_distance_of(2.0, "fixed-wing")), float(vlos_distance_of(5.0))
    (347.0, 1010.0, 1500.0)
    """
    d = np.asarray(dimension_m, dtype=float)
    if not np.all(np.isfinite(d)) or np.any(d <= 0):
        raise InputError(f"UA characteristic dimension {dimension_m!r} m: must be finite and > 0")
    if not (math.isfinite(ground_visibility_m) and ground_visibility_m > 0):
        raise InputError(f"ground visibility {ground_visibility_m!r} m: must be finite and > 0")
    fixed = np.asarray(kind) == "fixed-wing"
    a = np.where(fixed, ALOS_FIXED_WING[0], ALOS_ROTORCRAFT[0])
    b = np.where(fixed, ALOS_FIXED_WING[1], ALOS_ROTORCRAFT[1])
    dlos = DLOS_FRACTION * min(ground_visibility_m, MAX_GROUND_VISIBILITY_M)
    return np.minimum(a * d + b, dlos)


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


def derive_operation(req: Requirements, *, vlos_default: tuple[float, str] | None = None) -> Operation:
    """Derive the operation from ``req``; see :class:`Operation`.

    ``vlos_default`` is (distance m, source) used when ``req`` gives no VLOS distance — the
    selector passes the largest :func:`vlos_distance_of` over its candidate UAS; without it the
    :data:`REFERENCE_UA` is assumed.
    """
    facts: list[Fact] = []
    dist = req.max_distance_m if req.max_distance_m is not None else req.range_m
    dist_req = (
        (req.max_distance_source or "--max-distance")
        if req.max_distance_m is not None
        else "--range (no --max-distance given)"
    )
    if req.vlos_distance_m is not None:
        vlos_d, vlos_src = req.vlos_distance_m, "--vlos-distance"
    elif vlos_default is not None:
        vlos_d, vlos_src = vlos_default
    else:
        vlos_d = float(vlos_distance_of(REFERENCE_UA[0], REFERENCE_UA[1]))
        vlos_src = f"{VLOS_SOURCE}, for a {REFERENCE_UA[0]:g} m {REFERENCE_UA[1]} (no UA given)"
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
            f"{dist_req} = {metres(dist, against=vlos_d)}, --observers = {req.observers}",
            f"kept in sight up to {metres(vlos_d)} ({vlos_src}); "
            "VLOS per (EU) 2019/947 Art. 2(7), 14 CFR §107.31; EVLOS: kept in sight by airspace "
            "observers posted along the route, each over the same distance (JARUS SORA glossary)",
        )
    )
    lvl = range_level(dist)
    facts.append(
        Fact(
            "range level", lvl, f"{dist_req} = {metres(dist)}", "thesis Table 18 levels <1 km, 1–5 km, >5 km"
        )
    )
    facts.append(
        Fact(
            "height",
            f"{metres(req.altitude_m)} AGL",
            req.altitude_source or f"--altitude = {metres(req.altitude_m)}",
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
            why_not.append(f"{metres(req.altitude_m, against=EU_MAX_HEIGHT_M)} above 120 m (Art. 4(1)(e))")
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


#: Density (ppl/km²) below which an area is "sparsely populated" for the STSs and PDRAs: the
#: upper bound of SORA 2.5's "sparsely populated" row ([AMC-2.5] p. 26: < 500 ppl/km²).
SPARSE_DENSITY = 500.0
#: PDRA-G03's height above the surface overflown (m): from a secondary summary (see its source).
PDRA_G03_MAX_HEIGHT_M = 30.0
#: The document behind each scenario check. Page numbers are given only where the primary text
#: was read with its pages; the EASA Easy Access Rules online (HTML) carry none.
PDRA_SOURCES = {
    "STS-01": (
        "(EU) 2019/947 Annex Appendix 1, UAS.STS-01.010/020, inserted by (EU) 2020/639 (OJ L 150, "
        "13.5.2020); not verified against a primary text, no page"
    ),
    "STS-02": (
        "(EU) 2019/947 Annex Appendix 1, UAS.STS-02.010/020, inserted by (EU) 2020/639 (OJ L 150, "
        "13.5.2020); not verified against a primary text, no page"
    ),
    "PDRA-G01": (
        "AMC2 Article 11 of (EU) 2019/947, PDRA-G01 v1.3 (edition September 2023, ED Decision "
        "2023/012/R), scope (a)(1)-(5); EASA Easy Access Rules online (HTML, no page)"
    ),
    "PDRA-S01": (
        "AMC4 Article 11 of (EU) 2019/947, PDRA-S01 v1.2 (edition September 2023, ED Decision "
        "2023/012/R), scope (a)(1)-(5); EASA Easy Access Rules online (HTML, no page)"
    ),
    "PDRA-S02": (
        "AMC5 Article 11 of (EU) 2019/947, PDRA-S02 v1.1 (edition January 2022, ED Decision "
        "2022/002/R), scope (a)(1)-(5); EASA Easy Access Rules online (HTML, no page)"
    ),
    "PDRA-G02": (
        "AMC3 Article 11 of (EU) 2019/947, PDRA-G02 v1.2 (edition September 2023, ED Decision "
        "2023/012/R), scope (a)(1)-(5); EASA Easy Access Rules online (HTML, no page)"
    ),
    "PDRA-G03": (
        "PDRA-G03 (AMC to Article 11 of (EU) 2019/947; EASA's PDRA list names it 'Linear "
        "inspections, agricultural works'): PRIMARY TEXT NOT REACHED; scope (<= 3 m, "
        "<= 34 kJ, BVLOS, sparsely populated, atypical air at <= 30 m above the surface, "
        "pre-programmed, within C2 range) from a secondary summary (eudroneport.com, 'PDRA G-03'), "
        "to be checked against the EASA text"
    ),
}


@dataclass(frozen=True)
class Limit:
    """One scope condition of a scenario: ``fact`` (of the operation and UA, see
    :func:`scenario_facts`) ``test`` ``value``, else the scenario does not apply, ``why``
    (formatted with the facts) saying so.

    ``test`` is ``==``, ``!=``, ``<=``, ``<``, ``in`` or ``not in``; ``<=obs`` compares with
    ``value[1]`` when airspace observers are employed, else ``value[0]``.
    """

    fact: str
    test: str
    value: Any
    why: str

    def met(self, facts: dict[str, Any]) -> bool:
        """Whether ``facts`` satisfy the condition."""
        x = facts[self.fact]
        if self.test == "<=obs":
            return bool(x <= self.value[1 if facts["observers"] > 0 else 0])
        return bool(_TESTS[self.test](x, self.value))


_TESTS: dict[str, Callable[[Any, Any], bool]] = {
    "==": lambda x, v: x == v,
    "!=": lambda x, v: x != v,
    "<=": lambda x, v: x <= v,
    "<": lambda x, v: x < v,
    "in": lambda x, v: x in v,
    "not in": lambda x, v: x not in v,
}


@dataclass(frozen=True)
class Scenario:
    """An EU standard scenario or PDRA: its scope (section (a)) as :class:`Limit` rows, the
    conditions that are not inputs (listed with every check) and its document."""

    id: str
    limits: tuple[Limit, ...]
    also: tuple[str, ...]
    source: str


# Scope conditions shared by several scenarios.
def _needs_vlos(sid: str) -> Limit:
    return Limit("vlos", "==", True, f"{sid} is VLOS")


def _needs_bvlos(sid: str, note: str = "") -> Limit:
    return Limit("vlos", "==", False, f"{sid} is BVLOS{note}")


def _range_1_2km(sid: str) -> Limit:
    """STS-02 / PDRA-S02: 1 km from the remote pilot, 2 km with airspace observers."""
    return Limit(
        "max_distance_m",
        "<=obs",
        (1000.0, 2000.0),
        "{max_distance} from the pilot, " + sid + " allows 1 km (2 km with airspace observers)",
    )


_DIM_3M = Limit("dimension_m", "<=", 3.0, "dimension {dimension_m:g} m > 3 m")
_KE_34KJ = Limit("kinetic_energy_j", "<=", 34e3, "kinetic energy {kinetic_energy_kj:.1f} kJ > 34 kJ")
_SPARSE = Limit("sparse", "==", True, "not a sparsely populated area")
_LOW_MANNED = Limit(
    "airspace",
    "not in",
    ("airport-bcd", "airport-efg", "tmz"),
    "airspace {airspace}: not a low probability of encountering manned aircraft",
)
_CONTROLLED_GROUND = "needs a controlled ground area under the UA"


def _controlled(sid: str) -> Limit:
    """A controlled ground area has no uninvolved people in it: a flight over uninvolved people
    (or assemblies) is outside the scenario."""
    return Limit(
        "over_people",
        "==",
        "none",
        "over {over_people} people: " + sid + " needs a controlled ground area (no uninvolved people)",
    )


_LOW_MANNED_ALSO = "needs a low probability of encountering manned aircraft"

#: The EU standard scenarios and PDRAs whose scope :func:`eu_scenarios` checks, each row with
#: its limits and document (:data:`PDRA_SOURCES`).
SCENARIOS: tuple[Scenario, ...] = (
    Scenario(
        "STS-01",
        (
            _needs_vlos("STS-01"),
            Limit("eu_class", "==", "C5", "UA class {eu_class_name}, STS-01 needs C5"),
            Limit("height_m", "<=", EU_MAX_HEIGHT_M, "above 120 m"),
            _controlled("STS-01"),
        ),
        (_CONTROLLED_GROUND,),
        PDRA_SOURCES["STS-01"],
    ),
    Scenario(
        "STS-02",
        (
            _needs_bvlos("STS-02", " (a VLOS flight needs none)"),
            Limit("eu_class", "==", "C6", "UA class {eu_class_name}, STS-02 needs C6"),
            _range_1_2km("STS-02"),
            _SPARSE,
            Limit("height_m", "<=", EU_MAX_HEIGHT_M, "above 120 m"),
            _controlled("STS-02"),
        ),
        (_CONTROLLED_GROUND,),
        PDRA_SOURCES["STS-02"],
    ),
    Scenario(
        "PDRA-G01",
        (
            _needs_bvlos("PDRA-G01"),
            _DIM_3M,
            _KE_34KJ,
            _SPARSE,
            Limit("height_m", "<", 150.0, "not below 150 m"),
            Limit("airspace", "in", ("uncontrolled", "atypical"), "not in uncontrolled airspace"),
        ),
        (),
        PDRA_SOURCES["PDRA-G01"],
    ),
    # PDRA-S01: STS-01's operation without the C5 label.
    Scenario(
        "PDRA-S01",
        (
            _needs_vlos("PDRA-S01"),
            _DIM_3M,
            Limit("height_m", "<", 150.0, "not below 150 m AGL"),
            _controlled("PDRA-S01"),
            _LOW_MANNED,
        ),
        ("needs a controlled ground area under the UA (may be in a populated area)", _LOW_MANNED_ALSO),
        PDRA_SOURCES["PDRA-S01"],
    ),
    # PDRA-S02: STS-02's operation without the C6 label.
    Scenario(
        "PDRA-S02",
        (
            _needs_bvlos("PDRA-S02", " (a VLOS flight needs none)"),
            _DIM_3M,
            Limit("mtom_g", "<=", 25e3, "MTOM {mtom_kg:.1f} kg > 25 kg"),
            _range_1_2km("PDRA-S02"),
            _SPARSE,
            Limit("height_m", "<", 150.0, "not below 150 m AGL"),
            _controlled("PDRA-S02"),
            _LOW_MANNED,
        ),
        ("needs a controlled ground area entirely in a sparsely populated area", _LOW_MANNED_ALSO),
        PDRA_SOURCES["PDRA-S02"],
    ),
    # PDRA-G02: BVLOS in reserved/segregated airspace (ARC-a).
    Scenario(
        "PDRA-G02",
        (
            _needs_bvlos("PDRA-G02"),
            _DIM_3M,
            _KE_34KJ,
            _SPARSE,
            Limit(
                "airspace",
                "==",
                "atypical",
                "airspace {airspace}: PDRA-G02 needs reserved or segregated airspace (ARC-a)",
            ),
        ),
        ("within the direct C2 link's radio line of sight",),
        PDRA_SOURCES["PDRA-G02"],
    ),
    # PDRA-G03: linear inspections close to the surface (atypical, very low level) — the
    # primary text was not reached: scope from a secondary summary, flagged in its source.
    Scenario(
        "PDRA-G03",
        (
            _needs_bvlos("PDRA-G03"),
            _DIM_3M,
            _KE_34KJ,
            _SPARSE,
            Limit(
                "height_m",
                "<=",
                PDRA_G03_MAX_HEIGHT_M,
                "{height} above the surface: PDRA-G03 flies at most " + f"{PDRA_G03_MAX_HEIGHT_M:g} m",
            ),
        ),
        ("pre-programmed flight within the direct C2 link's range",),
        PDRA_SOURCES["PDRA-G03"],
    ),
)


def scenario_facts(
    op: Operation, *, eu_class: str | None, mtom_g: float, dimension_m: float, speed_ms: float
) -> dict[str, Any]:
    """The facts the :class:`Limit` rows read: the operation's and one UA's (typical kinetic
    energy ½·m·v² at the UA's maximum speed, J); ``height`` and ``max_distance`` are the same
    lengths as text for the ``why`` lines (:func:`~uasnav.mission.readable.metres`)."""
    ke = 0.5 * mtom_g / 1000.0 * speed_ms**2
    return {
        "vlos": op.visibility == "VLOS",
        "eu_class": eu_class,
        "eu_class_name": eu_class or "none",
        "height_m": op.height_m,
        "height": metres(op.height_m, against=PDRA_G03_MAX_HEIGHT_M),
        "over_people": op.over_people,
        "max_distance_m": op.max_distance_m,
        "max_distance": metres(op.max_distance_m, against=2000.0 if op.observers else 1000.0),
        "observers": op.observers,
        "sparse": DENSITY_CLASSES[op.population] < SPARSE_DENSITY,
        "airspace": op.airspace,
        "dimension_m": dimension_m,
        "kinetic_energy_j": ke,
        "kinetic_energy_kj": ke / 1e3,
        "mtom_g": mtom_g,
        "mtom_kg": mtom_g / 1e3,
    }


def eu_scenarios(
    op: Operation, *, eu_class: str | None, mtom_g: float, dimension_m: float, speed_ms: float
) -> tuple[ScenarioCheck, ...]:
    """Which EU standard scenarios (STS-01, STS-02) and PDRAs (G01, S01, S02, G02, G03) fit the
    operation with one UA: every :data:`SCENARIOS` row evaluated on :func:`scenario_facts`.

    Only the scope of each PDRA is checked (its section (a)); conditions that are not inputs
    (a controlled ground area, a low probability of meeting manned aircraft, the C2 range) are
    listed with the check.
    """
    facts = scenario_facts(op, eu_class=eu_class, mtom_g=mtom_g, dimension_m=dimension_m, speed_ms=speed_ms)
    out = []
    for sc in SCENARIOS:
        why = tuple(lim.why.format(**facts) for lim in sc.limits if not lim.met(facts))
        out.append(ScenarioCheck(sc.id, not why, (*why, *sc.also), sc.source))
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
