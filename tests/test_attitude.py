"""Quaternion attitude: closed forms, identities, conventions, drift tables."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from uasnav import attitude as att
from uasnav.errors import InputError

finite = st.floats(min_value=-3.0, max_value=3.0, allow_nan=False)


def test_convention_scalar_first_body_to_ned():
    q = att.euler_to_quat([[0.0, 0.0, np.pi / 2]])[0]
    np.testing.assert_allclose(q, [np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)], atol=1e-15)
    c = att.quat_to_dcm(q)[0]
    # The nose (body x) points East after a +90° yaw.
    np.testing.assert_allclose(c @ [1, 0, 0], [0, 1, 0], atol=1e-15)


def test_constant_rate_theta_is_rate_times_time():
    w = np.array([2e-3, -1e-3, 5e-4])
    d = att.drift(w, 0.01, duration=100.0)
    np.testing.assert_allclose(d.theta, np.linalg.norm(w) * d.t, rtol=1e-10)
    for th, t in zip(d.thresholds, d.crossing_times, strict=True):
        assert t == pytest.approx(th / np.linalg.norm(w), rel=1e-9)


def test_propagate_matches_scipy_rotation():
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(4)
    rates = rng.normal(0, 0.5, (500, 3))
    dt = 0.01
    q = att.propagate([1, 0, 0, 0], rates, dt)
    r = Rotation.identity()
    for w in rates:
        r = r * Rotation.from_rotvec(w * dt)  # right-multiplied body increments
    xyzw = r.as_quat()
    ref = np.r_[xyzw[3], xyzw[:3]]
    assert min(np.abs(q[-1] - ref).max(), np.abs(q[-1] + ref).max()) < 1e-12


def test_drift_table_reproduces_thesis_table7_scale():
    # Table 7 BPNN column is linear in t: |ω| = 1.75e-2 / 29.4.
    w = 1.75e-2 / 29.4
    d = att.drift([w, 0, 0], 0.01, duration=40.0)
    assert [round(t, 1) for t in d.crossing_times] == [2.9, 5.9, 14.6, 29.4]
    rows = att.crossing_table(d, att.drift([1.75e-2 / 23.0, 0, 0], 0.01, duration=40.0))
    assert rows[-1][3] == pytest.approx((29.4 - 23.0) / 23.0 * 100, rel=1e-6)
    never = att.drift([1e-6, 0, 0], 0.01, duration=1.0)
    assert never.crossing_times == (None, None, None, None)
    assert att.delta_t_percent(None, 2.0) is None


def test_attitude_experiment_reproduces_tables_7_and_8():
    """The attitude chapter's experiment (what ``uasnav report --only attitude`` renders)."""
    from uasnav.experiments import attitude as exp
    from uasnav.experiments.thesis import TABLE7, TABLE8

    res = exp.run()
    for tc, ref in ((res.table7, TABLE7), (res.table8, TABLE8)):
        assert tc.thresholds_rad == tuple(sorted(ref))
        # the largest threshold defines |ω|, so it is reproduced exactly; the others within 0.3 s
        assert tc.t_nn_s[-1] == pytest.approx(ref[1.75e-2][0], abs=1e-9)
        assert tc.t_pf_s[-1] == pytest.approx(ref[1.75e-2][1], abs=1e-9)
        for th, t_nn, t_pf in zip(tc.thresholds_rad, tc.t_nn_s, tc.t_pf_s, strict=True):
            assert t_nn == pytest.approx(ref[th][0], abs=0.3)
            assert t_pf == pytest.approx(ref[th][1], abs=0.3)
        # constant rates: Δt% is the same at every threshold
        assert max(tc.dt_percent) - min(tc.dt_percent) < 1e-9
    assert res.table7.w_nn_rad_s == pytest.approx(1.75e-2 / 29.4)
    assert res.table7.dt_percent[-1] == pytest.approx((29.4 - 23.0) / 23.0 * 100, rel=1e-9)


@settings(max_examples=60, deadline=None)
@given(st.floats(-3.1, 3.1), st.floats(-1.5, 1.5), st.floats(-3.1, 3.1))
def test_euler_round_trip(r, p, y):
    e = att.quat_to_euler(att.euler_to_quat([[r, p, y]]))[0]
    np.testing.assert_allclose(e, [r, p, y], atol=1e-9)


@settings(max_examples=60, deadline=None)
@given(arrays(np.float64, (2, 3), elements=finite))
def test_dcm_quat_round_trip_and_orthonormality(v):
    q = att.propagate([1, 0, 0, 0], v, 1.0)
    c = att.quat_to_dcm(q)
    for m in c:
        np.testing.assert_allclose(m.T @ m, np.eye(3), atol=1e-12)
        assert np.linalg.det(m) == pytest.approx(1.0, abs=1e-12)
    back = att.dcm_to_quat(c)
    # q and −q are the same rotation.
    same = np.minimum(np.abs(back - q).max(axis=1), np.abs(back + q).max(axis=1))
    assert np.all(same < 1e-9)


@settings(max_examples=60, deadline=None)
@given(arrays(np.float64, (1, 3), elements=st.floats(-1.5, 1.5)))
def test_single_step_angle_is_rotation_vector_norm(v):
    q = att.propagate([1, 0, 0, 0], v, 1.0)
    assert att.rotation_angle(q)[0] == pytest.approx(np.linalg.norm(v), abs=1e-12)


def test_bad_inputs():
    with pytest.raises(InputError, match="shape"):
        att.propagate([1, 0, 0, 0], np.zeros((5, 2)), 0.01)
    with pytest.raises(InputError, match="dt"):
        att.propagate([1, 0, 0, 0], np.zeros((5, 3)), -1.0)
    rates = np.zeros((5, 3))
    rates[3, 1] = np.nan
    with pytest.raises(InputError, match="index 3"):
        att.propagate([1, 0, 0, 0], rates, 0.01)
    with pytest.raises(InputError, match="zero norm"):
        att.propagate([0, 0, 0, 0], np.zeros((5, 3)), 0.01)
    with pytest.raises(InputError, match="not a rotation"):
        att.dcm_to_quat(np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(InputError, match="duration"):
        att.drift([1e-3, 0, 0], 0.01)
