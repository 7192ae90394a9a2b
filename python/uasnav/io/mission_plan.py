"""The mission-plan model shared by every plan format: :class:`MissionPlan` of :class:`MissionItem`.

A plan is what a ground station uploads to an autopilot: a sequence of MAVLink mission items
(``MAV_CMD`` command, ``MAV_FRAME`` frame, four parameters and a position), plus the planned
home position and the ground station's default speeds. The model keeps every item, including
the ones that do not move the vehicle (camera triggers, ``DO_CHANGE_SPEED``, ``DO_JUMP``), so a
plan read from one format and written to the same one comes back item for item.

Altitude frames are explicit (:class:`AltitudeFrame`): relative to home, above mean sea level,
above terrain, or none for items without a position; the MAVLink frame number is kept too.
The formats (:mod:`uasnav.io.plan_formats`) only read and write; what the plan *means* for a
flight — the order items are flown in (``DO_JUMP`` expanded), the horizontal route, the
commanded speed — is computed here, once.

Positions: latitude and longitude in degrees (WGS-84), altitude in metres in the item's frame.
A MAVLink navigation command whose latitude and longitude are both exactly 0 means "here" (the
vehicle's current position; ArduPilot's take-off, land and RTL items are written so): such
items have no horizontal position (:attr:`MissionItem.has_position` is false). A plan given as
local north/east metres (the CSV ``north,east`` layout) has no geodetic positions at all: its
route is :attr:`MissionPlan.local_ne`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from uasnav.errors import DataFormatError, InputError


class AltitudeFrame(str, Enum):
    """What an item's altitude is measured from."""

    #: Above the home (take-off) position, m (``MAV_FRAME_GLOBAL_RELATIVE_ALT``).
    RELATIVE = "relative"
    #: Above mean sea level, m (``MAV_FRAME_GLOBAL``: MAVLink's "global" altitude is AMSL).
    AMSL = "amsl"
    #: Above the terrain below the vehicle, m (``MAV_FRAME_GLOBAL_TERRAIN_ALT``).
    TERRAIN = "terrain"
    #: The item has no position (``MAV_FRAME_MISSION``: a command such as a camera trigger).
    NONE = "none"


class ItemKind(str, Enum):
    """What a mission item does to the flight."""

    WAYPOINT = "waypoint"
    TAKEOFF = "takeoff"
    LAND = "land"
    LOITER = "loiter"
    RETURN = "return"  # return to launch: fly to the home position
    SPEED = "speed"  # DO_CHANGE_SPEED
    JUMP = "jump"  # DO_JUMP
    OTHER = "other"  # any other command (camera, servo, …): kept, not flown


#: MAVLink ``MAV_FRAME`` → altitude frame. 0/5 GLOBAL(_INT), 3/6 GLOBAL_RELATIVE_ALT(_INT),
#: 10/11 GLOBAL_TERRAIN_ALT(_INT), 2 MISSION.
MAV_FRAMES: dict[int, AltitudeFrame] = {
    0: AltitudeFrame.AMSL,
    5: AltitudeFrame.AMSL,
    3: AltitudeFrame.RELATIVE,
    6: AltitudeFrame.RELATIVE,
    10: AltitudeFrame.TERRAIN,
    11: AltitudeFrame.TERRAIN,
    2: AltitudeFrame.NONE,
}
#: The MAVLink frame written for an altitude frame when an item has none of its own.
FRAME_CODES: dict[AltitudeFrame, int] = {
    AltitudeFrame.AMSL: 0,
    AltitudeFrame.RELATIVE: 3,
    AltitudeFrame.TERRAIN: 10,
    AltitudeFrame.NONE: 2,
}

MAV_CMD_NAV_WAYPOINT = 16
MAV_CMD_NAV_LOITER_UNLIM = 17
MAV_CMD_NAV_LOITER_TURNS = 18
MAV_CMD_NAV_LOITER_TIME = 19
MAV_CMD_NAV_RETURN_TO_LAUNCH = 20
MAV_CMD_NAV_LAND = 21
MAV_CMD_NAV_TAKEOFF = 22
MAV_CMD_NAV_LOITER_TO_ALT = 31
MAV_CMD_NAV_SPLINE_WAYPOINT = 82
MAV_CMD_NAV_VTOL_TAKEOFF = 84
MAV_CMD_NAV_VTOL_LAND = 85
MAV_CMD_DO_JUMP = 177
MAV_CMD_DO_CHANGE_SPEED = 178

