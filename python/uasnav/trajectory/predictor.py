"""`TrajectoryPredictor`: LVQ classes → ΔV → element times, ETA and 4D waypoint times (§5.1.3).

Training: the LVQ network learns to map element features to the 4×8×4 cells (×kind blocks) of
the thesis; each cell's ΔV is the mean ΔV of the training elements in it. Prediction: the
network's class gives ΔV and eq. (47) the time t = L/(V_ref + ΔV), V_ref the commanded speed.

Lower-confidence predictions are flagged per element (``PlanPrediction.flags``), never hidden:
the element's own cell had no training data (the network's nearest populated class was used),
the wind is outside the wind classes (> 11.25 m/s) or the trained wind range, a corner element
was shortened (leg shorter than 2 L), or the predicted speed V_ref + ΔV was not positive.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from uasnav import jsoncheck as jc
from uasnav.atomicfile import atomic_write_text
from uasnav.errors import DataFormatError, InputError
from uasnav.trajectory.features import N_CELLS, WIND_MAX_MS, Features, cell_index, features
from uasnav.trajectory.geometry import DEFAULT_SEGMENT_M, Elements, discretise, merge_short_legs
from uasnav.trajectory.lvq import LVQClassifier
from uasnav.trajectory.samples import ElementSamples
from uasnav.trajectory.timebounds import TimeBounds

MODEL_FORMAT = "uasnav-trajectory-lvq/1"
_N_TABLE = 3 * N_CELLS
#: Slowest speed (m/s) accepted from V_ref + ΔV before the element is flagged and clamped.
MIN_SPEED_MS = 0.2
#: Shortest segment length L (m) a model is trained or loaded with. The thesis uses 10 m; below
#: 1 m an element is shorter than GNSS position noise, and a plan's element count (memory,
#: time) grows as its length / L (``segment_m`` = 1e-9 would ask for 10⁹ elements per metre).
MIN_SEGMENT_M = 1.0
#: Longest segment length L (m): a plan must be at least 2 L long to hold one element.
MAX_SEGMENT_M = 10_000.0
#: Largest speed, speed change ΔV and wind (m/s) a model file may hold: beyond any small UAS
#: (and the CLI's ``--wind`` bound of 100 m/s); larger values are corrupt.
MAX_SPEED_MS = 150.0
#: Most competitive neurons S¹ a model may declare (the thesis uses 256).
MAX_PROTOTYPES = 100_000
#: Largest model file read (bytes); a 256-prototype model is about 40 kB.
MAX_MODEL_BYTES = 64 * 2**20
#: Width of the LVQ input (:meth:`uasnav.trajectory.features.Features.matrix`): θ, θ_w (cos,
#: sin), |V_w|, kind.
N_FEATURES = 5


@dataclass
class PlanPrediction:
    """Prediction for one plan.

    Attributes
    ----------
    elements : Elements
    features : Features
    cell : ndarray of int, shape (m,)  — the element's own class cell.
    cell_used : ndarray of int, shape (m,) — the network's class (its ΔV was used).
    dv_ms : ndarray, shape (m,) — predicted ΔV (m/s).
    time_s : ndarray, shape (m,) — predicted element times (eq. 47), s.
    eta_s : float — sum of element times, s.
    waypoint_times_s : ndarray, shape (n,) — predicted time at each waypoint (4D plan), s.
    flags : list of list of str — lower-confidence reasons per element (empty = confident).
    """

    elements: Elements
    features: Features
    cell: np.ndarray
    cell_used: np.ndarray
    dv_ms: np.ndarray
    time_s: np.ndarray
    eta_s: float
    waypoint_times_s: np.ndarray
    flags: list[list[str]] = field(default_factory=list)

    @property
    def low_confidence(self) -> np.ndarray:
        """Boolean mask of flagged elements."""
        return np.array([bool(f) for f in self.flags], dtype=bool)

    def element_rows(self) -> list[dict]:
        """One plain dict per element (what ``uasnav trajectory predict --json`` prints under
        ``elements`` and the web app shows): kind, length (m), turn and relative wind angles
        (deg), wind (m/s), class used, ΔV (m/s), predicted time (s), lower-confidence flags."""
        el, f = self.elements, self.features
        return [
            {
                "element": i,
                "kind": str(el.kind[i]),
                "length_m": float(el.length_m[i]),
                "theta_deg": float(f.theta_deg[i]),
                "theta_w_deg": float(f.theta_w_deg[i]),
                "wind_ms": float(f.wind_ms[i]),
                "class": int(self.cell_used[i]),
                "dv_ms": float(self.dv_ms[i]),
                "time_s": float(self.time_s[i]),
                "low_confidence": bool(self.flags[i]),
                "flags": list(self.flags[i]),
            }
            for i in range(len(el))
        ]


@dataclass
class Feasibility:
    """Feasibility of a 4D operation plan: each waypoint's required vs predicted time (s)."""

    required_s: np.ndarray
    predicted_s: np.ndarray
    tolerance_s: float

    @property
    def ok(self) -> np.ndarray:
        """Waypoints reached within the tolerance."""
        return np.abs(self.predicted_s - self.required_s) <= self.tolerance_s

    @property
    def feasible(self) -> bool:
        """Every waypoint reached within the tolerance."""
        return bool(self.ok.all())

    @classmethod
    def of(
        cls,
        predictor: Any,
        plan_ne: np.ndarray,
        required_times_s: np.ndarray,
        wind_ne: np.ndarray,
        tolerance_s: float = 5.0,
        cruise_ms: float | None = None,
    ) -> Feasibility:
        """Each waypoint's required time (s from the start) against ``predictor``'s prediction of
        the plan (any method: ``predictor.predict(plan_ne, wind_ne, cruise_ms)``)."""
        req = np.asarray(required_times_s, dtype=float)
        p = np.asarray(plan_ne)
        if req.shape != (p.shape[0],) or not np.isfinite(req).all():
            raise InputError(f"need one finite required time per waypoint ({p.shape[0]}), got {req.shape}")
        pred = predictor.predict(p, wind_ne, cruise_ms)
        return cls(required_s=req, predicted_s=pred.waypoint_times_s, tolerance_s=float(tolerance_s))


