"""Sensor faults injected into simulated multi-sensor outputs (redundancy FDI experiments).

The simulator produces healthy sensors; :func:`inject_fault` turns one sensor of a stacked
array output (one column per sensor axis, ``uasnav.redundancy.stack_logs`` layout) faulty
from a given sample on. The kinds are the ones a fault detection and isolation scheme must
handle: a bias step, a stuck output, a noise burst, saturation and a dropout.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav.errors import InputError

FAULT_KINDS = ("bias step", "stuck", "noise burst", "saturation", "dropout")

#: Default magnitudes for gyros (rad/s): a 2 deg/s bias step, a 1 deg/s rms noise burst and
#: the ±250 deg/s full scale of a consumer MEMS gyro.
GYRO_DEFAULTS = {
    "bias step": math.radians(2.0),
    "noise burst": math.radians(1.0),
    "saturation": math.radians(250.0),
}


def inject_fault(
    z: ArrayLike,
    kind: str,
    *,
    sensor: int,
    start: int,
    axis: int = 0,
    axes_per_sensor: int = 3,
    magnitude: float | None = None,
    duration: int = 300,
    seed: int = 0,
) -> NDArray[np.float64]:
    """A copy of ``z`` with one sensor faulty from sample ``start`` on.

    Parameters
    ----------
    z : array_like, shape (m, n)
        Sensor-axis samples; sensor ``i`` owns columns ``i·axes_per_sensor …``.
    kind : {"bias step", "stuck", "noise burst", "saturation", "dropout"}
        ``bias step``: ``magnitude`` added to one axis; ``stuck``: every axis of the sensor
        repeats its last good sample; ``noise burst``: white noise of rms ``magnitude`` on
        every axis for ``duration`` samples; ``saturation``: one axis pinned at
        ``magnitude``; ``dropout``: every axis NaN.
    sensor, axis : int
        Faulty sensor and, for single-axis faults, its axis (0 … axes_per_sensor − 1).
    start : int
        First faulty sample (≥ 1, so that a stuck output has a last good value).
    magnitude : float, optional
        In the unit of ``z``; default :data:`GYRO_DEFAULTS` (rad/s).
    duration : int
        Length of a noise burst (samples).
    seed : int
        Seed of the noise burst.
    """
    out = np.array(z, dtype=np.float64)
    if out.ndim != 2:
        raise InputError(f"z: expected shape (m, n), got {out.shape}")
    m, n = out.shape
    if kind not in FAULT_KINDS:
        raise InputError(f"kind: expected one of {', '.join(FAULT_KINDS)}, got {kind!r}")
    cols = slice(sensor * axes_per_sensor, (sensor + 1) * axes_per_sensor)
    if not (0 <= sensor and cols.stop <= n):
        raise InputError(f"sensor: {sensor} is not one of the {n // axes_per_sensor} sensors of z")
    if not 0 <= axis < axes_per_sensor:
        raise InputError(f"axis: must be within 0 … {axes_per_sensor - 1}, got {axis}")
    if not 1 <= start < m:
        raise InputError(f"start: must be within 1 … {m - 1}, got {start}")
    mag = GYRO_DEFAULTS.get(kind, 0.0) if magnitude is None else float(magnitude)
    col = cols.start + axis
    if kind == "bias step":
        out[start:, col] += mag
    elif kind == "stuck":
        out[start:, cols] = out[start - 1, cols]
    elif kind == "noise burst":
        k = min(m, start + duration)
        out[start:k, cols] += mag * np.random.default_rng(seed).standard_normal((k - start, axes_per_sensor))
    elif kind == "saturation":
        out[start:, col] = mag
    else:
        out[start:, cols] = np.nan
    return out


__all__ = ["FAULT_KINDS", "GYRO_DEFAULTS", "inject_fault"]
