"""EUROCAE ED-269 geographical zone files (UAS geozones, JSON) read into typed zones.

ED-269 ("Minimum Operational Performance Standard for UAS Geo-Fencing", 2020) defines the
``UASZoneList`` JSON that EU Member States publish for (EU) 2019/947 Art. 15 zones. A zone has
a restriction (``PROHIBITED``, ``REQ_AUTHORISATION``, ``CONDITIONAL``, ``NO_RESTRICTION``), a
message, applicability schedules and one or more volumes: a horizontal projection (GeoJSON
``Polygon`` in WGS84 lon/lat, or ``Circle`` with ``center`` and ``radius`` in m) between a lower
and an upper limit, each with its vertical reference (``AGL``, ``AMSL``, ``WGS84``) in the
unit ``uomDimensions`` (``M`` or ``FT``).

The file is untrusted input (it may come from a URL): it is read bounded in bytes and nesting
depth (:mod:`uasnav.jsoncheck`), every value is checked for type and range, unknown enum values
are refused, polygons must be closed rings of finite lon/lat with at most
:data:`MAX_VERTICES` vertices in the file, and :data:`MAX_ZONES` zones at most. Every refusal
is one :class:`~uasnav.errors.DataFormatError` naming the file and the JSON path.

>>> z = parse_zones(b'{"UASZoneList": [{"identifier": "Z1", "restriction": "PROHIBITED", '
...     b'"geometry": [{"uomDimensions": "FT", "lowerLimit": 0, "lowerVerticalReference": "AGL", '
...     b'"upperLimit": 400, "upperVerticalReference": "AGL", "horizontalProjection": '
...     b'{"type": "Circle", "center": [6.1, 46.2], "radius": 500}}]}]}', "mem")
>>> z[0].restriction, round(z[0].volumes[0].upper_m, 2), z[0].volumes[0].circle
('PROHIBITED', 121.92, ((6.1, 46.2), 500.0))
"""

from __future__ import annotations

import datetime as dt
import os
import re
from dataclasses import dataclass
from typing import Any

from uasnav import jsoncheck as jc
from uasnav.errors import DataFormatError
from uasnav.limits import read_file_limited

#: Largest zone file accepted (bytes).
MAX_BYTES = 16 * 1024 * 1024
#: Most zones per file.
MAX_ZONES = 10_000
#: Most polygon vertices per file (all zones together).
MAX_VERTICES = 1_000_000
RESTRICTIONS = ("PROHIBITED", "REQ_AUTHORISATION", "CONDITIONAL", "NO_RESTRICTION")
REFERENCES = ("AGL", "AMSL", "WGS84")
DAYS = ("MON", "TUE", "WED", "THU", "FRI", "SAT", "SUN", "ANY")
_FT = 0.3048
_TIME = re.compile(r"^([01]\d|2[0-3]):([0-5]\d)(?::([0-5]\d)(?:\.\d+)?)?(Z|[+-]00:?00)?$")


@dataclass(frozen=True)
class Volume:
    """One airspace volume of a zone.

    ``polygon``: exterior ring ((lon, lat) deg, closed) or None; ``circle``: ((lon, lat), radius
    m) or None. ``lower_m``/``upper_m``: limits in m in their references (``lower_ref``,
    ``upper_ref``); ``upper_m`` is inf when the file gives none, ``lower_m`` 0 (surface, AGL).
    """

    polygon: tuple[tuple[float, float], ...] | None
    circle: tuple[tuple[float, float], float] | None
    lower_m: float
    lower_ref: str
    upper_m: float
    upper_ref: str


@dataclass(frozen=True)
class DailyPeriod:
    """Days (``MON`` … ``SUN``, ``ANY``) and a UTC time-of-day window; None = all day."""

    days: tuple[str, ...]
    start: dt.time | None
    end: dt.time | None


