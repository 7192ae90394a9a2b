"""4D volumes as arrays in a local plane: what the Rust space-time index takes.

:class:`VolumeArrays` holds n volumes of several intents in structure-of-arrays form:
``intent`` (n,) intent number, ``alt_m`` (n, 2) lower/upper altitude (m, W84), ``time_s``
(n, 2) start/end (s, Unix time), ``offsets`` (n + 1,) into ``vertices_m`` (m, 2) — the
polygon of volume i is ``vertices_m[offsets[i]:offsets[i+1]]`` — and ``circle_m`` (n, 3)
(x, y, radius) for volumes with an empty vertex range.

Horizontal coordinates are metres east/north in the ENU tangent plane at ``origin`` (the
centre of the data's latitude/longitude box, :func:`uasnav.geo.frames.geodetic_to_enu` at zero height). Over a
city (tens of km) the plane distorts distances between nearby points by less than
(d/R)² ≈ 10⁻⁵ relative; data spread over more than :data:`MAX_SPREAD_KM` is refused rather
than deconflicted in a badly distorted plane (split it by region). Polygon edges are straight
in the plane; F3548 defines them as shortest paths on the ellipsoid, which differ by
centimetres for edges of a few km.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from uasnav.errors import InputError
from uasnav.io.operational_intent import NamedIntent

#: Largest distance (km) of any vertex from the origin of the plane.
MAX_SPREAD_KM = 500.0


@dataclass(frozen=True)
class VolumeArrays:
    """Volumes of several intents as arrays (see module for the layout and units).

    ``names[k]`` is the name of intent k; ``first[k]`` the index of its first volume (volumes
    are grouped by intent, in order), so volume i is volume ``i - first[intent[i]]`` of its
    intent.
    """

    intent: np.ndarray
    alt_m: np.ndarray
    time_s: np.ndarray
    offsets: np.ndarray
    vertices_m: np.ndarray
    circle_m: np.ndarray
    names: tuple[str, ...]
    first: np.ndarray
    origin: tuple[float, float] = (0.0, 0.0)

    def __len__(self) -> int:
        return int(self.intent.size)

    def shifted(self, intent: int, delay_s: float) -> VolumeArrays:
        """A copy with the volumes of ``intent`` later by ``delay_s`` seconds."""
        t = self.time_s.copy()
        t[self.intent == intent] += delay_s
        return VolumeArrays(
            self.intent,
            self.alt_m,
            t,
            self.offsets,
            self.vertices_m,
            self.circle_m,
            self.names,
            self.first,
            self.origin,
        )


def _outline(v: Any) -> tuple[np.ndarray, np.ndarray | None]:
    """(lat, lon) arrays of a polygon, or of a circle's centre plus its radius."""
    vol = v.volume
    if vol.get("outline_polygon") is not None:
        pts = vol.outline_polygon.vertices
        return np.array([[p.lat, p.lng] for p in pts], dtype=float), None
    c = vol.outline_circle
    return np.array([[c.center.lat, c.center.lng]], dtype=float), np.array([float(c.radius.value)])


def volume_arrays(intents: Sequence[NamedIntent], off_nominal: bool = False) -> VolumeArrays:
    """Arrays of the ``volumes`` (and with ``off_nominal`` the ``off_nominal_volumes``) of
    ``intents`` (checked F3548 details, :mod:`uasnav.io.operational_intent`)."""
    from uasnav.geo import frames

    if not intents:
        raise InputError("no intents to deconflict")
    latlon: list[np.ndarray] = []
    radius: list[float] = []
    intent: list[int] = []
    alt: list[tuple[float, float]] = []
    time: list[tuple[float, float]] = []
    first: list[int] = []
    for k, it in enumerate(intents):
        first.append(len(intent))
        vols = list(it.details.volumes) + (
            list(it.details.get("off_nominal_volumes") or []) if off_nominal else []
        )
        for v in vols:
            pts, r = _outline(v)
            latlon.append(pts)
            radius.append(float("nan") if r is None else float(r[0]))
            intent.append(k)
            lo, hi = v.volume.altitude_lower.value, v.volume.altitude_upper.value
            alt.append((float(lo), float(hi)))
            time.append((v.time_start.value.datetime.timestamp(), v.time_end.value.datetime.timestamp()))
    allpts = np.vstack(latlon)
    lat0 = float((allpts[:, 0].min() + allpts[:, 0].max()) / 2)
    lon0 = float((allpts[:, 1].min() + allpts[:, 1].max()) / 2)
    if allpts[:, 1].max() - allpts[:, 1].min() > 180:
        raise InputError("intents on both sides of the antimeridian: deconflict each side separately")
    e, n, _ = frames.geodetic_to_enu(allpts[:, 0], allpts[:, 1], 0.0, lat0, lon0, 0.0)
    en = np.column_stack([e, n])
    spread = float(np.hypot(e, n).max()) / 1000
    if spread > MAX_SPREAD_KM:
        raise InputError(
            f"intents spread over {spread:.0f} km from their centre (more than {MAX_SPREAD_KM:g} km): "
            "a single local plane would distort them; deconflict each region separately"
        )
    offsets = [0]
    verts: list[np.ndarray] = []
    circle = np.zeros((len(intent), 3))
    row = 0
    for i, pts in enumerate(latlon):
        block = en[row : row + pts.shape[0]]
        row += pts.shape[0]
        if np.isnan(radius[i]):
            verts.append(block)
            offsets.append(offsets[-1] + block.shape[0])
        else:
            circle[i] = [block[0, 0], block[0, 1], radius[i]]
            offsets.append(offsets[-1])
    return VolumeArrays(
        intent=np.array(intent, dtype=np.uint32),
        alt_m=np.array(alt, dtype=float).reshape(-1, 2),
        time_s=np.array(time, dtype=float).reshape(-1, 2),
        offsets=np.array(offsets, dtype=np.uint64),
        vertices_m=np.vstack(verts) if verts else np.zeros((0, 2)),
        circle_m=circle,
        names=tuple(it.name for it in intents),
        first=np.array(first, dtype=np.int64),
        origin=(lat0, lon0),
    )


__all__ = ["MAX_SPREAD_KM", "VolumeArrays", "volume_arrays"]
