"""WGS-84 defining and derived constants (NIMA TR8350.2, 3rd ed., Tables 3.1–3.3).

The one place these numbers live: :mod:`uasnav.earth` (gravity, Earth rate) and
:mod:`uasnav.geo.frames` (coordinate conversions) use them.
"""

from __future__ import annotations

#: Semi-major axis a (m).
WGS84_A = 6378137.0
#: Flattening f.
WGS84_F = 1.0 / 298.257223563
#: First eccentricity squared e² = f (2 − f).
WGS84_E2 = WGS84_F * (2.0 - WGS84_F)
#: Semi-minor axis b = a (1 − f) (m).
WGS84_B = WGS84_A * (1.0 - WGS84_F)
#: Earth gravitational constant GM (m³/s²).
WGS84_MU = 3.986004418e14
#: Earth rotation rate ω_ie (rad/s).
OMEGA_IE = 7.292115e-5

__all__ = ["OMEGA_IE", "WGS84_A", "WGS84_B", "WGS84_E2", "WGS84_F", "WGS84_MU"]
