"""ArduPilot DataFlash (``.bin``) through pymavlink: one pass per command for the message types
its views need.

Views and their messages (:attr:`DataflashFormat.SOURCES`):

- ``imus`` (:func:`read_dataflash`): ``IMU``, ``IMU2``, ``IMU3`` (older logs) or ``IMU`` with an
  instance field ``I`` (newer logs); ``GyrX/Y/Z`` rad/s, ``AccX/Y/Z`` m/s², ``Temp`` °C, keyed
  ``"IMU"``, ``"IMU2"``, ``"IMU3"`` (or ``"IMU[i]"``); already in the body frame (FRD).
- ``nav`` (:func:`read_dataflash_nav`): ``GPS``, ``BARO``, ``MAG``, the EKF (``XKF1``/``NKF1``/
  ``EKF1``, ``AHR2``, ``ATT``, origin ``ORGN``).
- ``flight`` (:func:`read_dataflash_flight`): ``GPS`` (position, speed, course, ``VZ``; fixes
  with ``Status`` ≥ 3), ``CMD`` (mission navigation waypoints), the ``MSG`` texts "Reached
  command #N" and the EKF wind (``VWN``, ``VWE`` of ``XKF2``/``NKF2``/``EKF2``).
- ``plan`` (``CMD``), ``params``/``limits`` (``PARM``), ``modes`` (``MODE``), ``identity``
  (``MSG`` firmware and board lines, ``GPS`` week); any other message:
  :func:`read_dataflash_messages`.

Time: ``TimeUS`` (µs, Copter ≥ 3.4) or ``TimeMS`` (ms, older logs), always in seconds.

Format rules kept here: the GPS delay (fix times moved back by :data:`ARDUPILOT_GPS_DELAY_S`),
accuracies from HDOP, the EKF origin (``ORGN``), the declination parameter (``COMPASS_DEC``
used only with ``COMPASS_AUTODEC`` 0) and the height datum (AMSL: ``GPS.Alt`` and ``ORGN.Alt``
are both above mean sea level as the receiver models it).

Errors and corrupt logs: a missing or unreadable file and an undecodable message are a
:class:`~uasnav.errors.DataFormatError` naming the file; an IMU message without a time or a
gyro/accelerometer field names the message and field; messages without a time field are
skipped by the flight and message readers (old logs write ``MSG`` without one). DataFlash
records carry no checksum: each reader keeps the valid records, warns once with the counts
(:class:`~uasnav.errors.CorruptDataWarning`) and fails only when nothing valid is left.
"""

from __future__ import annotations

import datetime as dt
import math
import os
import re
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from uasnav.errors import DataFormatError, InputError
from uasnav.geo.datum import HeightDatum
from uasnav.geo.frames import ned_to_geodetic
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
from uasnav.io.flight import (
    FIX_LIMITS,
    BaroData,
    Flight,
    GnssData,
    MagData,
    Trajectory,
    flight_from_fixes,
    strictly_increasing,
)
from uasnav.io.formats._scan import MavlinkScan
from uasnav.io.formats.base import ScannedFormat
from uasnav.io.plan_formats.logs import read_dataflash_plan
from uasnav.io.views import Identity, ModeTimeline, changes, gps_to_utc

FloatArray = NDArray[np.float64]

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


#: The messages of the navigation data.
NAV_TYPES = ("GPS", "BARO", "MAG", "XKF1", "NKF1", "EKF1", "AHR2", "ATT", "ORGN")
#: ArduCopter's mode numbers (``MODE.Mode``).
COPTER_MODES = {
    0: "STABILIZE", 1: "ACRO", 2: "ALT_HOLD", 3: "AUTO", 4: "GUIDED", 5: "LOITER", 6: "RTL",
    7: "CIRCLE", 9: "LAND", 11: "DRIFT", 13: "SPORT", 14: "FLIP", 15: "AUTOTUNE", 16: "POSHOLD",
    17: "BRAKE", 18: "THROW", 19: "AVOID_ADSB", 20: "GUIDED_NOGPS", 21: "SMART_RTL",
}  # fmt: skip
_FIRMWARE = re.compile(r"^(?:APM:|Ardu)(\w+) V(\d+\.\d+(?:\.\d+)?\S*)(?: \((\w+)\))?")
#: A board's identity line in ``MSG`` (e.g. ``PX4v2 004A002F 33345119 32383433``: board and the
#: processor's 96-bit unique id), logged at every boot by ArduPilot.
_BOARD_ID = re.compile(r"^(\S+) ([0-9A-F]{8} [0-9A-F]{8} [0-9A-F]{8})$")


