"""Altitudes of a plan in the WGS-84 ellipsoidal frame (``W84``) that ASTM F3548 requires.

h_W84 = H_AMSL + N, with N the geoid height (undulation) at the place, m. A plan's altitudes
are relative to home (h = home AMSL + alt + N), AMSL (h = alt + N) or above terrain (refused:
that needs a terrain model). N varies from −106 m to +85 m over the Earth: it is never assumed
to be 0. uasnav ships no geoid model and no installed offline package provides one (the EGM96
and EGM2008 grids are not on PyPI with their data), so N is the user's to give
(``--geoid-height``, e.g. from GeographicLib's ``GeoidEval`` or the national geodetic agency).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from uasnav.errors import InputError
from uasnav.io.mission_plan import AltitudeFrame, RoutePoint

#: Largest |N| on Earth (EGM2008 ranges from about −107 m to +86 m), with a margin.
MAX_GEOID_HEIGHT_M = 120.0


def w84_altitudes(
    points: Sequence[RoutePoint],
    *,
    home_amsl_m: float | None,
    geoid_height_m: float | None,
    source: str = "plan",
) -> np.ndarray:
    """Ellipsoidal altitudes (m, W84) of route points.

    Raises
    ------
    InputError
        A terrain-relative altitude; a relative altitude without the home AMSL altitude; any
        altitude without the geoid height; a geoid height beyond ±120 m.
    """
    frames = {p.frame for p in points}
    if AltitudeFrame.TERRAIN in frames:
        raise InputError(
            f"{source}: altitudes above terrain cannot be converted to W84 without a terrain model"
        )
    if geoid_height_m is None:
        raise InputError(
            f"{source}: F3548 altitudes are WGS-84 ellipsoidal and the plan's are "
            f"{' and '.join(sorted(f.value for f in frames))}: give the geoid height N at the site "
            "(--geoid-height, m; W84 = AMSL + N); uasnav never assumes N = 0"
        )
    if not (math.isfinite(geoid_height_m) and abs(geoid_height_m) <= MAX_GEOID_HEIGHT_M):
        raise InputError(f"geoid height {geoid_height_m!r} m is outside ±{MAX_GEOID_HEIGHT_M:g} m")
    if AltitudeFrame.RELATIVE in frames and (home_amsl_m is None or not math.isfinite(home_amsl_m)):
        raise InputError(
            f"{source}: relative altitudes need the home altitude above mean sea level: the plan has none "
            "(give --home-alt, m AMSL)"
        )
    out = np.empty(len(points))
    for i, p in enumerate(points):
        base = home_amsl_m if (p.frame is AltitudeFrame.RELATIVE and home_amsl_m is not None) else 0.0
        out[i] = base + p.alt_m + geoid_height_m
    return out


__all__ = ["MAX_GEOID_HEIGHT_M", "w84_altitudes"]
