"""A flight log as the MAVLink messages a ground station receives, in the log's timing.

A ``.tlog`` *is* such a stream: its messages are given as recorded, each with the ground
station's receive time. DataFlash (``.bin``) and ULog (``.ulg``) logs are converted from the
views of :func:`uasnav.io.open_log` into the messages an autopilot streams, encoded by
pymavlink's ``ardupilotmega`` dialect (MAVLink 2), system id 1, component 1:

===================== ===================================================== ==============
message               from                                                  rate
===================== ===================================================== ==============
``HEARTBEAT``         armed, custom mode 0, system state ACTIVE             1 Hz
``SYSTEM_TIME``       the log's UTC at boot (``identity.utc_at_zero``)        1 Hz
``GPS_RAW_INT``       ``gnss``: AMSL and ellipsoidal heights, accuracies    each fix
``GLOBAL_POSITION_INT`` ``autopilot_estimate`` (AMSL), else the GNSS fixes   ≤ 10 Hz
``ATTITUDE``          ``autopilot_estimate`` Euler angles                   ≤ 10 Hz
``RAW_IMU`` (.bin)    the primary IMU, mG and mrad/s as ArduPilot sends     logged rate
``HIGHRES_IMU`` (.ulg) the primary IMU, m/s² and rad/s as PX4 sends          logged rate
===================== ===================================================== ==============

Heights follow MAVLink: ``GLOBAL_POSITION_INT.alt`` and ``GPS_RAW_INT.alt`` are AMSL, the
ellipsoidal height is ``GPS_RAW_INT.alt_ellipsoid``; a view whose heights carry another datum
is converted with the EGM96 geoid (:mod:`uasnav.geo.geoid`).
"""

from __future__ import annotations

import heapq
import math
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from uasnav.errors import InputError

#: Largest rate (Hz) of the converted ``GLOBAL_POSITION_INT``/``ATTITUDE`` streams.
POSITION_RATE_HZ = 10.0
#: Extensions :func:`log_packets` reads.
LOG_EXTENSIONS = (".tlog", ".bin", ".ulg")

_MAV_TYPE_QUADROTOR = 2
_MAV_AUTOPILOT_ARDUPILOTMEGA = 3
_MAV_AUTOPILOT_PX4 = 12
_MAV_STATE_ACTIVE = 4
_MAV_MODE_FLAG_SAFETY_ARMED = 128
_MAV_MODE_FLAG_CUSTOM_MODE_ENABLED = 1
_GPS_FIX_TYPE_3D = 3
_G = 9.80665


@dataclass(frozen=True)
class Packet:
    """One message of a stream: ``t_s`` the log time (s) it was received or logged at, ``msg``
    the pymavlink message (its ``get_msgbuf()`` the bytes on the wire)."""

    t_s: float
    msg: Any


def mavlink_dialect() -> Any:
    """pymavlink's MAVLink 2 ``ardupilotmega`` dialect module (the one every reader uses)."""
    from pymavlink.dialects.v20 import ardupilotmega

    return ardupilotmega


def log_packets(path: str | os.PathLike[str]) -> Iterator[Packet]:
    """The messages of the log at ``path`` in time order (see the module for the conversion).

    Raises
    ------
    InputError
        For an extension other than ``.tlog``, ``.bin``, ``.ulg``.
    DataFormatError
        For a log that cannot be read.
    """
    p = Path(path)
    ext = p.suffix.lower()
    if ext not in LOG_EXTENSIONS:
        raise InputError(
            f"{p}: cannot replay {ext or 'a file without extension'} (supported: .tlog, .bin, .ulg)"
        )
    if ext == ".tlog":
        return _tlog_packets(p)
    return _converted_packets(p)


def _tlog_packets(p: Path) -> Iterator[Packet]:
    from uasnav.errors import DataFormatError
    from uasnav.io._mavlink import connect

    # read lazily (a long log is never held in memory); pymavlink's own printing is not
    # captured here, since a capture would swallow the caller's output while the generator lives
    conn = connect(p, dialect="ardupilotmega")
    try:
        while True:
            try:
                msg = conn.recv_msg()
            except Exception as e:  # struct.error, IndexError … on a truncated or corrupt log
                raise DataFormatError(
                    f"corrupt MAVLink message ({type(e).__name__}: {e})", path=str(p)
                ) from None
            if msg is None:
                return
            if msg.get_type() == "BAD_DATA":
                continue
            yield Packet(float(msg._timestamp), msg)
    finally:
        conn.close()


def _amsl(lat: np.ndarray, lon: np.ndarray, alt: np.ndarray, datum: Any) -> tuple[np.ndarray, np.ndarray]:
    """(AMSL, ellipsoidal) heights (m) of heights in ``datum`` (EGM96 between the two)."""
    from uasnav.geo.datum import HeightDatum
    from uasnav.geo.geoid import geoid_height

    n = np.asarray(geoid_height(lat, lon), dtype=np.float64)
    if HeightDatum(datum) == HeightDatum.ELLIPSOID:
        return alt - n, alt
    # AMSL as the log gives it; any other datum is sent as it is (MAVLink has no field for it)
    return alt, alt + n


