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

Corrupt logs: DataFlash records carry no checksum, so a flipped bit shows up as a bad header
(pymavlink then prints a line per bad byte, silenced here) or a bad value. Each reader keeps the
valid records, warns once with the counts (:class:`~uasnav.errors.CorruptDataWarning`) and
fails only when nothing valid is left.
"""

from __future__ import annotations

import datetime as dt
import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uasnav.errors import DataFormatError
from uasnav.imu import ImuLog
from uasnav.io._common import (
    because,
    build_log,
    corruption_meta,
    drop_sparse_streams,
    imu_limits,
    nothing_valid,
    report_corruption,
    salvage,
)
from uasnav.io._mavlink import messages, reading
from uasnav.io.flight import FIX_LIMITS, Flight, flight_from_fixes
from uasnav.io.views import gps_to_utc

#: Message names of the IMUs in older logs (newer logs use ``IMU`` with an instance field ``I``).
IMU_TYPES = ("IMU", "IMU2", "IMU3")
_FLIGHT_TYPES = ("GPS", "CMD", "MSG", "XKF2", "NKF2", "EKF2")
_MAV_NAV_WAYPOINT = 16
_REACHED = re.compile(r"Reached (?:command|waypoint) #(\d+)")
#: EKF wind estimates above this (m/s) are corrupt records.
_MAX_WIND_M_S = 100.0


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
    ``temp`` is ``None`` for an IMU without a finite ``Temp`` in most messages.

    A corrupt log (DataFlash has no checksums) is read as far as it is valid: records with time
    out of order, non-finite or implausible values (:func:`uasnav.io._common.salvage`) and
    instance streams of a few stray records are dropped, pymavlink's complaints are silenced,
    and one :class:`~uasnav.errors.CorruptDataWarning` gives the counts (also in each log's
    ``meta["corrupt_records_dropped"]`` and ``meta["corruption"]``).

    Raises
    ------
    DataFormatError
        Missing/unreadable file, corrupt message, no IMU message, an IMU message without a time
        or a gyro/accelerometer field, or fewer than 2 valid records in every IMU stream.
    """
    p = Path(path)
    rows: dict[str, list[tuple[float, ...]]] = {}
    with reading(p) as (conn, decoder):
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
                    (
                        t,
                        d["GyrX"],
                        d["GyrY"],
                        d["GyrZ"],
                        d["AccX"],
                        d["AccY"],
                        d["AccZ"],
                        d.get("Temp", np.nan),
                    )
                )
            except KeyError as e:
                raise DataFormatError(
                    f"{key}: missing field {e.args[0]!r}", path=str(p), column=f"{key}.{e.args[0]}"
                ) from None
    if not rows:
        raise DataFormatError(f"no IMU/IMU2/IMU3 messages{because(decoder)}", path=str(p))
    total = sum(len(r) for r in rows.values())
    # a corrupt instance number makes a "sensor" of a few records
    sparse = drop_sparse_streams({k: len(r) for k, r in rows.items()}) if len(rows) > 1 else []
    dropped = sum(len(rows.pop(k)) for k in sparse)
    kept: dict[str, tuple[np.ndarray, np.ndarray | None]] = {}
    for key in sorted(rows):
        a = np.asarray(rows[key], dtype=np.float64)
        has_temp = bool(np.mean(np.isfinite(a[:, 7])) > 0.5)
        values = {"gyro": a[:, 1:4], "accel": a[:, 4:7]}
        if has_temp:
            values["temp"] = a[:, 7]
        keep = salvage(a[:, 0], values, imu_limits(has_temp))
        dropped += int((~keep).sum())
        if keep.sum() >= 2:
            kept[key] = (a[keep], a[keep, 7] if has_temp else None)
    if not kept:
        raise nothing_valid(str(p), "IMU", total, decoder)
    report_corruption(str(p), decoder, dropped, total, "IMU")
    out = {}
    for key, (a, temp) in kept.items():
        meta = {"source": str(p), "format": "ardupilot-dataflash", "message": key, "frame": "FRD"}
        meta.update(corruption_meta(decoder, dropped))
        out[key] = build_log(str(p), key, a[:, 0], a[:, 1:4], a[:, 4:7], temp, meta)
    return out


