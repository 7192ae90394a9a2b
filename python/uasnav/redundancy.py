"""Redundant IMUs on regular polyhedra (thesis §4.3, eqs. 38–46).

Geometry (:class:`SensorArray`, built by :func:`configuration` and :func:`from_mountings`;
:func:`kr`, :func:`table14`), weighted least-squares fusion with parity-space fault detection
and isolation (:func:`fuse`, :func:`fuse_axes`), Kalman fusion with per-axis bias states
(:func:`kalman_fuse`) and relative alignment (:func:`relative_alignment`,
:func:`relative_rotation`). All numerics run in ``nav-core`` (``uasnav._core``).

The log-file pipeline of ``uasnav redundancy fuse`` is here too: :func:`load_logs`,
:func:`array_for_logs` (the sensor array from ``--shape`` or the logs' ``mounting`` metadata)
and :func:`fuse_files` (both, then :func:`fuse`), whose :class:`FileFusion` gives the fused
:class:`~uasnav.imu.ImuLog` to write with :func:`uasnav.io.write_log`.

>>> cube = configuration("cube", 1, triaxial=True)   # the thesis' six-SensorTile cube
>>> cube.n_sensors, cube.n_axes
(6, 18)
>>> [round(float(k), 3) for k in cube.k_r()]
[0.408, 0.408, 0.408]

Frames: the *IMU frame* is the polyhedron's frame (the cube's face normals are its x, y, z
axes). A triaxial sensor's mounting ``C`` maps IMU-frame vectors into the sensor frame,
``ω_s = C·ω_imu`` (the convention of ``log.meta["mounting"]`` of ``uasnav.sim``).

Table 14 rows (``k_r`` of eq. 40 for the cube): the thesis counts *single-axis* gyros, each
along a cube face normal, spread evenly over the three IMU axes (a gyro on face −x measures
the x axis like one on +x):

====== =============== ===== ========================================= =====
config gyros per face  total arrangement                               k_r
====== =============== ===== ========================================= =====
1      0.5             3     one gyro on each of faces +x, +y, +z       1
2      1.0             6     one gyro on every face (2 per axis)        0.71
3      1.5             9     two on +x, +y, +z, one on −x, −y, −z       0.58
4      2.0             12    two on every face (4 per axis)             0.50
5      3.0             18    three on every face (6 per axis) ≡ six     0.41
                             triaxial sensors, one per face (the
                             thesis' six-SensorTile prototype)
====== =============== ===== ========================================= =====

``k_r = 1/√(Σ cos² α)`` only depends on the total number of sensor axes for the Platonic
solids (their normals satisfy ``Σ n nᵀ = (F/3)·I``), and for triaxial sensors it is
``1/√(number of sensors)`` whatever their orientation.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav import _core
from uasnav.errors import InputError
from uasnav.imu import ImuLog, require_log
from uasnav.io import read_log

SHAPES = ("tetrahedron", "cube", "octahedron", "dodecahedron", "icosahedron")
FACES = {"tetrahedron": 4, "cube": 6, "octahedron": 8, "dodecahedron": 12, "icosahedron": 20}

#: Health bit flags per sensor and sample (``FusionResult.health``).
HEALTH_NON_FINITE = 1
HEALTH_SATURATED = 2
HEALTH_STUCK = 4
HEALTH_PARITY = 8

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class SensorArray:
    """A redundant sensor array (its configuration): the rows of the design matrix ``H``.

    Built by :func:`configuration` (sensors on the faces of a polyhedron) or
    :func:`from_mountings` (triaxial sensors with given mountings). Not to be confused with
    :class:`uasnav.mission.RankedPair` (a ranked UAS/camera pair of the mission selector).

    Attributes
    ----------
    axes : ndarray, shape (n, 3)
        Unit sensitive direction of every sensor axis (IMU frame).
    sensor_of : ndarray, shape (n,)
        Index of the sensor each axis belongs to (a triaxial sensor owns three adjacent axes).
    shape : str or None
        Polyhedron name, if built from one.
    per_face : float or None
        Sensors per face, if built from a polyhedron.
    triaxial : bool
        True when every sensor is triaxial (one log per sensor can be fused).
    """

    axes: FloatArray
    sensor_of: NDArray[np.int64]
    shape: str | None = None
    per_face: float | None = None
    triaxial: bool = False

    @property
    def n_axes(self) -> int:
        """Number of sensor axes."""
        return int(self.axes.shape[0])

    @property
    def n_sensors(self) -> int:
        """Number of sensors."""
        return int(self.sensor_of[-1]) + 1

    def _args(self) -> tuple[FloatArray, list[int]]:
        return np.ascontiguousarray(self.axes), [int(s) for s in self.sensor_of]

    def k_r(self) -> FloatArray:
        """Improvement factor per IMU axis, eq. (40), shape (3,)."""
        return np.array(_core.redundancy_kr(*self._args()))

    def ls_covariance(self, sigma: ArrayLike | float = 1.0) -> FloatArray:
        """LS covariance ``(HᵀWH)⁻¹`` (3, 3) for per-axis noise σ (scalar or (n,))."""
        s = np.broadcast_to(np.asarray(sigma, dtype=np.float64), (self.n_axes,))
        return _core.redundancy_ls_covariance(*self._args(), np.ascontiguousarray(s))

    def mountings(self) -> FloatArray:
        """Mountings (s, 3, 3) IMU → sensor of a triaxial configuration."""
        if not self.triaxial:
            raise InputError("mountings: only triaxial configurations have mounting matrices")
        return self.axes.reshape(-1, 3, 3).copy()


#: Largest deviation from a rotation :func:`from_mountings` may be told to tolerate.
_MAX_MOUNTING_TOL = 0.01
#: Most sensors per face :func:`configuration` builds (Table 14 goes to 3).
_MAX_PER_FACE = 1000


def _face_counts(shape: str, per_face: float) -> list[int]:
    if shape not in FACES:
        raise InputError(f"shape: expected one of {', '.join(SHAPES)}, got {shape!r}")
    twice = per_face * 2
    if not (math.isfinite(per_face) and per_face > 0 and abs(twice - round(twice)) < 1e-9):
        raise InputError(f"per_face: expected a positive multiple of 0.5, got {per_face}")
    if per_face > _MAX_PER_FACE:
        raise InputError(f"per_face: at most {_MAX_PER_FACE} sensors per face, got {per_face:g}")
    f = FACES[shape]
    base = math.floor(per_face + 1e-9)
    # A half sensor per face: one more on the first half of the faces, which holds one face
    # of every antipodal pair (nav-core orders the faces so).
    extra = round(twice) % 2
    if extra and shape == "tetrahedron":
        raise InputError("per_face: half sensors per face need antipodal faces (not a tetrahedron)")
    return [base + (extra if i < f // 2 else 0) for i in range(f)]


def configuration(shape: str = "cube", per_face: float = 1, *, triaxial: bool = False) -> SensorArray:
    """Sensors on every face of a regular polyhedron.

    Parameters
    ----------
    shape : {"tetrahedron", "cube", "octahedron", "dodecahedron", "icosahedron"}
    per_face : float
        Sensors per face; a multiple of 0.5 (0.5 = one sensor on half of the faces, one face
        of each antipodal pair; 1.5 = two on that half, one on the others), as in Table 14.
    triaxial : bool
        Triaxial sensors (z along the outward normal) instead of single-axis gyros along the
        normal.

    Raises
    ------
    InputError
        Unknown shape, bad ``per_face``, or a result that cannot observe three axes.
    """
    counts = _face_counts(shape, float(per_face))
    axes, sensor_of = _core.redundancy_face_config(shape, counts, bool(triaxial))
    return SensorArray(axes, sensor_of, shape=shape, per_face=float(per_face), triaxial=bool(triaxial))


def from_mountings(mountings: ArrayLike, tol: float = 1e-6) -> SensorArray:
    """Triaxial sensors with user mountings (s, 3, 3) (IMU → sensor), validated as rotations.

    Raises
    ------
    InputError
        A mounting that is not a proper rotation within ``tol`` (names its index), or too
        few sensors to observe three axes.
    """
    # NaN compares false with everything: a NaN (or negative, or huge) tol would accept any matrix.
    if isinstance(tol, bool) or not (0.0 < float(tol) <= _MAX_MOUNTING_TOL):
        raise InputError(f"tol: expected a number in (0, {_MAX_MOUNTING_TOL:g}], got {tol}")
    m = np.asarray(mountings, dtype=np.float64)
    if m.ndim != 3 or m.shape[1:] != (3, 3):
        raise InputError(f"mountings: expected shape (s, 3, 3), got {m.shape}")
    axes, sensor_of = _core.redundancy_mountings_config(np.ascontiguousarray(m), float(tol))
    return SensorArray(axes, sensor_of, triaxial=True)


def face_normals(shape: str) -> FloatArray:
    """Outward unit face normals (F, 3) of a Platonic solid, in nav-core's face order."""
    if shape not in FACES:
        raise InputError(f"shape: expected one of {', '.join(SHAPES)}, got {shape!r}")
    return _core.redundancy_face_normals(shape)


