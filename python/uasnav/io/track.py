"""Navigation-track files: TRACK.csv, GeoJSON and KML of a navigation solution, and its plot.

The writers take any object with the per-row histories of a navigation solution
(:class:`NavTrack`; :class:`uasnav.ins.InsResult` is one) and write atomically.

========== =========================== ===================================================
file       writer                      content
========== =========================== ===================================================
TRACK.csv  :func:`write_track_csv`     :data:`TRACK_COLUMNS`, 17 significant digits
.geojson   :func:`write_track_geojson` :func:`track_geojson`: LineString + event Points
.kml       :func:`write_track_kml`     LineString, absolute altitude (ellipsoidal height)
========== =========================== ===================================================

Heights are ellipsoidal (WGS-84) in every file; coordinates are degrees (lon, lat order in
GeoJSON and KML, as both formats require).
"""

from __future__ import annotations

import json
import math
import os
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from numpy.typing import NDArray

from uasnav.atomicfile import atomic_open

if TYPE_CHECKING:
    from matplotlib.axes import Axes

FloatArray = NDArray[np.float64]

#: TRACK.csv columns (SI; degrees only for lat/lon/roll/pitch/yaw).
TRACK_COLUMNS = "t,lat,lon,alt,vn,ve,vd,roll,pitch,yaw,bgx,bgy,bgz,bax,bay,baz,hpl,vpl,gnss_used".split(",")


class NavTrack(Protocol):
    """What the writers read: per-row histories (row ``i`` at time ``t[i]``) and events."""

    #: Time (s), latitude and longitude (degrees), ellipsoidal height (m), shape (n,).
    t: FloatArray
    lat: FloatArray
    lon: FloatArray
    alt: FloatArray
    #: NED velocity (m/s), roll/pitch/yaw 3-2-1 (degrees), gyro (rad/s) and accelerometer
    #: (m/s²) bias in the body frame, shape (n, 3).
    vel: FloatArray
    euler_deg: FloatArray
    gyro_bias: FloatArray
    accel_bias: FloatArray
    #: Horizontal and vertical protection levels (m), shape (n,).
    hpl: FloatArray
    vpl: FloatArray
    #: A GNSS fix was used since the previous row, shape (n,).
    gnss_used: NDArray[np.bool_]

    @property
    def excluded_fixes(self) -> list[dict[str, Any]]:
        """Excluded GNSS fixes: ``t`` (s) and further properties."""
        ...

    @property
    def alerts(self) -> list[dict[str, Any]]:
        """Alert intervals: ``t_start`` (s) and further properties."""
        ...


def track_table(track: NavTrack) -> FloatArray:
    """The TRACK.csv rows, shape (n, 19), in :data:`TRACK_COLUMNS` order."""
    return np.column_stack(
        [
            track.t,
            track.lat,
            track.lon,
            track.alt,
            track.vel,
            track.euler_deg,
            track.gyro_bias,
            track.accel_bias,
            track.hpl,
            track.vpl,
            track.gnss_used.astype(np.float64),
        ]
    )


def write_track_csv(track: NavTrack, path: str | os.PathLike[str]) -> None:
    """Write TRACK.csv (columns :data:`TRACK_COLUMNS`, 17 significant digits, ``gnss_used``
    as 0/1), atomically."""
    table = track_table(track)
    with atomic_open(path, "w") as fh:
        fh.write(",".join(TRACK_COLUMNS) + "\n")
        for row in table:
            fh.write(",".join(f"{x:.17g}" for x in row[:-1]) + f",{int(row[-1])}\n")


def _decimated(n: int, max_points: int) -> NDArray[np.intp]:
    """Every ``ceil(n / max_points)``-th row index and the last one."""
    step = max(1, math.ceil(n / max_points))
    return np.unique(np.r_[np.arange(0, n, step), n - 1])


