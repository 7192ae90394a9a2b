"""The mission plan embedded in a PX4 ULog (read with pyulog).

PX4 keeps the mission itself in its dataman (on the SD card), not in the log. What a log can
carry:

- ``navigator_mission_item`` (PX4 ≥ 1.13): each mission item as the navigator makes it the
  current one — ``sequence_current``, ``nav_cmd`` (MAVLink command), ``latitude``/``longitude``
  (deg; PX4 logs them as float32, a resolution of about 1e-5° ≈ 0.4 m at mid latitudes, so
  the positions read back are that coarse), ``altitude`` (m; relative to home if
  ``altitude_is_relative``, else AMSL; a log without that field is read by its ``frame``
  (MAV_FRAME: 0/5 global = AMSL, 3/6 global-relative, 10/11 above terrain), and one with
  neither is refused — the frame is never assumed),
  ``time_inside`` (hold/loiter time, s → param 1), ``acceptance_radius`` (m → param 2),
  ``loiter_radius`` (m → param 3), ``yaw`` (rad → param 4 in degrees), ``autocontinue``. The
  last record of each sequence number wins. It is the mission *as flown*: items the vehicle
  never reached are not in it, and ``DO_*`` items (e.g. ``DO_CHANGE_SPEED``) keep their
  command but not their parameters (the topic has no fields for them).
- ``home_position`` (``lat``, ``lon``, ``alt`` AMSL): the plan's home position.
- ``mission`` (``count``, ``current_seq``, ``dataman_id``) and ``mission_result``
  (``seq_total``): how many items the mission had, used to say what is missing.

A log without ``navigator_mission_item`` records is refused with what it does hold (an empty
mission, or a mission of N items the log does not carry).
"""

from __future__ import annotations

import math

import numpy as np

from uasnav.errors import DataFormatError, InputError
from uasnav.io.mission_plan import (
    MAV_FRAMES,
    AltitudeFrame,
    HomePosition,
    MissionItem,
    MissionPlan,
    check_item,
)

#: MAV_FRAME_GLOBAL (AMSL) and MAV_FRAME_GLOBAL_RELATIVE_ALT (relative to home).
_FRAME_AMSL, _FRAME_RELATIVE, _FRAME_NONE = 0, 3, 2
_MAV_CMD_NAV_LAST = 95
#: The topics the plan is read from.
TOPICS = ("navigator_mission_item", "home_position", "mission", "mission_result")


def _topic(ulog: object, name: str) -> dict[str, np.ndarray] | None:
    for d in getattr(ulog, "data_list", []):
        if d.name == name and d.multi_id == 0:
            return d.data  # type: ignore[no-any-return]
    return None


def _need(data: dict[str, np.ndarray], fields: tuple[str, ...], topic: str, source: str) -> None:
    missing = [f for f in fields if f not in data]
    if missing:
        raise DataFormatError(f"ULog topic {topic} lacks field(s) {', '.join(missing)}", path=source)


def _altitude_frame(nav: dict[str, np.ndarray], r: int, seq: int, source: str) -> int:
    """The MAV_FRAME of record ``r``: ``altitude_is_relative`` (what PX4's navigator flies by),
    else the ``frame`` field when it is a global frame; refused when neither says it."""
    if "altitude_is_relative" in nav:
        return _FRAME_RELATIVE if bool(nav["altitude_is_relative"][r]) else _FRAME_AMSL
    if "frame" not in nav:
        raise DataFormatError(
            "ULog topic navigator_mission_item lacks both altitude_is_relative and frame: the "
            "altitude frame (relative to home or AMSL) of its items is unknown",
            path=source,
        )
    f = int(nav["frame"][r])
    if MAV_FRAMES.get(f, AltitudeFrame.NONE) == AltitudeFrame.NONE:
        raise DataFormatError(
            f"navigator_mission_item {seq}: frame {f} is not a global altitude frame (MAV_FRAME "
            "0/5 AMSL, 3/6 relative to home, 10/11 above terrain) and the topic has no "
            "altitude_is_relative",
            path=source,
        )
    return f


def ulog_plan(ulog: object, source: str) -> MissionPlan:
    """The mission of a PX4 ULog parsed by pyulog (at least the :data:`TOPICS`; see module);
    ``source`` names the file in errors.

    Raises
    ------
    DataFormatError
        No mission items in the log (naming what the log says of its mission), an item with an
        invalid command, position or altitude.
    """
    nav = _topic(ulog, "navigator_mission_item")
    if nav is None or nav["timestamp"].size == 0:
        mission = _topic(ulog, "mission")
        result = _topic(ulog, "mission_result")
        if mission is not None and "count" in mission and mission["count"].size:
            n = int(mission["count"][-1])
            what = (
                "an empty mission (mission.count = 0)"
                if n == 0
                else f"a mission of {n} items (mission.count) but not the items themselves"
            )
        elif result is not None and "seq_total" in result and result["seq_total"].size:
            what = f"a mission of {int(result['seq_total'][-1])} items (mission_result) but not the items"
        else:
            what = "no mission topic"
        raise DataFormatError(
            f"no navigator_mission_item records: the log holds {what} (PX4 keeps missions in its "
            "dataman; logs from PX4 ≥ 1.13 carry the items the navigator flew)",
            path=source,
        )
    fields = ("sequence_current", "nav_cmd", "latitude", "longitude", "altitude")
    _need(nav, fields, "navigator_mission_item", source)
    last: dict[int, int] = {}
    for r, seq in enumerate(nav["sequence_current"]):
        last[int(seq)] = r  # the last record of each sequence number wins

    def get(name: str, r: int, default: float = 0.0) -> float:
        return float(nav[name][r]) if name in nav else default

    items = []
    for seq in sorted(last):
        r = last[seq]
        yaw = get("yaw", r, math.nan)
        cmd = int(nav["nav_cmd"][r])
        # MAVLink NAV commands are numbered below 95 (MAV_CMD_NAV_LAST); the others (DO_*,
        # CONDITION_*) have no position, and this topic does not carry their parameters
        nav_item = cmd < _MAV_CMD_NAV_LAST
        frame = _altitude_frame(nav, r, seq, source) if nav_item else _FRAME_NONE
        pos = (get("latitude", r), get("longitude", r), get("altitude", r)) if nav_item else (math.nan,) * 3
        it = MissionItem(
            command=cmd,
            frame=frame,
            params=(
                get("time_inside", r),
                get("acceptance_radius", r),
                get("loiter_radius", r),
                math.degrees(yaw) if math.isfinite(yaw) else math.nan,
            ),
            lat_deg=pos[0],
            lon_deg=pos[1],
            alt_m=pos[2],
            autocontinue=bool(nav["autocontinue"][r]) if "autocontinue" in nav else True,
            jump_id=seq,
        )
        try:
            check_item(it, f"navigator_mission_item {seq}")
        except InputError as e:
            raise DataFormatError(str(e), path=source) from None
        items.append(it)
    home = None
    hp = _topic(ulog, "home_position")
    if hp is not None and all(k in hp for k in ("lat", "lon", "alt")) and hp["lat"].size:
        lat, lon, alt = (float(hp[k][-1]) for k in ("lat", "lon", "alt"))
        if all(map(math.isfinite, (lat, lon, alt))) and abs(lat) <= 90 and abs(lon) <= 180:
            home = HomePosition(lat, lon, alt)
    return MissionPlan(items=tuple(items), home=home, source=source)


__all__ = ["TOPICS", "ulog_plan"]
