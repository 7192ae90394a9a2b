"""Shared pieces of the thermal models: input checks, clipping to the calibrated range, the
65/20/15 split uniform over temperature, and the selection rule of eqs. (32)–(33)."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav.errors import InputError, UasnavError

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


#: Physical range of a sensor die temperature (°C): training data and model files outside it
#: are refused. Wider than any IMU's operating range (typically −40…85 °C, −55…125 °C for
#: military grades) so that only corrupt or mis-scaled values are caught.
TEMP_MIN_C = -100.0
TEMP_MAX_C = 200.0
#: Largest |bias| (rad/s) accepted for training: ≈ 5700 °/s, above the full scale of any MEMS
#: gyro (±2000 °/s ≈ ±35 rad/s); larger values are corrupt or not in rad/s.
BIAS_MAX_RADS = 100.0


class TemperatureRangeWarning(UserWarning):
    """Temperatures outside a model's calibrated range were clipped to it (never extrapolated)."""


class NotFittedError(UasnavError, AttributeError):
    """A model was used before ``fit`` (or loading)."""


def check_temp(temp: ArrayLike, name: str = "temp") -> FloatArray:
    """Temperatures (n,) °C as a finite float64 vector, or :class:`InputError`."""
    t = np.ascontiguousarray(np.asarray(temp, dtype=np.float64))
    if t.ndim == 0:
        t = t[None]
    if t.ndim != 1:
        raise InputError(f"{name}: expected shape (n,), got {t.shape}")
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise InputError(f"{name}: non-finite temperature at row {bad[0]}")
    return t


def check_training_temp(temp: ArrayLike, name: str = "temp") -> FloatArray:
    """Temperatures (n,) °C to train a model on: finite and inside the physical range
    [:data:`TEMP_MIN_C`, :data:`TEMP_MAX_C`] °C, or :class:`InputError` naming the first bad row.

    A model's calibrated range is the span of its training temperatures; one absurd value
    (1e308 °C from a corrupt log) would otherwise make a "valid" model over [27, 1e308] °C.
    """
    t = check_temp(temp, name)
    out = np.flatnonzero((t < TEMP_MIN_C) | (t > TEMP_MAX_C))
    if out.size:
        i = int(out[0])
        raise temp_range_error(name, float(t[i]), i, int(out.size))
    return t


def temp_range_error(name: str, value_c: float, row: int, count: int) -> InputError:
    """The error of :func:`check_training_temp`: ``value_c`` (°C) at ``row`` is the first of
    ``count`` temperatures outside the physical range."""
    return InputError(
        f"{name}: {value_c:g} °C at row {row} is outside the physical range "
        f"[{TEMP_MIN_C:g}, {TEMP_MAX_C:g}] °C of a sensor die temperature "
        f"({count} such row{'s' if count > 1 else ''})"
    )


def check_fit_data(temp: ArrayLike, bias: ArrayLike, min_samples: int = 4) -> tuple[FloatArray, FloatArray]:
    """(temp (n,) °C, bias (n, k) rad/s) validated for fitting: temperatures finite and physical
    (:func:`check_training_temp`), biases finite and within ±:data:`BIAS_MAX_RADS` rad/s, at
    least ``min_samples`` samples, a temperature span > 0."""
    t = check_training_temp(temp)
    b = np.asarray(bias, dtype=np.float64)
    if b.ndim == 1:
        b = b[:, None]
    if b.ndim != 2 or b.shape[0] != t.size or b.shape[1] == 0:
        raise InputError(f"bias: expected shape ({t.size}, k) matching temp, got {b.shape}")
    bad = np.argwhere(~np.isfinite(b))
    if bad.size:
        raise InputError(f"bias: non-finite value at row {bad[0][0]}, column {bad[0][1]}")
    big = np.argwhere(np.abs(b) > BIAS_MAX_RADS)
    if big.size:
        i, j = int(big[0][0]), int(big[0][1])
        raise InputError(
            f"bias: {b[i, j]:g} rad/s at row {i}, column {j} exceeds ±{BIAS_MAX_RADS:g} rad/s "
            "(beyond any gyro's full scale; is the unit rad/s?)"
        )
    if t.size < min_samples:
        raise InputError(f"temp: need at least {min_samples} samples to fit, got {t.size}")
    if np.ptp(t) <= 0:
        raise InputError("temp: all temperatures are equal; a thermal model needs a temperature span")
    return t, b


