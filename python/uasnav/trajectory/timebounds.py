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

A handful of real runs cannot carry that guarantee (n runs give at most n/(n + 1)), and the
largest |miss| of a model that is biased for this vehicle makes a band centred on the biased
prediction. :class:`PaceBounds` is the parametric alternative for few runs: each run j gives
its slowest and fastest pace relative to the prediction,

    u_j = max over s of log((T(s) + τ)/(T̂(s) + τ)),   l_j = min over s of the same,

and, assuming u and l are each normal across runs (a vehicle flies a mission at its own pace,
scattered log-normally from run to run), the Student-t prediction bounds of a new run

    U = ū + t_{n−1,(1+c)/2}·s_u·√(1 + 1/n),   L = l̄ − t_{n−1,(1+c)/2}·s_l·√(1 + 1/n)

give the band (T̂ + τ + w)·e^L − τ − w ≤ T ≤ (T̂ + τ + w)·e^U − τ − w over the whole run with
probability ≥ c (each side misses with (1 − c)/2; Hahn & Meeker, *Statistical Intervals*,
2017, §4.7). The band follows the vehicle's own bias, and its lower edge at the departure is
below 0 when runs start early: the first volume then opens before the filed start.
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

    def describe(self, coverage: float = DEFAULT_COVERAGE) -> str:
        """What calibrated the bounds."""
        return self.source

    def to_dict(self) -> dict[str, object]:
        return {"scores": self.scores.tolist(), "tau_s": self.tau_s, "source": self.source}


#: Fewest runs :class:`PaceBounds` accepts (a standard deviation from two runs is no estimate).
MIN_PACE_RUNS = 3


