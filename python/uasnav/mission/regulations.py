"""Regulations database: per jurisdiction, mass classes and categories with cited limits.

Limits are stored as printed in the legal text (value, unit, "less than" = ``lt`` or "at most"
= ``le``) and converted to g, m and m/s here. Tests sit exactly on the limits (249/250 g,
899/900 g, 3.99/4 kg, 119/120 m, 400 ft), so comparisons are exact on the converted value
with a relative slack of 1e-12 only for the floating-point rounding of the unit conversion.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from uasnav.errors import InputError
from uasnav.mission.loading import load_document
from uasnav.units import convert

_MASS_G = {"g": 1.0, "kg": 1000.0, "lb": 453.59237}
_SI = {"mtom": "g", "height": "m", "span": "m", "speed": "m/s"}
_EPS = 1e-12

#: The category assumed per jurisdiction when none is given (``uasnav select --category``).
DEFAULT_CATEGORY: dict[str, str] = {"easa": "open", "faa": "part107"}


@dataclass(frozen=True)
class Limit:
    """One legal limit: ``quantity`` (mtom g, height m, speed m/s, span m) ``op`` value."""

    quantity: str
    op: str
    value: float
    unit: str
    value_si: float
    source: str

    def allows(self, x: float) -> bool:
        """Whether ``x`` (in g, m or m/s) satisfies the limit."""
        if self.op == "lt":
            return x < self.value_si * (1.0 - _EPS)
        return x <= self.value_si * (1.0 + _EPS)

    def describe(self) -> str:
        """E.g. ``"mtom < 4 kg (EU2019/945 Annex Part 3 (1))"``."""
        return f"{self.quantity} {'<' if self.op == 'lt' else '≤'} {self.value:g} {self.unit} ({self.source})"


@dataclass(frozen=True)
class Subcategory:
    """An EASA open subcategory: the classes it admits and the distances to people it keeps.

    ``overfly_uninvolved``: classes (``"legacy"`` for unmarked UA below ``legacy_mtom_lt_g``)
    allowed over uninvolved persons; ``people_distance_m``: horizontal distance kept from
    uninvolved persons (m); ``residential_distance_m``: distance kept from residential,
    commercial, industrial or recreational areas (m) — such a subcategory is closed to urban
    operations.
    """

    id: str
    classes: tuple[str, ...]
    legacy_mtom_lt_g: float | None
    source: str
    overfly_uninvolved: tuple[str, ...] = ()
    people_distance_m: float | None = None
    residential_distance_m: float | None = None


@dataclass(frozen=True)
class Category:
    """An operational category (EASA open/specific, FAA Part 107)."""

    id: str
    vlos_required: bool
    limits: tuple[Limit, ...]
    subcategories: dict[str, Subcategory]
    source: str

    def limit(self, quantity: str) -> Limit | None:
        """The category's limit on ``quantity``, if any."""
        return next((lim for lim in self.limits if lim.quantity == quantity), None)


@dataclass(frozen=True)
class Jurisdiction:
    """One jurisdiction: legal references, mass classes and categories."""

    id: str
    name: str
    references: dict[str, str]
    classes: dict[str, tuple[Limit, ...]]
    categories: dict[str, Category]


@dataclass(frozen=True)
class RuleCheck:
    """Outcome of checking one value against one limit; ``margin`` > 0 inside, SI units."""

    limit: Limit
    value: float
    ok: bool

    @property
    def margin(self) -> float:
        return self.limit.value_si - self.value


