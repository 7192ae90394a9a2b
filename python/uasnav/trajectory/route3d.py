"""3D routes and their elements: horizontal legs, turns, climbs, descents and hovers.

A :class:`Route3D` is what a mission plan flies (take-off climb, waypoints with hold times and
speed changes, landing descent; :func:`uasnav.io.mission_plan.route_points`) in a local
north/east frame with altitudes. :func:`predict_route` times it element by element:

* **leg / turn** — the horizontal stretches between stops (the start, the end, a hold, a
  vertical move) are predicted by the trajectory predictor (kinematic point mass by default, or
  the thesis' LVQ), element by element; corner elements are ``turn``, the others ``leg``.
  After a ``DO_CHANGE_SPEED`` the kinematic model flies each leg at its own speed
  (accelerating and braking included; corner speeds from the slower of the two legs, as the
  simulator and ArduPilot's waypoint controller do), so a straight leg of length L from rest to
  rest at V takes L/V + V/a. The LVQ network has no speed input besides the one commanded
  speed it predicts a stretch at, so for it a leg's element times are scaled by (prediction
  speed ÷ leg speed) — an approximation that also scales the acceleration and braking phases,
  whose true time grows with V instead (for a point mass at a = 1 m/s², scaling the 5 m/s time
  of a 200 m leg gives 22.5 s at 10 m/s against the true 30 s, 112.5 s at 2 m/s against 102 s).
  A sloped leg (climbing or descending while it moves) cannot be flown faster than
  its vertical limit allows — ArduPilot's waypoint controller caps the speed along a 3D leg
  so that its vertical part stays within ``WPNAV_SPEED_UP/DN`` — so its time is at least the
  vertical time of its height change.
* **climb / descent** — a vertical move at a point (take-off, landing, a change of altitude
  over the same place): a trapezoidal speed profile with the vertical speed limit v and
  acceleration limit a, t = |Δz|/v + v/a (or 2·√(|Δz|/a) when |Δz| < v²/a, the limit never
  reached).
* **hover** — a hold (``NAV_WAYPOINT`` hold time, ``LOITER_TIME``): its time exactly.

Each element carries its kind, horizontal length, height change and climb rate Δz/t (the
feature a vertical move adds), and the predictor's flags (which widen the time bounds).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from uasnav.errors import InputError
from uasnav.trajectory.timebounds import FLAG_WIDENING

if TYPE_CHECKING:
    from uasnav.io.mission_plan import MissionPlan

#: Element kinds of a 3D route.
ELEMENT_KINDS = ("leg", "turn", "climb", "descent", "hover")
#: Horizontal distance (m) below which two route points are one place (a vertical move).
SAME_PLACE_M = 0.01
#: Height change (m) below which a move at one place is no vertical move.
SAME_HEIGHT_M = 0.01


#: Longest hold at a waypoint (s): ArduPilot stores a waypoint's hold time (``param1``) as
#: 16-bit seconds (``AP_Mission`` ``p1``); a longer one is a typing error, and a hold of 10¹² s
#: would carry the intent's times past the year 9999.
MAX_HOLD_S = 65535


@dataclass(frozen=True)
class Route3D:
    """A 3D route in a local frame.

    Attributes
    ----------
    ne : ndarray, shape (n, 2) — points, north/east m.
    alt_m : ndarray, shape (n,) — altitudes, m up (one vertical frame for all points).
    hold_s : ndarray, shape (n,) — time held at each point after reaching it, s (0 = none).
    speed_ms : ndarray, shape (n,) — commanded horizontal speed of the leg *into* each point,
        m/s (NaN = the default cruise speed).
    """

    ne: np.ndarray
    alt_m: np.ndarray
    hold_s: np.ndarray
    speed_ms: np.ndarray

    def __post_init__(self) -> None:
        ne = np.asarray(self.ne, dtype=float)
        n = ne.shape[0] if ne.ndim == 2 else 0
        if ne.ndim != 2 or ne.shape[1] != 2 or n < 2:
            raise InputError(f"a route needs at least 2 points of (north, east), got shape {ne.shape}")
        arrays = {"alt_m": self.alt_m, "hold_s": self.hold_s, "speed_ms": self.speed_ms}
        for name, x in arrays.items():
            a = np.asarray(x, dtype=float)
            if a.shape != (n,):
                raise InputError(f"route {name} needs shape ({n},), got {a.shape}")
            object.__setattr__(self, name, a)
        object.__setattr__(self, "ne", ne)
        if not (np.isfinite(ne).all() and np.isfinite(self.alt_m).all()):
            raise InputError("route positions and altitudes must be finite")
        if not (np.isfinite(self.hold_s).all() and (self.hold_s >= 0).all()):
            raise InputError("route hold times must be finite and ≥ 0 s")
        if (long := np.flatnonzero(self.hold_s > MAX_HOLD_S)).size:
            raise InputError(
                f"route point {long[0]}: a hold of {self.hold_s[long[0]]:g} s is beyond the {MAX_HOLD_S} s "
                "an autopilot stores (ArduPilot: 16-bit seconds)"
            )
        v = self.speed_ms[np.isfinite(self.speed_ms)]
        if (v <= 0).any() or np.isinf(self.speed_ms).any():
            raise InputError("route leg speeds must be > 0 m/s (NaN = cruise)")

    @classmethod
    def flat(cls, ne: np.ndarray, alt_m: float = 0.0) -> Route3D:
        """A horizontal route at one altitude, no holds, the cruise speed."""
        p = np.asarray(ne, dtype=float)
        n = p.shape[0] if p.ndim == 2 else 0
        return cls(p, np.full(n, float(alt_m)), np.zeros(n), np.full(n, np.nan))

    def __len__(self) -> int:
        return int(self.ne.shape[0])

    @property
    def horizontal_m(self) -> np.ndarray:
        """Horizontal length of each segment, shape (n − 1,), m."""
        return np.hypot(*np.diff(self.ne, axis=0).T)

    @property
    def dz_m(self) -> np.ndarray:
        """Height change of each segment, shape (n − 1,), m."""
        return np.diff(self.alt_m)


def check_holds(plan: MissionPlan) -> list[Any]:
    """The plan's route points (:func:`uasnav.io.mission_plan.route_points`), refusing holds
    without a predictable end (an unlimited loiter, a loiter of N turns) or longer than
    :data:`MAX_HOLD_S`: cheap, so commands call it before any long work on the plan.

    Raises
    ------
    InputError
        Naming the plan and the item.
    """
    from uasnav.io.mission_plan import route_points

    pts = route_points(plan)
    for p in pts:
        if not math.isfinite(p.hold_s):
            what = "an unlimited loiter" if p.hold_s == math.inf else "a loiter of N turns (time unknown)"
            raise InputError(f"{plan.source}: item {p.item}: {what} has no predictable end")
        if p.hold_s > MAX_HOLD_S:
            raise InputError(
                f"{plan.source}: item {p.item}: a hold of {p.hold_s:g} s is beyond the {MAX_HOLD_S} s "
                "an autopilot stores (ArduPilot: 16-bit seconds)"
            )
    return pts


def route_from_plan(plan: MissionPlan, home_amsl_m: float | None = None) -> Route3D:
    """The 3D route of a geodetic mission plan (:func:`uasnav.io.mission_plan.route_points`:
    take-off from the ground, waypoints with holds, ``DO_CHANGE_SPEED``, landing) in the local
    north/east frame of its first point; altitudes in metres above mean sea level when the plan
    mixes relative and AMSL items (``home_amsl_m``, else the plan's home), else in the plan's
    one frame (only differences matter for the timing).

    Raises :class:`InputError` for altitudes above terrain (no terrain model), mixed frames
    without a home altitude, and unbounded holds (an unlimited loiter, a loiter of N turns).
    """
    from uasnav.io.mission_plan import AltitudeFrame, ItemKind
    from uasnav.trajectory.geometry import geodetic_to_local

    pts = check_holds(plan)
    frames = {p.frame for p in pts}
    if AltitudeFrame.TERRAIN in frames:
        raise InputError(f"{plan.source}: altitudes above terrain need a terrain model to be timed")
    alt = np.array([p.alt_m for p in pts], dtype=float)
    if len(frames) > 1:
        home = home_amsl_m if home_amsl_m is not None else (plan.home.alt_amsl_m if plan.home else None)
        if home is None:
            # the ground points the route adds (before a take-off, the touch-down of a land or
            # return) are 0 m relative to home: with AMSL items their height is unknown, and
            # taking it from the first item would time a take-off climb of 0 m
            own = {
                p.frame for p in pts if p.item is not None and p.kind not in (ItemKind.TAKEOFF, ItemKind.LAND)
            }
            added = [
                p
                for p in pts
                if p.frame == AltitudeFrame.RELATIVE and p.kind in (ItemKind.TAKEOFF, ItemKind.LAND)
            ]
            if own == {AltitudeFrame.AMSL} and added:
                raise InputError(
                    f"{plan.source}: the plan's altitudes are AMSL but its take-off/landing on the "
                    "ground is relative to home, and the plan has no home altitude (give it: "
                    "--home-alt, m AMSL)"
                )
            raise InputError(
                f"{plan.source}: relative and AMSL altitudes mixed and no home altitude (give it: "
                "--home-alt, m AMSL)"
            )
        alt = np.array(
            [a + home if p.frame == AltitudeFrame.RELATIVE else a for a, p in zip(alt, pts, strict=True)]
        )
    lat = np.array([p.lat_deg for p in pts])
    lon = np.array([p.lon_deg for p in pts])
    ne = geodetic_to_local(lat, lon, np.zeros(lat.size))[:, :2]
    speeds, v = [], math.nan
    for i, p in enumerate(pts):  # a speed change holds until the next one
        v = p.speed_ms if p.speed_ms is not None and i > 0 else v
        speeds.append(v)
    return Route3D(ne, alt, np.array([p.hold_s for p in pts]), np.array(speeds))


def vertical_time(dz_m: np.ndarray | float, speed_ms: float, accel_ms2: float) -> np.ndarray:
    """Time (s) of a vertical move of |Δz| from rest to rest: trapezoidal speed profile with
    limits ``speed_ms`` and ``accel_ms2`` (triangular when the limit is not reached)."""
    d = np.abs(np.asarray(dz_m, dtype=float))
    v, a = float(speed_ms), float(accel_ms2)
    if not (v > 0 and a > 0 and math.isfinite(v) and math.isfinite(a)):
        raise InputError(f"vertical speed and acceleration limits must be > 0, got {v}, {a}")
    if not np.isfinite(d).all():
        raise InputError("vertical move: the height changes must be finite")
    with np.errstate(over="ignore"):
        t = np.where(d >= v * v / a, d / v + v / a, 2.0 * np.sqrt(d / a))
    if not np.isfinite(t).all():  # e.g. 1e308 m at 1e-300 m/s
        raise InputError(f"vertical move: {float(np.max(d)):g} m at {v:g} m/s: a time beyond the float range")
    return t


@dataclass(frozen=True)
class RouteElements:
    """The elements of a 3D route, in flight order (arrays of length m).

    Attributes
    ----------
    kind : ndarray of str — one of :data:`ELEMENT_KINDS`.
    segment : ndarray of int — route segment (point i → i + 1) of the element; for a hover,
        the point held at.
    length_m : ndarray — horizontal length, m (0 for climbs, descents, hovers).
    dz_m : ndarray — height change, m.
    time_s : ndarray — predicted time, s.
    climb_rate_ms : ndarray — Δz / t, m/s (0 for a hover).
    stretch_s_end_m : ndarray — for a leg or turn, the arc length (m) from the start of its
        horizontal stretch (the points between two stops) to the element's end; NaN otherwise.
    flagged : ndarray of bool — the predictor flagged the element (outside its training data).
    flags : list of list of str — the predictor's reasons.
    """

    kind: np.ndarray
    segment: np.ndarray
    length_m: np.ndarray
    dz_m: np.ndarray
    time_s: np.ndarray
    climb_rate_ms: np.ndarray
    stretch_s_end_m: np.ndarray
    flagged: np.ndarray
    flags: list[list[str]]

    def __len__(self) -> int:
        return int(self.time_s.size)

    def rows(self) -> list[dict]:
        """One plain dict per element (kind, segment, lengths, time, climb rate, flags)."""
        return [
            {
                "element": i,
                "kind": str(self.kind[i]),
                "segment": int(self.segment[i]),
                "length_m": float(self.length_m[i]),
                "dz_m": float(self.dz_m[i]),
                "time_s": float(self.time_s[i]),
                "climb_rate_ms": float(self.climb_rate_ms[i]),
                "flags": list(self.flags[i]),
            }
            for i in range(len(self))
        ]


@dataclass(frozen=True)
class RoutePrediction:
    """Predicted timing of a 3D route.

    Attributes
    ----------
    elements : RouteElements
    t_arrive_s, t_depart_s : ndarray, shape (n,) — arrival at each route point and departure
        after its hold, s from the start.
    w_arrive_s, w_depart_s : ndarray, shape (n,) — the time bounds' widening there, s (the
        flagged elements' time before the point, :func:`uasnav.trajectory.timebounds.widening`).
    eta_s : float — departure from the last point, s.
    """

    elements: RouteElements
    t_arrive_s: np.ndarray
    t_depart_s: np.ndarray
    w_arrive_s: np.ndarray
    w_depart_s: np.ndarray
    eta_s: float


def _scaled(t: np.ndarray, t_wp: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Times ``t`` of a stretch whose waypoints are reached at ``t_wp`` with the time spent in
    each leg g multiplied by ``f[g]``."""
    spent = np.clip(t[:, None], t_wp[None, :-1], t_wp[None, 1:]) - t_wp[None, :-1]
    return spent @ f


def vertical_limits(
    predictor: object,
    climb_ms: float | None = None,
    descent_ms: float | None = None,
    accel_z_ms2: float | None = None,
) -> tuple[float, float, float]:
    """The vertical limits (climb m/s, descent m/s, vertical acceleration m/s²) a route is
    timed with: each given value, else the predictor's own (a kinematic model holds the
    vehicle's, from its log), else ArduPilot's defaults (``WPNAV_SPEED_UP`` 2.5 m/s,
    ``WPNAV_SPEED_DN`` 1.5 m/s, ``WPNAV_ACCEL_Z`` 1 m/s²). Raises :class:`InputError` for a
    limit that is not finite and > 0."""
    out = []
    for name, given, attr, default in (
        ("climb rate", climb_ms, "climb_ms", 2.5),
        ("descent rate", descent_ms, "descent_ms", 1.5),
        ("vertical accel", accel_z_ms2, "accel_z_ms2", 1.0),
    ):
        x = float(given if given is not None else getattr(predictor, attr, default))
        if not (math.isfinite(x) and x > 0):
            raise InputError(f"{name} must be finite and > 0, got {x!r}")
        out.append(x)
    return out[0], out[1], out[2]


def predict_route(
    predictor: object,
    route: Route3D,
    wind_ne: np.ndarray,
    cruise_ms: float | None = None,
    climb_ms: float | None = None,
    descent_ms: float | None = None,
    accel_z_ms2: float | None = None,
) -> RoutePrediction:
    """Time every element of ``route`` (see module).

    Parameters
    ----------
    predictor : KinematicPredictor or TrajectoryPredictor
        Fitted; its ``predict`` times the horizontal stretches.
    route : Route3D
    wind_ne : ndarray, shape (2,) — wind velocity, m/s toward north/east.
    cruise_ms : float, optional — horizontal speed (default the model's).
    climb_ms, descent_ms, accel_z_ms2 : float, optional
        Vertical limits (m/s, m/s²); default the predictor's own (a kinematic model holds the
        vehicle's), else ArduPilot's defaults 2.5, 1.5, 1.0 (:func:`vertical_limits`).
    """
    from uasnav.trajectory.kinematic import KinematicPredictor

    v_ref = float(cruise_ms if cruise_ms is not None else predictor.cruise_ms_)  # type: ignore[attr-defined]
    if not (math.isfinite(v_ref) and v_ref > 0):
        raise InputError(f"cruise speed must be finite and > 0, got {v_ref!r}")
    up, down, a_z = vertical_limits(predictor, climb_ms, descent_ms, accel_z_ms2)
    own_speeds = isinstance(predictor, KinematicPredictor)
    n = len(route)
    dh, dz = route.horizontal_m, route.dz_m
    moves = dh > SAME_PLACE_M
    v_leg = np.where(np.isfinite(route.speed_ms), route.speed_ms, v_ref)
    kinds: list[str] = []
    segs: list[int] = []
    lens: list[float] = []
    dzs: list[float] = []
    times: list[float] = []
    flags: list[list[str]] = []
    t_arr = np.zeros(n)
    t_dep = np.zeros(n)

    s_end: list[float] = []

    def add(
        kind: str, seg: int, length: float, dz_el: float, t: float, why: list[str], s_e: float = np.nan
    ) -> None:
        s_end.append(s_e)
        kinds.append(kind)
        segs.append(seg)
        lens.append(length)
        dzs.append(dz_el)
        times.append(t)
        flags.append(why)

    def hover(i: int) -> None:
        if route.hold_s[i] > 0:
            add("hover", i, 0.0, 0.0, float(route.hold_s[i]), [])
        t_dep[i] = t_arr[i] + route.hold_s[i]

    hover(0)
    i = 0
    while i < n - 1:
        if not moves[i]:  # a vertical move over one place (or nothing)
            if abs(dz[i]) > SAME_HEIGHT_M:
                t = float(vertical_time(dz[i], up if dz[i] > 0 else down, a_z))
                add("climb" if dz[i] > 0 else "descent", i, 0.0, float(dz[i]), t, [])
            else:
                t = 0.0
            t_arr[i + 1] = t_dep[i] + t
            hover(i + 1)
            i += 1
            continue
        # a horizontal stretch: points i … j, no hold or vertical move inside
        j = i + 1
        while j < n - 1 and moves[j] and route.hold_s[j] == 0:
            j += 1
        w = np.asarray(wind_ne, dtype=float)
        # each leg at its own speed (the leg into point g + 1 flies v_leg[g + 1])
        if isinstance(predictor, KinematicPredictor):
            pred = predictor.predict(route.ne[i : j + 1], w, v_ref, leg_speed_ms=v_leg[i + 1 : j + 1])
        else:
            pred = predictor.predict(route.ne[i : j + 1], w, v_ref)  # type: ignore[attr-defined]
        el = pred.elements
        leg = i + np.asarray(el.leg, dtype=int)
        # time T(s) along the stretch as predicted, then one factor per leg: the LVQ's speed
        # scaling (1 for the kinematic model, which flew each leg at its speed) and, for a
        # sloped leg, no faster than the vertical limit allows;
        # T'(s) = Σ_g f_g · (time spent in leg g before s)
        s_knots = np.concatenate([[el.s_start_m[0]], el.s_end_m])
        t_knots = np.concatenate([[0.0], np.cumsum(np.asarray(pred.time_s, dtype=float))])
        s_wp = np.concatenate([[0.0], np.cumsum(dh[i:j])])
        t_wp0 = np.interp(s_wp, s_knots, t_knots)
        f = np.empty(j - i)
        for g in range(i, j):
            t_h = float(t_wp0[g - i + 1] - t_wp0[g - i])
            f[g - i] = 1.0 if own_speeds else v_ref / v_leg[g + 1]
            if abs(dz[g]) > SAME_HEIGHT_M and t_h > 0:
                t_v = float(vertical_time(dz[g], up if dz[g] > 0 else down, a_z))
                f[g - i] = max(f[g - i], t_v / t_h)
        t_el = np.diff(_scaled(t_knots, t_wp0, f))
        t_wp = _scaled(t_wp0, t_wp0, f)
        for q in range(i + 1, j + 1):
            t_arr[q] = t_dep[i] + t_wp[q - i]
            t_dep[q] = t_arr[q]
        for e in range(len(el)):
            g = int(leg[e])
            # height change over the element's arc (a corner element spans two legs)
            z_a, z_b = np.interp([el.s_start_m[e], el.s_end_m[e]], s_wp, route.alt_m[i : j + 1])
            kind = "turn" if str(el.kind[e]) == "corner" else "leg"
            add(
                kind, g, float(el.length_m[e]), float(z_b - z_a), float(t_el[e]), list(pred.flags[e]),
                float(el.s_end_m[e]),
            )  # fmt: skip
        hover(j)
        i = j
    time_s = np.array(times)
    dz_e = np.array(dzs)
    flagged = np.array([bool(r) for r in flags], dtype=bool)
    # widening at each point: flagged time before it (elements are in flight order)
    w_el = np.concatenate([[0.0], np.cumsum(FLAG_WIDENING * np.where(flagged, time_s, 0.0))])
    t_el_end = np.concatenate([[0.0], np.cumsum(time_s)])
    w_arr = np.interp(t_arr, t_el_end, w_el)
    w_dep = np.interp(t_dep, t_el_end, w_el)
    elements = RouteElements(
        kind=np.array(kinds, dtype=object).astype(str),
        segment=np.array(segs, dtype=int),
        length_m=np.array(lens),
        dz_m=dz_e,
        time_s=time_s,
        climb_rate_ms=np.where(time_s > 0, dz_e / np.maximum(time_s, 1e-12), 0.0),
        stretch_s_end_m=np.array(s_end, dtype=float),
        flagged=flagged,
        flags=flags,
    )
    return RoutePrediction(elements, t_arr, t_dep, w_arr, w_dep, float(t_dep[-1]))


__all__ = [
    "ELEMENT_KINDS",
    "Route3D",
    "RouteElements",
    "RoutePrediction",
    "predict_route",
    "route_from_plan",
    "vertical_limits",
    "vertical_time",
]
