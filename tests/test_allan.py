"""Allan deviation against allantools, NIST SP 1065 and a published ADIS16405 analysis."""

from __future__ import annotations

import csv

import allantools
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uasnav.allan import cluster_sizes, oadev
from uasnav.errors import InputError, UnitError
from uasnav.experiments.allan import NIST_OADEV, nbs14_series
from uasnav.noise import FilterNoise, identify
from uasnav.units import convert


def test_nist_sp1065_reference_values():
    x = nbs14_series()
    # The documented Lehmer sequence: n[1] = 395529916 → x[1] = n[1]/(2^31 − 1).
    assert x[1] == pytest.approx(395529916 / 2147483647, rel=1e-15)
    r = oadev(x, rate=1.0, taus=[1, 10, 100])
    for tau, dev in zip(r.taus, r.adev, strict=True):
        assert dev == pytest.approx(NIST_OADEV[round(tau)], rel=2e-6)


def test_allan_experiment_quick():
    """The Allan chapter's experiment (what ``uasnav report --only allan`` renders)."""
    from uasnav.experiments import allan as exp
    from uasnav.experiments.thesis import TABLE3

    res = exp.run(quick=True)
    assert res.nist.rel_diff.max() < 1e-5
    np.testing.assert_array_equal(res.nist.taus, [1.0, 10.0, 100.0])
    g = res.gyro
    assert g.hours == 0.25 and g.arw_configured_deg_sqrt_h == TABLE3["arw_deg_sqrt_h"] == 3.18
    # thesis Table 3's ARW recovered from 0.25 h of simulated data, by the fit and at τ = 1 s
    np.testing.assert_allclose(g.arw_fit_deg_sqrt_h, 3.18, rtol=0.05)
    np.testing.assert_allclose(g.arw_points_deg_sqrt_h, 3.18, rtol=0.05)
    assert g.rrw_fit_deg_h_sqrt_h.shape == (3,)


@pytest.mark.parametrize("taus", ["octave", "decade", "all"])
def test_equals_allantools_oadev(taus):
    rng = np.random.default_rng(7)
    n = 3000 if taus == "all" else 50_000
    y = rng.normal(0.2, 0.05, n) + np.cumsum(rng.normal(0, 1e-4, n))
    ours = oadev(y, rate=100.0, taus=taus)
    t, dev, err, ns = allantools.oadev(y, rate=100.0, data_type="freq", taus=taus)
    np.testing.assert_allclose(ours.taus, t, rtol=1e-12)
    np.testing.assert_allclose(ours.adev, dev, rtol=1e-9)
    np.testing.assert_array_equal(ours.n_terms, ns)
    # allantools' error bar is dev/√n.
    np.testing.assert_allclose(err, dev / np.sqrt(ns), rtol=1e-12)


def test_explicit_taus_and_multi_axis_match_allantools_per_column():
    rng = np.random.default_rng(3)
    y = rng.normal(0, 1, (20_000, 3)) * [1.0, 2.0, 3.0]
    taus = [0.01, 0.05, 0.29, 1.0, 7.5]
    ours = oadev(y, rate=100.0, taus=taus)
    np.testing.assert_array_equal(ours.m, [1, 5, 29, 100, 750])
    for j in range(3):
        _, dev, _, _ = allantools.oadev(y[:, j], rate=100.0, data_type="freq", taus=ours.taus)
        np.testing.assert_allclose(ours.adev[:, j], dev, rtol=1e-9)


def test_published_adis16405_allan_variance(shared_data):
    npz = np.load(shared_data / "imu" / "adis16405_static_imu1.npz")
    rate = float(npz["rate_hz"])
    with open(shared_data / "imu" / "adis16405_imu1_published_avar.csv") as fh:
        rows = list(csv.DictReader(fh))
    channels = {
        ("Gyroscope", "X"): npz["gyro_dps"][:, 0],
        ("Gyroscope", "Y"): npz["gyro_dps"][:, 1],
        ("Gyroscope", "Z"): npz["gyro_dps"][:, 2],
        ("Accelerometer", "X"): npz["accel_g"][:, 0],
        ("Accelerometer", "Y"): npz["accel_g"][:, 1],
        ("Accelerometer", "Z"): npz["accel_g"][:, 2],
    }
    checked = 0
    for (sensor, axis), series in channels.items():
        ref = [r for r in rows if r["sensor"] == sensor and r["axis"] == axis]
        assert len(ref) == 18
        taus = [float(r["tau_s"]) for r in ref]
        ours = oadev(series, rate=rate, taus=taus)
        np.testing.assert_allclose(ours.taus, taus, rtol=1e-12)
        np.testing.assert_allclose(ours.avar, [float(r["avar"]) for r in ref], rtol=1e-5)
        # The published error column is the IEEE 952 relative error 1/√(2(N/m − 1)).
        np.testing.assert_allclose(ours.rel_error, [float(r["errors"]) for r in ref], rtol=1e-6)
        checked += len(ref)
    assert checked == 6 * 18


