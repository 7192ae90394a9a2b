"""uasnav.earth against WGS-84 published values (NIMA TR8350.2 Table 3.3/3.4)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from uasnav import earth


def test_normal_gravity_equator_and_poles_match_tr8350() -> None:
    assert earth.normal_gravity(0.0, 0.0) == pytest.approx(9.7803253359, abs=1e-10)
    assert earth.normal_gravity(math.pi / 2, 0.0) == pytest.approx(9.8321849378, abs=1e-9)
    assert earth.normal_gravity(-math.pi / 2, 0.0) == pytest.approx(9.8321849378, abs=1e-9)


def test_free_air_gradient_is_about_3_086e_6_per_metre() -> None:
    lat = math.radians(45.0)
    g0 = earth.normal_gravity(lat, 0.0)
    g1 = earth.normal_gravity(lat, 1000.0)
    assert (g0 - g1) / 1000.0 == pytest.approx(3.086e-6, rel=2e-3)


def test_earth_rate_and_gravity_vectors() -> None:
    lat = math.radians(30.0)
    w = earth.earth_rate_ned(lat)
    np.testing.assert_allclose(w, 7.292115e-5 * np.array([math.sqrt(3) / 2, 0.0, -0.5]), rtol=1e-15)
    assert np.linalg.norm(w) == pytest.approx(earth.OMEGA_IE)
    g = earth.gravity_ned(lat, 100.0)
    assert g[0] == 0.0 and g[1] == 0.0
    assert g[2] == earth.normal_gravity(lat, 100.0)
    assert earth.WGS84_E2 == pytest.approx(6.69437999014e-3, rel=1e-11)
