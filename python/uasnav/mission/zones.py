"""Geographical zones (EUROCAE ED-269) against the mission area: which zones the flight enters,
in plan, in height and in time, and what each requires.

The mission area is GeoJSON (``Polygon``/``MultiPolygon``, a ``Feature`` or
``FeatureCollection`` of them; a ``Point`` — the take-off point — or a ``LineString`` is
buffered by ``buffer_m``). Both area and zones are projected to a local East-North plane (m)
about the area's centre with :func:`uasnav.geo.frames.geodetic_to_enu` and intersected with shapely.

Height: the flight occupies the band from the ground to ``height_m`` above ground. A zone
limit given AGL is compared directly; one given AMSL/WGS84 needs the ground elevation
(``ground_elevation_m``, m AMSL): without it the zone counts as hit and the hit says why.
A zone whose lower limit equals the top of the flight band is not entered (touching).

Time: a zone with a schedule is hit only when active at some instant of the flight window
[``when``, ``until``] (aware datetimes: take-off and the end of the flight; ``until`` None: the
take-off instant only); without ``when`` a scheduled zone counts as hit and the hit says why.

Plans: the area may also be a mission plan (QGroundControl ``.plan``, Mission Planner
``.waypoints``/``.txt``, uasnav plan ``.csv``, read by :mod:`uasnav.io.plans`); its footprint
is the flown route buffered by ``buffer_m`` (:func:`area_from_plan`).
"""

from __future__ import annotations

import datetime as dt
import math
import os
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
from shapely import geometry as sg
from shapely.ops import unary_union
from shapely.validation import explain_validity

from uasnav import jsoncheck as jc
from uasnav.errors import DataFormatError, InputError
from uasnav.geo import frames
from uasnav.io.ed269 import MAX_BYTES, Volume, Zone, parse_zones
from uasnav.io.mission_plan import AltitudeFrame, MissionPlan, plan_route
from uasnav.io.plan_formats.csv_plan import parse_plan_csv
from uasnav.io.plan_formats.qgc import parse_qgc_plan
from uasnav.io.plan_formats.source import MAX_PLAN_BYTES
from uasnav.io.plan_formats.wpl import parse_wpl
from uasnav.limits import read_file_limited

#: What each ED-269 restriction asks of the operator.
REQUIRES = {
    "PROHIBITED": "flight prohibited in the zone (unless exempted by the zone authority)",
    "REQ_AUTHORISATION": "authorisation from the zone authority before the flight",
    "CONDITIONAL": "the conditions of the zone (its message / restrictionConditions) apply",
    "NO_RESTRICTION": "no restriction (information only)",
}
MAX_AREA_VERTICES = 100_000


@dataclass(frozen=True)
class ZoneHit:
    """A zone the mission enters (or may enter: ``certain`` False says why not sure)."""

    identifier: str
    name: str
    restriction: str
    message: str
    reasons: tuple[str, ...]
    requires: str
    certain: bool
    why: tuple[str, ...]

    def to_dict(self) -> dict:
        d = dict(self.__dict__)
        d["reasons"], d["why"] = list(self.reasons), list(self.why)
        return d


@dataclass(frozen=True)
class ZoneCheck:
    """Outcome of checking one area against a zone file: the hits and how many zones were read."""

    source: str
    n_zones: int
    hits: tuple[ZoneHit, ...]

    def to_dict(self) -> dict:
        return {"source": self.source, "n_zones": self.n_zones, "hits": [h.to_dict() for h in self.hits]}


