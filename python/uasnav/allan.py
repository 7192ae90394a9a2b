"""Overlapping Allan deviation of inertial sensor rate series.

Mirrors :func:`allantools.oadev` (``oadev(data, rate=1.0, taus=...)``) but computes in Rust
(one O(N) pass per cluster time, GIL released), accepts multi-axis ``(n, k)`` arrays in one
call, and returns an :class:`AllanResult` dataclass with error bars instead of a bare tuple.

Notes
-----
With ``θ_k = τ₀·Σ_{i<k} Ω_i`` (thesis eq. 26) and τ = m·τ₀, the overlapping Allan variance is

    σ²(τ) = 1 / (2 τ² (N + 1 − 2m)) · Σ_k (θ_{k+2m} − 2θ_{k+m} + θ_k)²        (thesis eq. 28)

the maximal-overlap estimator of IEEE Std 952-1997 and NIST SP 1065 §5.2.4.

References
----------
W. J. Riley, *Handbook of Frequency Stability Analysis*, NIST SP 1065 (2008).
IEEE Std 952-1997, Annex C.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import stats

from uasnav import _core
from uasnav.errors import InputError, NumericalError
from uasnav.limits import check_work

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from uasnav.noise import NoiseReport

TauSpec = Literal["octave", "decade", "all"] | Sequence[float] | NDArray[np.float64]
NoiseType = Literal["white", "flicker", "random-walk"]

# Power-law exponent α of the frequency (rate) PSD for each noise name (NIST SP 1065 §5.2).
#: Highest sample rate accepted (Hz): far beyond any inertial sensor; above, τ₀² underflows.
_MAX_RATE_HZ = 1e12
#: Data whose largest magnitude exceeds this are scaled by a power of two before squaring.
_SCALE_ABOVE = 1e100

_ALPHA = {"white": 0, "flicker": -1, "random-walk": -2}


@dataclass(frozen=True)
class AllanResult:
    """An Allan deviation curve (one column per input axis).

    Attributes
    ----------
    taus : ndarray, shape (k,)
        Cluster times τ (s).
    m : ndarray of int, shape (k,)
        Cluster sizes (samples).
    adev : ndarray, shape (k,) or (k, c)
        Allan deviation σ(τ), in the unit of the data (``unit``).
    avar : ndarray, same shape as ``adev``
        Allan variance σ²(τ), unit².
    n_terms : ndarray of int, shape (k,)
        Number of second differences averaged at each τ.
    rel_error : ndarray, shape (k,)
        Relative 1-σ error of σ(τ), ``1/√(2(N/m − 1))`` (IEEE Std 952 C.1).
    edf : ndarray, shape (k,)
        Equivalent degrees of freedom (NIST SP 1065 Table 5 approximations) for ``noise``.
    ci_low, ci_high : ndarray, same shape as ``adev``
        χ² confidence interval of σ(τ) at ``confidence``.
    rate : float
        Sample rate (Hz).
    n_samples : int
        Length of the input series.
    unit : str
        Unit of the data (``"rad/s"``, ``"m/s^2"``, … or ``""`` if not given).
    confidence : float
        Confidence level of ``ci_low``/``ci_high``.
    noise : str
        Noise type assumed for the EDF.
    """

    taus: NDArray[np.float64]
    m: NDArray[np.int64]
    adev: NDArray[np.float64]
    avar: NDArray[np.float64]
    n_terms: NDArray[np.int64]
    rel_error: NDArray[np.float64]
    edf: NDArray[np.float64]
    ci_low: NDArray[np.float64]
    ci_high: NDArray[np.float64]
    rate: float
    n_samples: int
    unit: str
    confidence: float
    noise: str

    @property
    def error(self) -> NDArray[np.float64]:
        """1-σ error bar of σ(τ) (``adev · rel_error``), same shape as ``adev``."""
        rel = self.rel_error if self.adev.ndim == 1 else self.rel_error[:, None]
        return self.adev * rel

    def identify(
        self,
        kind: Literal["gyro", "accel"] | None = None,
        *,
        min_tau: float | Literal["auto"] | None = "auto",
    ) -> NoiseReport:
        """Identify the IEEE 952 noise terms of this curve (see :func:`uasnav.noise.identify`)."""
        from uasnav.noise import identify

        return identify(self, kind=kind, min_tau=min_tau)

    def plot(
        self,
        ax: Axes | None = None,
        labels: Sequence[str] | None = None,
        errorbars: bool = True,
    ) -> Axes:
        """Log-log plot of σ(τ) with confidence intervals; returns the axes."""
        return plot_adev(self, ax=ax, labels=labels, errorbars=errorbars)


def plot_adev(
    res: AllanResult,
    ax: Axes | None = None,
    labels: Sequence[str] | None = None,
    errorbars: bool = True,
    report: NoiseReport | None = None,
) -> Axes:
    """Log-log Allan deviation with χ² intervals, optional fitted model and slope guides."""
    if ax is None:
        from uasnav.plotting import new_figure

        _, ax = new_figure()
    adev = res.adev if res.adev.ndim == 2 else res.adev[:, None]
    lo = res.ci_low if res.ci_low.ndim == 2 else res.ci_low[:, None]
    hi = res.ci_high if res.ci_high.ndim == 2 else res.ci_high[:, None]
    names = list(labels) if labels is not None else [f"axis {j}" for j in range(adev.shape[1])]
    # σ = 0 (a noise-free axis, a skipped fit) has no place on a log axis: leave it out, and say
    # so in the legend, rather than let matplotlib warn about non-positive values.
    ax.set_xscale("log")
    ax.set_yscale("log")
    positive = lambda a: np.where(a > 0, a, np.nan)  # noqa: E731
    for j in range(adev.shape[1]):
        if not np.any(adev[:, j] > 0):
            ax.plot([], [], " ", label=f"{names[j]}: σ(τ) = 0 (no noise above resolution)")
            continue
        (line,) = ax.plot(res.taus, positive(adev[:, j]), "o-", ms=3, label=names[j])
        if errorbars:
            ok = (lo[:, j] > 0) & (hi[:, j] > 0)
            ax.fill_between(res.taus, lo[:, j], hi[:, j], where=ok, color=line.get_color(), alpha=0.2, lw=0)
        if report is not None and np.any(report.model_adev()[:, j] > 0):
            ax.plot(res.taus, positive(report.model_adev()[:, j]), "--", color=line.get_color(), lw=1)
    if not np.any(adev > 0):
        ax.set_xlim(float(res.taus[0]) / 2.0, float(res.taus[-1]) * 2.0)
        ax.set_ylim(1e-3, 1.0)  # an empty panel: fixed limits instead of autoscaling no data
    if report is not None and adev.size:
        _slope_guides(ax, res, report)
    ax.set_xlabel("cluster time τ (s)")
    ax.set_ylabel(f"Allan deviation σ(τ) ({res.unit})" if res.unit else "Allan deviation σ(τ)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def _slope_guides(ax: Axes, res: AllanResult, report: NoiseReport) -> None:
    """Dotted lines of slope −½ through N at τ = 1 s and +½ through K at τ = 3 s (axis 0)."""
    t = res.taus
    # only terms the data identify (a guide through an unidentified value would suggest one)
    ok = report.identifiable[:, 0] if report.identifiable.shape[1] else np.ones(5, dtype=bool)
    n = float(report.fit.random_walk[0]) * ok[1]
    k = float(report.fit.rate_random_walk[0]) * ok[3]
    b = float(report.fit.bias_instability[0]) * ok[2]
    if n > 0:
        ax.loglog(t, n / np.sqrt(t), ":", color="grey", lw=1, label="slope −½ (N)")
    if k > 0:
        ax.loglog(t, k * np.sqrt(t / 3.0), ":", color="black", lw=1, label="slope +½ (K)")
    if b > 0:
        ax.axhline(0.664 * b, ls="-.", color="grey", lw=0.8, label="0.664·B")


def _edf(n_phase: int, m: NDArray[np.int64], alpha: int) -> NDArray[np.float64]:
    """EDF of the overlapping Allan variance, NIST SP 1065 Table 5 (Howe et al. 1981)."""
    N = float(n_phase)
    mf = m.astype(np.float64)
    if alpha == 0:  # white FM (white rate noise: ARW/VRW)
        return (3.0 * (N - 1.0) / (2.0 * mf) - 2.0 * (N - 2.0) / N) * (4.0 * mf**2 / (4.0 * mf**2 + 5.0))
    if alpha == -1:  # flicker FM (bias instability)
        out = 5.0 * N**2 / (4.0 * mf * (N + 3.0 * mf))
        return np.where(mf == 1, 2.0 * (N - 2.0) / (2.3 * N - 4.9), out)
    if alpha == -2:  # random-walk FM (rate random walk)
        return (N - 2.0) / (mf * (N - 3.0) ** 2) * ((N - 1.0) ** 2 - 3.0 * mf * (N - 1.0) + 4.0 * mf**2)
    raise InputError(f"noise: unsupported power-law exponent {alpha}")


def cluster_sizes(n: int, rate: float, taus: TauSpec) -> NDArray[np.int64]:
    """Cluster sizes m for ``n`` samples at ``rate`` Hz: a spacing name or cluster times (s).

    Cluster times are mapped to ``m = round(τ·rate)`` when that is within 1e-9 of an integer,
    else ``floor`` (as allantools); duplicates are removed; a τ longer than the series allows
    (fewer than two second differences) raises :class:`InputError`.
    """
    if not (math.isfinite(rate) and rate > 0):
        raise InputError(f"rate: must be finite and > 0, got {rate!r}")
    if isinstance(taus, str):
        ms = _core.allan_cluster_sizes(int(n), taus)
        if not ms:
            raise InputError(f"data: {n} samples are too few for any cluster time")
        return np.asarray(ms, dtype=np.int64)
    t = np.asarray(taus, dtype=np.float64).ravel()
    if t.size == 0:
        raise InputError("taus: empty list of cluster times")
    ms_list = [_core.allan_cluster_size_for_tau(float(x), 1.0 / rate) for x in t]
    max_m = (n - 1) // 2
    too_long = [float(x) for x, m in zip(t, ms_list, strict=True) if m > max_m]
    if too_long:
        raise InputError(
            f"taus: {too_long[0]:g} s is too long for {n} samples at {rate:g} Hz (maximum {max_m / rate:g} s)"
        )
    return np.unique(np.asarray(ms_list, dtype=np.int64))


def oadev(
    data: ArrayLike,
    rate: float = 1.0,
    taus: TauSpec = "octave",
    *,
    unit: str = "",
    confidence: float = 0.683,
    noise: NoiseType = "white",
) -> AllanResult:
    """Overlapping Allan deviation of a rate series.

    Parameters
    ----------
    data : array_like, shape (n,) or (n, c)
        Rate samples (e.g. gyro rad/s or accelerometer m/s²), uniformly sampled; each column
        is an axis.
    rate : float
        Sample rate (Hz), > 0.
    taus : {"octave", "decade", "all"} or sequence of float
        Cluster-size spacing (m = 1, 2, 4, 8…; 1, 2, 4, 10, 20, 40…; every m) or cluster
        times in seconds.
    unit : str, optional
        Unit of ``data``, carried into the result (for plots and noise identification).
    confidence : float
        Confidence level of the χ² interval (default 0.683, i.e. ±1σ).
    noise : {"white", "flicker", "random-walk"}
        Noise type assumed for the equivalent degrees of freedom (default: white rate noise,
        which dominates inertial sensors at short τ).

    Returns
    -------
    AllanResult

    Raises
    ------
    InputError
        On NaN/inf (the message names the row and column), fewer than 3 samples, a
        non-positive rate, an unknown spacing or a cluster time too long for the data.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> r = oadev(rng.normal(0, 0.01, 100_000), rate=100.0)
    >>> bool(abs(r.adev[0] / 0.01 - 1) < 0.02)   # white noise: σ(τ₀) = σ
    True
    """
    arr = np.asarray(data, dtype=np.float64)
    if arr.ndim not in (1, 2):
        raise InputError(f"data: expected shape (n,) or (n, c), got {arr.shape}")
    if not (np.isfinite(rate) and rate > 0):
        raise InputError(f"rate: must be finite and > 0, got {rate}")
    if not (0.0 < confidence < 1.0):
        raise InputError(f"confidence: must be in (0, 1), got {confidence}")
    if noise not in _ALPHA:
        raise InputError(f"noise: expected one of {sorted(_ALPHA)}, got {noise!r}")
    one_d = arr.ndim == 1
    mat = np.ascontiguousarray(arr[:, None] if one_d else arr)
    n = mat.shape[0]
    if n < 3:
        raise InputError(f"data: too short ({n} samples, need at least 3)")
    if rate > _MAX_RATE_HZ:
        raise InputError(
            f"rate: {rate:g} Hz is beyond any sensor's sample rate (at most {_MAX_RATE_HZ:g} Hz)"
        )
    ms = cluster_sizes(n, rate, taus)
    # one pass over the n phase samples of each column per cluster size (≈ 4 operations each)
    check_work(
        4.0 * n * mat.shape[1] * len(ms),
        f"Allan deviation of {n} samples × {mat.shape[1]} axes at {len(ms)} cluster sizes",
        option='taus ("octave" or "decade" instead of "all")',
    )
    # A constant column (a noise-free or quantisation-limited axis) has σ(τ) = 0 exactly; summed
    # into the phase, its value would leave float rounding (~1e-25) instead: zero it (a copy).
    # Column extremes in two reductions, no n-sized temporaries (this runs on 10⁷-sample logs);
    # NaN/inf are left for the Rust core to report with their index.
    col_max, col_min = mat.max(axis=0), mat.min(axis=0)
    const = col_max == col_min
    if np.any(const):
        mat = mat.copy()
        mat[:, const] = 0.0
    # Squared differences of values near the float range overflow: compute on data scaled by a
    # power of two (exact, so ordinary data give bit-identical results) and scale back.
    peak = float(np.max(np.maximum(np.abs(col_max), np.abs(col_min)))) if mat.size else 0.0
    scale = 2.0 ** math.floor(math.log2(peak)) if math.isfinite(peak) and peak > _SCALE_ABOVE else 1.0
    tau_arr, avar, n_terms, rel = _core.allan_oavar(
        mat / scale if scale != 1.0 else mat, 1.0 / rate, [int(x) for x in ms]
    )
    with np.errstate(over="ignore", invalid="ignore"):
        adev = np.sqrt(avar) * scale
        avar = np.asarray(avar) * scale * scale
    edf = _edf(n + 1, ms, _ALPHA[noise])
    edf_c = np.maximum(edf, 1e-3)[:, None]
    lo_q = stats.chi2.ppf(0.5 + confidence / 2.0, edf_c)
    hi_q = stats.chi2.ppf(0.5 - confidence / 2.0, edf_c)
    ci_low = adev * np.sqrt(edf_c / lo_q)
    ci_high = adev * np.sqrt(edf_c / hi_q)
    if not all(np.all(np.isfinite(a)) for a in (avar, ci_low, ci_high)):
        # Never a silent NaN/inf deviation: say why instead.
        raise NumericalError(
            "Allan variance: not representable as a float (data or rate at the edge of the float range)"
        )
    squeeze = (lambda a: a[:, 0]) if one_d else (lambda a: a)
    return AllanResult(
        taus=np.asarray(tau_arr),
        m=ms,
        adev=squeeze(adev),
        avar=squeeze(avar),
        n_terms=np.asarray(n_terms, dtype=np.int64),
        rel_error=np.asarray(rel),
        edf=edf,
        ci_low=squeeze(ci_low),
        ci_high=squeeze(ci_high),
        rate=float(rate),
        n_samples=int(n),
        unit=unit,
        confidence=float(confidence),
        noise=noise,
    )


__all__ = ["AllanResult", "cluster_sizes", "oadev", "plot_adev"]
