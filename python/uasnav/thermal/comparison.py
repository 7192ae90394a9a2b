"""The thesis' comparison of thermal calibrations (§4.2.5): calibrate on a soak test, evaluate
on a ramp test, Δω(T) between the neural and polynomial models (eq. 34), and the attitude
drift at the temperatures where Δω is maximum and at its RMS value (Tables 7–8)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from uasnav.attitude import DriftResult, crossing_table, drift
from uasnav.thermal._common import FloatArray, sr


@dataclass
class DeltaOmega:
    """Δω(T) of eq. (34) over a temperature grid.

    Attributes
    ----------
    temp_c : ndarray, shape (m,)
        Temperatures (°C).
    delta : ndarray, shape (m,)
        ‖ω_NN(T) − ω_PF(T)‖ (rad/s) per temperature (the summand of eq. 34).
    max_value, rms_value : float
        Maximum and RMS of ``delta`` (rad/s).
    t_max_c, t_rms_c : float
        Temperature of the maximum, and of the point where ``delta`` is closest to its RMS (°C).
    """

    temp_c: FloatArray
    delta: FloatArray
    max_value: float
    rms_value: float
    t_max_c: float
    t_rms_c: float


def delta_omega(nn: Any, pf: Any, temp_c: FloatArray) -> DeltaOmega:
    """Δω(T) = ‖ω_NN(T) − ω_PF(T)‖ on ``temp_c`` and its max / RMS points (eq. 34)."""
    d = np.linalg.norm(nn.predict(temp_c) - pf.predict(temp_c), axis=1)
    i_max = int(np.argmax(d))
    rms = float(np.sqrt(np.mean(d**2)))
    i_rms = int(np.argmin(np.abs(d - rms)))
    return DeltaOmega(temp_c, d, float(d[i_max]), rms, float(temp_c[i_max]), float(temp_c[i_rms]))


@dataclass
class DriftComparison:
    """Attitude drift of two calibrations' residual rates at one temperature."""

    temp_c: float
    residual_nn: FloatArray
    residual_pf: FloatArray
    drift_nn: DriftResult
    drift_pf: DriftResult
    rows: list[tuple[float, float | None, float | None, float | None]] = field(default_factory=list)


def drift_at(
    nn: Any, pf: Any, truth_bias: FloatArray, temp_c: float, *, dt: float = 0.01, duration: float = 60.0
) -> DriftComparison:
    """θ(t) from integrating each model's residual (truth − model) at ``temp_c`` as a constant
    rate, and the Table 7/8 rows (threshold, t_NN, t_PF, Δt%)."""
    t = np.array([temp_c])
    r_nn = truth_bias - nn.predict(t)[0]
    r_pf = truth_bias - pf.predict(t)[0]
    d_nn = drift(r_nn, dt, duration)
    d_pf = drift(r_pf, dt, duration)
    return DriftComparison(temp_c, r_nn, r_pf, d_nn, d_pf, crossing_table(d_nn, d_pf))


def residual_table(
    models: dict[str, Any], temp_c: FloatArray, truth: FloatArray
) -> dict[str, dict[str, Any]]:
    """RMS and max |truth − model| per axis (rad/s) and Sr for each named model."""
    out = {}
    for name, m in models.items():
        res = truth - m.predict(temp_c)
        out[name] = {
            "rms": np.sqrt(np.mean(res**2, axis=0)),
            "max": np.max(np.abs(res), axis=0),
            "sr": sr(res),
        }
    return out
