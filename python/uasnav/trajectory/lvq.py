"""Learning Vector Quantization classifier (Kohonen LVQ1, LVQ2.1; Sato–Yamada GLVQ).

A competitive layer of ``n_prototypes`` neurons (S¹) mapped to the target classes (S²) by a
fixed 0/1 layer (thesis Figure 54). Reference semantics are MATLAB's ``lvqnet``:

* learning rate 0.01, constant (``learnlv1``/``learnlv2`` do not decay it); ``lr_decay="linear"``
  is offered as Kohonen's recommended schedule α(t) = α₀(1 − t/T);
* samples presented one at a time in random order (``trainr``);
* competitive neurons shared among classes in proportion to class frequency (every class gets
  at least one; largest-remainder rounding);
* LVQ2.1 window w = 0.25: the winner i and the runner-up j are the two nearest *neurons* (by
  neuron index, whatever their class); both are updated only if exactly one is of the sample's
  class and min(d_i/d_j, d_j/d_i) > (1 − w)/(1 + w).

Initialisation: MATLAB puts every prototype at the midpoint of the input ranges
(``init="midpoint"``); ties are then broken by the lowest neuron index, which makes LVQ1 very
slow to separate neurons. The default ``init="sample"`` draws each class's prototypes from
that class's own training samples (with replacement if the class has fewer samples), a common
choice (Kohonen's LVQ_PAK) that converges in far fewer presentations.

Iterations: ``max_iter`` is the number of single-sample presentations; by default
max(50·S¹, n_samples) — Kohonen's 30–50 × prototypes rule, and at least one full epoch.
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

from uasnav.errors import InputError
from uasnav.limits import check_memory, check_work

_ALGORITHMS = ("lvq1", "lvq2.1", "glvq")


def neurons_per_class(counts: np.ndarray, n_prototypes: int) -> np.ndarray:
    """Share ``n_prototypes`` among classes in proportion to ``counts`` (≥ 1 each).

    Largest-remainder rounding of ``n_prototypes · counts / Σcounts`` (MATLAB lvqnet's class
    percentages); a class left with none takes one from the class holding most.
    """
    c = np.asarray(counts, dtype=float)
    k = c.size
    if n_prototypes < k:
        raise InputError(f"n_prototypes = {n_prototypes} is fewer than the {k} classes")
    share = n_prototypes * c / c.sum()
    n = np.floor(share).astype(int)
    rest = n_prototypes - int(n.sum())
    # Ties broken by class order (stable) so the split is deterministic.
    order = np.argsort(-(share - n), kind="stable")
    n[order[:rest]] += 1
    for i in np.flatnonzero(n == 0):
        n[int(np.argmax(n))] -= 1
        n[i] = 1
    return n


class LVQClassifier(ClassifierMixin, BaseEstimator):
    """LVQ network classifier, scikit-learn compatible.

    Parameters
    ----------
    n_prototypes : int, default 256
        Competitive neurons S¹ (the thesis uses 256 for 128 target classes).
    algorithm : {"lvq1", "lvq2.1", "glvq"}, default "lvq1"
        Update rule. ``glvq`` minimises Σ sigmoid(μ), μ = (d⁺ − d⁻)/(d⁺ + d⁻) with squared
        distances to the nearest correct (d⁺) and wrong (d⁻) prototypes (Sato & Yamada 1996).
    learning_rate : float, default 0.01
        α₀ (MATLAB lvqnet default).
    lr_decay : {"none", "linear"}, default "none"
        Constant α (MATLAB) or α(t) = α₀(1 − t/T).
    window : float, default 0.25
        LVQ2.1 window w.
    max_iter : int or None
        Single-sample presentations; None → max(50·S¹, n_samples).
    init : {"sample", "midpoint"}, default "sample"
        Prototype initialisation (see module notes).
    random_state : int, Generator or None
        Seed of the initialisation and presentation order.

    Attributes
    ----------
    classes_ : ndarray, shape (S²,)
    prototypes_ : ndarray, shape (S¹, n_features)
    prototype_labels_ : ndarray of int, shape (S¹,)
        Index into ``classes_`` of each neuron (the 0/1 second layer).
    n_iter_ : int
    n_features_in_ : int

    References
    ----------
    Kohonen, T. (1990) The self-organizing map, Proc. IEEE 78(9). Sato, A., Yamada, K. (1996)
    Generalized learning vector quantization, NIPS 8. MATLAB ``lvqnet``, ``learnlv1``,
    ``learnlv2``.
    """

    def __init__(
        self,
        n_prototypes: int = 256,
        algorithm: str = "lvq1",
        learning_rate: float = 0.01,
        lr_decay: str = "none",
        window: float = 0.25,
        max_iter: int | None = None,
        init: str = "sample",
        random_state: int | np.random.Generator | None = None,
    ) -> None:
        self.n_prototypes = n_prototypes
        self.algorithm = algorithm
        self.learning_rate = learning_rate
        self.lr_decay = lr_decay
        self.window = window
        self.max_iter = max_iter
        self.init = init
        self.random_state = random_state

    # -- fitting -------------------------------------------------------------------------
    def _check_params(self) -> None:
        if self.algorithm not in _ALGORITHMS:
            raise InputError(f"algorithm must be one of {_ALGORITHMS}, got {self.algorithm!r}")
        if self.lr_decay not in ("none", "linear"):
            raise InputError(f"lr_decay must be 'none' or 'linear', got {self.lr_decay!r}")
        if self.init not in ("sample", "midpoint"):
            raise InputError(f"init must be 'sample' or 'midpoint', got {self.init!r}")
        if not (np.isfinite(self.learning_rate) and self.learning_rate > 0):
            raise InputError(f"learning_rate must be > 0, got {self.learning_rate}")
        if not (0 < self.window < 1):
            raise InputError(f"window must be in (0, 1), got {self.window}")
        if self.max_iter is not None and self.max_iter < 1:
            raise InputError(f"max_iter must be ≥ 1, got {self.max_iter}")
        if isinstance(self.n_prototypes, bool) or not isinstance(self.n_prototypes, int | np.integer):
            raise InputError(f"n_prototypes must be an integer ≥ 1, got {self.n_prototypes!r}")

    @classmethod
    def from_arrays(
        cls, classes: np.ndarray, prototypes: np.ndarray, prototype_labels: np.ndarray, **params: object
    ) -> LVQClassifier:
        """A fitted classifier from its arrays (a saved model), checked: ``classes`` (S²,)
        integers, strictly increasing (as :func:`numpy.unique` leaves them); ``prototypes``
        (S¹, n_features) finite; ``prototype_labels`` (S¹,) indices into ``classes``, every class
        held by at least one prototype. Raises :class:`InputError` naming the array at fault."""
        c = np.asarray(classes)
        w = np.asarray(prototypes)
        lab = np.asarray(prototype_labels)
        if c.ndim != 1 or c.size < 2 or c.dtype.kind not in "iu" or np.any(np.diff(c) <= 0):
            raise InputError("classes: expected ≥ 2 distinct integers in increasing order")
        if w.ndim != 2 or w.shape[0] < 1 or w.shape[1] < 1 or w.dtype.kind not in "fiu":
            raise InputError(f"prototypes: expected a (S¹, n_features) matrix, got shape {w.shape}")
        if not np.isfinite(w).all():
            raise InputError("prototypes: non-finite value")
        if lab.shape != (w.shape[0],) or lab.dtype.kind not in "iu":
            raise InputError(f"prototype_labels: expected {w.shape[0]} integers (one per prototype)")
        if lab.min() < 0 or lab.max() >= c.size:
            raise InputError(f"prototype_labels: indices must be in 0…{c.size - 1}")
        if np.unique(lab).size != c.size:
            raise InputError("prototype_labels: a class has no prototype (it could never be predicted)")
        m = cls(n_prototypes=int(w.shape[0]), **params)  # type: ignore[arg-type]
        m.classes_ = c.astype(np.int64)
        m.prototypes_ = w.astype(np.float64)
        m.prototype_labels_ = lab.astype(np.intp)
        m.n_features_in_ = int(w.shape[1])
        m.n_iter_ = 0
        return m

    def fit(self, X: np.ndarray, y: np.ndarray) -> LVQClassifier:
        """Train on X, shape (n, n_features), labels y, shape (n,). Returns self."""
        self._check_params()
        X, y = validate_data(self, X, y, dtype=np.float64)
        check_classification_targets(y)
        classes, y_idx, counts = np.unique(y, return_inverse=True, return_counts=True)
        if classes.size < 2:
            raise ValueError(f"LVQ needs samples of at least 2 classes; got 1 class: {classes[0]!r}")
        _check_cost(int(self.n_prototypes), X.shape, self.max_iter)
        rng = np.random.default_rng(self.random_state)
        per = neurons_per_class(counts, int(self.n_prototypes))
        labels = np.repeat(np.arange(classes.size), per)
        if self.init == "midpoint":
            w = np.tile((X.min(axis=0) + X.max(axis=0)) / 2.0, (labels.size, 1))
        else:
            w = np.empty((labels.size, X.shape[1]))
            for c in range(classes.size):
                members = np.flatnonzero(y_idx == c)
                pick = rng.choice(members, size=per[c], replace=per[c] > members.size)
                w[labels == c] = X[pick]
        n_steps = int(self.max_iter) if self.max_iter is not None else max(50 * labels.size, X.shape[0])
        order = np.concatenate([rng.permutation(X.shape[0]) for _ in range(-(-n_steps // X.shape[0]))])[
            :n_steps
        ]
        step = {"lvq1": _train_lvq1, "lvq2.1": _train_lvq21, "glvq": _train_glvq}[self.algorithm]
        alpha = self.learning_rate * (
            1.0 - np.arange(n_steps) / n_steps if self.lr_decay == "linear" else np.ones(n_steps)
        )
        step(w, labels, X[order], y_idx[order], alpha, float(self.window))
        if not np.isfinite(w).all():
            raise ArithmeticError("LVQ prototypes became non-finite; lower learning_rate")
        self.classes_ = classes
        self.prototypes_ = w
        self.prototype_labels_ = labels
        self.n_iter_ = n_steps
        return self

    # -- prediction ----------------------------------------------------------------------
    def _dist2(self, X: np.ndarray) -> np.ndarray:
        w = self.prototypes_
        d = (X * X).sum(1)[:, None] - 2.0 * X @ w.T + (w * w).sum(1)[None, :]
        return np.maximum(d, 0.0)

    def winner(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Index of the winning neuron and its Euclidean distance (eq. 51), for each row of X.

        Exact nearest prototype by a k-d tree over the S¹ prototypes (built per call: S¹ is
        small), which on this shared 2-core machine is 3–7× faster than a chunked distance
        matrix; ties between equidistant prototypes may be broken differently from argmin.
        """
        from scipy.spatial import cKDTree

        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)
        dist, idx = cKDTree(self.prototypes_).query(X, k=1, workers=-1)
        return np.asarray(idx, dtype=np.intp), np.asarray(dist)

    def predict(self, X: np.ndarray) -> np.ndarray:
        """Class of the nearest prototype, shape (n,)."""
        j, _ = self.winner(X)
        return self.classes_[self.prototype_labels_[j]]

    def class_distances(self, X: np.ndarray) -> np.ndarray:
        """Distance from each sample to the nearest prototype of each class, shape (n, S²)."""
        check_is_fitted(self)
        X = validate_data(self, X, dtype=np.float64, reset=False)
        d = np.sqrt(self._dist2(X))
        out = np.full((X.shape[0], self.classes_.size), np.inf)
        for c in range(self.classes_.size):
            out[:, c] = d[:, self.prototype_labels_ == c].min(axis=1)
        return out

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        """Soft-min of the class distances, exp(−d²)/Σ, shape (n, S²) (a confidence, not a
        calibrated probability). Its argmax equals :meth:`predict`."""
        d = self.class_distances(X)
        z = -(d**2)
        z -= z.max(axis=1, keepdims=True)
        p = np.exp(z)
        return p / p.sum(axis=1, keepdims=True)

    def __sklearn_tags__(self):  # type: ignore[no-untyped-def]
        tags = super().__sklearn_tags__()
        tags.classifier_tags.multi_class = True
        return tags


