"""Mission Planner / QGroundControl ``.waypoints`` text files (``QGC WPL 110``).

Layout: a first line ``QGC WPL 110``, then one item per line, 12 fields separated by tabs (or
spaces): ``seq current frame command p1 p2 p3 p4 x y z autocontinue`` — x, y latitude and
longitude (deg), z altitude (m, in the frame ``frame``). Blank lines are skipped.

Home: ArduPilot keeps the home position as item 0, and Mission Planner and QGroundControl write
it as the line with sequence number 0 when that line is a ``NAV_WAYPOINT`` (command 16). That
line becomes :attr:`MissionPlan.home` (its altitude is AMSL), not a mission item; a file whose
line 0 is another command (a PX4 mission starting with a take-off) has no home.

The sequence number of each line is kept as the item's :attr:`~MissionItem.jump_id` (a
``DO_JUMP`` names its target by it). The writer numbers items from 1 after a home line (from 0
without one) and renumbers ``DO_JUMP`` targets to match.

Errors name the file, the line and the field.
"""

from __future__ import annotations

import math
import os

from uasnav.atomicfile import atomic_write_text
from uasnav.errors import DataFormatError, InputError
from uasnav.io.mission_plan import (
    MAV_CMD_DO_JUMP,
    MAV_CMD_NAV_WAYPOINT,
    MAX_ITEMS,
    HomePosition,
    MissionItem,
    MissionPlan,
    check_item,
    require_items,
)
from uasnav.io.plan_formats.source import read_plan_text

HEADER = "QGC WPL 110"
FIELDS = (
    "seq",
    "current",
    "frame",
    "command",
    "param1",
    "param2",
    "param3",
    "param4",
    "lat",
    "lon",
    "alt",
    "autocontinue",
)


def _int(cell: str, source: str, line: int, column: str, lo: int, hi: int) -> int:
    try:
        v = int(cell)
    except ValueError:
        try:  # some tools write integers as 16.000000
            f = float(cell)
        except ValueError:
            f = math.nan
        if not (math.isfinite(f) and f.is_integer()):
            raise DataFormatError(
                f"expected an integer, got {cell[:40]!r}", path=source, line=line, column=column
            ) from None
        v = int(f)
    if not lo <= v <= hi:
        raise DataFormatError(f"{v} outside [{lo}, {hi}]", path=source, line=line, column=column)
    return v


def _float(cell: str, source: str, line: int, column: str) -> float:
    try:
        v = float(cell)
    except ValueError:
        raise DataFormatError(f"not a number: {cell[:40]!r}", path=source, line=line, column=column) from None
    if math.isinf(v):
        raise DataFormatError("infinite value", path=source, line=line, column=column)
    return v


def parse_wpl(text: str, source: str = "<plan>") -> MissionPlan:
    """A :class:`MissionPlan` from the text of a ``.waypoints`` file (``source`` names it)."""
    lines = text.splitlines()
    if not lines or lines[0].strip() != HEADER:
        first = lines[0].strip()[:40] if lines else ""
        raise DataFormatError(
            f"not a QGC WPL 110 file: first line {first!r}, expected {HEADER!r}", path=source, line=1
        )
    items: list[MissionItem] = []
    home: HomePosition | None = None
    last_seq = -1
    for n, raw in enumerate(lines[1:], start=2):
        if not raw.strip():
            continue
        cells = raw.split()
        if len(cells) != len(FIELDS):
            raise DataFormatError(
                f"expected {len(FIELDS)} fields ({' '.join(FIELDS)}), got {len(cells)}", path=source, line=n
            )
        seq = _int(cells[0], source, n, "seq", 0, 10**9)
        if seq <= last_seq:
            raise DataFormatError(
                f"sequence number {seq} does not follow {last_seq}", path=source, line=n, column="seq"
            )
        last_seq = seq
        frame = _int(cells[2], source, n, "frame", 0, 255)
        command = _int(cells[3], source, n, "command", 0, 65535)
        p = [_float(cells[k], source, n, FIELDS[k]) for k in range(4, 11)]
        auto = _int(cells[11], source, n, "autocontinue", 0, 1)
        if seq == 0 and command == MAV_CMD_NAV_WAYPOINT:
            if not (abs(p[4]) <= 90 and abs(p[5]) <= 180):
                raise DataFormatError("home position outside ±90°/±180°", path=source, line=n, column="lat")
            home = HomePosition(p[4], p[5], p[6])
            continue
        item = MissionItem(
            command=command,
            frame=frame,
            params=(p[0], p[1], p[2], p[3]),
            lat_deg=p[4],
            lon_deg=p[5],
            alt_m=p[6],
            autocontinue=bool(auto),
            jump_id=seq,
        )
        try:
            check_item(item, "item")
        except InputError as e:
            raise DataFormatError(str(e).removeprefix("item: "), path=source, line=n) from None
        items.append(item)
        if len(items) > MAX_ITEMS:
            raise DataFormatError(f"more than {MAX_ITEMS} mission items", path=source, line=n)
    require_items(items, source)
    return MissionPlan(items=tuple(items), home=home, source=source)


def read_wpl(path: str | os.PathLike[str]) -> MissionPlan:
    """Read a ``.waypoints`` (``QGC WPL 110``) file."""
    p = os.fspath(path)
    return parse_wpl(read_plan_text(p), p)


def _num(v: float) -> str:
    return "nan" if math.isnan(v) else repr(float(v))


def wpl_text(plan: MissionPlan) -> str:
    """The ``QGC WPL 110`` text of ``plan``."""
    if plan.is_local:
        raise InputError(
            f"{plan.source}: a local north/east plan has no positions to write in a .waypoints file"
        )
    first = 1 if plan.home is not None else 0
    new_seq = {it.jump_id: first + k for k, it in enumerate(plan.items) if it.jump_id is not None}
    out = [HEADER]
    if plan.home is not None:
        h = plan.home
        alt = 0.0 if math.isnan(h.alt_amsl_m) else h.alt_amsl_m
        out.append(
            "\t".join(
                ["0", "1", "0", "16", "0", "0", "0", "0", _num(h.lat_deg), _num(h.lon_deg), _num(alt), "1"]
            )
        )
    for k, it in enumerate(plan.items):
        params = list(it.params)
        if it.command == MAV_CMD_DO_JUMP and math.isfinite(params[0]) and int(params[0]) in new_seq:
            params[0] = float(new_seq[int(params[0])])
        cells = [str(first + k), "0", str(it.frame), str(it.command), *map(_num, params)]
        cells += [
            _num(it.lat_deg if math.isfinite(it.lat_deg) else 0.0),
            _num(it.lon_deg if math.isfinite(it.lon_deg) else 0.0),
        ]
        cells += [_num(it.alt_m if math.isfinite(it.alt_m) else 0.0), "1" if it.autocontinue else "0"]
        out.append("\t".join(cells))
    return "\n".join(out) + "\n"


def write_wpl(plan: MissionPlan, path: str | os.PathLike[str]) -> None:
    """Write ``plan`` as a ``.waypoints`` (``QGC WPL 110``) file, atomically."""
    atomic_write_text(path, wpl_text(plan))


__all__ = ["FIELDS", "HEADER", "parse_wpl", "read_wpl", "wpl_text", "write_wpl"]
