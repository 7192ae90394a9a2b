"""The GNSS/INS filter on a MAVLink stream, one batch of messages at a time.

:class:`LiveNav` turns received messages into the inputs of ``uasnav._core.InsStream``
(nav-core's ``InsStream``: causal, no lag after the start-up levelling; see its docs) and
returns the solution after every IMU sample. The same object serves ``uasnav nav --live`` (a
network stream) and ``uasnav nav --causal`` (a log's messages, :mod:`uasnav.live.source`), so
both give the same numbers on the same messages whatever the batching: each fix carries the
number of IMU samples that arrived before it.

Inputs:

- IMU: ``HIGHRES_IMU`` (m/s², rad/s) or ``RAW_IMU`` (ArduPilot's mG and mrad/s), instance 0,
  time ``time_usec`` (µs since boot).
- GNSS: ``GPS_RAW_INT`` with a 3D fix: ellipsoidal height ``alt_ellipsoid`` when sent, else the
  AMSL ``alt`` plus the EGM96 geoid height; north/east velocity from ``vel``/``cog``, down
  velocity the difference of consecutive heights (the message has none); accuracies
  ``h_acc``/``v_acc``/``vel_acc`` (defaults 2.5 m, 4 m, 0.5 m/s when not sent). Its time
  ``time_usec`` is since boot, or Unix time (> 10⁹ s) turned to boot time by ``SYSTEM_TIME``.

Compared with the offline mode (``uasnav nav LOG``), which levels on a window centred on the
start, uses the barometer, magnetometer and static updates and shifts fixes by the receiver's
delay, the causal filter levels on the first samples, uses GNSS only and takes fixes at their
stamped time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from uasnav.ins.core import InsConfig

_G = 9.80665
#: Default accuracies (1σ) for fixes that do not report them: horizontal m, vertical m, speed m/s.
DEFAULT_ACCURACY = (2.5, 4.0, 0.5)
#: A GNSS time stamp above this (s) is Unix time, not time since boot.
UNIX_TIME_S = 1e9


@dataclass
class NavBatch:
    """Solutions after each processed IMU sample of one batch (arrays of the binding)."""

    t: np.ndarray
    llh: np.ndarray
    vel: np.ndarray
    attitude: np.ndarray
    protection: np.ndarray
    gyro_bias: np.ndarray
    accel_bias: np.ndarray
    fixes_used: np.ndarray
    fixes_excluded: np.ndarray

    def __len__(self) -> int:
        return int(self.t.size)


class LiveNav:
    """Collects messages (:meth:`on_message`) and runs them through the filter (:meth:`flush`)."""

    def __init__(self, config: InsConfig | None = None, levelling_samples: int = 100) -> None:
        from uasnav import _core

        self.config = config if config is not None else InsConfig.for_logged_imu()
        self._stream = _core.InsStream(
            config=self.config.filter_config(0.0), levelling_samples=levelling_samples
        )
        self._imu: list[tuple[float, float, float, float, float, float, float]] = []
        self._gnss: list[
            tuple[float, float, float, float, float, float, float, float, float, float, int]
        ] = []
        self._boot_to_unix_s: float | None = None
        self._last_fix: tuple[float, float] | None = None
        self.imu_messages = 0
        self.gnss_messages = 0

    @property
    def running(self) -> bool:
        return bool(self._stream.running)

    def counts(self) -> dict[str, Any]:
        return dict(self._stream.counts())

    def on_message(self, msg: Any) -> None:
        """Take one received message (others than the inputs are ignored)."""
        t = msg.get_type()
        if t == "HIGHRES_IMU" and getattr(msg, "id", 0) == 0:
            self.imu_messages += 1
            self._imu.append(
                (msg.time_usec * 1e-6, msg.xgyro, msg.ygyro, msg.zgyro, msg.xacc, msg.yacc, msg.zacc)
            )
        elif t == "RAW_IMU" and getattr(msg, "id", 0) == 0:
            self.imu_messages += 1
            a = _G * 1e-3
            self._imu.append(
                (msg.time_usec * 1e-6, msg.xgyro * 1e-3, msg.ygyro * 1e-3, msg.zgyro * 1e-3,
                 msg.xacc * a, msg.yacc * a, msg.zacc * a)
            )  # fmt: skip
        elif t == "SYSTEM_TIME" and msg.time_unix_usec > 0:
            self._boot_to_unix_s = msg.time_unix_usec * 1e-6 - msg.time_boot_ms * 1e-3
        elif t == "GPS_RAW_INT" and msg.fix_type >= 3:
            self._fix(msg)

    def _fix(self, msg: Any) -> None:
        from uasnav.geo.geoid import geoid_height

        ts = msg.time_usec * 1e-6
        if ts > UNIX_TIME_S:
            if self._boot_to_unix_s is None:
                return
            ts -= self._boot_to_unix_s
        lat, lon = msg.lat * 1e-7, msg.lon * 1e-7
        alt_e = getattr(msg, "alt_ellipsoid", 0)
        h = alt_e * 1e-3 if alt_e else msg.alt * 1e-3 + float(geoid_height(lat, lon))
        if self._last_fix is not None and ts <= self._last_fix[0]:
            return  # duplicated or late
        vd = 0.0 if self._last_fix is None else -(h - self._last_fix[1]) / (ts - self._last_fix[0])
        self._last_fix = (ts, h)
        self.gnss_messages += 1
        speed, cog = msg.vel * 1e-2, math.radians(msg.cog * 1e-2)
        d = DEFAULT_ACCURACY
        h_acc = getattr(msg, "h_acc", 0) * 1e-3 or d[0]
        v_acc = getattr(msg, "v_acc", 0) * 1e-3 or d[1]
        s_acc = getattr(msg, "vel_acc", 0) * 1e-3 or d[2]
        self._gnss.append(
            (ts, math.radians(lat), math.radians(lon), h, speed * math.cos(cog), speed * math.sin(cog), vd,
             h_acc, v_acc, s_acc, len(self._imu))
        )  # fmt: skip

    @property
    def pending(self) -> int:
        """Messages waiting for :meth:`flush`."""
        return len(self._imu) + len(self._gnss)

    def flush(self) -> NavBatch:
        """Run the collected messages through the filter (one FFI call, GIL released)."""
        imu = np.asarray(self._imu, dtype=np.float64).reshape(-1, 7)
        g = np.asarray(self._gnss, dtype=np.float64).reshape(-1, 11)
        self._imu.clear()
        self._gnss.clear()
        out = self._stream.step(
            np.ascontiguousarray(imu[:, 0]),
            np.ascontiguousarray(imu[:, 1:4]),
            np.ascontiguousarray(imu[:, 4:7]),
            np.ascontiguousarray(g[:, 0]),
            np.ascontiguousarray(g[:, 1:4]),
            np.ascontiguousarray(g[:, 4:7]),
            np.ascontiguousarray(g[:, 7:10]),
            np.ascontiguousarray(g[:, 10]).astype(np.uint64),
        )
        return NavBatch(**{k: out[k] for k in NavBatch.__dataclass_fields__})


def track_rows(b: NavBatch) -> np.ndarray:
    """TRACK.csv rows (:data:`uasnav.io.track.TRACK_COLUMNS`) of a batch."""
    from uasnav.attitude import quat_to_euler

    n = len(b)
    if n == 0:
        return np.zeros((0, 19))
    euler = np.degrees(quat_to_euler(b.attitude))
    return np.column_stack(
        [b.t, np.degrees(b.llh[:, 0]), np.degrees(b.llh[:, 1]), b.llh[:, 2], b.vel, euler, b.gyro_bias,
         b.accel_bias, b.protection, (b.fixes_used > 0).astype(np.float64)]
    )  # fmt: skip


def format_rows(rows: np.ndarray) -> str:
    """TRACK.csv lines (17 significant digits, ``gnss_used`` 0/1) of ``rows``."""
    return "".join(",".join(f"{x:.17g}" for x in r[:-1]) + f",{int(r[-1])}\n" for r in rows)