class TrajectoryPredictor:
    """Element-time predictor trained on flown elements (thesis §5.1).

    Parameters
    ----------
    segment_m : float
        Segment length L (m), 10.
    n_prototypes, algorithm, learning_rate, lr_decay, max_iter, random_state
        Passed to :class:`LVQClassifier` (S¹ = 256, LVQ1, 0.01 as in the thesis/MATLAB).
    target : {"cell", "dv"}
        The network's target classes: the thesis' 4×8×4 feature cells (each carrying its mean
        ΔV), or ΔV itself quantised in bins of ``dv_bin_ms`` (the network then learns which
        features lead to which speed change, and may merge or split cells).
    dv_bin_ms : float
        ΔV bin width for ``target="dv"`` (m/s).

    Attributes (after fit)
    ----------------------
    lvq_ : LVQClassifier or None (None if the training data fill a single cell)
    dv_table_ : ndarray, shape (384,) — mean ΔV per cell, NaN where no data (m/s).
    count_table_ : ndarray of int, shape (384,)
    cruise_ms_ : float — median commanded speed of the training flights (m/s).
    wind_range_ms_ : (float, float) — trained wind speeds.
    """

    def __init__(
        self,
        segment_m: float = DEFAULT_SEGMENT_M,
        n_prototypes: int = 256,
        algorithm: str = "lvq1",
        learning_rate: float = 0.01,
        lr_decay: str = "none",
        max_iter: int | None = None,
        random_state: int = 0,
        target: str = "cell",
        dv_bin_ms: float = 0.1,
    ) -> None:
        self.target = target
        self.dv_bin_ms = dv_bin_ms
        self.segment_m = segment_m
        self.n_prototypes = n_prototypes
        self.algorithm = algorithm
        self.learning_rate = learning_rate
        self.lr_decay = lr_decay
        self.max_iter = max_iter
        self.random_state = random_state

    # -- training ------------------------------------------------------------------------
    def fit(self, samples: ElementSamples) -> TrajectoryPredictor:
        """Train the network and the per-cell ΔV table on measured elements. Returns self."""
        try:
            _check_params(self.get_params())
        except DataFormatError as e:  # the same rules as a model file's "params", as InputError
            raise InputError(str(e)) from None
        if len(samples) == 0:
            raise InputError("no training elements")
        # calibrated time bounds belong to one fitted model: set after fitting
        # (:mod:`uasnav.trajectory.calibration`), saved with it
        self.time_bounds_: TimeBounds | None = None
        good = np.isfinite(samples.dv_ms)
        if not good.all():
            raise InputError(f"{int((~good).sum())} training element(s) have a NaN ΔV")
        # The limits a model file is loaded with: a model that could not be read back is refused
        # here, at training, naming the element (a corrupt log's 1e308 m/s would otherwise do).
        v_max = MAX_SPEED_MS
        for name, x, ok, accepted in (
            ("ΔV", samples.dv_ms, np.abs(samples.dv_ms) <= v_max, f"[-{v_max:g}, {v_max:g}]"),
            ("commanded speed", samples.v_ref_ms, (samples.v_ref_ms > 0) & (samples.v_ref_ms <= v_max),
             f"(0, {v_max:g}]"),
            ("wind speed", samples.features.wind_ms,
             (samples.features.wind_ms >= 0) & (samples.features.wind_ms <= v_max), f"[0, {v_max:g}]"),
        ):  # fmt: skip
            bad = np.flatnonzero(~ok)
            if bad.size:
                i = int(bad[0])
                raise InputError(
                    f"training element {i}: {name} {float(x[i]):g} m/s is outside {accepted} m/s "
                    f"({bad.size} such element{'s' if bad.size > 1 else ''})"
                )
        cells = samples.cell
        self.count_table_ = np.bincount(cells, minlength=_N_TABLE)
        sums = np.bincount(cells, weights=samples.dv_ms, minlength=_N_TABLE)
        with np.errstate(invalid="ignore", divide="ignore"):
            self.dv_table_ = np.where(self.count_table_ > 0, sums / np.maximum(self.count_table_, 1), np.nan)
        self.dv_global_ = float(samples.dv_ms.mean())
        if self.target not in ("cell", "dv"):
            raise InputError(f"target must be 'cell' or 'dv', got {self.target!r}")
        if self.target == "dv":
            if not (np.isfinite(self.dv_bin_ms) and self.dv_bin_ms > 0):
                raise InputError(f"dv_bin_ms must be > 0, got {self.dv_bin_ms}")
            y = np.rint(samples.dv_ms / self.dv_bin_ms).astype(int)
        else:
            y = cells
        populated, inv = np.unique(y, return_inverse=True)
        self.labels_ = populated
        self.label_dv_ = np.bincount(inv, weights=samples.dv_ms) / np.bincount(inv)
        if populated.size >= 2:
            self.lvq_: LVQClassifier | None = LVQClassifier(
                n_prototypes=max(int(self.n_prototypes), populated.size),
                algorithm=self.algorithm,
                learning_rate=self.learning_rate,
                lr_decay=self.lr_decay,
                max_iter=self.max_iter,
                random_state=self.random_state,
            ).fit(samples.features.matrix(), y)
        else:
            self.lvq_ = None
            self.single_cell_ = int(populated[0])
        self.cruise_ms_ = float(np.median(samples.v_ref_ms))
        self.wind_range_ms_ = (float(samples.features.wind_ms.min()), float(samples.features.wind_ms.max()))
        self.n_train_ = len(samples)
        return self

    def _check_fitted(self) -> None:
        if not hasattr(self, "dv_table_"):
            raise InputError("TrajectoryPredictor is not fitted: call fit() or load a model")

    # -- prediction ----------------------------------------------------------------------
    def classify(self, f: Features) -> tuple[np.ndarray, np.ndarray]:
        """(own cell, network class) of each element, vectorised (the class is a cell or, with
        ``target="dv"``, a ΔV bin index)."""
        self._check_fitted()
        cell = cell_index(f)
        if self.lvq_ is None:
            return cell, np.full(cell.shape, self.single_cell_)
        return cell, self.lvq_.predict(f.matrix()).astype(int)

    def predict_dv(self, f: Features) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """ΔV (m/s) of elements with features ``f``: (dv, own cell, network cell)."""
        cell, used = self.classify(f)
        return self.label_dv_[np.searchsorted(self.labels_, used)], cell, used

    def element_times(self, f: Features, length_m: np.ndarray, v_ref_ms: float | np.ndarray) -> np.ndarray:
        """Eq. (47) for many elements at once: t = L/(V_ref + ΔV), s (clamped at MIN_SPEED_MS)."""
        dv, _, _ = self.predict_dv(f)
        return np.asarray(length_m) / np.maximum(np.asarray(v_ref_ms) + dv, MIN_SPEED_MS)

    def predict(
        self, plan_ne: np.ndarray, wind_ne: np.ndarray, cruise_ms: float | None = None
    ) -> PlanPrediction:
        """Predict element times, ETA and 4D waypoint times of a plan (north/east m).

        Parameters
        ----------
        plan_ne : ndarray, shape (n, 2)
        wind_ne : ndarray, shape (2,)
            Wind velocity (m/s, toward); see :func:`uasnav.trajectory.features.wind_vector`.
        cruise_ms : float, optional
            Commanded speed; default the training flights' speed.
        """
        self._check_fitted()
        v_ref = self.cruise_ms_ if cruise_ms is None else float(cruise_ms)
        if not (np.isfinite(v_ref) and v_ref > 0):
            raise InputError(f"cruise speed must be > 0 m/s, got {cruise_ms}")
        # legs shorter than L merge into their neighbours (geometry.merge_short_legs); each
        # waypoint's time is that of the merged waypoint standing for it
        plan_ne, wp_index = merge_short_legs(np.asarray(plan_ne, dtype=float)[:, :2], self.segment_m)
        el = discretise(plan_ne, self.segment_m)
        f = features(el.heading1_deg, el.turn_deg, el.kind, wind_ne)
        dv, cell, used = self.predict_dv(f)
        v = v_ref + dv
        t = el.length_m / np.maximum(v, MIN_SPEED_MS)
        lo, hi = self.wind_range_ms_
        flags: list[list[str]] = []
        for i in range(len(el)):
            r = []
            if self.target == "cell" and used[i] != cell[i]:
                r.append(f"no training data in class {int(cell[i])}: nearest populated class {int(used[i])}")
            elif self.target == "dv" and self.count_table_[cell[i]] == 0:
                r.append(f"no training data in class {int(cell[i])}: ΔV from the nearest prototype")
            if f.wind_ms[i] > WIND_MAX_MS:
                r.append(f"wind {f.wind_ms[i]:.1f} m/s above the highest wind class ({WIND_MAX_MS} m/s)")
            elif f.wind_ms[i] > hi + 1.25 or f.wind_ms[i] < lo - 1.25:
                r.append(f"wind {f.wind_ms[i]:.1f} m/s outside the trained range {lo:.1f}–{hi:.1f} m/s")
            if el.shortened[i]:
                r.append("corner element shortened (leg shorter than 2 L)")
            if v[i] < MIN_SPEED_MS:
                r.append(f"predicted speed {v[i]:.2f} m/s clamped to {MIN_SPEED_MS} m/s")
            flags.append(r)
        p = np.asarray(plan_ne, dtype=float)[:, :2]
        s_wp = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))])
        s_knots = np.concatenate([[el.s_start_m[0]], el.s_end_m])
        t_knots = np.concatenate([[0.0], np.cumsum(t)])
        return PlanPrediction(
            elements=el,
            features=f,
            cell=cell,
            cell_used=used,
            dv_ms=dv,
            time_s=t,
            eta_s=float(t.sum()),
            waypoint_times_s=np.interp(s_wp, s_knots, t_knots)[wp_index],
            flags=flags,
        )

    def feasibility(
        self,
        plan_ne: np.ndarray,
        required_times_s: np.ndarray,
        wind_ne: np.ndarray,
        tolerance_s: float = 5.0,
        cruise_ms: float | None = None,
    ) -> Feasibility:
        """Is each 4D waypoint (required time from the start, s) reached within ``tolerance_s``?"""
        return Feasibility.of(self, plan_ne, required_times_s, wind_ne, tolerance_s, cruise_ms)

    # -- persistence ---------------------------------------------------------------------
    def get_params(self) -> dict[str, Any]:
        """The constructor parameters (the model file's ``"params"``)."""
        return {k: getattr(self, k) for k in _PARAM_KEYS}

    def to_dict(self) -> dict[str, Any]:
        """The fitted model as JSON-able data."""
        self._check_fitted()
        d: dict[str, Any] = {
            "format": MODEL_FORMAT,
            "params": self.get_params(),
            "label_dv_ms": {str(int(k)): float(v) for k, v in zip(self.labels_, self.label_dv_, strict=True)},
            "cruise_ms": self.cruise_ms_,
            "wind_range_ms": list(self.wind_range_ms_),
            "n_train": self.n_train_,
            "dv_global_ms": self.dv_global_,
            "dv_table_ms": {str(c): float(self.dv_table_[c]) for c in np.flatnonzero(self.count_table_)},
            "count_table": {str(c): int(self.count_table_[c]) for c in np.flatnonzero(self.count_table_)},
        }
        bounds = getattr(self, "time_bounds_", None)
        if bounds is not None:
            d["time_bounds"] = bounds.to_dict()
        if self.lvq_ is not None:
            d["lvq"] = {
                "classes": self.lvq_.classes_.tolist(),
                "prototypes": self.lvq_.prototypes_.tolist(),
                "prototype_labels": self.lvq_.prototype_labels_.tolist(),
            }
        else:
            d["single_cell"] = self.single_cell_
        return d

    def save(self, path: str | Path) -> None:
        """Write the model as JSON, atomically."""
        d = self.to_dict()
        try:
            text = json.dumps(d, indent=1, allow_nan=False)  # JSON has no NaN: never write one
        except ValueError:
            raise InputError("the model holds non-finite numbers and cannot be saved") from None
        atomic_write_text(path, text)

    @classmethod
    def from_dict(cls, d: dict[str, Any], source: str = "<dict>") -> TrajectoryPredictor:
        """Rebuild a fitted predictor from :meth:`to_dict` data, every value checked: types,
        finiteness, ranges (:data:`MIN_SEGMENT_M` ≤ ``segment_m`` ≤ :data:`MAX_SEGMENT_M`,
        speeds and ΔV within ±:data:`MAX_SPEED_MS`), class keys inside the class grid, shapes
        of the LVQ arrays. Raises :class:`DataFormatError` naming ``source`` and the JSON path."""
        if not isinstance(d, dict) or d.get("format") != MODEL_FORMAT:
            raise DataFormatError(f"not a {MODEL_FORMAT} model", path=source)
        with jc.reraise_in(source):
            return cls._from_checked(d)

    @classmethod
    def _from_checked(cls, d: dict[str, Any]) -> TrajectoryPredictor:
        jc.only(d, _FILE_KEYS)
        params = _check_params(jc.obj(jc.field(d, "params"), "params"), "params")
        self = cls(**params)
        self.cruise_ms_ = jc.number(jc.field(d, "cruise_ms"), "cruise_ms", positive=True, hi=MAX_SPEED_MS)
        self.wind_range_ms_ = _wind_range(jc.field(d, "wind_range_ms"))
        self.n_train_ = jc.integer(jc.field(d, "n_train"), "n_train", lo=1)
        self.dv_global_ = jc.number(
            jc.field(d, "dv_global_ms"), "dv_global_ms", lo=-MAX_SPEED_MS, hi=MAX_SPEED_MS
        )
        # Class keys: feature cells 0…383 for target "cell"; ΔV bins k (ΔV ≈ k·dv_bin_ms) for "dv".
        if self.target == "cell":
            lab_lo, lab_hi = 0, _N_TABLE - 1
        else:
            lab_hi = int(MAX_SPEED_MS / self.dv_bin_ms)
            lab_lo = -lab_hi
        labels = _int_map(jc.field(d, "label_dv_ms"), "label_dv_ms", lab_lo, lab_hi, _dv)
        self.labels_ = np.array(sorted(labels), dtype=int)
        self.label_dv_ = np.array([labels[k] for k in self.labels_])
        dv = _int_map(jc.field(d, "dv_table_ms"), "dv_table_ms", 0, _N_TABLE - 1, _dv)
        counts = _int_map(jc.field(d, "count_table"), "count_table", 0, _N_TABLE - 1, _count)
        if set(counts) != set(dv):
            odd = min(set(counts) ^ set(dv))
            raise jc.fail("count_table", f"cell {odd} is in only one of dv_table_ms and count_table")
        if sum(counts.values()) != self.n_train_:
            raise jc.fail("count_table", f"counts sum to {sum(counts.values())}, n_train is {self.n_train_}")
        if self.target == "cell" and set(labels) != set(dv):
            raise jc.fail("label_dv_ms", "classes differ from the cells of dv_table_ms (target 'cell')")
        self.dv_table_ = np.full(_N_TABLE, np.nan)
        self.count_table_ = np.zeros(_N_TABLE, dtype=int)
        for k, v in dv.items():
            self.dv_table_[k] = v
            self.count_table_[k] = counts[k]
        if ("lvq" in d) == ("single_cell" in d):
            raise jc.fail("lvq", "a model holds exactly one of 'lvq' and 'single_cell'")
        if "lvq" in d:
            self.lvq_ = _lvq(jc.obj(d["lvq"], "lvq"), self.labels_)
        else:
            self.lvq_ = None
            self.single_cell_ = jc.integer(d["single_cell"], "single_cell", lo=lab_lo, hi=lab_hi)
            if self.labels_.tolist() != [self.single_cell_]:
                raise jc.fail("single_cell", f"{self.single_cell_} is not the one class of label_dv_ms")
        self.time_bounds_ = _time_bounds(d["time_bounds"]) if "time_bounds" in d else None
        return self

    @classmethod
    def load(cls, path: str | Path) -> TrajectoryPredictor:
        """Read a model written by :meth:`save` (at most :data:`MAX_MODEL_BYTES`), checked as
        :meth:`from_dict` does."""
        with jc.reraise_in(str(path)):
            d = jc.parse(jc.read_text(path, MAX_MODEL_BYTES), "invalid JSON")
        return cls.from_dict(d, source=str(path))


