"""KML plans: the waypoints of a ``LineString`` placemark, or a sequence of ``Point`` placemarks.

Read: the first placemark holding a ``LineString`` (or the one named ``name``); without one,
every ``Point`` placemark in document order. Coordinates are ``lon,lat[,alt]``. Altitude frame
from ``altitudeMode``: ``absolute`` → AMSL, ``relativeToGround`` → above terrain,
``clampToGround`` (KML's default) → on the terrain (altitude 0 above terrain: the file gives no
flight altitude, and says so by its mode). ``gx:`` modes are refused.

Parsing is hardened (lxml without DTDs, entities or network; a ``<!DOCTYPE`` is refused), sizes
are bounded, and errors name the file and the line.

Write: one ``LineString`` placemark with ``altitudeMode`` absolute (AMSL plans) or
relativeToGround (terrain plans); KML cannot say "relative to home", so such plans are refused.
"""

from __future__ import annotations

import math
import os
from typing import Any

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

NS = "http://www.opengis.net/kml/2.2"
MODES = {
    "absolute": AltitudeFrame.AMSL,
    "relativetoground": AltitudeFrame.TERRAIN,
    "clamptoground": AltitudeFrame.TERRAIN,
}


def _parse(text: str, source: str) -> Any:
    from lxml import etree

    if "<!DOCTYPE" in text:
        line = text[: text.index("<!DOCTYPE")].count("\n") + 1
        raise DataFormatError(
            "DTD (<!DOCTYPE …>) is not allowed (entity expansion / XXE guard)", path=source, line=line
        )
    parser = etree.XMLParser(
        resolve_entities=False, load_dtd=False, no_network=True, huge_tree=False, remove_pis=True
    )
    try:
        return etree.fromstring(text.encode("utf-8"), parser)
    except etree.XMLSyntaxError as e:
        raise DataFormatError(f"malformed XML: {e.msg}", path=source, line=e.lineno) from None


def _local(tag: object) -> str:
    return str(tag).rpartition("}")[2] if isinstance(tag, str) else ""


def _find(el: Any, name: str) -> list[Any]:
    return [e for e in el.iter() if _local(e.tag) == name]


def _coords(el: Any, source: str) -> list[tuple[float, float, float]]:
    out = []
    text = el.text or ""
    for tok in text.split():
        parts = tok.split(",")
        try:
            vals = [float(p) for p in parts]
        except ValueError:
            raise DataFormatError(
                f"coordinate {tok[:40]!r} is not lon,lat[,alt]", path=source, line=el.sourceline
            ) from None
        if len(vals) not in (2, 3) or not all(math.isfinite(v) for v in vals):
            raise DataFormatError(
                f"coordinate {tok[:40]!r} is not lon,lat[,alt]", path=source, line=el.sourceline
            )
        out.append((vals[0], vals[1], vals[2] if len(vals) == 3 else 0.0))
    return out


def _mode(geom: Any, source: str) -> AltitudeFrame:
    modes = [e for e in geom.iter() if _local(e.tag) == "altitudeMode"]
    if not modes:
        return AltitudeFrame.TERRAIN
    m = (modes[0].text or "").strip()
    if _local(modes[0].tag) == "altitudeMode" and modes[0].tag.startswith("{http://www.google.com/kml/ext"):
        raise DataFormatError(
            f"gx:altitudeMode {m!r} is not supported", path=source, line=modes[0].sourceline
        )
    if m.lower() not in MODES:
        raise DataFormatError(
            f"unknown altitudeMode {m!r} (absolute, relativeToGround, clampToGround)",
            path=source,
            line=modes[0].sourceline,
        )
    return MODES[m.lower()]


def parse_kml(text: str, source: str = "<plan>", name: str | None = None) -> MissionPlan:
    """A :class:`MissionPlan` from KML text (see module)."""
    root = _parse(text, source)
    marks = _find(root, "Placemark")
    pts: list[tuple[float, float, float]] = []
    frame = AltitudeFrame.TERRAIN
    clamp = False
    for pm in marks:
        nm = next((e.text for e in pm if _local(e.tag) == "name"), None)
        if name is not None and (nm or "").strip() != name:
            continue
        lines = _find(pm, "LineString")
        if lines:
            coords = _find(lines[0], "coordinates")
            if not coords:
                raise DataFormatError("LineString without coordinates", path=source, line=lines[0].sourceline)
            pts = _coords(coords[0], source)
            frame = _mode(lines[0], source)
            clamp = (
                not _find(lines[0], "altitudeMode")
                or (_find(lines[0], "altitudeMode")[0].text or "").strip().lower() == "clamptoground"
            )
            break
    if not pts:
        for pm in marks:
            for p in _find(pm, "Point"):
                c = _find(p, "coordinates")
                if c:
                    pts += _coords(c[0], source)
                    frame = _mode(p, source)
                    clamp = (
                        not _find(p, "altitudeMode")
                        or (_find(p, "altitudeMode")[0].text or "").strip().lower() == "clamptoground"
                    )
    if not pts:
        what = f"no placemark named {name!r}" if name is not None else "no LineString or Point placemark"
        raise DataFormatError(what, path=source)
    items = []
    for k, (lon, lat, alt) in enumerate(pts):
        it = MissionItem(
            MAV_CMD_NAV_WAYPOINT, FRAME_CODES[frame], lat_deg=lat, lon_deg=lon, alt_m=0.0 if clamp else alt
        )
        try:
            check_item(it, f"waypoint {k}")
        except InputError as e:
            raise DataFormatError(str(e), path=source) from None
        items.append(it)
    return MissionPlan(items=tuple(items), source=source)


def read_kml(path: str | os.PathLike[str], name: str | None = None) -> MissionPlan:
    """Read a KML plan (the first LineString, or the placemark named ``name``)."""
    p = os.fspath(path)
    return parse_kml(read_plan_text(p), p, name)


def kml_text(plan: MissionPlan) -> str:
    """KML of the plan's positioned navigation items as one LineString."""
    if plan.is_local:
        raise InputError(f"{plan.source}: a local north/east plan has no positions to write in KML")
    pos = [it for it in plan.items if it.has_position]
    frames = {it.altitude_frame for it in pos}
    if frames - {AltitudeFrame.AMSL, AltitudeFrame.TERRAIN} or len(frames) != 1:
        raise InputError(
            f"{plan.source}: KML holds one altitude frame, absolute (AMSL) or relativeToGround; "
            f"the plan's are {', '.join(sorted(f.value for f in frames))}: write a .plan or .waypoints"
        )
    mode = "absolute" if frames == {AltitudeFrame.AMSL} else "relativeToGround"
    coords = " ".join(
        f"{it.lon_deg!r},{it.lat_deg!r},{(it.alt_m if math.isfinite(it.alt_m) else 0.0)!r}" for it in pos
    )
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        f'<kml xmlns="{NS}"><Document><Placemark><name>plan</name><LineString>'
        f"<altitudeMode>{mode}</altitudeMode><coordinates>{coords}</coordinates>"
        "</LineString></Placemark></Document></kml>\n"
    )


def write_kml(plan: MissionPlan, path: str | os.PathLike[str]) -> None:
    """Write ``plan`` as KML, atomically."""
    atomic_write_text(path, kml_text(plan))


__all__ = ["kml_text", "parse_kml", "read_kml", "write_kml"]
