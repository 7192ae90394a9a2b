"""A second implementation of the encounter search in Python with shapely's ``STRtree``.

The reference the Rust index (:func:`uasnav.utm.deconflict.encounters`) is tested and
benchmarked against: shapely builds an R-tree (sort-tile-recursive) of the outlines, queries
each outline grown by the horizontal buffer, and the candidates are filtered by time overlap,
intent, vertical gap and shapely's exact distance (GEOS). Circles are exact: their distance is
the centre's distance minus the radius (never a polygonised buffer).
"""

from __future__ import annotations

import numpy as np

from uasnav.utm.volumes import VolumeArrays


def _geometries(v: VolumeArrays) -> tuple[list, np.ndarray]:
    import shapely

    geoms = []
    radius = np.zeros(len(v))
    for i in range(len(v)):
        a, b = int(v.offsets[i]), int(v.offsets[i + 1])
        if b > a:
            geoms.append(shapely.Polygon(v.vertices_m[a:b]))
        else:
            geoms.append(shapely.Point(v.circle_m[i, :2]))
            radius[i] = v.circle_m[i, 2]
    return geoms, radius


def strtree_encounters(
    v: VolumeArrays, horizontal_m: float = 0.0, vertical_m: float = 0.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Encounters as :func:`uasnav.utm.deconflict.encounters` returns them: pairs (k, 2)
    sorted, overlap (k, 2) s, distances (k, 2) m."""
    import shapely

    geoms, radius = _geometries(v)
    # an R-tree of the outlines' boxes (circles: centre ± radius), queried with each box grown
    # by the buffer: a superset of the candidates; exact filters follow
    b = shapely.bounds(np.array(geoms, dtype=object))
    r = radius[:, None]
    tree = shapely.STRtree(shapely.box(*(b[:, :2] - r).T, *(b[:, 2:] + r).T))
    h = radius[:, None] + horizontal_m
    boxes = shapely.box(*(b[:, :2] - h).T, *(b[:, 2:] + h).T)
    qi, qj = tree.query(boxes)
    keep = qi < qj
    qi, qj = qi[keep], qj[keep]
    t0 = np.maximum(v.time_s[qi, 0], v.time_s[qj, 0])
    t1 = np.minimum(v.time_s[qi, 1], v.time_s[qj, 1])
    gap = np.maximum(
        np.maximum(v.alt_m[qi, 0], v.alt_m[qj, 0]) - np.minimum(v.alt_m[qi, 1], v.alt_m[qj, 1]), 0.0
    )
    ok = (v.intent[qi] != v.intent[qj]) & (t0 < t1) & (gap <= vertical_m)
    qi, qj, t0, t1, gap = qi[ok], qj[ok], t0[ok], t1[ok], gap[ok]
    ga = np.array(geoms, dtype=object)
    d = np.maximum(shapely.distance(ga[qi], ga[qj]) - radius[qi] - radius[qj], 0.0)
    near = d <= horizontal_m
    pairs = np.column_stack([qi[near], qj[near]]).astype(np.uint32)
    order = np.lexsort((pairs[:, 1], pairs[:, 0])) if pairs.size else np.zeros(0, dtype=int)
    return (
        pairs[order].reshape(-1, 2),
        np.column_stack([t0[near], t1[near]])[order].reshape(-1, 2),
        np.column_stack([d[near], gap[near]])[order].reshape(-1, 2),
    )


__all__ = ["strtree_encounters"]