def _check_cost(n_prototypes: int, x_shape: tuple[int, ...], max_iter: int | None) -> None:
    """Refuse, before allocating, a fit beyond the memory or work limit (:mod:`uasnav.limits`):
    the presentation order, learning rates and presented samples take n_steps·(n_features + 2)
    floats, and each presentation costs about S¹·n_features operations plus Python overhead."""
    n, nf = int(x_shape[0]), int(x_shape[1])
    n_steps = float(max_iter) if max_iter is not None else max(50.0 * n_prototypes, float(n))
    what = f"LVQ training with {n_prototypes} prototypes over {n_steps:.3g} presentations"
    hint = "n_prototypes (--prototypes)"
    check_memory(8.0 * (n_steps * (nf + 2) + n_prototypes * (nf + 2)), what, option=hint)
    check_work(n_steps * (3.0 * n_prototypes * nf + 5e3), what, option=hint)


def _train_lvq1(
    w: np.ndarray, labels: np.ndarray, xs: np.ndarray, ys: np.ndarray, alpha: np.ndarray, _window: float
) -> None:
    # Kohonen LVQ1 / MATLAB learnlv1: the winner moves toward a sample of its class, away otherwise.
    for x, y, a in zip(xs, ys, alpha, strict=True):
        diff = x - w
        i = int(np.argmin(np.einsum("ij,ij->i", diff, diff)))
        w[i] += (a if labels[i] == y else -a) * diff[i]


