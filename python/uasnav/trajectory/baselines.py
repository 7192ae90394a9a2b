"""Baselines the LVQ predictor must beat, and a common evaluation (e%, eq. 59).

* distance ÷ speed: what ground stations print (QGroundControl uses the hover/cruise speed;
  Mission Planner's survey tool 0.8 × speed);
* per-cell mean-ΔV table: the 128-cell grid without a network (empty cell → global mean);
* regression on the same features: k-nearest neighbours and gradient boosting (scikit-learn);
* kinematic point mass: a speed profile along the plan with acceleration from rest, braking
  to a corner speed V·cos(θ/2) and to a stop at the end, no wind.

A class-based method (the two LVQ variants) is reported as not applicable, with the reason,
instead of as a number, when its training data cannot support it (see
:func:`class_method_reason`): e.g. 0.1 m/s ΔV bins over a few dozen real elements give almost one
class per element, and the "classifier" then memorises single samples.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from uasnav.errors import InputError
from uasnav.limits import check_memory
from uasnav.trajectory.geometry import plan_length
from uasnav.trajectory.samples import ElementSamples


def percent_error(t_pred: np.ndarray, t_real: np.ndarray) -> np.ndarray:
    """e% = |t_pred − t_real| / t_real · 100 (eq. 59)."""
    return np.abs(np.asarray(t_pred) - np.asarray(t_real)) / np.asarray(t_real) * 100.0


def distance_over_speed(length_m: np.ndarray, speed_ms: np.ndarray, factor: float = 1.0) -> np.ndarray:
    """t = L / (factor · V) (s); factor 0.8 is Mission Planner's survey estimate."""
    return np.asarray(length_m) / (factor * np.asarray(speed_ms))


class CellMeanDV:
    """ΔV = mean ΔV of the training elements in the element's own cell; global mean if empty."""

    def fit(self, train: ElementSamples) -> CellMeanDV:
        c = train.cell
        n = np.bincount(c, minlength=384)
        s = np.bincount(c, weights=train.dv_ms, minlength=384)
        self.table_ = np.where(n > 0, s / np.maximum(n, 1), train.dv_ms.mean())
        return self

    def predict_dv(self, test: ElementSamples) -> np.ndarray:
        return self.table_[test.cell]


class RegressorDV:
    """A scikit-learn regressor of ΔV on the network's input features."""

    def __init__(self, kind: str = "knn", random_state: int = 0) -> None:
        self.kind = kind
        self.random_state = random_state

    def fit(self, train: ElementSamples) -> RegressorDV:
        from sklearn.ensemble import GradientBoostingRegressor
        from sklearn.neighbors import KNeighborsRegressor

        if self.kind == "knn":
            self.model_ = KNeighborsRegressor(n_neighbors=min(5, len(train)))
        else:
            self.model_ = GradientBoostingRegressor(
                n_estimators=100, max_depth=2, learning_rate=0.1, random_state=self.random_state
            )
        self.model_.fit(train.features.matrix(), train.dv_ms)
        return self

    def predict_dv(self, test: ElementSamples) -> np.ndarray:
        return np.asarray(self.model_.predict(test.features.matrix()))


