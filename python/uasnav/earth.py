"""WGS-84 Earth model: normal gravity and Earth rotation in the local NED frame.

Conventions: latitude φ geodetic (rad), height h above the ellipsoid (m), NED navigation frame
(north, east, down). Gravity is returned down-positive, so a unit at rest measures the
specific force ``f = −g_ned = [0, 0, −g]`` (accelerometer "up" reaction).

References
----------
P. D. Groves, *Principles of GNSS, Inertial, and Multisensor Integrated Navigation Systems*,
2nd ed., Artech House (2013): eq. 2.134 (Somigliana normal gravity on the ellipsoid) and
eq. 2.139 (second-order free-air height correction).
NIMA TR8350.2, *Department of Defense World Geodetic System 1984*, 3rd ed. (2000), Table 3.1–3.3
(the constants live in :mod:`uasnav.geo.wgs84`).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from uasnav.errors import InputError
from uasnav.geo.wgs84 import OMEGA_IE, WGS84_A, WGS84_B, WGS84_E2, WGS84_F, WGS84_MU

#: Normal gravity at the equator (m/s²), WGS-84.
GAMMA_EQUATOR = 9.7803253359
#: Largest |height| (m) the free-air series is used for (the top of the atmosphere; far above,
#: it returns a number that only looks like gravity). Same bound as nav_core::earth.
MAX_HEIGHT_M = 100_000.0


def _latitude(latitude_rad: float) -> float:
    """A geodetic latitude (rad), finite and within ±π/2, or :class:`InputError`."""
    lat = float(latitude_rad)
    if not abs(lat) <= math.pi / 2:
        raise InputError(f"latitude_rad: must be finite and within ±π/2 rad, got {latitude_rad!r}")
    return lat


#: Somigliana constant k = (b·γ_p)/(a·γ_e) − 1, WGS-84.
SOMIGLIANA_K = 0.00193185265241


def normal_gravity(latitude_rad: float, height_m: float = 0.0) -> float:
    """WGS-84 normal gravity magnitude (m/s²) at geodetic latitude and ellipsoidal height.

    Somigliana's closed form on the ellipsoid, then the second-order free-air correction
    ``γ(h) = γ₀ [1 − 2/a (1 + f + m − 2 f sin²φ) h + 3 h²/a²]`` (Groves eq. 2.139), with
    ``m = ω_ie² a² b / GM``.

    Parameters
    ----------
    latitude_rad : float
        Geodetic latitude φ (rad).
    height_m : float
        Height above the WGS-84 ellipsoid (m).

    Returns
    -------
    float
        |g| (m/s²); 9.780 m/s² at the equator, 9.832 m/s² at the poles (h = 0).
    """
    h = float(height_m)
    # NaN compares false: test for the valid range, so NaN, inf and absurd heights all fail.
    if not abs(h) <= MAX_HEIGHT_M:
        raise InputError(f"height_m: must be within ±{MAX_HEIGHT_M:g} m of the ellipsoid, got {height_m!r}")
    s2 = math.sin(_latitude(latitude_rad)) ** 2
    g0 = GAMMA_EQUATOR * (1.0 + SOMIGLIANA_K * s2) / math.sqrt(1.0 - WGS84_E2 * s2)
    m = OMEGA_IE**2 * WGS84_A**2 * WGS84_B / WGS84_MU
    return g0 * (
        1.0 - 2.0 / WGS84_A * (1.0 + WGS84_F + m - 2.0 * WGS84_F * s2) * h + 3.0 * h * h / WGS84_A**2
    )


def earth_rate_ned(latitude_rad: float) -> NDArray[np.float64]:
    """Earth rotation ω_ie resolved in NED (rad/s): ``ω_ie · [cos φ, 0, −sin φ]``, shape (3,)."""
    lat = _latitude(latitude_rad)
    return OMEGA_IE * np.array([math.cos(lat), 0.0, -math.sin(lat)])


def gravity_ned(latitude_rad: float, height_m: float = 0.0) -> NDArray[np.float64]:
    """Normal gravity vector in NED (m/s²), down positive: ``[0, 0, γ(φ, h)]``, shape (3,).

    The small north component of plumb-line gravity (centrifugal deflection, < 1e-5 g with
    normal gravity defined along the ellipsoid normal) is zero by construction.
    """
    return np.array([0.0, 0.0, normal_gravity(latitude_rad, height_m)])


__all__ = [
    "GAMMA_EQUATOR",
    "OMEGA_IE",
    "SOMIGLIANA_K",
    "WGS84_A",
    "WGS84_B",
    "WGS84_E2",
    "WGS84_F",
    "WGS84_MU",
    "earth_rate_ned",
    "gravity_ned",
    "normal_gravity",
]
