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
naming the file. ULog records carry no checksum: the readers drop corrupt records (time out of
order, non-finite or implausible values), silence pyulog's notices (it prints them to stdout)
and warn once with the counts (:class:`~uasnav.errors.CorruptDataWarning`).
"""

from __future__ import annotations

import datetime as dt
import os
from pathlib import Path
from typing import Any

import numpy as np

from uasnav.errors import DataFormatError
from uasnav.imu import ImuLog
from uasnav.io._active import lookup
from uasnav.io._common import (
    TEMP_RANGE_C,
    build_log,
    corruption_meta,
    imu_limits,
    nothing_valid,
    report_corruption,
    salvage,
)
from uasnav.io._quiet import LibraryOutput, library_output_captured
from uasnav.io.flight import Flight, flight_from_fixes

#: |magnetic field| above which a record is corrupt, µT (sensors saturate near ±5000 µT).
MAX_MAG_UT = 10_000.0
#: Wind estimates above this (m/s) are corrupt records.
MAX_WIND_M_S = 100.0


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


def parse_ulog(p: Path, topics: list[str] | None = None) -> tuple[Any, LibraryOutput]:
    """The ULog ``p`` parsed by pyulog (only ``topics`` when given: its
    ``message_name_filter_list``) and what pyulog printed meanwhile (its corruption notices go
    to stdout, which must stay clean for ``--json``).

    Raises
    ------
    DataFormatError
        Missing file, not a regular file (a device or FIFO), or not a ULog pyulog can parse.
    """
    from pyulog import ULog

    if not p.exists():
        raise DataFormatError("no such file", path=str(p))
    if not p.is_file():
        raise DataFormatError("not a regular file", path=str(p))  # a device or FIFO
    ulog = None
    failure: Exception | None = None
    with library_output_captured() as decoder:
        try:
            ulog = ULog(str(p), message_name_filter_list=topics)
        except Exception as e:  # pyulog raises bare exceptions on corrupt headers
            failure = e
    if ulog is None:
        raise DataFormatError(
            f"not a readable ULog ({type(failure).__name__}: {failure})", path=str(p)
        ) from None
    if getattr(ulog, "file_corruption", False) and not decoder.lines:
        decoder.note("pyulog detected file corruption")
    return ulog, decoder


def _open(p: Path, topics: list[str] | None = None) -> tuple[Any, LibraryOutput]:
    """The parsed ULog ``p``: the active scan's (:mod:`uasnav.io.formats._scan`) when there is
    one, else a fresh parse of ``topics`` (None: every topic)."""
    scan = lookup(p)
    if scan is not None and hasattr(scan, "ulog"):
        return scan.ulog, scan.decoder
    return parse_ulog(p, topics)


def _no_topic(ulog: Any, decoder: LibraryOutput, what: str, sp: str) -> DataFormatError:
    names = sorted({d.name for d in ulog.data_list})
    if not names and decoder.problems:
        return DataFormatError(f"corrupt ULog: no topic could be read ({decoder.summary()})", path=sp)
    return DataFormatError(f"no {what} topic (topics: {', '.join(names) or 'none'})", path=sp)


def _temperature(
    ulog: Any, sc: Any | None, t: np.ndarray, meta: dict[str, Any]
) -> tuple[np.ndarray | None, int]:
    """Temperature (°C) on the IMU time stamps ``t`` (see the module docs), and the number of
    corrupt temperature records dropped."""
    lo, hi = TEMP_RANGE_C
    for name, field in (("sensor_gyro", "temperature"), ("sensor_accel", "temperature")):
        d = _dataset(ulog, name)
        if d is not None and field in d.data:
            temp_t = np.asarray(d.data["timestamp"], dtype=np.float64) * 1e-6
            temp = np.asarray(d.data[field], dtype=np.float64)
            keep = salvage(temp_t, {"temp": temp}, {"temp": (lo, hi)})
            if keep.sum() < 2:
                continue  # nothing valid: try the next source
            meta["temperature_source"] = f"{name}.{field}"
            return np.interp(t, temp_t[keep], temp[keep]), int((~keep).sum())
    if sc is not None and np.any(np.asarray(sc.data.get("baro_temp_celcius", [0.0])) != 0):
        # logged as exactly 0 when the barometer did not report: treat as absent
        meta["temperature_source"] = "sensor_combined.baro_temp_celcius"
        return np.asarray(sc.data["baro_temp_celcius"], dtype=np.float64), 0
    return None, 0


def read_ulog(path: str | os.PathLike[str]) -> ImuLog:
    """Read the primary IMU of a PX4 ULog (see the module docs for topics and units).

    A corrupt log (ULog records carry no checksum) is read as far as it is valid: records with
    time out of order, non-finite or implausible values are dropped, pyulog's notices are
    silenced, and one :class:`~uasnav.errors.CorruptDataWarning` gives the counts (also in
    ``meta["corrupt_records_dropped"]``, ``meta["corruption"]``).

    Raises
    ------
    DataFormatError
        Missing/unreadable file, no IMU topic, a missing field, or fewer than 2 valid records.
    """
    p = Path(path)
    ulog, decoder = _open(p)
    sp = str(p)
    meta: dict[str, Any] = {"source": sp, "format": "px4-ulog", "frame": "FRD"}
    # the flight controller's identity when the log records it (uasnav.fleet partitions by it)
    info = getattr(ulog, "msg_info_dict", None) or {}
    meta.update(
        {k: str(info[i]) for k, i in (("vehicle", "sys_uuid"), ("hardware", "ver_hw")) if info.get(i)}
    )
    start = _start_utc(ulog)
    if start is not None:
        meta["start_time"] = start
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
            raise _no_topic(ulog, decoder, "sensor_combined or vehicle_imu", sp)
        t = np.asarray(vi.data["timestamp"], dtype=np.float64) * 1e-6
        dt_a = np.asarray(vi.data["delta_angle_dt"], dtype=np.float64) * 1e-6
        dt_v = np.asarray(vi.data["delta_velocity_dt"], dtype=np.float64) * 1e-6
        with np.errstate(divide="ignore", invalid="ignore"):
            # a non-positive integration interval is a corrupt record: NaN, dropped below
            gyro = _cols(vi, "delta_angle", sp) / np.where(dt_a > 0, dt_a, np.nan)[:, None]
            accel = _cols(vi, "delta_velocity", sp) / np.where(dt_v > 0, dt_v, np.nan)[:, None]
        topic = "vehicle_imu"
    values = {"gyro": gyro, "accel": accel}
    limits = imu_limits(False)
    if mag is not None:
        values["mag"] = mag
        limits["mag"] = (-MAX_MAG_UT, MAX_MAG_UT)
    keep = salvage(t, values, limits)
    if keep.sum() < 2:
        raise nothing_valid(sp, topic, t.size, decoder)
    dropped = int((~keep).sum())
    t, gyro, accel = t[keep], gyro[keep], accel[keep]
    mag = None if mag is None else mag[keep]
    temp, temp_dropped = _temperature(ulog, sc, t, meta)
    if temp is not None and temp.shape != t.shape:  # baro_temp_celcius: one per IMU record
        temp = temp[keep]
    if temp is not None and not np.all(np.isfinite(temp)):
        temp, _ = None, meta.pop("temperature_source", None)
    report_corruption(sp, decoder, dropped + temp_dropped, keep.size, topic)
    meta["topic"] = topic
    meta.update(corruption_meta(decoder, dropped + temp_dropped))
    return build_log(sp, topic, t, gyro, accel, temp, meta, mag=mag)


def _start_utc(ulog: Any) -> str | None:
    """UTC (ISO 8601) of the log's start from the first GNSS record with a UTC time, or None."""
    g = _dataset(ulog, "vehicle_gps_position") or _dataset(ulog, "sensor_gps")
    if g is None or "time_utc_usec" not in g.data:
        return None
    utc = np.asarray(g.data["time_utc_usec"], dtype=np.float64)
    k = np.flatnonzero(utc > 946_684_800e6)  # after 2000: a real UTC time
    if not k.size:
        return None
    i = int(k[0])
    t0 = float(utc[i] - (float(g.data["timestamp"][i]) - float(ulog.start_timestamp))) * 1e-6
    return dt.datetime.fromtimestamp(t0, tz=dt.timezone.utc).isoformat(timespec="milliseconds")


