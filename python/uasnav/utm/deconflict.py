"""Strategic deconfliction of ASTM F3548 operational intents with the Rust space-time index.

:func:`encounters` finds every pair of volumes of different intents that intersect in space
and time (conflicts) or, with buffers, come within a horizontal distance and vertical gap
while overlapping in time (near misses); the search is the ``utm-index`` crate's grid index
(see ``crates/utm-index``), not a test of all pairs. :func:`deconflict` groups them by pair
of intents and adds, for each conflict, the smallest departure delay of the later intent (the
one whose first volume starts later) that leaves it free of conflict with *every* other
intent, found by the same index.

Conventions (as in the index): outlines and altitude ranges are closed (touching volumes
conflict), time intervals are half-open (a volume ending when another starts does not).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime, timezone

import numpy as np

from uasnav import _core
from uasnav.errors import InputError
from uasnav.io.operational_intent import NamedIntent
from uasnav.utm.volumes import VolumeArrays, volume_arrays

#: Longest departure delay searched by default, s (one day).
DEFAULT_MAX_DELAY_S = 86_400.0


def _threads() -> int:
    return max(1, min(len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1, 8))


def encounters(
    v: VolumeArrays,
    horizontal_m: float = 0.0,
    vertical_m: float = 0.0,
    *,
    brute: bool = False,
    threads: int | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every encounter of volumes of different intents.

    Parameters
    ----------
    v : VolumeArrays
    horizontal_m, vertical_m : float
        Near-miss buffers, m (0: conflicts only).
    brute : bool
        Test all pairs (O(n²) reference) instead of the index.
    threads : int, optional
        Threads of the index scan (default: the CPUs available, at most 8).

    Returns
    -------
    pairs : ndarray of uint32, shape (k, 2) — volume indices (a < b), sorted.
    overlap_s : ndarray, shape (k, 2) — start/end of the time overlap, s.
    distance_m : ndarray, shape (k, 2) — horizontal distance and vertical gap, m (both 0 for
        a conflict).
    """
    return _core.utm_encounters(
        np.ascontiguousarray(v.intent, dtype=np.uint32),
        np.ascontiguousarray(v.alt_m, dtype=np.float64),
        np.ascontiguousarray(v.time_s, dtype=np.float64),
        np.ascontiguousarray(v.offsets, dtype=np.uint64),
        np.ascontiguousarray(v.vertices_m, dtype=np.float64).reshape(-1, 2),
        np.ascontiguousarray(v.circle_m, dtype=np.float64),
        float(horizontal_m),
        float(vertical_m),
        _threads() if threads is None else int(threads),
        bool(brute),
    )


def earliest_delays(
    v: VolumeArrays, intents: Sequence[int], max_delay_s: float = DEFAULT_MAX_DELAY_S
) -> np.ndarray:
    """Smallest departure delay (s) of each of ``intents`` (numbers) that leaves it free of
    conflict with every other intent; NaN where no delay up to ``max_delay_s`` does."""
    return _core.utm_earliest_delays(
        np.ascontiguousarray(v.intent, dtype=np.uint32),
        np.ascontiguousarray(v.alt_m, dtype=np.float64),
        np.ascontiguousarray(v.time_s, dtype=np.float64),
        np.ascontiguousarray(v.offsets, dtype=np.uint64),
        np.ascontiguousarray(v.vertices_m, dtype=np.float64).reshape(-1, 2),
        np.ascontiguousarray(v.circle_m, dtype=np.float64),
        np.asarray(intents, dtype=np.uint32),
        float(max_delay_s),
    )


@dataclass(frozen=True)
class Conflict:
    """Two intents whose volumes intersect in space and time.

    Attributes
    ----------
    intents : (str, str) — the names, in input order.
    volumes : list of (int, int) — the conflicting volume pairs (index within each intent).
    overlap : (datetime, datetime) — earliest start and latest end of the overlaps (UTC).
    later : str — the intent that departs later (its first volume starts later).
    delay_s : float or None — smallest departure delay of ``later`` that frees it of conflict
        with every other intent (None: none within the searched horizon).
    """

    intents: tuple[str, str]
    volumes: list[tuple[int, int]]
    overlap: tuple[datetime, datetime]
    later: str
    delay_s: float | None


@dataclass(frozen=True)
class NearMiss:
    """Two intents whose volumes overlap in time and come within the buffers without
    intersecting: the smallest horizontal distance and vertical gap over those volume pairs (m)."""

    intents: tuple[str, str]
    volumes: list[tuple[int, int]]
    horizontal_m: float
    vertical_m: float


