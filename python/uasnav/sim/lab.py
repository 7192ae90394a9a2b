"""Simulated laboratory calibration data: what a thermal-chamber soak test gives a lab.

In the lab the unit's orientation is known, so the gyro output minus the true input rate is
the bias. The simulator's non-thermal part of it (turn-on, instability, random walk: truth
``gyro_bias − gyro_bias_thermal``) is removed too, so that fitted models are about the
thermal curve alone, and the result is block-averaged: the thesis' Sr values (~1e-5 rad/s)
are far below the CRS05-02's white noise at any usable rate, so its soak data must have been
averaged (we use 60 s means).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from uasnav.errors import InputError
from uasnav.sim.core import _as_model, simulate_one
from uasnav.sim.model import SensorModel

FloatArray = NDArray[np.float64]

#: Default averaging of the calibration data (s).
AVERAGE_S = 60.0


@dataclass(frozen=True)
class CalibrationData:
    """Block means of a simulated soak test.

    Attributes
    ----------
    temp : ndarray, shape (m,)
        Mean measured die temperature of each block (°C).
    gyro_bias : ndarray, shape (m, 3)
        Mean thermal gyro bias of each block (rad/s, sensor axes).
    average_s : float
        Block length (s).
    rate_hz : float
        Sample rate of the simulated soak (Hz).
    """

    temp: FloatArray
    gyro_bias: FloatArray
    average_s: float
    rate_hz: float


def block_average(x: NDArray[np.float64], k: int) -> FloatArray:
    """Means of consecutive blocks of ``k`` rows (a trailing partial block is dropped)."""
    if k < 1:
        raise InputError(f"block length: expected >= 1 sample, got {k}")
    n = x.shape[0] // k * k
    if n == 0:
        raise InputError(f"block length {k} exceeds the {x.shape[0]} samples")
    return np.asarray(x[:n].reshape(n // k, k, *x.shape[1:]).mean(axis=1), dtype=np.float64)


def soak_calibration_data(
    preset: str | SensorModel = "ax1",
    *,
    seed: int = 0,
    rate: float = 10.0,
    average_s: float = AVERAGE_S,
) -> CalibrationData:
    """Simulate the thesis' soak test (Figure 29) and return block-mean thermal gyro bias.

    Parameters
    ----------
    preset : str or SensorModel
        Sensor preset or model.
    seed : int
        Simulation seed.
    rate : float
        Sample rate of the simulated soak (Hz); the soak lasts ~6 h, so 1–10 Hz suffice.
    average_s : float
        Block length (s) of the means.
    """
    log = simulate_one(_as_model(preset), profile="soak", rate=rate, seed=seed)
    if log.temp is None:  # every preset has a temperature channel; a user model might not
        raise InputError(f"{log.meta.get('preset')}: the soak test needs a temperature channel")
    other = log.truth["gyro_bias"] - log.truth["gyro_bias_thermal"]
    k = max(1, round(rate * average_s))
    temp = block_average(log.temp, k)
    bias = block_average(log.gyro - log.truth["rate_true"] - other, k)
    return CalibrationData(temp=temp, gyro_bias=bias, average_s=k / rate, rate_hz=rate)


__all__ = ["AVERAGE_S", "CalibrationData", "block_average", "soak_calibration_data"]
