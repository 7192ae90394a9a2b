"""Geometry, element discretisation and features (eqs. 47–58) against hand-computed cases."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from uasnav.errors import InputError
from uasnav.trajectory.features import cell_centre, cell_index, features, fold, wind_vector
from uasnav.trajectory.geometry import (
    arc_length_along,
    discretise,
    geodetic_to_local,
    signed_angle_deg,
)


def test_signed_angle_eq52_and_sign():
    # North then east is a right turn of 90°; north then north-west a left turn of 45°.
    assert signed_angle_deg(np.array([1.0, 0]), np.array([0, 1.0])) == pytest.approx(90.0)
    assert signed_angle_deg(np.array([1.0, 0]), np.array([1.0, -1.0])) == pytest.approx(-45.0)
    # |angle| equals acos of eq. (52)/(53)
    v1, v2 = np.array([3.0, 1.0]), np.array([-1.0, 2.0])
    ref = np.degrees(np.arccos(v1 @ v2 / np.linalg.norm(v1) / np.linalg.norm(v2)))
    assert abs(signed_angle_deg(v1, v2)) == pytest.approx(ref)


def test_discretise_l_shape_by_hand():
    # 40 m north, then 40 m east, L = 10: start 0–20, straight 20–30, corner 30–50 (10 m either
    # side of the waypoint), straight 50–70, end 70–80.
    el = discretise(np.array([[0.0, 0], [40, 0], [40, 40]]), 10.0)
    assert list(el.kind) == ["start", "straight", "corner", "straight", "end"]
    np.testing.assert_allclose(el.length_m, [20, 10, 20, 20, 10])
    corner = int(np.flatnonzero(el.kind == "corner")[0])
    assert el.turn_deg[corner] == pytest.approx(90.0)
    np.testing.assert_allclose(el.start_ne[corner], [30.0, 0.0])
    np.testing.assert_allclose(el.mid_ne[corner], [40.0, 0.0])
    np.testing.assert_allclose(el.end_ne[corner], [40.0, 10.0])
    assert el.length_m.sum() == pytest.approx(80.0)
    np.testing.assert_allclose(el.s_end_m[:-1], el.s_start_m[1:])  # contiguous cover


def test_discretise_long_straight_pieces():
    el = discretise(np.array([[0.0, 0], [100, 0]]), 10.0)
    np.testing.assert_allclose(el.length_m, [20.0] * 5)
    assert el.kind[0] == "start" and el.kind[-1] == "end"
    assert np.all(el.turn_deg == 0)


def test_left_turn_and_mirror_folding_figure53():
    # Right turn of 90° with wind from the left of the first segment (θ_w = 270°) equals
    # the mirrored left turn with wind from the right (θ_w = 90°).
    w_from_east = wind_vector(5.0, 90.0)  # blows toward west
    w_from_west = wind_vector(5.0, 270.0)
    right = features(np.array([0.0]), np.array([90.0]), np.array(["corner"]), w_from_east)
    left = features(np.array([0.0]), np.array([-90.0]), np.array(["corner"]), w_from_west)
    assert right.theta_w_deg[0] == pytest.approx(270.0)
    assert left.theta_deg[0] == pytest.approx(90.0) and left.mirrored[0]
    assert left.theta_w_deg[0] == pytest.approx(270.0)
    assert cell_index(left)[0] == cell_index(right)[0]
    _th, tw, m = fold(np.array([0.0, 0.0]), np.array([300.0, 60.0]))
    np.testing.assert_allclose(tw, [60.0, 60.0])
    assert m.tolist() == [True, False]


def test_theta_w_eq56_and_cells():
    # First segment heading east, wind blowing toward north-east: θ_w = 315° (counter-clockwise 45°).
    f = features(
        np.array([90.0]), np.array([45.0]), np.array(["corner"]), np.array([1.0, 1.0]) * 5 / np.sqrt(2)
    )
    assert f.theta_w_deg[0] == pytest.approx(315.0)
    assert f.wind_ms[0] == pytest.approx(5.0)
    c = cell_index(f)[0]
    th, tw, v, block = cell_centre(np.array([c]))
    assert (th[0], tw[0], v[0], block[0]) == (45.0, 315.0, 5.0, 0)
    assert 0 <= c < 128


def test_wind_vector_from_convention():
    np.testing.assert_allclose(wind_vector(2.0, 0.0), [-2.0, 0.0], atol=1e-12)  # from north → south


@pytest.mark.parametrize(
    ("plan", "msg"),
    [
        (np.array([[0.0, 0.0]]), "at least two waypoints"),
        (np.array([[0.0, 0], [0, 0], [10, 10]]), "coincide"),
        (np.array([[0.0, 0], [np.nan, 0], [10, 10]]), "NaN"),
        (np.array([[0.0, 0], [5, 0], [30, 0]]), "shorter than the segment"),
        (np.array([[0.0, 0], [15, 0]]), "fewer than two segments"),
    ],
)
def test_bad_plans(plan, msg):
    with pytest.raises(InputError, match=msg):
        discretise(plan, 10.0)


def test_geodetic_to_local_against_small_offset():
    lat0, lon0 = 45.0, 7.0
    ned = geodetic_to_local(np.array([lat0, lat0 + 1e-4]), np.array([lon0, lon0]), np.array([0.0, 0.0]))
    assert ned[1, 0] == pytest.approx(11.11, abs=0.02)  # 1e-4° of latitude ≈ 11.1 m
    with pytest.raises(InputError, match="non-finite"):
        geodetic_to_local(np.array([np.nan]), np.array([0.0]), np.array([0.0]))


def test_arc_length_follows_crossing_legs():
    # A figure whose last leg passes over the first: the projection must not jump ahead.
    plan = np.array([[0.0, 0], [0, 40], [20, 40], [20, 20], [-10, 20]])
    pos = np.array([[0.0, 5], [0.5, 20], [0, 35], [10, 40], [20, 30], [10, 20], [0, 20]])
    s = arc_length_along(plan, pos)
    np.testing.assert_allclose(s, [5, 20, 35, 50, 70, 90, 100], atol=0.6)


@settings(max_examples=40, deadline=None)
@given(
    headings=st.lists(st.floats(0, 360), min_size=2, max_size=5),
    legs=st.lists(st.floats(25, 80), min_size=5, max_size=5),
    wind_speed=st.floats(0, 11),
    wind_from=st.floats(0, 360),
)
def test_mirror_image_plan_has_identical_folded_features(headings, legs, wind_speed, wind_from):
    # Reflecting a whole plan and the wind about the north axis (east → −east) must give the
    # same folded features and cells (Figure 53), element by element.
    pts = [np.zeros(2)]
    for h, length in zip(headings, legs, strict=False):
        pts.append(pts[-1] + length * np.array([np.cos(np.radians(h)), np.sin(np.radians(h))]))
    plan = np.array(pts)
    legs_len = np.hypot(*np.diff(plan, axis=0).T)
    assume(np.all(legs_len > 20))
    mirror = plan * [1.0, -1.0]
    w = wind_vector(wind_speed, wind_from)
    a = discretise(plan)
    b = discretise(mirror)
    fa = features(a.heading1_deg, a.turn_deg, a.kind, w)
    fb = features(b.heading1_deg, b.turn_deg, b.kind, w * [1.0, -1.0])
    np.testing.assert_allclose(fa.theta_deg, fb.theta_deg, atol=1e-6)
    # θ_w agrees on the circle (0° and 360° are the same direction)
    d = np.mod(fa.theta_w_deg - fb.theta_w_deg + 180.0, 360.0) - 180.0
    np.testing.assert_allclose(d, 0.0, atol=1e-6)
    np.testing.assert_allclose(fa.matrix(), fb.matrix(), atol=1e-6)
