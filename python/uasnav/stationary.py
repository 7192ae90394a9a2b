"""Static-interval detection on IMU logs: the SHOE generalised likelihood-ratio test.

For a window Ω_k of W samples centred on sample k, the SHOE detector (Skog, Händel, Nilsson,
Rantakokko, *Zero-velocity detection — an algorithm evaluation*, IEEE TBME 57(11), 2010,
eq. 15) is

    T_k = 1/W Σ_{j∈Ω_k} [ ‖a_j − g ā_k/‖ā_k‖‖² / σ_a² + ‖ω_j − b_g‖² / σ_g² ]

and the unit is declared static where ``T_k < γ``. The statistic is computed in Rust
(``nav_core::zupt::detect_static``): the streaming detector the ZUPT filter runs per sample,
here over a centred window (the first and last W/2 samples reuse the nearest full window).
This module is the one public detector; :func:`uasnav.zupt.detect_stationary` is the same
test with the filter's fixed thresholds and no parameter estimation.

Defaults (documented so results are reproducible):

* ``g`` — the median ‖ā‖ over the quietest 20 % of windows (the accelerometer's own view of
  gravity, so its scale-factor error does not bias the test);
* ``σ_a``, ``σ_g`` — per-sample white-noise std from the 20th percentile of the per-window
  sample variances (the quiet windows are static in any log that is ≥ 20 % static);
* ``b_g`` — the median window-mean gyro over those quiet windows (removes turn-on bias, which
  on consumer MEMS reaches ±3 deg/s and would otherwise dominate ‖ω‖²);
* ``γ`` — for a static window with these σ the statistic is ≈ χ²(6W − 2)/W, so the default
  threshold is that quantile at a false-alarm probability ``1e-3`` (×1.5 margin for the
  estimated σ): static windows pass, motion of a few σ in the window is rejected.

The window holds at most :data:`MAX_WINDOW_SAMPLES` samples (the Rust detector's fixed
buffer): 0.2 s up to 1280 Hz.

Examples
--------
>>> from uasnav.sim import simulate
>>> log = simulate("lsm6dsm", duration=5.0, rate=100.0, seed=1)
>>> res = detect_static(log)
>>> res.fraction, res.window_samples, res.intervals
(1.0, 20, [(0.0, 4.99)])
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav import _core
from uasnav.errors import InputError
from uasnav.imu import ImuLog, require_log

FloatArray = NDArray[np.float64]

#: Largest window (samples) of the Rust detector (``nav_core::zupt::DETECT_CAPACITY``).
MAX_WINDOW_SAMPLES = 256


@dataclass(frozen=True)
class StaticIntervals:
    """Result of :func:`detect_static` (and of :func:`uasnav.zupt.detect_stationary`).

    Attributes
    ----------
    mask : ndarray of bool, shape (n,)
        True where the unit is detected static (``statistic < threshold``).
    intervals : list of (t_start, t_end)
        Static intervals (s), from the log's time stamps, in order.
    statistic : ndarray, shape (n,)
        The test statistic T_k (dimensionless).
    threshold : float
        γ used.
    sigma_a, sigma_g : float
        Noise levels used (m/s², rad/s per sample).
    gravity : float
        Gravity magnitude used (m/s²).
    window_samples : int
        Window length W used (samples).
    gyro_bias : ndarray, shape (3,)
        Gyro bias b_g removed before the test (rad/s).
    """

    mask: NDArray[np.bool_]
    intervals: list[tuple[float, float]]
    statistic: FloatArray = field(repr=False)
    threshold: float = 0.0
    sigma_a: float = 0.0
    sigma_g: float = 0.0
    gravity: float = 0.0
    window_samples: int = 0
    gyro_bias: FloatArray = field(default_factory=lambda: np.zeros(3), repr=False)

    @property
    def fraction(self) -> float:
        """Fraction of samples detected static."""
        return float(self.mask.mean())


def _window_sums(x: FloatArray, w: int) -> FloatArray:
    """Sums of ``x`` (n, …) over centred windows of ``w`` samples (clipped at the ends, as the
    Rust detector's windows are)."""
    n = x.shape[0]
    c = np.concatenate([np.zeros((1, *x.shape[1:])), np.cumsum(x, axis=0)])
    lo = np.clip(np.arange(n) - w // 2, 0, n - w)
    return c[lo + w] - c[lo]


def _mask_to_intervals(t: FloatArray, mask: NDArray[np.bool_]) -> list[tuple[float, float]]:
    m = np.concatenate([[False], mask, [False]]).astype(np.int8)
    d = np.diff(m)
    starts = np.flatnonzero(d == 1)
    ends = np.flatnonzero(d == -1) - 1
    return [(float(t[a]), float(t[b])) for a, b in zip(starts, ends, strict=True)]


@dataclass(frozen=True)
class _QuietEstimates:
    """Default test parameters from the quietest windows (see the module docs)."""

    sigma_a: float
    sigma_g: float
    gravity: float
    gyro_bias: FloatArray


def _quiet_estimates(log: ImuLog, w: int) -> _QuietEstimates:
    a, g = log.accel, log.gyro
    mean_a = _window_sums(a, w) / w
    mean_g = _window_sums(g, w) / w
    # per-window sample variance averaged over axes (noise level estimate)
    var_a = (_window_sums(a * a, w) / w - mean_a**2).mean(axis=1) * w / (w - 1)
    var_g = (_window_sums(g * g, w) / w - mean_g**2).mean(axis=1) * w / (w - 1)
    quiet_a = var_a <= np.percentile(var_a, 20)
    quiet_g = var_g <= np.percentile(var_g, 20)
    quiet = quiet_a & quiet_g
    if not quiet.any():
        quiet = quiet_a
    return _QuietEstimates(
        sigma_a=math.sqrt(max(float(np.percentile(var_a, 20)), 1e-20)),
        sigma_g=math.sqrt(max(float(np.percentile(var_g, 20)), 1e-20)),
        gravity=float(np.median(np.linalg.norm(mean_a, axis=1)[quiet])),
        gyro_bias=np.asarray(np.median(mean_g[quiet], axis=0), dtype=np.float64),
    )


def _rust_statistic(
    accel: FloatArray, gyro: FloatArray, w: int, sigma_a: float, sigma_g: float, gravity: float
) -> FloatArray:
    """T_k (n,) of ``nav_core::zupt::detect_static`` over centred windows of ``w`` samples (the
    first and last samples take the nearest full window)."""
    out, _ = _core.zupt_detect_static(
        np.ascontiguousarray(accel, dtype=np.float64),
        np.ascontiguousarray(gyro, dtype=np.float64),
        sigma_accel_m_s2=sigma_a,
        sigma_gyro_rad_s=sigma_g,
        window_samples=w,
        threshold=1.0,  # the decision T < γ is made by the caller (γ may be ≤ 0)
        gravity_m_s2=gravity,
    )
    return np.asarray(out, dtype=np.float64)


def detect_static(
    log: ImuLog,
    *,
    window_s: float = 0.2,
    threshold: float | None = None,
    method: str = "glrt",
    sigma_a: float | None = None,
    sigma_g: float | None = None,
    gyro_bias: ArrayLike | None = None,
    gravity: float | None = None,
    min_duration_s: float = 0.0,
    false_alarm: float = 1e-3,
    window_samples: int | None = None,
) -> StaticIntervals:
    """Detect static intervals with the SHOE GLRT (see the module docs for the defaults).

    Parameters
    ----------
    log : ImuLog
        Uniformly sampled log (gyro rad/s, accel m/s²).
    window_s : float
        Window length (s); W = max(3, round(window_s · rate)) samples, at most
        :data:`MAX_WINDOW_SAMPLES`.
    threshold : float, optional
        γ; default from the χ² quantile at ``false_alarm``.
    method : {"glrt", "shoe"}
        Both names select the SHOE GLRT.
    sigma_a, sigma_g : float, optional
        Per-sample noise std (m/s², rad/s); default estimated from the quietest windows.
    gyro_bias : array_like, shape (3,), optional
        Gyro bias removed before the test (rad/s); default estimated.
    gravity : float, optional
        |g| (m/s²); default estimated.
    min_duration_s : float
        Static runs shorter than this are discarded.
    false_alarm : float
        Probability that a static window exceeds the default threshold.
    window_samples : int, optional
        W in samples, instead of ``window_s`` (then the sampling need not be uniform unless
        ``min_duration_s`` is set).

    Returns
    -------
    StaticIntervals

    Raises
    ------
    InputError
        Unknown method, window longer than the log or than :data:`MAX_WINDOW_SAMPLES`,
        non-uniform sampling, bad parameters, non-finite data.
    """
    log = require_log(log)
    if method not in ("glrt", "shoe"):
        raise InputError(f"method: expected 'glrt' (SHOE), got {method!r}")
    for name, value, lo in (("window_s", window_s, 0.0), ("min_duration_s", min_duration_s, None)):
        ok = (
            isinstance(value, int | float)
            and math.isfinite(value)
            and (value > lo if lo is not None else value >= 0)
        )
        if not ok:
            bound = "> 0" if lo is not None else ">= 0"
            raise InputError(f"{name}: expected a finite number of seconds {bound}, got {value!r}")
    if window_samples is None:
        w_f = window_s * log.uniform_rate(rtol=0.05)
        if not w_f <= log.n:  # (also inf: 1e308 s × 100 Hz, which round() cannot take)
            raise InputError(f"window_s: {window_s:g} s is longer than the log ({log.n} samples)")
        w = max(3, round(w_f))
        what = "window_s"
    else:
        w = int(window_samples)
        what = "window_samples"
        if w < 1:
            raise InputError(f"window_samples: expected an int >= 1, got {window_samples!r}")
    if w > log.n:
        raise InputError(f"{what}: window of {w} samples is longer than the log ({log.n} samples)")
    if w > MAX_WINDOW_SAMPLES:
        raise InputError(
            f"{what}: window of {w} samples is longer than the detector's {MAX_WINDOW_SAMPLES}; "
            "use a shorter window or resample the log"
        )
    if not 0 < false_alarm < 1:
        raise InputError(f"false_alarm: must be in (0, 1), got {false_alarm!r}")
    if threshold is not None and not (math.isfinite(threshold) and threshold >= 0):
        # the statistic is >= 0: a negative threshold would silently find nothing, inf everything
        raise InputError(f"threshold: must be finite and >= 0, got {threshold!r}")
    s_a, s_g, g_mag, b_in = sigma_a, sigma_g, gravity, gyro_bias
    if s_a is None or s_g is None or g_mag is None or b_in is None:
        if w < 3:
            raise InputError(f"{what}: estimating the noise needs a window of >= 3 samples, got {w}")
        est = _quiet_estimates(log, w)
        s_a = est.sigma_a if s_a is None else s_a
        s_g = est.sigma_g if s_g is None else s_g
        g_mag = est.gravity if g_mag is None else g_mag
        b_in = est.gyro_bias if b_in is None else b_in
    s_a, s_g, g_mag = float(s_a), float(s_g), float(g_mag)
    if not (s_a > 0 and s_g > 0 and math.isfinite(s_a) and math.isfinite(s_g)):
        raise InputError(f"sigma_a and sigma_g must be finite and > 0, got {s_a!r}, {s_g!r}")
    b = np.asarray(b_in, dtype=np.float64)
    if b.shape != (3,):
        raise InputError(f"gyro_bias: expected shape (3,), got {b.shape}")
    if threshold is None:
        from scipy import stats  # slow to import; only the default threshold needs it

        gamma = 1.5 * float(stats.chi2.ppf(1.0 - false_alarm, 6 * w - 2)) / w
        if not math.isfinite(gamma):  # 1 − false_alarm rounds to 1 below ≈ 1e-16
            raise InputError(f"false_alarm: {false_alarm!r} is too small for a finite threshold (≥ 1e-15)")
    else:
        gamma = float(threshold)
    stat = _rust_statistic(log.accel, log.gyro - b[None, :], w, s_a, s_g, g_mag)
    mask = stat < gamma
    if min_duration_s > 0:
        rate = log.uniform_rate(rtol=0.05)
        for t0, t1 in _mask_to_intervals(np.arange(log.n, dtype=np.float64), mask):
            if (t1 - t0 + 1) / rate < min_duration_s:
                mask[int(t0) : int(t1) + 1] = False
    return StaticIntervals(
        mask=mask,
        intervals=_mask_to_intervals(log.t, mask),
        statistic=stat,
        threshold=gamma,
        sigma_a=s_a,
        sigma_g=s_g,
        gravity=g_mag,
        window_samples=w,
        gyro_bias=b,
    )


__all__ = ["MAX_WINDOW_SAMPLES", "StaticIntervals", "detect_static"]