_PARAM_KEYS = (
    "segment_m", "n_prototypes", "algorithm", "learning_rate", "lr_decay", "max_iter", "random_state",
    "target", "dv_bin_ms",
)  # fmt: skip
_FILE_KEYS = (
    "format", "params", "label_dv_ms", "cruise_ms", "wind_range_ms", "n_train", "dv_global_ms",
    "dv_table_ms", "count_table", "lvq", "single_cell", "time_bounds",
)  # fmt: skip


def _time_bounds(x: object) -> TimeBounds:
    """The optional ``time_bounds`` of a model file (:mod:`uasnav.trajectory.timebounds`)."""
    d = jc.only(jc.obj(x, "time_bounds"), ("scores", "tau_s", "source"), "time_bounds")
    scores = jc.vector(jc.field(d, "scores", "time_bounds"), "time_bounds.scores", lo=0.0, hi=1e6)
    tau = jc.number(jc.field(d, "tau_s", "time_bounds"), "time_bounds.tau_s", lo=0.0, hi=1e6, unit="s")
    source = jc.string(d.get("source", ""), "time_bounds.source")
    return TimeBounds(scores, tau, source)


def _check_params(p: dict[str, Any], path: str = "") -> dict[str, Any]:
    """The predictor's parameters checked (by a model file's rules: JSON types, ranges);
    missing keys keep their defaults. Raises :class:`DataFormatError` naming the key."""
    jc.only(p, _PARAM_KEYS, path)
    # NumPy scalars (from a caller's arithmetic) are checked as the Python numbers they hold.
    p = {k: v.item() if isinstance(v, np.generic) else v for k, v in p.items()}
    checks = {
        "segment_m": lambda v, q: jc.number(v, q, lo=MIN_SEGMENT_M, hi=MAX_SEGMENT_M, unit="m"),
        "n_prototypes": lambda v, q: jc.integer(v, q, lo=1, hi=MAX_PROTOTYPES),
        "algorithm": lambda v, q: jc.string(v, q, ("lvq1", "lvq2.1", "glvq")),
        "learning_rate": lambda v, q: jc.number(v, q, positive=True),
        "lr_decay": lambda v, q: jc.string(v, q, ("none", "linear")),
        "max_iter": lambda v, q: None if v is None else jc.integer(v, q, lo=1),
        "random_state": lambda v, q: None if v is None else jc.integer(v, q, lo=0),
        "target": lambda v, q: jc.string(v, q, ("cell", "dv")),
        "dv_bin_ms": lambda v, q: jc.number(v, q, positive=True, hi=MAX_SPEED_MS, unit="m/s"),
    }
    return {k: checks[k](v, jc.at(path, k)) for k, v in p.items()}