def _geom(g: Any, path: str, buffer_m: float, heights: list[tuple[float, float, float]]) -> list[Any]:
    """The parts of GeoJSON object ``g``; each position's third coordinate (a height) is added
    to ``heights`` as (lon, lat, h)."""
    g = jc.obj(g, path)
    t = jc.string(jc.field(g, "type", path), jc.at(path, "type"))
    if t == "FeatureCollection":
        feats = jc.array(jc.field(g, "features", path), jc.at(path, "features"), max_len=10_000)
        return [
            x
            for i, f in enumerate(feats)
            for x in _geom(f, jc.at(jc.at(path, "features"), i), buffer_m, heights)
        ]
    if t == "Feature":
        return _geom(jc.field(g, "geometry", path), jc.at(path, "geometry"), buffer_m, heights)
    coords = jc.field(g, "coordinates", path)
    cpath = jc.at(path, "coordinates")

    def pts(seq: Any, p: str) -> list[tuple[float, float]]:
        arr = jc.array(seq, p, max_len=MAX_AREA_VERTICES)
        out = []
        for i, v in enumerate(arr):
            x = jc.vector(v, jc.at(p, i), max_len=3)
            if x.size < 2 or not (-180 <= x[0] <= 180 and -90 <= x[1] <= 90):
                raise jc.fail(jc.at(p, i), "expected a WGS84 [lon, lat] in degrees")
            out.append((float(x[0]), float(x[1])))
            if x.size == 3:
                heights.append((float(x[0]), float(x[1]), float(x[2])))
        return out

    def ring(seq: Any, p: str) -> list[tuple[float, float]]:
        # RFC 7946 §3.1.6: a linear ring is closed and has >= 4 positions (3 distinct corners)
        r = pts(seq, p)
        if len(r) >= 2 and r[0] != r[-1]:
            warnings.warn(
                f"{p}: polygon ring not closed (its last position differs from the first); closed it",
                stacklevel=2,
            )
            r = [*r, r[0]]
        if len(set(r)) < 3:
            raise jc.fail(p, f"a polygon ring needs at least 3 distinct corners, got {len(set(r))}")
        return r

    if t == "Polygon":
        rings = jc.array(coords, cpath, max_len=1000)
        return [("poly", [ring(r, jc.at(cpath, i)) for i, r in enumerate(rings)])]
    if t == "MultiPolygon":
        polys = jc.array(coords, cpath, max_len=1000)
        return [
            ("poly", [ring(r, jc.at(jc.at(cpath, k), i)) for i, r in enumerate(jc.array(p, jc.at(cpath, k)))])
            for k, p in enumerate(polys)
        ]
    if t in ("Point", "LineString"):
        if not buffer_m > 0:
            raise jc.fail(path, f"a {t} needs a buffer > 0 m to make an area")
        return [
            (
                "line" if t == "LineString" else "point",
                pts(coords, cpath) if t == "LineString" else pts([coords], cpath),
            )
        ]
    raise jc.fail(
        jc.at(path, "type"),
        "expected a Polygon, MultiPolygon, Point, LineString, Feature or FeatureCollection, "
        f"got {jc.show(t)}",
    )


@dataclass(frozen=True)
class MissionArea:
    """The mission area in WGS84: the parsed parts and the buffer (m) applied to them."""

    parts: tuple[Any, ...]
    buffer_m: float
    where: str
    #: For a plan's footprint: each positioned item's altitude as (altitude m, frame — an
    #: :class:`~uasnav.io.mission_plan.AltitudeFrame` value —, item index); empty otherwise.
    plan_altitudes: tuple[tuple[float, str, int], ...] = ()
    #: For a plan's footprint: the plan's home position (lat, lon deg, altitude m AMSL; NaN when
    #: the plan gives no altitude); None otherwise.
    home: tuple[float, float, float] | None = None
    #: For a GeoJSON area: the positions that carry a third coordinate, as (lon, lat deg, height
    #: m above the WGS-84 ellipsoid, RFC 7946 §4); empty otherwise.
    heights: tuple[tuple[float, float, float], ...] = ()

    def centre(self) -> tuple[float, float]:
        """(lon, lat) deg: mean of every vertex (the projection origin)."""
        v = [p for kind, data in self.parts for p in (data if kind != "poly" else data[0])]
        a = np.asarray(v)
        return float(a[:, 0].mean()), float(a[:, 1].mean())

    def local(self, lon0: float, lat0: float):
        """Shapely geometry in the local East-North plane (m) about (lon0, lat0)."""
        shapes = []
        for kind, data in self.parts:
            if kind == "poly":
                rings = [_enu(r, lon0, lat0) for r in data]
                shapes.append(sg.Polygon(rings[0], rings[1:]))
            elif kind == "line":
                shapes.append(sg.LineString(_enu(data, lon0, lat0)))
            else:
                shapes.append(sg.Point(_enu(data, lon0, lat0)[0]))
        g = unary_union(shapes)
        if self.buffer_m > 0:
            g = g.buffer(self.buffer_m)
        if not g.is_valid:
            raise DataFormatError(
                f"mission area is not a valid polygon: {explain_validity(g)}", path=self.where
            )
        return g


def _enu(pts: list[tuple[float, float]], lon0: float, lat0: float) -> list[tuple[float, float]]:
    a = np.asarray(pts, dtype=float)
    e, n, _ = frames.geodetic_to_enu(a[:, 1], a[:, 0], 0.0, lat0, lon0, 0.0)
    return list(zip(np.atleast_1d(e).tolist(), np.atleast_1d(n).tolist(), strict=True))


