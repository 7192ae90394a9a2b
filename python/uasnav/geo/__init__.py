"""Geodesy and height datums of uasnav, in one place.

- :mod:`uasnav.geo.wgs84` — the WGS-84 constants (once).
- :mod:`uasnav.geo.frames` — geodetic ↔ ECEF ↔ local NED / ENU, all through pymap3d; the
  frame is in every function's name.
- :mod:`uasnav.geo.datum` — :class:`HeightDatum` (ellipsoid, AMSL, above home, above ground)
  and :class:`Height`; every height a log view or a comparison carries names its datum.
- :mod:`uasnav.geo.geoid` — the EGM96 geoid (import it directly: it loads a grid).
"""

from __future__ import annotations

from uasnav.geo.datum import Height, HeightDatum, receiver_undulation
from uasnav.geo.frames import (
    ecef_to_geodetic,
    enu_to_geodetic,
    geodetic_to_ecef,
    geodetic_to_enu,
    geodetic_to_ned,
    ned_to_geodetic,
    radii_of_curvature,
)
from uasnav.geo.wgs84 import OMEGA_IE, WGS84_A, WGS84_B, WGS84_E2, WGS84_F, WGS84_MU

__all__ = [
    "OMEGA_IE",
    "WGS84_A",
    "WGS84_B",
    "WGS84_E2",
    "WGS84_F",
    "WGS84_MU",
    "Height",
    "HeightDatum",
    "ecef_to_geodetic",
    "enu_to_geodetic",
    "geodetic_to_ecef",
    "geodetic_to_enu",
    "geodetic_to_ned",
    "ned_to_geodetic",
    "radii_of_curvature",
    "receiver_undulation",
]