#: MAV_CMD → kind, for the commands whose meaning the model knows.
COMMAND_KINDS: dict[int, ItemKind] = {
    MAV_CMD_NAV_WAYPOINT: ItemKind.WAYPOINT,
    MAV_CMD_NAV_SPLINE_WAYPOINT: ItemKind.WAYPOINT,
    MAV_CMD_NAV_LOITER_UNLIM: ItemKind.LOITER,
    MAV_CMD_NAV_LOITER_TURNS: ItemKind.LOITER,
    MAV_CMD_NAV_LOITER_TIME: ItemKind.LOITER,
    MAV_CMD_NAV_LOITER_TO_ALT: ItemKind.LOITER,
    MAV_CMD_NAV_RETURN_TO_LAUNCH: ItemKind.RETURN,
    MAV_CMD_NAV_LAND: ItemKind.LAND,
    MAV_CMD_NAV_VTOL_LAND: ItemKind.LAND,
    MAV_CMD_NAV_TAKEOFF: ItemKind.TAKEOFF,
    MAV_CMD_NAV_VTOL_TAKEOFF: ItemKind.TAKEOFF,
    MAV_CMD_DO_JUMP: ItemKind.JUMP,
    MAV_CMD_DO_CHANGE_SPEED: ItemKind.SPEED,
}
#: Kinds that move the vehicle to the item's position (when it has one).
NAV_KINDS = frozenset({ItemKind.WAYPOINT, ItemKind.TAKEOFF, ItemKind.LAND, ItemKind.LOITER})

#: Highest plausible item altitude, m, in any frame (the Everest is 8 849 m AMSL; small UAS fly
#: below a few hundred metres): beyond it the altitude is an error (feet, mm, a corrupt file).
MAX_ALTITUDE_M = 20_000.0
#: Lowest plausible altitude, m (the Dead Sea shore is −430 m AMSL).
MIN_ALTITUDE_M = -1_000.0
#: Most items a plan may hold (ArduPilot stores at most a few thousand; a survey grid a few
#: hundred): bounds memory and the expansion of ``DO_JUMP`` loops.
MAX_ITEMS = 100_000
#: Longest flown sequence after ``DO_JUMP`` expansion.
MAX_SEQUENCE = 1_000_000