def track_geojson(track: NavTrack, max_points: int = 5000) -> dict[str, Any]:
    """A GeoJSON FeatureCollection: the track as a LineString (lon, lat, ellipsoidal height;
    decimated to at most ``max_points``), and a Point per excluded fix and per alert start."""
    coords = [
        [float(track.lon[i]), float(track.lat[i]), float(track.alt[i])]
        for i in _decimated(track.t.size, max_points)
    ]
    feats: list[dict[str, Any]] = [
        {
            "type": "Feature",
            "geometry": {"type": "LineString", "coordinates": coords},
            "properties": {
                "name": "uasnav INS track",
                "t_start": float(track.t[0]),
                "t_end": float(track.t[-1]),
            },
        }
    ]
    for ev in track.excluded_fixes:
        i = min(int(np.searchsorted(track.t, ev["t"])), track.t.size - 1)
        feats.append(
            {
                "type": "Feature",
                "geometry": {"type": "Point", "coordinates": [float(track.lon[i]), float(track.lat[i])]},
                "properties": {"event": "excluded_fix", **ev},
            }
        )
    for al in track.alerts:
        i = int(np.searchsorted(track.t, al["t_start"]))
        feats.append(
            {
                "type": "Feature",
                "geometry": {"type": "Point", "coordinates": [float(track.lon[i]), float(track.lat[i])]},
                "properties": {"event": "alert", **al},
            }
        )
    return {"type": "FeatureCollection", "features": feats}


def write_track_geojson(track: NavTrack, path: str | os.PathLike[str]) -> None:
    """Write :func:`track_geojson` atomically."""
    with atomic_open(path, "w") as fh:
        json.dump(track_geojson(track), fh)


def write_track_kml(track: NavTrack, path: str | os.PathLike[str], max_points: int = 5000) -> None:
    """Write the track as a KML LineString (absolute altitude = ellipsoidal height; decimated
    to at most ``max_points``), atomically."""
    from xml.sax.saxutils import escape

    idx = _decimated(track.t.size, max_points)
    coords = " ".join(f"{track.lon[i]:.9f},{track.lat[i]:.9f},{track.alt[i]:.3f}" for i in idx)
    with atomic_open(path, "w") as fh:
        fh.write(
            '<?xml version="1.0" encoding="UTF-8"?>\n<kml xmlns="http://www.opengis.net/kml/2.2">'
            f"<Document><name>{escape('uasnav INS track')}</name><Placemark><name>track</name>"
            f"<LineString><altitudeMode>absolute</altitudeMode><coordinates>{coords}</coordinates>"
            "</LineString></Placemark></Document></kml>\n"
        )


def plot_track(track: NavTrack, ax: Axes | None = None, *, reference: Any = None) -> Axes:
    """Plot the horizontal track (east vs north, m, WGS-84 local NED about the first point)
    with its excluded fixes; ``reference`` (anything with ``lat``, ``lon`` in degrees and a
    ``name``, e.g. the autopilot's estimate) is drawn beside it.

    Both are projected at the first point's height: the plot is horizontal, so heights (and
    their datums) play no part.
    """
    import matplotlib.pyplot as plt
    import pymap3d

    if ax is None:
        _, ax = plt.subplots(figsize=(6, 6))
    lat0, lon0, h0 = float(track.lat[0]), float(track.lon[0]), float(track.alt[0])

    def ne(lat: FloatArray, lon: FloatArray) -> tuple[FloatArray, FloatArray]:
        n, e, _ = pymap3d.geodetic2ned(lat, lon, h0, lat0, lon0, h0)
        return np.asarray(n, dtype=np.float64), np.asarray(e, dtype=np.float64)

    n, e = ne(track.lat, track.lon)
    ax.plot(e, n, lw=1.2, label="uasnav INS")
    if reference is not None:
        rn, re = ne(np.asarray(reference.lat), np.asarray(reference.lon))
        ax.plot(re, rn, lw=0.8, ls="--", label=reference.name)
    for ev in track.excluded_fixes:
        i = min(int(np.searchsorted(track.t, ev["t"])), track.t.size - 1)
        ax.plot(e[i], n[i], "rx")
    ax.set_xlabel("east (m)")
    ax.set_ylabel("north (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(loc="best")
    return ax