def _train_lvq21(
    w: np.ndarray, labels: np.ndarray, xs: np.ndarray, ys: np.ndarray, alpha: np.ndarray, window: float
) -> None:
    s = (1.0 - window) / (1.0 + window)
    for x, y, a in zip(xs, ys, alpha, strict=True):
        diff = x - w
        d = np.einsum("ij,ij->i", diff, diff)
        i, j = np.argpartition(d, 1)[:2]
        if d[j] < d[i]:
            i, j = j, i
        # Runner-up by neuron index: the second-nearest neuron whatever its class.
        ci, cj = labels[i] == y, labels[j] == y
        if ci == cj:
            continue
        di, dj = np.sqrt(d[i]), np.sqrt(d[j])
        ratio = min(di / dj, dj / di) if di > 0 and dj > 0 else 0.0
        if ratio <= s:
            continue
        good, bad = (i, j) if ci else (j, i)
        w[good] += a * diff[good]
        w[bad] -= a * diff[bad]


def _train_glvq(
    w: np.ndarray, labels: np.ndarray, xs: np.ndarray, ys: np.ndarray, alpha: np.ndarray, _window: float
) -> None:
    for x, y, a in zip(xs, ys, alpha, strict=True):
        diff = x - w
        d = np.einsum("ij,ij->i", diff, diff)
        same = labels == y
        dp = np.where(same, d, np.inf)
        dm = np.where(same, np.inf, d)
        p = int(np.argmin(dp))
        m = int(np.argmin(dm))
        s = d[p] + d[m]
        if s <= 0:
            continue
        mu = (d[p] - d[m]) / s
        f = 1.0 / (1.0 + np.exp(-mu))
        g = f * (1.0 - f)
        w[p] += a * g * (4.0 * d[m] / s**2) * diff[p]
        w[m] -= a * g * (4.0 * d[p] / s**2) * diff[m]


__all__ = ["LVQClassifier", "neurons_per_class"]
