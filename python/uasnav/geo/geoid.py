"""The EGM96 geoid: geoid height N (m) above the WGS-84 ellipsoid, shipped with the package.

Heights: ``h_ellipsoid = H_AMSL + N`` (m), with ``H_AMSL`` an orthometric height above the EGM96
geoid (mean sea level) and ``h_ellipsoid`` above the WGS-84 ellipsoid. N ranges from about
−107 m (south of India) to +85 m (New Guinea): it is never assumed to be 0.

The grid is NGA's EGM96 geoid on a 15′ lattice (721 × 1440 nodes, 90° S → 90° N and
180° W → 179.75° E, longitudes wrapping), the one PROJ distributes as ``egm96_15.gtx``. It is
package data (``uasnav/geo/data/egm96_15.npy.xz``, ≈ 0.5 MB): int16 centimetres, rounded to
≤ 5 mm, differenced along longitude and latitude and xz-compressed
(``scripts/make_geoid_grid.py`` derives it from ``egm96_15.gtx``). EGM96 is a work of the U.S.
Government (NGA, NASA GSFC and Ohio State University) and in the public domain. No PROJ
installation, network or ``proj-data`` package is needed.

Interpolation is bilinear in latitude and longitude between the four surrounding nodes, as
PROJ's ``vgridshift`` does on this grid: the two agree to the grid's rounding (≤ 5 mm). Against
GeographicLib's ``GeoidEval`` (EGM96 5′ grid, cubic) it agrees to 1 cm at Timbuktu and at the
grid's corners and centre (``tests/test_geoid.py``); EGM96 itself is good to about 0.5–1 m.

>>> round(float(geoid_height(16.775833, -3.009444)), 2)  # Timbuktu (GeoidEval: 28.7068 m)
28.71
>>> geoid_height([0.0, 90.0], [0.0, 180.0]).round(2).tolist()
[17.16, 13.61]
"""

from __future__ import annotations

import functools
import io
import lzma
from importlib import resources

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav.errors import InputError

#: What :func:`geoid_height` evaluates, as reported to users.
GEOID_MODEL = "EGM96 (NGA 15′ grid, bilinear)"
#: The package data file holding the grid.
GEOID_DATA = "egm96_15.npy.xz"
#: Grid spacing (degrees) and the south-west node (latitude, longitude in degrees).
STEP_DEG = 0.25
SOUTH_WEST_DEG = (-90.0, -180.0)
#: Grid shape (latitude rows, longitude columns); the column after the last is the first.
SHAPE = (721, 1440)


@functools.cache
def geoid_grid() -> NDArray[np.float64]:
    """The EGM96 15′ grid, N in metres, shape (721, 1440): row i at latitude −90° + i/4,
    column j at longitude −180° + j/4.

    Raises
    ------
    InputError
        The package data file is missing or damaged (a broken installation).
    """
    try:
        packed = resources.files("uasnav.geo").joinpath("data", GEOID_DATA).read_bytes()
        diff = np.load(io.BytesIO(lzma.decompress(packed)), allow_pickle=False)
    except (OSError, lzma.LZMAError, ValueError) as e:
        raise InputError(
            f"the EGM96 geoid grid of this uasnav installation ({GEOID_DATA}) is missing or damaged "
            f"({e}); reinstall uasnav"
        ) from None
    if diff.shape != SHAPE:
        raise InputError(f"the EGM96 geoid grid {GEOID_DATA} has shape {diff.shape}, expected {SHAPE}")
    # the file holds differences along longitude then latitude: undo them (exact in integers)
    cm = np.cumsum(np.cumsum(diff.astype(np.int32), axis=0), axis=1)
    grid = cm / 100.0
    grid.flags.writeable = False
    return grid


def geoid_height(lat_deg: ArrayLike, lon_deg: ArrayLike) -> float | NDArray[np.float64]:
    """EGM96 geoid height N (m above the WGS-84 ellipsoid) at WGS-84 latitudes and longitudes.

    Parameters
    ----------
    lat_deg : float or array_like
        Latitudes (degrees), within [−90, 90].
    lon_deg : float or array_like
        Longitudes (degrees), any value (wrapped to [−180, 180)); broadcast against ``lat_deg``.

    Returns
    -------
    float or ndarray
        N (m): a float for scalar inputs, else an array of the broadcast shape.
        ``h_ellipsoid = H_AMSL + N``.

    Raises
    ------
    InputError
        A position that is not finite, or a latitude beyond ±90°.
    """
    try:
        lat = np.asarray(lat_deg, dtype=np.float64)
        lon = np.asarray(lon_deg, dtype=np.float64)
        lat, lon = np.broadcast_arrays(lat, lon)
    except (TypeError, ValueError) as e:
        raise InputError(
            f"geoid height: latitudes/longitudes must be numbers of matching shapes ({e})"
        ) from None
    if not (np.all(np.isfinite(lat)) and np.all(np.isfinite(lon)) and np.all(np.abs(lat) <= 90)):
        raise InputError("geoid height: latitudes/longitudes must be finite, |latitude| ≤ 90°")
    grid = geoid_grid()
    rows, cols = SHAPE
    y = (lat - SOUTH_WEST_DEG[0]) / STEP_DEG
    x = np.mod(lon - SOUTH_WEST_DEG[1], 360.0) / STEP_DEG
    i = np.minimum(np.floor(y).astype(np.intp), rows - 2)  # 90° N: the top row, weight 1
    j = np.floor(x).astype(np.intp) % cols
    fy = y - i
    fx = x - np.floor(x)
    j1 = (j + 1) % cols  # 179.75° E → 180° W
    n = (1.0 - fy) * ((1.0 - fx) * grid[i, j] + fx * grid[i, j1]) + fy * (
        (1.0 - fx) * grid[i + 1, j] + fx * grid[i + 1, j1]
    )
    return float(n) if n.ndim == 0 else n


__all__ = ["GEOID_DATA", "GEOID_MODEL", "SHAPE", "SOUTH_WEST_DEG", "STEP_DEG", "geoid_grid", "geoid_height"]