def read_ulog_imus(path: str | os.PathLike[str]) -> dict[str, ImuLog]:
    """Every IMU of a PX4 ULog: the primary (:func:`read_ulog`, keyed by its topic) and each
    ``sensor_gyro``/``sensor_accel`` instance pair N logged, keyed ``sensor_imu[N]`` (the
    accelerometer interpolated to the gyro's sample times, both FRD in rad/s and m/s²; the
    gyro's temperature, °C). An instance with fewer than 2 valid records is left out.

    Raises
    ------
    DataFormatError
        As :func:`read_ulog` (the primary IMU is required).
    """
    p = Path(path)
    primary = read_ulog(p)
    out = {str(primary.meta["topic"]): primary}
    ulog, _ = _open(p)
    sp = str(p)
    for g in [d for d in ulog.data_list if d.name == "sensor_gyro"]:
        a = _dataset(ulog, "sensor_accel", g.multi_id)
        if a is None or not {"x", "y", "z"} <= set(g.data) or not {"x", "y", "z"} <= set(a.data):
            continue
        tg = np.asarray(g.data["timestamp"], dtype=np.float64) * 1e-6
        ta = np.asarray(a.data["timestamp"], dtype=np.float64) * 1e-6
        if tg.size < 2 or ta.size < 2 or np.any(np.diff(ta) <= 0):
            continue
        gyro = np.column_stack([np.asarray(g.data[c], dtype=np.float64) for c in "xyz"])
        accel = np.column_stack([np.interp(tg, ta, np.asarray(a.data[c], dtype=np.float64)) for c in "xyz"])
        temp = np.asarray(g.data["temperature"], dtype=np.float64) if "temperature" in g.data else None
        values = {"gyro": gyro, "accel": accel}
        keep = salvage(tg, values, imu_limits(False))
        keep &= (tg >= ta[0]) & (tg <= ta[-1])  # no extrapolated accelerometer samples
        if keep.sum() < 2:
            continue
        if temp is not None and not np.all(np.isfinite(temp[keep])):
            temp = None
        name = f"sensor_imu[{g.multi_id}]"
        meta = {"source": sp, "format": "px4-ulog", "frame": "FRD", "topic": name}
        meta.update({k: primary.meta[k] for k in ("vehicle", "hardware", "start_time") if k in primary.meta})
        if "device_id" in g.data:
            meta["device_id"] = str(int(g.data["device_id"][0]))
        out[name] = build_log(
            sp, name, tg[keep], gyro[keep], accel[keep], None if temp is None else temp[keep], meta
        )
    return out


