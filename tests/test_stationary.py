"""SHOE static detection on simulated logs with known motion segments."""

from __future__ import annotations

import numpy as np
import pytest

from uasnav.errors import InputError
from uasnav.imu import ImuLog
from uasnav.sim import simulate
from uasnav.stationary import detect_static


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