@dataclass(frozen=True)
class MissionItem:
    """One MAVLink mission item.

    Attributes
    ----------
    command : int
        ``MAV_CMD`` number (16 waypoint, 22 take-off, 21 land, 19 loiter time, 178 change
        speed …).
    frame : int
        ``MAV_FRAME`` number (3 relative to home, 0 AMSL, 10 above terrain, 2 none).
    params : tuple of 4 float
        ``param1`` … ``param4`` (NaN where the file gives none, e.g. QGC's ``null``).
    lat_deg, lon_deg : float
        WGS-84 position, degrees; NaN for an item without a position (and for local plans).
    alt_m : float
        Altitude in :attr:`altitude_frame`, m (NaN when the item has none).
    autocontinue : bool
        Continue to the next item when this one completes.
    jump_id : int or None
        The number a ``DO_JUMP`` names this item by (the sequence number of a ``.waypoints``
        file, QGC's ``doJumpId``).
    """

    command: int
    frame: int
    params: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    lat_deg: float = math.nan
    lon_deg: float = math.nan
    alt_m: float = math.nan
    autocontinue: bool = True
    jump_id: int | None = None

    def __post_init__(self) -> None:
        # numbers as floats whatever the caller passed (ints, numpy scalars): the writers and
        # the properties rely on float methods; anything that is not a number is refused here
        try:
            params = tuple(float(x) for x in self.params)
            lat, lon, alt = float(self.lat_deg), float(self.lon_deg), float(self.alt_m)
        except (TypeError, ValueError):
            raise InputError(
                f"mission item (command {self.command}): params and lat/lon/alt must be numbers"
            ) from None
        if len(params) != 4:
            raise InputError(f"mission item (command {self.command}): expected 4 params, got {len(params)}")
        object.__setattr__(self, "params", params)
        object.__setattr__(self, "lat_deg", lat)
        object.__setattr__(self, "lon_deg", lon)
        object.__setattr__(self, "alt_m", alt)

    @property
    def kind(self) -> ItemKind:
        """What the item does (:class:`ItemKind`); unknown commands are ``OTHER``."""
        return COMMAND_KINDS.get(self.command, ItemKind.OTHER)

    @property
    def altitude_frame(self) -> AltitudeFrame:
        """The altitude frame of :attr:`alt_m` (raises :class:`InputError` for a frame that is
        not a global one, which the readers already refuse)."""
        try:
            return MAV_FRAMES[self.frame]
        except KeyError:
            raise InputError(f"MAV_FRAME {self.frame} is not a global altitude frame") from None

    @property
    def has_position(self) -> bool:
        """The item names a horizontal position (finite, not the 0°, 0° meaning "here")."""
        return (
            math.isfinite(self.lat_deg)
            and math.isfinite(self.lon_deg)
            and not (self.lat_deg == 0.0 and self.lon_deg == 0.0)
        )

    @property
    def hold_s(self) -> float:
        """Time the vehicle stays at the item, s: ``param1`` of a waypoint (hold time) or of a
        timed loiter; ``inf`` for an unlimited loiter; NaN for a loiter of N turns (its time
        depends on radius and speed); 0 otherwise."""
        if self.command in (MAV_CMD_NAV_WAYPOINT, MAV_CMD_NAV_LOITER_TIME, MAV_CMD_NAV_SPLINE_WAYPOINT):
            p = self.params[0]
            return float(p) if math.isfinite(p) and p > 0 else 0.0
        if self.command == MAV_CMD_NAV_LOITER_UNLIM:
            return math.inf
        if self.command == MAV_CMD_NAV_LOITER_TURNS:
            return math.nan
        return 0.0

    @property
    def speed_ms(self) -> float | None:
        """New commanded ground/air speed of a ``DO_CHANGE_SPEED`` item, m/s (``param2``); None
        for other items and for "no change" (−1, 0 or NaN)."""
        if self.command != MAV_CMD_DO_CHANGE_SPEED:
            return None
        v = self.params[1]
        return float(v) if math.isfinite(v) and v > 0 else None


@dataclass(frozen=True)
class HomePosition:
    """The planned home (take-off) position: WGS-84 degrees, altitude AMSL in m (NaN if the
    plan does not say)."""

    lat_deg: float
    lon_deg: float
    alt_amsl_m: float = math.nan


@dataclass(frozen=True)
class MissionPlan:
    """A mission plan: items in upload order, home position and default speeds.

    Attributes
    ----------
    items : tuple of MissionItem
    home : HomePosition or None
        Planned home position (QGC ``plannedHomePosition``, item 0 of an ArduPilot
        ``.waypoints`` file), None if the file has none.
    cruise_speed_ms, hover_speed_ms : float or None
        Ground station default speeds (QGC ``cruiseSpeed``/``hoverSpeed``), m/s.
    local_ne : ndarray, shape (n, 2), or None
        For a plan given in local metres (CSV ``north,east``): the waypoints, north/east m.
    source : str
        Where the plan was read from (file name), for messages.
    vehicle_type : int or None
        MAVLink ``MAV_TYPE`` the plan was made for (QGC ``vehicleType``: 1 fixed wing,
        2 quadrotor …), None if the file does not say.
    """

    items: tuple[MissionItem, ...]
    home: HomePosition | None = None
    cruise_speed_ms: float | None = None
    hover_speed_ms: float | None = None
    local_ne: np.ndarray | None = field(default=None, compare=False)
    source: str = "<plan>"
    vehicle_type: int | None = None

    def __post_init__(self) -> None:
        if len(self.items) > MAX_ITEMS:
            raise InputError(f"{self.source}: {len(self.items)} mission items, more than {MAX_ITEMS}")
        for name in ("cruise_speed_ms", "hover_speed_ms"):
            v = getattr(self, name)
            if v is not None and not (math.isfinite(v) and v > 0):
                raise InputError(f"{self.source}: {name} must be a positive speed, got {v!r}")
        for i, it in enumerate(self.items):
            check_item(it, f"{self.source}: item {i}")

    def __len__(self) -> int:
        return len(self.items)

    @property
    def is_local(self) -> bool:
        """The plan is given in local north/east metres (no geodetic positions)."""
        return self.local_ne is not None

    @property
    def altitude_frames(self) -> set[AltitudeFrame]:
        """The altitude frames of the positioned items."""
        return {it.altitude_frame for it in self.items if it.has_position or math.isfinite(it.alt_m)} - {
            AltitudeFrame.NONE
        }


