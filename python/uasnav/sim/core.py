"""The simulation engine: static scenario, error terms, thermal terms, output path.

Signal chain per triad (sensor frame s, mounting ``M = C_b^s``, all vectorised):

    y = LPF( (I + S + k_sf ΔT) x_true + G f_true + b_on + b_T(T, branch) + b_GM + b_RRW
             + N (1 + k_N ΔT) √f_s ε )                then rounded to the LSB

with ``x_true`` the true rate (Earth rate) or specific force (gravity reaction), ``S`` the
scale-factor/misalignment matrix, ``G`` the gyro g-sensitivity, ``ΔT = T_die − T_ref``,
``b_GM`` the bias instability as a sum of first-order Gauss–Markov processes, ``b_RRW`` a
random walk, ``ε`` unit white noise and LPF the AHRS anti-alias low-pass (Butterworth,
default 2nd order, 30 Hz; skipped when the cut-off is not below 0.45 f_s).

Flicker approximation: Gauss–Markov processes with correlation times τ_k spaced by a ratio
``r`` (3 per decade) over the preset's ``bias_instability_tau_s`` range, each of variance
``σ_k² = B² ln r / π``, sum to the two-sided PSD ``B²/(2π f)`` of IEEE Std 952 flicker noise
between the extreme corner frequencies, so the Allan deviation is flat at 0.664 B there.
Slow processes (τ_k ≫ 1/f_s, and the rate random walk) are generated on a coarser grid
(step ≤ τ_k/20) and interpolated linearly, which changes their spectrum only where the white
noise dominates by orders of magnitude; this keeps 10⁷ samples to a few seconds.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import signal
from scipy.spatial.transform import Rotation

from uasnav import earth
from uasnav.errors import InputError
from uasnav.imu import ImuLog
from uasnav.limits import check_memory
from uasnav.sim.model import SensorModel, ThermalErrorTruth, TriadModel, load_preset
from uasnav.sim.profiles import TemperatureProfile, named_profile

FloatArray = NDArray[np.float64]
Progress = Callable[[float], None] | None

# Independent random streams (a term switched off does not change the others).
_STREAMS = {
    name: i
    for i, name in enumerate(
        [
            "gyro_white",
            "gyro_gm",
            "gyro_rrw",
            "gyro_turn_on",
            "gyro_static",
            "accel_white",
            "accel_gm",
            "accel_rrw",
            "accel_turn_on",
            "accel_static",
            "temp",
            "array",
            "mounting",
        ]
    )
}
GM_PER_DECADE = 3
# Streams that a repeated recording of the same hardware draws afresh (``noise_seed``).
_NOISE_STREAMS = frozenset(
    {"gyro_white", "gyro_gm", "gyro_rrw", "accel_white", "accel_gm", "accel_rrw", "temp"}
)


def _rng(seed: int, sensor: int, stream: str, noise_seed: int | None = None) -> np.random.Generator:
    key: tuple[int, ...] = (int(sensor), _STREAMS[stream])
    if noise_seed is not None and stream in _NOISE_STREAMS:
        key += (int(noise_seed),)
    return np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=key))


def _euler_dcm(euler: ArrayLike) -> FloatArray:
    """C_b^n (body → NED) of 3-2-1 Euler angles ``[roll, pitch, yaw]`` (rad)."""
    r, p, y = (float(v) for v in np.asarray(euler, dtype=np.float64).ravel())
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array(
        [
            [cp * cy, sr * sp * cy - cr * sy, cr * sp * cy + sr * sy],
            [cp * sy, sr * sp * sy + cr * cy, cr * sp * sy - sr * cy],
            [-sp, sr * cp, cr * cp],
        ]
    )


def _dcm_quat(c: FloatArray) -> FloatArray:
    """Scalar-first quaternion of a rotation matrix (Shepperd's method)."""
    tr = np.trace(c)
    k = int(np.argmax([tr, c[0, 0], c[1, 1], c[2, 2]]))
    if k == 0:
        s = math.sqrt(1.0 + tr) * 2.0
        q = [0.25 * s, (c[2, 1] - c[1, 2]) / s, (c[0, 2] - c[2, 0]) / s, (c[1, 0] - c[0, 1]) / s]
    elif k == 1:
        s = math.sqrt(1.0 + c[0, 0] - c[1, 1] - c[2, 2]) * 2.0
        q = [(c[2, 1] - c[1, 2]) / s, 0.25 * s, (c[0, 1] + c[1, 0]) / s, (c[0, 2] + c[2, 0]) / s]
    elif k == 2:
        s = math.sqrt(1.0 + c[1, 1] - c[0, 0] - c[2, 2]) * 2.0
        q = [(c[0, 2] - c[2, 0]) / s, (c[0, 1] + c[1, 0]) / s, 0.25 * s, (c[1, 2] + c[2, 1]) / s]
    else:
        s = math.sqrt(1.0 + c[2, 2] - c[0, 0] - c[1, 1]) * 2.0
        q = [(c[1, 0] - c[0, 1]) / s, (c[0, 2] + c[2, 0]) / s, (c[1, 2] + c[2, 1]) / s, 0.25 * s]
    qa = np.array(q)
    return qa if qa[0] >= 0 else -qa


def _quat_mul(p: FloatArray, q: FloatArray) -> FloatArray:
    """Hamilton product p ⊗ q of scalar-first quaternions (n, 4) ⊗ (4,) → (n, 4)."""
    pw, px, py, pz = p[:, 0], p[:, 1], p[:, 2], p[:, 3]
    qw, qx, qy, qz = q
    return np.stack(
        [
            pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
        ],
        axis=1,
    )


def _rows_to_columns(x: FloatArray) -> FloatArray:
    """(k, n) → C-contiguous (n, k); column-wise copies beat a generic strided transpose."""
    out = np.empty((x.shape[1], x.shape[0]))
    for j in range(x.shape[0]):
        out[:, j] = x[j]
    return out


def _interp_rows(idx: FloatArray, grid: FloatArray, values: FloatArray, out: FloatArray) -> None:
    """out[j] += interp(idx, grid, values[j]) for each row of a (k, m) array (in place)."""
    for j in range(values.shape[0]):
        out[j] += np.interp(idx, grid, values[j])


class SlowSum:
    """Sum of slowly varying 3-row processes (layout (3, n)), each sampled every ``m`` samples.

    Processes are added on their own grids; :meth:`render` accumulates them from the coarsest
    grid to the finest by linear interpolation, so each interpolation costs the size of the
    finer grid and the total cost is a small multiple of one full-rate interpolation.
    """

    def __init__(self, n: int, rows: int = 3) -> None:
        self.n = n
        self.rows = rows
        self.parts: dict[int, FloatArray] = {}

    def grid_size(self, m: int) -> int:
        """Number of grid points of step ``m`` covering samples 0 … n−1 (n when m = 1)."""
        return self.n if m == 1 else (self.n - 1) // m + 2

    def add(self, m: int, x: FloatArray) -> None:
        """Add a process sampled at samples 0, m, 2m … (shape (rows, grid_size(m))); the
        array is taken over (not copied)."""
        if m in self.parts:
            self.parts[m] += x
        else:
            self.parts[m] = x

    def render(self) -> FloatArray:
        """The sum at every output sample, shape (rows, n)."""
        acc: FloatArray | None = None
        acc_m = 0
        levels = sorted(self.parts, reverse=True)
        if 1 not in self.parts:
            levels.append(1)
        for m in levels:
            size = self.grid_size(m)
            x = self.parts.get(m)
            cur = np.zeros((self.rows, size)) if x is None else x
            if acc is not None:
                xs = np.arange(size, dtype=np.float64)
                if m > 1:
                    xs *= m
                _interp_rows(xs, np.arange(acc.shape[1], dtype=np.float64) * acc_m, acc, cur)
            acc, acc_m = cur, m
        assert acc is not None
        return acc


def _pow2_step(samples: float) -> int:
    """Largest power of two ≤ ``samples`` (at least 1): grid steps shared between processes."""
    return 1 if samples < 2 else 1 << math.floor(math.log2(samples))


def gauss_markov_sum(
    rng: np.random.Generator,
    n: int,
    dt: float,
    b: float,
    tau_range: tuple[float, float],
    acc: SlowSum | None = None,
) -> FloatArray | None:
    """Flicker-floor bias instability of level ``b`` (IEEE 952 B) as a sum of GM processes.

    Each process starts from its stationary distribution and is generated every
    ``≤ τ_k/20`` s. Added to ``acc`` if given (returns None), else returned as (3, n) (SI).
    """
    target = SlowSum(n) if acc is None else acc
    if b != 0.0:
        lo, hi = tau_range
        k = max(2, math.ceil(math.log10(hi / lo) * GM_PER_DECADE) + 1)
        taus = np.geomspace(lo, hi, k)
        var = b * b * math.log(taus[1] / taus[0]) / math.pi
        for tc in taus:
            m = _pow2_step(tc / 20.0 / dt)
            nc = target.grid_size(m)
            phi = math.exp(-m * dt / tc)
            w = rng.standard_normal((3, nc))
            w *= math.sqrt(var * (1.0 - phi * phi))
            x0 = rng.standard_normal(3) * math.sqrt(var)
            x, _ = signal.lfilter([1.0], [1.0, -phi], w, axis=-1, zi=(phi * x0)[:, None])
            target.add(m, x)
    return target.render() if acc is None else None


def random_walk(
    rng: np.random.Generator, n: int, dt: float, k: float, duration: float, acc: SlowSum | None = None
) -> FloatArray | None:
    """Rate random walk of density ``k`` (SI per √s), zero at t = 0, generated every
    ≤ min(1 s, duration/1000). Added to ``acc`` if given (returns None), else (3, n)."""
    target = SlowSum(n) if acc is None else acc
    if k != 0.0:
        m = _pow2_step(min(1.0, duration / 1000.0) / dt)
        nc = target.grid_size(m)
        steps = rng.standard_normal((3, nc)) * (k * math.sqrt(m * dt))
        steps[:, 0] = 0.0
        target.add(m, np.cumsum(steps, axis=1))
    return target.render() if acc is None else None


def _error_matrix(rng: np.random.Generator, sf: float, mis: float) -> FloatArray:
    """Scale-factor (diagonal) and misalignment (off-diagonal) error matrix S."""
    s = np.zeros((3, 3))
    d = rng.standard_normal(3)
    o = rng.standard_normal(6)
    s[np.diag_indices(3)] = sf * d
    s[~np.eye(3, dtype=bool)] = mis * o
    return s


def _antialias(y: FloatArray, rate: float, cutoff: float | None, order: int) -> FloatArray:
    """Butterworth low-pass along the last axis, started in steady state on the first sample."""
    if cutoff is None or cutoff >= 0.45 * rate:
        return y
    b, a = signal.butter(order, cutoff, fs=rate)
    zi = signal.lfilter_zi(b, a)[None, :] * y[:, :1]
    out, _ = signal.lfilter(b, a, y, axis=-1, zi=zi)
    return out


def _quantize(y: FloatArray, lsb: float) -> FloatArray:
    if lsb > 0.0:
        np.divide(y, lsb, out=y)
        np.round(y, out=y)
        np.multiply(y, lsb, out=y)
    return y


def _resolve_profile(model: SensorModel, profile: str | TemperatureProfile) -> TemperatureProfile:
    if isinstance(profile, TemperatureProfile):
        return profile
    tm = model.temperature
    return named_profile(
        str(profile), self_heating_c=tm.self_heating_c, ambient_c=tm.ambient_c, warmup_tau_s=tm.warmup_tau_s
    )


def die_temperature(
    model: SensorModel, profile: TemperatureProfile, t: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """``(chamber, die)`` temperatures (°C) at times ``t`` (s, uniform): first-order lag
    ``τ dT_die/dt = T_chamber − T_die`` plus self-heating (exponential after power-on for a
    warm-up profile), starting in equilibrium with the chamber."""
    tm = model.temperature
    chamber = profile.chamber(t)
    if tm.lag_s > 0 and t.size > 1:
        dt = float(t[1] - t[0])
        a = math.exp(-dt / tm.lag_s)
        die, _ = signal.lfilter([1.0 - a], [1.0, -a], chamber, zi=[a * chamber[0]])
    else:
        die = chamber.copy()
    if profile.warmup:
        die = die + tm.self_heating_c * (1.0 - np.exp(-(t - t[0]) / max(tm.warmup_tau_s, 1e-9)))
    else:
        die = die + tm.self_heating_c
    return chamber, die


def _triad(
    tri: TriadModel,
    *,
    seed: int,
    sensor: int,
    n: int,
    rate: float,
    duration: float,
    x_true: FloatArray,
    f_true: FloatArray,
    die_grid: FloatArray,
    gstep: int,
    thermal_factors: FloatArray | None,
    model: SensorModel,
    noise_seed: int | None = None,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Simulate one triad. Returns (output, total bias, thermal bias), each (n, 3); the
    thermal part is only interpolated to full rate for the gyro (a truth channel)."""
    k = tri.kind
    dt = 1.0 / rate
    st = _rng(seed, sensor, f"{k}_static")
    s_mat = _error_matrix(st, tri.scale_factor, tri.misalignment)
    g_mat = tri.g_sensitivity * st.standard_normal((3, 3)) if k == "gyro" else np.zeros((3, 3))
    const = _rng(seed, sensor, f"{k}_turn_on").standard_normal(3) * tri.turn_on_bias
    const += g_mat @ f_true
    moving = x_true.ndim == 2  # (3, n) true input on a rate table, else constant (3,)
    if not moving:
        const += s_mat @ x_true
    slow = SlowSum(n)
    th = tri.thermal
    noise_scale: FloatArray | None = None
    thermal_grid = np.zeros((3, die_grid.size))
    if th is not None:
        if thermal_factors is not None:
            th = th.scaled(thermal_factors)
        thermal_grid = th.bias(die_grid).T.copy()
        d_t = die_grid - th.t_ref_c
        extra = thermal_grid.copy()
        if th.scale_factor_tc != 0.0 and not moving:
            extra += th.scale_factor_tc * d_t[None, :] * x_true[:, None]
        slow.add(gstep, extra)
        if th.noise_tc != 0.0:
            noise_scale = np.interp(
                np.arange(n, dtype=np.float64),
                np.arange(die_grid.size) * float(gstep),
                np.maximum(1.0 + th.noise_tc * d_t, 0.1),
            )
    gm_rng = _rng(seed, sensor, f"{k}_gm", noise_seed)
    gauss_markov_sum(gm_rng, n, dt, tri.bias_instability, tri.bias_instability_tau_s, slow)
    random_walk(_rng(seed, sensor, f"{k}_rrw", noise_seed), n, dt, tri.rate_random_walk, duration, slow)
    bias = slow.render()
    bias += const[:, None]
    if moving:
        bias += s_mat @ x_true
        if th is not None and th.scale_factor_tc != 0.0:
            d_full = np.interp(np.arange(n, dtype=np.float64), np.arange(die_grid.size) * float(gstep), d_t)
            bias += th.scale_factor_tc * d_full[None, :] * x_true
    if tri.white > 0.0:
        y = _rng(seed, sensor, f"{k}_white", noise_seed).standard_normal((3, n))
        y *= tri.white * math.sqrt(rate)
        if noise_scale is not None:
            y *= noise_scale[None, :]
        y += bias
    else:  # an ideal triad (e.g. the accelerometers of the gyro-only crs05-02 preset)
        y = bias.copy()
    y += x_true if moving else x_true[:, None]
    y = _quantize(_antialias(y, rate, model.antialias_hz, model.antialias_order), tri.quantization)
    thermal = np.zeros((n, 3)) if k == "gyro" else np.zeros((0, 3))
    if th is not None and k == "gyro":
        idx = np.arange(n, dtype=np.float64)
        grid = np.arange(die_grid.size, dtype=np.float64) * gstep
        for j in range(3):
            thermal[:, j] = np.interp(idx, grid, thermal_grid[j])
    return _rows_to_columns(y), _rows_to_columns(bias), thermal


#: Peak memory per output sample (bytes) while one sensor is simulated (measured ≈ 225 B
#: static, more on a rate table), and per sample of each finished log kept in memory (≈ 232 B:
#: outputs and truth channels). Used to refuse absurd durations before allocating.
_PEAK_BYTES_PER_SAMPLE = 320
_KEPT_BYTES_PER_SAMPLE = 240


def check_size(duration: float, rate: float, sensors: int = 1) -> None:
    """Refuse (:class:`~uasnav.errors.ResourceLimitError`) a simulation of ``duration`` s at
    ``rate`` Hz for ``sensors`` sensors whose memory would exceed the limit of
    :mod:`uasnav.limits` (``UASNAV_MAX_MEMORY``). Invalid durations and rates are left to the
    checks that name them (:func:`simulate`)."""
    try:
        duration, rate = float(duration), float(rate)
    except (TypeError, ValueError):
        return
    if not (math.isfinite(duration) and duration > 0 and math.isfinite(rate) and rate > 0):
        return
    n = duration * rate
    each = _KEPT_BYTES_PER_SAMPLE * sensors + _PEAK_BYTES_PER_SAMPLE
    who = f" × {sensors} sensors" if sensors > 1 else ""
    check_memory(
        n * each,
        f"simulate: {n:.3g} samples ({duration:g} s at {rate:g} Hz){who}",
        option="the duration or the rate",
    )


def simulate_one(
    model: SensorModel,
    *,
    profile: str | TemperatureProfile = "static",
    duration: float | None = None,
    rate: float = 100.0,
    seed: int = 0,
    latitude_deg: float = 45.0,
    height_m: float = 0.0,
    euler_rad: tuple[float, float, float] = (0.0, 0.0, 0.0),
    progress: Progress = None,
    mounting: ArrayLike | None = None,
    sensor: int = 0,
    thermal_factors: FloatArray | None = None,
    table_rate_dps: float = 0.0,
    noise_seed: int | None = None,
) -> ImuLog:
    """Simulate one sensor (see :func:`uasnav.sim.simulate`); ``mounting`` is C_b^s."""
    if not (math.isfinite(rate) and rate > 0):
        raise InputError(f"rate: must be a positive number of Hz, got {rate!r}")
    if not -90.0 <= latitude_deg <= 90.0:
        raise InputError(f"latitude_deg: must be within [-90, 90], got {latitude_deg!r}")
    prof = _resolve_profile(model, profile)
    dur = prof.duration if duration is None else float(duration)
    if not (math.isfinite(dur) and dur > 0):
        raise InputError(f"duration: must be a positive number of seconds, got {duration!r}")
    check_size(dur, rate)
    n = round(dur * rate)
    if n < 2:
        raise InputError(f"duration × rate gives {n} samples; need at least 2")

    def tick(f: float) -> None:
        if progress is not None:
            progress(f)

    tick(0.0)
    t = np.arange(n, dtype=np.float64) / rate
    idx = np.arange(n, dtype=np.float64)
    m_bs = np.eye(3) if mounting is None else np.asarray(mounting, dtype=np.float64)
    if m_bs.shape != (3, 3):
        raise InputError(f"mounting: expected a 3×3 matrix, got shape {m_bs.shape}")
    lat = math.radians(latitude_deg)
    c_bn = _euler_dcm(euler_rad)
    w_b = c_bn.T @ earth.earth_rate_ned(lat)
    f_b = -(c_bn.T @ earth.gravity_ned(lat, height_m))
    w_s, f_s = m_bs @ w_b, m_bs @ f_b
    q0 = _dcm_quat(c_bn)
    if table_rate_dps != 0.0:
        # single-axis rate table turning about the local vertical (NED down) at Ω:
        # C_b^n(t) = R_z(Ω t) C_b^n(0); ω_ib^b = C_n^b(t) (ω_ie^n + Ω e_z); f^b is unchanged
        om = math.radians(table_rate_dps)
        th_t = om * t
        c, s_ = np.cos(th_t), np.sin(th_t)
        v = earth.earth_rate_ned(lat) + np.array([0.0, 0.0, om])
        # R_z(θ)^T v, then C_b^n(0)^T, then the mounting
        v_rot = np.stack([c * v[0] + s_ * v[1], -s_ * v[0] + c * v[1], np.full(n, v[2])])
        w_s_t = (m_bs @ c_bn.T) @ v_rot  # (3, n)
        half = 0.5 * th_t
        qz = np.stack([np.cos(half), np.zeros(n), np.zeros(n), np.sin(half)], axis=1)
        att = _quat_mul(qz, q0)
    else:
        w_s_t = w_s
        att = np.broadcast_to(q0, (n, 4))

    # thermal grid: slow dynamics, evaluated every ≥ 0.1 s and interpolated
    gstep = max(1, int(0.1 * rate))
    ng = n if gstep == 1 else (n - 1) // gstep + 2
    grid_idx = np.arange(ng, dtype=np.float64) * gstep
    chamber_g, die_g = die_temperature(model, prof, grid_idx / rate)
    tick(0.05)
    common = dict(seed=seed, sensor=sensor, n=n, rate=rate, duration=dur, die_grid=die_g, gstep=gstep)
    common.update(thermal_factors=thermal_factors, model=model, noise_seed=noise_seed)
    gyro, gbias, gtherm = _triad(model.gyro, x_true=w_s_t, f_true=f_s, **common)  # type: ignore[arg-type]
    tick(0.5)
    accel, abias, _ = _triad(model.accel, x_true=f_s, f_true=f_s, **common)  # type: ignore[arg-type]
    tick(0.9)
    die = np.interp(idx, grid_idx, die_g)
    tm = model.temperature
    temp = die.copy()
    if tm.noise_c > 0:
        temp += _rng(seed, sensor, "temp", noise_seed).standard_normal(n) * tm.noise_c
    if tm.resolution_c > 0:
        temp = np.round(temp / tm.resolution_c) * tm.resolution_c
    truth = {
        "rate_true": np.ascontiguousarray(w_s_t.T) if w_s_t.ndim == 2 else np.broadcast_to(w_s, (n, 3)),
        "specific_force_true": np.broadcast_to(f_s, (n, 3)),
        "gyro_bias": gbias,
        "gyro_bias_thermal": gtherm,
        "accel_bias": abias,
        "attitude": att,
        "temp_die": die,
        "temp_chamber": np.interp(idx, grid_idx, chamber_g),
    }
    meta: dict[str, Any] = {
        "source": "uasnav.sim",
        "preset": model.name,
        "seed": int(seed),
        "sensor_index": int(sensor),
        "profile": prof.name,
        "rate_hz": float(rate),
        "duration_s": float(dur),
        "latitude_deg": float(latitude_deg),
        "height_m": float(height_m),
        "euler_rad": [float(v) for v in euler_rad],
        "mounting": m_bs.tolist(),
        "antialias_hz": model.antialias_hz
        if model.antialias_hz and model.antialias_hz < 0.45 * rate
        else None,
        "temp_resolution_c": tm.resolution_c,
        "table_rate_dps": float(table_rate_dps),
    }
    if noise_seed is not None:
        meta["noise_seed"] = int(noise_seed)
    if thermal_factors is not None:
        meta["thermal_factors"] = [float(v) for v in thermal_factors]
    log = ImuLog(t=t, gyro=gyro, accel=accel, temp=temp, truth=truth, meta=meta)
    tick(1.0)
    return log


def _as_model(preset: str | SensorModel) -> SensorModel:
    return preset if isinstance(preset, SensorModel) else load_preset(preset)


def simulate(
    preset: str | SensorModel,
    *,
    profile: str | TemperatureProfile = "static",
    duration: float | None = None,
    rate: float = 100.0,
    seed: int = 0,
    latitude_deg: float = 45.0,
    height_m: float = 0.0,
    euler_rad: tuple[float, float, float] = (0.0, 0.0, 0.0),
    progress: Progress = None,
    table_rate_dps: float = 0.0,
    noise_seed: int | None = None,
) -> ImuLog:
    """Simulate a static IMU (one sensor) with every error term and its ground truth.

    Parameters
    ----------
    preset : str or SensorModel
        ``"crs05-02"``, ``"ms8010"``, ``"ax1"``, ``"lsm6dsm"``, a preset JSON path, or a model
        (e.g. ``load_preset("ax1").without("thermal")``).
    profile : {"static", "soak", "ramp", "warmup"} or TemperatureProfile
        Chamber temperature profile (see :mod:`uasnav.sim.profiles`).
    duration : float, optional
        Length (s); default the profile's natural length.
    rate : float
        Output sample rate (Hz), typically 100–1000.
    seed : int
        Seed; the output is a deterministic function of all arguments.
    latitude_deg, height_m : float
        Location (WGS-84) setting Earth rate and normal gravity.
    euler_rad : (roll, pitch, yaw)
        Attitude of the body frame w.r.t. NED (rad, 3-2-1).
    progress : callable(float), optional
        Called with the completed fraction 0 … 1.
    table_rate_dps : float
        Optional slow motion: the unit sits (at ``euler_rad``) on a single-axis rate table
        turning about the local vertical at this rate (deg/s, positive clockwise seen from
        above); the true rate, attitude and sensor outputs follow (specific force unchanged).
    noise_seed : int, optional
        Draw the noise processes (white noise, bias instability, random walks, temperature
        noise) afresh from ``(seed, noise_seed)`` while keeping every hardware property of
        ``seed`` (turn-on biases, scale factors, misalignments, thermal curve): the same unit
        recorded again, e.g. in another attitude of a multi-position test.

    Returns
    -------
    ImuLog
        Outputs (rad/s, m/s², measured die temperature °C) and ``truth`` channels
        (``rate_true``, ``specific_force_true``, ``gyro_bias``, ``gyro_bias_thermal``,
        ``accel_bias``, ``attitude``, ``temp_die``, ``temp_chamber``). ``gyro_bias`` is
        everything in the output that is neither the true rate nor white noise nor
        quantisation: turn-on + thermal + instability + random walk, plus the (constant,
        when static) scale-factor/misalignment and g-sensitivity errors of the true input.
    """
    return simulate_one(
        _as_model(preset),
        profile=profile,
        duration=duration,
        rate=rate,
        seed=seed,
        latitude_deg=latitude_deg,
        height_m=height_m,
        euler_rad=euler_rad,
        progress=progress,
        table_rate_dps=table_rate_dps,
        noise_seed=noise_seed,
    )


ARRAY_SHAPES = ("tetrahedron", "cube", "octahedron", "dodecahedron", "icosahedron", "planar")


def array_mountings(shape: str = "cube", per_face: float = 1) -> list[FloatArray]:
    """Mounting matrices C_b^s (IMU body → sensor frame) of an array.

    A Platonic solid (``"tetrahedron"``, ``"cube"``, ``"octahedron"``, ``"dodecahedron"``,
    ``"icosahedron"``): ``per_face`` triaxial sensors on each face, sensor z axis along the
    outward face normal, in the face order and orientation of
    :func:`uasnav.redundancy.configuration` (one geometry for simulation and fusion; the
    cube's faces are +x, +y, +z, −x, −y, −z). ``"planar"``: ``per_face`` sensors all aligned
    with the body (the thesis' six SensorTiles on one cradle board, §4.3.4).
    """
    from uasnav import redundancy

    if not (per_face > 0 and math.isfinite(per_face)):
        raise InputError(f"per_face: must be a finite number > 0, got {per_face!r}")
    # At most 20 faces, ~1 KiB per mounting: refuse before building 10⁹ matrices.
    check_memory(per_face * 20 * 1024.0, f"an array of {per_face:g} sensors per face", option="per_face")
    if shape == "planar":
        if per_face != int(per_face):
            raise InputError(f"per_face: a planar array needs a whole number of sensors, got {per_face}")
        return [np.eye(3) for _ in range(int(per_face))]
    if shape not in redundancy.SHAPES:
        raise InputError(f"unknown array shape {shape!r}; expected one of {', '.join(ARRAY_SHAPES)}")
    return list(redundancy.configuration(shape, per_face, triaxial=True).mountings())


def simulate_array(
    preset: str | SensorModel,
    *,
    shape: str = "cube",
    per_face: float = 1,
    mountings: ArrayLike | None = None,
    mounting_error_rad: float = 0.0,
    thermal_spread: float = 0.5,
    progress: Progress = None,
    **kwargs: Any,
) -> list[ImuLog]:
    """Simulate several sensors of one type in a rigid array, with independent errors.

    Each sensor has its own random streams, its own mounting (``log.meta["mounting"]`` =
    nominal C_b^s, outputs and ``rate_true``/``specific_force_true``/biases in the sensor's
    actual frame; ``attitude`` stays body → NED), and its own thermal curve: the preset's curve
    per axis scaled by a factor drawn uniformly in ``[1 − thermal_spread, 1 + thermal_spread]``
    with a random sign (``meta["thermal_factors"]``). Other keyword arguments as
    :func:`simulate` (``noise_seed`` re-records the same array).

    Parameters
    ----------
    shape, per_face
        Layout of :func:`array_mountings`, unless ``mountings`` is given.
    mountings : array_like, shape (s, 3, 3), optional
        Nominal C_b^s of every sensor (e.g. ``uasnav.redundancy.configuration("icosahedron",
        triaxial=True).mountings()``); ``meta["array_shape"]`` is then ``"user"``.
    mounting_error_rad : float
        σ (rad, per axis) of a random rotation of each sensor against its nominal mounting
        (a hardware property: fixed by ``seed``). The actual C_b^s is
        ``meta["mounting_true"] = exp([φ×])·C_nominal``.
    """
    model = _as_model(preset)
    if mountings is None:
        mounts = array_mountings(shape, per_face)
    else:
        m = np.asarray(mountings, dtype=np.float64)
        if m.ndim != 3 or m.shape[1:] != (3, 3) or m.shape[0] < 1:
            raise InputError(f"mountings: expected shape (s, 3, 3), got {m.shape}")
        mounts = list(m)
        shape = "user"
    if not (math.isfinite(mounting_error_rad) and mounting_error_rad >= 0):
        raise InputError(f"mounting_error_rad: must be finite and >= 0, got {mounting_error_rad!r}")
    # All logs are kept: refuse up front rather than after simulating most of the sensors.
    duration = kwargs.get("duration")
    if duration is None:
        duration = _resolve_profile(model, kwargs.get("profile", "static")).duration
    check_size(duration, kwargs.get("rate", 100.0), len(mounts))
    seed = int(kwargs.get("seed", 0))
    rng = _rng(seed, 10_000, "array")
    logs = []
    for i, m_nom in enumerate(mounts):
        factors = rng.uniform(1.0 - thermal_spread, 1.0 + thermal_spread, 3) * rng.choice([-1.0, 1.0], 3)
        phi = _rng(seed, i, "mounting").standard_normal(3) * mounting_error_rad
        m_true = Rotation.from_rotvec(phi).as_matrix() @ m_nom

        def sub(f: float, i: int = i) -> None:
            if progress is not None:
                progress((i + f) / len(mounts))

        log = simulate_one(model, mounting=m_true, sensor=i, thermal_factors=factors, progress=sub, **kwargs)
        log.meta["mounting"] = np.asarray(m_nom).tolist()
        log.meta["mounting_true"] = m_true.tolist()
        logs.append(log)
    for log in logs:
        log.meta["array_shape"] = shape
        log.meta["array_size"] = len(mounts)
    return logs


def thermal_model(
    preset: str | SensorModel, sensor: str = "gyro", factors: ArrayLike | None = None
) -> ThermalErrorTruth | None:
    """The :class:`~uasnav.sim.model.ThermalErrorTruth` of a preset's gyro (or ``"accel"``).

    None if the triad has no thermal block; ``factors`` (3,) scale each axis' curve.
    """
    model = _as_model(preset)
    tri = model.gyro if sensor == "gyro" else model.accel
    th = tri.thermal
    if th is not None and factors is not None:
        th = th.scaled(np.asarray(factors, dtype=np.float64))
    return th


def thermal_bias(
    preset: str | SensorModel, temp_c: ArrayLike, branch: str = "heating", *, factors: ArrayLike | None = None
) -> FloatArray:
    """True thermal gyro bias (n, 3) (rad/s) at die temperatures ``temp_c`` (°C).

    ``branch`` selects the hysteresis branch (``"heating"``: curve + h/2, ``"cooling"``:
    curve − h/2), matching ``truth["gyro_bias_thermal"]`` once the branch is established.
    ``factors`` are an array sensor's ``meta["thermal_factors"]``.
    """
    th = thermal_model(preset, "gyro", factors)
    t = np.atleast_1d(np.asarray(temp_c, dtype=np.float64))
    if th is None:
        return np.zeros((t.size, 3))
    return th.branch_bias(t, branch)


def thermal_bias_derivative(
    preset: str | SensorModel, temp_c: ArrayLike, branch: str = "heating", *, factors: ArrayLike | None = None
) -> FloatArray:
    """∂b/∂T (n, 3) (rad/s/°C) of :func:`thermal_bias` (equal on both branches)."""
    th = thermal_model(preset, "gyro", factors)
    t = np.atleast_1d(np.asarray(temp_c, dtype=np.float64))
    if branch not in ("heating", "cooling"):
        raise InputError(f"branch: expected 'heating' or 'cooling', got {branch!r}")
    if th is None:
        return np.zeros((t.size, 3))
    return th.derivative(t)


__all__ = [
    "ARRAY_SHAPES",
    "array_mountings",
    "check_size",
    "die_temperature",
    "gauss_markov_sum",
    "random_walk",
    "simulate",
    "simulate_array",
    "simulate_one",
    "thermal_bias",
    "thermal_bias_derivative",
    "thermal_model",
]
