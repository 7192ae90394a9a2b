"""MAVLink telemetry logs (``.tlog``, ArduPilot and PX4 dialects) through pymavlink: one pass
per command for the message types its views need (:attr:`TlogFormat.SOURCES`).

- ``imus``/``imu`` (:func:`read_tlog`): ``HIGHRES_IMU`` (SI), ``SCALED_IMU``/``SCALED_IMU2``/
  ``SCALED_IMU3`` and ``RAW_IMU`` as ArduPilot sends them (mg → m/s², mrad/s → rad/s,
  temperature cdegC when present and non-zero), time ``time_usec`` or ``time_boot_ms`` (s). A
  telemetry log can span autopilot reboots (boot time restarts): each stream is split there and
  later parts are keyed ``"SCALED_IMU2#2"`` … Frame: body FRD, as uasnav.
- ``nav``: :func:`read_tlog_nav`.
- ``flight`` (:func:`read_tlog_flight`): ``GLOBAL_POSITION_INT``, ``MISSION_ITEM(_INT)``,
  ``MISSION_ITEM_REACHED``, ``WIND`` (ArduPilot, if present), the ``WPNAV_SPEED`` parameter and
  ``DO_CHANGE_SPEED`` mission items.
- ``plan``: ``MISSION_ITEM(_INT)``; ``params``/``limits``: ``PARAM_VALUE``; ``modes``:
  ``HEARTBEAT.custom_mode``; ``identity``: ``HEARTBEAT`` (autopilot, vehicle type),
  ``AUTOPILOT_VERSION``.

Log time is the ground station's wall clock (UTC, s since 1970).

Errors: a missing or unreadable file and an undecodable message are a
:class:`~uasnav.errors.DataFormatError` naming the file. Corrupt messages fail their MAVLink
checksum and are dropped by pymavlink; the readers count them and warn once
(:class:`~uasnav.errors.CorruptDataWarning`). The 8-byte time stamp that a ``.tlog`` puts before
each message has no checksum: fixes whose time stamp is out of order are dropped too
(:func:`uasnav.io.flight.valid_fixes`).
"""

from __future__ import annotations

import datetime as dt
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from uasnav.errors import DataFormatError
from uasnav.geo.datum import HeightDatum, receiver_undulation
from uasnav.imu import ImuLog
from uasnav.io._common import because, build_log, corruption_meta, report_corruption
from uasnav.io._mavlink import messages, reading
from uasnav.io.autopilot_params import ARDUPILOT_PARAMS, PX4_PARAMS
from uasnav.io.flight import BaroData, Flight, GnssData, MagData, Trajectory, flight_from_fixes, wind_from
from uasnav.io.formats._scan import MavlinkScan
from uasnav.io.formats.alfa import isa_pressure_altitude
from uasnav.io.formats.base import ScannedFormat
from uasnav.io.formats.dataflash import COPTER_MODES
from uasnav.io.plan_formats.logs import read_tlog_plan
from uasnav.io.views import Identity, ModeTimeline, changes
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


def read_tlog_flight(path: str | os.PathLike[str]) -> Flight:
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


NAV_TYPES = ("SCALED_IMU", "RAW_IMU", "GPS_RAW_INT", "SCALED_PRESSURE", "GLOBAL_POSITION_INT", "ATTITUDE")
#: MAV_AUTOPILOT and MAV_TYPE numbers of HEARTBEAT (common subset).
AUTOPILOTS = {3: "ArduPilot", 12: "PX4"}
MAV_TYPES = {1: "fixed-wing", 2: "multirotor", 13: "multirotor", 14: "multirotor", 15: "multirotor",
             10: "rover", 19: "VTOL", 20: "VTOL", 21: "VTOL", 22: "VTOL"}  # fmt: skip
_GCS = 6  # MAV_TYPE_GCS: the ground station's own heartbeat


