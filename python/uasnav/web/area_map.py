"""The offline map of the selection page: an inline SVG drawn from the uploaded documents.

No tiles and no requests: the mission area, the ED-269 zones coloured by restriction, the
survey lines, the take-off and pilot points, a scale bar and a north arrow are drawn in a local
East-North plane (m) about the area's centre (the same projection the zone check uses), north
up. Coordinates in the SVG are metres scaled to the drawing; y grows southwards. The ``svg``
carries the drawing's georeference (``data-origin``, ``data-m-per-deg``, ``data-view``), so the
page's script turns a click into latitude and longitude.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from html import escape
from typing import Any

import numpy as np
from markupsafe import Markup
from shapely import geometry as sg

from uasnav.geo import frames
from uasnav.io.ed269 import Zone
from uasnav.mission.zones import MissionArea

#: Drawing size (SVG user units); the page scales it to the column.
WIDTH, HEIGHT, PAD = 640.0, 420.0, 28.0
#: Zone restriction → CSS class (colour in app.css) and legend text.
RESTRICTIONS: dict[str, tuple[str, str]] = {
    "PROHIBITED": ("z-prohibited", "prohibited"),
    "REQ_AUTHORISATION": ("z-auth", "authorisation required"),
    "CONDITIONAL": ("z-conditional", "conditional"),
    "NO_RESTRICTION": ("z-none", "no restriction"),
}


@dataclass
class MapLayers:
    """What the map draws, in WGS84 degrees."""

    area: MissionArea
    zones: Sequence[Zone] = ()
    #: Survey lines, each a sequence of (lat, lon) deg.
    lines: Sequence[Sequence[tuple[float, float]]] = ()
    #: Named points (label → (lat, lon) deg): take-off, pilot.
    points: dict[str, tuple[float, float]] = field(default_factory=dict)


def _enu(latlon: Iterable[tuple[float, float]], lat0: float, lon0: float) -> list[tuple[float, float]]:
    a = np.asarray(list(latlon), dtype=float).reshape(-1, 2)
    e, n, _ = frames.geodetic_to_enu(a[:, 0], a[:, 1], 0.0, lat0, lon0, 0.0)
    return list(zip(np.atleast_1d(e).tolist(), np.atleast_1d(n).tolist(), strict=True))


def _zone_shapes(zone: Zone, lat0: float, lon0: float) -> list[Any]:
    out = []
    for v in zone.volumes:
        if v.polygon is not None:
            out.append(sg.Polygon(_enu(((lat, lon) for lon, lat in v.polygon), lat0, lon0)))
        elif v.circle is not None:
            (clon, clat), r = v.circle
            out.append(sg.Point(_enu([(clat, clon)], lat0, lon0)[0]).buffer(r, quad_segs=32))
    return out


def _nice_length(m: float) -> float:
    """The round length (1, 2, 5 × 10^k m) at most ``m``."""
    if m <= 0:
        return 1.0
    k = 10 ** math.floor(math.log10(m))
    return max(s * k for s in (1, 2, 5) if s * k <= m)


def area_map(layers: MapLayers, title: str = "Mission area") -> Markup:
    """The map as inline SVG markup (role="img", with a text legend)."""
    lon0, lat0 = layers.area.centre()
    area = layers.area.local(lon0, lat0)
    zones = [(z, s) for z in layers.zones for s in _zone_shapes(z, lat0, lon0)]
    lines = [_enu(line, lat0, lon0) for line in layers.lines if len(line) >= 2]
    points = {k: _enu([v], lat0, lon0)[0] for k, v in layers.points.items()}

    # the view: the area, the lines and points, and the zones that come near them
    xs, ys = [area.bounds[0], area.bounds[2]], [area.bounds[1], area.bounds[3]]
    for line in lines:
        xs += [p[0] for p in line]
        ys += [p[1] for p in line]
    for p in points.values():
        xs.append(p[0])
        ys.append(p[1])
    span = max(max(xs) - min(xs), max(ys) - min(ys), 50.0)
    near = sg.box(min(xs), min(ys), max(xs), max(ys)).buffer(0.5 * span)
    zones = [(z, s.intersection(near)) for z, s in zones if s.intersects(near)]
    x0, x1 = min(xs) - 0.08 * span, max(xs) + 0.08 * span
    y0, y1 = min(ys) - 0.08 * span, max(ys) + 0.08 * span
    k = min((WIDTH - 2 * PAD) / (x1 - x0), (HEIGHT - 2 * PAD) / (y1 - y0))
    ox = PAD + ((WIDTH - 2 * PAD) - k * (x1 - x0)) / 2
    oy = PAD + ((HEIGHT - 2 * PAD) - k * (y1 - y0)) / 2

    def xy(e: float, n: float) -> str:
        return f"{ox + k * (e - x0):.1f},{oy + k * (y1 - n):.1f}"

    def path_of(g: Any) -> str:
        if g.is_empty:
            return ""
        if g.geom_type in ("MultiPolygon", "GeometryCollection"):
            return " ".join(path_of(p) for p in g.geoms)
        if g.geom_type != "Polygon":
            return ""
        rings = [g.exterior, *g.interiors]
        return " ".join("M" + " L".join(xy(e, n) for e, n in r.coords) + " Z" for r in rings)

    # the drawing → (lat, lon) for the page's script (a click sets the take-off or pilot point):
    # east/north from the drawing, then degrees through the radii of curvature at the centre
    # (a linearisation: 8 cm off at 1 km from the centre, 1.6 m at 4 km, against the drawing's
    # pixel of span/580: 1.7 m and 7 m)
    m_north, m_east = frames.radii_of_curvature(lat0)
    m_lat, m_lon = math.radians(m_north), math.radians(m_east * math.cos(math.radians(lat0)))
    geo = (
        f'data-origin="{lat0:.9f},{lon0:.9f}" data-m-per-deg="{m_lat:.4f},{m_lon:.4f}" '
        f'data-view="{ox:.6f},{oy:.6f},{k:.9g},{x0:.6f},{y1:.6f}"'
    )
    out = [
        f'<svg class="map" viewBox="0 0 {WIDTH:.0f} {HEIGHT:.0f}" role="img" aria-labelledby="map-t map-d" '
        f'xmlns="http://www.w3.org/2000/svg" {geo}>',
        f'<title id="map-t">{escape(title)}</title>',
        '<rect class="map-bg" x="0" y="0" width="100%" height="100%"/>',
    ]
    seen: dict[str, str] = {}
    for z, g in zones:
        cls, label = RESTRICTIONS.get(z.restriction, ("z-none", z.restriction.lower()))
        seen[cls] = label
        out.append(
            f'<path class="zone {cls}" d="{path_of(g)}"><title>{escape(z.identifier)} {escape(z.name)}: '
            f"{escape(label)}</title></path>"
        )
    out.append(f'<path class="area" d="{path_of(area)}"><title>mission area</title></path>')
    for line in lines:
        out.append(f'<polyline class="survey" points="{" ".join(xy(e, n) for e, n in line)}"/>')
    for name, (e, n) in points.items():
        cls = "pilot" if "pilot" in name.lower() else "takeoff"
        p = xy(e, n).split(",")
        out.append(
            f'<g class="pt {cls}"><circle cx="{p[0]}" cy="{p[1]}" r="6"/>'
            f'<text x="{float(p[0]) + 9:.1f}" y="{float(p[1]) + 4:.1f}">{escape(name)}</text></g>'
        )
    # scale bar (bottom left) and north arrow (top right)
    bar_m = _nice_length(0.3 * (WIDTH - 2 * PAD) / k)
    bar = k * bar_m
    label = f"{bar_m / 1000:g} km" if bar_m >= 1000 else f"{bar_m:g} m"
    out.append(
        f'<g class="scale"><rect x="{PAD - 8}" y="{HEIGHT - PAD - 14}" width="{bar + 16:.1f}" '
        'height="30" class="halo"/>'
        f'<path d="M{PAD},{HEIGHT - PAD} h{bar:.1f} M{PAD},{HEIGHT - PAD - 5} v10 '
        f'M{PAD + bar:.1f},{HEIGHT - PAD - 5} v10"/>'
        f'<text x="{PAD + bar / 2:.1f}" y="{HEIGHT - PAD + 13}">{label}</text></g>'
    )
    nx = WIDTH - PAD
    out.append(
        f'<g class="north" aria-label="north up"><path d="M{nx},{PAD - 10} l-8,22 l8,-6 l8,6 Z"/>'
        f'<text x="{nx}" y="{PAD + 26}">N</text></g>'
    )
    out.append("</svg>")
    legend = ["mission area"]
    if lines:
        legend.append(f"{len(lines)} survey line{'s' if len(lines) != 1 else ''}")
    legend += [f"{name}" for name in points]
    legend += [f"zone: {label}" for label in seen.values()]
    desc = (
        f'<figcaption id="map-d">Offline map, north up: {escape(", ".join(legend))}. '
        f"Scale bar {escape(label)}.</figcaption>"
    )
    keys = "".join(f'<li><i class="key {cls}"></i>{escape(lbl)}</li>' for cls, lbl in seen.items())
    return Markup("".join(out) + desc + (f'<ul class="map-keys">{keys}</ul>' if keys else ""))


__all__ = ["RESTRICTIONS", "MapLayers", "area_map"]