def _field(d: Mapping[str, Any], kind: str, name: str, p: Path) -> Any:
    try:
        return d[name]
    except KeyError:
        raise DataFormatError(
            f"{kind}: missing field {name!r}", path=str(p), column=f"{kind}.{name}"
        ) from None


def read_dataflash_flight(path: str | os.PathLike[str]) -> Flight:
    """The flight telemetry of a DataFlash log (see the module docs for the messages).

    Times are the messages' own ``TimeUS``/``TimeMS`` in seconds (in Copter 3.3 logs the ``GPS``
    message's ``TimeMS`` is the GPS time of week). A corrupt log is read as far as it is valid
    (corrupt fixes, waypoints and wind records are dropped; one
    :class:`~uasnav.errors.CorruptDataWarning` gives the counts).

    Raises
    ------
    DataFormatError
        Missing/unreadable file, corrupt message, a GPS/CMD message without a needed field, or
        fewer than 2 valid GPS messages with a 3D fix.
    """
    p = Path(path)
    fixes: list[tuple[float, ...]] = []
    wps: dict[int, tuple[float, float, float]] = {}
    reached: list[tuple[float, int]] = []
    wind: list[tuple[float, float]] = []
    lat_lo, lat_hi = FIX_LIMITS["lat"]
    lon_lo, lon_hi = FIX_LIMITS["lon"]
    with reading(p) as (conn, decoder):
        for m in messages(conn, _FLIGHT_TYPES, p, "DataFlash"):
            kind = m.get_type()
            d = m.to_dict()
            ts = message_time_s(d)
            if ts is None:
                continue
            if kind == "GPS" and d.get("Status", 3) >= 3:
                crs = np.radians(_field(d, kind, "GCrs", p))
                spd = _field(d, kind, "Spd", p)
                fixes.append(
                    (
                        ts,
                        _field(d, kind, "Lat", p),
                        _field(d, kind, "Lng", p),
                        _field(d, kind, "Alt", p),
                        spd * np.cos(crs),
                        spd * np.sin(crs),
                        d.get("VZ", 0.0),
                    )
                )
            elif kind == "CMD" and d.get("CId") == _MAV_NAV_WAYPOINT and d.get("CNum", 0) > 0:
                lat, lon, alt = (_field(d, kind, k, p) for k in ("Lat", "Lng", "Alt"))
                # (0, 0) is "no position"; outside the globe or non-finite is a corrupt record
                if (lat != 0 or lon != 0) and lat_lo <= lat <= lat_hi and lon_lo <= lon <= lon_hi:
                    if np.isfinite(alt):
                        wps[int(d["CNum"])] = (lat, lon, alt)
            elif kind == "MSG":
                hit = _REACHED.search(str(d.get("Message", "")))
                if hit:
                    reached.append((ts, int(hit.group(1))))
            elif kind in ("XKF2", "NKF2", "EKF2") and "VWN" in d:
                vw = (float(d["VWN"]), float(d.get("VWE", np.nan)))
                if np.all(np.isfinite(vw)) and np.hypot(*vw) <= _MAX_WIND_M_S:
                    wind.append(vw)
    if not fixes:
        raise DataFormatError(f"no GPS messages with a 3D fix{because(decoder)}", path=str(p))
    return flight_from_fixes(fixes, p, waypoints=wps, reached=reached, wind=wind, decoder=decoder)


