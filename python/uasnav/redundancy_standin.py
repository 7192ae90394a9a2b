"""Stand-in multi-sensor generator for the redundancy experiments (static unit only).

**Stand-in**: the project's simulator (``uasnav.sim.simulate_array``) had not landed when
the redundancy work was done, so the redundancy report section and tests generate their
static multi-sensor data here. It models only what eqs. (38)–(46) are about, per sensor and
axis: white noise, a turn-on bias and a bias instability (first-order Gauss–Markov), with
LSM6DSM datasheet values (gyro 3.8 mdps/√Hz, ±3 dps turn-on; accelerometer 40 µg/√Hz,
±40 mg turn-on). The bias instability is not on the datasheet: we assume 10 °/h and
0.05 mg with a 100 s correlation time, typical of consumer MEMS.

Each returned log is in its sensor's frame, with ``meta["mounting"]`` the nominal mounting
(IMU → sensor) and ``meta["mounting_true"]`` the actual one when mounting errors are drawn.
"""

from __future__ import annotations

import math

import numpy as np

from uasnav.errors import InputError
from uasnav.imu import ImuLog

OMEGA_IE = 7.292115e-5
DEG = math.pi / 180.0
G0 = 9.80665

#: LSM6DSM-like parameters (SI): white-noise densities, turn-on half ranges, instabilities.
LSM6DSM = {
    "gyro_nd": 3.8e-3 * DEG,  # rad/s/√Hz
    "accel_nd": 40e-6 * G0,  # m/s²/√Hz
    "gyro_turn_on": 3.0 * DEG,  # rad/s, uniform ±
    "accel_turn_on": 40e-3 * G0,  # m/s², uniform ±
    "gyro_bi": 10.0 * DEG / 3600.0,  # rad/s (assumed)
    "accel_bi": 0.05e-3 * G0,  # m/s² (assumed)
    "bi_tau_s": 100.0,
}


def _dcm_321(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """C_b^n of 3-2-1 Euler angles (rad)."""
    cr, sr, cp, sp, cy, sy = (
        math.cos(roll),
        math.sin(roll),
        math.cos(pitch),
        math.sin(pitch),
        math.cos(yaw),
        math.sin(yaw),
    )
    return np.array(
        [
            [cp * cy, sr * sp * cy - cr * sy, cr * sp * cy + sr * sy],
            [cp * sy, sr * sp * sy + cr * cy, cr * sp * sy - sr * cy],
            [-sp, sr * cp, cr * cp],
        ]
    )


def _small_rotation(phi: np.ndarray) -> np.ndarray:
    """exp([φ×]) by Rodrigues' formula."""
    a = float(np.linalg.norm(phi))
    if a == 0.0:
        return np.eye(3)
    k = phi / a
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(a) * kx + (1 - math.cos(a)) * kx @ kx


def _gauss_markov(
    rng: np.random.Generator, n: int, k: int, sigma: float, tau: float, dt: float
) -> np.ndarray:
    from scipy.signal import lfilter

    phi = math.exp(-dt / tau)
    q = sigma * math.sqrt(1.0 - phi * phi)
    w = q * rng.standard_normal((n, k))
    # x_k = φ·x_{k−1} + w_k started in steady state (x_0 ~ N(0, σ²)).
    x0 = sigma * rng.standard_normal(k)
    zi = (phi * x0)[None, :]
    x, _ = lfilter([1.0], [1.0, -phi], w, axis=0, zi=zi)
    return np.asarray(x)


def standin_array(
    mountings: np.ndarray,
    *,
    duration: float = 120.0,
    rate: float = 100.0,
    seed: int = 0,
    latitude_deg: float = 45.0,
    euler_rad: tuple[float, float, float] = (0.0, 0.0, 0.0),
    mounting_error_rad: float = 0.0,
    params: dict[str, float] | None = None,
    noise_seed: int = 0,
) -> list[ImuLog]:
    """Static logs of triaxial sensors with the given nominal mountings (s, 3, 3).

    Parameters
    ----------
    mountings : ndarray, shape (s, 3, 3)
        Nominal mountings IMU → sensor.
    duration, rate : float
        Length (s) and sample rate (Hz).
    seed : int
        Seed of every random draw (deterministic).
    latitude_deg : float
        Latitude for the Earth rate.
    euler_rad : tuple
        Attitude of the IMU frame (3-2-1 roll, pitch, yaw, rad; body → NED).
    mounting_error_rad : float
        σ (rad, per axis) of a random mounting error of every sensor but the first.
    params : dict, optional
        Overrides of :data:`LSM6DSM`.
    noise_seed : int
        Seed of the noise and bias-instability draws only: runs with the same ``seed`` and
        different ``noise_seed`` share the mounting errors and turn-on biases (the same
        hardware recorded twice).
    """
    m = np.asarray(mountings, dtype=np.float64)
    if m.ndim != 3 or m.shape[1:] != (3, 3):
        raise InputError(f"mountings: expected shape (s, 3, 3), got {m.shape}")
    if not (duration > 0 and rate > 0):
        raise InputError("duration, rate: must be > 0")
    p = {**LSM6DSM, **(params or {})}
    rng = np.random.default_rng(seed)
    rng_noise = np.random.default_rng([seed, noise_seed])
    n = round(duration * rate)
    dt = 1.0 / rate
    t = np.linspace(0.0, (n - 1) * dt, n)
    lat = math.radians(latitude_deg)
    c_bn = _dcm_321(*euler_rad)
    w_imu = c_bn.T @ (OMEGA_IE * np.array([math.cos(lat), 0.0, -math.sin(lat)]))
    f_imu = c_bn.T @ np.array([0.0, 0.0, -G0])
    logs = []
    for i, c_nom in enumerate(m):
        err = rng.normal(0.0, mounting_error_rad, 3) if (mounting_error_rad > 0 and i > 0) else np.zeros(3)
        c_true = _small_rotation(err) @ c_nom
        b_g = rng.uniform(-p["gyro_turn_on"], p["gyro_turn_on"], 3) + _gauss_markov(
            rng_noise, n, 3, p["gyro_bi"], p["bi_tau_s"], dt
        )
        b_a = rng.uniform(-p["accel_turn_on"], p["accel_turn_on"], 3) + _gauss_markov(
            rng_noise, n, 3, p["accel_bi"], p["bi_tau_s"], dt
        )
        w_s = c_true @ w_imu
        f_s = c_true @ f_imu
        gyro = w_s + b_g + p["gyro_nd"] * math.sqrt(rate) * rng_noise.standard_normal((n, 3))
        accel = f_s + b_a + p["accel_nd"] * math.sqrt(rate) * rng_noise.standard_normal((n, 3))
        logs.append(
            ImuLog(
                t=t,
                gyro=gyro,
                accel=accel,
                truth={
                    "rate_true": np.broadcast_to(w_s, (n, 3)).copy(),
                    "specific_force_true": np.broadcast_to(f_s, (n, 3)).copy(),
                    "gyro_bias": b_g,
                    "accel_bias": b_a,
                },
                meta={
                    "preset": "lsm6dsm-standin",
                    "seed": seed,
                    "rate_hz": rate,
                    "sensor": i,
                    "mounting": c_nom.tolist(),
                    "mounting_true": c_true.tolist(),
                },
            )
        )
    return logs


__all__ = ["LSM6DSM", "standin_array"]
