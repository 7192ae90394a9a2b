"""Flight plans in a local tangent plane and their discretisation into elements (thesis §5.1.2).

Frames: positions are (north, east) metres in a local NED tangent plane; headings and wind
directions are degrees clockwise from north. A *plan* is a polyline of waypoints; it is cut
into *elements* of two segments (eq. 47, Figure 52): a corner element straddles each interior
waypoint (the last ``L`` metres before it and the first ``L`` after it), and the straight
stretches in between are cut into straight elements of ``2 L`` (the remainder of a stretch
becomes one shorter straight element). Element times then add up to the time of the plan.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from uasnav.errors import InputError
from uasnav.limits import check_memory, check_work

#: Default segment length L of an element (m), as in the thesis (§5.1.4.2).
DEFAULT_SEGMENT_M = 10.0

#: Element kinds: a corner at an interior waypoint, a straight piece, the first (from rest at
#: the start waypoint) and the last (braking to the final waypoint) piece of a plan.
KINDS = ("corner", "straight", "start", "end")


def geodetic_to_local(
    lat_deg: np.ndarray,
    lon_deg: np.ndarray,
    alt_m: np.ndarray,
    origin: tuple[float, float, float] | None = None,
) -> np.ndarray:
    """WGS-84 geodetic coordinates → local NED (:func:`uasnav.geo.frames.geodetic_to_ned`).

    Parameters
    ----------
    lat_deg, lon_deg : array_like, shape (n,)
        Latitude and longitude, degrees.
    alt_m : array_like, shape (n,)
        Height above the ellipsoid (or any consistent altitude), m.
    origin : (lat_deg, lon_deg, alt_m), optional
        Tangent point; default the first point.

    Returns
    -------
    ndarray, shape (n, 3)
        North, east, down, m.
    """
    from uasnav.geo import frames

    lat = np.asarray(lat_deg, dtype=float)
    lon = np.asarray(lon_deg, dtype=float)
    alt = np.asarray(alt_m, dtype=float)
    if not (lat.shape == lon.shape == alt.shape) or lat.ndim != 1 or lat.size == 0:
        raise InputError(f"lat/lon/alt must be 1-D arrays of equal non-zero length, got {lat.shape}")
    bad = ~(np.isfinite(lat) & np.isfinite(lon) & np.isfinite(alt))
    if bad.any():
        raise InputError(f"non-finite coordinate at waypoint {int(np.flatnonzero(bad)[0])}")
    if np.any(np.abs(lat) > 90.0):
        raise InputError(f"latitude out of range at waypoint {int(np.flatnonzero(np.abs(lat) > 90)[0])}")
    o = (lat[0], lon[0], alt[0]) if origin is None else origin
    n, e, d = frames.geodetic_to_ned(lat, lon, alt, o[0], o[1], o[2])
    return np.column_stack([n, e, d])


def check_plan(plan_ne: np.ndarray, min_leg_m: float = 0.0) -> np.ndarray:
    """Validate a plan: shape (n, 2), n ≥ 2, finite, no coincident waypoints, legs ≥ ``min_leg_m``,
    and at least two segments of length ``min_leg_m`` in total (one element).

    Returns the plan as a float array. Raises :class:`InputError` naming the waypoint or leg.
    """
    p = np.asarray(plan_ne, dtype=float)
    if p.ndim != 2 or p.shape[1] < 2:
        raise InputError(f"plan must have shape (n, 2) of north/east metres, got {p.shape}")
    p = p[:, :2]
    if p.shape[0] < 2:
        raise InputError(f"plan needs at least two waypoints, got {p.shape[0]}")
    bad = ~np.isfinite(p).all(axis=1)
    if bad.any():
        raise InputError(f"plan waypoint {int(np.flatnonzero(bad)[0])} has a NaN/inf coordinate")
    with np.errstate(over="ignore", invalid="ignore"):  # ±1e308 coordinates: an inf leg
        legs = np.hypot(*np.diff(p, axis=0).T)
    if np.any(legs < 1e-6):
        i = int(np.flatnonzero(legs < 1e-6)[0])
        raise InputError(f"plan waypoints {i} and {i + 1} coincide (repeated waypoint)")
    if np.any(legs < min_leg_m - 1e-3):
        i = int(np.flatnonzero(legs < min_leg_m - 1e-3)[0])
        raise InputError(
            f"plan leg {i} (waypoints {i}→{i + 1}) is {legs[i]:.2f} m, shorter than the segment "
            f"length L = {min_leg_m:g} m"
        )
    if min_leg_m > 0 and legs.sum() < 2 * min_leg_m - 1e-3:
        raise InputError(
            f"plan is {legs.sum():.2f} m long: fewer than two segments of L = {min_leg_m:g} m (one element)"
        )
    return p


def heading_deg(v_ne: np.ndarray) -> np.ndarray:
    """Heading of north/east vectors, degrees clockwise from north in [0, 360)."""
    v = np.asarray(v_ne, dtype=float)
    return np.mod(np.degrees(np.arctan2(v[..., 1], v[..., 0])), 360.0)


def signed_angle_deg(a_ne: np.ndarray, b_ne: np.ndarray) -> np.ndarray:
    """Angle from vector a to vector b, degrees, positive clockwise (a right turn), in (−180, 180].

    Its magnitude is eq. (52)/(56): acos(a·b / |a||b|) with the dot product of eq. (53)/(57);
    the sign comes from the vertical component of a × b (north × east points down).
    """
    a = np.asarray(a_ne, dtype=float)
    b = np.asarray(b_ne, dtype=float)
    dot = a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1]
    cross = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return np.degrees(np.arctan2(cross, dot))


@dataclass(frozen=True)
class Elements:
    """The elements of a plan (all arrays of length m, one entry per element, in flight order).

    Attributes
    ----------
    start_ne, mid_ne, end_ne : ndarray, shape (m, 2)
        Element start point, the joint of its two segments, and its end point (north, east m).
    s_start_m, s_end_m : ndarray, shape (m,)
        Arc length along the plan at the element's start and end, m.
    length_m : ndarray, shape (m,)
        Path length of the element (the two segments), m — the L of eq. (47).
    heading1_deg : ndarray, shape (m,)
        Course of the first segment, degrees from north.
    turn_deg : ndarray, shape (m,)
        Signed turn angle between the segments (eq. 52), positive right, degrees.
    kind : ndarray of str, shape (m,)
        One of :data:`KINDS`.
    shortened : ndarray of bool, shape (m,)
        A corner element whose segments had to be shorter than L (leg shorter than 2 L).
    leg : ndarray of int, shape (m,)
        Plan leg (index of its first waypoint) holding the element's start.
    """

    start_ne: np.ndarray
    mid_ne: np.ndarray
    end_ne: np.ndarray
    s_start_m: np.ndarray
    s_end_m: np.ndarray
    length_m: np.ndarray
    heading1_deg: np.ndarray
    turn_deg: np.ndarray
    kind: np.ndarray
    shortened: np.ndarray
    leg: np.ndarray

    def __len__(self) -> int:
        return int(self.length_m.size)


def _points_at(p: np.ndarray, cum: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Points at arc lengths ``s`` (m) along the polyline ``p`` with cumulative lengths ``cum``."""
    i = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, p.shape[0] - 2)
    d = p[i + 1] - p[i]
    return p[i] + d * ((s - cum[i]) / (cum[i + 1] - cum[i]))[:, None]


