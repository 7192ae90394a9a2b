"""ArduPilot DataFlash (``.bin``) and MAVLink telemetry (``.tlog``) readers via pymavlink.

DataFlash: messages ``IMU``, ``IMU2``, ``IMU3`` (older logs) or ``IMU`` with an instance
field ``I`` (newer logs); fields ``GyrX/Y/Z`` rad/s, ``AccX/Y/Z`` m/s², ``Temp`` °C, time
``TimeUS`` µs (or ``TimeMS`` ms). Each IMU becomes its own :class:`ImuLog`, keyed by
``"IMU"``, ``"IMU2"``, ``"IMU3"`` (or ``"IMU[i]"`` for instance-numbered logs).

MAVLink tlog: ``HIGHRES_IMU`` (SI), ``SCALED_IMU``/``SCALED_IMU2``/``SCALED_IMU3`` and
``RAW_IMU`` as sent by ArduPilot (acceleration mg → m/s², rate mrad/s → rad/s, temperature
cdegC when present and non-zero), time ``time_usec`` or ``time_boot_ms``.
A telemetry log can span autopilot reboots (boot time restarts): each stream is split there
and later parts are keyed ``"SCALED_IMU2#2"`` … Frame: ArduPilot body FRD, as uasnav.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from uasnav.errors import DataFormatError
from uasnav.imu import ImuLog
from uasnav.io._common import build_log
from uasnav.units import STANDARD_GRAVITY

_DF_TYPES = ["IMU", "IMU2", "IMU3"]
_TLOG_TYPES = ["HIGHRES_IMU", "SCALED_IMU", "SCALED_IMU2", "SCALED_IMU3", "RAW_IMU"]


def _connect(p: Path, **kw: Any) -> Any:
    from pymavlink import mavutil

    if not p.is_file():
        raise DataFormatError("no such file", path=str(p))
    try:
        return mavutil.mavlink_connection(str(p), **kw)
    except Exception as e:  # pymavlink raises many exception types on bad input
        raise DataFormatError(f"not readable by pymavlink ({type(e).__name__}: {e})", path=str(p)) from None


def read_dataflash(path: str | os.PathLike[str]) -> dict[str, ImuLog]:
    """Every IMU of an ArduPilot DataFlash log, keyed by message name (see module docs)."""
    p = Path(path)
    conn = _connect(p)
    rows: dict[str, list[tuple[float, ...]]] = {}
    while True:
        try:
            msg = conn.recv_match(type=_DF_TYPES)
        except Exception as e:
            raise DataFormatError(
                f"corrupt DataFlash message ({type(e).__name__}: {e})", path=str(p)
            ) from None
        if msg is None:
            break
        d = msg.to_dict()
        key = msg.get_type()
        if "I" in d and key == "IMU":
            key = f"IMU[{int(d['I'])}]"
        if "TimeUS" in d:
            t = d["TimeUS"] * 1e-6
        elif "TimeMS" in d:
            t = d["TimeMS"] * 1e-3
        else:
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


def read_tlog(path: str | os.PathLike[str]) -> dict[str, ImuLog]:
    """Every IMU message stream of a MAVLink telemetry log, keyed by message name."""
    p = Path(path)
    conn = _connect(p, dialect="ardupilotmega")
    rows: dict[str, list[tuple[float, ...]]] = {}
    while True:
        try:
            msg = conn.recv_match(type=_TLOG_TYPES)
        except Exception as e:
            raise DataFormatError(f"corrupt MAVLink message ({type(e).__name__}: {e})", path=str(p)) from None
        if msg is None:
            break
        key = msg.get_type()
        d = msg.to_dict()
        t = d["time_usec"] * 1e-6 if "time_usec" in d else d["time_boot_ms"] * 1e-3
        if key == "HIGHRES_IMU":
            row = (t, d["xgyro"], d["ygyro"], d["zgyro"], d["xacc"], d["yacc"], d["zacc"], d["temperature"])
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
        raise DataFormatError(f"no IMU messages ({', '.join(_TLOG_TYPES)})", path=str(p))
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
            }
            out[name] = build_log(str(p), name, seg[:, 0], seg[:, 1:4], seg[:, 4:7], temp, meta)
    return out


__all__ = ["read_dataflash", "read_tlog"]
