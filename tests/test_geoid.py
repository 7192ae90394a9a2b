"""EGM96 geoid heights (``uasnav.geo.geoid``, used by ``uasnav.utm.altitude`` for W84
altitudes) against GeographicLib's published ``GeoidEval`` values and PROJ's ``vgridshift``,
without PROJ installed, and the altitude conversion with and without a given N."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from uasnav.errors import InputError
from uasnav.geo import geoid
from uasnav.geo.geoid import geoid_grid, geoid_height
from uasnav.io.mission_plan import AltitudeFrame, RoutePoint
from uasnav.utm import altitude
from uasnav.utm.altitude import GEOID_MODEL, geoid_heights, geoid_model, w84_altitudes

# GeographicLib GeoidEval, EGM96 (egm96-5, cubic): its manual's example (Timbuktu,
# 16:46:33N 3:00:34W → 28.7068 m) and the grid's lower-left, centre and upper-right nodes.
GEOIDEVAL_EGM96 = [
    (16 + 46 / 60 + 33 / 3600, -(3 + 34 / 3600), 28.7068, 0.02),
    (-90.0, -180.0, -29.535, 0.01),
    (0.0, 0.0, 17.163, 0.01),
    (90.0, 180.0, 13.605, 0.01),
]


def test_geoid_heights_match_geographiclib():
    assert geoid_model() == GEOID_MODEL
    lat, lon, want, tol = (np.array(c) for c in zip(*GEOIDEVAL_EGM96, strict=True))
    got = geoid_heights(lat, lon)
    assert np.all(np.abs(got - want) <= tol), got - want
    # longitudes wrap: 180° W and 180° E are the same meridian
    assert geoid_heights(np.array([47.0]), np.array([-180.0]))[0] == pytest.approx(
        geoid_heights(np.array([47.0]), np.array([180.0]))[0], abs=1e-6
    )


def _pt(lat: float, lon: float, alt: float, frame: AltitudeFrame) -> RoutePoint:
    from uasnav.io.mission_plan import ItemKind

    return RoutePoint(
        lat_deg=lat,
        lon_deg=lon,
        alt_m=alt,
        frame=frame,
        hold_s=0.0,
        speed_ms=None,
        kind=ItemKind.WAYPOINT,
        item=None,
    )


def test_w84_altitudes_use_egm96_unless_n_is_given():
    tim = GEOIDEVAL_EGM96[0]
    pts = [_pt(tim[0], tim[1], 100.0, AltitudeFrame.AMSL), _pt(0.0, 0.0, 50.0, AltitudeFrame.RELATIVE)]
    z = w84_altitudes(pts, home_amsl_m=10.0, geoid_height_m=None)
    assert z == pytest.approx([100.0 + 28.7068, 10.0 + 50.0 + 17.163], abs=0.02)
    z = w84_altitudes(pts, home_amsl_m=10.0, geoid_height_m=-5.0)  # the user's N wins
    assert z == pytest.approx([95.0, 55.0])
    with pytest.raises(InputError, match="home altitude"):
        w84_altitudes(pts, home_amsl_m=None, geoid_height_m=None)


def test_without_the_grid_n_must_be_given(monkeypatch):
    # a broken installation (the package data removed): N must be given, never assumed 0
    monkeypatch.setattr(altitude, "geoid_grid_path", lambda: None)
    assert geoid_model() is None
    pts = [_pt(47.0, 8.0, 100.0, AltitudeFrame.AMSL)]
    with pytest.raises(InputError, match=r"--geoid-height.*never assumes N = 0"):
        w84_altitudes(pts, home_amsl_m=None, geoid_height_m=None)
    with pytest.raises(InputError, match="reinstall uasnav"):
        geoid_heights(np.array([47.0]), np.array([8.0]))
    assert w84_altitudes(pts, home_amsl_m=None, geoid_height_m=47.0) == pytest.approx([147.0])


# PROJ 9.5.1 (pyproj 3.7.2), "+proj=vgridshift +grids=egm96_15.gtx +multiplier=1" on Debian's
# proj-data grid: N (m) at places spread over the globe, the extremes of N (New Guinea, south of
# India), both poles' first rows and the antimeridian's last column.
PROJ_VGRIDSHIFT = [
    (47.0, 8.0, 48.3887),
    (-8.5, 147.0, 82.2135),
    (5.0, 78.0, -104.6826),
    (47.3977, 8.5456, 47.3364),
    (-33.87, 151.21, 22.4138),
    (64.1, -21.9, 66.3900),
    (-77.85, 166.67, -53.3815),
    (89.9, 179.9, 13.5607),
    (-89.875, -179.875, -29.8094),
    (37.4, -122.1, -32.1134),
    (0.125, 179.875, 21.0991),
    (28.0, 86.9, -28.6442),
]


def test_geoid_heights_match_proj_vgridshift_to_a_centimetre():
    lat, lon, want = (np.array(c) for c in zip(*PROJ_VGRIDSHIFT, strict=True))
    got = geoid_height(lat, lon)
    assert got.shape == lat.shape
    assert np.max(np.abs(got - want)) <= 0.01, got - want
    # scalars in, a float out; longitudes beyond ±180° wrap
    assert isinstance(geoid_height(47.0, 8.0), float)
    assert geoid_height(47.0, 8.0 + 360.0) == pytest.approx(geoid_height(47.0, 8.0), abs=1e-9)


def test_grid_nodes_are_the_geoideval_values_to_rounding():
    """At a node the interpolation returns the node: the grid's corners are GeoidEval's."""
    grid = geoid_grid()
    assert grid.shape == (721, 1440)
    assert grid[0, 0] == pytest.approx(-29.535, abs=0.005)  # 90° S
    assert grid[360, 720] == pytest.approx(17.163, abs=0.005)  # 0° N 0° E
    assert geoid_height(-90.0, -180.0) == grid[0, 0] and geoid_height(0.0, 0.0) == grid[360, 720]
    assert -107.5 < grid.min() < -106 and 85 < grid.max() < 86


def test_geoid_works_without_proj(tmp_path):
    """After ``pip install`` alone: no pyproj, no PROJ data directory, no /usr/share/proj."""
    code = (
        "import sys; sys.modules['pyproj'] = None\n"
        "from uasnav.utm.altitude import geoid_heights, geoid_model\n"
        "import numpy as np\n"
        "print(geoid_model(), float(geoid_heights(np.array([16.775833]), np.array([-3.009444]))[0]))\n"
    )
    env = {**os.environ, "PROJ_DATA": str(tmp_path), "PROJ_LIB": str(tmp_path)}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    model, n = out.stdout.rsplit(" ", 1)
    assert model == GEOID_MODEL and abs(float(n) - 28.7068) <= 0.02
    assert (
        "pyproj" not in Path(geoid.__file__).read_text()
        and "/usr/share" not in Path(geoid.__file__).read_text()
    )


def test_the_grid_is_package_data():
    # shipped inside the package (maturin's python-source puts it in the wheel)
    path = Path(altitude.geoid_grid_path())
    assert path.is_file() and path.parent == Path(geoid.__file__).parent / "data"
    assert path.stat().st_size < 1_000_000


def test_bad_positions_are_refused():
    with pytest.raises(InputError, match="finite"):
        geoid_heights(np.array([np.nan]), np.array([8.0]))
    with pytest.raises(InputError, match="latitude"):
        geoid_heights(np.array([91.0]), np.array([8.0]))