def kinematic_times(
    plan_ne: np.ndarray,
    s_start_m: np.ndarray,
    s_end_m: np.ndarray,
    cruise_ms: float,
    accel_ms2: float = 1.0,
    ds_m: float = 0.1,
    leg_speed_ms: np.ndarray | None = None,
) -> np.ndarray:
    """Times (s) to fly arc-length intervals [s_start, s_end] (m) of the plan for a point mass:
    v(s) = min(V_g(s), √(v_k² + 2a|s − s_k|) around each waypoint k)
    with V_g the commanded speed of the leg g holding s (``leg_speed_ms``, shape (n − 1,), m/s,
    NaN = ``cruise_ms``; default every leg at ``cruise_ms``), corner speed
    v_k = min(V_{k−1}, V_k)·max(cos(θ_k/2), 0.1) (the simulator's rule), 0 at the ends. A
    straight leg of length L flown from rest to rest at V takes L/V + V/a (L ≥ V²/a)."""
    checks = (("cruise_ms", cruise_ms, 1e4), ("accel_ms2", accel_ms2, 1e4), ("ds_m", ds_m, math.inf))
    for name, x, top in checks:
        if not (math.isfinite(x) and x > 0):
            raise InputError(f"{name}: must be finite and > 0, got {x!r}")
        if x > top:  # beyond any aircraft; squared, 1e308 would leave the float range
            raise InputError(f"{name}: {x:g} is beyond {top:g}")
    p = np.asarray(plan_ne, dtype=float)[:, :2]
    d = np.diff(p, axis=0)
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(d[:, 0], d[:, 1]))])
    total = plan_length(p)
    if not math.isfinite(total):
        raise InputError(f"plan_ne: the plan's length is not finite ({total!r} m)")
    check_memory(
        4 * 8 * (total / ds_m + 2), f"a kinematic profile of {total:g} m at {ds_m:g} m steps", option="ds_m"
    )
    s = np.arange(0.0, total + ds_m, ds_m)
    s[-1] = min(s[-1], total)
    v_leg = np.full(d.shape[0], float(cruise_ms))
    if leg_speed_ms is not None:
        ls = np.asarray(leg_speed_ms, dtype=float)
        if ls.shape != v_leg.shape or np.any(ls[np.isfinite(ls)] <= 0) or np.isinf(ls).any():
            raise InputError(f"leg_speed_ms needs {v_leg.size} speeds > 0 m/s (NaN = cruise), got {ls}")
        v_leg = np.where(np.isfinite(ls), ls, v_leg)
    v = v_leg[np.clip(np.searchsorted(cum, s, side="right") - 1, 0, v_leg.size - 1)]
    v_top = float(v_leg.max()) if v_leg.size else 0.0
    for k in range(p.shape[0]):
        if k in (0, p.shape[0] - 1):
            vk = 0.0
        else:
            c = d[k - 1] @ d[k] / (np.hypot(*d[k - 1]) * np.hypot(*d[k]))
            theta = np.arccos(np.clip(c, -1.0, 1.0))
            vk = min(v_leg[k - 1], v_leg[k]) * max(np.cos(theta / 2.0), 0.1)
        # The ramp around waypoint k exceeds every leg speed beyond (V_max² − v_k²)/2a of it:
        # only the grid points within reach (with a margin for rounding) can change, which keeps
        # the profile linear in the plan's length instead of quadratic in its points.
        reach = (v_top**2 - vk**2) / (2.0 * accel_ms2) * (1.0 + 1e-9) + 2.0 * ds_m
        lo, hi = np.searchsorted(s, [cum[k] - reach, cum[k] + reach])
        w = slice(int(lo), int(hi) + 1)
        v[w] = np.minimum(v[w], np.sqrt(vk**2 + 2.0 * accel_ms2 * np.abs(s[w] - cum[k])))
    # Time to each grid point: v² is linear in s on every ramp, so each grid interval is flown
    # at constant acceleration and takes exactly 2·Δs / (v₁ + v₂) (exact also from rest, where
    # the trapezoid rule on 1/v diverges; only intervals where the profile changes branch are
    # approximate).
    tau = np.concatenate([[0.0], np.cumsum(2.0 * np.diff(s) / np.maximum(v[1:] + v[:-1], 1e-9))])
    return np.interp(s_end_m, s, tau) - np.interp(s_start_m, s, tau)


#: Name of the method "kinematic point mass × median real/kinematic ratio of the training runs".
KINEMATIC_RESIDUAL = "kinematic + residual"


def kinematic_residual_factor(t_real_s: np.ndarray, t_kinematic_s: np.ndarray) -> float:
    """The learned residual of the kinematic model: Σ real ÷ Σ kinematic time of the training
    elements — the factor that makes the kinematic ETA of the training runs right (a median of
    per-element ratios was tried and did worse on the real runs: short elements cut by the
    telemetry's time resolution dominate it). 1 if there is no positive kinematic time."""
    r, k = np.asarray(t_real_s, dtype=float), np.asarray(t_kinematic_s, dtype=float)
    ok = np.isfinite(r) & np.isfinite(k) & (k > 0) & (r > 0)
    return float(r[ok].sum() / k[ok].sum()) if ok.any() else 1.0


#: A class-based method needs on average at least this many training elements per class.
#: Below it (more classes than half the samples) the classes are a regression target in disguise —
#: the same criterion as scikit-learn's "number of unique classes is greater than 50%" warning.
MIN_ELEMENTS_PER_CLASS = 2.0


def class_method_reason(labels: np.ndarray, what: str) -> str | None:
    """Why a classifier cannot be fitted sensibly on ``labels``, or None if it can.

    Rule: not applicable when the number of distinct classes k exceeds n / MIN_ELEMENTS_PER_CLASS
    for n training elements (fewer than two elements per class on average).

    Parameters
    ----------
    labels : ndarray, shape (n,)
        The class label of each training element.
    what : str
        What the classes are, for the message (e.g. "ΔV classes of 0.1 m/s").
    """
    y = np.asarray(labels)
    n = int(y.size)
    k = int(np.unique(y).size)
    if n == 0:
        return "no training elements"
    if k > n / MIN_ELEMENTS_PER_CLASS:
        return (
            f"{k} {what} from {n} training elements: fewer than {MIN_ELEMENTS_PER_CLASS:g} elements "
            "per class on average, so a classifier cannot be fitted sensibly (train on more "
            "elements or use coarser classes)"
        )
    return None


