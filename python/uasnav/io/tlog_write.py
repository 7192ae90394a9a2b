"""Writing MAVLink telemetry logs (``.tlog``): the ground station's record of a flight.

A ``.tlog`` is a sequence of records, each an 8-byte big-endian UNIX time stamp in µs (the
ground station's wall clock) followed by one MAVLink packet. :func:`write_tlog_flight` writes
what :func:`uasnav.io.formats.tlog.read_tlog_flight` reads back: ``GLOBAL_POSITION_INT`` fixes, the
mission (``MISSION_ITEM_INT``: home at seq 0, ``DO_CHANGE_SPEED`` with the cruise speed, then the
navigation waypoints) and ``MISSION_ITEM_REACHED`` events. Packets are MAVLink 2, encoded by
pymavlink (its ``ardupilotmega`` dialect, the one the readers use). Used by the synthetic fleet
(:mod:`uasnav.fleet.simulate`) to carry the plan a simulated flight flew.
"""

from __future__ import annotations

import os
import struct
from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike

from uasnav.atomicfile import atomic_write_bytes
from uasnav.errors import InputError

_MAV_FRAME_GLOBAL_INT = 5  # MSL altitude, lat/lon in 1e-7 deg
_MAV_NAV_WAYPOINT = 16
_MAV_DO_CHANGE_SPEED = 178


def write_tlog_flight(
    path: str | os.PathLike[str],
    *,
    t_unix: ArrayLike,
    lat: ArrayLike,
    lon: ArrayLike,
    alt: ArrayLike,
    vel_ned: ArrayLike,
    waypoints: Mapping[int, tuple[float, float, float]],
    reached: Sequence[tuple[float, int]] = (),
    cruise_ms: float | None = None,
) -> None:
    """Write a telemetry log atomically.

    Parameters
    ----------
    path : path
    t_unix : array, shape (k,)
        Wall-clock time of each fix, s since 1970 (UTC); increasing.
    lat, lon, alt : array, shape (k,)
        Position: deg, deg, m.
    vel_ned : array, shape (k, 3)
        Ground velocity, m/s, NED.
    waypoints : dict seq → (lat, lon, alt)
        Navigation waypoints (deg, deg, m); seq ≥ 1 (seq 0 is written as the home position, the
        first fix).
    reached : sequence of (t_unix, seq)
        Waypoint-reached events (s, sequence number).
    cruise_ms : float, optional
        Mission speed (m/s), written as a ``DO_CHANGE_SPEED`` item.

    Raises
    ------
    InputError
        Shapes that do not match, non-finite values, time not increasing, seq < 1.
    """
    from pymavlink.dialects.v20 import ardupilotmega as mavlink

    t = np.asarray(t_unix, dtype=np.float64)
    cols = [np.asarray(a, dtype=np.float64) for a in (lat, lon, alt)]
    vel = np.asarray(vel_ned, dtype=np.float64)
    n = t.size
    if t.ndim != 1 or n < 1 or any(c.shape != (n,) for c in cols) or vel.shape != (n, 3):
        raise InputError(f"write_tlog_flight: expected t, lat, lon, alt of shape ({n},) and vel_ned ({n}, 3)")
    if not (np.isfinite(t).all() and all(np.isfinite(c).all() for c in cols) and np.isfinite(vel).all()):
        raise InputError("write_tlog_flight: non-finite time, position or velocity")
    if n > 1 and not np.all(np.diff(t) > 0):
        raise InputError("write_tlog_flight: time stamps are not increasing")
    if any(int(s) < 1 for s in waypoints):
        raise InputError("write_tlog_flight: waypoint sequence numbers start at 1 (0 is home)")
    mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    records: list[tuple[float, int, bytes]] = []  # (time, order, packet): stable sort by time
    t0 = float(t[0])

    def add(when: float, msg: object) -> None:
        records.append((when, len(records), msg.pack(mav)))  # type: ignore[attr-defined]

    def item(seq: int, command: int, x: float, y: float, z: float, param2: float = 0.0) -> object:
        return mavlink.MAVLink_mission_item_int_message(
            1, 1, seq, _MAV_FRAME_GLOBAL_INT, command, 0, 1, 0.0, param2, 0.0, 0.0,
            round(float(x * 1e7)), round(float(y * 1e7)), float(z), 0,
        )  # fmt: skip

    # the mission as the ground station downloads it before take-off
    add(t0, item(0, _MAV_NAV_WAYPOINT, float(cols[0][0]), float(cols[1][0]), float(cols[2][0])))
    seqs = sorted(int(s) for s in waypoints)
    shift = 1 if cruise_ms is not None else 0
    if cruise_ms is not None:
        add(t0, item(1, _MAV_DO_CHANGE_SPEED, 0.0, 0.0, 0.0, param2=float(cruise_ms)))
    for s in seqs:
        la, lo, al = waypoints[s]
        add(t0, item(s + shift, _MAV_NAV_WAYPOINT, la, lo, al))
    for k in range(n):
        add(
            float(t[k]),
            mavlink.MAVLink_global_position_int_message(
                round(float((t[k] - t0) * 1e3)) & 0xFFFFFFFF,
                round(float(cols[0][k] * 1e7)),
                round(float(cols[1][k] * 1e7)),
                round(float(cols[2][k] * 1e3)),
                round(float((cols[2][k] - cols[2][0]) * 1e3)),
                round(float(vel[k, 0] * 100)),
                round(float(vel[k, 1] * 100)),
                round(float(vel[k, 2] * 100)),
                65535,
            ),
        )
    for when, s in reached:
        add(float(when), mavlink.MAVLink_mission_item_reached_message(int(s) + shift))
    records.sort(key=lambda r: (r[0], r[1]))
    out = b"".join(struct.pack(">Q", round(float(w * 1e6))) + pkt for w, _, pkt in records)
    atomic_write_bytes(path, out)


__all__ = ["write_tlog_flight"]
