"""ASTM F3548 conformance monitoring of operational intents on live telemetry.

The monitor plays the USS's part: it follows each vehicle (MAVLink system id) flying an
accepted intent and checks every position report against the intent's 4D volumes.

States (F3548 §4.4 operational intent states), per vehicle:

- **Accepted** — the intent is known, the vehicle is heard but not flying it yet.
- **Activated** — inferred from arming inside a volume alive at that time (activation is the
  operator's act; the monitor sees its effect). A vehicle armed on the ground before the
  intent's first volume opens waits in Accepted and is Activated when it opens; one that leaves
  the ground before then is Activated and Nonconforming at once.
- **Nonconforming** — a position report outside every volume alive at its time: horizontally,
  vertically or in time. Back to Activated when a report is inside again.
- **Contingent** — by the operator's rule: nonconforming for longer than
  ``contingent_after_outside_s``, telemetry lost for longer than ``contingent_after_loss_s``,
  or the vehicle reporting a failsafe (``HEARTBEAT.system_status`` CRITICAL or EMERGENCY, MAVLink's
  way to report a lost C2 link). Stays until Ended.
- **Ended** — landing (a report within :data:`GROUND_M` of home's height after the flight
  rose above :data:`AIRBORNE_M`) or disarm after the flight; a vehicle that lands is not
  activated again before it disarms and arms.

On the ground is ``GLOBAL_POSITION_INT.relative_alt`` (height above home, which the autopilot
zeroes at arming) ≤ :data:`GROUND_M`: the vehicle sitting on its pad before the start and after
touch-down is not flying outside its intent.

Telemetry loss (no message from the vehicle for ``telemetry_timeout_s`` of vehicle time) is
its own event, ``telemetry_lost``/``telemetry_restored``, not a C2 loss: the ground station's
link is not the operator's C2 link.

Geometry. Volumes are polygons (or circles) in the intent's local ENU plane
(:func:`uasnav.utm.volumes.volume_arrays`) with W84 altitude limits. A position is inside a
volume when its horizontal distance to the outline and its height above the floor and below
the ceiling all exceed the vehicle's reported 95 % uncertainty (1.96 σ of ``GPS_RAW_INT``
``h_acc``/``v_acc``; 0 when not reported): the monitor calls a vehicle conforming only when its
whole uncertainty region is inside. The *margin* of an event is the signed distance (m, positive
inside) to the boundary of the nearest alive volume, the smaller of the horizontal and vertical
distances. Heights: ``GLOBAL_POSITION_INT.alt`` is AMSL, turned into W84 by adding the EGM96
geoid height at the position (:mod:`uasnav.geo.geoid`).

Time. Everything is judged on vehicle time: ``time_boot_ms`` of the position report plus the
boot-to-UTC offset from ``SYSTEM_TIME``, so a stream replayed faster is judged the same.
Reports older than the newest seen (duplicates, reordered or late packets) are counted and
skipped; a clock that jumps back by more than :data:`REBOOT_JUMP_S` is a reboot and starts over.
Memory per vehicle is constant.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import datetime, timezone
from typing import Any

import numpy as np

from uasnav.errors import InputError
from uasnav.io.operational_intent import NamedIntent

ACCEPTED = "Accepted"
ACTIVATED = "Activated"
NONCONFORMING = "Nonconforming"
CONTINGENT = "Contingent"
ENDED = "Ended"
STATES = (ACCEPTED, ACTIVATED, NONCONFORMING, CONTINGENT, ENDED)

#: A vehicle clock that goes back by more than this (s) is a reboot.
REBOOT_JUMP_S = 30.0
#: Height above home (m, ``relative_alt``) at or below which the vehicle is on the ground: a
#: barometer's drift over a flight stays within it, a multirotor's final descent (≤ 0.5 m/s)
#: covers it in about 3 s.
GROUND_M = 1.5
#: Height above home (m) above which the vehicle has taken off (a later report on the ground
#: is its landing).
AIRBORNE_M = 5.0
#: 95 % of a normal distribution in one dimension, in σ.
K95 = 1.96
_MAV_MODE_FLAG_SAFETY_ARMED = 128
_MAV_STATE_CRITICAL = 5
_MAV_STATE_EMERGENCY = 6


@dataclass(frozen=True)
class ContingencyRule:
    """When the monitor declares Contingent (vehicle seconds; ``None`` disables a clause)."""

    after_outside_s: float | None = 30.0
    after_loss_s: float | None = 10.0
    on_failsafe: bool = True


@dataclass(frozen=True)
class IntentGeometry:
    """One intent's volumes ready for point queries: shapely outlines in the ENU plane at
    ``origin`` (m), altitude limits (m W84) and times (s, Unix)."""

    name: str
    origin: tuple[float, float]
    outlines: tuple[Any, ...]
    alt_m: np.ndarray
    time_s: np.ndarray

    @classmethod
    def of(cls, intent: NamedIntent) -> IntentGeometry:
        from shapely.geometry import Point, Polygon

        from uasnav.utm.volumes import volume_arrays

        va = volume_arrays([intent])
        outlines = []
        for i in range(len(va)):
            a, b = int(va.offsets[i]), int(va.offsets[i + 1])
            if b > a:
                outlines.append(Polygon(va.vertices_m[a:b]))
            else:
                x, y, r = va.circle_m[i]
                outlines.append(Point(x, y).buffer(r, quad_segs=32))
        return cls(intent.name, va.origin, tuple(outlines), va.alt_m, va.time_s)

    def margin(self, e: float, n: float, h: float, t: float) -> tuple[float, int | None, float, float]:
        """``(margin, volume, horizontal, vertical)`` of the point (east, north m; h m W84) at
        Unix time ``t``: the volume alive at ``t`` whose boundary is farthest inside (or
        nearest outside), ``None`` and −inf when no volume is alive."""
        from shapely.geometry import Point

        best: tuple[float, int | None, float, float] = (-math.inf, None, -math.inf, -math.inf)
        p = Point(e, n)
        alive = np.flatnonzero((self.time_s[:, 0] <= t) & (t <= self.time_s[:, 1]))
        for i in alive:
            poly = self.outlines[i]
            d = poly.exterior.distance(p)
            horiz = d if poly.contains(p) else -d
            vert = min(h - self.alt_m[i, 0], self.alt_m[i, 1] - h)
            m = min(horiz, vert)
            if m > best[0]:
                best = (m, int(i), horiz, vert)
        return best


@dataclass
class _Vehicle:
    sysid: int
    geometry: IntentGeometry
    state: str | None = None
    armed: bool = False
    boot_to_unix_s: float | None = None
    last_boot_s: float = -math.inf
    last_vehicle_s: float | None = None
    last_wall_s: float | None = None
    rate: deque[tuple[float, float]] = field(default_factory=lambda: deque(maxlen=64))
    h_unc_m: float = 0.0
    v_unc_m: float = 0.0
    outside_since_s: float | None = None
    telemetry_lost: bool = False
    failsafe: bool = False
    last_position: tuple[float, float, float] | None = None
    height_above_home_m: float | None = None
    airborne: bool = False
    landed: bool = False
    stale: int = 0
    reports: int = 0


@dataclass
class MonitorStats:
    """Counts over the whole stream."""

    messages: int = 0
    position_reports: int = 0
    stale_reports: int = 0
    unknown_vehicles: int = 0
    seq_lost: int = 0
    events: int = 0


class ConformanceMonitor:
    """Feed messages (:meth:`on_message`) and wall-clock ticks (:meth:`on_tick`); both return
    the events they cause, as JSON-ready dicts (see module).

    Parameters
    ----------
    intents : sequence of NamedIntent
    vehicles : dict sysid → intent name, optional
        Which vehicle flies which intent; default: vehicle ``k + 1`` flies intent ``k``.
    rule : ContingencyRule
    telemetry_timeout_s : float
        Vehicle seconds without a message that make a telemetry loss.
    """

    def __init__(
        self,
        intents: Sequence[NamedIntent],
        vehicles: dict[int, str] | None = None,
        rule: ContingencyRule = ContingencyRule(),
        telemetry_timeout_s: float = 3.0,
    ) -> None:
        if not intents:
            raise InputError("monitor: no operational intent given")
        by_name = {it.name: it for it in intents}
        if len(by_name) != len(intents):
            raise InputError("monitor: two intents have the same name (rename a file)")
        if vehicles is None:
            vehicles = {k + 1: it.name for k, it in enumerate(intents)}
        for sysid, name in vehicles.items():
            if name not in by_name:
                raise InputError(
                    f"--vehicle {sysid}={name}: no intent named {name!r} (have {', '.join(by_name)})"
                )
        geoms = {name: IntentGeometry.of(by_name[name]) for name in set(vehicles.values())}
        self._vehicles = {s: _Vehicle(s, geoms[n]) for s, n in vehicles.items()}
        self.rule = rule
        self.telemetry_timeout_s = float(telemetry_timeout_s)
        self.stats = MonitorStats()
        self._seq: dict[tuple[int, int], int] = {}
        self._warm_up(next(iter(geoms.values())))

    @staticmethod
    def _warm_up(g: IntentGeometry) -> None:
        """Load the geoid grid and the geodesy and geometry libraries now, so the first position
        report is judged as fast as the others."""
        from uasnav.geo import geodetic_to_enu
        from uasnav.geo.geoid import geoid_height

        geoid_height(g.origin[0], g.origin[1])
        geodetic_to_enu(g.origin[0], g.origin[1], 0.0, g.origin[0], g.origin[1], 0.0)
        g.margin(0.0, 0.0, 0.0, float(g.time_s[0, 0]))

    # --- events --------------------------------------------------------------------------------
    def _event(
        self, v: _Vehicle, kind: str, t_vehicle: float | None, reason: str, **extra: Any
    ) -> dict[str, Any]:
        utc = None
        if t_vehicle is not None and v.boot_to_unix_s is not None:
            utc = (
                datetime.fromtimestamp(t_vehicle + v.boot_to_unix_s, timezone.utc)
                .isoformat()
                .replace("+00:00", "Z")
            )
        pos = v.last_position
        ev: dict[str, Any] = {
            "event": kind,
            "vehicle": v.sysid,
            "intent": v.geometry.name,
            "state": v.state,
            "time_utc": utc,
            "time_boot_s": t_vehicle,
            "lat": None if pos is None else pos[0],
            "lon": None if pos is None else pos[1],
            "alt_w84_m": None if pos is None else pos[2],
            "reason": reason,
        }
        ev.update((k, val) for k, val in extra.items() if k != "why")
        self.stats.events += 1
        return ev

    def _to(
        self, v: _Vehicle, state: str, t: float | None, reason: str, out: list[dict[str, Any]], **extra: Any
    ) -> None:
        if v.state == state:
            return
        previous, v.state = v.state, state
        out.append(self._event(v, "state", t, reason, previous=previous, **extra))

    # --- input ---------------------------------------------------------------------------------
    def on_message(self, msg: Any, wall_s: float) -> list[dict[str, Any]]:
        """Process one received message at wall-clock time ``wall_s`` (s, monotonic)."""
        self.stats.messages += 1
        out: list[dict[str, Any]] = []
        sysid = msg.get_srcSystem()
        key = (sysid, msg.get_srcComponent())
        seq = msg.get_seq()
        last = self._seq.get(key)
        if last is not None:
            gap = (seq - last - 1) % 256
            if gap < 128:  # ahead: packets in between were lost; behind: late or duplicated
                self.stats.seq_lost += gap
        if last is None or (seq - last) % 256 < 128:
            self._seq[key] = seq
        v = self._vehicles.get(sysid)
        if v is None:
            self.stats.unknown_vehicles += 1
            return out
        if v.state is None:
            self._to(v, ACCEPTED, None, "vehicle heard, intent accepted", out)
        t = msg.get_type()
        boot_s = self._boot_time(msg)
        if boot_s is not None:
            if v.last_vehicle_s is not None and boot_s < v.last_vehicle_s - REBOOT_JUMP_S:
                v.last_vehicle_s, v.last_boot_s = None, -math.inf  # reboot
            if v.last_vehicle_s is None or boot_s > v.last_vehicle_s:
                v.last_vehicle_s = boot_s
                v.rate.append((wall_s, boot_s))
        v.last_wall_s = wall_s
        if v.telemetry_lost:
            v.telemetry_lost = False
            out.append(self._event(v, "telemetry_restored", v.last_vehicle_s, "messages again"))
        if t == "SYSTEM_TIME":
            if msg.time_unix_usec > 0:
                v.boot_to_unix_s = msg.time_unix_usec * 1e-6 - msg.time_boot_ms * 1e-3
        elif t == "GPS_RAW_INT":
            h_acc, v_acc = getattr(msg, "h_acc", 0), getattr(msg, "v_acc", 0)
            v.h_unc_m = K95 * h_acc * 1e-3 if h_acc else 0.0
            v.v_unc_m = K95 * v_acc * 1e-3 if v_acc else 0.0
        elif t == "HEARTBEAT":
            self._heartbeat(v, msg, out)
        elif t == "GLOBAL_POSITION_INT":
            self._position(v, msg, out)
        return out

    @staticmethod
    def _boot_time(msg: Any) -> float | None:
        ms = getattr(msg, "time_boot_ms", None)
        if ms is not None:
            return float(ms) * 1e-3
        return None

    def _heartbeat(self, v: _Vehicle, msg: Any, out: list[dict[str, Any]]) -> None:
        if msg.autopilot == 8:  # MAV_AUTOPILOT_INVALID: a ground station or companion, not the vehicle
            return
        armed = bool(msg.base_mode & _MAV_MODE_FLAG_SAFETY_ARMED)
        t = v.last_vehicle_s
        if armed and not v.armed and v.state in (ACCEPTED, ENDED):
            v.armed = True
            if v.last_position is None:
                return  # judged at the first position report
            self._judge_armed(v, t, out)
        elif not armed and v.armed:
            v.armed = v.airborne = v.landed = False
            if v.state in (ACTIVATED, NONCONFORMING, CONTINGENT):
                self._to(v, ENDED, t, "disarmed after the flight", out)
        failsafe = msg.system_status in (_MAV_STATE_CRITICAL, _MAV_STATE_EMERGENCY)
        if failsafe and not v.failsafe and self.rule.on_failsafe and v.state in (ACTIVATED, NONCONFORMING):
            self._to(v, CONTINGENT, t, f"vehicle reports failsafe (system status {msg.system_status})", out)
        v.failsafe = failsafe

    def _on_ground(self, v: _Vehicle) -> bool:
        h = v.height_above_home_m
        return h is not None and h <= GROUND_M

    def _judge_armed(self, v: _Vehicle, t: float | None, out: list[dict[str, Any]]) -> None:
        m = self._check(v, t)
        if m is None or v.landed:
            return
        if m["volume"] is None and t is not None and self._on_ground(v):
            assert v.boot_to_unix_s is not None  # _check needs it
            if t + v.boot_to_unix_s < float(v.geometry.time_s[:, 0].min()):
                return  # armed on the pad before the intent's first volume opens: waits
        self._to(v, ACTIVATED, t, "armed", out, **m)
        if not m["inside"]:
            v.outside_since_s = t
            self._to(v, NONCONFORMING, t, "armed " + m["why"], out, **m)

    def _check(self, v: _Vehicle, t: float | None) -> dict[str, Any] | None:
        if v.last_position is None or t is None or v.boot_to_unix_s is None:
            return None
        from uasnav.geo import geodetic_to_enu

        lat, lon, h = v.last_position
        e, n, _ = geodetic_to_enu(lat, lon, 0.0, v.geometry.origin[0], v.geometry.origin[1], 0.0)
        margin, vol, horiz, vert = v.geometry.margin(float(e), float(n), h, t + v.boot_to_unix_s)
        inside = vol is not None and horiz >= v.h_unc_m and vert >= v.v_unc_m
        if vol is None:
            why = "outside the intent's times"
        elif horiz < v.h_unc_m:
            why = "outside horizontally"
        elif vert < v.v_unc_m:
            why = "outside vertically"
        else:
            why = "inside"
        return {
            "inside": bool(inside),
            "why": why,
            "margin_m": None if vol is None else round(float(margin), 2),
            "volume": vol,
            "uncertainty_h_m": round(v.h_unc_m, 2),
            "uncertainty_v_m": round(v.v_unc_m, 2),
        }

    def _position(self, v: _Vehicle, msg: Any, out: list[dict[str, Any]]) -> None:
        from uasnav.geo.geoid import geoid_height

        self.stats.position_reports += 1
        t = msg.time_boot_ms * 1e-3
        if t <= v.last_boot_s:
            v.stale += 1
            self.stats.stale_reports += 1
            return
        v.last_boot_s = t
        if msg.lat == 0 and msg.lon == 0:
            return  # no position yet
        lat, lon = msg.lat * 1e-7, msg.lon * 1e-7
        h = msg.alt * 1e-3 + float(geoid_height(lat, lon))  # AMSL → W84
        v.last_position = (lat, lon, h)
        v.height_above_home_m = msg.relative_alt * 1e-3
        if v.armed and v.state in (ACTIVATED, NONCONFORMING, CONTINGENT):
            if v.height_above_home_m > AIRBORNE_M:
                v.airborne = True
            elif v.airborne and self._on_ground(v):
                v.landed, v.outside_since_s = True, None
                self._to(v, ENDED, t, f"landed ({v.height_above_home_m:.1f} m above home)", out)
                return
        if v.armed and v.state in (ACCEPTED, ENDED):
            self._judge_armed(v, t, out)
            return
        if v.state not in (ACTIVATED, NONCONFORMING, CONTINGENT):
            return
        m = self._check(v, t)
        if m is None:
            return
        if v.state == CONTINGENT:
            return
        if m["inside"]:
            v.outside_since_s = None
            self._to(v, ACTIVATED, t, "back inside the intent", out, **m)
            return
        if v.outside_since_s is None:
            v.outside_since_s = t
        self._to(v, NONCONFORMING, t, m["why"], out, **m)
        limit = self.rule.after_outside_s
        if limit is not None and t - v.outside_since_s >= limit:
            self._to(v, CONTINGENT, t, f"nonconforming for {t - v.outside_since_s:.1f} s", out, **m)

    def _vehicle_rate(self, v: _Vehicle) -> float:
        """Vehicle seconds per wall second over the recent messages (1 when unknown)."""
        if len(v.rate) < 2:
            return 1.0
        (w0, b0), (w1, b1) = v.rate[0], v.rate[-1]
        if w1 - w0 <= 0.05 or b1 <= b0:
            return 1.0
        return min(max((b1 - b0) / (w1 - w0), 0.01), 10_000.0)

    def on_tick(self, wall_s: float) -> list[dict[str, Any]]:
        """Check telemetry loss at wall-clock time ``wall_s``: the silence in vehicle seconds is
        the wall-clock silence times the stream's recent rate (so it holds under ``--speed``)."""
        out: list[dict[str, Any]] = []
        for v in self._vehicles.values():
            if v.last_wall_s is None or v.state in (None, ENDED):
                continue
            silent_s = (wall_s - v.last_wall_s) * self._vehicle_rate(v)
            t = None if v.last_vehicle_s is None else v.last_vehicle_s + silent_s
            if not v.telemetry_lost and silent_s >= self.telemetry_timeout_s:
                v.telemetry_lost = True
                out.append(
                    self._event(v, "telemetry_lost", t, f"no message for {silent_s:.1f} s (vehicle time)")
                )
            limit = self.rule.after_loss_s
            if (
                v.telemetry_lost
                and limit is not None
                and silent_s >= limit
                and v.state in (ACTIVATED, NONCONFORMING)
            ):
                self._to(v, CONTINGENT, t, f"telemetry lost for {silent_s:.1f} s", out)
        return out

    def states(self) -> dict[int, str | None]:
        """The current state of each vehicle."""
        return {s: v.state for s, v in self._vehicles.items()}