@dataclass(frozen=True)
class Applicability:
    """When a zone is active: ``permanent``, or from ``start`` to ``end`` (UTC, either may be
    None = open) on the ``daily`` periods (empty = every day, all day)."""

    permanent: bool
    start: dt.datetime | None
    end: dt.datetime | None
    daily: tuple[DailyPeriod, ...]

    def active(self, t: dt.datetime) -> bool:
        """Whether this applicability covers the instant ``t`` (aware datetime)."""
        if self.permanent:
            return True
        if self.start is not None and t < self.start:
            return False
        if self.end is not None and t > self.end:
            return False
        if not self.daily:
            return True
        tu = t.astimezone(dt.UTC)
        day = DAYS[tu.weekday()]
        tod = tu.time().replace(tzinfo=None)
        for p in self.daily:
            if p.days and "ANY" not in p.days and day not in p.days:
                continue
            lo = p.start or dt.time(0, 0)
            hi = p.end or dt.time(23, 59, 59, 999999)
            inside = lo <= tod <= hi if lo <= hi else (tod >= lo or tod <= hi)  # window over midnight
            if inside:
                return True
        return False

    def active_during(self, t0: dt.datetime, t1: dt.datetime) -> bool:
        """Whether this applicability covers some instant of the closed window [t0, t1] (aware).

        Exact: the active set is a union of closed intervals, so the window meets it iff it
        contains ``t0`` or the left end of one of those intervals — ``start`` or a daily
        period's start (or midnight, for periods over midnight and all-day ones) on one of the
        UTC days the window spans.
        """
        if t1 < t0:
            raise ValueError("window end before its start")
        if self.permanent or self.active(t0):
            return True
        cands = [self.start] if self.start is not None else []
        u0, u1 = t0.astimezone(dt.UTC), t1.astimezone(dt.UTC)
        day = u0.date() - dt.timedelta(days=1)
        while day <= u1.date():
            starts = {dt.time(0, 0)} | {p.start for p in self.daily if p.start is not None}
            cands += [dt.datetime.combine(day, t, tzinfo=dt.UTC) for t in starts]
            day += dt.timedelta(days=1)
        return any(t0 <= c <= t1 and self.active(c) for c in cands)


@dataclass(frozen=True)
class Zone:
    """One ED-269 UAS geographical zone."""

    identifier: str
    name: str
    country: str
    restriction: str
    message: str
    reasons: tuple[str, ...]
    applicability: tuple[Applicability, ...]
    volumes: tuple[Volume, ...]

    @property
    def scheduled(self) -> bool:
        """True if the zone is not permanent (it has a schedule)."""
        return bool(self.applicability) and not any(a.permanent for a in self.applicability)

    def active(self, t: dt.datetime) -> bool:
        """Whether the zone applies at ``t`` (no applicability given = always)."""
        return not self.applicability or any(a.active(t) for a in self.applicability)

    def active_during(self, t0: dt.datetime, t1: dt.datetime) -> bool:
        """Whether the zone applies at some instant of the window [t0, t1] (aware datetimes)."""
        return not self.applicability or any(a.active_during(t0, t1) for a in self.applicability)


def _opt_str(d: dict[str, Any], key: str, path: str) -> str:
    v = d.get(key)
    if v is None:
        return ""
    return jc.string(v, jc.at(path, key))[:2000]


def _limit(v: Any, path: str, unit: str, default: float) -> float:
    if v is None:
        return default
    if isinstance(v, str):
        try:
            x = float(v.strip())
        except ValueError:
            raise jc.fail(path, f"expected a number, got {jc.show(v)}") from None
        v = x
    x = jc.number(v, path, lo=-1e5, hi=1e6, unit=unit)
    return x * _FT if unit == "FT" else x


def _datetime(v: Any, path: str) -> dt.datetime | None:
    if v is None:
        return None
    s = jc.string(v, path)
    try:
        t = dt.datetime.fromisoformat(s.replace("Z", "+00:00"))
    except ValueError:
        raise jc.fail(path, f"not an ISO 8601 date-time: {jc.show(s)}") from None
    if t.tzinfo is None:
        raise jc.fail(path, f"date-time without a time zone: {jc.show(s)} (ED-269 times are UTC)")
    return t