#: Peak memory (bytes) and work (elementary operations) per element of :func:`discretise`
#: (measured ≈ 390 B and a few µs per element; rounded up). Used to refuse, before any
#: allocation, a plan whose element count is absurd (a 10⁹ m leg, a segment of 10⁻⁹ m).
_BYTES_PER_ELEMENT = 512
_WORK_PER_ELEMENT = 1e4
#: Peak memory per (position, leg) pair in :func:`arc_length_along` (u, dist and temporaries).
_BYTES_PER_PAIR = 64


def element_count_bound(plan_ne: np.ndarray, segment_m: float) -> float:
    """Upper bound of the number of elements :func:`discretise` makes of a plan (no allocation).

    Each of the n − 1 stretches between corners holds at most ``length / (2 L) + 1`` straight
    elements, and there are n − 2 corners; inf for a non-finite plan or segment.
    """
    p = np.asarray(plan_ne, dtype=float)
    if p.ndim != 2 or p.shape[0] < 2 or not (np.isfinite(segment_m) and segment_m > 0):
        return 0.0
    with np.errstate(over="ignore", invalid="ignore"):
        total = float(np.hypot(*np.diff(p[:, :2], axis=0).T).sum())
    return total / (2.0 * segment_m) + 2.0 * p.shape[0]


def check_element_count(plan_ne: np.ndarray, segment_m: float, what: str = "plan") -> float:
    """Refuse (:class:`~uasnav.errors.ResourceLimitError`) a plan whose elements at segment
    length ``segment_m`` would exceed the memory or work limit (:mod:`uasnav.limits`).

    Returns the element-count bound.
    """
    n = element_count_bound(plan_ne, segment_m)
    desc = f"{what}: about {n:.3g} elements of 2 × {segment_m:g} m"
    check_memory(n * _BYTES_PER_ELEMENT, desc, option="the plan's length or raise the segment length")
    check_work(n * _WORK_PER_ELEMENT, desc, option="the plan's length or raise the segment length")
    return n


