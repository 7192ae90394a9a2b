"""Specific Operations Risk Assessment (JARUS SORA), editions 2.5 and 2.0.

Every table is transcribed from the primary JARUS document and names it (edition, table).
Public encodings of these tables disagree with each other (some swap the 2.0 and 2.5 SAIL
tables, some give 2.5's iGRC rows with 2.0's kinetic-energy columns); the tests in
``tests/test_mission_sora.py`` check every table boundary against the values below, each of
which was read from the document named beside it. Page numbers are not given where we could not
re-check them against a copy of the document in this session (the edition and the table number
identify the cell unambiguously).

Sources
-------
* JARUS SORA 2.5: "JARUS guidelines on Specific Operations Risk Assessment (SORA)", edition 2.5,
  JAR-DEL-SRM-SORA-MB-2.5, 13 May 2024 (Main Body): Table 2 (iGRC), Table 5 (ground risk
  mitigations), Figure 6 (initial ARC decision tree), Table 6 (TMPR), Table 7 (SAIL),
  Table 14 (OSOs).
* JARUS SORA 2.0: "JARUS guidelines on SORA", edition 2.0, JAR-DEL-WG6-D.04, 30 January 2019
  (the basis of EASA's AMC1 Article 11 of Regulation (EU) 2019/947, Easy Access Rules for
  UAS): Table 2 (iGRC), Table 3 (mitigations), Figure 4 (ARC), Table 4 (TMPR), Table 5 (SAIL),
  Table 6 (OSOs).

The flow is the SORA's steps: #2 iGRC → #3 final GRC (mitigations, floor = the column's
controlled-ground-area value) → #4 initial ARC → #5 residual ARC (strategic mitigations: given
by the user, never assumed) → #6 TMPR → #7 SAIL → #9 OSOs.

>>> r = assess(dimension_m=0.35, speed_ms=20.0, population="sparsely", bvlos=True)
>>> r.edition, r.igrc, r.final_grc, r.initial_arc, r.sail
('2.5', 4, 4, 'b', 'III')
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

from uasnav.errors import InputError

EDITIONS = ("2.5", "2.0")
ROBUSTNESS = ("none", "low", "medium", "high")
ARCS = ("a", "b", "c", "d")

# --- SORA 2.5 ------------------------------------------------------------------------------

#: SORA 2.5 Main Body Table 2 columns: (max characteristic dimension m, max speed m/s). A UA
#: goes in the first column whose dimension AND speed both bound it.
IGRC25_COLUMNS: tuple[tuple[float, float], ...] = (
    (1.0, 25.0),
    (3.0, 35.0),
    (8.0, 75.0),
    (20.0, 120.0),
    (40.0, 200.0),
)
#: SORA 2.5 Main Body Table 2 rows: (name, population density upper bound ppl/km² (exclusive),
#: iGRC per column; None = grey cell, out of the SORA's scope).
IGRC25_ROWS: tuple[tuple[str, float, tuple[int | None, ...]], ...] = (
    ("controlled", 0.0, (1, 1, 2, 3, 3)),
    ("remote", 5.0, (2, 3, 4, 5, 6)),
    ("lightly", 50.0, (3, 4, 5, 6, 7)),
    ("sparsely", 500.0, (4, 5, 6, 7, 8)),
    ("suburban", 5000.0, (5, 6, 7, 8, 9)),
    ("high-density", 50000.0, (6, 7, 8, 9, 10)),
    ("assemblies", math.inf, (7, 8, None, None, None)),
)
#: Named density classes (SORA 2.5 Table 3 qualitative descriptors) → a representative density
#: (ppl/km²) inside the class, used when the user names a class instead of a number.
DENSITY_CLASSES: dict[str, float] = {
    "controlled": 0.0,
    "remote": 1.0,
    "lightly": 10.0,
    "sparsely": 100.0,
    "suburban": 1000.0,
    "high-density": 10000.0,
    "assemblies": 100000.0,
}
#: SORA 2.5 Main Body Table 2, note: a UA of at most 250 g and at most 25 m/s has iGRC 1.
SMALL_UA_MASS_G, SMALL_UA_SPEED_MS = 250.0, 25.0
#: SORA 2.5 Main Body Table 5: GRC reduction per mitigation and robustness (None = N/A).
MITIGATIONS25: dict[str, dict[str, int | None]] = {
    "M1A": {"none": 0, "low": -1, "medium": -2, "high": None},
    "M1B": {"none": 0, "low": None, "medium": -1, "high": -2},
    "M1C": {"none": 0, "low": -1, "medium": None, "high": None},
    "M2": {"none": 0, "low": None, "medium": -1, "high": -2},
}

# --- SORA 2.0 ------------------------------------------------------------------------------

#: SORA 2.0 Table 2 columns: (max characteristic dimension m, typical kinetic energy J).
IGRC20_COLUMNS: tuple[tuple[float, float], ...] = (
    (1.0, 700.0),
    (3.0, 34e3),
    (8.0, 1084e3),
    (math.inf, math.inf),
)
#: SORA 2.0 Table 2 rows: operational scenario → iGRC per column (None = grey, not SORA).
IGRC20_ROWS: dict[str, tuple[int | None, ...]] = {
    "controlled": (1, 2, 3, 4),
    "vlos-sparsely": (2, 3, 4, 5),
    "bvlos-sparsely": (3, 4, 5, 6),
    "vlos-populated": (4, 5, 6, 8),
    "bvlos-populated": (5, 6, 8, 10),
    "vlos-assemblies": (7, None, None, None),
    "bvlos-assemblies": (8, None, None, None),
}
#: SORA 2.0 Table 3: GRC correction per mitigation and robustness (M3: ERP, +1 if absent/low).
MITIGATIONS20: dict[str, dict[str, int | None]] = {
    "M1": {"none": 0, "low": -1, "medium": -2, "high": -4},
    "M2": {"none": 0, "low": 0, "medium": -1, "high": -2},
    "M3": {"none": 1, "low": 1, "medium": 0, "high": -1},
}
#: Density (ppl/km²) below which an area counts as "sparsely populated" for SORA 2.0's
#: scenarios. 2.0 gives no number; we reuse 2.5's sparsely-populated bound (< 500 ppl/km²)
#: so the two editions classify the same area the same way.
SPARSE_LIMIT_20 = 500.0

# --- both editions -------------------------------------------------------------------------

#: SAIL from final GRC (rows ≤2, 3, 4, 5, 6, 7) and residual ARC (columns a–d). The tables are
#: the same in 2.0 (Table 5) and 2.5 (Table 7); 2.5 sends GRC > 7 to the certified category.
SAIL_TABLE: dict[int, tuple[str, str, str, str]] = {
    2: ("I", "II", "IV", "VI"),
    3: ("II", "II", "IV", "VI"),
    4: ("III", "III", "IV", "VI"),
    5: ("IV", "IV", "IV", "VI"),
    6: ("V", "V", "V", "VI"),
    7: ("VI", "VI", "VI", "VI"),
}
#: TMPR and its robustness per residual ARC (2.0 Table 4, 2.5 Table 6); VLOS operations meet
#: the TMPR by the pilot's (and observers') see-and-avoid (2.5 §4.6.2 / 2.0 §2.4.2 step 6).
TMPR: dict[str, str] = {"a": "none", "b": "low", "c": "medium", "d": "high"}

SAILS = ("I", "II", "III", "IV", "V", "VI")
# OSO robustness per SAIL I..VI: O optional, L low, M medium, H high.
#: SORA 2.0 Table 6 (24 OSOs).
OSO20: dict[str, tuple[str, str]] = {
    "OSO#01": ("Operator is competent and/or proven", "OLMHHH"),
    "OSO#02": ("UAS manufactured by competent and/or proven entity", "OOLMHH"),
    "OSO#03": ("UAS maintained by competent and/or proven entity", "LLMMHH"),
    "OSO#04": ("UAS developed to authority recognised design standards", "OOOLMH"),
    "OSO#05": ("UAS is designed considering system safety and reliability", "OOLMHH"),
    "OSO#06": ("C3 link performance is appropriate for the operation", "OLLMHH"),
    "OSO#07": ("Inspection of the UAS (product inspection)", "LLMMHH"),
    "OSO#08": ("Operational procedures are defined, validated and adhered to", "LMHHHH"),
    "OSO#09": ("Remote crew trained and current", "LLMMHH"),
    "OSO#10": ("Safe recovery from technical issue", "LLMMHH"),
    "OSO#11": ("Procedures to handle the deterioration of external systems", "LMHHHH"),
    "OSO#12": ("UAS designed to manage the deterioration of external systems", "LLMMHH"),
    "OSO#13": ("External services supporting UAS operations are adequate", "LLMHHH"),
    "OSO#14": ("Operational procedures (human error)", "LMHHHH"),
    "OSO#15": ("Remote crew trained and current (human error)", "LLMMHH"),
    "OSO#16": ("Multi crew coordination", "LLMMHH"),
    "OSO#17": ("Remote crew is fit to operate", "LLMMHH"),
    "OSO#18": ("Automatic protection of the flight envelope from human error", "OOLMHH"),
    "OSO#19": ("Safe recovery from human error", "OOLMMH"),
    "OSO#20": ("A human factors evaluation has been performed (HMI)", "OLLMMH"),
    "OSO#21": ("Operational procedures (adverse operating conditions)", "LMHHHH"),
    "OSO#22": ("Remote crew trained to identify critical environmental conditions", "LLMMMH"),
    "OSO#23": ("Environmental conditions for safe operations defined, measurable and adhered to", "LLMMHH"),
    "OSO#24": ("UAS designed and qualified for adverse environmental conditions", "OOMHHH"),
}
#: SORA 2.5 Table 14 (17 OSOs: 2.5 merged OSO#10–12, #14–15 and #21–22 into others).
OSO25: dict[str, tuple[str, str]] = {
    k: OSO20[k]
    for k in (
        "OSO#01",
        "OSO#02",
        "OSO#03",
        "OSO#04",
        "OSO#05",
        "OSO#06",
        "OSO#07",
        "OSO#08",
        "OSO#09",
        "OSO#13",
        "OSO#16",
        "OSO#17",
        "OSO#18",
        "OSO#19",
        "OSO#20",
        "OSO#23",
        "OSO#24",
    )
}
_LEVEL = {"O": "optional", "L": "low", "M": "medium", "H": "high"}

#: Airspace situations (encounter categories of 2.0 Figure 4 / 2.5 Figure 6) accepted as input.
AIRSPACES = ("uncontrolled", "controlled", "tmz", "airport-bcd", "airport-efg", "atypical")
#: 500 ft AGL, the height that splits the ARC decision tree (both editions).
ARC_SPLIT_M = 152.4


@dataclass(frozen=True)
class Oso:
    """One operational safety objective and its required level of robustness."""

    id: str
    title: str
    robustness: str  # optional | low | medium | high


@dataclass(frozen=True)
class SoraResult:
    """A SORA assessment; ``edition`` is ``"2.5"`` or ``"2.0"`` and is part of every output.

    ``final_grc`` above 7 (2.5) or a grey iGRC cell means the operation is outside the
    specific category's SORA (certified category): ``sail`` is then None and ``certified`` True.
    ``steps`` lists each step with the table it comes from.
    """

    edition: str
    population: str
    igrc: int | None
    final_grc: int | None
    mitigations: dict[str, str]
    initial_arc: str
    residual_arc: str
    tmpr: str
    sail: str | None
    certified: bool
    osos: tuple[Oso, ...]
    steps: tuple[str, ...] = field(default_factory=tuple)
    #: SORA 2.5's quantitative alternative (Annex F, computed with ``casex``): (iGRC, raw iGRC,
    #: critical area m²) for this UA and density; None when not computed.
    annex_f: tuple[int, float, float] | None = None

    def to_dict(self) -> dict:
        """Plain JSON."""
        return {
            "edition": self.edition,
            "population": self.population,
            "igrc": self.igrc,
            "final_grc": self.final_grc,
            "mitigations": dict(self.mitigations),
            "initial_arc": self.initial_arc,
            "residual_arc": self.residual_arc,
            "tmpr": self.tmpr,
            "sail": self.sail,
            "certified": self.certified,
            "osos": [o.__dict__ for o in self.osos],
            "steps": list(self.steps),
            "annex_f": None
            if self.annex_f is None
            else {"igrc": self.annex_f[0], "raw_igrc": self.annex_f[1], "critical_area_m2": self.annex_f[2]},
        }


def density_class(density_ppl_km2: float) -> str:
    """SORA 2.5 Table 2 row of a population density (ppl/km²): the first row whose bound is
    above it (< 5 remote, < 50 lightly, …); 0 is ``controlled`` only when named so."""
    if not math.isfinite(density_ppl_km2) or density_ppl_km2 < 0:
        raise InputError(f"population density {density_ppl_km2}: must be a finite number >= 0")
    for name, bound, _ in IGRC25_ROWS[1:]:
        if density_ppl_km2 < bound:
            return name
    return "assemblies"


def _column25(dimension_m: float, speed_ms: float) -> int:
    for i, (d, v) in enumerate(IGRC25_COLUMNS):
        if dimension_m <= d and speed_ms <= v:
            return i
    raise InputError(
        f"SORA 2.5: UA of {dimension_m:g} m / {speed_ms:g} m/s exceeds Table 2 (40 m, 200 m/s): "
        "certified category"
    )


def igrc_25(dimension_m: float, speed_ms: float, population: str, mass_g: float | None = None) -> int | None:
    """SORA 2.5 Main Body Table 2: intrinsic GRC (None: grey cell, outside the SORA).

    Parameters
    ----------
    dimension_m : float
        Maximum characteristic dimension (span, rotor-tip to rotor-tip), m.
    speed_ms : float
        Maximum speed, m/s.
    population : str
        Row name (:data:`DENSITY_CLASSES`).
    mass_g : float, optional
        Take-off mass (g): ≤ 250 g with ≤ 25 m/s gives iGRC 1 (Table 2 note).
    """
    if mass_g is not None and mass_g <= SMALL_UA_MASS_G and speed_ms <= SMALL_UA_SPEED_MS:
        return 1
    col = _column25(dimension_m, speed_ms)
    row = next((r for r in IGRC25_ROWS if r[0] == population), None)
    if row is None:
        raise InputError(f"unknown population class {population!r}; known: {', '.join(DENSITY_CLASSES)}")
    return row[2][col]


#: casex warns that its models are not valid below 1 kg.
CASEX_MIN_MASS_G = 1000.0


def annex_f_igrc(
    *, dimension_m: float, speed_ms: float, mass_g: float, density_ppl_km2: float
) -> tuple[int, float, float]:
    """JARUS SORA Annex F quantitative iGRC with ``casex`` (the Annex F authors' package).

    Critical area of a generic UA of width ``dimension_m`` (m) and mass ``mass_g`` (g) impacting
    at ``speed_ms`` (m/s) at Annex F's 35° scenario angle, with the obstacle reduction and the
    0.3 conservative compensation Annex F applies to build Table 2; then
    iGRC = ⌈log10(CA·density) + offset⌉ (casex ``AnnexFParms.iGRC``, TLOS 1e-6/h).
    Returns (iGRC, raw iGRC, critical area m²).
    """
    from casex import AircraftSpecs, AnnexFParms, CriticalAreaModels, enums

    afp = AnnexFParms()
    ac = AircraftSpecs(enums.AircraftType.GENERIC, dimension_m, mass_g / 1000.0)
    ac.set_friction_coefficient(afp.friction_coefficient)
    ac.set_fuel_type(enums.FuelType.GASOLINE)
    ac.set_fuel_quantity(0)
    angle = AnnexFParms.scenario_angles[1]
    ac.set_coefficient_of_restitution(AnnexFParms.CoR_from_impact_angle(angle))
    ca = float(CriticalAreaModels().critical_area(ac, speed_ms, angle, use_obstacle_reduction=True)[0])
    ig, raw = afp.iGRC(max(density_ppl_km2, 1e-9), ca, width=dimension_m, use_conservative_compensation=True)
    return int(ig), float(raw), ca


def kinetic_energy_j(mass_g: float, speed_ms: float) -> float:
    """Typical kinetic energy ½·m·v² (J) from the take-off mass (g) and the speed (m/s)."""
    return 0.5 * mass_g / 1000.0 * speed_ms**2


def igrc_20(dimension_m: float, energy_j: float, scenario: str) -> int | None:
    """SORA 2.0 Table 2: intrinsic GRC of an operational ``scenario`` (:data:`IGRC20_ROWS`).

    The column is the first whose dimension bound (≤ 1, 3, 8 m) and kinetic-energy bound
    (< 700 J, < 34 kJ, < 1084 kJ) both hold. None: grey cell (outside the SORA).
    """
    col = next(i for i, (d, e) in enumerate(IGRC20_COLUMNS) if (dimension_m <= d and energy_j < e) or i == 3)
    try:
        return IGRC20_ROWS[scenario][col]
    except KeyError:
        raise InputError(f"unknown SORA 2.0 scenario {scenario!r}; known: {', '.join(IGRC20_ROWS)}") from None


def final_grc(igrc: int, mitigations: Mapping[str, str], edition: str, floor: int) -> int:
    """Step #3: iGRC plus the corrections of the claimed mitigations, never below ``floor``
    (the column's controlled-ground-area value: 2.5 §4.3, 2.0 §2.3.2)."""
    table = MITIGATIONS25 if edition == "2.5" else MITIGATIONS20
    g = igrc
    for name, rob in mitigations.items():
        if name not in table:
            raise InputError(f"SORA {edition}: unknown mitigation {name!r}; known: {', '.join(table)}")
        if rob not in ROBUSTNESS:
            raise InputError(f"SORA {edition}: {name}={rob!r}: robustness is one of {', '.join(ROBUSTNESS)}")
        delta = table[name][rob]
        if delta is None:
            allowed = [r for r, d in table[name].items() if d is not None and r != "none"]
            raise InputError(
                f"SORA {edition}: {name} cannot be claimed at {rob} robustness (Table "
                f"{'5' if edition == '2.5' else '3'}: {', '.join(allowed)} only)"
            )
        g += delta
    if edition == "2.0" and "M3" not in mitigations:
        g += MITIGATIONS20["M3"]["none"]  # no emergency response plan: +1
    return max(g, floor)


def initial_arc(airspace: str, height_m: float, urban: bool) -> str:
    """Step #4, the initial ARC decision tree (2.0 Figure 4, 2.5 Figure 6).

    ``airspace``: one of :data:`AIRSPACES`; ``height_m`` above ground (split at 500 ft);
    ``urban`` decides the uncontrolled low-level case (ARC-c over urban, ARC-b over rural).
    """
    if airspace not in AIRSPACES:
        raise InputError(f"unknown airspace {airspace!r}; known: {', '.join(AIRSPACES)}")
    if airspace == "atypical":
        return "a"  # AEC 12: atypical/segregated airspace
    if airspace == "airport-bcd":
        return "d"  # AEC 1
    if airspace == "airport-efg":
        return "c"  # AEC 6
    if height_m > ARC_SPLIT_M:
        # AEC 2 (TMZ/Mode-S veil), 3 (controlled), 4/5 (uncontrolled urban/rural)
        return "d" if airspace in ("tmz", "controlled") else "c"
    if airspace in ("tmz", "controlled"):
        return "c"  # AEC 7, 8
    return "c" if urban else "b"  # AEC 9 urban, AEC 10 rural


def sail(grc: int, arc: str) -> str | None:
    """Step #7: SAIL from the final GRC and the residual ARC (2.0 Table 5 = 2.5 Table 7).
    None for GRC > 7 (certified category)."""
    if arc not in ARCS:
        raise InputError(f"unknown ARC {arc!r}")
    if grc > 7:
        return None
    return SAIL_TABLE[max(grc, 2)][ARCS.index(arc)]


def osos(sail_level: str, edition: str) -> tuple[Oso, ...]:
    """Step #9: the OSOs and their required robustness at ``sail_level``."""
    table = OSO25 if edition == "2.5" else OSO20
    k = SAILS.index(sail_level)
    return tuple(Oso(oid, title, _LEVEL[lv[k]]) for oid, (title, lv) in table.items())


def assess(
    *,
    dimension_m: float,
    speed_ms: float,
    population: str,
    bvlos: bool,
    mass_g: float | None = None,
    height_m: float = 50.0,
    airspace: str = "uncontrolled",
    urban: bool = False,
    mitigations: Mapping[str, str] | None = None,
    residual_arc: str | None = None,
    edition: str = "2.5",
    density_ppl_km2: float | None = None,
    quantitative: bool = True,
) -> SoraResult:
    """The whole SORA for one UA and operation.

    Parameters
    ----------
    dimension_m, speed_ms : float
        UA maximum characteristic dimension (m) and maximum speed (m/s).
    population : str
        SORA 2.5 Table 2 row name (:data:`DENSITY_CLASSES`); for 2.0, classes below 500
        ppl/km² are "sparsely populated", above "populated", ``assemblies`` and ``controlled``
        map to their scenarios.
    bvlos : bool
        Beyond visual line of sight (2.0 scenarios; 2.5 TMPR).
    mass_g : float, optional
        Take-off mass (g): 2.5's ≤ 250 g rule, 2.0's kinetic energy (needs it).
    height_m, airspace, urban
        Inputs of the ARC decision tree.
    mitigations : mapping, optional
        Mitigation → robustness (2.5: M1A, M1B, M1C, M2; 2.0: M1, M2, M3).
    residual_arc : str, optional
        Residual ARC after strategic mitigations, when the operator claims one (must not be
        above the initial ARC); default: the initial ARC (no strategic mitigation assumed).
    edition : {"2.5", "2.0"}
    density_ppl_km2 : float, optional
        Population density (ppl/km²) for the Annex F quantitative iGRC (2.5, with ``mass_g``),
        reported beside the table's; default: the class's representative density.
    quantitative : bool
        Compute the Annex F iGRC (``annex_f``) too (about 2 ms with casex).
    """
    if edition not in EDITIONS:
        raise InputError(f"SORA edition {edition!r}: known {', '.join(EDITIONS)}")
    for name, v in (("dimension_m", dimension_m), ("speed_ms", speed_ms), ("height_m", height_m)):
        if not math.isfinite(v) or v <= 0:
            raise InputError(f"SORA: {name}={v}: must be finite and > 0")
    if population not in DENSITY_CLASSES:
        raise InputError(f"unknown population class {population!r}; known: {', '.join(DENSITY_CLASSES)}")
    mit = dict(mitigations or {})
    steps = []
    if edition == "2.5":
        ig = igrc_25(dimension_m, speed_ms, population, mass_g)
        col = _column25(dimension_m, speed_ms)
        floor = IGRC25_ROWS[0][2][col] or 1
        steps.append(
            f"iGRC {ig} (SORA 2.5 Table 2: {dimension_m:g} m, {speed_ms:g} m/s, population {population})"
        )
    else:
        if mass_g is None:
            raise InputError("SORA 2.0 needs the take-off mass (kinetic energy column)")
        e = kinetic_energy_j(mass_g, speed_ms)
        if population == "controlled":
            scen = "controlled"
        else:
            where = (
                "assemblies"
                if population == "assemblies"
                else ("sparsely" if DENSITY_CLASSES[population] < SPARSE_LIMIT_20 else "populated")
            )
            scen = f"{'bvlos' if bvlos else 'vlos'}-{where}"
        ig = igrc_20(dimension_m, e, scen)
        col = next(i for i, (d, en) in enumerate(IGRC20_COLUMNS) if (dimension_m <= d and e < en) or i == 3)
        floor = IGRC20_ROWS["controlled"][col] or 1
        steps.append(f"iGRC {ig} (SORA 2.0 Table 2: {dimension_m:g} m, {e:.0f} J, scenario {scen})")
    arc0 = initial_arc(airspace, height_m, urban)
    arc = arc0 if residual_arc is None else residual_arc
    if arc not in ARCS or ARCS.index(arc) > ARCS.index(arc0):
        raise InputError(f"residual ARC {residual_arc!r} must be one of a–{arc0} (initial ARC-{arc0})")
    tm = TMPR[arc] if bvlos else "none"
    if ig is None:
        steps.append("grey cell of the iGRC table: outside the SORA, certified category")
        return SoraResult(edition, population, None, None, mit, arc0, arc, tm, None, True, (), tuple(steps))
    grc = final_grc(ig, mit, edition, floor)
    table = "Table 5" if edition == "2.5" else "Table 3"
    steps.append(f"final GRC {grc} (mitigations {mit or 'none'}, {table}; floor {floor})")
    steps.append(
        f"initial ARC-{arc0} (airspace {airspace}, {height_m:g} m AGL, {'urban' if urban else 'rural'})"
    )
    steps.append(
        f"residual ARC-{arc}" + (" (no strategic mitigation claimed)" if residual_arc is None else "")
    )
    steps.append(
        f"TMPR {tm}"
        + (
            " (VLOS: see-and-avoid by the remote crew)"
            if not bvlos
            else f" ({'Table 6' if edition == '2.5' else 'Table 4'})"
        )
    )
    af = None
    if quantitative and edition == "2.5" and mass_g is not None and mass_g < CASEX_MIN_MASS_G:
        steps.append("Annex F quantitative iGRC not computed: casex is not valid below 1 kg")
    elif quantitative and edition == "2.5" and mass_g is not None and population != "controlled":
        dens = density_ppl_km2 if density_ppl_km2 is not None else DENSITY_CLASSES[population]
        af = annex_f_igrc(dimension_m=dimension_m, speed_ms=speed_ms, mass_g=mass_g, density_ppl_km2=dens)
        steps.append(
            f"Annex F quantitative iGRC {af[0]} (raw {af[1]:.2f}, critical area {af[2]:.1f} m², casex; "
            "the table value above is the one used)"
        )
    s = sail(grc, arc)
    if s is None:
        steps.append(f"final GRC {grc} > 7: certified category")
        return SoraResult(edition, population, ig, grc, mit, arc0, arc, tm, None, True, (), tuple(steps), af)
    steps.append(f"SAIL {s} ({'Table 7' if edition == '2.5' else 'Table 5'})")
    return SoraResult(
        edition, population, ig, grc, mit, arc0, arc, tm, s, False, osos(s, edition), tuple(steps), af
    )