def test_adis16405_noise_identification_order_of_magnitude(shared_data):
    npz = np.load(shared_data / "imu" / "adis16405_static_imu1.npz")
    gyro = convert(npz["gyro_dps"], "deg/s", "rad/s")
    rep = oadev(gyro, rate=100.0, unit="rad/s").identify()
    arw, unit = rep.fit.field("random_walk")
    assert unit == "deg/√h"
    # README: ARW ≈ 2.4 deg/√h (datasheet 2.0 typical).
    assert np.all((arw > 1.8) & (arw < 3.0)), arw
    pts, _ = rep.points.field("random_walk")
    np.testing.assert_allclose(pts, arw, rtol=0.15)


def _white_rrw(n, rate, arw, rrw, seed):
    rng = np.random.default_rng(seed)
    dt = 1.0 / rate
    return rng.normal(0, arw / np.sqrt(dt), (n, 3)) + np.cumsum(
        rng.normal(0, rrw * np.sqrt(dt), (n, 3)), axis=0
    )


def test_noise_fit_recovers_simulated_terms_with_units():
    arw = float(convert(3.18, "deg/√h", "rad/√s"))
    rrw = float(convert(300.0, "deg/h/√h", "rad/s/√s"))
    ratios = []
    for seed in range(4):
        y = _white_rrw(720_000, 100.0, arw, rrw, seed=11 + seed)
        rep = oadev(y, 100.0, unit="rad/s").identify()
        np.testing.assert_allclose(rep.fit.random_walk, arw, rtol=0.05)
        np.testing.assert_allclose(rep.fit.to("random_walk", "deg/√h"), 3.18, rtol=0.05)
        ratios.extend(rep.fit.rate_random_walk / rrw)
    # RRW from 2 h of data rests on a few long clusters (EDF of a handful): single axes scatter
    # by ±50 % and part of the floor is taken as bias instability, so check the ensemble.
    ratios = np.maximum(ratios, 1e-3)
    geo = float(np.exp(np.mean(np.log(ratios))))
    assert 0.6 < geo < 1.2, ratios
    # Dimension checks: a bias instability is not an ARW.
    with pytest.raises(UnitError):
        rep.fit.to("bias_instability", "deg/√h")
    noise = FilterNoise.from_reports(rep, _accel_report())
    assert noise.sigma_arw_rad_sqrt_s == pytest.approx(np.max(rep.fit.random_walk))
    g_std, _ = noise.white_sample_std(0.01)
    assert g_std == pytest.approx(noise.sigma_arw_rad_sqrt_s * 10.0)


def _accel_report():
    vrw = float(convert(0.05, "m/s/√h", "m/s/√s"))
    y = _white_rrw(100_000, 100.0, vrw, 1e-6, seed=5)
    return oadev(y, 100.0, unit="m/s^2").identify()


def test_anti_alias_flattened_points_are_left_out_of_the_fit():
    """A 30 Hz second-order anti-alias filter at 100 Hz (the thesis' AX1) flattens σ(τ) at
    10–40 ms; fitting those points reads the ARW low (outside its interval). The automatic
    rule leaves them out and reads the true ARW; a quantisation-dominated start (slope −1) is
    kept."""
    from scipy.signal import butter, sosfilt

    arw = float(convert(3.18, "deg/√h", "rad/√s"))
    rng = np.random.default_rng(21)
    white = rng.normal(0.0, arw * 10.0, (1_000_000, 2))
    aa = sosfilt(butter(2, 30.0, fs=100.0, output="sos"), white, axis=0)
    curve = oadev(aa, 100.0, "octave", unit="rad/s")
    rep = identify(curve)
    np.testing.assert_allclose(rep.fit.random_walk, arw, rtol=0.03)
    assert np.all((rep.ci_low.random_walk <= arw) & (arw <= rep.ci_high.random_walk))
    assert np.all(rep.fit_min_tau_s >= 0.04) and np.all(rep.fit_min_tau_s <= 0.16)
    everything = identify(curve, min_tau=None)
    # What the rule prevents: with the flattened points the truth falls outside the 95 % interval.
    assert np.all(everything.ci_high.random_walk < arw)
    assert np.all(everything.fit_min_tau_s == curve.taus[0])
    explicit = identify(curve, min_tau=0.1)
    assert np.all(explicit.fit_min_tau_s == pytest.approx(0.16))
    # Quantisation noise (the rate is the difference of a white angle error, IEEE 952's Q
    # model) falls as τ⁻¹ at the short end: nothing is cut.
    angle_err = rng.uniform(-0.5, 0.5, 1_000_001) * arw * 2.0
    q = white[:, 0] + np.diff(angle_err) / 0.01
    qcurve = oadev(q, 100.0, "octave", unit="rad/s")
    assert np.log(qcurve.adev[1] / qcurve.adev[0]) / np.log(2.0) < -0.9  # Q-dominated start
    qrep = identify(qcurve)
    assert qrep.fit_min_tau_s[0] == pytest.approx(0.01)
    with pytest.raises(InputError, match="min_tau"):
        identify(curve, min_tau=-1.0)
    with pytest.raises(InputError, match="min_tau"):
        identify(curve, min_tau=1e4)


