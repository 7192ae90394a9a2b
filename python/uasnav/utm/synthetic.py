"""A seeded generator of many operational intents over a city and a day (benchmarks, tests).

Each intent is a flight of 10–50 legs (a random walk: legs of 150–400 m, turns up to ±60°)
inside a square city (default 30 km), cruising at one altitude (30–120 m, ± a 10 m buffer),
departing at a uniformly random time of the day at 8–15 m/s. Each leg is one volume: the leg
grown by a 15 m lateral buffer (a rectangle, 4 vertices) alive from 10 s before the predicted
arrival at its start to 10 s after the arrival at its end. Coordinates are local metres
(:class:`~uasnav.utm.volumes.VolumeArrays`), times seconds of the day.
"""

from __future__ import annotations

import numpy as np

from uasnav.limits import check_count
from uasnav.utm.volumes import VolumeArrays


def synthetic_intents(
    n_intents: int,
    seed: int = 0,
    *,
    city_m: float = 30_000.0,
    day_s: float = 86_400.0,
    volumes: tuple[int, int] = (10, 50),
    buffer_m: float = 15.0,
) -> VolumeArrays:
    """``n_intents`` random intents (see module) as arrays."""
    rng = np.random.default_rng(seed)
    k = rng.integers(volumes[0], volumes[1] + 1, n_intents)
    n = int(k.sum())
    check_count(n, 200.0, f"{n} synthetic volumes", option="n_intents")
    intent = np.repeat(np.arange(n_intents, dtype=np.uint32), k)
    first = np.concatenate([[0], np.cumsum(k)[:-1]])
    # headings: a random start per intent plus cumulative turns within the intent
    turn = np.radians(rng.uniform(-60, 60, n))
    turn[first] = rng.uniform(0, 2 * np.pi, n_intents)
    cum = np.cumsum(turn)
    heading = cum - np.repeat(cum[first] - turn[first], k)
    length = rng.uniform(150.0, 400.0, n)
    step = np.column_stack([np.cos(heading), np.sin(heading)]) * length[:, None]
    cstep = np.cumsum(step, axis=0)
    start_xy = rng.uniform(0.0, city_m, (n_intents, 2))
    before = cstep - step  # displacement before each leg, within its intent
    before -= np.repeat(before[first], k, axis=0)
    p0 = np.repeat(start_xy, k, axis=0) + before
    p1 = p0 + step
    speed = np.repeat(rng.uniform(8.0, 15.0, n_intents), k)
    t_leg = length / speed
    ct = np.cumsum(t_leg)
    t_before = ct - t_leg - np.repeat((ct - t_leg)[first], k)
    t0 = np.repeat(rng.uniform(0.0, day_s, n_intents), k) + t_before
    time = np.column_stack([t0 - 10.0, t0 + t_leg + 10.0])
    z = np.repeat(rng.uniform(30.0, 120.0, n_intents), k)
    alt = np.column_stack([z - 10.0, z + 10.0])
    # rectangle around each leg: ±buffer across, ±buffer beyond each end
    u = step / length[:, None]
    v = np.column_stack([-u[:, 1], u[:, 0]])
    a, b = p0 - buffer_m * u, p1 + buffer_m * u
    rect = np.stack([a - buffer_m * v, b - buffer_m * v, b + buffer_m * v, a + buffer_m * v], axis=1)
    return VolumeArrays(
        intent=intent,
        alt_m=alt,
        time_s=time,
        offsets=np.arange(0, 4 * n + 1, 4, dtype=np.uint64),
        vertices_m=rect.reshape(-1, 2),
        circle_m=np.zeros((n, 3)),
        names=tuple(f"intent{i}" for i in range(n_intents)),
        first=first.astype(np.int64),
    )


def subsample(v: VolumeArrays, n_intents: int) -> VolumeArrays:
    """The first ``n_intents`` intents of ``v`` (volumes are grouped by intent)."""
    n = int(v.first[n_intents]) if n_intents < len(v.names) else len(v)
    return VolumeArrays(
        intent=v.intent[:n],
        alt_m=v.alt_m[:n],
        time_s=v.time_s[:n],
        offsets=v.offsets[: n + 1],
        vertices_m=v.vertices_m[: int(v.offsets[n])],
        circle_m=v.circle_m[:n],
        names=v.names[:n_intents],
        first=v.first[:n_intents],
    )


__all__ = ["subsample", "synthetic_intents"]
