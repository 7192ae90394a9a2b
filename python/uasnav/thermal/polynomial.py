"""Polynomial thermal model of gyro bias (thesis §4.2.2.1, eqs. 6–7) and order selection by
Sr_PF (eq. 32).

The least-squares fit uses the centred, scaled variable ``u = (T − c)/s`` with ``c`` the
middle and ``s`` the half-width of the calibrated range, so ``u ∈ [−1, 1]`` and the
Vandermonde matrix stays well conditioned at any order (a raw ``T^j`` basis loses digits at
order 6 already over −20…40 °C).
"""

from __future__ import annotations

import os
from typing import Literal, overload

import numpy as np
from numpy.typing import ArrayLike

from uasnav.errors import InputError
from uasnav.thermal._common import (
    BoolArray,
    FloatArray,
    NotFittedError,
    SelectionResult,
    check_fit_data,
    check_temp,
    choose,
    clip_temp,
    split_uniform,
    sr,
)
from uasnav.thermal.base import ModelDict, register_model
from uasnav.thermal.modelfile import save_model


@register_model
class PolynomialBiasModel:
    """Least-squares polynomial bias(T) per axis (eq. 6–7).

    Parameters
    ----------
    order : int
        Polynomial order m ≥ 0.

    Attributes
    ----------
    coef_ : ndarray, shape (order + 1, k)
        Coefficients a_j of ``u^j`` per axis (rad/s), ``u = (T − center_c_)/scale_c_``.
    center_c_, scale_c_ : float
        Centre and half-width of the calibrated range (°C).
    range_c_ : tuple of float
        Calibrated temperature range (°C); inputs outside it are clipped and flagged.
    """

    kind = "polynomial"

    def __init__(self, order: int = 2) -> None:
        self.order = order

    def fit(self, temp: ArrayLike, bias: ArrayLike) -> PolynomialBiasModel:
        """Fit to temperatures (n,) °C and biases (n, k) rad/s; returns self."""
        if not (isinstance(self.order, int | np.integer) and 0 <= self.order <= 20):
            raise InputError(f"order: expected an integer in 0…20, got {self.order!r}")
        t, b = check_fit_data(temp, bias, min_samples=self.order + 1)
        lo, hi = float(t.min()), float(t.max())
        self.center_c_ = 0.5 * (lo + hi)
        self.scale_c_ = 0.5 * (hi - lo)
        self.range_c_ = (lo, hi)
        v = np.polynomial.polynomial.polyvander((t - self.center_c_) / self.scale_c_, self.order)
        self.coef_, *_ = np.linalg.lstsq(v, b, rcond=None)
        return self

    def _check(self) -> None:
        if not hasattr(self, "coef_"):
            raise NotFittedError("PolynomialBiasModel: call fit() or load_model() first")

    @overload
    def predict(self, temp: ArrayLike, *, return_clipped: Literal[False] = ...) -> FloatArray: ...

    @overload
    def predict(self, temp: ArrayLike, *, return_clipped: Literal[True]) -> tuple[FloatArray, BoolArray]: ...

    def predict(
        self, temp: ArrayLike, *, return_clipped: bool = False
    ) -> FloatArray | tuple[FloatArray, BoolArray]:
        """Bias (n, k) rad/s at temperatures (n,) °C (clipped to the calibrated range, with a
        :class:`TemperatureRangeWarning`); with ``return_clipped`` also the (n,) clip mask."""
        self._check()
        t, clipped = clip_temp(check_temp(temp), *self.range_c_, "PolynomialBiasModel")
        u = (t - self.center_c_) / self.scale_c_
        out = np.polynomial.polynomial.polyval(u, self.coef_).T.copy()
        return (out, clipped) if return_clipped else out

    def derivative(self, temp: ArrayLike) -> FloatArray:
        """∂bias/∂T (n, k) rad/s/°C; 0 where the temperature was clipped."""
        self._check()
        t, clipped = clip_temp(check_temp(temp), *self.range_c_, "PolynomialBiasModel")
        u = (t - self.center_c_) / self.scale_c_
        dc = np.polynomial.polynomial.polyder(self.coef_, axis=0) / self.scale_c_
        out = np.polynomial.polynomial.polyval(u, dc).T.copy()
        out[clipped] = 0.0
        return np.asarray(out, dtype=np.float64)

    def to_dict(self) -> ModelDict:
        """The ``models`` entries of the model file (one per axis)."""
        self._check()
        return {
            "models": [
                {"center_c": self.center_c_, "scale_c": self.scale_c_, "coefficients": col.tolist()}
                for col in self.coef_.T
            ]
        }

    @classmethod
    def from_dict(cls, d: ModelDict, range_c: tuple[float, float]) -> PolynomialBiasModel:
        """Inverse of :meth:`to_dict`."""
        models = d["models"]
        coefs = [m["coefficients"] for m in models]
        if len({len(c) for c in coefs}) != 1:
            raise InputError("models: axes have different polynomial orders")
        m = cls(order=len(coefs[0]) - 1)
        m.center_c_ = float(models[0]["center_c"])
        m.scale_c_ = float(models[0]["scale_c"])
        m.coef_ = np.asarray(coefs, dtype=np.float64).T.copy()
        m.range_c_ = (float(range_c[0]), float(range_c[1]))
        return m

    def save(self, path: str | os.PathLike[str], training: ModelDict | None = None) -> None:
        """Write the model file atomically (see :mod:`uasnav.thermal.modelfile`)."""
        save_model(self, path, training=training)


def select_polynomial_order(
    temp: ArrayLike,
    bias: ArrayLike,
    orders: tuple[int, ...] = tuple(range(1, 11)),
    *,
    rel_tol: float = 0.05,
    seed: int = 0,
) -> SelectionResult:
    """Order selection by Sr_PF (eq. 32) on held-out data.

    Fits each order on the 65 % training subset (uniform over temperature) and evaluates
    Sr_PF on the remaining 35 %; picks by :func:`uasnav.thermal._common.choose` (minimum, or
    the smallest order within ``rel_tol`` of it).
    """
    t, b = check_fit_data(temp, bias)
    tr, va, te = split_uniform(t, seed=seed)
    held = np.concatenate([va, te])
    srs = np.array(
        [
            sr(b[held] - PolynomialBiasModel(m).fit(t[tr], b[tr]).predict(np.clip(t[held], *_rng(t[tr]))))
            for m in orders
        ]
    )
    return SelectionResult(tuple(orders), srs, choose(tuple(orders), srs, rel_tol), rel_tol)


def _rng(t: FloatArray) -> tuple[float, float]:
    return float(t.min()), float(t.max())