class Regulations:
    """The regulations database; see :func:`load_regulations`."""

    def __init__(self, jurisdictions: dict[str, Jurisdiction], where: str) -> None:
        self.jurisdictions = jurisdictions
        self.where = where

    def category(self, jurisdiction: str, category: str) -> Category:
        """The category or an InputError naming what exists."""
        try:
            jur = self.jurisdictions[jurisdiction]
        except KeyError:
            raise InputError(
                f"unknown jurisdiction {jurisdiction!r}; known: {', '.join(self.jurisdictions)}"
            ) from None
        try:
            return jur.categories[category]
        except KeyError:
            raise InputError(
                f"{jurisdiction}: unknown category {category!r}; known: {', '.join(jur.categories)}"
            ) from None

    def max_height_m(self, jurisdiction: str, category: str) -> float:
        """Highest flight height (m above ground) allowed by the category (inf if none)."""
        lim = self.category(jurisdiction, category).limit("height")
        return lim.value_si if lim is not None else float("inf")

    def check(
        self,
        jurisdiction: str,
        category: str,
        *,
        mtom_g: float | None = None,
        height_m: float | None = None,
        speed_ms: float | None = None,
        span_m: float | None = None,
    ) -> list[RuleCheck]:
        """Check the given quantities against every limit of the category."""
        values = {"mtom": mtom_g, "height": height_m, "speed": speed_ms, "span": span_m}
        out = []
        for lim in self.category(jurisdiction, category).limits:
            v = values[lim.quantity]
            if v is not None:
                out.append(RuleCheck(lim, float(v), lim.allows(float(v))))
        return out

    def allowed(self, jurisdiction: str, category: str, **values: float) -> bool:
        """True when every applicable limit is satisfied."""
        return all(c.ok for c in self.check(jurisdiction, category, **values))

    def classes_for(self, jurisdiction: str, *, mtom_g: float, speed_ms: float | None = None) -> list[str]:
        """Classes whose limits admit the given values, lightest first."""
        jur = self.jurisdictions[jurisdiction]
        vals = {"mtom": mtom_g, "speed": speed_ms}
        ok = []
        for cid, limits in jur.classes.items():
            if all(lim.allows(vals[lim.quantity]) for lim in limits if vals.get(lim.quantity) is not None):
                ok.append(cid)
        return ok

    def open_subcategory(
        self,
        mtom_g: float,
        eu_class: str | None = None,
        *,
        over_people: str = "none",
        urban: bool = False,
    ) -> str | None:
        """EASA open subcategory (A1/A2/A3) for a UAS; None if the open category is closed to it.

        A class-marked UAS flies in the subcategories that list its class; an unmarked one
        (legacy, Art. 20 of (EU) 2019/947) in A1 below 250 g, else A3 below 25 kg. The
        operation narrows the choice: over ``"uninvolved"`` persons only a subcategory that lets
        this class overfly them (A1 with C0 or an unmarked UA below 250 g); over
        ``"assemblies"`` none (Art. 4(1)(c)); in an ``urban`` area not A3 (150 m from
        residential areas, UAS.OPEN.040(2)).
        """
        cat = self.category("easa", "open")
        if over_people == "assemblies":
            return None
        if not all(c.ok for c in self.check("easa", "open", mtom_g=mtom_g)):
            return None
        for sid, sub in cat.subcategories.items():
            legacy = eu_class is None and sub.legacy_mtom_lt_g is not None and mtom_g < sub.legacy_mtom_lt_g
            if not (legacy or (eu_class is not None and eu_class in sub.classes)):
                continue
            if (
                over_people == "uninvolved"
                and ("legacy" if legacy else eu_class) not in sub.overfly_uninvolved
            ):
                continue
            if urban and sub.residential_distance_m is not None:
                continue
            return sid
        return None


def _limit(el) -> Limit:
    q, unit, value = el.get("quantity"), el.get("unit"), float(el.get("value"))
    si = value * _MASS_G[unit] if q == "mtom" else convert(value, unit, _SI[q])
    return Limit(q, el.get("op"), value, unit, float(si), el.get("source"))


def load_regulations(source: str | os.PathLike | None = None, **fetch_kw) -> Regulations:
    """Load and validate the regulations database (default: the shipped copy)."""
    tree, where = load_document(source, "regulations", default="regulations.xml", **fetch_kw)
    jurs = {}
    for j in tree.getroot().iterfind("jurisdiction"):
        refs = {r.get("id"): (r.text or "").strip() for r in j.iterfind("reference")}
        classes = {c.get("id"): tuple(_limit(x) for x in c.iterfind("limit")) for c in j.iterfind("class")}
        cats = {}
        for c in j.iterfind("category"):
            subs = {
                s.get("id"): Subcategory(
                    s.get("id"),
                    tuple(s.get("classes").split()),
                    float(s.get("legacy-mtom-lt-g")) if s.get("legacy-mtom-lt-g") else None,
                    s.get("source"),
                    tuple((s.get("overfly-uninvolved") or "").split()),
                    float(s.get("people-distance-m")) if s.get("people-distance-m") else None,
                    float(s.get("residential-distance-m")) if s.get("residential-distance-m") else None,
                )
                for s in c.iterfind("subcategory")
            }
            cats[c.get("id")] = Category(
                c.get("id"),
                c.get("vlos") == "required",
                tuple(_limit(x) for x in c.iterfind("limit")),
                subs,
                c.get("source"),
            )
        jurs[j.get("id")] = Jurisdiction(j.get("id"), j.get("name"), refs, classes, cats)
    return Regulations(jurs, where)