def kr(shape: str = "cube", per_face: float = 1, *, triaxial: bool = False) -> FloatArray:
    """``k_r`` per IMU axis (eq. 40) of :func:`configuration` ``(shape, per_face, triaxial)``."""
    return configuration(shape, per_face, triaxial=triaxial).k_r()


def chi2_threshold(dof: int, p_fa: float) -> float:
    """FDI threshold: the χ² upper quantile with ``P(χ²_dof > T) = p_fa`` (nav-core)."""
    return float(_core.redundancy_chi2_threshold(int(dof), float(p_fa)))


def white_noise_sigma(z: ArrayLike) -> FloatArray:
    """Per-column white-noise σ per sample of (m, n) samples: the Allan deviation at τ₀.

    For white noise ``σ_A(τ₀)² = ½·E[(z_{k+1} − z_k)²]`` equals the per-sample variance, and
    slow bias motion barely contributes, so this weights sensors by their Allan white noise
    without fitting a full curve. Non-finite samples are skipped.
    """
    a = np.asarray(z, dtype=np.float64)
    d = np.diff(a, axis=0)
    out = np.sqrt(0.5 * np.nanmean(np.where(np.isfinite(d), d, np.nan) ** 2, axis=0))
    if a.shape[0] < 3 or not np.all(np.isfinite(out)) or np.any(out <= 0):
        raise InputError("sigma: cannot estimate white noise (need ≥ 3 finite, non-constant samples)")
    return out