def _area_text(data: bytes, where: str, *, limit: int = MAX_BYTES, what: str = "area file") -> str:
    """An area document's bytes as text: at most ``limit`` bytes of UTF-8 (a BOM dropped), else
    one error naming ``where``."""
    if len(data) > limit:
        raise DataFormatError(f"{what} larger than {limit} bytes", path=where)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise DataFormatError("not a UTF-8 text file", path=where) from None


def parse_area(data: bytes | str | dict, where: str = "area", *, buffer_m: float = 0.0) -> MissionArea:
    """The mission area from GeoJSON (bytes, text or a parsed object); see the module doc."""
    if not math.isfinite(buffer_m) or buffer_m < 0:
        raise InputError(f"area buffer {buffer_m} m: must be finite and >= 0")
    if isinstance(data, bytes):
        data = _area_text(data, where)
    heights: list[tuple[float, float, float]] = []
    with jc.reraise_in(where):
        doc = jc.parse(data, "not a GeoJSON area (not valid JSON)") if isinstance(data, str) else data
        parts = _geom(doc, "area", buffer_m, heights)
        if not parts:
            raise jc.fail("area", "no geometry")
    return MissionArea(tuple(parts), float(buffer_m), where, heights=tuple(heights))


def area_from_plan(plan: MissionPlan, where: str = "plan", *, buffer_m: float) -> MissionArea:
    """The footprint of a mission plan: its route in flown order (:func:`uasnav.io.plans.plan_route`,
    north/east m about the plan's origin) back to WGS84, buffered by ``buffer_m`` (m, > 0).

    Raises
    ------
    InputError
        A plan without a geographic origin (a north/east CSV): it cannot be placed on the map.
    """
    if not math.isfinite(buffer_m) or buffer_m <= 0:
        raise InputError(f"plan footprint buffer {buffer_m} m: must be finite and > 0")
    route, origin = plan_route(plan)
    if origin is None:
        raise InputError(f"{where}: a plan in local north/east has no geographic origin; give a GeoJSON area")
    if len(route) == 0:
        raise InputError(f"{where}: the plan has no positioned item")
    lat0, lon0 = origin[0], origin[1]
    lat, lon, _ = frames.ned_to_geodetic(route[:, 0], route[:, 1], 0.0, lat0, lon0, 0.0)
    pts = list(zip(np.atleast_1d(lon).tolist(), np.atleast_1d(lat).tolist(), strict=True))
    part = ("point", pts[:1]) if len(pts) == 1 else ("line", pts)
    alts = tuple(
        (float(it.alt_m), it.altitude_frame.value, k)
        for k, it in enumerate(plan.items)
        if it.has_position and math.isfinite(it.alt_m) and it.altitude_frame is not AltitudeFrame.NONE
    )
    h = plan.home
    home = (
        (float(h.lat_deg), float(h.lon_deg), float(h.alt_amsl_m))
        if h is not None and all(math.isfinite(x) for x in (h.lat_deg, h.lon_deg))
        else None
    )
    return MissionArea((part,), float(buffer_m), where, alts, home)


def plan_height(area: MissionArea, *, ground_elevation_m: float | None) -> tuple[float, str] | None:
    """The highest height above ground (m) a plan's footprint ``area`` flies, and which item and
    frame gave it; None when the area is no plan or no item carries an altitude.

    Frames: ``terrain`` is above the ground below the UA (AGL); ``relative`` is above the
    take-off point, taken as AGL (level ground: the plan says nothing of the terrain); ``amsl``
    needs the ground elevation (m AMSL) of the area to become AGL.

    Raises
    ------
    InputError
        An AMSL altitude without ``ground_elevation_m``: the frames cannot be compared.
    """
    best: tuple[float, str] | None = None
    n = len(area.plan_altitudes)
    # Items are named by their 1-based place among the plan's items (the home position apart).
    for alt, frame, k in area.plan_altitudes:
        if frame == AltitudeFrame.AMSL.value:
            if ground_elevation_m is None:
                raise InputError(
                    f"{area.where}: item {k + 1} flies at {alt:g} m AMSL, which cannot be compared with "
                    "--altitude (above ground) or the height limits without --ground-elevation"
                )
            h, how = alt - ground_elevation_m, f"{alt:g} m AMSL - ground {ground_elevation_m:g} m"
        elif frame == AltitudeFrame.TERRAIN.value:
            h, how = alt, f"{alt:g} m above terrain"
        else:
            h, how = alt, f"{alt:g} m above take-off, taken as above ground"
        if best is None or h > best[0]:
            best = (h, f"{area.where} item {k + 1} of {n}: {how}")
    return best


