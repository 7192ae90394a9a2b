"""Fusion of the three IMUs of an ArduPilot DataFlash log, compared with each IMU and with
ArduPilot's own pre-arm consistency gates.

ArduPilot (``AP_InertialSensor::gyros_consistent`` / ``accels_consistent``) calls its IMUs
consistent when every pair of gyro vectors differs by at most 5 deg/s and every pair of
accelerometer vectors by at most 0.75 m/s². The ``IMU``, ``IMU2`` and ``IMU3`` messages are
already rotated into the vehicle body frame, so the three sensors share one mounting
(identity) and fusion is a weighted average whose weights come from each IMU's white noise in
a static window.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from uasnav import redundancy as R
from uasnav.errors import DataFormatError, InputError
from uasnav.imu import ImuLog

GYRO_GATE_RAD_S = np.radians(5.0)
ACCEL_GATE_M_S2 = 0.75


def read_dataflash_imus(path: str | os.PathLike[str]) -> list[ImuLog]:
    """The ``IMU``, ``IMU2``, ``IMU3`` streams of a DataFlash log on their common timestamps.

    Raises
    ------
    DataFormatError
        If the file is unreadable or has fewer than two IMU streams.
    """
    try:
        from pymavlink import mavutil
    except ImportError as e:  # pragma: no cover - a declared dependency
        raise DataFormatError(f"pymavlink is required to read DataFlash logs ({e})", path=str(path)) from None
    if not os.path.isfile(path):
        raise DataFormatError("no such file", path=str(path))
    conn = mavutil.mavlink_connection(str(path))
    rows: dict[str, dict[int, list[float]]] = {"IMU": {}, "IMU2": {}, "IMU3": {}}
    while True:
        msg = conn.recv_match(type=list(rows))
        if msg is None:
            break
        d = msg.to_dict()
        t = d.get("TimeUS", None)
        t_us = int(t) if t is not None else int(d["TimeMS"]) * 1000
        rows[msg.get_type()][t_us] = [
            d["GyrX"],
            d["GyrY"],
            d["GyrZ"],
            d["AccX"],
            d["AccY"],
            d["AccZ"],
            d.get("Temp", np.nan),
        ]
    streams = [r for r in rows.values() if r]
    if len(streams) < 2:
        raise DataFormatError("fewer than two IMU streams (IMU, IMU2, IMU3)", path=str(path))
    common = sorted(set.intersection(*(set(r) for r in streams)))
    if len(common) < 10:
        raise DataFormatError("the IMU streams share fewer than 10 timestamps", path=str(path))
    t = np.array(common, dtype=np.float64) * 1e-6
    logs = []
    for r in streams:
        a = np.array([r[k] for k in common], dtype=np.float64)
        logs.append(ImuLog(t=t, gyro=a[:, 0:3], accel=a[:, 3:6], temp=a[:, 6], meta={"source": str(path)}))
    return logs


@dataclass(frozen=True)
class ArduPilotFusion:
    """Result of :func:`analyse_log` (noise σ per sample per axis, in a static window).

    Attributes
    ----------
    n_samples : int
    rate_hz : float
    static_window_s : tuple of float
        Start and end (s, log time) of the window used for noise and weights.
    single_noise_gyro, single_noise_accel : ndarray, shape (n_imu, 3)
        White-noise σ of each IMU (rad/s, m/s²).
    fused_noise_gyro, fused_noise_accel : ndarray, shape (3,)
        White-noise σ of the fused IMU.
    predicted_noise_gyro, predicted_noise_accel : ndarray, shape (3,)
        σ predicted by the LS covariance from the single-IMU noise.
    average_noise_gyro, average_noise_accel : ndarray, shape (3,)
        White-noise σ of the plain (unweighted) average of the IMUs, for comparison.
    static_gates_ok : bool
        Every sample of the static window passes both gates.
    gyro_gate_ok_fraction, accel_gate_ok_fraction : float
        Fraction of samples passing ArduPilot's consistency gates.
    max_gyro_diff_rad_s, max_accel_diff_m_s2 : float
        Largest pairwise vector difference.
    fdi_alarm_fraction : float
        Fraction of samples on which the parity test (p_fa = 1e-6, σ from the static window)
        fired: vibration the IMUs see differently is not white noise.
    robust_fdi_alarm_fraction : float
        The same with σ from the robust spread of the whole log's parity residuals
        (:func:`uasnav.redundancy.robust_sigma`).
    robust_alarm_gate_overlap : float
        Fraction of gyro-gate failures on which the robust parity test also fired.
    fused : FusionResult
    """

    n_samples: int
    rate_hz: float
    static_window_s: tuple[float, float]
    single_noise_gyro: NDArray[np.float64]
    single_noise_accel: NDArray[np.float64]
    fused_noise_gyro: NDArray[np.float64]
    fused_noise_accel: NDArray[np.float64]
    predicted_noise_gyro: NDArray[np.float64]
    predicted_noise_accel: NDArray[np.float64]
    average_noise_gyro: NDArray[np.float64]
    average_noise_accel: NDArray[np.float64]
    static_gates_ok: bool
    gyro_gate_ok_fraction: float
    accel_gate_ok_fraction: float
    max_gyro_diff_rad_s: float
    max_accel_diff_m_s2: float
    fdi_alarm_fraction: float
    robust_fdi_alarm_fraction: float
    robust_alarm_gate_overlap: float
    fused: R.FusionResult


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


def _max_pairwise(vs: list[NDArray[np.float64]]) -> NDArray[np.float64]:
    out = np.zeros(vs[0].shape[0])
    for i in range(len(vs)):
        for j in range(i + 1, len(vs)):
            out = np.maximum(out, np.linalg.norm(vs[i] - vs[j], axis=1))
    return out


def analyse_log(path: str | os.PathLike[str], *, static_window_s: float = 10.0) -> ArduPilotFusion:
    """Fuse a DataFlash log's IMUs and compare with each IMU and ArduPilot's gates."""
    logs = read_dataflash_imus(path)
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
    return ArduPilotFusion(
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


__all__ = ["ACCEL_GATE_M_S2", "GYRO_GATE_RAD_S", "ArduPilotFusion", "analyse_log", "read_dataflash_imus"]