def read_tlog_nav(path: str | os.PathLike[str]) -> Flight:
    """Navigation data of a MAVLink log as a :class:`~uasnav.io.flight.Flight`: the IMU from
    ``SCALED_IMU`` (else ``RAW_IMU``, ArduPilot scaling: mg, mrad/s), ``GPS_RAW_INT`` (fixes
    with ``fix_type`` ≥ 3; ``h_acc``/``v_acc``/``vel_acc`` when sent, else σ from ``eph``),
    ``SCALED_PRESSURE`` (ISA pressure altitude), the IMU's magnetometer, and the reference from
    ``GLOBAL_POSITION_INT`` and ``ATTITUDE``. Heights: AMSL (``GPS_RAW_INT.alt``,
    ``GLOBAL_POSITION_INT.alt``), or ellipsoidal when every fix carries MAVLink 2's
    ``alt_ellipsoid`` (the estimate then moved by the receiver's own undulation). All on the
    log's wall clock (the time stamp the ground station wrote on arrival: telemetry jitter of
    tens of ms is part of the data).
    Telemetry IMU streams are typically 10–50 Hz: say so where it limits accuracy.

    Raises
    ------
    DataFormatError
        No IMU message, no GPS_RAW_INT, or fewer than 2 3-D fixes.
    """
    p = Path(path)
    imu_rows: dict[str, list[tuple[float, ...]]] = {"SCALED_IMU": [], "RAW_IMU": []}
    gps: list[tuple[float, ...]] = []
    baro: list[tuple[float, float]] = []
    ref: list[tuple[float, ...]] = []
    att: list[tuple[float, ...]] = []
    types = NAV_TYPES
    with reading(p, dialect="ardupilotmega") as (conn, decoder):
        for m in messages(conn, types, p, "MAVLink"):
            kind = m.get_type()
            ts = float(m._timestamp)
            if kind in imu_rows:
                imu_rows[kind].append(
                    (
                        ts,
                        m.xgyro * 1e-3,
                        m.ygyro * 1e-3,
                        m.zgyro * 1e-3,
                        m.xacc * 1e-3 * STANDARD_GRAVITY,
                        m.yacc * 1e-3 * STANDARD_GRAVITY,
                        m.zacc * 1e-3 * STANDARD_GRAVITY,
                        m.xmag * 1e-1,
                        m.ymag * 1e-1,
                        m.zmag * 1e-1,
                    )
                )
            elif kind == "GPS_RAW_INT" and m.fix_type >= 3:
                h_acc = getattr(m, "h_acc", 0) * 1e-3 or max(m.eph * 1e-2, 0.5) * 1.5
                v_acc = getattr(m, "v_acc", 0) * 1e-3 or 1.5 * h_acc
                s_acc = getattr(m, "vel_acc", 0) * 1e-3 or 0.3
                cog = np.radians(m.cog * 1e-2)
                gps.append(
                    (
                        ts,
                        m.lat * 1e-7,
                        m.lon * 1e-7,
                        m.alt * 1e-3,
                        m.vel * 1e-2 * np.cos(cog),
                        m.vel * 1e-2 * np.sin(cog),
                        0.0,
                        h_acc,
                        v_acc,
                        s_acc,
                        getattr(m, "alt_ellipsoid", 0) * 1e-3,
                    )
                )
            elif kind == "SCALED_PRESSURE":
                baro.append((ts, float(m.press_abs) * 100.0))
            elif kind == "GLOBAL_POSITION_INT":
                ref.append(
                    (ts, m.lat * 1e-7, m.lon * 1e-7, m.alt * 1e-3, m.vx * 0.01, m.vy * 0.01, m.vz * 0.01)
                )
            elif kind == "ATTITUDE":
                att.append((ts, np.degrees(m.roll), np.degrees(m.pitch), np.degrees(m.yaw)))
    key = "SCALED_IMU" if len(imu_rows["SCALED_IMU"]) >= 2 else "RAW_IMU"
    if len(imu_rows[key]) < 2:
        raise DataFormatError(
            f"no SCALED_IMU/RAW_IMU messages{because(decoder)}", path=str(p), column="SCALED_IMU"
        )
    if len(gps) < 2:
        raise DataFormatError(
            f"fewer than 2 GPS_RAW_INT fixes with fix_type >= 3{because(decoder)}",
            path=str(p),
            column="GPS_RAW_INT",
        )

    def increasing(a: np.ndarray) -> np.ndarray:
        keep = np.zeros(a.shape[0], dtype=bool)
        last = -np.inf
        for i, x in enumerate(a[:, 0]):
            if x > last:
                keep[i], last = True, x
        return a[keep]

    a = increasing(np.asarray(imu_rows[key], dtype=np.float64))
    g = increasing(np.asarray(gps, dtype=np.float64))
    t0 = float(a[0, 0])
    imu = ImuLog(
        a[:, 0] - t0,
        a[:, 1:4],
        a[:, 4:7],
        meta={"source": str(p), "format": "mavlink-tlog", "message": key, "frame": "FRD"},
    )
    mag_ok = np.linalg.norm(a[:, 7:10], axis=1) > 0
    mag = MagData(a[mag_ok, 0] - t0, a[mag_ok, 7:10]) if mag_ok.sum() >= 2 else None
    # GPS_RAW_INT.alt is AMSL; MAVLink 2 adds alt_ellipsoid (0 when not sent): then the fixes are
    # ellipsoidal and the estimate (GLOBAL_POSITION_INT.alt, AMSL) moves by the receiver's N
    n_geoid = None
    datum = HeightDatum.AMSL
    has_ell = g[:, 10] != 0
    if np.all(has_ell):
        n_geoid = receiver_undulation(g[:, 10], g[:, 3])
        g[:, 3] = g[:, 10]
        datum = HeightDatum.ELLIPSOID
    # GPS_RAW_INT has no vertical velocity: derive it from the fixes' height.
    g[:, 6] = -np.gradient(g[:, 3], g[:, 0]) if g.shape[0] >= 2 else 0.0
    gnss = GnssData(
        g[:, 0] - t0, g[:, 1], g[:, 2], g[:, 3], g[:, 4:7], g[:, 7], g[:, 8], g[:, 9],
        alt_datum=datum, geoid_undulation_m=n_geoid,
    )  # fmt: skip
    b = increasing(np.asarray(baro, dtype=np.float64)) if len(baro) >= 2 else None
    baro_d = BaroData(b[:, 0] - t0, isa_pressure_altitude(b[:, 1])) if b is not None else None
    reference = None
    if len(ref) >= 2:
        r = increasing(np.asarray(ref, dtype=np.float64))
        r[:, 6] *= vz_down_sign(r[:, 0], r[:, 3], r[:, 6])
        eul = None
        if len(att) >= 2:
            at = increasing(np.asarray(att, dtype=np.float64))
            eul = np.column_stack(
                [np.interp(r[:, 0], at[:, 0], at[:, i]) for i in (1, 2)]
                + [
                    np.degrees(
                        np.arctan2(
                            np.interp(r[:, 0], at[:, 0], np.sin(np.radians(at[:, 3]))),
                            np.interp(r[:, 0], at[:, 0], np.cos(np.radians(at[:, 3]))),
                        )
                    )
                ]
            )
        reference = Trajectory(
            r[:, 0] - t0,
            r[:, 1],
            r[:, 2],
            r[:, 3] + (n_geoid or 0.0),
            r[:, 4:7],
            eul,
            name="ArduPilot GLOBAL_POSITION_INT + ATTITUDE"
            + ("" if n_geoid is None else f" (AMSL + receiver geoid undulation {n_geoid:+.2f} m)"),
            alt_datum=datum,
        )
    return Flight(
        imu,
        gnss,
        baro_d,
        mag,
        reference=reference,
        imus={key: imu},
        meta={
            "source": str(p),
            "format": "mavlink-tlog",
            "imu": key,
            "t0_wall_s": t0,
            "note": f"telemetry IMU at {imu.sample_rate:.1f} Hz on arrival time stamps: "
            "it limits the accuracy",
        },
    )


