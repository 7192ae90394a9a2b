"""MAVLink telemetry logs (``.tlog``, ArduPilot dialect) via pymavlink: IMU streams and flight.

IMUs (:func:`read_tlog`): ``HIGHRES_IMU`` (SI), ``SCALED_IMU``/``SCALED_IMU2``/``SCALED_IMU3``
and ``RAW_IMU`` as sent by ArduPilot (acceleration mg → m/s², rate mrad/s → rad/s,
temperature cdegC when present and non-zero), time ``time_usec`` or ``time_boot_ms`` (s).
A telemetry log can span autopilot reboots (boot time restarts): each stream is split there
and later parts are keyed ``"SCALED_IMU2#2"`` … Frame: ArduPilot body FRD, as uasnav.

Flight (:func:`read_tlog_flight`): ``GLOBAL_POSITION_INT``, ``MISSION_ITEM(_INT)``,
``MISSION_ITEM_REACHED``, ``WIND`` (ArduPilot, if present), the ``WPNAV_SPEED`` parameter and
``DO_CHANGE_SPEED`` mission items; times are the log's wall clock (s).

Errors: a missing or unreadable file and an undecodable message are a
:class:`~uasnav.errors.DataFormatError` naming the file. Corrupt messages fail their MAVLink
checksum and are dropped by pymavlink; the readers count them and warn once
(:class:`~uasnav.errors.CorruptDataWarning`). The 8-byte time stamp that a ``.tlog`` puts before
each message has no checksum: fixes whose time stamp is out of order are dropped too
(:func:`uasnav.io.flight.valid_fixes`).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from uasnav.errors import DataFormatError
from uasnav.imu import ImuLog
from uasnav.io._common import because, build_log, corruption_meta, report_corruption
from uasnav.io._mavlink import messages, reading
from uasnav.io.flight import FlightLog, flight_from_fixes, wind_from
from uasnav.units import STANDARD_GRAVITY

#: IMU message streams read by :func:`read_tlog`.
IMU_TYPES = ("HIGHRES_IMU", "SCALED_IMU", "SCALED_IMU2", "SCALED_IMU3", "RAW_IMU")
_FLIGHT_TYPES = (
    "GLOBAL_POSITION_INT",
    "MISSION_ITEM_INT",
    "MISSION_ITEM",
    "MISSION_ITEM_REACHED",
    "WIND",
    "PARAM_VALUE",
)
_MAV_NAV_WAYPOINT = 16
_MAV_DO_CHANGE_SPEED = 178


def read_tlog(path: str | os.PathLike[str]) -> dict[str, ImuLog]:
    """Every IMU message stream of a MAVLink telemetry log, keyed by message name.

    Raises
    ------
    DataFormatError
        Missing/unreadable file, corrupt message, no IMU message, a non-finite value.
    """
    p = Path(path)
    rows: dict[str, list[tuple[float, ...]]] = {}
    with reading(p, dialect="ardupilotmega") as (conn, decoder):
        for msg in messages(conn, IMU_TYPES, p, "MAVLink"):
            key = msg.get_type()
            d = msg.to_dict()
            t = d["time_usec"] * 1e-6 if "time_usec" in d else d["time_boot_ms"] * 1e-3
            if key == "HIGHRES_IMU":
                row = (
                    t,
                    d["xgyro"],
                    d["ygyro"],
                    d["zgyro"],
                    d["xacc"],
                    d["yacc"],
                    d["zacc"],
                    d["temperature"],
                )
            else:
                temp = d.get("temperature", 0)
                row = (
                    t,
                    d["xgyro"] * 1e-3,
                    d["ygyro"] * 1e-3,
                    d["zgyro"] * 1e-3,
                    d["xacc"] * 1e-3 * STANDARD_GRAVITY,
                    d["yacc"] * 1e-3 * STANDARD_GRAVITY,
                    d["zacc"] * 1e-3 * STANDARD_GRAVITY,
                    temp * 0.01 if temp else np.nan,
                )
            rows.setdefault(key, []).append(row)
    if not rows:
        raise DataFormatError(f"no IMU messages ({', '.join(IMU_TYPES)}){because(decoder)}", path=str(p))
    # MAVLink messages carry a checksum: corrupt ones were dropped by pymavlink (counted here)
    report_corruption(str(p), decoder, 0, sum(len(r) for r in rows.values()), "IMU")
    out = {}
    for key in sorted(rows):
        a = np.asarray(rows[key], dtype=np.float64)
        # a telemetry log spans autopilot reboots: boot time restarts, so split there
        cuts = np.flatnonzero(np.diff(a[:, 0]) < 0) + 1
        for k, seg in enumerate(np.split(a, cuts)):
            if seg.shape[0] < 2:
                continue
            name = key if k == 0 else f"{key}#{k + 1}"
            temp = seg[:, 7] if np.all(np.isfinite(seg[:, 7])) else None
            meta = {
                "source": str(p),
                "format": "mavlink-tlog",
                "message": key,
                "boot_segment": k + 1,
                "frame": "FRD",
                **corruption_meta(decoder, 0),
            }
            out[name] = build_log(str(p), name, seg[:, 0], seg[:, 1:4], seg[:, 4:7], temp, meta)
    return out


def vz_down_sign(t: np.ndarray, alt_m: np.ndarray, vz: np.ndarray) -> float:
    """The factor (+1 or −1) that turns ``GLOBAL_POSITION_INT.vz`` of a log into a downward
    speed. MAVLink defines vz positive down; older ArduPilot firmware sent it positive up (its
    ``send_location`` wrote ``vel.z * -100`` "+ve up"), so the log's own altitude decides: −1
    when vz rises with the altitude on nearly every sample where the altitude changes by more
    than 0.5 m/s, +1 (the definition) otherwise or when there are too few such samples."""
    t, alt_m, vz = (np.asarray(x, dtype=np.float64) for x in (t, alt_m, vz))
    if t.size < 3:
        return 1.0
    dt = np.diff(t)
    ok = dt > 0
    climb = np.diff(alt_m)[ok] / dt[ok]
    v = 0.5 * (vz[1:] + vz[:-1])[ok]
    moving = np.abs(climb) > 0.5
    if moving.sum() < 5:
        return 1.0
    # positive down: vz and the climb rate have opposite signs
    agree_down = float(np.mean(np.sign(v[moving]) == -np.sign(climb[moving])))
    return -1.0 if agree_down < 0.2 else 1.0


def read_tlog_flight(path: str | os.PathLike[str]) -> FlightLog:
    """The flight telemetry of a MAVLink log (see the module docs for the messages).

    Navigation waypoints are the ``NAV_WAYPOINT`` items with a position (seq 0, ArduPilot's
    home, is left out); the cruise speed is the first ``DO_CHANGE_SPEED`` item's speed, else
    ``WPNAV_SPEED`` (cm/s → m/s).

    Raises
    ------
    DataFormatError
        Missing/unreadable file, corrupt message, or no GLOBAL_POSITION_INT message.
    """
    p = Path(path)
    fixes: list[tuple[float, ...]] = []
    items: dict[int, tuple[int, float, float, float, float]] = {}
    reached: list[tuple[float, int]] = []
    wind = []
    wpnav = None
    with reading(p, dialect="ardupilotmega") as (conn, decoder):
        for m in messages(conn, _FLIGHT_TYPES, p, "MAVLink"):
            kind = m.get_type()
            if kind == "GLOBAL_POSITION_INT":
                fixes.append(
                    (
                        m._timestamp,
                        m.lat * 1e-7,
                        m.lon * 1e-7,
                        m.alt * 1e-3,
                        m.vx * 0.01,
                        m.vy * 0.01,
                        m.vz * 0.01,
                    )
                )
            elif kind in ("MISSION_ITEM_INT", "MISSION_ITEM"):
                scale = 1e-7 if kind == "MISSION_ITEM_INT" else 1.0
                items[m.seq] = (m.command, m.x * scale, m.y * scale, m.z, m.param2)
            elif kind == "MISSION_ITEM_REACHED":
                reached.append((m._timestamp, int(m.seq)))
            elif kind == "WIND":
                speed, direction = float(m.speed), float(m.direction)
                # a wind the autopilot could not estimate (NaN, negative) is no estimate
                if np.isfinite(speed) and np.isfinite(direction) and speed >= 0:
                    wind.append(wind_from(speed, direction))
            elif kind == "PARAM_VALUE" and m.param_id.rstrip("\x00") == "WPNAV_SPEED":
                value = float(m.param_value) * 0.01
                wpnav = value if np.isfinite(value) and value > 0 else None
    if not fixes:
        raise DataFormatError(f"no GLOBAL_POSITION_INT messages{because(decoder)}", path=str(p))
    fx = np.asarray(fixes, dtype=np.float64)
    fx[:, 6] *= vz_down_sign(fx[:, 0], fx[:, 3], fx[:, 6])
    fixes = [tuple(row) for row in fx]
    # seq 0 is the home position on ArduPilot; navigation waypoints carry a position.
    wps = {
        s: (x, y, z)
        for s, (cmd, x, y, z, _) in items.items()
        if s > 0 and cmd == _MAV_NAV_WAYPOINT and (x != 0 or y != 0) and np.all(np.isfinite((x, y, z)))
    }
    speeds = [
        p2 for s, (cmd, *_, p2) in items.items() if cmd == _MAV_DO_CHANGE_SPEED and np.isfinite(p2) and p2 > 0
    ]
    cruise = speeds[0] if speeds else wpnav
    return flight_from_fixes(
        fixes, p, waypoints=wps, reached=reached, wind=wind, cruise_ms=cruise, decoder=decoder
    )


__all__ = ["IMU_TYPES", "read_tlog", "read_tlog_flight", "vz_down_sign"]