def parity_residuals(config: SensorArray, z: ArrayLike, sigma: ArrayLike) -> FloatArray:
    """Least-squares residuals ``z − H·x̂`` (m, n) with weights ``1/σ²``; NaN rows where a
    sample is non-finite. Their mean over a window is the observable (parity-space) part of
    the axis biases; their spread measures how well the sensors agree."""
    a = np.ascontiguousarray(np.asarray(z, dtype=np.float64))
    if a.ndim != 2 or a.shape[1] != config.n_axes:
        raise InputError(f"z: expected shape (m, {config.n_axes}), got {a.shape}")
    s = np.ascontiguousarray(np.broadcast_to(np.asarray(sigma, dtype=np.float64), (config.n_axes,)))
    return _core.redundancy_parity_residuals(*config._args(), a, s)


def robust_sigma(config: SensorArray, z: ArrayLike, sigma: ArrayLike) -> FloatArray:
    """Per-axis σ (n,) implied by the robust spread of the parity residuals of ``z``.

    ``σ_i = 1.4826·MAD(r_i)/√(1 − h_ii)`` with ``h_ii = h_iᵀ(HᵀWH)⁻¹h_i/σ_i²`` the leverage of
    axis i (weights from ``sigma``). Use it as the FDI noise when the sensors disagree by more
    than their white noise in normal operation (vibration, flexible mounts), so that the χ²
    test flags gross faults rather than the vehicle's normal environment.
    """
    sg = np.broadcast_to(np.asarray(sigma, dtype=np.float64), (config.n_axes,))
    r = parity_residuals(config, z, sg)
    r = r[np.all(np.isfinite(r), axis=1)]
    if r.shape[0] < 10:
        raise InputError("z: fewer than 10 complete samples for a robust σ")
    mad = 1.4826 * np.median(np.abs(r - np.median(r, axis=0)), axis=0)
    cov = config.ls_covariance(sg)
    lev = np.einsum("ij,jk,ik->i", config.axes, cov, config.axes) / sg**2
    out = mad / np.sqrt(np.clip(1.0 - lev, 1e-12, None))
    if np.any(out <= 0):
        raise InputError("z: an axis has zero residual spread (no redundancy on it?)")
    return out


@dataclass(frozen=True)
class AxisFusion:
    """Fusion of one quantity (rate or specific force) over all sensor axes.

    Attributes
    ----------
    value : ndarray, shape (m, 3)
        Fused IMU-frame vector (rad/s or m/s²); NaN where ``valid`` is False.
    variance : ndarray, shape (m, 3)
        Diagonal of ``(HᵀWH)⁻¹`` (unit²).
    chi2 : ndarray, shape (m,)
        Parity statistic of the axes used.
    valid : ndarray of bool, shape (m,)
        False where too few healthy axes remain or a fault could not be isolated.
    alarm : ndarray of bool, shape (m,)
        The parity test fired (before isolation).
    health : ndarray of uint8, shape (m, n_sensors)
        Bit flags per sensor: 1 non-finite, 2 saturated, 4 stuck, 8 isolated by parity.
    sigma : ndarray, shape (n,)
        White-noise σ per axis used as weights.
    bias : ndarray, shape (n,)
        Per-axis bias corrections subtracted before fusion.
    """

    value: FloatArray
    variance: FloatArray
    chi2: FloatArray
    valid: NDArray[np.bool_]
    alarm: NDArray[np.bool_]
    health: NDArray[np.uint8]
    sigma: FloatArray
    bias: FloatArray