def _tod(v: Any, path: str) -> dt.time | None:
    if v is None:
        return None
    s = jc.string(v, path)
    m = _TIME.match(s)
    if not m:
        raise jc.fail(path, f"not a UTC time of day HH:MM[:SS][Z]: {jc.show(s)}")
    return dt.time(int(m.group(1)), int(m.group(2)), int(m.group(3) or 0))


def _ring(coords: Any, path: str, budget: list[int]) -> tuple[tuple[float, float], ...]:
    rings = jc.array(coords, path, max_len=1000)
    outer = jc.array(rings[0], jc.at(path, 0), max_len=MAX_VERTICES)
    budget[0] += sum(len(r) if isinstance(r, list) else 0 for r in rings)
    if budget[0] > MAX_VERTICES:
        raise jc.fail(path, f"more than {MAX_VERTICES} polygon vertices in the file")
    pts = []
    for i, p in enumerate(outer):
        pp = jc.at(jc.at(path, 0), i)
        v = jc.vector(p, pp, max_len=3)
        if v.size not in (2, 3):
            raise jc.fail(pp, f"expected [lon, lat], got {v.size} numbers")
        lon, lat = float(v[0]), float(v[1])
        if not (-180.0 <= lon <= 180.0 and -90.0 <= lat <= 90.0):
            raise jc.fail(pp, f"[{lon:g}, {lat:g}] is not a WGS84 [lon, lat] in degrees")
        pts.append((lon, lat))
    if len(pts) < 4 or pts[0] != pts[-1]:
        raise jc.fail(
            jc.at(path, 0), "a polygon ring needs at least 4 positions, the last equal to the first"
        )
    return tuple(pts)


def _volume(g: Any, path: str, budget: list[int]) -> Volume:
    g = jc.obj(g, path)
    unit = jc.string(g.get("uomDimensions", "M"), jc.at(path, "uomDimensions"), ("M", "FT"))
    lo_ref = jc.string(
        g.get("lowerVerticalReference", "AGL"), jc.at(path, "lowerVerticalReference"), REFERENCES
    )
    hi_ref = jc.string(
        g.get("upperVerticalReference", "AGL"), jc.at(path, "upperVerticalReference"), REFERENCES
    )
    lo = _limit(g.get("lowerLimit"), jc.at(path, "lowerLimit"), unit, 0.0)
    hi = _limit(g.get("upperLimit"), jc.at(path, "upperLimit"), unit, float("inf"))
    if lo_ref == hi_ref and not lo < hi:
        raise jc.fail(path, f"lower limit {lo:g} m is not below upper limit {hi:g} m")
    hp = jc.obj(jc.field(g, "horizontalProjection", path), jc.at(path, "horizontalProjection"))
    hpath = jc.at(path, "horizontalProjection")
    kind = jc.string(jc.field(hp, "type", hpath), jc.at(hpath, "type"), ("Polygon", "Circle"))
    if kind == "Polygon":
        return Volume(
            _ring(jc.field(hp, "coordinates", hpath), jc.at(hpath, "coordinates"), budget),
            None,
            lo,
            lo_ref,
            hi,
            hi_ref,
        )
    c = jc.vector(jc.field(hp, "center", hpath), jc.at(hpath, "center"), length=2)
    if not (-180.0 <= c[0] <= 180.0 and -90.0 <= c[1] <= 90.0):
        raise jc.fail(jc.at(hpath, "center"), "not a WGS84 [lon, lat] in degrees")
    r = jc.number(jc.field(hp, "radius", hpath), jc.at(hpath, "radius"), positive=True, hi=1e6, unit="m")
    return Volume(None, ((float(c[0]), float(c[1])), r), lo, lo_ref, hi, hi_ref)