#: ArduPilot's GPS message has no accuracy fields in older logs: σ_H = HDOP × this UERE (m),
#: σ_V = 1.5 σ_H, and the speed accuracy below. Stated, not measured: a u-blox receiver with
#: HDOP ≈ 1.5 typically reaches 1–3 m.
ARDUPILOT_UERE_M = 1.0
ARDUPILOT_SPEED_ACC_M_S = 0.3
#: ArduPilot logs a GPS message when it arrives; the fix is valid this long before (s): the
#: autopilot's own default ``EKF_GPS_DELAY`` / ``GPS_DELAY_MS`` of 220 ms.
ARDUPILOT_GPS_DELAY_S = 0.22


def _pick(
    tables: dict[str, dict[str, FloatArray]], names: tuple[str, ...]
) -> tuple[str, dict[str, FloatArray]] | None:
    for n in names:
        if n in tables and tables[n]["t"].size >= 2:
            return n, tables[n]
    return None


def _declination_meta(path: Any, gp: dict[str, FloatArray], first: int) -> dict[str, Any]:
    """``declination_deg``/``declination_source`` from ``PARM`` ``COMPASS_DEC`` (radians) when
    the autopilot used it (``COMPASS_AUTODEC`` 0: with auto-declination on it takes its own
    table's value at run time and the logged parameter is not that value), and ``utc_year``
    (decimal year) from the ``GPS`` week and time of week of fix ``first``."""
    from uasnav.io.gpstime import decimal_year, gps_week_ms_to_utc

    p = Path(path)
    params: dict[str, float] = {}
    with reading(p) as (conn, _):
        for m in messages(conn, ["PARM"], p, "DataFlash"):
            name = str(m.Name).rstrip("\x00")
            if name in ("COMPASS_DEC", "COMPASS_AUTODEC"):
                params[name] = float(m.Value)  # the last value logged wins
    meta: dict[str, Any] = {}
    dec = params.get("COMPASS_DEC")
    if dec is not None and math.isfinite(dec) and params.get("COMPASS_AUTODEC", 0.0) == 0.0:
        meta["declination_deg"] = math.degrees(dec)
        meta["declination_source"] = "log: PARM COMPASS_DEC (COMPASS_AUTODEC = 0)"
    week = gp.get("GWk", gp.get("Week"))
    tow = gp.get("GMS", gp.get("TimeMS"))
    if week is not None and tow is not None:
        w, ms = float(week[first]), float(tow[first])
        if math.isfinite(w) and math.isfinite(ms) and 1000 < w < 10000 and 0 <= ms < 604_800_000:
            meta["utc_year"] = decimal_year(gps_week_ms_to_utc(w, ms))
    return meta


