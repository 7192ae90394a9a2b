"""The simulated flight's latitude and longitude against pymap3d: a constant course at constant
ellipsoidal height is a rhumb line, which ``pymap3d.lox.loxodrome_direct`` solves on WGS-84."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pymap3d.lox import loxodrome_direct

from uasnav.geo.frames import radii_of_curvature
from uasnav.sim.flight import simulate_flight


@pytest.mark.parametrize(("north", "east", "lat0"), [(30_000.0, 0.0, 45.0), (24_000.0, 18_000.0, 60.0)])
def test_long_straight_leg_is_the_wgs84_rhumb_line(north: float, east: float, lat0: float) -> None:
    # no climb, start on the ellipsoid: the leg flies at h = 0 exactly
    f = simulate_flight(
        waypoints=((north, east, 0.0),),
        latitude_deg=lat0,
        longitude_deg=7.0,
        height_m=0.0,
        speed_m_s=60.0,
        rate_hz=50.0,
        gnss_rate_hz=1.0,
        static_s=2.0,
    )
    tr = f.truth
    assert tr is not None
    assert np.abs(tr.alt).max() == 0.0
    dist = math.hypot(north, east)
    az = math.degrees(math.atan2(east, north))
    lat_ref, lon_ref = loxodrome_direct(lat0, 7.0, dist, az)
    rn, re = radii_of_curvature(lat_ref)
    err_n = math.radians(tr.lat[-1] - lat_ref) * rn
    err_e = math.radians(tr.lon[-1] - lon_ref) * re * math.cos(math.radians(lat_ref))
    # a flat mapping with the start point's radii is 0.71 m off at the end of the 30 km leg
    assert abs(err_n) < 0.01 and abs(err_e) < 0.01, (err_n, err_e)
    # the GNSS fixes scatter around the same track (σ 1.5 m, 1 Hz)
    lat_t = np.interp(f.gnss.t, tr.t, tr.lat)
    dn = np.radians(f.gnss.lat - lat_t) * rn
    assert abs(np.mean(dn)) < 0.5 and 1.0 < np.std(dn) < 2.0