def read_dataflash_messages(
    path: str | os.PathLike[str], types: Sequence[str]
) -> dict[str, dict[str, NDArray[np.float64]]]:
    """The numeric fields of the DataFlash messages ``types`` (e.g. ``["BARO", "MAG", "ATT"]``).

    Returns one table per message type found: field name → array (n,) float64, with ``"t"``
    the message time in seconds. Text fields are left out; so are messages without a time.
    In a corrupt log, records whose time is out of order are dropped (one
    :class:`~uasnav.errors.CorruptDataWarning` gives the count); other values are returned
    as logged (NaN is a legitimate value of some fields).

    Raises
    ------
    DataFormatError
        Missing/unreadable file or corrupt message.
    """
    p = Path(path)
    rows: dict[str, list[dict[str, Any]]] = {}
    with reading(p) as (conn, decoder):
        for m in messages(conn, list(types), p, "DataFlash"):
            d = m.to_dict()
            t = message_time_s(d)
            if t is None:
                continue
            d.pop("mavpackettype", None)
            rows.setdefault(m.get_type(), []).append({"t": t, **d})
    out: dict[str, dict[str, NDArray[np.float64]]] = {}
    dropped = total = 0
    for kind, recs in rows.items():
        names = [
            k
            for k, v in recs[0].items()
            if isinstance(v, int | float | np.number) and not isinstance(v, bool)
        ]
        table = {k: np.array([_number(r.get(k)) for r in recs], dtype=np.float64) for k in names}
        keep = salvage(table["t"], {})
        total += keep.size
        dropped += int((~keep).sum())
        out[kind] = {k: v[keep] for k, v in table.items()}
    report_corruption(str(p), decoder, dropped, total, "message")
    return out


def _number(v: Any) -> float:
    """A field value as float; NaN for a missing or non-numeric one (a corrupt record)."""
    if isinstance(v, int | float | np.number) and not isinstance(v, bool):
        return float(v)
    return float("nan")


#: A board's identity line in ``MSG`` (e.g. ``PX4v2 004A002F 33345119 32383433``: board and the
#: processor's 96-bit unique id), logged at every boot by ArduPilot.
_BOARD_ID = re.compile(r"^\S+ [0-9A-F]{8} [0-9A-F]{8} [0-9A-F]{8}$")


def read_dataflash_identity(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The vehicle identity and clock of a DataFlash log, where it carries them.

    Returns a dict with ``vehicle`` (the board identity line of ``MSG``, board name and unique
    processor id) and ``boot_utc`` (UTC :class:`datetime.datetime` of boot time 0, from the
    first ``GPS`` message with a 3-D fix and a GPS week: ``GWk``/``GMS`` or, in old logs,
    ``Week``/``TimeMS``, minus its boot time ``TimeUS``/``T``) with ``leap_seconds`` (GPS − UTC
    applied, :func:`uasnav.io.views.gps_to_utc`); keys are absent when the log lacks them.
    """
    p = Path(path)
    out: dict[str, Any] = {}
    with reading(p) as (conn, _decoder):
        for m in messages(conn, ("MSG", "GPS"), p, "DataFlash"):
            d = m.to_dict()
            if m.get_type() == "MSG":
                text = str(d.get("Message", "")).strip()
                if "vehicle" not in out and _BOARD_ID.match(text):
                    out["vehicle"] = text
            elif "boot_utc" not in out and d.get("Status", 0) >= 3:
                week, ms = (d.get("GWk"), d.get("GMS")) if "GWk" in d else (d.get("Week"), d.get("TimeMS"))
                boot_s = d["TimeUS"] * 1e-6 if "TimeUS" in d else (d["T"] * 1e-3 if "T" in d else None)
                if week and ms is not None and boot_s is not None:
                    utc, leap = gps_to_utc(int(week), float(ms))
                    out["boot_utc"] = utc - dt.timedelta(seconds=boot_s)
                    out["leap_seconds"] = leap
            if len(out) == 3:
                break
    return out


__all__ = [
    "IMU_TYPES",
    "message_time_s",
    "read_dataflash",
    "read_dataflash_flight",
    "read_dataflash_identity",
    "read_dataflash_messages",
]
