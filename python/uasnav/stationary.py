"""Static-interval detection on IMU logs: the SHOE generalised likelihood-ratio test.

For a window Ω_k of W samples centred on sample k, the SHOE detector (Skog, Händel, Nilsson,
Rantakokko, *Zero-velocity detection — an algorithm evaluation*, IEEE TBME 57(11), 2010,
eq. 15) is

    T_k = 1/W Σ_{j∈Ω_k} [ ‖a_j − g ā_k/‖ā_k‖‖² / σ_a² + ‖ω_j − b_g‖² / σ_g² ]

and the unit is declared static where ``T_k < γ``. Vectorised with cumulative sums (one
O(n) pass, no Python loop over samples).

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
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy import stats

from uasnav.errors import InputError
from uasnav.imu import ImuLog

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class StaticIntervals:
    """Result of :func:`detect_static`.

    Attributes
    ----------
    mask : ndarray of bool, shape (n,)
        True where the unit is detected static.
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
    """

    mask: NDArray[np.bool_]
    intervals: list[tuple[float, float]]
    statistic: FloatArray = field(repr=False)
    threshold: float = 0.0
    sigma_a: float = 0.0
    sigma_g: float = 0.0
    gravity: float = 0.0

    @property
    def fraction(self) -> float:
        """Fraction of samples detected static."""
        return float(self.mask.mean())


def _window_sums(x: FloatArray, w: int) -> FloatArray:
    """Sums of ``x`` (n, …) over centred windows of ``w`` samples (clipped at the ends)."""
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


def detect_static(
    log: ImuLog,
    *,
    window_s: float = 0.2,
    threshold: float | None = None,
    method: str = "glrt",
    sigma_a: float | None = None,
    sigma_g: float | None = None,
    gyro_bias: NDArray[np.float64] | None = None,
    gravity: float | None = None,
    min_duration_s: float = 0.0,
    false_alarm: float = 1e-3,
) -> StaticIntervals:
    """Detect static intervals with the SHOE GLRT (see the module docs for the defaults).

    Parameters
    ----------
    log : ImuLog
        Uniformly sampled log (gyro rad/s, accel m/s²).
    window_s : float
        Window length (s); W = max(3, round(window_s · rate)) samples.
    threshold : float, optional
        γ; default from the χ² quantile at ``false_alarm``.
    method : {"glrt", "shoe"}
        Both names select the SHOE GLRT.
    sigma_a, sigma_g : float, optional
        Per-sample noise std (m/s², rad/s); default estimated from the quietest windows.
    gyro_bias : array (3,), optional
        Gyro bias removed before the test (rad/s); default estimated.
    gravity : float, optional
        |g| (m/s²); default estimated.
    min_duration_s : float
        Static runs shorter than this are discarded.
    false_alarm : float
        Probability that a static window exceeds the default threshold.

    Returns
    -------
    StaticIntervals
    """
    if method not in ("glrt", "shoe"):
        raise InputError(f"method: expected 'glrt' (SHOE), got {method!r}")
    rate = log.uniform_rate(rtol=0.05)
    w = max(3, round(window_s * rate))
    if w > log.n:
        raise InputError(f"window_s: window of {w} samples is longer than the log ({log.n} samples)")
    if not 0 < false_alarm < 1:
        raise InputError(f"false_alarm: must be in (0, 1), got {false_alarm!r}")
    a, g = log.accel, log.gyro
    sa = _window_sums(a, w)
    sg = _window_sums(g, w)
    saa = _window_sums(np.sum(a * a, axis=1), w)
    sgg = _window_sums(g * g, w)
    mean_a = sa / w
    mean_g = sg / w
    # per-window sample variance averaged over axes (noise level estimate)
    var_a = (_window_sums(a * a, w) / w - mean_a**2).mean(axis=1) * w / (w - 1)
    var_g = (sgg / w - mean_g**2).mean(axis=1) * w / (w - 1)
    quiet_a = var_a <= np.percentile(var_a, 20)
    quiet_g = var_g <= np.percentile(var_g, 20)
    quiet = quiet_a & quiet_g
    if not quiet.any():
        quiet = quiet_a
    s_a = math.sqrt(max(float(np.percentile(var_a, 20)), 1e-20)) if sigma_a is None else float(sigma_a)
    s_g = math.sqrt(max(float(np.percentile(var_g, 20)), 1e-20)) if sigma_g is None else float(sigma_g)
    if s_a <= 0 or s_g <= 0:
        raise InputError("sigma_a and sigma_g must be > 0")
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
    mask = stat < gamma
    if min_duration_s > 0:
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
    )


__all__ = ["StaticIntervals", "detect_static"]
