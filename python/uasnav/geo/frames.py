"""Coordinate conversions between geodetic (WGS-84 latitude, longitude, ellipsoidal height),
ECEF and local tangent frames, through one implementation (pymap3d).

Local frames are explicit in the names: NED (north, east, down) — the navigation frame of the
filter and the mission planner — and ENU (east, north, up) — the frame of the airspace
geometry. Angles in degrees, lengths in metres; heights are ellipsoidal (a caller with an AMSL
height converts it first, :mod:`uasnav.geo.datum`). Arrays broadcast like numpy.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav.geo.wgs84 import WGS84_A, WGS84_E2

FloatArray = NDArray[np.float64]
Triple = tuple[Any, Any, Any]


def _pm() -> Any:
    import pymap3d

    return pymap3d


def geodetic_to_ned(
    lat: ArrayLike, lon: ArrayLike, h: ArrayLike, lat0: float, lon0: float, h0: float
) -> Triple:
    """(north, east, down) m of points (deg, deg, m ellipsoidal) from the origin (lat0, lon0, h0)."""
    return _pm().geodetic2ned(lat, lon, h, lat0, lon0, h0)  # type: ignore[no-any-return]


def ned_to_geodetic(n: ArrayLike, e: ArrayLike, d: ArrayLike, lat0: float, lon0: float, h0: float) -> Triple:
    """(lat, lon, h) deg, deg, m ellipsoidal of NED offsets (m) from the origin (lat0, lon0, h0)."""
    return _pm().ned2geodetic(n, e, d, lat0, lon0, h0)  # type: ignore[no-any-return]


def geodetic_to_enu(
    lat: ArrayLike, lon: ArrayLike, h: ArrayLike, lat0: float, lon0: float, h0: float
) -> Triple:
    """(east, north, up) m of points (deg, deg, m ellipsoidal) from the origin (lat0, lon0, h0)."""
    return _pm().geodetic2enu(lat, lon, h, lat0, lon0, h0)  # type: ignore[no-any-return]


def enu_to_geodetic(e: ArrayLike, n: ArrayLike, u: ArrayLike, lat0: float, lon0: float, h0: float) -> Triple:
    """(lat, lon, h) deg, deg, m ellipsoidal of ENU offsets (m) from the origin (lat0, lon0, h0)."""
    return _pm().enu2geodetic(e, n, u, lat0, lon0, h0)  # type: ignore[no-any-return]


def geodetic_to_ecef(lat: ArrayLike, lon: ArrayLike, h: ArrayLike) -> Triple:
    """ECEF (x, y, z) m of points (deg, deg, m ellipsoidal)."""
    return _pm().geodetic2ecef(lat, lon, h)  # type: ignore[no-any-return]


def ecef_to_geodetic(x: ArrayLike, y: ArrayLike, z: ArrayLike) -> Triple:
    """(lat, lon, h) deg, deg, m ellipsoidal of ECEF points (m)."""
    return _pm().ecef2geodetic(x, y, z)  # type: ignore[no-any-return]


def radii_of_curvature(lat: ArrayLike, *, degrees: bool = True) -> tuple[Any, Any]:
    """Meridian (north–south) and prime-vertical (east–west) radii of curvature (m) at geodetic
    latitude ``lat`` (degrees, or radians with ``degrees=False``; Groves eqs. 2.105–2.106).
    A scalar gives floats, an array arrays."""
    if np.ndim(lat) == 0:
        phi = math.radians(float(lat)) if degrees else float(lat)  # type: ignore[arg-type]
        d = 1.0 - WGS84_E2 * math.sin(phi) ** 2
        r_e = WGS84_A / math.sqrt(d)
        return r_e * (1.0 - WGS84_E2) / d, r_e
    a = np.asarray(lat, dtype=np.float64)
    s2 = np.sin(np.radians(a) if degrees else a) ** 2
    dd = 1.0 - WGS84_E2 * s2
    re = WGS84_A / np.sqrt(dd)
    return re * (1.0 - WGS84_E2) / dd, re


__all__ = [
    "ecef_to_geodetic",
    "enu_to_geodetic",
    "geodetic_to_ecef",
    "geodetic_to_enu",
    "geodetic_to_ned",
    "ned_to_geodetic",
    "radii_of_curvature",
]