def _dv(v: object, path: str) -> float:
    return jc.number(v, path, lo=-MAX_SPEED_MS, hi=MAX_SPEED_MS, unit="m/s")


def _count(v: object, path: str) -> int:
    return jc.integer(v, path, lo=1)


def _int_map(x: object, path: str, lo: int, hi: int, value: Any) -> dict[int, Any]:
    """A JSON object with integer keys in [lo, hi] (class indices), values checked by ``value``."""
    d = jc.obj(x, path)
    if not d:
        raise jc.fail(path, "empty")
    return {jc.integer_key(k, path, lo=lo, hi=hi): value(v, jc.at(path, k)) for k, v in d.items()}


def _wind_range(x: object) -> tuple[float, float]:
    if not (isinstance(x, list) and len(x) == 2):
        raise jc.fail("wind_range_ms", f"expected [min, max] as an array of two numbers, got {jc.show(x)}")
    lo, hi = (
        jc.number(v, jc.at("wind_range_ms", i), lo=0, hi=MAX_SPEED_MS, unit="m/s") for i, v in enumerate(x)
    )
    if lo > hi:
        raise jc.fail("wind_range_ms", f"minimum {jc.show(x[0])} exceeds maximum {jc.show(x[1])}")
    return lo, hi


def _lvq(d: dict[str, Any], labels: np.ndarray) -> LVQClassifier:
    """The LVQ network of a model file (``"lvq"``), checked against the model's classes."""
    jc.only(d, ("classes", "prototypes", "prototype_labels"), "lvq")
    classes = jc.array(jc.field(d, "classes", "lvq"), "lvq.classes", max_len=MAX_PROTOTYPES)
    c = np.array([jc.integer(v, jc.at("lvq.classes", i)) for i, v in enumerate(classes)], dtype=np.int64)
    if not np.isin(c, labels).all():
        raise jc.fail("lvq.classes", "a class has no ΔV entry in label_dv_ms")
    w = jc.matrix(jc.field(d, "prototypes", "lvq"), "lvq.prototypes", cols=N_FEATURES)
    if w.shape[0] > MAX_PROTOTYPES:
        raise jc.fail("lvq.prototypes", f"{w.shape[0]} prototypes, at most {MAX_PROTOTYPES}")
    pl = jc.array(jc.field(d, "prototype_labels", "lvq"), "lvq.prototype_labels", max_len=MAX_PROTOTYPES)
    lab = np.array(
        [jc.integer(v, jc.at("lvq.prototype_labels", i), lo=0, hi=c.size - 1) for i, v in enumerate(pl)],
        dtype=np.intp,
    )
    try:
        return LVQClassifier.from_arrays(c, w, lab)
    except InputError as e:
        raise jc.fail("lvq", str(e)) from None


__all__ = [
    "MAX_SEGMENT_M",
    "MIN_SEGMENT_M",
    "MIN_SPEED_MS",
    "MODEL_FORMAT",
    "Feasibility",
    "PlanPrediction",
    "TrajectoryPredictor",
]
