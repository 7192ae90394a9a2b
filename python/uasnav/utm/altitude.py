"""Altitudes of a plan in the WGS-84 ellipsoidal frame (``W84``) that ASTM F3548 requires.

h_W84 = H_AMSL + N, with N the geoid height (undulation) at the place, m. A plan's altitudes
are relative to home (h = home AMSL + alt + N), AMSL (h = alt + N) or above terrain (refused:
that needs a terrain model). N varies from −106 m to +85 m over the Earth: it is never assumed
to be 0.

N comes from the user (``geoid_height_m``, ``--geoid-height``: one value for the site, e.g. from
a national geoid model) or, by default, from the EGM96 geoid at each route point:
:func:`uasnav.geo.geoid.geoid_height`, NGA's 15′ grid shipped with uasnav and interpolated
bilinearly (as PROJ's ``vgridshift`` does; no PROJ data needed). Against GeographicLib's
``GeoidEval`` (EGM96, 5′ grid, cubic) it agrees to 1 cm at Timbuktu and at the grid's corners
and centre (``tests/test_geoid.py``); EGM96 itself is good to about 0.5–1 m.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from importlib import resources

import numpy as np

from uasnav.errors import InputError
from uasnav.geo import geoid
from uasnav.io.mission_plan import AltitudeFrame, RoutePoint

#: Largest |N| on Earth (EGM2008 ranges from about −107 m to +86 m), with a margin.
MAX_GEOID_HEIGHT_M = 120.0
#: The geoid grid used when N is not given (package data of :mod:`uasnav.geo.geoid`).
GEOID_GRID = geoid.GEOID_DATA
#: What :func:`geoid_heights` evaluates, as reported to the user (``--json`` key ``geoid``).
GEOID_MODEL = geoid.GEOID_MODEL


def geoid_grid_path() -> str | None:
    """Path of the EGM96 grid shipped with uasnav (:data:`GEOID_GRID`), or None if the
    installation lacks it."""
    p = resources.files("uasnav.geo").joinpath("data", GEOID_GRID)
    return str(p) if p.is_file() else None


def geoid_model() -> str | None:
    """:data:`GEOID_MODEL` if its grid is installed, else None."""
    return GEOID_MODEL if geoid_grid_path() is not None else None


def geoid_heights(lat_deg: np.ndarray, lon_deg: np.ndarray) -> np.ndarray:
    """EGM96 geoid heights N (m above the WGS-84 ellipsoid) at WGS-84 positions (degrees).

    Raises
    ------
    InputError
        The grid is missing from the installation, or a position is not finite / beyond ±90°.
    """
    if geoid_grid_path() is None:
        raise InputError(
            f"no geoid model installed: the EGM96 grid {GEOID_GRID} is missing; reinstall uasnav"
        )
    return np.asarray(geoid.geoid_height(lat_deg, lon_deg), dtype=float)


def w84_altitudes(
    points: Sequence[RoutePoint],
    *,
    home_amsl_m: float | None,
    geoid_height_m: float | None,
    source: str = "plan",
) -> np.ndarray:
    """Ellipsoidal altitudes (m, W84) of route points.

    ``geoid_height_m`` None: N of the EGM96 geoid at each point (:func:`geoid_heights`).

    Raises
    ------
    InputError
        A terrain-relative altitude; a relative altitude without the home AMSL altitude; any
        altitude without the geoid height when no geoid grid is installed; a geoid height beyond
        ±120 m.
    """
    frames = {p.frame for p in points}
    if AltitudeFrame.TERRAIN in frames:
        raise InputError(
            f"{source}: altitudes above terrain cannot be converted to W84 without a terrain model"
        )
    if geoid_height_m is None:
        if geoid_grid_path() is None:
            raise InputError(
                f"{source}: F3548 altitudes are WGS-84 ellipsoidal and the plan's are "
                f"{' and '.join(sorted(f.value for f in frames))}: give the geoid height N at the site "
                f"(--geoid-height, m; W84 = AMSL + N) or reinstall uasnav (its EGM96 grid {GEOID_GRID} "
                "is missing); uasnav never assumes N = 0"
            )
        n = geoid_heights(np.array([p.lat_deg for p in points]), np.array([p.lon_deg for p in points]))
        return _w84(points, home_amsl_m, n, source)
    if not (math.isfinite(geoid_height_m) and abs(geoid_height_m) <= MAX_GEOID_HEIGHT_M):
        raise InputError(f"geoid height {geoid_height_m!r} m is outside ±{MAX_GEOID_HEIGHT_M:g} m")
    return _w84(points, home_amsl_m, np.full(len(points), float(geoid_height_m)), source)


def _w84(points: Sequence[RoutePoint], home_amsl_m: float | None, n: np.ndarray, source: str) -> np.ndarray:
    if any(p.frame is AltitudeFrame.RELATIVE for p in points) and (
        home_amsl_m is None or not math.isfinite(home_amsl_m)
    ):
        raise InputError(
            f"{source}: relative altitudes need the home altitude above mean sea level: the plan has none "
            "(give --home-alt, m AMSL)"
        )
    out = np.empty(len(points))
    for i, p in enumerate(points):
        base = home_amsl_m if (p.frame is AltitudeFrame.RELATIVE and home_amsl_m is not None) else 0.0
        out[i] = base + p.alt_m + n[i]
    return out


__all__ = [
    "GEOID_GRID",
    "GEOID_MODEL",
    "MAX_GEOID_HEIGHT_M",
    "geoid_grid_path",
    "geoid_heights",
    "geoid_model",
    "w84_altitudes",
]
