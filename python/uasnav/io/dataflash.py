"""ArduPilot DataFlash (``.bin``) logs via pymavlink: every IMU, the flight telemetry, any message.

Time: ``TimeUS`` (µs, Copter ≥ 3.4) or ``TimeMS`` (ms, older logs), always returned in seconds.

IMUs (:func:`read_dataflash`): messages ``IMU``, ``IMU2``, ``IMU3`` (older logs) or ``IMU``
with an instance field ``I`` (newer logs); fields ``GyrX/Y/Z`` rad/s, ``AccX/Y/Z`` m/s²,
``Temp`` °C. Each IMU becomes its own :class:`~uasnav.imu.ImuLog`, keyed by ``"IMU"``,
``"IMU2"``, ``"IMU3"`` (or ``"IMU[i]"`` for instance-numbered logs). The messages are already
rotated into the vehicle body frame (FRD, as uasnav).

Flight (:func:`read_dataflash_flight`): ``GPS`` (position, speed, course, ``VZ``; fixes with
``Status`` ≥ 3), ``CMD`` (mission navigation waypoints), the ``MSG`` texts "Reached command #N"
and the EKF wind (``VWN``, ``VWE`` of ``XKF2``/``NKF2``/``EKF2``).

Any other message (``BARO``, ``MAG``, ``ATT`` …): :func:`read_dataflash_messages`.

Errors: a missing or unreadable file and an undecodable message are a
:class:`~uasnav.errors.DataFormatError` naming the file; an IMU message without a time or a
gyro/accelerometer field names the message and field. Messages without a time field are
skipped by the flight and message readers (old logs write ``MSG`` without one).
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uasnav.errors import DataFormatError
from uasnav.imu import ImuLog
from uasnav.io._common import build_log
from uasnav.io._mavlink import connect, messages
from uasnav.io.flight import FlightLog, flight_from_fixes

#: Message names of the IMUs in older logs (newer logs use ``IMU`` with an instance field ``I``).
IMU_TYPES = ("IMU", "IMU2", "IMU3")
_FLIGHT_TYPES = ("GPS", "CMD", "MSG", "XKF2", "NKF2", "EKF2")
_MAV_NAV_WAYPOINT = 16
_REACHED = re.compile(r"Reached (?:command|waypoint) #(\d+)")


def message_time_s(fields: Mapping[str, Any]) -> float | None:
    """Time of a DataFlash message (s) from ``TimeUS`` or ``TimeMS``; ``None`` if it has neither.

    Examples
    --------
    >>> message_time_s({"TimeUS": 1_500_000}), message_time_s({"TimeMS": 250}), message_time_s({})
    (1.5, 0.25, None)
    """
    if "TimeUS" in fields:
        return float(fields["TimeUS"] * 1e-6)
    if "TimeMS" in fields:
        return float(fields["TimeMS"] * 1e-3)
    return None


def read_dataflash(path: str | os.PathLike[str]) -> dict[str, ImuLog]:
    """Every IMU of an ArduPilot DataFlash log, keyed by message name (see the module docs).

    Exact duplicate time stamps are dropped (counted in ``meta["dropped_duplicates"]``);
    ``temp`` is ``None`` for an IMU without a finite ``Temp`` in every message.

    Raises
    ------
    DataFormatError
        Missing/unreadable file, corrupt message, no IMU message, an IMU message without a time
        or a gyro/accelerometer field, a non-finite value or time going backwards.
    """
    p = Path(path)
    conn = connect(p)
    rows: dict[str, list[tuple[float, ...]]] = {}
    for msg in messages(conn, IMU_TYPES, p, "DataFlash"):
        d = msg.to_dict()
        key = msg.get_type()
        if "I" in d and key == "IMU":
            key = f"IMU[{int(d['I'])}]"
        t = message_time_s(d)
        if t is None:
            raise DataFormatError(f"{key}: no TimeUS/TimeMS field", path=str(p), column=f"{key}.TimeUS")
        try:
            rows.setdefault(key, []).append(
                (t, d["GyrX"], d["GyrY"], d["GyrZ"], d["AccX"], d["AccY"], d["AccZ"], d.get("Temp", np.nan))
            )
        except KeyError as e:
            raise DataFormatError(
                f"{key}: missing field {e.args[0]!r}", path=str(p), column=f"{key}.{e.args[0]}"
            ) from None
    if not rows:
        raise DataFormatError("no IMU/IMU2/IMU3 messages", path=str(p))
    out = {}
    for key in sorted(rows):
        a = np.asarray(rows[key], dtype=np.float64)
        temp = a[:, 7] if np.all(np.isfinite(a[:, 7])) else None
        meta = {"source": str(p), "format": "ardupilot-dataflash", "message": key, "frame": "FRD"}
        out[key] = build_log(str(p), key, a[:, 0], a[:, 1:4], a[:, 4:7], temp, meta)
    return out


def read_dataflash_flight(path: str | os.PathLike[str]) -> FlightLog:
    """The flight telemetry of a DataFlash log (see the module docs for the messages).

    Times are the messages' own ``TimeUS``/``TimeMS`` in seconds (in Copter 3.3 logs the ``GPS``
    message's ``TimeMS`` is the GPS time of week).

    Raises
    ------
    DataFormatError
        Missing/unreadable file, corrupt message, or no GPS message with a 3D fix.
    """
    p = Path(path)
    conn = connect(p)
    fixes: list[tuple[float, ...]] = []
    wps: dict[int, tuple[float, float, float]] = {}
    reached: list[tuple[float, int]] = []
    wind: list[tuple[float, float]] = []
    for m in messages(conn, _FLIGHT_TYPES, p, "DataFlash"):
        kind = m.get_type()
        d = m.to_dict()
        ts = message_time_s(d)
        if ts is None:
            continue
        if kind == "GPS" and d.get("Status", 3) >= 3:
            crs = np.radians(d["GCrs"])
            fixes.append(
                (
                    ts,
                    d["Lat"],
                    d["Lng"],
                    d["Alt"],
                    d["Spd"] * np.cos(crs),
                    d["Spd"] * np.sin(crs),
                    d.get("VZ", 0.0),
                )
            )
        elif (
            kind == "CMD"
            and d["CId"] == _MAV_NAV_WAYPOINT
            and d["CNum"] > 0
            and (d["Lat"] != 0 or d["Lng"] != 0)
        ):
            wps[int(d["CNum"])] = (d["Lat"], d["Lng"], d["Alt"])
        elif kind == "MSG":
            hit = _REACHED.search(d["Message"])
            if hit:
                reached.append((ts, int(hit.group(1))))
        elif kind in ("XKF2", "NKF2", "EKF2") and "VWN" in d:
            wind.append((d["VWN"], d["VWE"]))
    if not fixes:
        raise DataFormatError("no GPS messages with a 3D fix", path=str(p))
    return flight_from_fixes(fixes, p, waypoints=wps, reached=reached, wind=wind)


def read_dataflash_messages(
    path: str | os.PathLike[str], types: Sequence[str]
) -> dict[str, dict[str, NDArray[np.float64]]]:
    """The numeric fields of the DataFlash messages ``types`` (e.g. ``["BARO", "MAG", "ATT"]``).

    Returns one table per message type found: field name → array (n,) float64, with ``"t"``
    the message time in seconds. Text fields are left out; so are messages without a time.

    Raises
    ------
    DataFormatError
        Missing/unreadable file or corrupt message.
    """
    p = Path(path)
    conn = connect(p)
    rows: dict[str, list[dict[str, Any]]] = {}
    for m in messages(conn, list(types), p, "DataFlash"):
        d = m.to_dict()
        t = message_time_s(d)
        if t is None:
            continue
        d.pop("mavpackettype", None)
        rows.setdefault(m.get_type(), []).append({"t": t, **d})
    out: dict[str, dict[str, NDArray[np.float64]]] = {}
    for kind, recs in rows.items():
        names = [
            k
            for k, v in recs[0].items()
            if isinstance(v, int | float | np.number) and not isinstance(v, bool)
        ]
        out[kind] = {k: np.array([r.get(k, np.nan) for r in recs], dtype=np.float64) for k in names}
    return out


__all__ = [
    "IMU_TYPES",
    "message_time_s",
    "read_dataflash",
    "read_dataflash_flight",
    "read_dataflash_messages",
]
