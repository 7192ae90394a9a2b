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

from uasnav import jsoncheck as jc
from uasnav.errors import InputError
from uasnav.thermal._common import (
    TEMP_MAX_C,
    TEMP_MIN_C,
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

#: Highest polynomial order fitted or loaded.
MAX_ORDER = 20


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
        if not (isinstance(self.order, int | np.integer) and 0 <= self.order <= MAX_ORDER):
            raise InputError(f"order: expected an integer in 0…{MAX_ORDER}, got {self.order!r}")
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
        """Inverse of :meth:`to_dict`, every value checked (:class:`DataFormatError` naming its
        JSON path): per axis ``center_c`` (°C, physical), ``scale_c`` > 0 (°C), 1…21
        finite coefficients; all axes share one centring and one order."""
        models = jc.array(jc.field(d, "models"), "models")
        if d.get("derivative_models") is not None:
            raise jc.fail("derivative_models", "a polynomial model has none (expected null)")
        coefs: list[FloatArray] = []
        norm: tuple[float, float] | None = None
        for i, entry in enumerate(models):
            p = jc.at("models", i)
            e = jc.only(jc.obj(entry, p), ("center_c", "scale_c", "coefficients"), p)
            c = jc.number(
                jc.field(e, "center_c", p), jc.at(p, "center_c"), lo=TEMP_MIN_C, hi=TEMP_MAX_C, unit="°C"
            )
            sc = jc.number(jc.field(e, "scale_c", p), jc.at(p, "scale_c"), positive=True, unit="°C")
            cp = jc.at(p, "coefficients")
            k = jc.vector(jc.field(e, "coefficients", p), cp, max_len=MAX_ORDER + 1)
            if norm is None:
                norm = (c, sc)
            elif (c, sc) != norm:
                # One centring serves every axis: differing values cannot be represented.
                raise jc.fail(p, "center_c/scale_c differ from models[0]'s (the axes share one)")
            if coefs and k.size != coefs[0].size:
                raise jc.fail(cp, f"{k.size} coefficients, models[0] has {coefs[0].size}")
            coefs.append(k)
        assert norm is not None
        m = cls(order=coefs[0].size - 1)
        m.center_c_, m.scale_c_ = norm
        m.coef_ = np.stack(coefs, axis=1)
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