def read_dataflash_nav(path: str | Any, imu: str | None = None) -> Flight:
    """Navigation data of an ArduPilot DataFlash log: every IMU (``IMU``/``IMU2``/``IMU3``
    with temperature), ``GPS`` (fixes with ``Status`` ≥ 3; time from its ``T`` field, the
    log clock, when ``TimeMS`` is GPS time of week), ``BARO`` (``Alt``), ``MAG`` (field minus
    nothing: the logged ``MagX/Y/Z`` are already offset-corrected), and the autopilot's
    estimate from ``XKF1``/``NKF1``/``EKF1`` (``PN/PE/PD`` from the origin, taken as the first
    3-D fix, ``VN/VE/VD``, ``Roll/Pitch/Yaw``), else ``AHR2``.

    Heights are AMSL throughout: the GPS ``Alt`` (the receiver's AMSL; the message carries no
    ellipsoidal height) and the estimate from the EKF origin ``ORGN`` (AMSL) when logged, else
    the first 3-D fix. Accuracies from HDOP (see
    :data:`ARDUPILOT_UERE_M`); fix times moved back by the GPS delay
    (:data:`ARDUPILOT_GPS_DELAY_S`).

    Raises
    ------
    DataFormatError
        No IMU, no GPS message, or fewer than 2 fixes with ``Status`` ≥ 3 (named).
    """
    imus = read_dataflash(path)
    tables = read_dataflash_messages(path, NAV_TYPES)
    if "GPS" not in tables:
        raise DataFormatError(
            "no GPS message: the GNSS/INS filter needs GNSS fixes", path=str(path), column="GPS"
        )
    gp = tables["GPS"]
    t_field = "T" if "T" in gp and np.all(np.isfinite(gp["T"])) and gp["T"].max() > 0 else None
    t = gp["T"] * 1e-3 if t_field else gp["t"]
    status = gp.get("Status", np.full(t.size, 3.0))
    ok = (status >= 3) & np.isfinite(gp["Lat"]) & np.isfinite(gp["Lng"]) & (np.abs(gp["Lat"]) > 1e-6)
    t, ok = t[ok], np.flatnonzero(ok)
    keep = strictly_increasing(t)
    t, ok = t[keep], ok[keep]
    if t.size < 2:
        raise DataFormatError(
            "GPS: fewer than 2 fixes with Status >= 3 (3-D fix)", path=str(path), column="GPS.Status"
        )
    spd, crs = gp["Spd"][ok], np.radians(gp["GCrs"][ok])
    vz = gp["VZ"][ok] if "VZ" in gp else np.zeros(t.size)
    hdop = gp["HDop"][ok] if "HDop" in gp else np.full(t.size, 1.5)
    h_acc = np.maximum(np.nan_to_num(hdop, nan=5.0), 0.5) * ARDUPILOT_UERE_M
    gnss = GnssData(
        t - ARDUPILOT_GPS_DELAY_S,
        gp["Lat"][ok],
        gp["Lng"][ok],
        gp["Alt"][ok],
        np.column_stack([spd * np.cos(crs), spd * np.sin(crs), vz]),
        h_acc,
        1.5 * h_acc,
        np.full(t.size, ARDUPILOT_SPEED_ACC_M_S),
        alt_datum=HeightDatum.AMSL,
    )
    baro = None
    if "BARO" in tables and tables["BARO"]["t"].size >= 2:
        b = tables["BARO"]
        k = strictly_increasing(b["t"]) & np.isfinite(b["Alt"])
        baro = BaroData(b["t"][k], b["Alt"][k])
    mag = None
    if "MAG" in tables and tables["MAG"]["t"].size >= 2:
        m = tables["MAG"]
        k = strictly_increasing(m["t"])
        fld = np.column_stack([m["MagX"], m["MagY"], m["MagZ"]])[k]
        k2 = np.all(np.isfinite(fld), axis=1) & (np.linalg.norm(fld, axis=1) > 0)
        mag = MagData(m["t"][k][k2], fld[k2])
    ref = None
    ekf = _pick(tables, ("XKF1", "NKF1", "EKF1"))
    if ekf is not None:
        name, e = ekf
        lat0, lon0, alt0 = float(gnss.lat[0]), float(gnss.lon[0]), float(gnss.alt[0])
        origin = "first 3-D fix"
        og = tables.get("ORGN")
        if og is not None and {"Lat", "Lng", "Alt"} <= set(og):
            # the EKF origin as the autopilot logged it (Type 0; Type 1 is the home position)
            k0 = np.flatnonzero((og.get("Type", np.zeros(og["t"].size)) == 0) & (np.abs(og["Lat"]) > 1e-6))
            if k0.size:
                lat0, lon0, alt0 = (float(og[f][k0[-1]]) for f in ("Lat", "Lng", "Alt"))
                origin = "ORGN"
        k = strictly_increasing(e["t"])
        lat, lon, alt = ned_to_geodetic(e["PN"][k], e["PE"][k], e["PD"][k], lat0, lon0, alt0)
        ref = Trajectory(
            e["t"][k],
            np.asarray(lat, dtype=np.float64),
            np.asarray(lon, dtype=np.float64),
            np.asarray(alt, dtype=np.float64),
            np.column_stack([e["VN"], e["VE"], e["VD"]])[k],
            np.column_stack([e["Roll"], e["Pitch"], e["Yaw"]])[k],
            name=f"ArduPilot EKF ({name}; origin = {origin})",
            alt_datum=HeightDatum.AMSL,
        )
    elif "AHR2" in tables:
        a = tables["AHR2"]
        k = strictly_increasing(a["t"]) & (np.abs(a["Lat"]) > 1e-6)
        if k.sum() >= 2:
            ref = Trajectory(
                a["t"][k],
                a["Lat"][k],
                a["Lng"][k],
                a["Alt"][k],
                None,
                np.column_stack([a["Roll"], a["Pitch"], a["Yaw"]])[k],
                name="ArduPilot AHR2",
                alt_datum=HeightDatum.AMSL,
            )
    key = imu or next(iter(imus))
    if key not in imus:
        raise InputError(f"imu: {key!r} not in the log (has {', '.join(imus)})")
    return Flight(
        imus[key],
        gnss,
        baro,
        mag,
        reference=ref,
        imus=imus,
        meta={
            "source": str(path),
            "format": "ardupilot-dataflash",
            "imu": key,
            **_declination_meta(path, gp, int(ok[0])),
        },
    )