def check_item(it: MissionItem, where: str) -> None:
    """Refuse an item no autopilot flies: an unknown frame on a positioned item, a latitude
    beyond ±90°, a longitude beyond ±180°, an altitude outside [−1 km, 20 km]."""
    if it.frame not in MAV_FRAMES:
        raise InputError(
            f"{where}: unknown or unsupported MAV_FRAME {it.frame} (supported: 0/5 AMSL, "
            "3/6 relative to home, 10/11 above terrain, 2 no position)"
        )
    for name, v in (("lat_deg", it.lat_deg), ("lon_deg", it.lon_deg), ("alt_m", it.alt_m)):
        if math.isinf(v):
            raise InputError(f"{where}: infinite {name}")
    if not math.isnan(it.lat_deg) and abs(it.lat_deg) > 90.0:
        raise InputError(f"{where}: latitude {it.lat_deg!r}° outside ±90°")
    if not math.isnan(it.lon_deg) and abs(it.lon_deg) > 180.0:
        raise InputError(f"{where}: longitude {it.lon_deg!r}° outside ±180°")
    if not math.isnan(it.alt_m) and not (MIN_ALTITUDE_M <= it.alt_m <= MAX_ALTITUDE_M):
        raise InputError(
            f"{where}: impossible altitude {it.alt_m!r} m "
            f"(expected {MIN_ALTITUDE_M:g} … {MAX_ALTITUDE_M:g} m)"
        )
    if it.kind in NAV_KINDS and it.has_position and it.frame == 2:
        raise InputError(f"{where}: navigation command {it.command} with a position but no altitude frame")


def flight_sequence(plan: MissionPlan) -> list[int]:
    """Indices of :attr:`MissionPlan.items` in the order the autopilot executes them.

    ``DO_JUMP`` (``param1`` the target's :attr:`MissionItem.jump_id`, ``param2`` the repeat
    count) is expanded as ArduPilot and PX4 do: each jump item sends the mission back to its
    target as many times as it says, then is passed. Raises :class:`InputError` for a jump to
    an unknown item, an endless jump (repeat −1) or an expansion beyond
    :data:`MAX_SEQUENCE` items.
    """
    ids = {it.jump_id: i for i, it in enumerate(plan.items) if it.jump_id is not None}
    left: dict[int, int] = {}
    out: list[int] = []
    i = 0
    while i < len(plan.items):
        it = plan.items[i]
        if it.kind is ItemKind.JUMP:
            target, repeat = it.params[0], it.params[1]
            if not (math.isfinite(target) and int(target) in ids):
                raise InputError(f"{plan.source}: item {i}: DO_JUMP to unknown item {target!r}")
            if not math.isfinite(repeat) or repeat < 0:
                raise InputError(f"{plan.source}: item {i}: DO_JUMP repeats forever: the flight has no end")
            left.setdefault(i, int(repeat))
            if left[i] > 0:
                left[i] -= 1
                i = ids[int(target)]
                continue
            i += 1
            continue
        out.append(i)
        if len(out) > MAX_SEQUENCE:
            raise InputError(f"{plan.source}: DO_JUMP loops expand to more than {MAX_SEQUENCE} items")
        i += 1
    return out


def route_items(plan: MissionPlan) -> list[int]:
    """Indices (flown order, see :func:`flight_sequence`) of the items the route passes through:
    positioned take-off, waypoint, loiter and land items, and return-to-launch (home)."""
    return [
        i
        for i in flight_sequence(plan)
        if (plan.items[i].kind in NAV_KINDS and plan.items[i].has_position)
        or (plan.items[i].kind is ItemKind.RETURN and plan.home is not None)
    ]