def clip_temp(temp: FloatArray, lo: float, hi: float, model: str) -> tuple[FloatArray, BoolArray]:
    """Clip to [lo, hi]; warn with :class:`TemperatureRangeWarning` if any sample was clipped."""
    clipped = (temp < lo) | (temp > hi)
    if clipped.any():
        warnings.warn(
            f"{model}: {int(clipped.sum())} of {temp.size} temperatures outside the calibrated range "
            f"[{lo:.2f}, {hi:.2f}] °C (min {temp.min():.2f}, max {temp.max():.2f}) were clipped to it",
            TemperatureRangeWarning,
            stacklevel=3,
        )
    return np.clip(temp, lo, hi), clipped


def split_uniform(
    temp: FloatArray, fractions=(0.65, 0.20, 0.15), seed: int = 0
) -> tuple[NDArray[np.intp], ...]:
    """Indices of train / validation / test subsets spread uniformly over temperature.

    Samples are sorted by temperature and dealt out in consecutive blocks of 20 (13 train,
    4 validation, 3 test for 65/20/15 %), shuffled inside each block, so every subset covers the
    whole range with the same density (the thesis' "uniformly distributed subsets", §4.2.3.1).
    """
    f = np.asarray(fractions, dtype=float)
    if f.shape != (3,) or np.any(f < 0) or abs(f.sum() - 1.0) > 1e-9:
        raise InputError(f"fractions: expected three non-negative numbers summing to 1, got {fractions}")
    block = 20
    counts = np.round(f * block).astype(int)
    counts[0] = block - counts[1] - counts[2]
    labels = np.repeat(np.arange(3), counts)
    order = np.argsort(temp, kind="stable")
    rng = np.random.default_rng(seed)
    n = temp.size
    lab = np.empty(n, dtype=int)
    for s in range(0, n, block):
        m = min(block, n - s)
        lab[s : s + m] = rng.permutation(labels)[:m]
    out = tuple(np.sort(order[lab == k]) for k in range(3))
    return out


def subsample_uniform(n: int, max_samples: int) -> NDArray[np.intp]:
    """Evenly spaced indices keeping at most ``max_samples`` of ``n``."""
    if n <= max_samples:
        return np.arange(n)
    return np.unique(np.linspace(0, n - 1, max_samples).round().astype(np.intp))


def sr(residuals: FloatArray) -> float:
    """Performance parameter Sr = √(res₁² + res₂² + res₃²) of eqs. (32), (33), (37), with
    res_i the RMS residual of axis i (residuals (n, k))."""
    rms = np.sqrt(np.mean(np.asarray(residuals) ** 2, axis=0))
    return float(np.sqrt(np.sum(rms**2)))


@dataclass(frozen=True)
class SelectionResult:
    """Outcome of an order / structure selection by Sr (eqs. 32, 33, 37).

    Attributes
    ----------
    candidates : tuple of int
        Polynomial orders or neurons per hidden layer tried.
    sr : ndarray, shape (len(candidates),)
        Sr on held-out data (output unit, rad/s or rad/s/°C).
    chosen : int
        The selected candidate (see :func:`choose`).
    rel_tol : float
        Relative tolerance of the "no significant improvement" rule.
    """

    candidates: tuple[int, ...]
    sr: FloatArray
    chosen: int
    rel_tol: float

    def plot(self, *, xlabel: str, ylabel: str = "Sr (rad/s)", ax: Any = None) -> Any:
        """Sr vs candidate on a log scale with the chosen one marked (thesis Figures 31, 32,
        37); returns the matplotlib Axes."""
        if ax is None:
            from uasnav.plotting import new_figure

            _, ax = new_figure()
        ax.semilogy(self.candidates, self.sr, "o-")
        ax.axvline(self.chosen, color="C1", ls="--", label=f"chosen: {self.chosen}")
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.legend()
        return ax


def choose(candidates: tuple[int, ...], srs: FloatArray, rel_tol: float = 0.05) -> int:
    """The thesis' rule made explicit: the minimum of Sr, or the smallest candidate whose Sr is
    within ``rel_tol`` (5 %) of the minimum — larger ones bring "no significant improvement"."""
    srs = np.asarray(srs, dtype=float)
    best = float(np.nanmin(srs))
    ok = np.flatnonzero(srs <= best * (1.0 + rel_tol))
    return int(candidates[int(ok[0])])
