"""PX4-compatible cubic thermal baseline (what practitioners use today).

PX4's thermal compensation (``TC_G*`` parameters, ``src/modules/temperature_compensation``)
models each gyro offset as a cubic in the temperature relative to a reference,
``offset = X3·ΔT³ + X2·ΔT² + X1·ΔT + X0`` with ``ΔT = T − TREF`` and ``T`` clipped to
``[TMIN, TMAX]``, and subtracts it from the raw rate. Its calibration script median-filters
the logged data and fits the cubic to temperature-binned values; we do the same: a running
median over ``median_window`` samples, medians per ``bin_c`` °C bin, a least-squares cubic
through the bins, ``TREF`` the middle of the calibrated range.
"""

from __future__ import annotations

import os
from typing import Literal, overload

import numpy as np
from numpy.typing import ArrayLike
from scipy.ndimage import median_filter

from uasnav import jsoncheck as jc
from uasnav.errors import InputError
from uasnav.limits import check_count
from uasnav.thermal._common import (
    TEMP_MAX_C,
    TEMP_MIN_C,
    BoolArray,
    FloatArray,
    NotFittedError,
    check_fit_data,
    check_temp,
    clip_temp,
)
from uasnav.thermal.base import ModelDict, register_model
from uasnav.thermal.modelfile import save_model