def _decimate(t: np.ndarray, rate_hz: float) -> np.ndarray:
    """Indices of ``t`` keeping at most ``rate_hz`` samples per second."""
    keep: list[int] = []
    last = -math.inf
    for i, ti in enumerate(t):
        if ti - last >= 1.0 / rate_hz - 1e-9:
            keep.append(i)
            last = float(ti)
    return np.asarray(keep, dtype=np.int64)


def _i(x: float) -> int:
    return round(float(x))


def _converted_packets(p: Path) -> Iterator[Packet]:
    """DataFlash/ULog → messages (module table), merged in time order."""
    from uasnav.io import open_log

    log = open_log(p)
    mav = mavlink_dialect()
    px4 = p.suffix.lower() == ".ulg"
    streams: list[Iterator[Packet]] = []
    imu = log.imu
    ident = log.identity if log.carries("identity") else None
    utc0 = getattr(ident, "utc_at_zero", None)
    utc0_s = utc0.timestamp() if utc0 is not None else 0.0
    t_first, t_last = float(imu.t[0]), float(imu.t[-1])

    def imu_packets() -> Iterator[Packet]:
        for t, g, a in zip(imu.t, imu.gyro, imu.accel, strict=True):
            us = _i(t * 1e6)
            if px4:
                m = mav.MAVLink_highres_imu_message(
                    us, *map(float, a), *map(float, g), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0x3F
                )
            else:
                acc = [_i(x / _G * 1000.0) for x in a]
                gyr = [_i(x * 1000.0) for x in g]
                m = mav.MAVLink_raw_imu_message(us, *acc, *gyr, 0, 0, 0)
            yield Packet(float(t), m)

    streams.append(imu_packets())

    def clock_packets() -> Iterator[Packet]:
        base = _MAV_MODE_FLAG_SAFETY_ARMED | _MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        autopilot = _MAV_AUTOPILOT_PX4 if px4 else _MAV_AUTOPILOT_ARDUPILOTMEGA
        t = t_first
        while t <= t_last:
            yield Packet(
                t,
                mav.MAVLink_heartbeat_message(_MAV_TYPE_QUADROTOR, autopilot, base, 0, _MAV_STATE_ACTIVE, 3),
            )
            unix_us = _i((utc0_s + t) * 1e6) if utc0 is not None else 0
            yield Packet(t, mav.MAVLink_system_time_message(unix_us, _i(t * 1000.0) & 0xFFFFFFFF))
            t += 1.0

    streams.append(clock_packets())

    gnss = log.gnss if log.carries("gnss") else None
    if gnss is not None and len(gnss.t):
        amsl, ell = _amsl(gnss.lat, gnss.lon, gnss.alt, gnss.alt_datum)

        def gnss_packets() -> Iterator[Packet]:
            for k in range(len(gnss.t)):
                vn, ve = float(gnss.vel[k][0]), float(gnss.vel[k][1])
                speed = math.hypot(vn, ve)
                cog = math.degrees(math.atan2(ve, vn)) % 360.0
                m = mav.MAVLink_gps_raw_int_message(
                    _i(gnss.t[k] * 1e6), _GPS_FIX_TYPE_3D, _i(gnss.lat[k] * 1e7), _i(gnss.lon[k] * 1e7),
                    _i(amsl[k] * 1000.0), min(_i(gnss.h_acc[k] * 100.0), 65535),
                    min(_i(gnss.v_acc[k] * 100.0), 65535), min(_i(speed * 100.0), 65535),
                    _i(cog * 100.0) % 36000, 10, _i(ell[k] * 1000.0), _i(gnss.h_acc[k] * 1000.0),
                    _i(gnss.v_acc[k] * 1000.0), _i(gnss.s_acc[k] * 1000.0), 0, 0,
                )  # fmt: skip
                yield Packet(float(gnss.t[k]), m)

        streams.append(gnss_packets())

    est = log.autopilot_estimate if log.carries("autopilot_estimate") else None
    pos: Any = est if est is not None and len(est.t) else gnss
    if pos is not None and len(pos.t):
        keep = _decimate(np.asarray(pos.t), POSITION_RATE_HZ)
        amsl, _ = _amsl(pos.lat, pos.lon, pos.alt, pos.alt_datum)
        vel = pos.vel if pos.vel is not None else np.zeros((len(pos.t), 3))
        euler = getattr(pos, "euler_deg", None)
        home = float(amsl[0])

        def position_packets() -> Iterator[Packet]:
            for k in keep:
                t = float(pos.t[k])
                ms = _i(t * 1000.0) & 0xFFFFFFFF
                yaw = float(euler[k][2]) if euler is not None else 0.0
                yield Packet(t, mav.MAVLink_global_position_int_message(
                    ms, _i(pos.lat[k] * 1e7), _i(pos.lon[k] * 1e7), _i(amsl[k] * 1000.0),
                    _i((amsl[k] - home) * 1000.0), *(_i(v * 100.0) for v in vel[k]), _i(yaw % 360.0 * 100.0),
                ))  # fmt: skip
                if euler is not None:
                    r, pt, y = (math.radians(float(x)) for x in euler[k])
                    yield Packet(t, mav.MAVLink_attitude_message(ms, r, pt, y, 0.0, 0.0, 0.0))

        streams.append(position_packets())
    # stable merge: at equal times the stream order above (IMU first, then clock, GNSS, position)
    yield from heapq.merge(*streams, key=lambda pk: pk.t_s)
