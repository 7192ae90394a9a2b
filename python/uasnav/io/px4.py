"""PX4 ULog (``.ulg``) logs via pyulog: the primary IMU and the flight telemetry.

IMU (:func:`read_ulog`): data come from ``sensor_combined`` (``gyro_rad[0..2]`` rad/s,
``accelerometer_m_s2[0..2]`` m/s², ``magnetometer_ga`` gauss → µT) or, in newer logs,
``vehicle_imu`` (delta angles/velocities divided by their integration intervals).
Temperature: the ``sensor_gyro``/``sensor_accel`` ``temperature`` field when logged, else
``sensor_combined.baro_temp_celcius`` (board temperature near the IMU), else none; it is
interpolated onto the IMU time stamps.
Time is ``timestamp`` (µs since boot) in seconds. Frame: PX4 body FRD, as uasnav.

Flight (:func:`read_ulog_flight`): ``vehicle_global_position`` (or ``vehicle_gps_position``),
the ``mission_result`` reached sequence numbers and ``wind_estimate``. PX4 logs hold no
waypoint coordinates (the mission lives in dataman), so ``waypoints`` stays empty.

Errors: a missing file or one pyulog cannot parse is a :class:`~uasnav.errors.DataFormatError`
naming the file.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from uasnav.errors import DataFormatError
from uasnav.imu import ImuLog
from uasnav.io._common import build_log
from uasnav.io.flight import FlightLog


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


def _open(p: Path) -> Any:
    """The parsed ULog ``p`` (one error handling for both readers)."""
    from pyulog import ULog

    if not p.is_file():
        raise DataFormatError("no such file", path=str(p))
    try:
        return ULog(str(p))
    except Exception as e:  # pyulog raises bare exceptions on corrupt headers
        raise DataFormatError(f"not a readable ULog ({type(e).__name__}: {e})", path=str(p)) from None


def read_ulog(path: str | os.PathLike[str]) -> ImuLog:
    """Read the primary IMU of a PX4 ULog (see the module docs for topics and units).

    Raises
    ------
    DataFormatError
        Missing/unreadable file, no IMU topic, a missing field, a non-finite value or time
        going backwards.
    """
    p = Path(path)
    ulog = _open(p)
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


def read_ulog_flight(path: str | os.PathLike[str]) -> FlightLog:
    """The flight telemetry of a PX4 ULog (see the module docs for the topics).

    Raises
    ------
    DataFormatError
        Missing/unreadable file, or neither vehicle_global_position nor vehicle_gps_position.
    """
    p = Path(path)
    ulog = _open(p)

    def topic(name: str) -> dict[str, np.ndarray] | None:
        d = _dataset(ulog, name)
        return None if d is None else d.data

    g = topic("vehicle_global_position")
    if g is not None and "vel_n" in g:
        t = g["timestamp"] * 1e-6
        lat, lon, alt = g["lat"], g["lon"], g["alt"]
        vel = np.column_stack([g["vel_n"], g["vel_e"], g["vel_d"]])
    else:
        g = topic("vehicle_gps_position")
        if g is None:
            raise DataFormatError("no vehicle_global_position / vehicle_gps_position topic", path=str(p))
        t = g["timestamp"] * 1e-6
        lat, lon, alt = g["lat"] * 1e-7, g["lon"] * 1e-7, g["alt"] * 1e-3
        vel = np.column_stack([g["vel_n_m_s"], g["vel_e_m_s"], g["vel_d_m_s"]])
    reached: list[tuple[float, int]] = []
    mr = topic("mission_result")
    if mr is not None and "seq_reached" in mr:
        last = -1
        for ts, s in zip(mr["timestamp"], mr["seq_reached"], strict=True):
            if s >= 0 and s != last:
                reached.append((ts * 1e-6, int(s)))
            last = s
    w = topic("wind_estimate")
    wind = np.array([w["windspeed_north"].mean(), w["windspeed_east"].mean()]) if w is not None else None
    return FlightLog(
        t=t, lat=lat, lon=lon, alt=alt, vel_ned=vel, reached=reached, wind_ne=wind, source=str(p)
    )


__all__ = ["read_ulog", "read_ulog_flight"]