def merge_short_legs(plan_ne: np.ndarray, segment_m: float) -> tuple[np.ndarray, np.ndarray]:
    """The plan with its legs shorter than the segment length L merged into their neighbours,
    so that the thesis' elements (two segments of L) can cover it; and, for each waypoint of
    ``plan_ne``, the index of the merged plan's waypoint that stands for it.

    A waypoint whose incoming leg is shorter than L is dropped (the vehicle passes within L of
    it at the next kept waypoint); when the last leg is short, the waypoint before the last is
    dropped instead, so the plan still ends where it ends. Repeated waypoints (legs of 0 m)
    merge the same way. Real plans have such legs: a VTOL landing a metre or two from the last
    waypoint, waypoints a few metres apart for a camera.

    >>> merged, idx = merge_short_legs(np.array([[0.0, 0.0], [100.0, 0.0], [101.0, 0.0]]), 10.0)
    >>> merged.tolist(), idx.tolist()
    ([[0.0, 0.0], [101.0, 0.0]], [0, 1, 1])
    """
    p = np.asarray(plan_ne, dtype=float)[:, :2]
    keep = [0]
    for i in range(1, len(p)):
        if float(np.hypot(*(p[i] - p[keep[-1]]))) >= segment_m:
            keep.append(i)
    if keep[-1] != len(p) - 1:
        if len(keep) > 1:
            keep[-1] = len(p) - 1  # the plan ends at its own last waypoint
        else:
            keep.append(len(p) - 1)
    keep_a = np.asarray(keep)
    idx = np.searchsorted(keep_a, np.arange(len(p)), side="left")
    return p[keep_a], np.minimum(idx, len(keep_a) - 1)


def discretise(plan_ne: np.ndarray, segment_m: float = DEFAULT_SEGMENT_M) -> Elements:
    """Cut a plan into elements of two segments of length ``segment_m`` (thesis §5.1.2).

    Parameters
    ----------
    plan_ne : ndarray, shape (n, 2)
        Waypoints, north/east m, n ≥ 2, at least 2 L long.
    segment_m : float
        Segment length L, m (default 10 m).

    Returns
    -------
    Elements

    Raises
    ------
    InputError
        Fewer than two segments of length L (a plan shorter than one element), NaN,
        coincident waypoints, or a leg shorter than L.
    ResourceLimitError
        More elements than the memory or work limit allows (:func:`check_element_count`).

    Notes
    -----
    A corner element around interior waypoint k uses ``min(L, leg/2)`` on each adjacent
    interior leg (``min(L, leg)`` on the first and last leg) so that elements never
    overlap; if that is less than L the element is flagged ``shortened`` (a lower-confidence
    prediction). The plan's first and last pieces of up to 2 L are kinds ``start``/``end``
    (the vehicle accelerates from, and brakes to, a waypoint).
    """
    if not np.isfinite(segment_m) or segment_m <= 0:
        raise InputError(f"segment length must be a positive number of metres, got {segment_m}")
    p = check_plan(plan_ne, min_leg_m=segment_m)
    check_element_count(p, segment_m)
    legs = np.hypot(*np.diff(p, axis=0).T)
    cum = np.concatenate([[0.0], np.cumsum(legs)])
    n_wp = p.shape[0]
    total = cum[-1]
    # Corner element extents: (s_a, s_k, s_b) around each interior waypoint k.
    corners = []
    for k in range(1, n_wp - 1):
        before = legs[k - 1] if k == 1 else legs[k - 1] / 2.0
        after = legs[k] if k == n_wp - 2 else legs[k] / 2.0
        a = min(segment_m, before)
        b = min(segment_m, after)
        corners.append((cum[k] - a, cum[k], cum[k] + b, a < segment_m - 1e-3 or b < segment_m - 1e-3))
    # Straight stretches between corners (and the plan ends) → pieces of 2 L.
    pieces: list[tuple[float, float, float, str, bool]] = []
    edges = [(0.0, 0.0)] + [(c[0], c[2]) for c in corners] + [(total, total)]
    for j in range(len(edges) - 1):
        s0 = edges[j][1]
        s1 = edges[j + 1][0]
        stretch = []
        s = s0
        # Comparisons carry a 1 mm tolerance so that plans of round lengths give the same
        # elements after a geodetic round trip (floating-point noise of ~1e-5 m).
        while s1 - s > 1e-3:
            e = min(s + 2 * segment_m, s1)
            # Do not leave a sliver shorter than L/2 at the end of a stretch: merge it.
            if s1 - e <= 0.5 * segment_m + 1e-3 and e < s1:
                e = s1
            stretch.append((s, (s + e) / 2.0, e, "straight", False))
            s = e
        pieces.extend(stretch)
        if j < len(corners):
            c = corners[j]
            pieces.append((c[0], c[1], c[2], "corner", c[3]))
    pieces.sort(key=lambda q: q[0])
    kinds = [q[3] for q in pieces]
    if kinds[0] == "straight":
        kinds[0] = "start"
    if kinds[-1] == "straight":
        kinds[-1] = "end"
    s_start = np.array([q[0] for q in pieces])
    s_mid = np.array([q[1] for q in pieces])
    s_end = np.array([q[2] for q in pieces])
    start = _points_at(p, cum, s_start)
    mid = _points_at(p, cum, s_mid)
    end = _points_at(p, cum, s_end)
    v1 = mid - start
    v2 = end - mid
    turn = np.where(
        np.array([k == "corner" for k in kinds]),
        signed_angle_deg(v1, v2),
        0.0,
    )
    leg = np.clip(np.searchsorted(cum, s_start + 1e-9, side="right") - 1, 0, n_wp - 2)
    return Elements(
        start_ne=start,
        mid_ne=mid,
        end_ne=end,
        s_start_m=s_start,
        s_end_m=s_end,
        length_m=s_end - s_start,
        heading1_deg=heading_deg(v1),
        turn_deg=turn,
        kind=np.array(kinds),
        shortened=np.array([q[4] for q in pieces], dtype=bool),
        leg=leg.astype(int),
    )


