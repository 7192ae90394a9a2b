"""QGroundControl ``.plan`` files (JSON, ``"fileType": "Plan"``, mission version 2).

Read: ``mission.items`` — ``SimpleItem`` s (``command``, ``frame``, ``params`` [p1 … p4, lat, lon,
alt] with ``null`` for "not set", ``autoContinue``, ``doJumpId``) and complex items whose flight
path QGroundControl saved with them (``survey``, ``CorridorScan``: the simple items under
``TransectStyleComplexItem.Items``, inlined in order); ``mission.plannedHomePosition``
[lat, lon, alt AMSL]; ``cruiseSpeed``, ``hoverSpeed``, ``vehicleType``. Geofence and rally points
are not part of the flight and are ignored. A ``StructureScan`` holds only its polygon and
layers (QGroundControl computes its path when it uploads): it is refused, with the advice to
save the plan as simple items.

Write: the same layout with every item a ``SimpleItem`` (complex items were inlined), so
QGroundControl opens it and a round trip keeps every item, parameter and position.

Errors name the file and the JSON path (``mission.items[3].params[4]``).
"""

from __future__ import annotations

import json
import math
import os
from typing import Any

from uasnav import jsoncheck as jc
from uasnav.atomicfile import atomic_write_text
from uasnav.errors import DataFormatError, InputError
from uasnav.io.mission_plan import HomePosition, MissionItem, MissionPlan, check_item, require_items
from uasnav.io.plan_formats.source import read_plan_text

_TRANSECT_TYPES = ("survey", "CorridorScan")


def _param(x: object, path: str) -> float:
    """A parameter: a number, or ``null`` (→ NaN: "not set")."""
    if x is None:
        return math.nan
    return jc.number(x, path)


def _item(d: object, path: str, out: list[MissionItem]) -> None:
    d = jc.obj(d, path)
    kind = jc.string(jc.field(d, "type", path), jc.at(path, "type"))
    if kind == "ComplexItem":
        ctype = jc.string(jc.field(d, "complexItemType", path), jc.at(path, "complexItemType"))
        if ctype in _TRANSECT_TYPES:
            ts = jc.obj(
                jc.field(d, "TransectStyleComplexItem", path), jc.at(path, "TransectStyleComplexItem")
            )
            ipath = jc.at(jc.at(path, "TransectStyleComplexItem"), "Items")
            for k, sub in enumerate(
                jc.array(jc.field(ts, "Items", jc.at(path, "TransectStyleComplexItem")), ipath)
            ):
                _item(sub, jc.at(ipath, k), out)
            return
        raise jc.fail(
            path,
            f"complex item {jc.show(ctype)} carries no flight path in the file (QGroundControl "
            "computes it on upload): save the mission with its items expanded (.waypoints) and read that",
        )
    if kind != "SimpleItem":
        raise jc.fail(jc.at(path, "type"), f'expected "SimpleItem" or "ComplexItem", got {jc.show(kind)}')
    command = jc.integer(jc.field(d, "command", path), jc.at(path, "command"), lo=0, hi=65535)
    frame = jc.integer(jc.field(d, "frame", path), jc.at(path, "frame"), lo=0, hi=255)
    ppath = jc.at(path, "params")
    params = jc.field(d, "params", path)
    if not (isinstance(params, list) and len(params) == 7):
        raise jc.fail(ppath, f"expected an array of 7 parameters, got {jc.show(params)}")
    p = [_param(v, jc.at(ppath, i)) for i, v in enumerate(params)]
    auto = d.get("autoContinue", True)
    if not isinstance(auto, bool):
        raise jc.fail(jc.at(path, "autoContinue"), f"expected true or false, got {jc.show(auto)}")
    jid = d.get("doJumpId")
    jump_id = None if jid is None else jc.integer(jid, jc.at(path, "doJumpId"), lo=0)
    item = MissionItem(
        command=command,
        frame=frame,
        params=(p[0], p[1], p[2], p[3]),
        lat_deg=p[4],
        lon_deg=p[5],
        alt_m=p[6],
        autocontinue=auto,
        jump_id=jump_id,
    )
    try:
        check_item(item, path)
    except InputError as e:
        raise DataFormatError(str(e)) from None
    out.append(item)


def _speed(m: dict[str, Any], key: str) -> float | None:
    v = m.get(key)
    if v is None:
        return None
    return jc.number(v, jc.at("mission", key), positive=True, hi=1000.0, unit="m/s")


