"""Mission plans embedded in flight logs.

- MAVLink telemetry (``.tlog``): the ``MISSION_ITEM_INT`` / ``MISSION_ITEM`` messages of the
  mission transfers the log recorded (x, y in 1e-7 degrees for the ``_INT`` form). A log may
  hold several transfers, often of item 0 (the home position) alone: the last message of each
  sequence number wins, and sequence numbers must be contiguous. (A log in which a shorter
  mission replaced a longer one would keep the longer one's tail: ``MISSION_COUNT`` is not
  read.)
- ArduPilot DataFlash (``.bin``): the ``CMD`` messages (``CNum``, ``CId``, ``Prm1…4``, ``Lat``,
  ``Lng``, ``Alt`` and, in newer logs, ``Frame``; without it ArduPilot stores altitudes
  relative to home, except item 0, the home position, which is absolute).

As in ``.waypoints`` files, item 0 with command 16 is ArduPilot's home position (AMSL). PX4
ULogs: :mod:`uasnav.io.plan_formats.ulog`.
"""

from __future__ import annotations

import os
from pathlib import Path

from uasnav.errors import DataFormatError, InputError
from uasnav.io._mavlink import messages, reading
from uasnav.io.mission_plan import MAV_CMD_NAV_WAYPOINT, HomePosition, MissionItem, MissionPlan, check_item


def _plan(rows: dict[int, tuple], source: str, what: str) -> MissionPlan:
    """Items from {seq: (frame, command, p1, p2, p3, p4, lat, lon, alt, autocontinue)}."""
    if not rows:
        raise DataFormatError(f"no {what} messages: the log holds no mission", path=source)
    seqs = sorted(rows)
    if seqs != list(range(seqs[0], seqs[0] + len(seqs))):
        missing = sorted(set(range(seqs[0], seqs[-1] + 1)) - set(seqs))
        raise DataFormatError(f"mission items {missing[:5]} missing from the log", path=source)
    home = None
    items = []
    for s in seqs:
        frame, cmd, p1, p2, p3, p4, lat, lon, alt, auto = rows[s]
        if s == 0 and cmd == MAV_CMD_NAV_WAYPOINT:
            home = HomePosition(lat, lon, alt)
            continue
        it = MissionItem(int(cmd), int(frame), (p1, p2, p3, p4), lat, lon, alt, bool(auto), s)
        try:
            check_item(it, f"{what} {s}")
        except InputError as e:
            raise DataFormatError(str(e), path=source) from None
        items.append(it)
    if not items:
        raise DataFormatError(f"the log's mission has only a home position ({what} 0)", path=source)
    return MissionPlan(items=tuple(items), home=home, source=source)


def read_tlog_plan(path: str | os.PathLike[str]) -> MissionPlan:
    """The mission of a MAVLink telemetry log (see module)."""
    p = Path(path)
    rows: dict[int, tuple] = {}
    with reading(p, dialect="ardupilotmega") as (conn, _):
        for m in messages(conn, ("MISSION_ITEM_INT", "MISSION_ITEM"), p, "MAVLink"):
            scale = 1e-7 if m.get_type() == "MISSION_ITEM_INT" else 1.0
            rows[int(m.seq)] = (
                m.frame, m.command, m.param1, m.param2, m.param3, m.param4,
                m.x * scale, m.y * scale, m.z, m.autocontinue,
            )  # fmt: skip
    return _plan(rows, str(p), "MISSION_ITEM")


def read_dataflash_plan(path: str | os.PathLike[str]) -> MissionPlan:
    """The mission of an ArduPilot DataFlash log (``CMD`` messages, see module)."""
    p = Path(path)
    rows: dict[int, tuple] = {}
    with reading(p) as (conn, _):
        for m in messages(conn, ("CMD",), p, "DataFlash"):
            d = m.to_dict()
            seq = int(d.get("CNum", 0))
            frame = int(d["Frame"]) if "Frame" in d else (0 if seq == 0 else 3)
            rows[seq] = (
                frame, int(d.get("CId", 0)), d.get("Prm1", 0.0), d.get("Prm2", 0.0), d.get("Prm3", 0.0),
                d.get("Prm4", 0.0), d.get("Lat", 0.0), d.get("Lng", 0.0), d.get("Alt", 0.0), 1,
            )  # fmt: skip
    return _plan(rows, str(p), "CMD")


__all__ = ["read_dataflash_plan", "read_tlog_plan"]