def fuse_axes(
    config: SensorArray,
    z: ArrayLike,
    *,
    sigma: ArrayLike | None = None,
    bias: ArrayLike | None = None,
    fdi: bool = True,
    p_fa: float = 1e-6,
    saturation: float | None = None,
    stuck_samples: int = 0,
    max_isolations: int = 2,
    parity_bias_samples: int = 0,
) -> AxisFusion:
    """Weighted least-squares fusion of per-axis samples, with optional FDI.

    Parameters
    ----------
    config : SensorArray
    z : array_like, shape (m, n)
        One column per sensor axis (``config.axes`` order); NaN marks a dropout.
    sigma : array_like, shape (n,), optional
        Noise σ per sample per axis (weights ``1/σ²`` and the χ² scale); default
        :func:`white_noise_sigma` of ``z`` (the Allan deviation at τ₀), or with ``fdi`` and a
        learning window, :func:`robust_sigma` over that window.
    bias : array_like, shape (n,), optional
        Per-axis bias corrections (subtracted).
    fdi : bool
        Parity-space fault detection, isolation and re-fusion; without it only non-finite
        samples are excluded (always, with a health flag).
    p_fa : float
        False-alarm probability per sample of the χ² test.
    saturation : float, optional
        Absolute output flagged as saturated.
    stuck_samples : int
        Identical consecutive samples that flag a stuck output (0 = off).
    max_isolations : int
        Sensors the parity test may isolate per sample.
    parity_bias_samples : int
        Learn the parity-space part of the axis biases from the mean LS residual of the first
        samples (redundancy's partial self-calibration) and add it to ``bias``. It does not
        change the fused value, only the parity test's consistency.
    """
    a = np.ascontiguousarray(np.asarray(z, dtype=np.float64))
    n = config.n_axes
    if a.ndim != 2 or a.shape[1] != n:
        raise InputError(f"z: expected shape (m, {n}) (one column per sensor axis), got {a.shape}")
    if sigma is None:
        sg = white_noise_sigma(a)
        if fdi and parity_bias_samples >= 10:
            # The χ² test needs the per-sample σ, which the Allan deviation at τ₀
            # underestimates when the sensor low-pass filters its output (correlated samples).
            sg = robust_sigma(config, a[:parity_bias_samples], sg)
    else:
        sg = np.asarray(sigma, dtype=np.float64)
    b = np.zeros(n) if bias is None else np.array(bias, dtype=np.float64)
    if sg.shape != (n,) or b.shape != (n,):
        raise InputError(f"sigma, bias: expected shape ({n},), got {sg.shape}, {b.shape}")
    if parity_bias_samples > 0:
        r = _core.redundancy_parity_residuals(*config._args(), a[:parity_bias_samples] - b, sg)
        ok = np.all(np.isfinite(r), axis=1)
        if ok.sum() < 2:
            raise InputError("parity_bias_samples: fewer than 2 complete samples to learn from")
        b = b + r[ok].mean(axis=0)
    sat = math.inf if saturation is None else float(saturation)
    value, var, chi2, valid, alarm, health = _core.redundancy_fuse(
        *config._args(),
        a,
        np.ascontiguousarray(sg),
        np.ascontiguousarray(b),
        bool(fdi),
        float(p_fa),
        sat,
        int(stuck_samples),
        int(max_isolations),
    )
    return AxisFusion(value, var, chi2, valid, alarm, health, sg, b)


def _check_logs(logs: Sequence[ImuLog]) -> None:
    """Every element an :class:`ImuLog` (else an AttributeError deep inside, not a message)."""
    if isinstance(logs, (str, bytes)) or not isinstance(logs, Sequence):
        raise InputError(f"logs: expected a sequence of ImuLog, got {type(logs).__name__}")
    for i, lg in enumerate(logs):
        if not isinstance(lg, ImuLog):
            raise InputError(f"logs[{i}]: expected an ImuLog, got {type(lg).__name__}")


