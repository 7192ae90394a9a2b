"""Real data: fusion of the three IMUs of an ArduPilot DataFlash log, compared with each IMU and
with ArduPilot's own pre-arm consistency gates.

ArduPilot (``AP_InertialSensor::gyros_consistent`` / ``accels_consistent``) calls its IMUs
consistent when every pair of gyro vectors differs by at most 5 deg/s and every pair of
accelerometer vectors by at most 0.75 m/s². The ``IMU``, ``IMU2`` and ``IMU3`` messages are
already rotated into the vehicle body frame, so the three sensors share one mounting
(identity) and fusion is a weighted average whose weights come from each IMU's white noise in
a static window.

The log is read by :func:`uasnav.io.open_log` (its ``imus`` view; times in s). The report runs on simulated
data only; this experiment is asserted by ``tests/test_redundancy.py::test_ardupilot_three_imus``
and printed by ``python benches/bench_python.py redundancy_ardupilot``.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from uasnav import redundancy as R
from uasnav.errors import DataFormatError, InputError
from uasnav.imu import ImuLog, require_log
from uasnav.io import open_log

FloatArray = NDArray[np.float64]

#: ArduPilot's gyro consistency gate (rad/s): 5 deg/s between any two IMUs.
GYRO_GATE_RAD_S = np.radians(5.0)
#: ArduPilot's accelerometer consistency gate (m/s²) between any two IMUs.
ACCEL_GATE_M_S2 = 0.75
#: The log of the shared reference data, relative to the data folder.
SHARED_LOG = Path("logs") / "ardupilot_log171.bin"


@dataclass(frozen=True)
class ArduPilotResult:
    """Result of :func:`analyse_log` (noise σ per sample per axis, in a static window).

    Attributes
    ----------
    n_samples : int
        Samples common to every IMU.
    rate_hz : float
        Sample rate (Hz).
    static_window_s : tuple of float
        Start and end (s, log time) of the window used for noise and weights.
    single_noise_gyro, single_noise_accel : ndarray, shape (n_imu, 3)
        White-noise σ of each IMU (rad/s, m/s²).
    fused_noise_gyro, fused_noise_accel : ndarray, shape (3,)
        White-noise σ of the fused IMU (rad/s, m/s²).
    predicted_noise_gyro, predicted_noise_accel : ndarray, shape (3,)
        σ predicted by the LS covariance from the single-IMU noise (rad/s, m/s²).
    average_noise_gyro, average_noise_accel : ndarray, shape (3,)
        White-noise σ of the plain (unweighted) average of the IMUs, for comparison.
    static_gates_ok : bool
        Every sample of the static window passes both gates.
    gyro_gate_ok_fraction, accel_gate_ok_fraction : float
        Fraction of samples passing ArduPilot's consistency gates.
    max_gyro_diff_rad_s, max_accel_diff_m_s2 : float
        Largest pairwise vector difference (rad/s, m/s²).
    fdi_alarm_fraction : float
        Fraction of samples on which the parity test (p_fa = 1e-6, σ from the static window)
        fired: vibration the IMUs see differently is not white noise.
    robust_fdi_alarm_fraction : float
        The same with σ from the robust spread of the whole log's parity residuals
        (:func:`uasnav.redundancy.robust_sigma`).
    robust_alarm_gate_overlap : float
        Fraction of gyro-gate failures on which the robust parity test also fired.
    fused : FusionResult
        The fusion of the whole log.
    """

    n_samples: int
    rate_hz: float
    static_window_s: tuple[float, float]
    single_noise_gyro: FloatArray
    single_noise_accel: FloatArray
    fused_noise_gyro: FloatArray
    fused_noise_accel: FloatArray
    predicted_noise_gyro: FloatArray
    predicted_noise_accel: FloatArray
    average_noise_gyro: FloatArray
    average_noise_accel: FloatArray
    static_gates_ok: bool
    gyro_gate_ok_fraction: float
    accel_gate_ok_fraction: float
    max_gyro_diff_rad_s: float
    max_accel_diff_m_s2: float
    fdi_alarm_fraction: float
    robust_fdi_alarm_fraction: float
    robust_alarm_gate_overlap: float
    fused: R.FusionResult


def common_samples(logs: Sequence[ImuLog], min_samples: int = 10) -> list[ImuLog]:
    """The logs restricted to the time stamps (s) they all share, in the given order.

    Raises
    ------
    InputError
        If fewer than ``min_samples`` time stamps are common to every log.
    """
    logs = [require_log(lg, f"logs[{i}]") for i, lg in enumerate(logs)]
    common = functools.reduce(np.intersect1d, [lg.t for lg in logs])
    if common.size < min_samples:
        raise InputError(f"the IMU streams share fewer than {min_samples} timestamps")
    out = []
    for lg in logs:
        i = np.searchsorted(lg.t, common)
        out.append(
            ImuLog(
                t=common,
                gyro=lg.gyro[i],
                accel=lg.accel[i],
                temp=None if lg.temp is None else lg.temp[i],
                meta=dict(lg.meta),
            )
        )
    return out


def read_imus(path: str | os.PathLike[str]) -> list[ImuLog]:
    """The IMU streams of a DataFlash log (message-name order) on their common time stamps (s).

    Raises
    ------
    DataFormatError
        If the file is unreadable, has fewer than two IMU streams, or the streams share fewer
        than 10 time stamps.
    """
    logs = open_log(path, need=("imus",)).imus
    if len(logs) < 2:
        raise DataFormatError(f"fewer than two IMU streams ({', '.join(sorted(logs))})", path=str(path))
    try:
        return common_samples([logs[k] for k in sorted(logs)])
    except InputError as e:
        raise DataFormatError(str(e), path=str(path)) from None


def _static_window(logs: list[ImuLog], window_s: float) -> slice:
    """The quietest window (smallest gyro spread of IMU 0) of length window_s."""
    g = logs[0].gyro
    rate = logs[0].sample_rate
    w = max(int(window_s * rate), 10)
    if g.shape[0] < 2 * w:
        raise InputError(f"log: shorter than two {window_s} s windows")
    best, best_k = np.inf, 0
    for k in range(0, g.shape[0] - w, w // 2):
        s = float(np.std(g[k : k + w], axis=0).sum())
        if s < best:
            best, best_k = s, k
    return slice(best_k, best_k + w)


def _max_pairwise(vs: list[FloatArray]) -> FloatArray:
    out = np.zeros(vs[0].shape[0])
    for i in range(len(vs)):
        for j in range(i + 1, len(vs)):
            out = np.maximum(out, np.linalg.norm(vs[i] - vs[j], axis=1))
    return out


def analyse_log(path: str | os.PathLike[str], *, static_window_s: float = 10.0) -> ArduPilotResult:
    """Fuse a DataFlash log's IMUs and compare with each IMU and ArduPilot's gates.

    Parameters
    ----------
    path : path-like
        ArduPilot DataFlash log (``.bin``) with at least two IMUs.
    static_window_s : float
        Length (s) of the quietest window used for the noise σ and the fusion weights.

    Raises
    ------
    DataFormatError
        Unreadable log, fewer than two IMUs or too few common samples.
    InputError
        Log shorter than two static windows.
    """
    logs = read_imus(path)
    n_imu = len(logs)
    cfg = R.from_mountings(np.repeat(np.eye(3)[None], n_imu, axis=0))
    win = _static_window(logs, static_window_s)
    _, g, a = R.stack_logs(logs, time_tol_s=1e-9)
    sg = R.white_noise_sigma(g[win])
    sa = R.white_noise_sigma(a[win])
    fused = R.fuse(logs, cfg, fdi=False, gyro_sigma=sg, accel_sigma=sa)
    fdi = R.fuse_axes(cfg, g, sigma=sg, fdi=True, parity_bias_samples=win.stop)
    s_rob = R.robust_sigma(cfg, g, sg)
    fdi_rob = R.fuse_axes(cfg, g, sigma=s_rob, fdi=True, parity_bias_samples=win.stop)
    dg = _max_pairwise([lg.gyro for lg in logs])
    da = _max_pairwise([lg.accel for lg in logs])
    t = logs[0].t
    return ArduPilotResult(
        n_samples=int(t.size),
        rate_hz=float(logs[0].sample_rate),
        static_window_s=(float(t[win.start]), float(t[win.stop - 1])),
        single_noise_gyro=sg.reshape(n_imu, 3),
        single_noise_accel=sa.reshape(n_imu, 3),
        fused_noise_gyro=R.white_noise_sigma(fused.gyro.value[win]),
        fused_noise_accel=R.white_noise_sigma(fused.accel.value[win]),
        predicted_noise_gyro=np.sqrt(np.diag(cfg.ls_covariance(sg))),
        predicted_noise_accel=np.sqrt(np.diag(cfg.ls_covariance(sa))),
        gyro_gate_ok_fraction=float(np.mean(dg <= GYRO_GATE_RAD_S)),
        accel_gate_ok_fraction=float(np.mean(da <= ACCEL_GATE_M_S2)),
        max_gyro_diff_rad_s=float(dg.max()),
        max_accel_diff_m_s2=float(da.max()),
        average_noise_gyro=R.white_noise_sigma(np.mean([lg.gyro[win] for lg in logs], axis=0)),
        average_noise_accel=R.white_noise_sigma(np.mean([lg.accel[win] for lg in logs], axis=0)),
        static_gates_ok=bool(np.all(dg[win] <= GYRO_GATE_RAD_S) and np.all(da[win] <= ACCEL_GATE_M_S2)),
        fdi_alarm_fraction=float(np.mean(fdi.alarm)),
        robust_fdi_alarm_fraction=float(np.mean(fdi_rob.alarm)),
        robust_alarm_gate_overlap=float(np.mean(fdi_rob.alarm[dg > GYRO_GATE_RAD_S]))
        if np.any(dg > GYRO_GATE_RAD_S)
        else 1.0,
        fused=fused,
    )


def shared_log_path() -> Path:
    """The shared reference log: ``$UASNAV_SHARED_DATA`` (or ``../shared/data`` beside the
    repository) / ``logs/ardupilot_log171.bin``."""
    root = os.environ.get("UASNAV_SHARED_DATA")
    base = Path(root) if root else Path(__file__).resolve().parents[3] / ".." / "shared" / "data"
    return (base / SHARED_LOG).resolve()


def run(
    *,
    seed: int = 2024,
    quick: bool = False,
    progress: Callable[[str], None] | None = None,
    path: str | os.PathLike[str] | None = None,
) -> ArduPilotResult:
    """:func:`analyse_log` of ``path`` (default :func:`shared_log_path`).

    ``seed`` and ``quick`` are accepted for the common experiment signature; the analysis of a
    recorded log draws no random numbers and has no reduced variant.

    Raises
    ------
    DataFormatError
        If the log is missing or unreadable (see :func:`analyse_log`).
    """
    p = Path(path) if path is not None else shared_log_path()
    if progress is not None:
        progress(f"ardupilot: fusing the IMUs of {p.name}")
    return analyse_log(p)


__all__ = [
    "ACCEL_GATE_M_S2",
    "GYRO_GATE_RAD_S",
    "ArduPilotResult",
    "analyse_log",
    "common_samples",
    "read_imus",
    "run",
    "shared_log_path",
]