def plan_route(plan: MissionPlan) -> tuple[np.ndarray, tuple[float, float, float] | None]:
    """The plan as the horizontal route that :meth:`TrajectoryPredictor.predict
    <uasnav.trajectory.predictor.TrajectoryPredictor.predict>` takes.

    Returns
    -------
    route_ne : ndarray, shape (n, 2)
        Waypoints in flown order (``DO_JUMP`` expanded), north/east metres in the local
        tangent plane at the first waypoint; consecutive waypoints at the same place (a
        take-off straight up, a land where the last waypoint was) are merged.
    origin : (lat_deg, lon_deg, alt_m) or None
        The tangent point (the first waypoint, its altitude in its own frame), None for a
        local plan.

    Raises
    ------
    InputError
        Fewer than two distinct horizontal positions (a plan the predictor cannot fly).
    """
    if plan.local_ne is not None:
        ne = np.asarray(plan.local_ne, dtype=float)
        if ne.shape[0] < 2:
            raise InputError(
                f"{plan.source}: a route needs at least two waypoints, the plan has {ne.shape[0]}"
            )
        return ne.copy(), None
    lat, lon, alt = [], [], []
    for i in route_items(plan):
        it = plan.items[i]
        if it.kind is ItemKind.RETURN:
            assert plan.home is not None
            la, lo, al = plan.home.lat_deg, plan.home.lon_deg, 0.0
        else:
            la, lo, al = it.lat_deg, it.lon_deg, (it.alt_m if math.isfinite(it.alt_m) else 0.0)
        lat.append(la)
        lon.append(lo)
        alt.append(al)
    if not lat:
        raise InputError(f"{plan.source}: the plan has no positioned waypoint")
    from uasnav.geo import frames

    origin = (lat[0], lon[0], alt[0])
    n, e, _ = frames.geodetic_to_ned(np.array(lat), np.array(lon), np.array(alt), *origin)
    ne = np.column_stack([n, e])
    keep = np.concatenate([[True], np.hypot(*np.diff(ne, axis=0).T) > 0.01])
    ne = ne[keep]
    if ne.shape[0] < 2:
        raise InputError(
            f"{plan.source}: the plan has {ne.shape[0]} distinct waypoint position(s): "
            "a route needs at least two waypoints"
        )
    return ne, origin


def plan_cruise_speed(plan: MissionPlan) -> float | None:
    """The speed the plan commands for its first leg, m/s: the first ``DO_CHANGE_SPEED`` before
    the first waypoint after take-off, else the ground station's cruise (fixed wing) or hover
    (multirotor) speed, else None (the autopilot's parameter, e.g. ``WPNAV_SPEED``, decides)."""
    for i in flight_sequence(plan):
        it = plan.items[i]
        if it.speed_ms is not None:
            return it.speed_ms
        if it.kind is ItemKind.WAYPOINT:
            break
    if plan.vehicle_type == 1:  # MAV_TYPE_FIXED_WING flies the cruise speed
        return plan.cruise_speed_ms or plan.hover_speed_ms
    return plan.hover_speed_ms or plan.cruise_speed_ms


def require_items(items: list[MissionItem], source: str) -> None:
    """A format reader's final check: at least one item."""
    if not items:
        raise DataFormatError("plan has no mission items", path=source)


__all__ = [
    "COMMAND_KINDS",
    "FRAME_CODES",
    "MAV_FRAMES",
    "MAX_ALTITUDE_M",
    "MAX_ITEMS",
    "AltitudeFrame",
    "HomePosition",
    "ItemKind",
    "MissionItem",
    "MissionPlan",
    "check_item",
    "flight_sequence",
    "plan_cruise_speed",
    "plan_route",
    "route_items",
]


