"""`KinematicPredictor`: element times of a point mass flying the plan within the autopilot's limits.

The default trajectory predictor (:data:`uasnav.trajectory.models.DEFAULT_METHOD`): chosen by
leave-one-run-out on the real flights available (``uasnav trajectory evaluate`` on the Phoenix
ArduCopter mission, 5 runs: run |e%| median 2.26, worst 9.73 against the LVQ's 5.17 / 9.71,
kNN 4.52 / 15.05, distance ÷ speed 13.75 / 21.02; the point mass plus a learned residual
factor did worse, 4.54 / 8.14 — see BENCHMARKS.md). The thesis' LVQ network stays available
as method ``"lvq"`` (:class:`uasnav.trajectory.predictor.TrajectoryPredictor`).

Model: along the horizontal plan the speed profile is

    v(s) = min(V, √(v_k² + 2 a |s − s_k|) for every waypoint k),

the commanded speed V, the acceleration limit a (ArduPilot ``WPNAV_ACCEL``, PX4
``MPC_ACC_HOR``), corner speeds v_k = V·max(cos(θ_k/2), 0.1) and a stop at both ends
(:func:`uasnav.trajectory.baselines.kinematic_times`). Vertical moves (take-off, landing,
climbs and descents) are timed by :mod:`uasnav.trajectory.route3d` with the vertical limits
held here (``WPNAV_SPEED_UP/DN``, ``MPC_Z_VEL_MAX_UP/DN``).

Wind does not change the predicted times: a multirotor's position controller holds the commanded
ground speed within its limits (the LVQ network, which learns the wind's effect, suits vehicles
that do not). What is learned from the training flights: the commanded speed (median), the wind range and
the populated feature cells — elements of a plan outside them are flagged, and flagged elements
widen the calibrated time bounds (:func:`uasnav.trajectory.timebounds.widening`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from uasnav import jsoncheck as jc
from uasnav.atomicfile import atomic_write_text
from uasnav.errors import DataFormatError, InputError
from uasnav.trajectory.baselines import kinematic_times
from uasnav.trajectory.features import N_CELLS, WIND_MAX_MS, cell_index, features
from uasnav.trajectory.geometry import DEFAULT_SEGMENT_M, check_element_count, discretise, merge_short_legs
from uasnav.trajectory.predictor import (
    MAX_MODEL_BYTES,
    MAX_SEGMENT_M,
    MAX_SPEED_MS,
    MIN_SEGMENT_M,
    Feasibility,
    PlanPrediction,
    _count,
    _int_map,
    _time_bounds,
    _wind_range,
)
from uasnav.trajectory.samples import ElementSamples
from uasnav.trajectory.timebounds import TimeBounds

MODEL_FORMAT = "uasnav-trajectory-kinematic/1"
#: Defaults of the limits (ArduPilot's defaults: WPNAV_ACCEL 100 cm/s², WPNAV_SPEED_UP 250 cm/s,
#: WPNAV_SPEED_DN 150 cm/s, WPNAV_ACCEL_Z 100 cm/s²), used when the training log carries none.
DEFAULT_ACCEL_MS2 = 1.0
DEFAULT_CLIMB_MS = 2.5
DEFAULT_DESCENT_MS = 1.5
DEFAULT_ACCEL_Z_MS2 = 1.0
#: Largest acceleration accepted (m/s²): ≈ 5 g, beyond any multirotor's waypoint limits.
MAX_ACCEL_MS2 = 50.0
_N_TABLE = 3 * N_CELLS


class KinematicPredictor:
    """Point-mass element-time predictor with the vehicle's configured limits.

    Parameters
    ----------
    segment_m : float
        Element length L (m), as the LVQ model's (10).
    accel_ms2 : float
        Horizontal acceleration limit, m/s².
    climb_ms, descent_ms : float
        Vertical speed limits up / down (> 0), m/s.
    accel_z_ms2 : float
        Vertical acceleration limit, m/s².
    limits_source : str
        Where the limits come from (e.g. a log's name), reported with predictions.

    Attributes (after fit)
    ----------------------
    cruise_ms_ : float — median commanded speed of the training flights, m/s.
    wind_range_ms_ : (float, float) — trained wind speeds, m/s.
    count_table_ : ndarray of int, shape (384,) — training elements per feature cell.
    n_train_ : int
    time_bounds_ : TimeBounds or None — calibrated bounds (:mod:`uasnav.trajectory.calibration`).
    """

    method = "kinematic"

    def __init__(
        self,
        segment_m: float = DEFAULT_SEGMENT_M,
        accel_ms2: float = DEFAULT_ACCEL_MS2,
        climb_ms: float = DEFAULT_CLIMB_MS,
        descent_ms: float = DEFAULT_DESCENT_MS,
        accel_z_ms2: float = DEFAULT_ACCEL_Z_MS2,
        limits_source: str = "defaults",
    ) -> None:
        self.segment_m = segment_m
        self.accel_ms2 = accel_ms2
        self.climb_ms = climb_ms
        self.descent_ms = descent_ms
        self.accel_z_ms2 = accel_z_ms2
        self.limits_source = limits_source

    def get_params(self) -> dict[str, Any]:
        """The constructor parameters (the model file's ``"params"``)."""
        return {k: getattr(self, k) for k in _PARAM_KEYS}

    def fit(self, samples: ElementSamples) -> KinematicPredictor:
        """Learn the commanded speed, wind range and populated cells of ``samples``. Returns self."""
        try:
            _check_params(self.get_params())
        except DataFormatError as e:
            raise InputError(str(e)) from None
        if len(samples) == 0:
            raise InputError("no training elements")
        v = samples.v_ref_ms
        bad = np.flatnonzero(~((v > 0) & (v <= MAX_SPEED_MS)))
        if bad.size:
            raise InputError(
                f"training element {int(bad[0])}: commanded speed {float(v[bad[0]]):g} m/s is outside "
                f"(0, {MAX_SPEED_MS:g}] m/s"
            )
        w = samples.features.wind_ms
        bad = np.flatnonzero(~((w >= 0) & (w <= MAX_SPEED_MS)))
        if bad.size:
            raise InputError(
                f"training element {int(bad[0])}: wind speed {float(w[bad[0]]):g} m/s is outside "
                f"[0, {MAX_SPEED_MS:g}] m/s"
            )
        self.time_bounds_: TimeBounds | None = None
        self.count_table_ = np.bincount(samples.cell, minlength=_N_TABLE)
        self.cruise_ms_ = float(np.median(v))
        self.wind_range_ms_ = (float(w.min()), float(w.max()))
        self.n_train_ = len(samples)
        return self

    def _check_fitted(self) -> None:
        if not hasattr(self, "count_table_"):
            raise InputError("KinematicPredictor is not fitted: call fit() or load a model")

    def predict(
        self,
        plan_ne: np.ndarray,
        wind_ne: np.ndarray,
        cruise_ms: float | None = None,
        leg_speed_ms: np.ndarray | None = None,
    ) -> PlanPrediction:
        """Element times, ETA and waypoint times of a horizontal plan (north/east m).

        Same interface and result as :meth:`TrajectoryPredictor.predict
        <uasnav.trajectory.predictor.TrajectoryPredictor.predict>`; ``dv_ms`` holds the speed
        change L/t − V the point mass implies, ``cell_used`` the element's own cell. The wind
        enters only the flags (the point mass flies the commanded ground speed).
        ``leg_speed_ms`` (shape (n − 1,), m/s, NaN = the cruise speed) gives legs their own
        commanded speed (``DO_CHANGE_SPEED``): each leg is flown, accelerations and braking
        included, at its own speed (:func:`~uasnav.trajectory.baselines.kinematic_times`).
        """
        self._check_fitted()
        v_ref = self.cruise_ms_ if cruise_ms is None else float(cruise_ms)
        if not (np.isfinite(v_ref) and v_ref > 0):
            raise InputError(f"cruise speed must be > 0 m/s, got {cruise_ms}")
        # legs shorter than L merge into their neighbours (geometry.merge_short_legs); each
        # waypoint's time is that of the merged waypoint standing for it
        plan_in = np.asarray(plan_ne, dtype=float)[:, :2]
        plan_ne, wp_index = merge_short_legs(plan_in, self.segment_m)
        if leg_speed_ms is not None and len(plan_ne) != len(plan_in):
            keep = np.flatnonzero(np.r_[True, np.diff(wp_index) > 0])
            leg_speed_ms = np.asarray(leg_speed_ms, dtype=float)[np.maximum(keep[1:] - 1, 0)]
        check_element_count(plan_ne, self.segment_m)
        el = discretise(plan_ne, self.segment_m)
        f = features(el.heading1_deg, el.turn_deg, el.kind, wind_ne)
        cell = cell_index(f)
        p = np.asarray(plan_ne, dtype=float)[:, :2]
        # speed-profile grid: 0.1 m, coarser on very long plans (at most 2·10⁵ points)
        ds = max(0.1, float(el.s_end_m[-1]) / 200_000)
        t = kinematic_times(
            p, el.s_start_m, el.s_end_m, v_ref, accel_ms2=self.accel_ms2, ds_m=ds, leg_speed_ms=leg_speed_ms
        )
        lo, hi = self.wind_range_ms_
        flags: list[list[str]] = []
        for i in range(len(el)):
            r = []
            if self.count_table_[cell[i]] == 0:
                r.append(f"no training data in class {int(cell[i])}")
            if f.wind_ms[i] > WIND_MAX_MS:
                r.append(f"wind {f.wind_ms[i]:.1f} m/s above the highest wind class ({WIND_MAX_MS} m/s)")
            elif f.wind_ms[i] > hi + 1.25 or f.wind_ms[i] < lo - 1.25:
                r.append(f"wind {f.wind_ms[i]:.1f} m/s outside the trained range {lo:.1f}–{hi:.1f} m/s")
            if el.shortened[i]:
                r.append("corner element shortened (leg shorter than 2 L)")
            flags.append(r)
        s_wp = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))])
        s_knots = np.concatenate([[el.s_start_m[0]], el.s_end_m])
        t_knots = np.concatenate([[0.0], np.cumsum(t)])
        return PlanPrediction(
            elements=el,
            features=f,
            cell=cell,
            cell_used=cell,
            dv_ms=el.length_m / t - v_ref,
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
    def to_dict(self) -> dict[str, Any]:
        """The fitted model as JSON-able data."""
        self._check_fitted()
        d: dict[str, Any] = {
            "format": MODEL_FORMAT,
            "params": self.get_params(),
            "cruise_ms": self.cruise_ms_,
            "wind_range_ms": list(self.wind_range_ms_),
            "n_train": self.n_train_,
            "count_table": {str(c): int(self.count_table_[c]) for c in np.flatnonzero(self.count_table_)},
        }
        if getattr(self, "time_bounds_", None) is not None:
            d["time_bounds"] = self.time_bounds_.to_dict()  # type: ignore[union-attr]
        return d

    def save(self, path: str | Path) -> None:
        """Write the model as JSON, atomically."""
        atomic_write_text(path, json.dumps(self.to_dict(), indent=1, allow_nan=False))

    @classmethod
    def from_dict(cls, d: dict[str, Any], source: str = "<dict>") -> KinematicPredictor:
        """Rebuild a fitted predictor from :meth:`to_dict` data, every value checked; raises
        :class:`DataFormatError` naming ``source`` and the JSON path."""
        if not isinstance(d, dict) or d.get("format") != MODEL_FORMAT:
            raise DataFormatError(f"not a {MODEL_FORMAT} model", path=source)
        with jc.reraise_in(source):
            jc.only(d, _FILE_KEYS)
            self = cls(**_check_params(jc.obj(jc.field(d, "params"), "params"), "params"))
            self.cruise_ms_ = jc.number(jc.field(d, "cruise_ms"), "cruise_ms", positive=True, hi=MAX_SPEED_MS)
            self.wind_range_ms_ = _wind_range(jc.field(d, "wind_range_ms"))
            self.n_train_ = jc.integer(jc.field(d, "n_train"), "n_train", lo=1)
            counts = _int_map(jc.field(d, "count_table"), "count_table", 0, _N_TABLE - 1, _count)
            if sum(counts.values()) != self.n_train_:
                raise jc.fail(
                    "count_table", f"counts sum to {sum(counts.values())}, n_train is {self.n_train_}"
                )
            self.count_table_ = np.zeros(_N_TABLE, dtype=int)
            for k, c in counts.items():
                self.count_table_[k] = c
            self.time_bounds_ = _time_bounds(d["time_bounds"]) if "time_bounds" in d else None
        return self

    @classmethod
    def load(cls, path: str | Path) -> KinematicPredictor:
        """Read a model written by :meth:`save` (checked as :meth:`from_dict` does)."""
        with jc.reraise_in(str(path)):
            d = jc.parse(jc.read_text(path, MAX_MODEL_BYTES), "invalid JSON")
        return cls.from_dict(d, source=str(path))


_PARAM_KEYS = ("segment_m", "accel_ms2", "climb_ms", "descent_ms", "accel_z_ms2", "limits_source")
_FILE_KEYS = ("format", "params", "cruise_ms", "wind_range_ms", "n_train", "count_table", "time_bounds")


def _check_params(p: dict[str, Any], path: str = "") -> dict[str, Any]:
    """Parameters checked by a model file's rules; raises :class:`DataFormatError` naming the key."""
    jc.only(p, _PARAM_KEYS, path)
    p = {k: v.item() if isinstance(v, np.generic) else v for k, v in p.items()}

    def accel(v: object, q: str) -> float:
        return jc.number(v, q, positive=True, hi=MAX_ACCEL_MS2, unit="m/s²")

    def speed(v: object, q: str) -> float:
        return jc.number(v, q, positive=True, hi=MAX_SPEED_MS, unit="m/s")

    checks = {
        "segment_m": lambda v, q: jc.number(v, q, lo=MIN_SEGMENT_M, hi=MAX_SEGMENT_M, unit="m"),
        "accel_ms2": accel,
        "climb_ms": speed,
        "descent_ms": speed,
        "accel_z_ms2": accel,
        "limits_source": lambda v, q: jc.string(v, q),
    }
    return {k: checks[k](v, jc.at(path, k)) for k, v in p.items()}


__all__ = [
    "DEFAULT_ACCEL_MS2",
    "DEFAULT_ACCEL_Z_MS2",
    "DEFAULT_CLIMB_MS",
    "DEFAULT_DESCENT_MS",
    "MODEL_FORMAT",
    "KinematicPredictor",
]