def _plan_parser(where: str, data: bytes | str | dict):
    """The plan parser for a document (by the name's extension, else by its content), or None
    for GeoJSON."""
    ext = os.path.splitext(where)[1].lower()
    by_ext = {".plan": parse_qgc_plan, ".waypoints": parse_wpl, ".txt": parse_wpl, ".csv": parse_plan_csv}
    if ext in by_ext:
        return by_ext[ext]
    if isinstance(data, dict):
        return parse_qgc_plan if data.get("fileType") == "Plan" else None
    head = data[:256] if isinstance(data, str) else data[:256].decode("utf-8", "replace")
    if head.lstrip("\ufeff").startswith("QGC WPL"):
        return parse_wpl
    if '"fileType"' in head and '"Plan"' in head:
        return parse_qgc_plan
    return None


def is_plan_document(where: str, data: bytes | str | dict) -> bool:
    """Whether an ``--area`` document is a mission plan (extension or content) rather than GeoJSON."""
    return _plan_parser(where, data) is not None


def parse_area_document(data: bytes | str | dict, where: str = "area", *, buffer_m: float) -> MissionArea:
    """An ``--area`` document: GeoJSON (:func:`parse_area`) or a mission plan (footprint of its
    route, :func:`area_from_plan`), told apart by ``where``'s extension or the content."""
    parser = _plan_parser(where, data)
    if parser is None:
        return parse_area(data, where, buffer_m=buffer_m)
    if isinstance(data, dict):
        import json

        text = json.dumps(data)
    elif isinstance(data, bytes):
        text = _area_text(data, where, limit=MAX_PLAN_BYTES, what="plan")
    else:
        text = data
    return area_from_plan(parser(text, where), where, buffer_m=buffer_m)


def read_area(path: str | os.PathLike[str], *, buffer_m: float = 0.0) -> MissionArea:
    """The mission area from a GeoJSON file (read bounded)."""
    p = os.fspath(path)
    return parse_area(read_file_limited(p, MAX_BYTES, p), p, buffer_m=buffer_m)


def load_zones(source: str | os.PathLike[str], **fetch_kw) -> tuple[tuple[Zone, ...], str]:
    """Zones from an ED-269 file path or an http(s) URL (fetched with the selector's hardened
    fetcher: deadline, size limit, validated cache). Returns (zones, where)."""
    from uasnav.mission.loading import fetch, is_url

    if is_url(source):
        url = str(source)
        fetched = fetch(url, check=lambda b, w: parse_zones(b, w), accept="application/json", **fetch_kw)
        return parse_zones(fetched.data, url), url
    p = os.fspath(source)
    if os.path.isdir(p):
        raise InputError(f"{p}: is a directory, not a zone file")
    return parse_zones(read_file_limited(p, MAX_BYTES, p), p), p


def _volume_shape(v: Volume, lon0: float, lat0: float):
    if v.polygon is not None:
        return sg.Polygon(_enu(list(v.polygon), lon0, lat0))
    (clon, clat), r = v.circle  # type: ignore[misc]
    return sg.Point(_enu([(clon, clat)], lon0, lat0)[0]).buffer(r, quad_segs=32)


def _vertical(v: Volume, height_m: float, ground_m: float | None) -> tuple[bool, bool, str]:
    """(enters, certain, why) for the flight band [0, height_m] AGL against the volume."""

    def to_agl(x: float, ref: str) -> float | None:
        if ref == "AGL" or not math.isfinite(x):
            return x
        return None if ground_m is None else x - ground_m

    lo = to_agl(v.lower_m, v.lower_ref)
    hi = to_agl(v.upper_m, v.upper_ref)
    if lo is None or hi is None:
        refs = sorted({r for r, x in ((v.lower_ref, lo), (v.upper_ref, hi)) if x is None})
        return (
            True,
            False,
            (
                f"{'/'.join(refs)} limit ({v.lower_m:g}–{v.upper_m:g} m) cannot be compared with a flight "
                "given above ground without --ground-elevation: counted as hit"
            ),
        )
    enters = height_m > lo and hi > 0.0
    return enters, True, f"zone {lo:g}–{hi:g} m AGL, flight 0–{height_m:g} m AGL"