def _applicability(a: Any, path: str) -> Applicability:
    a = jc.obj(a, path)
    perm = a.get("permanent", "NO")
    perm = jc.string(perm, jc.at(path, "permanent"), ("YES", "NO")) == "YES"
    start = _datetime(a.get("startDateTime"), jc.at(path, "startDateTime"))
    end = _datetime(a.get("endDateTime"), jc.at(path, "endDateTime"))
    if start is not None and end is not None and not start < end:
        raise jc.fail(path, "startDateTime is not before endDateTime")
    daily = []
    for i, p in enumerate(a.get("dailyPeriod") or []):
        pp = jc.at(jc.at(path, "dailyPeriod"), i)
        p = jc.obj(p, pp)
        days = tuple(jc.string(d, jc.at(jc.at(pp, "day"), k), DAYS) for k, d in enumerate(p.get("day") or []))
        s, e = _tod(p.get("startTime"), jc.at(pp, "startTime")), _tod(p.get("endTime"), jc.at(pp, "endTime"))
        if (s is None) != (e is None):
            raise jc.fail(pp, "give both startTime and endTime, or neither")
        if days or s is not None:
            daily.append(DailyPeriod(days, s, e))
    if not perm and start is None and end is None and not daily:
        raise jc.fail(path, "not permanent and no schedule (startDateTime, endDateTime or dailyPeriod)")
    return Applicability(perm, start, end, tuple(daily))


def zones_from_json(doc: Any) -> tuple[Zone, ...]:
    """Zones from a parsed ED-269 document (errors name the JSON path, not the file)."""
    doc = jc.obj(doc, "document")
    lst = jc.array(jc.field(doc, "UASZoneList"), "UASZoneList", max_len=MAX_ZONES)
    budget = [0]
    out = []
    for i, z in enumerate(lst):
        zp = jc.at("UASZoneList", i)
        z = jc.obj(z, zp)
        ident = jc.string(jc.field(z, "identifier", zp), jc.at(zp, "identifier"))
        if not 0 < len(ident) <= 7 * 10:
            raise jc.fail(jc.at(zp, "identifier"), "expected 1 to 70 characters")
        restriction = jc.string(jc.field(z, "restriction", zp), jc.at(zp, "restriction"), RESTRICTIONS)
        reasons = tuple(
            jc.string(r, jc.at(jc.at(zp, "reason"), k))[:100] for k, r in enumerate(z.get("reason") or [])
        )
        geoms = jc.array(jc.field(z, "geometry", zp), jc.at(zp, "geometry"), max_len=1000)
        vols = tuple(_volume(g, jc.at(jc.at(zp, "geometry"), k), budget) for k, g in enumerate(geoms))
        apps = tuple(
            _applicability(a, jc.at(jc.at(zp, "applicability"), k))
            for k, a in enumerate(z.get("applicability") or [])
        )
        out.append(
            Zone(
                ident,
                _opt_str(z, "name", zp),
                _opt_str(z, "country", zp),
                restriction,
                _opt_str(z, "message", zp),
                reasons,
                apps,
                vols,
            )
        )
    return tuple(out)


def parse_zones(data: bytes, where: str, *, max_bytes: int = MAX_BYTES) -> tuple[Zone, ...]:
    """Zones from the bytes of an ED-269 file; ``where`` names it in errors."""
    if len(data) > max_bytes:
        raise DataFormatError(f"zone file larger than {max_bytes} bytes", path=where)
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise DataFormatError("not a UTF-8 text file", path=where) from None
    with jc.reraise_in(where):
        return zones_from_json(jc.parse(text, "not an ED-269 zone file (not valid JSON)"))


def read_zones(path: str | os.PathLike[str], *, max_bytes: int = MAX_BYTES) -> tuple[Zone, ...]:
    """Zones of the ED-269 file at ``path`` (read bounded: a device or FIFO cannot exhaust
    memory)."""
    p = os.fspath(path)
    return parse_zones(read_file_limited(p, max_bytes, p), p, max_bytes=max_bytes)
