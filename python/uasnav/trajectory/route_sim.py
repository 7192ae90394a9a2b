"""A 3D route flown by the simulated multirotor, with truth: take-off, sloped legs, holds, landing.

The route is flown as ArduPilot flies a mission: horizontal stretches between stops with
:func:`uasnav.trajectory.simulator.simulate_flight` (its altitude channel follows the legs'
slopes within the vertical limits; ``DO_CHANGE_SPEED`` as per-leg speeds); vertical moves at
one place (take-off, landing, a climb in place) by a vertical point mass with the
acceleration-limited speed command of the same vertical limits and the flight's speed spread;
holds as the vehicle keeping its position (hold time counted from arrival, as ArduPilot's
``NAV_WAYPOINT`` delay and ``LOITER_TIME`` do). Every phase starts where the previous one
ended, at rest. Deterministic from the seed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from uasnav.errors import NumericalError
from uasnav.trajectory.route3d import SAME_HEIGHT_M, SAME_PLACE_M, Route3D
from uasnav.trajectory.simulator import (
    MultirotorParams,
    Telemetry,
    VerticalLimits,
    WindModel,
    simulate_flight,
)


@dataclass(frozen=True)
class RouteTruth:
    """The simulated flight of a route: samples of time (s), position (north/east m), altitude
    (m, the route's frame), and the time each route point was reached (s; departure after a
    hold is ``t_reached_s + hold``). ``stretches`` holds each horizontal stretch flown: (first
    point i, last point j, its start time s, its telemetry from that start)."""

    t: np.ndarray
    pos_ne: np.ndarray
    alt_m: np.ndarray
    t_reached_s: np.ndarray
    stretches: tuple[tuple[int, int, float, Telemetry], ...] = ()


def _vertical(
    z0: float, z1: float, vl: VerticalLimits, scale: float, dt: float, every: int
) -> tuple[np.ndarray, np.ndarray]:
    """A vertical move from rest at z0 to rest at z1: (times from 0, altitudes) sampled."""
    v_max = (vl.climb_ms if z1 > z0 else vl.descent_ms) * scale
    sign = 1.0 if z1 > z0 else -1.0
    z, vz, cmd_prev = z0, 0.0, 0.0
    ts, zs = [], []
    for step in range(int(10_000 / dt)):
        rem = (z1 - z) * sign
        if rem < 0.02 and abs(vz) < 0.05:
            ts.append(step * dt)
            zs.append(z1)
            return np.array(ts), np.array(zs)
        # braking curve toward the target, limited by the speed and acceleration limits
        cmd = sign * min(v_max, np.sqrt(2.0 * vl.accel_z_ms2 * max(rem, 0.0)))
        if rem < 0:
            cmd = -sign * min(v_max, vl.kp_z_per_s * -rem)
        d = vl.accel_z_ms2 * dt
        cmd = float(np.clip(cmd, cmd_prev - d, cmd_prev + d))
        cmd_prev = cmd
        if step % every == 0:
            ts.append(step * dt)
            zs.append(z)
        vz += (cmd - vz) * dt / vl.tau_z_s
        z += vz * dt
    raise NumericalError(f"simulated vertical move {z0:g} → {z1:g} m did not end")


def simulate_route(
    route: Route3D,
    params: MultirotorParams | None = None,
    wind: WindModel | None = None,
    vertical: VerticalLimits | None = None,
    seed: int = 0,
    dt: float = 0.05,
    rate_hz: float = 10.0,
) -> RouteTruth:
    """Fly ``route`` (see module). Returns the truth sampled at ``rate_hz``."""
    prm = params or MultirotorParams()
    vl = vertical or VerticalLimits()
    rng = np.random.default_rng(seed)
    every = max(round(1.0 / (rate_hz * dt)), 1)
    n = len(route)
    dh, dz = route.horizontal_m, route.dz_m
    moves = dh > SAME_PLACE_M
    t_now = 0.0
    ts, ps, zs = [np.zeros(1)], [route.ne[:1].copy()], [route.alt_m[:1].copy()]
    reached = np.zeros(n)
    stretches: list[tuple[int, int, float, Telemetry]] = []

    def add(t: np.ndarray, ne: np.ndarray, z: np.ndarray) -> None:
        ts.append(t)
        ps.append(ne)
        zs.append(z)

    def hold(i: int) -> None:
        nonlocal t_now
        h = float(route.hold_s[i])
        if h > 0:
            k = max(int(h * rate_hz), 1)
            tt = t_now + np.linspace(0.0, h, k + 1)[1:]
            add(tt, np.repeat(ps[-1][-1:], k, axis=0), np.full(k, zs[-1][-1]))
            t_now += h

    hold(0)
    i = 0
    while i < n - 1:
        if not moves[i]:
            if abs(dz[i]) > SAME_HEIGHT_M:
                scale = float(np.clip(1.0 + rng.normal(0.0, prm.speed_sigma_frac), 0.5, 1.5))
                tt, zz = _vertical(float(zs[-1][-1]), float(route.alt_m[i + 1]), vl, scale, dt, every)
                add(t_now + tt[1:], np.repeat(ps[-1][-1:], tt.size - 1, axis=0), zz[1:])
                t_now += float(tt[-1])
            reached[i + 1] = t_now
            hold(i + 1)
            i += 1
            continue
        j = i + 1
        while j < n - 1 and moves[j] and route.hold_s[j] == 0:
            j += 1
        sp = route.speed_ms[i + 1 : j + 1]
        tel = simulate_flight(
            route.ne[i : j + 1],
            params=prm,
            wind=wind,
            seed=int(rng.integers(2**31)),
            dt=dt,
            rate_hz=rate_hz,
            alt_m=route.alt_m[i : j + 1],
            leg_speed_ms=sp if np.isfinite(sp).any() else None,
            vertical=vl,
        )
        assert tel.alt_m is not None
        stretches.append((i, j, t_now, tel))
        add(t_now + tel.t[1:], tel.pos_ne[1:], tel.alt_m[1:])
        # the stretch's inner points: reached when the track passes closest to them
        for q in range(i + 1, j):
            reached[q] = t_now + float(tel.t[np.hypot(*(tel.pos_ne - route.ne[q]).T).argmin()])
        t_now += float(tel.t[-1])
        reached[j] = t_now
        hold(j)
        i = j
    return RouteTruth(np.concatenate(ts), np.concatenate(ps), np.concatenate(zs), reached, tuple(stretches))


__all__ = ["RouteTruth", "simulate_route"]
