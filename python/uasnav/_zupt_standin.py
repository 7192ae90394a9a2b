"""STAND-IN data for the ZUPT evaluation until the simulator (``uasnav.sim``) and the thermal
models (``uasnav.thermal``) are on main.

A deliberately small generator of AX1-like static logs (CRS05-02 gyro noise of the thesis'
Table 3, MS8010 accelerometer noise of Table 4) with a quadratic thermal gyro bias, an
optional heating/cooling hysteresis, and a polynomial calibration model fitted on a soak
sweep. Everything here is a stand-in: the report and the tests say so wherever it is used.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav.imu import ImuLog

FloatArray = NDArray[np.float64]

_DEG = np.pi / 180.0
ARW_RAD_SQRT_S = 3.18 * _DEG / 60.0  # Table 3
VRW_M_S_SQRT_S = 0.05 / 60.0  # Table 4
GYRO_RRW_RAD_S_SQRT_S = 2e-7  # small bias random walk (stand-in value)
T_REF_C = 30.0
#: Thermal bias b(T) = C1·(T − 30) + C2·(T − 30)² per axis (rad/s/°C, rad/s/°C²).
C1 = np.array([2.0e-5, -3.0e-5, 1.5e-5])
C2 = np.array([1.5e-6, 1.0e-6, -1.2e-6])


def thermal_bias(temp: ArrayLike) -> FloatArray:
    """True thermal gyro bias (n, 3) rad/s of the stand-in sensor at die temperature (°C)."""
    d = np.asarray(temp, dtype=np.float64)[:, None] - T_REF_C
    return np.asarray(C1 * d + C2 * d * d, dtype=np.float64)


def ramp_profile(t: FloatArray, lo: float = 27.28, hi: float = 34.08, rate_c_min: float = 2.0) -> FloatArray:
    """Die temperature (°C) of the thesis' ramp test: 60 s at ``lo``, then triangular ramps
    between ``lo`` and ``hi`` at ``rate_c_min`` with 60 s dwells, smoothed by a 20 s lag."""
    up = (hi - lo) / (rate_c_min / 60.0)
    period = 2 * up + 120.0
    tt = np.maximum(t - 60.0, 0.0) % period
    chamber = np.where(
        tt < up,
        lo + (hi - lo) * tt / up,
        np.where(tt < up + 60, hi, np.where(tt < 2 * up + 60, hi - (hi - lo) * (tt - up - 60) / up, lo)),
    )
    chamber[t < 60.0] = lo
    a = np.exp(-np.median(np.diff(t)) / 20.0) if t.size > 1 else 0.0
    # First-order lag of the die behind the chamber (a recursive filter, vectorised by scipy).
    from scipy.signal import lfilter

    die = lfilter([1 - a], [1, -a], chamber - lo) + lo
    return np.asarray(die, dtype=np.float64)


@dataclass(frozen=True)
class PolyThermalModel:
    """Stand-in calibration model: per-axis cubic ``b(T)`` fitted on a soak sweep."""

    coeffs: FloatArray  # (3, 4), highest power first, in (T − 30)

    @classmethod
    def fit(cls, temp: ArrayLike, bias: ArrayLike, order: int = 3) -> PolyThermalModel:
        d = np.asarray(temp, dtype=np.float64) - T_REF_C
        b = np.asarray(bias, dtype=np.float64)
        return cls(np.array([np.polyfit(d, b[:, j], order) for j in range(3)]))

    def predict(self, temp: ArrayLike) -> FloatArray:
        d = np.asarray(temp, dtype=np.float64) - T_REF_C
        return np.column_stack([np.polyval(c, d) for c in self.coeffs])

    def derivative(self, temp: ArrayLike) -> FloatArray:
        d = np.asarray(temp, dtype=np.float64) - T_REF_C
        return np.column_stack([np.polyval(np.polyder(c), d) for c in self.coeffs])


def soak_calibration(seed: int = 1, hysteresis_rad_s: float = 0.0) -> PolyThermalModel:
    """Fit the stand-in model on a stabilised soak (−20.5 … 37.3 °C in 5 °C steps, 30 min of
    averaged static output per step, heating branch only)."""
    rng = np.random.default_rng(seed)
    steps = np.arange(-20.53, 37.31, 5.0)
    # 30 min of white rate noise averages to ARW/√1800 per point.
    noise = rng.normal(0.0, ARW_RAD_SQRT_S / np.sqrt(1800.0), (steps.size, 3))
    bias = thermal_bias(steps) + hysteresis_rad_s + noise
    return PolyThermalModel.fit(steps, bias)


def static_log(
    duration_s: float = 1560.0,
    *,
    rate_hz: float = 100.0,
    seed: int = 0,
    latitude_deg: float = 45.0,
    euler_rad: tuple[float, float, float] = (0.012, -0.021, 0.4),
    profile: str = "ramp",
    hysteresis_rad_s: float = 0.0,
    turn_on_std_rad_s: float = 1e-3,
) -> ImuLog:
    """A static AX1-like log with truth channels ``gyro_bias`` (total), ``gyro_bias_thermal``,
    ``accel_bias`` (n, 3) and ``temp_die`` (n,). ``profile``: ``"ramp"`` (thesis ramp test)
    or ``"constant"`` (30 °C). With ``hysteresis_rad_s`` the bias is offset by +h while
    heating and −h while cooling (smoothly switched on dT/dt)."""
    rng = np.random.default_rng(seed)
    n = round(duration_s * rate_hz)
    dt = 1.0 / rate_hz
    t = np.arange(n) * dt
    temp = ramp_profile(t) if profile == "ramp" else np.full(n, T_REF_C)
    lat = np.deg2rad(latitude_deg)
    roll, pitch, yaw = euler_rad
    cr, sr, cp, sp, cy, sy = (
        np.cos(roll),
        np.sin(roll),
        np.cos(pitch),
        np.sin(pitch),
        np.cos(yaw),
        np.sin(yaw),
    )
    c_bn = np.array(
        [
            [cp * cy, cp * sy, -sp],
            [sr * sp * cy - cr * sy, sr * sp * sy + cr * cy, sr * cp],
            [cr * sp * cy + sr * sy, cr * sp * sy - sr * cy, cr * cp],
        ]
    )
    w_b = c_bn @ (7.292115e-5 * np.array([np.cos(lat), 0.0, -np.sin(lat)]))
    s2 = np.sin(lat) ** 2
    g = 9.7803253359 * (1 + 0.00193185265241 * s2) / np.sqrt(1 - 0.00669437999014 * s2)
    f_b = c_bn @ np.array([0.0, 0.0, -g])
    turn_on = rng.normal(0.0, turn_on_std_rad_s, 3)
    rw = np.cumsum(rng.normal(0.0, GYRO_RRW_RAD_S_SQRT_S * np.sqrt(dt), (n, 3)), axis=0)
    thermal = thermal_bias(temp)
    if hysteresis_rad_s:
        dtemp = np.gradient(temp, dt)
        thermal = thermal + hysteresis_rad_s * np.tanh(dtemp / 2e-3)[:, None]
    bias = turn_on + rw + thermal
    gyro = w_b + bias + rng.normal(0.0, ARW_RAD_SQRT_S / np.sqrt(dt), (n, 3))
    ba = rng.normal(0.0, 0.02, 3)
    accel = f_b + ba + rng.normal(0.0, VRW_M_S_SQRT_S / np.sqrt(dt), (n, 3))
    measured = np.round(temp / 0.0625) * 0.0625
    return ImuLog(
        t=t,
        gyro=gyro,
        accel=accel,
        temp=measured,
        truth={
            "gyro_bias": bias,
            "gyro_bias_thermal": thermal,
            "accel_bias": np.broadcast_to(ba, (n, 3)).copy(),
            "temp_die": temp,
        },
        meta={"preset": "standin-ax1", "seed": seed, "rate_hz": rate_hz, "latitude_deg": latitude_deg},
    )


__all__ = ["PolyThermalModel", "ramp_profile", "soak_calibration", "static_log", "thermal_bias"]