@dataclass(frozen=True)
class Deconfliction:
    """Result of :func:`deconflict`."""

    conflicts: list[Conflict]
    near_misses: list[NearMiss]
    n_intents: int
    n_volumes: int


def _utc(t: float) -> datetime:
    return datetime.fromtimestamp(t, tz=timezone.utc)


def deconflict(
    intents: Sequence[NamedIntent] | VolumeArrays,
    horizontal_m: float = 0.0,
    vertical_m: float = 0.0,
    max_delay_s: float = DEFAULT_MAX_DELAY_S,
) -> Deconfliction:
    """Conflicts (with the delay that resolves each) and near misses between intents.

    Parameters
    ----------
    intents : sequence of NamedIntent, or VolumeArrays
        Checked F3548 intents (:func:`uasnav.io.operational_intent.read_intents`).
    horizontal_m, vertical_m : float
        Near-miss buffers, m.
    max_delay_s : float
        Longest departure delay searched, s.
    """
    for name, x in (
        ("horizontal buffer", horizontal_m),
        ("vertical buffer", vertical_m),
        ("max delay", max_delay_s),
    ):
        if not (np.isfinite(x) and x >= 0):
            raise InputError(f"{name} must be finite and ≥ 0, got {x!r}")
    v = intents if isinstance(intents, VolumeArrays) else volume_arrays(intents)
    if len(set(v.names)) != len(v.names):
        dup = next(n for n in v.names if v.names.count(n) > 1)
        raise InputError(f"two intents are named {dup!r}: names must be unique")
    pairs, overlap, dist = encounters(v, horizontal_m, vertical_m)
    ia, ib = v.intent[pairs[:, 0]].astype(int), v.intent[pairs[:, 1]].astype(int)
    local_a = pairs[:, 0].astype(int) - v.first[ia]
    local_b = pairs[:, 1].astype(int) - v.first[ib]
    start = np.full(len(v.names), np.inf)
    np.minimum.at(start, v.intent.astype(int), v.time_s[:, 0])
    groups: dict[tuple[int, int], list[int]] = {}
    for k in range(pairs.shape[0]):
        key = (min(ia[k], ib[k]), max(ia[k], ib[k]))
        groups.setdefault(key, []).append(k)
    conflict_keys: list[tuple[int, int]] = []
    near_keys: list[tuple[int, int]] = []
    for key, ks in groups.items():
        (conflict_keys if any(dist[k, 0] == 0 and dist[k, 1] == 0 for k in ks) else near_keys).append(key)
    later = {key: (key[1] if start[key[1]] >= start[key[0]] else key[0]) for key in conflict_keys}
    need = sorted(set(later.values()))
    delays = dict(zip(need, earliest_delays(v, need, max_delay_s), strict=True)) if need else {}
    conflicts = []
    for key in sorted(conflict_keys):
        ks = [k for k in groups[key] if dist[k, 0] == 0 and dist[k, 1] == 0]
        vols = [
            (int(local_a[k]), int(local_b[k])) if ia[k] == key[0] else (int(local_b[k]), int(local_a[k]))
            for k in ks
        ]
        d = float(delays[later[key]])
        conflicts.append(
            Conflict(
                intents=(v.names[key[0]], v.names[key[1]]),
                volumes=sorted(vols),
                overlap=(_utc(float(overlap[ks, 0].min())), _utc(float(overlap[ks, 1].max()))),
                later=v.names[later[key]],
                delay_s=None if np.isnan(d) else d,
            )
        )
    near = []
    for key in sorted(near_keys):
        ks = groups[key]
        vols = [
            (int(local_a[k]), int(local_b[k])) if ia[k] == key[0] else (int(local_b[k]), int(local_a[k]))
            for k in ks
        ]
        near.append(
            NearMiss(
                intents=(v.names[key[0]], v.names[key[1]]),
                volumes=sorted(vols),
                horizontal_m=float(dist[ks, 0].min()),
                vertical_m=float(dist[ks, 1].min()),
            )
        )
    return Deconfliction(conflicts, near, len(v.names), len(v))


__all__ = [
    "DEFAULT_MAX_DELAY_S",
    "Conflict",
    "Deconfliction",
    "NearMiss",
    "deconflict",
    "earliest_delays",
    "encounters",
]