@register_model
class Px4BiasModel:
    """PX4 ``TC_G`` cubic offset model.

    Attributes
    ----------
    coef_ : ndarray, shape (4, k)
        ``X0…X3`` per axis (rad/s/°C^j).
    tref_c_ : float
        Reference temperature TREF (°C).
    range_c_ : tuple of float
        (TMIN, TMAX) (°C).
    """

    kind = "px4"

    def __init__(self, median_window: int = 31, bin_c: float = 0.5) -> None:
        self.median_window = median_window
        self.bin_c = bin_c

    def fit(self, temp: ArrayLike, bias: ArrayLike) -> Px4BiasModel:
        """Fit to time-ordered temperatures (n,) °C and gyro biases (n, k) rad/s."""
        if isinstance(self.median_window, bool) or not isinstance(self.median_window, int | np.integer):
            raise InputError(f"median_window: expected an integer ≥ 1, got {self.median_window!r}")
        if not (np.isfinite(self.bin_c) and self.bin_c > 0):
            raise InputError(f"bin_c: expected a bin width > 0 °C, got {self.bin_c}")
        t, b = check_fit_data(temp, bias, min_samples=8)
        check_count(np.ptp(t) / self.bin_c + 2, 8, f"temperature bins of {self.bin_c:g} °C", option="bin_c")
        w = max(1, min(int(self.median_window), t.size))
        tf = median_filter(t, size=w, mode="nearest")
        bf = median_filter(b, size=(w, 1), mode="nearest")
        edges = np.arange(tf.min(), tf.max() + self.bin_c, self.bin_c)
        idx = np.clip(np.digitize(tf, edges) - 1, 0, max(edges.size - 2, 0))
        tb, bb = [], []
        for i in np.unique(idx):
            m = idx == i
            tb.append(np.median(tf[m]))
            bb.append(np.median(bf[m], axis=0))
        tb_a, bb_a = np.asarray(tb), np.asarray(bb)
        self.range_c_ = (float(t.min()), float(t.max()))
        self.tref_c_ = 0.5 * (self.range_c_[0] + self.range_c_[1])
        deg = min(3, tb_a.size - 1)
        v = np.polynomial.polynomial.polyvander(tb_a - self.tref_c_, deg)
        c, *_ = np.linalg.lstsq(v, bb_a, rcond=None)
        self.coef_ = np.zeros((4, b.shape[1]))
        self.coef_[: deg + 1] = c
        return self

    def _check(self) -> None:
        if not hasattr(self, "coef_"):
            raise NotFittedError("Px4BiasModel: call fit() or load_model() first")

    @overload
    def predict(self, temp: ArrayLike, *, return_clipped: Literal[False] = ...) -> FloatArray: ...

    @overload
    def predict(self, temp: ArrayLike, *, return_clipped: Literal[True]) -> tuple[FloatArray, BoolArray]: ...

    def predict(
        self, temp: ArrayLike, *, return_clipped: bool = False
    ) -> FloatArray | tuple[FloatArray, BoolArray]:
        """Offset (n, k) rad/s; temperature clipped to [TMIN, TMAX] (flagged, warned)."""
        self._check()
        t, clipped = clip_temp(check_temp(temp), *self.range_c_, "Px4BiasModel")
        out = np.asarray(
            np.polynomial.polynomial.polyval(t - self.tref_c_, self.coef_).T, dtype=np.float64
        ).copy()
        return (out, clipped) if return_clipped else out

    def derivative(self, temp: ArrayLike) -> FloatArray:
        """∂offset/∂T (n, k) rad/s/°C; 0 where clipped."""
        self._check()
        t, clipped = clip_temp(check_temp(temp), *self.range_c_, "Px4BiasModel")
        dc = np.polynomial.polynomial.polyder(self.coef_, axis=0)
        out = np.polynomial.polynomial.polyval(t - self.tref_c_, dc).T.copy()
        out[clipped] = 0.0
        return np.asarray(out, dtype=np.float64)

    def px4_params(self, instance: int = 0, device_id: int = 0) -> dict[str, float | int]:
        """The fitted model as PX4 parameters ``TC_G{i}_*`` (rad/s units, as PX4 stores them)."""
        self._check()
        p: dict[str, float | int] = {
            f"TC_G{instance}_ID": int(device_id),
            f"TC_G{instance}_TMIN": self.range_c_[0],
            f"TC_G{instance}_TMAX": self.range_c_[1],
            f"TC_G{instance}_TREF": self.tref_c_,
        }
        for j in range(4):
            for a in range(min(3, self.coef_.shape[1])):
                p[f"TC_G{instance}_X{j}_{a}"] = float(self.coef_[j, a])
        return p

    def px4_param_file(
        self, instance: int = 0, device_id: int = 0, vehicle: int = 1, component: int = 1
    ) -> str:
        """QGroundControl parameter file text (tab separated, type 9 = float, 6 = int32)."""
        lines = ["# Onboard parameters for Vehicle 1", "# Vehicle-Id Component-Id Name Value Type"]
        for k, v in self.px4_params(instance, device_id).items():
            typ = 6 if isinstance(v, int) else 9
            lines.append(
                f"{vehicle}\t{component}\t{k}\t{v:.9g}\t{typ}"
                if typ == 9
                else f"{vehicle}\t{component}\t{k}\t{v}\t{typ}"
            )
        lines.append(f"{vehicle}\t{component}\tTC_G_ENABLE\t1\t6")
        return "\n".join(lines) + "\n"

    def to_dict(self) -> ModelDict:
        """``models`` entries of the model file."""
        self._check()
        return {"models": [{"tref_c": self.tref_c_, "coefficients": c.tolist()} for c in self.coef_.T]}

    @classmethod
    def from_dict(cls, d: ModelDict, range_c: tuple[float, float]) -> Px4BiasModel:
        """Inverse of :meth:`to_dict`, every value checked (:class:`DataFormatError` naming its
        JSON path): per axis ``tref_c`` (°C, physical, the same on every axis) and exactly 4
        finite coefficients X0…X3."""
        models = jc.array(jc.field(d, "models"), "models")
        if d.get("derivative_models") is not None:
            raise jc.fail("derivative_models", "a px4 model has none (expected null)")
        tref: float | None = None
        coefs = []
        for i, entry in enumerate(models):
            p = jc.at("models", i)
            e = jc.only(jc.obj(entry, p), ("tref_c", "coefficients"), p)
            t = jc.number(
                jc.field(e, "tref_c", p), jc.at(p, "tref_c"), lo=TEMP_MIN_C, hi=TEMP_MAX_C, unit="°C"
            )
            if tref is not None and t != tref:
                # PX4 holds one TREF per sensor: differing values cannot be represented.
                raise jc.fail(jc.at(p, "tref_c"), f"{t:g} °C differs from models[0]'s {tref:g} °C")
            tref = t
            coefs.append(jc.vector(jc.field(e, "coefficients", p), jc.at(p, "coefficients"), length=4))
        assert tref is not None
        m = cls()
        m.tref_c_ = tref
        m.coef_ = np.stack(coefs, axis=1)
        m.range_c_ = (float(range_c[0]), float(range_c[1]))
        return m

    def save(self, path: str | os.PathLike[str], training: ModelDict | None = None) -> None:
        """Write the model file atomically (see :mod:`uasnav.thermal.modelfile`)."""
        save_model(self, path, training=training)
