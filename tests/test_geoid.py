"""EGM96 geoid heights for W84 altitudes (``uasnav.utm.altitude``) against GeographicLib's
published ``GeoidEval`` values, and the altitude conversion with and without a given N."""

from __future__ import annotations

import numpy as np
import pytest

from uasnav.errors import InputError
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
    monkeypatch.setattr(altitude, "geoid_grid_path", lambda: None)
    assert geoid_model() is None
    pts = [_pt(47.0, 8.0, 100.0, AltitudeFrame.AMSL)]
    with pytest.raises(InputError, match=r"--geoid-height.*never assumes N = 0"):
        w84_altitudes(pts, home_amsl_m=None, geoid_height_m=None)
    with pytest.raises(InputError, match="proj-data"):
        geoid_heights(np.array([47.0]), np.array([8.0]))
    assert w84_altitudes(pts, home_amsl_m=None, geoid_height_m=47.0) == pytest.approx([147.0])


def test_bad_positions_are_refused():
    with pytest.raises(InputError, match="finite"):
        geoid_heights(np.array([np.nan]), np.array([8.0]))
    with pytest.raises(InputError, match="latitude"):
        geoid_heights(np.array([91.0]), np.array([8.0]))
