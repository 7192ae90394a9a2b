"""Calibrated time bounds of predicted waypoint times and ETA: normalised split-conformal.

For a prediction T̂(s) of the time at which the vehicle reaches arc length s of the plan
(cumulative element times), a calibration run with true times T(s) scores

    r = max over s in S of |T(s) − T̂(s)| / (T̂(s) + τ + w(s)),

S the element boundaries, τ a time floor (s; it keeps the first metres from dominating) and
w(s) the *widening*: the sum of the predicted times of the elements before s that the
predictor flags as outside its training data (a class without training data, a wind beyond
the trained range, a clamped speed) times :data:`FLAG_WIDENING`. With n calibration runs and
their scores sorted, r₍ₖ₎ with k = ⌈(n + 1)·c⌉ is the split-conformal quantile (Vovk et al.,
*Algorithmic Learning in a Random World*, 2005; Lei et al., JASA 2018): for a new run drawn
like the calibration runs, the band

    T̂(s) ± r₍ₖ₎·(T̂(s) + τ + w(s))     for every s at once

holds with probability ≥ c (the max over s makes the guarantee simultaneous over the whole
trajectory, which an operational intent needs). Flagged elements therefore widen the band
instead of only being flagged. The guarantee needs exchangeable runs: calibration on
simulated runs covers simulated runs; real flights are checked separately (k of n covered,
with a Clopper–Pearson interval, :func:`clopper_pearson`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from uasnav.errors import InputError

#: Time floor τ of the normalisation, s.
DEFAULT_TAU_S = 10.0
#: Fraction of a flagged element's predicted time added to the band's scale.
FLAG_WIDENING = 1.0
#: Default coverage of the bounds.
DEFAULT_COVERAGE = 0.95


@dataclass(frozen=True)
class TimeBounds:
    """Calibration of the time bounds: the sorted scores of the calibration runs.

    Attributes
    ----------
    scores : ndarray, shape (n,)
        Nonconformity scores r of the calibration runs, sorted ascending.
    tau_s : float
        Time floor τ, s.
    source : str
        What the runs were (e.g. ``"200 simulated runs, seed 0"``).
    """

    scores: np.ndarray = field(repr=False)
    tau_s: float = DEFAULT_TAU_S
    source: str = ""

    def __post_init__(self) -> None:
        s = np.asarray(self.scores, dtype=float)
        if s.ndim != 1 or s.size == 0 or not np.all(np.isfinite(s)) or np.any(s < 0):
            raise InputError("time-bound scores must be a non-empty 1-D array of finite values ≥ 0")
        if not (math.isfinite(self.tau_s) and self.tau_s >= 0):
            raise InputError(f"tau_s must be finite and ≥ 0, got {self.tau_s!r}")
        object.__setattr__(self, "scores", np.sort(s))

    @property
    def n_runs(self) -> int:
        return int(self.scores.size)

    def quantile(self, coverage: float = DEFAULT_COVERAGE) -> float:
        """The conformal quantile r₍ₖ₎, k = ⌈(n + 1)·coverage⌉.

        Raises :class:`InputError` if the coverage is outside (0, 1) or needs more runs than
        calibrated (k > n: n ≥ coverage/(1 − coverage) runs are needed, 19 for 95 %).
        """
        if not (0.0 < coverage < 1.0):
            raise InputError(f"coverage must be in (0, 1), got {coverage!r}")
        n = self.n_runs
        k = math.ceil((n + 1) * coverage - 1e-12)
        if k > n:
            raise InputError(
                f"coverage {coverage:g} needs at least {math.ceil(coverage / (1 - coverage))} "
                f"calibration runs, the calibration has {n}"
            )
        return float(self.scores[k - 1])

    def band(
        self, t_pred_s: np.ndarray, widening_s: np.ndarray | float = 0.0, coverage: float = DEFAULT_COVERAGE
    ) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) bounds, s, of predicted times ``t_pred_s`` (lower clipped at 0)."""
        t = np.asarray(t_pred_s, dtype=float)
        half = self.quantile(coverage) * (t + self.tau_s + np.asarray(widening_s, dtype=float))
        return np.maximum(t - half, 0.0), t + half

    def to_dict(self) -> dict[str, object]:
        return {"scores": self.scores.tolist(), "tau_s": self.tau_s, "source": self.source}


def widening(time_s: np.ndarray, flagged: np.ndarray) -> np.ndarray:
    """w at the element boundaries (m + 1,): cumulative :data:`FLAG_WIDENING` × time of the
    flagged elements before each boundary."""
    w = FLAG_WIDENING * np.where(np.asarray(flagged, dtype=bool), np.asarray(time_s, dtype=float), 0.0)
    return np.concatenate([[0.0], np.cumsum(w)])


def score(
    t_true_s: np.ndarray, t_pred_s: np.ndarray, widening_s: np.ndarray, tau_s: float = DEFAULT_TAU_S
) -> float:
    """Nonconformity r of one run (see module); NaN true times (never reached) are an error."""
    t, p = np.asarray(t_true_s, dtype=float), np.asarray(t_pred_s, dtype=float)
    if not np.all(np.isfinite(t)):
        raise InputError("a calibration run does not reach every element boundary")
    return float(np.max(np.abs(t - p) / (p + tau_s + np.asarray(widening_s, dtype=float))))


def clopper_pearson(k: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Exact (Clopper–Pearson) confidence interval of a proportion k/n.

    >>> lo, hi = clopper_pearson(19, 20)
    >>> round(lo, 4), round(hi, 4)
    (0.7513, 0.9987)
    """
    from scipy.stats import beta

    if not (0 <= k <= n and n > 0):
        raise InputError(f"need 0 ≤ k ≤ n and n > 0, got k={k}, n={n}")
    a = 1.0 - confidence
    lo = 0.0 if k == 0 else float(beta.ppf(a / 2, k, n - k + 1))
    hi = 1.0 if k == n else float(beta.ppf(1 - a / 2, k + 1, n - k))
    return lo, hi


__all__ = [
    "DEFAULT_COVERAGE",
    "DEFAULT_TAU_S",
    "FLAG_WIDENING",
    "TimeBounds",
    "clopper_pearson",
    "score",
    "widening",
]
