"""uasnav's plan CSV: one row per waypoint.

Header (case-insensitive, any column order, ``#`` lines are comments, a UTF-8 byte-order mark
is accepted), one of:

``lat,lon[,alt]``
    WGS-84 degrees and altitude in m. Optional columns: ``frame`` (``relative`` — the default:
    above the home position, which is the first row's position —, ``amsl`` or ``terrain``),
    ``command`` (``waypoint`` — default —, ``takeoff``, ``land``, ``loiter``), ``hold_s`` (time
    held at the waypoint, s) and ``speed_ms`` (commanded speed from this waypoint on, m/s; empty
    for no change).
``north,east``
    Local metres in a tangent plane (a plan without a geodetic position:
    :attr:`MissionPlan.local_ne`).

The writer writes every column; it keeps positioned navigation items and speed changes and
refuses a plan with other commands (a camera trigger, a ``DO_JUMP``) rather than drop them.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Mapping

import numpy as np

from uasnav.atomicfile import atomic_write_text
from uasnav.errors import DataFormatError, InputError
from uasnav.io.mission_plan import (
    FRAME_CODES,
    MAV_CMD_DO_CHANGE_SPEED,
    MAV_CMD_NAV_LAND,
    MAV_CMD_NAV_LOITER_TIME,
    MAV_CMD_NAV_TAKEOFF,
    MAV_CMD_NAV_WAYPOINT,
    AltitudeFrame,
    ItemKind,
    MissionItem,
    MissionPlan,
    check_item,
)
from uasnav.io.plan_formats.source import read_plan_text

COMMANDS = {
    "waypoint": MAV_CMD_NAV_WAYPOINT,
    "takeoff": MAV_CMD_NAV_TAKEOFF,
    "land": MAV_CMD_NAV_LAND,
    "loiter": MAV_CMD_NAV_LOITER_TIME,
}
_NAMES = {v: k for k, v in COMMANDS.items()}
FRAMES = {"relative": AltitudeFrame.RELATIVE, "amsl": AltitudeFrame.AMSL, "terrain": AltitudeFrame.TERRAIN}
COLUMNS = ("lat", "lon", "alt", "frame", "command", "hold_s", "speed_ms")


def _number(cell: str, source: str, line: int, column: str, empty: float | None = None) -> float:
    if empty is not None and not cell.strip():
        return empty
    try:
        v = float(cell)
    except ValueError:
        raise DataFormatError("not a number", path=source, line=line, column=column) from None
    if not math.isfinite(v):
        raise DataFormatError(
            "NaN coordinate" if column in ("lat", "lon", "alt", "north", "east") else "not finite",
            path=source,
            line=line,
            column=column,
        )
    return v


def _choice(
    cell: str, choices: Mapping[str, object], source: str, line: int, column: str, default: str
) -> str:
    c = cell.strip().lower() or default
    if c not in choices:
        raise DataFormatError(
            f"unknown {column} {cell[:20]!r} (expected {', '.join(choices)})",
            path=source,
            line=line,
            column=column,
        )
    return c


def parse_plan_csv(text: str, source: str = "<plan>") -> MissionPlan:
    """A :class:`MissionPlan` from the text of a plan CSV (``source`` names it)."""
    reader = csv.reader(io.StringIO(text, newline=""))
    rows: list[tuple[int, list[str]]] = []
    try:
        for r in reader:
            if r and not r[0].lstrip().startswith("#"):
                rows.append((reader.line_num, r))
    except csv.Error as exc:
        raise DataFormatError(f"malformed CSV ({exc})", path=source, line=reader.line_num) from None
    if not rows:
        raise DataFormatError("empty plan", path=source)
    head_line, head_raw = rows[0]
    head = [h.strip().lower() for h in head_raw]
    if {"lat", "lon"} <= set(head):
        local = False
    elif {"north", "east"} <= set(head):
        local = True
    else:
        raise DataFormatError("header must name lat,lon[,alt] or north,east", path=source, line=head_line)
    col = {h: head.index(h) for h in head if h}

    def cell(r: list[str], name: str) -> str:
        k = col.get(name)
        if k is None:
            return ""
        if k >= len(r):
            raise DataFormatError(
                "not a number" if name in ("lat", "lon", "north", "east", "alt") else "missing",
                path=source,
                line=line,
                column=name,
            )
        return r[k]

    if not rows[1:]:
        raise DataFormatError("plan has no waypoints", path=source)
    if local:
        ne = np.empty((len(rows) - 1, 2))
        for i, (line, r) in enumerate(rows[1:]):
            ne[i] = [_number(cell(r, c), source, line, c) for c in ("north", "east")]
        items = tuple(
            MissionItem(command=MAV_CMD_NAV_WAYPOINT, frame=FRAME_CODES[AltitudeFrame.RELATIVE]) for _ in ne
        )
        return MissionPlan(items=items, local_ne=ne, source=source)
    out: list[MissionItem] = []
    for line, r in rows[1:]:
        lat = _number(cell(r, "lat"), source, line, "lat")
        lon = _number(cell(r, "lon"), source, line, "lon")
        alt = _number(cell(r, "alt"), source, line, "alt") if "alt" in col else 0.0
        frame = FRAMES[_choice(cell(r, "frame"), FRAMES, source, line, "frame", "relative")]
        command = COMMANDS[_choice(cell(r, "command"), COMMANDS, source, line, "command", "waypoint")]
        hold = _number(cell(r, "hold_s"), source, line, "hold_s", empty=0.0)
        speed = _number(cell(r, "speed_ms"), source, line, "speed_ms", empty=math.nan)
        if hold < 0:
            raise DataFormatError("negative hold time", path=source, line=line, column="hold_s")
        if not (math.isnan(speed) or speed > 0):
            raise DataFormatError(
                "speed must be > 0 m/s (empty for no change)", path=source, line=line, column="speed_ms"
            )
        if not math.isnan(speed):
            out.append(MissionItem(command=MAV_CMD_DO_CHANGE_SPEED, frame=2, params=(1.0, speed, -1.0, 0.0)))
        p1 = hold if command in (MAV_CMD_NAV_WAYPOINT, MAV_CMD_NAV_LOITER_TIME) else 0.0
        item = MissionItem(
            command=command,
            frame=FRAME_CODES[frame],
            params=(p1, 0.0, 0.0, 0.0),
            lat_deg=lat,
            lon_deg=lon,
            alt_m=alt,
        )
        try:
            check_item(item, "item")
        except InputError as e:
            raise DataFormatError(str(e).removeprefix("item: "), path=source, line=line) from None
        out.append(item)
    return MissionPlan(items=tuple(out), source=source)


def read_plan_csv(path: str | os.PathLike[str]) -> MissionPlan:
    """Read a plan CSV (see the module for the layout)."""
    p = os.fspath(path)
    return parse_plan_csv(read_plan_text(p), p)


def plan_csv_text(plan: MissionPlan) -> str:
    """The CSV text of ``plan``; :class:`InputError` for items the layout cannot hold."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    if plan.local_ne is not None:
        w.writerow(["north", "east"])
        for n, e in np.asarray(plan.local_ne, dtype=float):
            w.writerow([repr(float(n)), repr(float(e))])
        return buf.getvalue()
    w.writerow(COLUMNS)
    speed = ""
    frames = {v: k for k, v in FRAMES.items()}
    for i, it in enumerate(plan.items):
        if it.kind is ItemKind.SPEED and it.speed_ms is not None:
            speed = repr(it.speed_ms)
            continue
        if it.command not in _NAMES or not it.has_position:
            raise InputError(
                f"{plan.source}: item {i} (command {it.command}) cannot be written to a plan CSV, which "
                "holds positioned waypoint/takeoff/land/loiter items and speed changes only: "
                "write a .plan or .waypoints"
            )
        hold = it.hold_s if it.command in (MAV_CMD_NAV_WAYPOINT, MAV_CMD_NAV_LOITER_TIME) else 0.0
        alt = it.alt_m if math.isfinite(it.alt_m) else 0.0
        w.writerow(
            [
                repr(it.lat_deg),
                repr(it.lon_deg),
                repr(alt),
                frames[it.altitude_frame],
                _NAMES[it.command],
                repr(hold),
                speed,
            ]
        )
        speed = ""
    return buf.getvalue()


def write_plan_csv(plan: MissionPlan, path: str | os.PathLike[str]) -> None:
    """Write ``plan`` as a plan CSV, atomically."""
    atomic_write_text(path, plan_csv_text(plan))


__all__ = ["COLUMNS", "parse_plan_csv", "plan_csv_text", "read_plan_csv", "write_plan_csv"]