class DataflashFormat(ScannedFormat):
    """ArduPilot DataFlash (see the module docs)."""

    name = "ardupilot-dataflash"
    SCANNER = MavlinkScan
    SOURCES: ClassVar[dict[str, tuple[str, ...]]] = {
        "imus": IMU_TYPES,
        "imu": IMU_TYPES,
        "nav": (*IMU_TYPES, *NAV_TYPES, "PARM"),
        "flight": ("GPS", "CMD", "MSG", "XKF2", "NKF2", "EKF2"),
        "plan": ("CMD",),
        "params": ("PARM",),
        "limits": ("PARM",),
        "modes": ("MODE", "MSG"),
        "identity": ("MSG", "GPS"),
    }
    READERS: ClassVar[dict[str, Callable[[Path], Any]]] = {
        "imus": read_dataflash,
        "nav": read_dataflash_nav,
        "flight": read_dataflash_flight,
        "plan": read_dataflash_plan,
    }

    def build_params(self) -> dict[str, float]:
        out: dict[str, float] = {}
        with reading(self.path) as (conn, _):
            for m in messages(conn, ["PARM"], self.path, "DataFlash"):
                out[str(m.Name).rstrip("\x00")] = float(m.Value)  # the last value logged wins
        return out

    def _texts(self) -> list[str]:
        with reading(self.path) as (conn, _):
            msgs = messages(conn, ["MSG"], self.path, "DataFlash")
            return [str(m.to_dict().get("Message", "")).strip() for m in msgs]

    def build_modes(self) -> ModeTimeline:
        copter = any(_vehicle(s) == "Copter" for s in self._texts())
        modes = read_dataflash_messages(self.path, ["MODE"]).get("MODE")
        if modes is None or "Mode" not in modes:
            return ModeTimeline(np.zeros(0), (), "MODE")
        names = [
            (COPTER_MODES.get(int(m), f"MODE_{int(m)}") if copter else f"MODE_{int(m)}")
            for m in modes["Mode"]
        ]
        return changes(modes["t"], names, "MODE.Mode")

    def build_identity(self) -> Identity:
        fields: dict[str, Any] = {"autopilot": "ArduPilot", "clock": "boot"}
        for text in self._texts():
            fw = _FIRMWARE.match(text)
            if fw and "firmware_version" not in fields:
                fields["vehicle_type"] = "Ardu" + fw.group(1)
                fields["firmware_version"] = fw.group(2)
                if fw.group(3):
                    fields["firmware_git"] = fw.group(3)
            board = _BOARD_ID.match(text)
            if board and "board" not in fields:
                fields["board"], fields["vehicle_id"] = board.group(1), board.group(2)
        ident = read_dataflash_identity(self.path)
        if "boot_utc" in ident:
            fields["utc_at_zero"] = ident["boot_utc"]
            fields["leap_seconds"] = ident.get("leap_seconds")
        return Identity(**fields)


def _vehicle(text: str) -> str | None:
    fw = _FIRMWARE.match(text)
    return None if fw is None else fw.group(1)


__all__ = [
    "ARDUPILOT_GPS_DELAY_S",
    "ARDUPILOT_SPEED_ACC_M_S",
    "ARDUPILOT_UERE_M",
    "IMU_TYPES",
    "DataflashFormat",
    "message_time_s",
    "read_dataflash",
    "read_dataflash_flight",
    "read_dataflash_identity",
    "read_dataflash_messages",
    "read_dataflash_nav",
]