def stack_logs(
    logs: Sequence[ImuLog], *, time_tol_s: float = 1e-6
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Time, gyro and accelerometer columns (m, 3·s) of s triaxial sensor logs.

    Raises
    ------
    InputError
        Fewer than two logs, different lengths, or sample times differing by more than
        ``time_tol_s`` (names the log and row).
    """
    if not (math.isfinite(time_tol_s) and time_tol_s >= 0):  # NaN would pass every comparison
        raise InputError(f"time_tol_s: expected a finite number of seconds >= 0, got {time_tol_s}")
    _check_logs(logs)
    if len(logs) < 2:
        raise InputError(f"logs: need at least 2 sensor logs, got {len(logs)}")
    t0 = logs[0].t
    for i, lg in enumerate(logs[1:], start=1):
        if lg.n != logs[0].n:
            raise InputError(f"logs[{i}]: {lg.n} samples, logs[0] has {logs[0].n}: mismatched sample times")
        d = np.abs(lg.t - t0)
        k = int(np.argmax(d))
        if d[k] > time_tol_s:
            raise InputError(
                f"logs[{i}]: sample time differs from logs[0] by {d[k]:.3g} s at row {k} "
                f"(tolerance {time_tol_s:g} s): mismatched sample times between sensors"
            )
    gyro = np.concatenate([lg.gyro for lg in logs], axis=1)
    accel = np.concatenate([lg.accel for lg in logs], axis=1)
    return t0.copy(), np.ascontiguousarray(gyro), np.ascontiguousarray(accel)


@dataclass(frozen=True)
class FusionResult:
    """Fused IMU from several triaxial sensor logs.

    Attributes
    ----------
    t : ndarray, shape (m,)
        Sample times (s).
    gyro, accel : AxisFusion
        Fusion of the angular rate (rad/s) and of the specific force (m/s²).
    config : SensorArray
    """

    t: FloatArray
    gyro: AxisFusion
    accel: AxisFusion
    config: SensorArray
    meta: dict[str, Any] = field(default_factory=dict)

    @property
    def valid(self) -> NDArray[np.bool_]:
        """Samples where both fusions are valid."""
        return self.gyro.valid & self.accel.valid

    def to_log(self) -> ImuLog:
        """The valid samples as an :class:`~uasnav.imu.ImuLog` (invalid rows are dropped,
        their count kept in ``meta["dropped_samples"]``)."""
        v = self.valid
        if v.sum() < 2:
            raise InputError("fused log: fewer than 2 valid samples (every sample failed FDI)")
        meta = {**self.meta, "dropped_samples": int((~v).sum())}
        return ImuLog(t=self.t[v], gyro=self.gyro.value[v], accel=self.accel.value[v], meta=meta)


def fuse(
    logs: Sequence[ImuLog],
    config: SensorArray | None = None,
    *,
    fdi: bool = True,
    p_fa: float = 1e-6,
    gyro_sigma: ArrayLike | None = None,
    accel_sigma: ArrayLike | None = None,
    gyro_saturation: float | None = None,
    accel_saturation: float | None = None,
    stuck_samples: int = 0,
    parity_bias_s: float = 0.0,
    time_tol_s: float = 1e-6,
) -> FusionResult:
    """Fuse triaxial sensor logs (one per sensor, same sample times) into one IMU.

    Parameters
    ----------
    logs : sequence of ImuLog
        Sensor ``i``'s log, in its own sensor frame.
    config : SensorArray, optional
        Triaxial configuration with one sensor per log; default: the logs' ``meta["mounting"]``
        (3×3, IMU → sensor) when every log has one, else an error.
    fdi, p_fa, stuck_samples
        See :func:`fuse_axes`.
    gyro_sigma, accel_sigma : array_like, shape (3·s,), optional
        White-noise σ per axis; default from the data (:func:`white_noise_sigma`).
    gyro_saturation, accel_saturation : float, optional
        Saturation limits (rad/s, m/s²).
    parity_bias_s : float
        Seconds at the start used to learn the parity-space biases (0 = off).
    """
    _check_logs(logs)
    if config is None:
        if not logs or any("mounting" not in lg.meta for lg in logs):
            raise InputError("config: not given and not every log has meta['mounting']")
        config = from_mountings(np.array([np.asarray(lg.meta["mounting"], dtype=float) for lg in logs]))
    if not config.triaxial or config.n_sensors != len(logs):
        raise InputError(
            f"config: needs one triaxial sensor per log ({len(logs)} logs, "
            f"{config.n_sensors} sensors, triaxial={config.triaxial})"
        )
    if not (math.isfinite(parity_bias_s) and parity_bias_s >= 0):
        raise InputError(f"parity_bias_s: expected a finite number of seconds >= 0, got {parity_bias_s}")
    t, g, a = stack_logs(logs, time_tol_s=time_tol_s)
    n0 = 0
    if parity_bias_s > 0:
        n0 = int(np.searchsorted(t, t[0] + parity_bias_s))
    common: dict[str, Any] = {
        "fdi": fdi,
        "p_fa": p_fa,
        "stuck_samples": stuck_samples,
        "parity_bias_samples": n0,
    }
    gf = fuse_axes(config, g, sigma=gyro_sigma, saturation=gyro_saturation, **common)
    af = fuse_axes(config, a, sigma=accel_sigma, saturation=accel_saturation, **common)
    return FusionResult(t=t, gyro=gf, accel=af, config=config, meta={"fused_sensors": len(logs), "fdi": fdi})


@dataclass(frozen=True)
class KalmanResult:
    """Kalman fusion with per-axis bias states.

    Attributes
    ----------
    rate : ndarray, shape (m, 3)
        Estimated IMU-frame value (rad/s or m/s²).
    rate_sigma : ndarray, shape (m, 3)
        Its standard deviation.
    bias : ndarray, shape (m, n)
        Estimated bias of each sensor axis.
    bias_sigma : ndarray, shape (m, n)
        Standard deviation of each bias estimate.
    """

    rate: FloatArray
    rate_sigma: FloatArray
    bias: FloatArray
    bias_sigma: FloatArray


def kalman_fuse(
    config: SensorArray,
    z: ArrayLike,
    dt: float,
    *,
    sigma: ArrayLike | None = None,
    rate_psd: float = 1.0,
    bias_psd: float = 0.0,
    bias_sigma0: float = math.radians(3.0),
    rate_sigma0: float = 1.0,
    zero_rate: ArrayLike | None = None,
    zero_rate_sigma: float = 1e-4,
) -> KalmanResult:
    """Kalman fusion of (m, n) axis samples with one random-walk bias state per axis.

    Only the parity-space part of the biases is observable from redundancy alone; mark
    static samples in ``zero_rate`` (a zero-rate update, σ ``zero_rate_sigma``) to observe
    them all. Defaults suit gyros (rad/s): ``bias_sigma0`` is the lsm6dsm ±3 dps turn-on bias.

    Parameters
    ----------
    dt : float
        Sample period (s).
    rate_psd, bias_psd : float
        Random-walk spectral densities of the true rate and of each bias (unit²/s).
    """
    a = np.ascontiguousarray(np.asarray(z, dtype=np.float64))
    if a.ndim != 2 or a.shape[1] != config.n_axes:
        raise InputError(f"z: expected shape (m, {config.n_axes}), got {a.shape}")
    if not (math.isfinite(dt) and dt > 0):
        raise InputError(f"dt: must be finite and > 0, got {dt}")
    sg = white_noise_sigma(a) if sigma is None else np.asarray(sigma, dtype=np.float64)
    zr = None if zero_rate is None else [bool(v) for v in np.asarray(zero_rate)]
    r, rs, b, bs = _core.redundancy_kalman(
        *config._args(),
        a,
        np.ascontiguousarray(sg),
        float(dt),
        float(rate_psd),
        float(bias_psd),
        float(bias_sigma0),
        float(rate_sigma0),
        zr,
        float(zero_rate_sigma),
    )
    return KalmanResult(r, rs, b, bs)


def level(specific_force: ArrayLike) -> FloatArray:
    """Roll and pitch (k, 2) rad of static sensors from mean specific forces (k, 3) m/s²."""
    f = np.atleast_2d(np.asarray(specific_force, dtype=np.float64))
    return _core.redundancy_level(np.ascontiguousarray(f))


def relative_rotation(c_bi_n: ArrayLike, c_br_n: ArrayLike) -> FloatArray:
    """Eq. (45): ``C_br^bi = (C_bi^n)ᵀ · C_br^n`` (reference → sensor i), each (3, 3)."""
    return _core.redundancy_relative_rotation(
        np.ascontiguousarray(np.asarray(c_bi_n, dtype=np.float64)),
        np.ascontiguousarray(np.asarray(c_br_n, dtype=np.float64)),
    )


@dataclass(frozen=True)
class AlignmentResult:
    """Relative alignment of triaxial sensors to a reference sensor.

    Attributes
    ----------
    relative : ndarray, shape (s, 3, 3)
        ``C_br^bi``: reference sensor frame → sensor i frame (identity for the reference).
    misalignment : ndarray, shape (s, 3)
        Small-angle rotation vector (rad) of ``relative[i]`` against the nominal relative
        rotation (zero if no nominal configuration was given).
    config : SensorArray or None
        Compensated configuration (mountings ``relative[i] · C_ref``) when a nominal
        configuration was given.
    """

    relative: FloatArray
    misalignment: FloatArray
    config: SensorArray | None


def relative_alignment(
    vectors: ArrayLike,
    *,
    reference: int = 0,
    nominal: SensorArray | None = None,
    differences: bool = True,
) -> AlignmentResult:
    """Relative rotations of sensors from vectors they measured together (Wahba, SVD).

    Parameters
    ----------
    vectors : array_like, shape (s, k, 3)
        For each sensor, k ≥ 2 non-parallel vectors in its own frame measured at the same
        instants by all sensors: e.g. the mean specific force in k static attitudes (levelling
        of every attitude), or mean rates during distinct rotations.
    reference : int
        Index of the reference sensor (face 1 in the thesis' Figure 49).
    nominal : SensorArray, optional
        Nominal triaxial configuration; returns misalignments against it and the compensated
        configuration whose mountings are ``C_br^bi · C_ref`` (the reference mounting is taken
        as nominal).
    differences : bool
        Align the differences ``v_k − v_0`` instead of the vectors (needs k ≥ 3): a constant
        sensor bias (accelerometer turn-on bias, tens of mg on consumer MEMS, i.e. degrees of
        tilt) cancels, so the sensors need no prior bias calibration.

    Notes
    -----
    Levelling alone gives each sensor's roll and pitch, so eq. (45) with levelled ``C_b^n``
    (:func:`level`, :func:`relative_rotation`) leaves the relative heading unobserved; two or
    more attitudes make the full rotation observable.
    """
    v = np.asarray(vectors, dtype=np.float64)
    if v.ndim != 3 or v.shape[2] != 3 or v.shape[1] < 2:
        raise InputError(f"vectors: expected shape (s, k ≥ 2, 3), got {v.shape}")
    if differences:
        if v.shape[1] < 3:
            raise InputError("vectors: differences need k ≥ 3 attitudes (use differences=False)")
        v = v[:, 1:, :] - v[:, :1, :]
    s = v.shape[0]
    if not 0 <= reference < s:
        raise InputError(f"reference: must index one of the {s} sensors, got {reference}")
    w = np.ones(v.shape[1])
    rel = np.empty((s, 3, 3))
    for i in range(s):
        rel[i] = _core.redundancy_wahba(np.ascontiguousarray(v[reference]), np.ascontiguousarray(v[i]), w)
    mis = np.zeros((s, 3))
    comp = None
    if nominal is not None:
        m = nominal.mountings()
        if m.shape[0] != s:
            raise InputError(f"nominal: {m.shape[0]} sensors, vectors has {s}")
        for i in range(s):
            e = rel[i] @ (m[i] @ m[reference].T).T
            mis[i] = 0.5 * np.array([e[2, 1] - e[1, 2], e[0, 2] - e[2, 0], e[1, 0] - e[0, 1]])
        comp = from_mountings(rel @ m[reference])
    return AlignmentResult(rel, mis, comp)


# --- log-file pipeline (``uasnav redundancy fuse``) ---------------------------------------------


def load_logs(paths: Sequence[str | os.PathLike[str]]) -> list[ImuLog]:
    """Read one triaxial sensor log per path (:func:`uasnav.io.read_log`: format by extension)."""
    return [read_log(p) for p in paths]


def _mounting(value: Any, where: str) -> NDArray[np.float64]:
    """A log's ``mounting`` (a 3×3 matrix, or its JSON text) as a finite 3×3 array; anything
    else is an :class:`InputError` naming the log."""
    try:
        m = json.loads(value) if isinstance(value, str) else value
        a = np.asarray(m, dtype=float)
    except (ValueError, TypeError, RecursionError):
        text = value if isinstance(value, str) else type(value).__name__
        raise InputError(f"{where}: '# mounting:' is not a 3×3 JSON matrix: {text[:80]!r}") from None
    if a.shape != (3, 3) or not np.all(np.isfinite(a)):
        what = f"shape {a.shape}" if a.shape != (3, 3) else "non-finite entries"
        raise InputError(f"{where}: '# mounting:' must be a finite 3×3 matrix, got {what}")
    return a


def array_for_logs(shape: str, logs: Sequence[ImuLog], *, names: Sequence[str] | None = None) -> SensorArray:
    """The triaxial sensor array that carries ``logs`` (one log per sensor, in order).

    Parameters
    ----------
    shape : str
        A polyhedron of :data:`SHAPES` (the logs in its face order, filling its faces in whole
        or half multiples: :func:`configuration` with ``per_face = len(logs)/F``),
        ``"aligned"`` (every sensor in the IMU frame, e.g. an autopilot's IMUs) or ``"meta"``
        (each log's ``meta["mounting"]``: a 3×3 IMU → sensor matrix, or its JSON text as read
        from a ``# mounting:`` comment).
    logs : sequence of ImuLog
    names : sequence of str, optional
        Names of the logs (e.g. file paths) for error messages; default ``logs[i]``.

    Raises
    ------
    InputError
        Unknown shape, a log without ``mounting`` (``"meta"``), a number of logs that does not
        fill the polyhedron's faces, or mountings that are not rotations.

    Examples
    --------
    >>> import numpy as np
    >>> from uasnav.imu import ImuLog
    >>> logs = [ImuLog(t=[0.0, 0.01], gyro=np.zeros((2, 3)), accel=np.zeros((2, 3)))] * 12
    >>> array_for_logs("cube", logs).per_face
    2.0
    >>> array_for_logs("aligned", logs[:3]).n_axes
    9
    """
    logs = [require_log(lg, f"logs[{i}]") for i, lg in enumerate(logs)]
    n = len(logs)
    labels = list(names) if names is not None else [f"logs[{i}]" for i in range(n)]
    if shape == "aligned":
        return from_mountings(np.repeat(np.eye(3)[None], n, axis=0))
    if shape == "meta":
        mounts = []
        for p, lg in zip(labels, logs, strict=True):
            if "mounting" not in lg.meta:
                raise InputError(f"{p}: no '# mounting:' comment (needed by --shape meta)")
            mounts.append(_mounting(lg.meta["mounting"], p))
        return from_mountings(np.asarray(mounts, dtype=float))
    if shape not in FACES:
        raise InputError(f"shape: expected one of {', '.join(SHAPES)}, aligned, meta; got {shape!r}")
    per_face = n / FACES[shape]
    if abs(per_face * 2 - round(per_face * 2)) > 1e-9:
        raise InputError(
            f"logs: {n} triaxial sensors do not fill the {FACES[shape]} faces of a {shape} "
            "in whole or half multiples"
        )
    return configuration(shape, per_face, triaxial=True)


@dataclass(frozen=True)
class FileFusion:
    """Sensor log files fused into one IMU (:func:`fuse_files`).

    Attributes
    ----------
    paths : tuple of str
        The sensor logs, in sensor order.
    shape : str
        How the array was configured (see :func:`array_for_logs`).
    result : FusionResult
        The fusion; ``result.config`` is the sensor array.
    """

    paths: tuple[str, ...]
    shape: str
    result: FusionResult

    @property
    def health(self) -> NDArray[np.uint8]:
        """Per-sensor bit flags (m, s) of both fusions (gyro | accel)."""
        return self.result.gyro.health | self.result.accel.health

    def fused_log(self) -> ImuLog:
        """The valid fused samples (IMU frame) with the metadata ``fused_from`` (the paths),
        ``shape``, ``fdi`` and ``dropped_samples`` (``# key: value`` lines in CSV v1).

        Raises
        ------
        InputError
            Fewer than two valid samples.
        """
        res = self.result
        v = res.valid
        if v.sum() < 2:
            raise InputError("fused log: fewer than 2 valid samples (every sample failed FDI)")
        meta = {
            "fused_from": " ".join(self.paths),
            "shape": self.shape,
            "fdi": bool(res.meta.get("fdi", False)),
            "dropped_samples": int((~v).sum()),
        }
        return ImuLog(t=res.t[v], gyro=res.gyro.value[v], accel=res.accel.value[v], meta=meta)

    def extra_columns(self) -> dict[str, FloatArray]:
        """Columns beside the fused log, valid samples only: ``chi2_gyro``, ``chi2_accel``
        (parity statistics) and ``health_<i>`` (sensor i's bit flags :data:`HEALTH_NON_FINITE`
        …, as floats)."""
        res = self.result
        v = res.valid
        cols = {"chi2_gyro": res.gyro.chi2[v], "chi2_accel": res.accel.chi2[v]}
        health = self.health
        for i in range(res.config.n_sensors):
            cols[f"health_{i}"] = health[v, i].astype(np.float64)
        return cols

    def summary(self) -> dict[str, Any]:
        """Counts (samples, written, dropped, parity alarms, flagged samples per sensor), k_r
        and the white-noise σ per axis (rad/s, m/s²) used as weights."""
        res = self.result
        v = res.valid
        health = self.health
        return {
            "n_samples": int(res.t.size),
            "written": int(v.sum()),
            "dropped": int((~v).sum()),
            "alarms_gyro": int(res.gyro.alarm.sum()),
            "alarms_accel": int(res.accel.alarm.sum()),
            "flagged_samples_per_sensor": {
                i: int(np.count_nonzero(health[:, i])) for i in range(res.config.n_sensors)
            },
            "k_r": res.config.k_r(),
            "gyro_sigma_rad_s": res.gyro.sigma,
            "accel_sigma_m_s2": res.accel.sigma,
        }


def fuse_files(
    paths: Sequence[str | os.PathLike[str]],
    shape: str = "cube",
    *,
    fdi: bool = False,
    p_fa: float = 1e-6,
    learn_bias_s: float = 10.0,
    stuck_samples: int = 20,
    time_tol_s: float = 1e-6,
) -> FileFusion:
    """Read triaxial sensor logs, configure their array and fuse them (``uasnav redundancy fuse``).

    Parameters
    ----------
    paths : sequence of path
        One log per sensor, same sample times (:func:`load_logs`).
    shape : str
        See :func:`array_for_logs`.
    fdi, p_fa : bool, float
        Parity-space FDI and its false-alarm probability per sample (:func:`fuse_axes`).
    learn_bias_s : float
        Seconds at the start used to learn the parity-space biases (with ``fdi`` only).
    stuck_samples : int
        Repeated samples flagging a stuck output (with ``fdi`` only; 0 = off).
    time_tol_s : float
        Tolerance on the sensors' sample times (s).
    """
    if not (math.isfinite(learn_bias_s) and learn_bias_s >= 0):
        # a negative window silently meant "no learning" (and most samples dropped by the test)
        raise InputError(f"learn_bias_s: expected a finite number of seconds >= 0, got {learn_bias_s}")
    if not (isinstance(stuck_samples, int) and stuck_samples >= 0):
        raise InputError(f"stuck_samples: expected an int >= 0 (0 = off), got {stuck_samples}")
    names = tuple(str(p) for p in paths)
    logs = load_logs(paths)
    cfg = array_for_logs(shape, logs, names=names)
    res = fuse(
        logs,
        cfg,
        fdi=fdi,
        p_fa=p_fa,
        stuck_samples=stuck_samples if fdi else 0,
        parity_bias_s=learn_bias_s if fdi else 0.0,
        time_tol_s=time_tol_s,
    )
    return FileFusion(paths=names, shape=shape, result=res)


__all__ = [
    "FACES",
    "HEALTH_NON_FINITE",
    "HEALTH_PARITY",
    "HEALTH_SATURATED",
    "HEALTH_STUCK",
    "SHAPES",
    "AlignmentResult",
    "AxisFusion",
    "FileFusion",
    "FusionResult",
    "KalmanResult",
    "SensorArray",
    "array_for_logs",
    "chi2_threshold",
    "configuration",
    "face_normals",
    "from_mountings",
    "fuse",
    "fuse_axes",
    "fuse_files",
    "kalman_fuse",
    "kr",
    "level",
    "load_logs",
    "parity_residuals",
    "relative_alignment",
    "relative_rotation",
    "robust_sigma",
    "stack_logs",
    "white_noise_sigma",
]