def test_filter_noise_from_thesis_tables():
    fn = FilterNoise.from_datasheet(arw="3.18 deg/√h", gbi="1.5e-4 deg/s", vrw="0.05 m/s/√h", abi="2 m/s/h")
    assert fn.sigma_arw_rad_sqrt_s == pytest.approx(3.18 * np.pi / 180 / 60)
    assert fn.sigma_gbi_rad_s == pytest.approx(1.5e-4 * np.pi / 180)
    assert fn.sigma_vrw_m_s_sqrt_s == pytest.approx(0.05 / 60)
    assert fn.sigma_abi_m_s2 == pytest.approx(2 / 3600)
    with pytest.raises(UnitError):
        FilterNoise.from_datasheet(arw="3.18 deg/h", gbi="1.5e-4 deg/s", vrw="0.05 m/s/√h", abi="2 m/s/h")


def test_identify_refuses_ambiguous_units():
    r = oadev(np.random.default_rng(0).normal(size=1000), rate=10.0, unit="deg/s")
    with pytest.raises(InputError):
        identify(r)
    with pytest.raises(UnitError):
        identify(r, kind="gyro")


@pytest.mark.parametrize(
    ("data", "kwargs", "match"),
    [
        (np.array([1.0, np.nan, 2.0, 3.0]), {}, "row 1"),
        (np.array([1.0, 2.0]), {}, "too short"),
        (np.ones((10, 2, 2)), {}, "shape"),
        (np.ones(100), {"rate": 0.0}, "rate"),
        (np.ones(100), {"rate": float("nan")}, "rate"),
        (np.ones(100), {"taus": "weekly"}, "spacing"),
        (np.ones(100), {"taus": [1000.0]}, "too long"),
        (np.ones(100), {"taus": []}, "empty"),
    ],
)
def test_bad_input_raises_specific_errors(data, kwargs, match):
    with pytest.raises(InputError, match=match):
        oadev(data, **kwargs)


def test_nan_in_second_column_is_located():
    y = np.zeros((50, 3))
    y[17, 2] = np.inf
    with pytest.raises(ValueError, match="row 17, column 2"):
        oadev(y, rate=1.0)


def test_non_contiguous_and_int_input_are_converted():
    y = np.arange(2000, dtype=np.int64).reshape(1000, 2) % 7
    a = oadev(y[::1, 1], rate=1.0)
    b = oadev(np.asarray(y, dtype=float)[:, 1].copy(), rate=1.0)
    np.testing.assert_array_equal(a.adev, b.adev)


def test_confidence_interval_brackets_estimate_and_edf_formula():
    rng = np.random.default_rng(2)
    r = oadev(rng.normal(size=10_000), rate=1.0, taus="octave")
    assert np.all(r.ci_low < r.adev) and np.all(r.adev < r.ci_high)
    # NIST SP 1065 white-FM EDF at m = 1, N = 10001 phase points.
    N, m = 10_001.0, 1.0
    expect = (3 * (N - 1) / (2 * m) - 2 * (N - 2) / N) * 4 * m**2 / (4 * m**2 + 5)
    assert r.edf[0] == pytest.approx(expect)
    # Coverage: over 200 white-noise series the 68 % interval holds the truth ~68 % of the time.
    hits = 0
    for s in range(200):
        rr = oadev(np.random.default_rng(100 + s).normal(size=4096), rate=1.0, taus=[16.0])
        hits += int(rr.ci_low[0] <= 0.25 <= rr.ci_high[0])
    assert 0.58 <= hits / 200 <= 0.78


def test_cluster_sizes_spacing():
    np.testing.assert_array_equal(cluster_sizes(1000, 1.0, "octave"), [1, 2, 4, 8, 16, 32, 64, 128, 256])
    np.testing.assert_array_equal(cluster_sizes(1000, 100.0, [0.01, 0.01, 0.02]), [1, 2])


@settings(max_examples=40, deadline=None)
@given(
    st.integers(min_value=16, max_value=400),
    st.floats(min_value=-1e3, max_value=1e3),
    st.floats(min_value=0.1, max_value=10.0),
    st.integers(min_value=0, max_value=2**31),
)
def test_property_offset_invariance_and_scaling(n, offset, scale, seed):
    y = np.random.default_rng(seed).normal(size=n)
    base = oadev(y, rate=10.0)
    moved = oadev(scale * y + offset, rate=10.0)
    np.testing.assert_allclose(moved.adev, scale * base.adev, rtol=1e-7, atol=1e-12)