@dataclass(frozen=True)
class PaceBounds:
    """Parametric time bounds from a few real runs (module: the Student-t prediction bounds of
    the runs' slowest and fastest log pace ratios).

    Attributes
    ----------
    upper_log : ndarray, shape (n,)
        u_j, each run's largest log((T + τ)/(T̂ + τ)).
    lower_log : ndarray, shape (n,)
        l_j, each run's smallest.
    tau_s : float
        Time floor τ, s.
    source : str
        What the runs were.
    runs : tuple of (ndarray, ndarray)
        Each run's true and predicted times, s (for :meth:`describe`'s held-out check; may
        be empty).
    """

    upper_log: np.ndarray = field(repr=False)
    lower_log: np.ndarray = field(repr=False)
    tau_s: float = DEFAULT_TAU_S
    source: str = ""
    runs: tuple[tuple[np.ndarray, np.ndarray], ...] = field(default=(), repr=False)

    @classmethod
    def of_runs(
        cls, runs: list[tuple[np.ndarray, np.ndarray]], tau_s: float = DEFAULT_TAU_S, source: str = ""
    ) -> PaceBounds:
        """The bounds of runs given as (true times, predicted times), s."""
        paces = [log_pace(t, p, tau_s) for t, p in runs]
        return cls(
            np.array([u for _, u in paces]),
            np.array([lo for lo, _ in paces]),
            tau_s,
            source,
            tuple((np.asarray(t, dtype=float), np.asarray(p, dtype=float)) for t, p in runs),
        )

    def describe(self, coverage: float = DEFAULT_COVERAGE) -> str:
        """The source, the assumption and, with the runs known, the leave-one-run-out check."""
        text = (
            f"{self.source}: Student-t prediction bounds of each run's slowest and fastest log pace "
            f"(T + {self.tau_s:g} s)/(T̂ + {self.tau_s:g} s), assuming they scatter normally from run to run"
        )
        if len(self.runs) > MIN_PACE_RUNS:
            k = sum(leave_one_run_out(list(self.runs), coverage, self.tau_s))
            text += f"; leave-one-run-out: {k}/{len(self.runs)} runs within the bounds of the others"
        return text

    def __post_init__(self) -> None:
        u = np.asarray(self.upper_log, dtype=float)
        lo = np.asarray(self.lower_log, dtype=float)
        if u.ndim != 1 or u.shape != lo.shape or not (np.all(np.isfinite(u)) and np.all(np.isfinite(lo))):
            raise InputError("pace bounds need two 1-D arrays of finite log ratios of the same length")
        if np.any(lo > u):
            raise InputError("a run's smallest log pace ratio exceeds its largest")
        if not (math.isfinite(self.tau_s) and self.tau_s > 0):
            raise InputError(f"tau_s must be finite and > 0, got {self.tau_s!r}")
        object.__setattr__(self, "upper_log", u)
        object.__setattr__(self, "lower_log", lo)

    @property
    def n_runs(self) -> int:
        return int(self.upper_log.size)

    def limits(self, coverage: float = DEFAULT_COVERAGE) -> tuple[float, float]:
        """(L, U): the prediction bounds of a new run's log pace ratios (module).

        Raises :class:`InputError` for a coverage outside (0, 1) or fewer than
        :data:`MIN_PACE_RUNS` runs.
        """
        from scipy.stats import t as student_t

        if not (0.0 < coverage < 1.0):
            raise InputError(f"coverage must be in (0, 1), got {coverage!r}")
        n = self.n_runs
        if n < MIN_PACE_RUNS:
            raise InputError(f"pace bounds need at least {MIN_PACE_RUNS} runs, have {n}")
        k = float(student_t.ppf((1.0 + coverage) / 2.0, n - 1)) * math.sqrt(1.0 + 1.0 / n)
        u, lo = self.upper_log, self.lower_log
        return float(lo.mean() - k * lo.std(ddof=1)), float(u.mean() + k * u.std(ddof=1))

    def quantile(self, coverage: float = DEFAULT_COVERAGE) -> float:
        """The band's largest relative half-width, max(e^U − 1, 1 − e^L): the counterpart of
        :meth:`TimeBounds.quantile` (the band is not symmetric about the prediction)."""
        lo, hi = self.limits(coverage)
        return max(math.expm1(hi), -math.expm1(lo))

    def band(
        self, t_pred_s: np.ndarray, widening_s: np.ndarray | float = 0.0, coverage: float = DEFAULT_COVERAGE
    ) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) bounds, s, of predicted times ``t_pred_s`` (the lower may be < 0:
        before the departure)."""
        lo, hi = self.limits(coverage)
        t = np.asarray(t_pred_s, dtype=float)
        scale = t + self.tau_s + np.asarray(widening_s, dtype=float)
        return t + scale * math.expm1(lo), t + scale * math.expm1(hi)

    def covers(self, t_true_s: np.ndarray, t_pred_s: np.ndarray, coverage: float = DEFAULT_COVERAGE) -> bool:
        """Whether every true time of a run lies within the band (no widening)."""
        lo, hi = self.band(t_pred_s, 0.0, coverage)
        t = np.asarray(t_true_s, dtype=float)
        return bool(np.all((lo <= t) & (t <= hi)))

    def to_dict(self) -> dict[str, object]:
        return {
            "kind": "student_t_log_pace",
            "upper_log": self.upper_log.tolist(),
            "lower_log": self.lower_log.tolist(),
            "tau_s": self.tau_s,
            "source": self.source,
        }


def log_pace(t_true_s: np.ndarray, t_pred_s: np.ndarray, tau_s: float = DEFAULT_TAU_S) -> tuple[float, float]:
    """(l, u) of one run: the smallest and largest log((T + τ)/(T̂ + τ)) over its times."""
    t, p = np.asarray(t_true_s, dtype=float), np.asarray(t_pred_s, dtype=float)
    if t.size == 0 or t.shape != p.shape or not (np.all(np.isfinite(t)) and np.all(np.isfinite(p))):
        raise InputError("a run needs finite true and predicted times, as many of each")
    if np.any(t + tau_s <= 0) or np.any(p + tau_s <= 0):
        raise InputError("times must be > −tau_s")
    r = np.log((t + tau_s) / (p + tau_s))
    return float(r.min()), float(r.max())


def leave_one_run_out(
    runs: list[tuple[np.ndarray, np.ndarray]],
    coverage: float = DEFAULT_COVERAGE,
    tau_s: float = DEFAULT_TAU_S,
) -> list[bool]:
    """For each run (true times, predicted times), whether the :class:`PaceBounds` of the
    other runs cover it: the held-out check of the parametric assumption on real runs."""
    paces = [log_pace(t, p, tau_s) for t, p in runs]
    out = []
    for j, (t, p) in enumerate(runs):
        rest = [x for i, x in enumerate(paces) if i != j]
        b = PaceBounds(np.array([u for _, u in rest]), np.array([lo for lo, _ in rest]), tau_s)
        out.append(b.covers(t, p, coverage))
    return out


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
    "MIN_PACE_RUNS",
    "PaceBounds",
    "TimeBounds",
    "clopper_pearson",
    "leave_one_run_out",
    "log_pace",
    "score",
    "widening",
]