def parse_qgc_plan(text: str, source: str = "<plan>") -> MissionPlan:
    """A :class:`MissionPlan` from the JSON text of a ``.plan`` file (``source`` names it)."""
    with jc.reraise_in(source):
        d = jc.obj(jc.parse(text, "not a QGroundControl plan: not valid JSON"), "")
        ft = d.get("fileType")
        if ft != "Plan":
            raise jc.fail("fileType", f'expected "Plan" (a QGroundControl plan), got {jc.show(ft)}')
        m = jc.obj(jc.field(d, "mission"), "mission")
        version = m.get("version", 2)
        if version != 2:
            raise jc.fail("mission.version", f"unsupported mission version {jc.show(version)} (expected 2)")
        items: list[MissionItem] = []
        raw = m.get("items", [])
        if not isinstance(raw, list):
            raise jc.fail("mission.items", "expected an array")
        for i, it in enumerate(raw):
            _item(it, jc.at("mission.items", i), items)
        require_items(items, source)
        home = None
        hp = m.get("plannedHomePosition")
        if hp is not None:
            if not (isinstance(hp, list) and len(hp) == 3):
                raise jc.fail("mission.plannedHomePosition", f"expected [lat, lon, alt], got {jc.show(hp)}")
            lat = jc.number(hp[0], "mission.plannedHomePosition[0]", lo=-90, hi=90, unit="°")
            lon = jc.number(hp[1], "mission.plannedHomePosition[1]", lo=-180, hi=180, unit="°")
            alt = _param(hp[2], "mission.plannedHomePosition[2]")
            home = HomePosition(lat, lon, alt)
        vt = m.get("vehicleType")
        vehicle = None if vt is None else jc.integer(vt, "mission.vehicleType", lo=0, hi=255)
        try:
            return MissionPlan(
                items=tuple(items),
                home=home,
                cruise_speed_ms=_speed(m, "cruiseSpeed"),
                hover_speed_ms=_speed(m, "hoverSpeed"),
                source=source,
                vehicle_type=vehicle,
            )
        except InputError as e:
            raise DataFormatError(str(e)) from None


def read_qgc_plan(path: str | os.PathLike[str]) -> MissionPlan:
    """Read a QGroundControl ``.plan`` file (at most :data:`MAX_PLAN_BYTES`)."""
    p = os.fspath(path)
    return parse_qgc_plan(read_plan_text(p), p)


def _json_num(x: float) -> float | int | None:
    if math.isnan(x):
        return None
    return int(x) if x.is_integer() and abs(x) < 2**53 else x


def qgc_plan_dict(plan: MissionPlan) -> dict[str, Any]:
    """The ``.plan`` JSON object of ``plan`` (every item a ``SimpleItem``)."""
    if plan.is_local:
        raise InputError(f"{plan.source}: a local north/east plan has no positions to write in a .plan file")
    items = []
    for k, it in enumerate(plan.items):
        items.append(
            {
                "autoContinue": it.autocontinue,
                "command": it.command,
                "doJumpId": it.jump_id if it.jump_id is not None else k + 1,
                "frame": it.frame,
                "params": [_json_num(v) for v in (*it.params, it.lat_deg, it.lon_deg, it.alt_m)],
                "type": "SimpleItem",
            }
        )
    # Speeds and vehicle type are written only when the plan has them: a default written here
    # would read back as a speed the plan commands.
    mission: dict[str, Any] = {"firmwareType": 0, "globalPlanAltitudeMode": 1, "items": items, "version": 2}
    if plan.cruise_speed_ms is not None:
        mission["cruiseSpeed"] = plan.cruise_speed_ms
    if plan.hover_speed_ms is not None:
        mission["hoverSpeed"] = plan.hover_speed_ms
    if plan.vehicle_type is not None:
        mission["vehicleType"] = plan.vehicle_type
    if plan.home is not None:
        h = plan.home
        mission["plannedHomePosition"] = [h.lat_deg, h.lon_deg, _json_num(h.alt_amsl_m)]
    return {
        "fileType": "Plan",
        "geoFence": {"circles": [], "polygons": [], "version": 2},
        "groundStation": "uasnav",
        "mission": mission,
        "rallyPoints": {"points": [], "version": 2},
        "version": 1,
    }


def write_qgc_plan(plan: MissionPlan, path: str | os.PathLike[str]) -> None:
    """Write ``plan`` as a QGroundControl ``.plan`` file, atomically."""
    atomic_write_text(path, json.dumps(qgc_plan_dict(plan), indent=4, allow_nan=False) + "\n")


__all__ = ["parse_qgc_plan", "qgc_plan_dict", "read_qgc_plan", "write_qgc_plan"]