class TlogFormat(ScannedFormat):
    """MAVLink telemetry log (see the module docs)."""

    name = "mavlink-tlog"
    SCANNER = MavlinkScan
    SCAN_OPTIONS: ClassVar[dict[str, Any]] = {"dialect": "ardupilotmega"}
    SOURCES: ClassVar[dict[str, tuple[str, ...]]] = {
        "imus": IMU_TYPES,
        "imu": IMU_TYPES,
        "nav": NAV_TYPES,
        "flight": ("GLOBAL_POSITION_INT", "MISSION_ITEM_INT", "MISSION_ITEM", "MISSION_ITEM_REACHED",
                   "WIND", "PARAM_VALUE"),
        "plan": ("MISSION_ITEM_INT", "MISSION_ITEM"),
        "params": ("PARAM_VALUE",),
        "limits": ("PARAM_VALUE",),
        "modes": ("HEARTBEAT",),
        "identity": ("HEARTBEAT", "AUTOPILOT_VERSION"),
    }  # fmt: skip
    READERS: ClassVar[dict[str, Callable[[Path], Any]]] = {
        "imus": read_tlog,
        "nav": read_tlog_nav,
        "flight": read_tlog_flight,
        "plan": read_tlog_plan,
    }

    def _messages(self, types: list[str]) -> list[Any]:
        with reading(self.path, dialect="ardupilotmega") as (conn, _):
            return list(messages(conn, types, self.path, "MAVLink"))

    def build_params(self) -> dict[str, float]:
        out = {}
        for m in self._messages(["PARAM_VALUE"]):
            out[str(m.param_id).rstrip("\x00")] = float(m.param_value)  # the last value wins
        return out

    def limit_parameters(self, params: dict[str, float]) -> dict[str, tuple[str, float]]:
        # a PX4 vehicle's telemetry carries PX4's parameters
        px4 = any(k.startswith(("MPC_", "EKF2_")) for k in params)
        return PX4_PARAMS if px4 else ARDUPILOT_PARAMS

    def build_modes(self) -> ModeTimeline:
        beats = [m for m in self._messages(["HEARTBEAT"]) if int(m.type) != _GCS]
        t = np.array([float(m._timestamp) for m in beats], dtype=np.float64)
        # ArduCopter's custom_mode numbers are its mode numbers (the DataFlash MODE.Mode)
        copter = [int(m.autopilot) == 3 and MAV_TYPES.get(int(m.type)) == "multirotor" for m in beats]
        names = [
            COPTER_MODES.get(int(m.custom_mode), f"MODE_{int(m.custom_mode)}")
            if c
            else f"MODE_{int(m.custom_mode)}"
            for m, c in zip(beats, copter, strict=True)
        ]
        if t.size and np.any(np.diff(t) < 0):
            order = np.argsort(t, kind="stable")
            t, names = t[order], [names[i] for i in order]
        return changes(t, names, "HEARTBEAT.custom_mode")

    def build_identity(self) -> Identity:
        msgs = self._messages(["HEARTBEAT", "AUTOPILOT_VERSION"])
        beat = next((m for m in msgs if m.get_type() == "HEARTBEAT" and int(m.type) != _GCS), None)
        ver = next((m for m in msgs if m.get_type() == "AUTOPILOT_VERSION"), None)
        version = None
        if ver is not None and int(ver.flight_sw_version):
            v = int(ver.flight_sw_version)
            version = f"{(v >> 24) & 0xFF}.{(v >> 16) & 0xFF}.{(v >> 8) & 0xFF}"
        return Identity(
            autopilot=None
            if beat is None
            else AUTOPILOTS.get(int(beat.autopilot), f"MAV_AUTOPILOT {beat.autopilot}"),
            vehicle_type=None if beat is None else MAV_TYPES.get(int(beat.type), f"MAV_TYPE {beat.type}"),
            firmware_version=version,
            vehicle_id=None if beat is None else f"sysid {beat.get_srcSystem()}",
            utc_at_zero=dt.datetime(1970, 1, 1, tzinfo=dt.timezone.utc),
            clock="wall",
        )


__all__ = ["IMU_TYPES", "TlogFormat", "read_tlog", "read_tlog_flight", "read_tlog_nav", "vz_down_sign"]