def check_zones(
    zones: tuple[Zone, ...],
    area: MissionArea,
    *,
    height_m: float,
    ground_elevation_m: float | None = None,
    when: dt.datetime | None = None,
    until: dt.datetime | None = None,
    source: str = "zones",
) -> ZoneCheck:
    """Every zone the mission area enters (see the module doc for height and time)."""
    if not math.isfinite(height_m) or height_m <= 0:
        raise InputError(f"flight height {height_m} m: must be finite and > 0")
    if when is not None and when.tzinfo is None:
        raise InputError("flight time must carry a time zone (UTC)")
    if until is not None and (when is None or until.tzinfo is None or until < when):
        raise InputError("flight window: the end needs a take-off time and must not be before it")
    lon0, lat0 = area.centre()
    a = area.local(lon0, lat0)
    hits = []
    for z in zones:
        why: list[str] = []
        certain = True
        entered = False
        for v in z.volumes:
            shape = _volume_shape(v, lon0, lat0)
            if not shape.is_valid:
                raise DataFormatError(
                    f"zone {z.identifier}: polygon is not valid ({explain_validity(shape)})", path=source
                )
            if not shape.intersects(a):
                continue
            ok, sure, w = _vertical(v, height_m, ground_elevation_m)
            if ok:
                entered = True
                certain &= sure
                why.append(f"area intersects the zone; {w}")
        if not entered:
            continue
        if z.scheduled:
            if when is None:
                certain = False
                why.append("the zone has a schedule and no flight time was given: counted as hit")
            elif until is not None and until > when:
                if not z.active_during(when, until):
                    continue
                why.append(
                    f"the zone's schedule is active during the flight window {when.isoformat()} – "
                    f"{until.isoformat()}"
                )
            elif not z.active(when):
                continue
            else:
                why.append(f"the zone's schedule is active at {when.isoformat()}")
        hits.append(
            ZoneHit(
                z.identifier,
                z.name,
                z.restriction,
                z.message,
                z.reasons,
                REQUIRES[z.restriction],
                certain,
                tuple(why),
            )
        )
    return ZoneCheck(source, len(zones), tuple(hits))


def parse_when(text: str) -> dt.datetime:
    """An ISO 8601 date-time with a time zone (``2026-05-01T10:00Z``) → aware datetime."""
    try:
        t = dt.datetime.fromisoformat(text.strip().replace("Z", "+00:00"))
    except ValueError:
        raise InputError(f"flight_time: {text!r} is not an ISO 8601 date-time") from None
    if t.tzinfo is None:
        raise InputError(f"flight_time: {text!r} has no time zone (add Z for UTC)")
    return t


__all__ = [
    "REQUIRES",
    "MissionArea",
    "ZoneCheck",
    "ZoneHit",
    "area_from_plan",
    "check_zones",
    "is_plan_document",
    "load_zones",
    "parse_area",
    "parse_area_document",
    "parse_when",
    "read_area",
]


def kml_area_geojson(data: bytes | str, where: str = "area.kml") -> dict[str, Any]:
    """A KML area (its ``Polygon`` placemarks; else a ``LineString`` or ``Point``) as the GeoJSON
    object :func:`parse_area` reads. Parsed by the hardened KML reader of
    :mod:`uasnav.io.plan_formats.kml` (no DTD, no entities, no network).

    KML altitudes are dropped, so they never give the ground elevation: under KML's default
    ``altitudeMode`` (``clampToGround``) they are ignored by definition, and the other modes
    give heights above the terrain or above sea level of the drawn shape, not of the ground."""
    from uasnav.io.plan_formats import kml

    if isinstance(data, bytes):
        data = _area_text(data, where)
    root = kml._parse(data, where)
    geoms: list[dict[str, Any]] = []
    for poly in kml._find(root, "Polygon"):
        rings = []
        for tag in ("outerBoundaryIs", "innerBoundaryIs"):
            for b in kml._find(poly, tag):
                for c in kml._find(b, "coordinates"):
                    rings.append([[x, y] for x, y, _ in kml._coords(c, where)])
        if rings:
            geoms.append({"type": "Polygon", "coordinates": rings})
    if not geoms:
        for ls in kml._find(root, "LineString"):
            for c in kml._find(ls, "coordinates"):
                geoms.append(
                    {"type": "LineString", "coordinates": [[x, y] for x, y, _ in kml._coords(c, where)]}
                )
    if not geoms:
        raise DataFormatError("no Polygon or LineString in the KML area", path=where)
    return {
        "type": "FeatureCollection",
        "features": [{"type": "Feature", "geometry": g, "properties": {}} for g in geoms],
    }