def read_ulog_flight(path: str | os.PathLike[str]) -> Flight:
    """The flight telemetry of a PX4 ULog (see the module docs for the topics).

    Corrupt position records are dropped (:func:`uasnav.io.flight.valid_fixes`; one
    :class:`~uasnav.errors.CorruptDataWarning` gives the counts).

    Raises
    ------
    DataFormatError
        Missing/unreadable file, neither vehicle_global_position nor vehicle_gps_position, or
        fewer than 2 valid position records.
    """
    p = Path(path)
    ulog, decoder = _open(p)

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
            raise _no_topic(ulog, decoder, "vehicle_global_position / vehicle_gps_position", str(p))
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
    wind = []
    if w is not None:
        wn = np.asarray(w["windspeed_north"], dtype=np.float64)
        we = np.asarray(w["windspeed_east"], dtype=np.float64)
        ok = np.isfinite(wn) & np.isfinite(we) & (np.hypot(wn, we) <= MAX_WIND_M_S)
        if ok.any():
            wind = [(wn[ok].mean(), we[ok].mean())]
    fixes = np.column_stack([t, lat, lon, alt, vel]).astype(np.float64)
    return flight_from_fixes(fixes, p, waypoints={}, reached=reached, wind=wind, decoder=decoder)


__all__ = ["parse_ulog", "read_ulog", "read_ulog_flight", "read_ulog_imus"]