@dataclass
class MethodResult:
    """Predicted element times (s) of one method on the test elements and their e%.

    ``reason`` is None for a method that was fitted; otherwise it says why the method is not
    applicable to the training data given, and ``time_s`` and ``error_pct`` are NaN (never
    averaged: check :attr:`applicable`).
    """

    name: str
    time_s: np.ndarray
    error_pct: np.ndarray
    reason: str | None = None

    @property
    def applicable(self) -> bool:
        """True if the method was fitted and its times are predictions."""
        return self.reason is None

    @classmethod
    def not_applicable(cls, name: str, n_test: int, reason: str) -> MethodResult:
        """A method that could not be fitted: NaN times and e% for ``n_test`` elements."""
        nan = np.full(n_test, np.nan)
        return cls(name, nan, nan.copy(), reason)


def evaluate_methods(
    train: ElementSamples,
    test: ElementSamples,
    lvq_factory: Callable[[], object] | None = None,
    kinematic_s: np.ndarray | None = None,
    random_state: int = 0,
    kinematic_train_s: np.ndarray | None = None,
) -> list[MethodResult]:
    """Train every method on ``train`` and predict the element times of ``test``.

    ``kinematic_s`` are the point-mass times of the test elements (they need the plans; see
    :func:`kinematic_times`). With ``kinematic_train_s``, those of the training elements, the
    kinematic model plus a learned residual is evaluated too: the point-mass times scaled by
    :func:`kinematic_residual_factor` of the training elements (one factor: what the few real
    runs available can support without over-fitting). Returns one :class:`MethodResult` per
    method, LVQ first.
    """
    from uasnav.trajectory.predictor import TrajectoryPredictor

    out = []
    lvq = lvq_factory() if lvq_factory else TrajectoryPredictor(random_state=random_state)
    lvq_dv = TrajectoryPredictor(random_state=random_state, target="dv")
    for name, model in (("LVQ (thesis)", lvq), ("LVQ on ΔV classes", lvq_dv)):
        reason = class_method_reason(*_class_labels(model, train))
        if reason is not None:
            out.append(MethodResult.not_applicable(name, len(test), reason))
            continue
        t = model.fit(train).element_times(test.features, test.length_m, test.v_ref_ms)  # type: ignore[attr-defined]
        out.append(MethodResult(name, t, percent_error(t, test.t_real_s)))
    for name, factor in (("distance ÷ speed", 1.0), ("distance ÷ 0.8·speed", 0.8)):
        t = distance_over_speed(test.length_m, test.v_ref_ms, factor)
        out.append(MethodResult(name, t, percent_error(t, test.t_real_s)))
    for name, model in (
        ("per-cell mean ΔV", CellMeanDV()),
        ("kNN regression", RegressorDV("knn")),
        ("gradient boosting", RegressorDV("gbr", random_state)),
    ):
        dv = model.fit(train).predict_dv(test)  # type: ignore[attr-defined]
        t = test.length_m / np.maximum(test.v_ref_ms + dv, 0.2)
        out.append(MethodResult(name, t, percent_error(t, test.t_real_s)))
    if kinematic_s is not None:
        out.append(
            MethodResult("kinematic point mass", kinematic_s, percent_error(kinematic_s, test.t_real_s))
        )
        if kinematic_train_s is not None:
            t = kinematic_s * kinematic_residual_factor(train.t_real_s, kinematic_train_s)
            out.append(MethodResult(KINEMATIC_RESIDUAL, t, percent_error(t, test.t_real_s)))
    return out


def _class_labels(model: object, train: ElementSamples) -> tuple[np.ndarray, str]:
    """The labels a TrajectoryPredictor would train its network on, and what they are."""
    if getattr(model, "target", "cell") == "dv":
        width = float(getattr(model, "dv_bin_ms", 0.1))
        return np.rint(train.dv_ms / width), f"ΔV classes of {width:g} m/s"
    return train.cell, "populated feature cells"


__all__ = [
    "MIN_ELEMENTS_PER_CLASS",
    "CellMeanDV",
    "MethodResult",
    "RegressorDV",
    "class_method_reason",
    "distance_over_speed",
    "evaluate_methods",
    "kinematic_times",
    "percent_error",
]
