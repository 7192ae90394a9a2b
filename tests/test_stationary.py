"""SHOE static detection on simulated logs with known motion segments, and the Rust-backed
detector against an independent vectorised Python SHOE (kept here as the reference)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from uasnav import sim, zupt
from uasnav.errors import InputError
from uasnav.imu import ImuLog
from uasnav.sim import simulate
from uasnav.stationary import MAX_WINDOW_SAMPLES, StaticIntervals, detect_static


def _window_sums(x, w):
    """Sums of ``x`` (n, …) over centred windows of ``w`` samples (clipped at the ends)."""
    n = x.shape[0]
    c = np.concatenate([np.zeros((1, *x.shape[1:])), np.cumsum(x, axis=0)])
    lo = np.clip(np.arange(n) - w // 2, 0, n - w)
    return c[lo + w] - c[lo]


def shoe_reference(log, *, window_s=0.2, threshold=None, sigma_a=None, sigma_g=None, gyro_bias=None,
                   gravity=None, false_alarm=1e-3):  # fmt: skip
    """The pure-Python SHOE (Skog et al. 2010, eq. 15) that uasnav.stationary used before it
    called the Rust detector: cumulative sums, every parameter estimated the same documented
    way. Returns (statistic, mask, γ, σ_a, σ_g, g, b_g)."""
    rate = log.uniform_rate(rtol=0.05)
    w = max(3, round(window_s * rate))
    a, g = log.accel, log.gyro
    sa = _window_sums(a, w)
    sg = _window_sums(g, w)
    saa = _window_sums(np.sum(a * a, axis=1), w)
    sgg = _window_sums(g * g, w)
    mean_a = sa / w
    mean_g = sg / w
    var_a = (_window_sums(a * a, w) / w - mean_a**2).mean(axis=1) * w / (w - 1)
    var_g = (sgg / w - mean_g**2).mean(axis=1) * w / (w - 1)
    quiet_a = var_a <= np.percentile(var_a, 20)
    quiet_g = var_g <= np.percentile(var_g, 20)
    quiet = quiet_a & quiet_g
    if not quiet.any():
        quiet = quiet_a
    s_a = math.sqrt(max(float(np.percentile(var_a, 20)), 1e-20)) if sigma_a is None else float(sigma_a)
    s_g = math.sqrt(max(float(np.percentile(var_g, 20)), 1e-20)) if sigma_g is None else float(sigma_g)
    norm_a = np.linalg.norm(mean_a, axis=1)
    g_mag = float(np.median(norm_a[quiet])) if gravity is None else float(gravity)
    b = np.median(mean_g[quiet], axis=0) if gyro_bias is None else np.asarray(gyro_bias, dtype=np.float64)
    u = g_mag * mean_a / np.maximum(norm_a, 1e-12)[:, None]
    acc_term = saa - 2.0 * np.sum(u * sa, axis=1) + w * np.sum(u * u, axis=1)
    gyr_term = sgg.sum(axis=1) - 2.0 * (sg @ b) + w * float(b @ b)
    stat = (acc_term / s_a**2 + gyr_term / s_g**2) / w
    if threshold is None:
        gamma = 1.5 * float(stats.chi2.ppf(1.0 - false_alarm, 6 * w - 2)) / w
    else:
        gamma = float(threshold)
    return stat, stat < gamma, gamma, s_a, s_g, g_mag, b


def _with_motion(preset: str, seed: int) -> tuple[ImuLog, np.ndarray]:
    base = simulate(preset, duration=60.0, rate=100.0, seed=seed)
    t = base.t
    moving = ((t > 10) & (t < 20)) | ((t > 35) & (t < 38)) | ((t > 50) & (t < 52))
    rng = np.random.default_rng(seed)
    # hand-held-like motion: 0.3–2 Hz rotations (~20 deg/s) and 1 m/s² accelerations
    ph = rng.uniform(0, 2 * np.pi, 6)
    rot = 0.35 * np.sin(2 * np.pi * np.array([0.7, 1.3, 0.4])[None, :] * t[:, None] + ph[None, :3])
    acc = 1.0 * np.sin(2 * np.pi * np.array([1.1, 0.5, 1.9])[None, :] * t[:, None] + ph[None, 3:])
    gyro = base.gyro + moving[:, None] * rot
    accel = base.accel + moving[:, None] * acc
    return ImuLog(t=t, gyro=gyro, accel=accel, temp=base.temp), ~moving


@pytest.mark.parametrize("preset", ["lsm6dsm", "ax1"])
def test_detects_static_and_moving_segments(preset: str) -> None:
    log, truth = _with_motion(preset, seed=3)
    res = detect_static(log)
    agree = np.mean(res.mask == truth)
    assert agree > 0.97
    # no static detection inside the motion segments except near their edges (window)
    inner = ~truth & ~np.convolve(truth, np.ones(41), "same").astype(bool)
    assert not np.any(res.mask[inner])
    assert res.gravity == pytest.approx(9.806, abs=0.1)
    long = [iv for iv in res.intervals if iv[1] - iv[0] > 5.0]
    assert len(long) == 4
    assert long[0][0] == pytest.approx(0.0, abs=0.05) and long[0][1] == pytest.approx(10.0, abs=0.2)


def test_threshold_and_min_duration_and_errors() -> None:
    log, _ = _with_motion("lsm6dsm", seed=4)
    strict = detect_static(log, threshold=0.0)
    assert not strict.mask.any() and strict.intervals == []
    res = detect_static(log, min_duration_s=5.0)
    assert all(b - a >= 4.99 for a, b in res.intervals)
    with pytest.raises(InputError, match="method"):
        detect_static(log, method="mv")
    with pytest.raises(InputError, match="window"):
        detect_static(log, window_s=1e6)


def test_log_between_segments_resample() -> None:
    log = simulate("lsm6dsm", duration=10.0, rate=100.0, seed=1)
    part = log.between(2.0, 4.0)
    assert part.t[0] == pytest.approx(2.0) and part.t[-1] == pytest.approx(4.0) and part.n == 201
    np.testing.assert_array_equal(part.truth["gyro_bias"], log.truth["gyro_bias"][200:401])
    segs = log.segments([(0.0, 1.0), (5.0, 5.001), (8.0, 9.0)])
    assert [s.n for s in segs] == [101, 101]
    r = log.resample(50.0)
    assert r.n == 500 and r.sample_rate == pytest.approx(50.0)
    np.testing.assert_allclose(r.gyro, log.gyro[::2], rtol=0, atol=1e-12)  # grid points coincide
    np.testing.assert_allclose(np.linalg.norm(r.truth["attitude"], axis=1), 1.0)
    up = log.resample(200.0)
    np.testing.assert_allclose(up.accel[1], 0.5 * (log.accel[0] + log.accel[1]))
    with pytest.raises(InputError, match="between"):
        log.between(20.0, 30.0)
    with pytest.raises(InputError, match="rate"):
        log.resample(0.0)


def test_real_xio_log_quiet_and_moving_windows(shared_data) -> None:
    from uasnav.io import read_log

    log = read_log(shared_data / "imu" / "xio_fusion_sensor_data.csv").resample(100.0)
    res = detect_static(log)
    w = np.rad2deg(np.linalg.norm(log.gyro, axis=1))
    quiet, moving = [], []
    for a in range(0, log.n - 500, 500):
        s = slice(a, a + 500)
        if np.percentile(w[s], 90) < 0.3:  # 5 s windows clearly at rest (x-IMU noise ≈ 0.1 deg/s)
            quiet.append(res.mask[s].mean())
        elif np.median(w[s]) > 2.0:  # clearly moving
            moving.append(res.mask[s].mean())
    assert len(quiet) >= 8 and len(moving) >= 10
    assert min(quiet) > 0.9
    assert max(moving) < 0.05


def test_rust_detector_matches_the_python_shoe_with_estimated_parameters() -> None:
    """detect_static (statistic in Rust) against the Python reference with every default
    estimated from the data: same parameters, statistic and decisions, at rest and in motion."""
    for preset, seed in (("lsm6dsm", 3), ("ax1", 5)):
        log, _ = _with_motion(preset, seed)
        res = detect_static(log)
        stat, mask, gamma, s_a, s_g, g_mag, b = shoe_reference(log)
        assert (res.threshold, res.sigma_a, res.sigma_g, res.gravity) == (gamma, s_a, s_g, g_mag)
        np.testing.assert_array_equal(res.gyro_bias, b)
        assert res.window_samples == 20  # even: the ends come from the first/last full window
        # The reference differences cumulative sums of |a|² ≈ 96 (m/s²)² over the whole log;
        # with the estimated σ_a ≈ 3e-3 m/s² (not 0.05 as below) that rounding is ~1e-6 of T.
        # The formulas still agree far inside the decision margin (≥ 10 % of γ here) …
        np.testing.assert_allclose(res.statistic, stat, rtol=5e-6)
        np.testing.assert_array_equal(res.mask, mask)
        # … and the Rust statistic is the direct window sum to 1e-8, ends included.
        w, n = res.window_samples, log.n
        for k in (0, 5, 10, 1500, 1800, 4085, n - 11, n - 10, n - 1):
            lo = min(max(k - w // 2, 0), n - w)
            a, g = log.accel[lo : lo + w], log.gyro[lo : lo + w] - res.gyro_bias
            u = res.gravity * a.mean(axis=0) / np.linalg.norm(a.mean(axis=0))
            direct = np.mean(np.sum((a - u) ** 2, axis=1) / s_a**2 + np.sum(g**2, axis=1) / s_g**2)
            assert res.statistic[k] == pytest.approx(direct, rel=1e-8), k


def test_rust_detector_matches_python_shoe_with_the_same_parameters() -> None:
    """nav_core's streaming GLRT (through both public names, uasnav.stationary.detect_static
    and uasnav.zupt.detect_stationary) and the vectorised Python SHOE are independent
    implementations of the same statistic: with the same σ_a, σ_g, W, γ, g and zero gyro bias
    they give the same statistic and mask, at rest and in motion."""
    log = sim.simulate("lsm6dsm", profile="static", duration=20.0, seed=3, table_rate_dps=0.0)
    rng = np.random.default_rng(0)
    gyro, accel = log.gyro.copy(), log.accel.copy()
    gyro[800:1200] += rng.normal(0.0, 0.5, (400, 3))  # 4 s of handling in the middle
    accel[800:1200] += rng.normal(0.0, 2.0, (400, 3))
    moved = ImuLog(t=log.t, gyro=gyro, accel=accel)
    kw = dict(sigma_accel_m_s2=0.05, sigma_gyro_rad_s=0.05, threshold=10.0, gravity_m_s2=9.806)
    rust = zupt.detect_stationary(moved, window_s=0.25, **kw)
    same = detect_static(
        moved, window_s=0.25, sigma_a=0.05, sigma_g=0.05, threshold=10.0, gravity=9.806, gyro_bias=np.zeros(3)
    )
    stat, mask, *_ = shoe_reference(
        moved, window_s=0.25, sigma_a=0.05, sigma_g=0.05, threshold=10.0, gravity=9.806, gyro_bias=np.zeros(3)
    )
    # The reference differences cumulative sums of |a|² ≈ 96 (m/s²)² over the whole log, which
    # cancels to ~1e-9 relative; the formulas agree well beyond any decision margin.
    np.testing.assert_allclose(rust.statistic, stat, rtol=1e-7)
    np.testing.assert_array_equal(rust.mask, mask)
    np.testing.assert_array_equal(same.statistic, rust.statistic)
    np.testing.assert_array_equal(same.mask, rust.mask)
    assert same.intervals == rust.intervals
    assert rust.mask[:700].all() and not rust.mask[850:1150].any() and rust.mask[1300:].all()


def test_one_result_type_and_the_zupt_alias() -> None:
    """zupt.detect_stationary is detect_static with the filter's fixed thresholds; one result
    type under both names."""
    assert zupt.StationarityResult is StaticIntervals
    log = simulate("lsm6dsm", duration=3.0, rate=100.0, seed=2)
    res = zupt.detect_stationary(log)
    assert isinstance(res, StaticIntervals)
    assert (res.threshold, res.sigma_a, res.sigma_g, res.gravity) == (10.0, 0.05, 0.01, 9.80665)
    assert res.window_samples == 25
    np.testing.assert_array_equal(res.gyro_bias, np.zeros(3))
    # Windows longer than the Rust buffer: detect_stationary clamps (documented), detect_static
    # refuses rather than silently using another window.
    fast = simulate("lsm6dsm", duration=1.0, rate=2000.0, seed=2)
    assert zupt.detect_stationary(fast).window_samples == MAX_WINDOW_SAMPLES
    with pytest.raises(InputError, match=r"window_s: window of 400 samples.*256"):
        detect_static(fast)
    assert detect_static(fast, window_s=0.1).window_samples == 200
    with pytest.raises(InputError, match="window_samples"):
        detect_static(log, window_samples=0)
    with pytest.raises(InputError, match="gyro_bias"):
        detect_static(log, gyro_bias=np.zeros(2))
    with pytest.raises(InputError, match="sigma_a"):
        detect_static(log, sigma_a=0.0)
