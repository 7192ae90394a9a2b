"""GeoJSON plans: a ``LineString`` (the first one found) or a sequence of ``Point`` features.

Positions are ``[lon, lat]`` or ``[lon, lat, alt]``. RFC 7946 makes a third coordinate a height
above the WGS-84 *ellipsoid*, which a MAVLink plan never carries; a plan file therefore states
its altitude frame in the foreign member ``"altitude_frame"`` (``"relative"`` to home,
``"amsl"`` or ``"terrain"``) of the collection, the feature or its properties. A file with
altitudes and no ``altitude_frame`` is refused rather than guessed; 2-D positions are on the
terrain (0 m above it). Errors name the file and the JSON path.
"""

from __future__ import annotations

import json
import math
import os
from typing import Any

from uasnav import jsoncheck as jc
from uasnav.atomicfile import atomic_write_text
from uasnav.errors import DataFormatError, InputError
from uasnav.io.mission_plan import (
    FRAME_CODES,
    MAV_CMD_NAV_WAYPOINT,
    AltitudeFrame,
    MissionItem,
    MissionPlan,
    check_item,
)
from uasnav.io.plan_formats.source import read_plan_text

FRAMES = {"relative": AltitudeFrame.RELATIVE, "amsl": AltitudeFrame.AMSL, "terrain": AltitudeFrame.TERRAIN}


def _frame(*objs: Any) -> str | None:
    for o in objs:
        if isinstance(o, dict):
            props = o.get("properties")
            for d in (o, props if isinstance(props, dict) else {}):
                if "altitude_frame" in d:
                    return d["altitude_frame"]
    return None


def _positions(coords: object, path: str, point: bool) -> list[list[float]]:
    pts = [coords] if point else jc.array(coords, path)
    out = []
    for k, p in enumerate(pts):
        pp = path if point else jc.at(path, k)
        if not (isinstance(p, list) and len(p) in (2, 3)):
            raise jc.fail(pp, f"expected [lon, lat] or [lon, lat, alt], got {jc.show(p)}")
        out.append([jc.number(v, jc.at(pp, i)) for i, v in enumerate(p)])
    return out


def parse_geojson(text: str, source: str = "<plan>") -> MissionPlan:
    """A :class:`MissionPlan` from GeoJSON text (see module)."""
    with jc.reraise_in(source):
        d = jc.obj(jc.parse(text, "not GeoJSON: not valid JSON"), "")
        kind = d.get("type")
        feats: list[tuple[Any, str]]
        if kind == "FeatureCollection":
            feats = [
                (f, f"features[{i}]") for i, f in enumerate(jc.array(jc.field(d, "features"), "features"))
            ]
        elif kind == "Feature":
            feats = [(d, "")]
        elif kind in ("LineString", "Point"):
            feats = [({"type": "Feature", "geometry": d}, "")]
        else:
            raise jc.fail(
                "type", f"expected a FeatureCollection, Feature, LineString or Point, got {jc.show(kind)}"
            )
        pts: list[list[float]] = []
        frame_name = None
        for f, fp in feats:
            g = jc.obj(
                jc.obj(f, fp or "feature").get("geometry"), jc.at(fp, "geometry") if fp else "geometry"
            )
            gpath = jc.at(fp, "geometry") if fp else "geometry"
            if g.get("type") == "LineString":
                pts = _positions(jc.field(g, "coordinates", gpath), jc.at(gpath, "coordinates"), point=False)
                frame_name = _frame(f, d)
                break
            if g.get("type") == "Point":
                pts += _positions(jc.field(g, "coordinates", gpath), jc.at(gpath, "coordinates"), point=True)
                frame_name = frame_name or _frame(f, d)
        if not pts:
            raise DataFormatError("no LineString or Point feature", path=source)
        has_alt = any(len(p) == 3 for p in pts)
        if has_alt and frame_name is None:
            raise DataFormatError(
                'positions have altitudes but no "altitude_frame" (relative, amsl or terrain): RFC 7946 '
                "altitudes are ellipsoidal, which a plan does not use; say which frame they are in",
                path=source,
            )
        if frame_name is not None and frame_name not in FRAMES:
            raise DataFormatError(
                f"altitude_frame {jc.show(frame_name)} is not one of relative, amsl, terrain", path=source
            )
        frame = FRAMES[frame_name] if (has_alt and frame_name is not None) else AltitudeFrame.TERRAIN
        items = []
        for k, p in enumerate(pts):
            it = MissionItem(
                MAV_CMD_NAV_WAYPOINT,
                FRAME_CODES[frame],
                lat_deg=p[1],
                lon_deg=p[0],
                alt_m=p[2] if len(p) == 3 else 0.0,
            )
            try:
                check_item(it, f"position {k}")
            except InputError as e:
                raise DataFormatError(str(e)) from None
            items.append(it)
        return MissionPlan(items=tuple(items), source=source)


def read_geojson(path: str | os.PathLike[str]) -> MissionPlan:
    """Read a GeoJSON plan."""
    p = os.fspath(path)
    return parse_geojson(read_plan_text(p), p)


def geojson_text(plan: MissionPlan) -> str:
    """A FeatureCollection with the plan's positioned navigation items as one LineString."""
    if plan.is_local:
        raise InputError(f"{plan.source}: a local north/east plan has no positions to write in GeoJSON")
    pos = [it for it in plan.items if it.has_position]
    frames = {it.altitude_frame for it in pos}
    if len(frames) != 1:
        raise InputError(
            f"{plan.source}: GeoJSON holds one altitude frame, the plan has {len(frames)}: write a .plan"
        )
    name = next(k for k, v in FRAMES.items() if v in frames)
    coords = [[it.lon_deg, it.lat_deg, it.alt_m if math.isfinite(it.alt_m) else 0.0] for it in pos]
    feat = {
        "type": "Feature",
        "properties": {"altitude_frame": name},
        "geometry": {"type": "LineString", "coordinates": coords},
    }
    return (
        json.dumps({"type": "FeatureCollection", "altitude_frame": name, "features": [feat]}, indent=1) + "\n"
    )


def write_geojson(plan: MissionPlan, path: str | os.PathLike[str]) -> None:
    """Write ``plan`` as GeoJSON, atomically."""
    atomic_write_text(path, geojson_text(plan))


__all__ = ["geojson_text", "parse_geojson", "read_geojson", "write_geojson"]