def plan_length(plan_ne: np.ndarray) -> float:
    """Total path length of a plan, m."""
    p = np.asarray(plan_ne, dtype=float)[:, :2]
    return float(np.hypot(*np.diff(p, axis=0).T).sum())


def arc_length_along(plan_ne: np.ndarray, pos_ne: np.ndarray, lookahead: int = 1) -> np.ndarray:
    """Arc length along the plan of the projection of each position, m.

    Positions are taken in time order and projected onto the current leg or the next
    ``lookahead`` legs only (the nearest of those), and the leg index never decreases: a plan
    whose legs cross or pass near each other is followed leg by leg rather than jumping to
    whichever leg happens to be nearest. The result is made non-decreasing (a vehicle flying
    the plan does not go back along it; this removes jitter of noisy fixes).
    """
    p = np.asarray(plan_ne, dtype=float)[:, :2]
    x = np.asarray(pos_ne, dtype=float)[:, :2]
    a = p[:-1]
    d = np.diff(p, axis=0)
    seg_len = np.hypot(d[:, 0], d[:, 1])
    cum = np.concatenate([[0.0], np.cumsum(seg_len)])
    n_leg = seg_len.size
    check_work(
        float(x.shape[0]) * n_leg * 20.0,
        f"projecting {x.shape[0]} positions on a plan of {n_leg} legs",
        option="the telemetry or the plan",
    )
    # Projection of every position on every leg (vectorised), then a sequential pass; done in
    # blocks of positions so that memory stays bounded (≈ 64 MiB) whatever the telemetry length.
    block = max(1, (64 << 20) // (_BYTES_PER_PAIR * max(n_leg, 1)))
    check_memory(
        float(min(block, x.shape[0])) * n_leg * _BYTES_PER_PAIR + x.nbytes,
        f"projecting positions on a plan of {n_leg} legs",
        option="the number of waypoints",
    )
    j = 0
    s = np.empty(x.shape[0])
    for b0 in range(0, x.shape[0], block):
        xb = x[b0 : b0 + block]
        rel = xb[:, None, :] - a[None, :, :]
        u = np.clip((rel * d[None]).sum(-1) / seg_len**2, 0.0, 1.0)
        proj = a[None] + u[..., None] * d[None]
        dist = np.hypot(*(xb[:, None, :] - proj).transpose(2, 0, 1))
        for i in range(xb.shape[0]):
            hi = min(j + lookahead + 1, n_leg)
            # Advance to a later leg only once the current one is (nearly) complete or the
            # later leg is strictly nearer.
            k = j + int(np.argmin(dist[i, j:hi]))
            j = k
            s[b0 + i] = cum[j] + u[i, j] * seg_len[j]
    return np.maximum.accumulate(s)


__all__ = [
    "DEFAULT_SEGMENT_M",
    "KINDS",
    "Elements",
    "arc_length_along",
    "check_element_count",
    "check_plan",
    "discretise",
    "element_count_bound",
    "geodetic_to_local",
    "heading_deg",
    "merge_short_legs",
    "plan_length",
    "signed_angle_deg",
]
