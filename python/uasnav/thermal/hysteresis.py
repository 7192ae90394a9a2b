"""Hysteresis-aware fitting (beyond the thesis): heating and cooling branches share one
temperature shape (hence one slope ∂b/∂T) and differ by a constant offset per branch.

``b(T, branch) = Σ_{j≥1} a_j u^j + c_branch``, ``u = (T − c)/s``, fitted jointly by least
squares; the hysteresis width is ``c_cooling − c_heating`` per axis. This is the structure the
thesis' TCZUPT argument relies on (§4.2.3.2: the derivative "tends to be constant on the
different branches that form the hysteresis loop", Gulmammadov 2009).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav.errors import InputError
from uasnav.thermal._common import FloatArray, check_fit_data, check_temp


def branch_from_temperature(t: ArrayLike, temp: ArrayLike, smooth_s: float = 30.0) -> NDArray[np.bool_]:
    """Heating mask (n,): True where the smoothed temperature rises, False where it falls.

    Stationary stretches inherit the previous branch (the sensor stays on the branch it came
    from); the start takes the first non-zero trend.
    """
    tt, tc = check_temp(t, "t"), check_temp(temp)
    if tt.size != tc.size:
        raise InputError(f"t and temp: lengths differ ({tt.size} vs {tc.size})")
    dt = float(np.median(np.diff(tt))) if tt.size > 1 else 1.0
    w = max(1, round(smooth_s / dt))
    kern = np.ones(w) / w
    pad = np.pad(tc, (w // 2, w - 1 - w // 2), mode="edge")
    sm = np.convolve(pad, kern, mode="valid")
    slope = np.gradient(sm, tt)
    eps = 1e-4  # °C/s: below this the temperature is considered stable
    s = np.where(slope > eps, 1, np.where(slope < -eps, -1, 0))
    nz = np.flatnonzero(s)
    first = s[nz[0]] if nz.size else 1
    idx = np.maximum.accumulate(np.where(s != 0, np.arange(s.size), 0))
    filled = np.where(s[idx] != 0, s[idx], first)
    return filled > 0


@dataclass(frozen=True)
class HysteresisFit:
    """Shared-shape, branch-offset fit.

    Attributes
    ----------
    coef : ndarray, shape (order, k)
        Shape coefficients a_1…a_m of u^j (rad/s).
    offsets : ndarray, shape (2, k)
        Branch offsets [heating, cooling] (rad/s).
    width : ndarray, shape (k,)
        Hysteresis width, cooling − heating (rad/s).
    center_c, scale_c : float
        Centring of the temperature variable (°C).
    rms_residual : ndarray, shape (k,)
        RMS residual of the fit (rad/s).
    width_std : ndarray, shape (k,)
        1-σ standard error of ``width`` for white residuals (rad/s); correlated noise makes
        the true uncertainty larger.
    """

    coef: FloatArray
    offsets: FloatArray
    width: FloatArray
    center_c: float
    scale_c: float
    rms_residual: FloatArray
    width_std: FloatArray

    def predict(self, temp: ArrayLike, heating: ArrayLike) -> FloatArray:
        """Bias (n, k) rad/s at temperatures (n,) on the given branches (n,) bool."""
        t = check_temp(temp)
        h = np.asarray(heating, dtype=bool)
        u = (t - self.center_c) / self.scale_c
        v = np.polynomial.polynomial.polyvander(u, self.coef.shape[0])[:, 1:]
        return v @ self.coef + np.where(h[:, None], self.offsets[0], self.offsets[1])

    def derivative(self, temp: ArrayLike) -> FloatArray:
        """Shared ∂b/∂T (n, k) rad/s/°C (the same on both branches)."""
        u = (check_temp(temp) - self.center_c) / self.scale_c
        c = np.vstack([np.zeros((1, self.coef.shape[1])), self.coef])
        return np.asarray(
            np.polynomial.polynomial.polyval(u, np.polynomial.polynomial.polyder(c, axis=0)).T / self.scale_c,
            dtype=np.float64,
        )


def fit_hysteresis(temp: ArrayLike, bias: ArrayLike, heating: ArrayLike, order: int = 3) -> HysteresisFit:
    """Fit a shared polynomial shape of ``order`` plus one offset per branch.

    Parameters
    ----------
    temp : array_like, shape (n,)
        Temperature (°C).
    bias : array_like, shape (n, k)
        Gyro bias (rad/s).
    heating : array_like of bool, shape (n,)
        Branch of each sample (True heating, False cooling), e.g. from
        :func:`branch_from_temperature`.
    order : int
        Order of the shared shape (≥ 1).
    """
    t, b = check_fit_data(temp, bias)
    h = np.asarray(heating, dtype=bool)
    if h.shape != t.shape:
        raise InputError(f"heating: expected shape {t.shape}, got {h.shape}")
    if h.all() or not h.any():
        raise InputError(
            "heating: the data hold only one branch; hysteresis needs heating and cooling samples"
        )
    if order < 1:
        raise InputError(f"order: must be ≥ 1, got {order}")
    c, s = 0.5 * (t.min() + t.max()), 0.5 * np.ptp(t)
    u = (t - c) / s
    v = np.polynomial.polynomial.polyvander(u, order)[:, 1:]
    x = np.hstack([v, h[:, None].astype(float), (~h)[:, None].astype(float)])
    sol, *_ = np.linalg.lstsq(x, b, rcond=None)
    res = b - x @ sol
    offsets = sol[order:]
    # Var(c_cool − c_heat) = σ² gᵀ(XᵀX)⁻¹g with g selecting the two offsets.
    g = np.zeros(x.shape[1])
    g[-1], g[-2] = 1.0, -1.0
    gcg = float(g @ np.linalg.solve(x.T @ x, g))
    dof = max(t.size - x.shape[1], 1)
    sigma2 = np.sum(res**2, axis=0) / dof
    return HysteresisFit(
        coef=sol[:order],
        offsets=offsets,
        width=offsets[1] - offsets[0],
        center_c=float(c),
        scale_c=float(s),
        rms_residual=np.sqrt(np.mean(res**2, axis=0)),
        width_std=np.sqrt(sigma2 * gcg),
    )
