"""Specific Operations Risk Assessment (JARUS SORA), editions 2.5 and 2.0.

Every table names its primary document: edition, table or section, and page. Public encodings
of these tables disagree with each other (some swap the 2.0 and 2.5 SAIL tables, some give
2.5's iGRC rows with 2.0's kinetic-energy columns); the tests in ``tests/test_mission_sora.py``
check every table boundary against the values below.

Sources
-------
``[AMC-2.5]`` — SORA 2.5, checked against its primary text:
    EASA, "Acceptable Means of Compliance and Guidance Material to Regulation (EU) 2019/947 —
    Issue 1, Amendment 3", Annex to ED Decision 2025/018/R; AMC1 Article 11 "Specific
    operations risk assessment (SORA) (source: JARUS SORA v2.5)", edition September 2025.
    Pages are the document's own "Page N of 204" footers. This is JARUS SORA 2.5 as the EU
    adopted it (EASA numbers some tables differently from the JARUS Main Body, noted below).

    * iGRC table: S.4.2.3(d), p. 24 (captioned "Table 1", cited in the text as Table 2);
      the ≤ 250 g / ≤ 25 m/s note, p. 24; "rightmost column matching both criteria", p. 25;
      qualitative density descriptors, Table 2, p. 26.
    * Ground-risk mitigations: Table 5, p. 29; the column floor (S.4.3.4(f)) and final GRC > 7
      → certified category, p. 30; M1(A) medium cannot be combined with M1(B): Annex B §B.2,
      p. 85.
    * Initial ARC: Figure 6, p. 32 (a figure: its text could not be read from our copy);
      atypical air environment → ARC-a, p. 33; residual = initial unless strategic mitigations
      are claimed (S.4.5.1(c)), p. 33; VLOS (or BVLOS with airspace observers) lowers the
      initial ARC by one class, never to ARC-a (S.4.5.4), p. 34.
    * TMPR: Table 6, p. 35; VLOS / BVLOS with observers is an acceptable tactical mitigation for
      all ARCs (S.4.6.4(a)), p. 35.
    * SAIL: p. 38 (captioned "Table 3", cited in the text as Table 7).
    * OSOs: Table 14, pp. 44–45 (17 OSOs). Differs from 2.0 in OSO #04 (NR NR NR M H H: EASA
      raised SAIL IV to medium, matching its Annex E OSO #04 criteria, pp. 105–106).

``[SORA-2.0]`` — SORA 2.0: JARUS, "JARUS guidelines on SORA", edition 2.0, JAR-DEL-WG6-D.04,
    30 January 2019 (the basis of EASA's earlier AMC1 Article 11, ED Decision 2019/021/R):
    Table 2 (iGRC), Table 3 (mitigations), Figure 4 (ARC), Table 4 (TMPR), Table 5 (SAIL),
    Table 6 (OSOs). The 2.0 tables are not verified against a primary text, so no page numbers
    are given for 2.0; where 2.0 and 2.5 share a table (SAIL, TMPR, the OSOs other than #04)
    they agree with ``[AMC-2.5]``. Secondary encodings disagree with each other and are not
    used. The edition is confirmed by JARUS's publication page "JAR doc 06 SORA (package)",
    6 March 2019 (main body edition 2.0, Annexes B–E edition 1.0). Unverified 2.0 tables:
    Table 2 (iGRC, incl. the 700 J / 34 kJ / 1084 kJ columns), Table 3 (M1/M2/M3 and the column
    floor), Figure 4 (ARC), Table 4 (TMPR), Table 5 (SAIL), Table 6 (OSO robustness).

ARC height split: 500 ft AGL (152.4 m). ``[AMC-2.5]`` Figure 6 could not be read, but the same
text speaks of "operations below 500 ft AGL" for the low TMPR (S.4.6.4(c), p. 36) and pairs
500 ft with 152 m in its grid-size Table 4 (p. 28); some secondary encodings use 150 m for 2.5
(JARUS Annex C Table C.1, not verified). The two differ by 2.4 m. ED Decision 2025/018/R carries
no Annex C of its own (its Annex B ends on p. 95 and Annex E begins on p. 96), so the EU
adoption of 2.5 gives no strategic-mitigation table to check the 150 m value or the Annex C
reduction limits against; ``residual_arc_of`` labels any claim beyond S.4.5.4 an Annex C claim
to be substantiated.

The flow is the SORA's steps: #2 iGRC → #3 final GRC (mitigations, floor = the column's
controlled-ground-area value) → #4 initial ARC → #5 residual ARC (strategic mitigations: given
by the user, never assumed) → #6 TMPR → #7 SAIL → #9 OSOs.

>>> r = assess(dimension_m=0.35, speed_ms=20.0, population="sparsely", bvlos=True)
>>> r.edition, r.igrc, r.final_grc, r.initial_arc, r.sail
('2.5', 4, 4, 'b', 'III')
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field

from uasnav.errors import InputError

EDITIONS = ("2.5", "2.0")
ROBUSTNESS = ("none", "low", "medium", "high")
ARCS = ("a", "b", "c", "d")

# --- SORA 2.5 ------------------------------------------------------------------------------

#: SORA 2.5 iGRC table columns: (max characteristic dimension m, max speed m/s) — [AMC-2.5]
#: S.4.2.3(d), p. 24 (the 20 m column is 120 m/s there; Annex F's 20 m reference UA cruises at
#: 150 m/s). A UA goes in the first column whose dimension AND speed both bound it ("the
#: rightmost column matching both criteria", p. 25, read from the UA's side).
IGRC25_COLUMNS: tuple[tuple[float, float], ...] = (
    (1.0, 25.0),
    (3.0, 35.0),
    (8.0, 75.0),
    (20.0, 120.0),
    (40.0, 200.0),
)
#: SORA 2.5 iGRC table rows: (name, population density upper bound ppl/km² (exclusive), iGRC
#: per column; None = grey cell, "not part of SORA") — [AMC-2.5] p. 24.
IGRC25_ROWS: tuple[tuple[str, float, tuple[int | None, ...]], ...] = (
    ("controlled", 0.0, (1, 1, 2, 3, 3)),
    ("remote", 5.0, (2, 3, 4, 5, 6)),
    ("lightly", 50.0, (3, 4, 5, 6, 7)),
    ("sparsely", 500.0, (4, 5, 6, 7, 8)),
    ("suburban", 5000.0, (5, 6, 7, 8, 9)),
    ("high-density", 50000.0, (6, 7, 8, 9, 10)),
    ("assemblies", math.inf, (7, 8, None, None, None)),
)
#: Named density classes (SORA 2.5 qualitative descriptors, [AMC-2.5] Table 2, p. 26; JARUS
#: Main Body Table 3) → a representative density
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
#: [AMC-2.5] p. 24, note to the iGRC table: a UA of at most 250 g and at most 25 m/s has iGRC 1
#: (unless over assemblies of people).
SMALL_UA_MASS_G, SMALL_UA_SPEED_MS = 250.0, 25.0
#: SORA 2.5 Table 5: GRC reduction per mitigation and robustness (None = n/a) — [AMC-2.5] p. 29.
MITIGATIONS25: dict[str, dict[str, int | None]] = {
    "M1A": {"none": 0, "low": -1, "medium": -2, "high": None},
    "M1B": {"none": 0, "low": None, "medium": -1, "high": -2},
    "M1C": {"none": 0, "low": -1, "medium": None, "high": None},
    "M2": {"none": 0, "low": None, "medium": -1, "high": -2},
}

# --- SORA 2.0 ------------------------------------------------------------------------------

#: SORA 2.0 Table 2 columns: (max characteristic dimension m, typical kinetic energy J)
#: — [SORA-2.0] (not verified against a primary text: no page).
IGRC20_COLUMNS: tuple[tuple[float, float], ...] = (
    (1.0, 700.0),
    (3.0, 34e3),
    (8.0, 1084e3),
    (math.inf, math.inf),
)
#: SORA 2.0 Table 2 rows: operational scenario → iGRC per column (None = grey, not SORA)
#: — [SORA-2.0] (no page: not verified against a primary text).
IGRC20_ROWS: dict[str, tuple[int | None, ...]] = {
    "controlled": (1, 2, 3, 4),
    "vlos-sparsely": (2, 3, 4, 5),
    "bvlos-sparsely": (3, 4, 5, 6),
    "vlos-populated": (4, 5, 6, 8),
    "bvlos-populated": (5, 6, 8, 10),
    "vlos-assemblies": (7, None, None, None),
    "bvlos-assemblies": (8, None, None, None),
}
#: SORA 2.0 Table 3: GRC correction per mitigation and robustness (M3: ERP, +1 if absent/low)
#: — [SORA-2.0] (no page: not verified against a primary text).
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

#: SAIL from final GRC (rows ≤2, 3, 4, 5, 6, 7) and residual ARC (columns a–d): [AMC-2.5]
#: p. 38 (JARUS 2.5 Table 7). 2.0's Table 5 holds the same cells ([SORA-2.0], not verified
#: against a primary text); GRC > 7 is the certified category.
SAIL_TABLE: dict[int, tuple[str, str, str, str]] = {
    2: ("I", "II", "IV", "VI"),
    3: ("II", "II", "IV", "VI"),
    4: ("III", "III", "IV", "VI"),
    5: ("IV", "IV", "IV", "VI"),
    6: ("V", "V", "V", "VI"),
    7: ("VI", "VI", "VI", "VI"),
}
#: TMPR and its robustness per residual ARC: [AMC-2.5] Table 6, p. 35 (2.0 Table 4, same
#: cells). VLOS, or BVLOS with airspace observers, meets the TMPR by see-and-avoid for every
#: ARC ([AMC-2.5] S.4.6.4(a), p. 35).
TMPR: dict[str, str] = {"a": "none", "b": "low", "c": "medium", "d": "high"}

SAILS = ("I", "II", "III", "IV", "V", "VI")
# OSO robustness per SAIL I..VI: O optional (2.0) / not required (2.5 "NR"), L low, M medium,
# H high.
#: SORA 2.0 Table 6 (24 OSOs) — [SORA-2.0] (not verified against a primary text: no page).
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
#: SORA 2.5 Table 14 (17 OSOs; 2.5 folded 2.0's OSO #10–12, #14–15 and #21–22 into others),
#: titles and levels as printed in [AMC-2.5] pp. 44–45.
OSO25: dict[str, tuple[str, str]] = {
    "OSO#01": ("Ensure that the UAS operator is a competent and/or proven organisation", "OLMHHH"),
    "OSO#02": ("UAS designed and produced by a competent and/or proven organisation", "OOLMHH"),
    "OSO#03": ("UAS maintenance", "LLMMHH"),
    "OSO#04": (
        "UAS components essential to safe operations are designed to an airworthiness design standard",
        "OOOMHH",
    ),
    "OSO#05": ("UAS is designed considering system safety and reliability", "OOLMHH"),
    "OSO#06": ("C3 link characteristics (e.g. performance, spectrum use) are appropriate", "OLLMHH"),
    "OSO#07": ("Conformity check of the UAS configuration", "LLMMHH"),
    "OSO#08": ("Operational procedures are defined, validated and adhered to", "LMHHHH"),
    "OSO#09": ("Remote crew trained and current", "LLMMHH"),
    "OSO#13": ("External services supporting UAS operations are adequate for the UAS operation", "LLMHHH"),
    "OSO#16": ("Multi-crew coordination", "LLMMHH"),
    "OSO#17": ("Remote crew is fit to operate", "LLMMHH"),
    "OSO#18": ("Automatic protection of the flight envelope from human errors", "OOLMHH"),
    "OSO#19": ("Safe recovery from human error", "OOLMMH"),
    "OSO#20": ("A human factors evaluation has been performed and the HMI found appropriate", "OLLMMH"),
    "OSO#23": ("Environmental conditions for safe operations defined and measurable", "LLMMHH"),
    "OSO#24": ("UAS designed and qualified to operate in adverse environmental conditions", "OOMHHH"),
}
_LEVEL = {"O": "optional", "L": "low", "M": "medium", "H": "high"}

#: Airspace situations (encounter categories of 2.0 Figure 4 / 2.5 Figure 6) accepted as input.
AIRSPACES = ("uncontrolled", "controlled", "tmz", "airport-bcd", "airport-efg", "atypical")
#: 500 ft AGL, the height that splits the ARC decision tree (both editions; see the module doc
#: for why 500 ft and not 150 m).
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
    #: The rule behind the residual ARC (no claim, the VLOS reduction, or an Annex C claim).
    residual_arc_rule: str = ""

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
            "residual_arc_rule": self.residual_arc_rule,
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


# A pure function of four numbers that rebuilds casex's models (≈ 2 ms) on every call: the web
# app asks for the same UA's value on every request, so the last results are kept.
@functools.lru_cache(maxsize=1024)
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
    if edition == "2.5" and mitigations.get("M1A") == "medium" and mitigations.get("M1B", "none") != "none":
        raise InputError(
            "SORA 2.5: M1A at medium robustness cannot be combined with M1B (time-based restrictions "
            "would count twice: [AMC-2.5] Annex B §B.2, p. 85)"
        )
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


def residual_arc_of(
    initial: str, claimed: str | None, *, bvlos: bool, edition: str = "2.5"
) -> tuple[str, str]:
    """Step #5: the residual ARC and the rule that allows it.

    ``claimed`` is the residual ARC the operator claims after strategic mitigations (None: no
    claim, the residual is the initial ARC, [AMC-2.5] S.4.5.1(c), p. 33). A claim above the
    initial ARC is refused. A VLOS operation (or BVLOS with airspace observers, ``bvlos``
    False) may lower the initial ARC by one class but never to ARC-a ([AMC-2.5] S.4.5.4,
    p. 34). Any other lower claim is an Annex C strategic-mitigation claim (operational
    restrictions or airspace structure) the operator must substantiate: it is accepted and
    labelled so; Annex C's own reduction limits are not checked.
    """
    if initial not in ARCS:
        raise InputError(f"unknown initial ARC {initial!r}")
    if claimed is None or claimed == initial:
        return (
            initial,
            "no strategic mitigation claimed: residual ARC = initial ARC ([AMC-2.5] S.4.5.1(c), p. 33)",
        )
    if claimed not in ARCS or ARCS.index(claimed) > ARCS.index(initial):
        raise InputError(
            f"residual ARC {claimed!r} must be one of a–{initial} (initial ARC-{initial}): strategic "
            "mitigations only lower the ARC ([AMC-2.5] S.4.5, p. 33)"
        )
    one_down = ARCS.index(initial) - ARCS.index(claimed) == 1
    if not bvlos and edition == "2.5" and one_down and claimed != "a":
        return claimed, (
            "VLOS (or BVLOS with airspace observers) lowers the initial ARC by one class ([AMC-2.5] "
            "S.4.5.4, p. 34)"
        )
    if not bvlos and edition == "2.5" and claimed == "a":
        raise InputError(
            "residual ARC-a: the VLOS/observer mitigation cannot reduce the ARC to ARC-a ([AMC-2.5] "
            "S.4.5.4, p. 34); ARC-a is the atypical air environment (p. 33): give --airspace atypical"
        )
    return claimed, (
        f"claimed strategic mitigation ARC-{initial} → ARC-{claimed} (SORA {edition} Annex C §5–6: "
        "operational restrictions or airspace structure), to be substantiated to the authority"
    )


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
        Residual ARC after strategic mitigations, when the operator claims one; checked by
        :func:`residual_arc_of`. Default: the initial ARC (no strategic mitigation assumed).
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
            f"iGRC {ig} (SORA 2.5 Table 2, [AMC-2.5] p. 24: {dimension_m:g} m, {speed_ms:g} m/s, "
            f"population {population})"
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
    arc, arc_rule = residual_arc_of(arc0, residual_arc, bvlos=bvlos, edition=edition)
    tm = TMPR[arc] if bvlos else "none"
    if ig is None:
        steps.append("grey cell of the iGRC table: outside the SORA, certified category")
        return SoraResult(
            edition, population, None, None, mit, arc0, arc, tm, None, True, (), tuple(steps), None, arc_rule
        )
    grc = final_grc(ig, mit, edition, floor)
    table = "Table 5, [AMC-2.5] p. 29" if edition == "2.5" else "Table 3"
    steps.append(f"final GRC {grc} (mitigations {mit or 'none'}, {table}; floor {floor})")
    steps.append(
        f"initial ARC-{arc0} (airspace {airspace}, {height_m:g} m AGL, {'urban' if urban else 'rural'})"
    )
    steps.append(f"residual ARC-{arc}: {arc_rule}")
    steps.append(
        f"TMPR {tm}"
        + (
            " (VLOS: see-and-avoid by the remote crew)"
            if not bvlos
            else f" ({'Table 6, [AMC-2.5] p. 35' if edition == '2.5' else 'Table 4'})"
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
        return SoraResult(
            edition, population, ig, grc, mit, arc0, arc, tm, None, True, (), tuple(steps), af, arc_rule
        )
    steps.append(f"SAIL {s} ({'[AMC-2.5] p. 38 (JARUS Table 7)' if edition == '2.5' else 'Table 5'})")
    return SoraResult(
        edition,
        population,
        ig,
        grc,
        mit,
        arc0,
        arc,
        tm,
        s,
        False,
        osos(s, edition),
        tuple(steps),
        af,
        arc_rule,
    )
