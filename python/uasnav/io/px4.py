"""PX4 ULog (``.ulg``) reader via pyulog.

IMU data come from ``sensor_combined`` (``gyro_rad[0..2]`` rad/s, ``accelerometer_m_s2[0..2]``
m/s², ``magnetometer_ga`` gauss → µT) or, in newer logs, ``vehicle_imu`` (delta angles/velocities
divided by their integration intervals). Temperature: the ``sensor_gyro``/``sensor_accel``
``temperature`` field when logged, else ``sensor_combined.baro_temp_celcius`` (board
temperature near the IMU), else none; it is interpolated onto the IMU time stamps.
Time is ``timestamp`` (µs since boot) in seconds. Frame: PX4 body FRD, as uasnav.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from uasnav.errors import DataFormatError
from uasnav.imu import ImuLog
from uasnav.io._common import build_log


def _dataset(ulog: Any, name: str, multi: int = 0) -> Any | None:
    for d in ulog.data_list:
        if d.name == name and d.multi_id == multi:
            return d
    return None


def _cols(d: Any, stem: str, path: str) -> np.ndarray:
    try:
        return np.column_stack([np.asarray(d.data[f"{stem}[{i}]"], dtype=np.float64) for i in range(3)])
    except KeyError as e:
        raise DataFormatError(
            f"{d.name}: missing field {e.args[0]!r}", path=path, column=f"{d.name}.{stem}"
        ) from None


def read_ulog(path: str | os.PathLike[str]) -> ImuLog:
    """Read the primary IMU of a PX4 ULog (see the module docs for topics and units)."""
    from pyulog import ULog

    p = Path(path)
    if not p.is_file():
        raise DataFormatError("no such file", path=str(p))
    try:
        ulog = ULog(str(p))
    except Exception as e:  # pyulog raises bare exceptions on corrupt headers
        raise DataFormatError(f"not a readable ULog ({type(e).__name__}: {e})", path=str(p)) from None
    sp = str(p)
    meta: dict[str, Any] = {"source": sp, "format": "px4-ulog", "frame": "FRD"}
    sc = _dataset(ulog, "sensor_combined")
    mag = None
    if sc is not None:
        t = np.asarray(sc.data["timestamp"], dtype=np.float64) * 1e-6
        gyro = _cols(sc, "gyro_rad", sp)
        accel = _cols(sc, "accelerometer_m_s2", sp)
        if "magnetometer_ga[0]" in sc.data:
            mag = _cols(sc, "magnetometer_ga", sp) * 100.0  # gauss → µT
        topic = "sensor_combined"
    else:
        vi = _dataset(ulog, "vehicle_imu")
        if vi is None:
            names = sorted({d.name for d in ulog.data_list})
            raise DataFormatError(
                f"no sensor_combined or vehicle_imu topic (topics: {', '.join(names)})", path=sp
            )
        t = np.asarray(vi.data["timestamp"], dtype=np.float64) * 1e-6
        dt_a = np.asarray(vi.data["delta_angle_dt"], dtype=np.float64) * 1e-6
        dt_v = np.asarray(vi.data["delta_velocity_dt"], dtype=np.float64) * 1e-6
        if np.any(dt_a <= 0) or np.any(dt_v <= 0):
            raise DataFormatError(
                "vehicle_imu: non-positive integration interval", path=sp, column="vehicle_imu"
            )
        gyro = _cols(vi, "delta_angle", sp) / dt_a[:, None]
        accel = _cols(vi, "delta_velocity", sp) / dt_v[:, None]
        topic = "vehicle_imu"
    temp = None
    for name, field in (("sensor_gyro", "temperature"), ("sensor_accel", "temperature")):
        d = _dataset(ulog, name)
        if d is not None and field in d.data:
            temp_t = np.asarray(d.data["timestamp"], dtype=np.float64) * 1e-6
            temp = np.interp(t, temp_t, np.asarray(d.data[field], dtype=np.float64))
            meta["temperature_source"] = f"{name}.{field}"
            break
    if temp is None and sc is not None and np.any(np.asarray(sc.data.get("baro_temp_celcius", [0.0])) != 0):
        # logged as exactly 0 when the barometer did not report: treat as absent
        temp = np.asarray(sc.data["baro_temp_celcius"], dtype=np.float64)
        meta["temperature_source"] = "sensor_combined.baro_temp_celcius"
    meta["topic"] = topic
    return build_log(sp, topic, t, gyro, accel, temp, meta, mag=mag)


__all__ = ["read_ulog"]