@dataclass(frozen=True)
class RoutePoint:
    """A point of the 3D route a plan flies (:func:`route_points`).

    Attributes
    ----------
    lat_deg, lon_deg : float — WGS-84 position, degrees.
    alt_m : float — altitude in ``frame``, m.
    frame : AltitudeFrame
    hold_s : float — time spent at the point before going on, s (NaN: unknown, a loiter of
        N turns; inf: an unlimited loiter).
    speed_ms : float or None — the speed a ``DO_CHANGE_SPEED`` just before this point's item
        set, m/s: the leg *into* this point flies it (autopilots run a DO command alongside the
        next navigation command), and so do the following legs until the next change.
    kind : ItemKind — the item that made the point (``TAKEOFF`` for the ground point before a
        take-off, ``LAND`` for the touch-down).
    item : int or None — index of that item in :attr:`MissionPlan.items` (None for points the
        route adds: the ground before take-off, the touch-down below a land or RTL point).
    """

    lat_deg: float
    lon_deg: float
    alt_m: float
    frame: AltitudeFrame
    hold_s: float = 0.0
    speed_ms: float | None = None
    kind: ItemKind = ItemKind.WAYPOINT
    item: int | None = None


def route_points(plan: MissionPlan) -> list[RoutePoint]:
    """The 3D route of a geodetic plan in flown order (``DO_JUMP`` expanded).

    * A take-off climbs from the ground (0 m relative to home) at the home position — or at
      its own position if it has one — to its altitude.
    * Waypoints and loiters are flown to; their hold/loiter time is :attr:`RoutePoint.hold_s`.
    * A land item flies to its position (if any) at the current altitude, then descends to the
      ground (0 m relative to home); return-to-launch flies to home at the current altitude
      and lands there.
    * A ``DO_CHANGE_SPEED`` sets :attr:`RoutePoint.speed_ms` of the next point.

    Raises :class:`InputError` for a local plan, a plan without positioned items, or a take-off
    or return whose position is unknown (no home position and no item position).
    """
    if plan.is_local:
        raise InputError(f"{plan.source}: a local north/east plan has no geodetic route")
    rel = AltitudeFrame.RELATIVE
    out: list[RoutePoint] = []
    speed: float | None = None
    home = plan.home

    def last() -> RoutePoint:
        if not out:
            raise InputError(f"{plan.source}: the route starts with an item that has no position")
        return out[-1]

    for i in flight_sequence(plan):
        it = plan.items[i]
        if it.speed_ms is not None:
            speed = it.speed_ms
            continue
        k = it.kind
        if k is ItemKind.TAKEOFF:
            if it.has_position:
                la, lo = it.lat_deg, it.lon_deg
            elif home is not None:
                la, lo = home.lat_deg, home.lon_deg
            elif out:
                la, lo = out[-1].lat_deg, out[-1].lon_deg
            else:
                raise InputError(f"{plan.source}: item {i}: take-off without a position and no home position")
            if not out:
                out.append(RoutePoint(la, lo, 0.0, rel, kind=ItemKind.TAKEOFF))
            out.append(RoutePoint(la, lo, it.alt_m, it.altitude_frame, speed_ms=speed, kind=k, item=i))
            speed = None
        elif k in (ItemKind.WAYPOINT, ItemKind.LOITER) and it.has_position:
            out.append(
                RoutePoint(it.lat_deg, it.lon_deg, it.alt_m, it.altitude_frame, it.hold_s, speed, k, i)
            )
            speed = None
        elif k is ItemKind.LAND:
            p = last()
            la, lo = (it.lat_deg, it.lon_deg) if it.has_position else (p.lat_deg, p.lon_deg)
            if it.has_position:
                out.append(
                    RoutePoint(la, lo, p.alt_m, p.frame, speed_ms=speed, kind=ItemKind.WAYPOINT, item=i)
                )
                speed = None
            out.append(RoutePoint(la, lo, 0.0, rel, kind=ItemKind.LAND, item=i))
        elif k is ItemKind.RETURN:
            if home is None:
                raise InputError(
                    f"{plan.source}: item {i}: return to launch but the plan has no home position"
                )
            p = last()
            out.append(
                RoutePoint(home.lat_deg, home.lon_deg, p.alt_m, p.frame, speed_ms=speed, kind=k, item=i)
            )
            out.append(RoutePoint(home.lat_deg, home.lon_deg, 0.0, rel, kind=ItemKind.LAND))
            speed = None
    if len(out) < 2:
        raise InputError(f"{plan.source}: the plan has no route (fewer than two positioned points)")
    return out


__all__ += ["RoutePoint", "route_points"]
