"""Flight telemetry readers (CSV, MAVLink .tlog, DataFlash .bin, PX4 ULog) and flown legs.

Each reader returns a :class:`FlightLog`: time (s), WGS-84 position, NED ground velocity, the
mission's navigation waypoints, waypoint-reached events and the wind estimate when the log has
them. :func:`flown_runs` cuts a log into mission runs (consecutive reached events of increasing
sequence number) and :func:`run_samples` measures their elements.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from uasnav.errors import DataFormatError, InputError
from uasnav.trajectory.features import wind_vector
from uasnav.trajectory.geometry import DEFAULT_SEGMENT_M, arc_length_along, geodetic_to_local, plan_length
from uasnav.trajectory.samples import ElementSamples, measure_elements

CSV_COLUMNS = ("t", "lat", "lon", "alt", "v_N", "v_E", "v_D")
_MAV_NAV_WAYPOINT = 16
_MAV_DO_CHANGE_SPEED = 178


@dataclass
class FlightLog:
    """Telemetry of one log.

    Attributes
    ----------
    t : ndarray, shape (k,) — time, s (wall clock for .tlog, boot time otherwise).
    lat, lon, alt : ndarray, shape (k,) — degrees, degrees, m.
    vel_ned : ndarray, shape (k, 3) — ground velocity, m/s.
    waypoints : dict seq → (lat, lon, alt) — mission navigation waypoints.
    reached : list of (t, seq) — waypoint-reached events.
    wind_ne : ndarray, shape (2,) or None — mean wind velocity (m/s, toward), if logged.
    cruise_ms : float or None — mission/waypoint speed, if logged.
    source : str
    """

    t: np.ndarray
    lat: np.ndarray
    lon: np.ndarray
    alt: np.ndarray
    vel_ned: np.ndarray
    waypoints: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    reached: list[tuple[float, int]] = field(default_factory=list)
    wind_ne: np.ndarray | None = None
    cruise_ms: float | None = None
    source: str = ""

    def __post_init__(self) -> None:
        n = np.asarray(self.t).size
        if n < 2:
            raise InputError(f"{self.source}: fewer than 2 position samples")
        order = np.argsort(self.t, kind="stable")
        for name in ("t", "lat", "lon", "alt", "vel_ned"):
            setattr(self, name, np.asarray(getattr(self, name), dtype=float)[order])
        keep = np.concatenate([[True], np.diff(self.t) > 0])
        for name in ("t", "lat", "lon", "alt", "vel_ned"):
            setattr(self, name, getattr(self, name)[keep])


def read_flight(path: str | Path) -> FlightLog:
    """Read any supported log by extension (.csv, .tlog, .bin, .ulg)."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"no such telemetry file: {p}")
    ext = p.suffix.lower()
    if ext == ".csv":
        return read_csv(p)
    if ext == ".tlog":
        return read_tlog(p)
    if ext == ".bin":
        return read_dataflash(p)
    if ext == ".ulg":
        return read_ulog(p)
    raise InputError(f"{p}: unknown telemetry format {ext!r} (expected .csv, .tlog, .bin, .ulg)")


def read_csv(path: str | Path) -> FlightLog:
    """CSV with header ``t,lat,lon,alt,v_N,v_E,v_D`` (s, deg, deg, m, m/s NED); no mission."""
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    if not rows:
        raise DataFormatError("empty file", path=str(path))
    head = [h.strip() for h in rows[0]]
    missing = [c for c in CSV_COLUMNS if c not in head]
    if missing:
        raise DataFormatError(f"missing column(s) {missing}; need {CSV_COLUMNS}", path=str(path), line=1)
    idx = [head.index(c) for c in CSV_COLUMNS]
    data = np.empty((len(rows) - 1, len(CSV_COLUMNS)))
    for i, r in enumerate(rows[1:]):
        for j, k in enumerate(idx):
            try:
                data[i, j] = float(r[k])
            except (ValueError, IndexError):
                raise DataFormatError(
                    "not a number", path=str(path), line=i + 2, column=CSV_COLUMNS[j]
                ) from None
    bad = ~np.isfinite(data)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise DataFormatError("NaN/inf", path=str(path), line=int(i) + 2, column=CSV_COLUMNS[j])
    return FlightLog(
        t=data[:, 0], lat=data[:, 1], lon=data[:, 2], alt=data[:, 3], vel_ned=data[:, 4:7], source=str(path)
    )


def _from_fixes(
    fixes: list[tuple[float, ...]],
    path: str | Path,
    *,
    waypoints: dict[int, tuple[float, float, float]],
    reached: list[tuple[float, int]],
    wind: list[Any],
    cruise_ms: float | None = None,
) -> FlightLog:
    """A FlightLog from position fixes ``(t, lat, lon, alt, v_N, v_E, v_D)`` and mission events."""
    if not fixes:
        raise DataFormatError("no position fixes", path=str(path))
    a = np.array(fixes, dtype=np.float64)
    return FlightLog(
        t=a[:, 0],
        lat=a[:, 1],
        lon=a[:, 2],
        alt=a[:, 3],
        vel_ned=a[:, 4:7],
        waypoints=waypoints,
        reached=sorted(reached),
        wind_ne=np.mean(wind, axis=0) if wind else None,
        cruise_ms=cruise_ms,
        source=str(path),
    )


def read_tlog(path: str | Path) -> FlightLog:
    """MAVLink telemetry log: GLOBAL_POSITION_INT, MISSION_ITEM(_INT), MISSION_ITEM_REACHED,
    WIND (ArduPilot, if present), WPNAV_SPEED / DO_CHANGE_SPEED. Times are the log's wall clock."""
    from pymavlink import mavutil

    conn = mavutil.mavlink_connection(str(path), dialect="ardupilotmega")
    fixes: list[tuple[float, ...]] = []
    items: dict[int, tuple[int, float, float, float, float]] = {}
    reached: list[tuple[float, int]] = []
    wind = []
    wpnav = None
    while True:
        m = conn.recv_match(
            type=[
                "GLOBAL_POSITION_INT",
                "MISSION_ITEM_INT",
                "MISSION_ITEM",
                "MISSION_ITEM_REACHED",
                "WIND",
                "PARAM_VALUE",
            ]
        )
        if m is None:
            break
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
            wind.append(wind_vector(float(m.speed), float(m.direction)))
        elif kind == "PARAM_VALUE" and m.param_id.rstrip("\x00") == "WPNAV_SPEED":
            wpnav = float(m.param_value) * 0.01
    if not fixes:
        raise DataFormatError("no GLOBAL_POSITION_INT messages", path=str(path))
    # seq 0 is the home position on ArduPilot; navigation waypoints carry a position.
    wps = {
        s: (x, y, z)
        for s, (cmd, x, y, z, _) in items.items()
        if s > 0 and cmd == _MAV_NAV_WAYPOINT and (x != 0 or y != 0)
    }
    speeds = [p2 for s, (cmd, *_, p2) in items.items() if cmd == _MAV_DO_CHANGE_SPEED and p2 > 0]
    cruise = speeds[0] if speeds else wpnav
    return _from_fixes(fixes, path, waypoints=wps, reached=reached, wind=wind, cruise_ms=cruise)


def read_dataflash(path: str | Path) -> FlightLog:
    """ArduPilot DataFlash log: GPS (position, speed, course, VZ), CMD (mission) and the
    "Reached command #N" messages; time from TimeUS."""
    import re

    from pymavlink import mavutil

    conn = mavutil.mavlink_connection(str(path))
    fixes: list[tuple[float, ...]] = []
    wps: dict[int, tuple[float, float, float]] = {}
    reached: list[tuple[float, int]] = []
    wind = []
    pat = re.compile(r"Reached (?:command|waypoint) #(\d+)")
    while True:
        m = conn.recv_match(type=["GPS", "CMD", "MSG", "XKF2", "NKF2", "EKF2"])
        if m is None:
            break
        kind = m.get_type()
        # Copter ≥ 3.4 logs TimeUS; older logs (3.3) TimeMS.
        if hasattr(m, "TimeUS"):
            ts = m.TimeUS * 1e-6
        elif hasattr(m, "TimeMS"):
            ts = m.TimeMS * 1e-3
        else:
            continue
        if kind == "GPS" and getattr(m, "Status", 3) >= 3:
            crs = np.radians(m.GCrs)
            fixes.append(
                (ts, m.Lat, m.Lng, m.Alt, m.Spd * np.cos(crs), m.Spd * np.sin(crs), getattr(m, "VZ", 0.0))
            )
        elif kind == "CMD" and m.CId == _MAV_NAV_WAYPOINT and m.CNum > 0 and (m.Lat != 0 or m.Lng != 0):
            wps[int(m.CNum)] = (m.Lat, m.Lng, m.Alt)
        elif kind == "MSG":
            hit = pat.search(m.Message)
            if hit:
                reached.append((ts, int(hit.group(1))))
        elif kind in ("XKF2", "NKF2", "EKF2") and hasattr(m, "VWN"):
            wind.append((m.VWN, m.VWE))
    if not fixes:
        raise DataFormatError("no GPS messages with a 3D fix", path=str(path))
    return _from_fixes(fixes, path, waypoints=wps, reached=reached, wind=wind)


def read_ulog(path: str | Path) -> FlightLog:
    """PX4 ULog: vehicle_global_position (or vehicle_gps_position), mission_result reached
    sequence numbers and wind_estimate. PX4 logs hold no waypoint coordinates (the mission
    lives in dataman), so ``waypoints`` stays empty unless a plan is given separately."""
    from pyulog import ULog

    try:
        ulog = ULog(str(path))
    except Exception as exc:  # pyulog raises bare exceptions on corrupt files
        raise DataFormatError(f"cannot parse ULog: {exc}", path=str(path)) from None

    def topic(name: str) -> dict[str, np.ndarray] | None:
        for d in ulog.data_list:
            if d.name == name and d.multi_id == 0:
                return d.data
        return None

    g = topic("vehicle_global_position")
    if g is not None and "vel_n" in g:
        t = g["timestamp"] * 1e-6
        lat, lon, alt = g["lat"], g["lon"], g["alt"]
        vel = np.column_stack([g["vel_n"], g["vel_e"], g["vel_d"]])
    else:
        g = topic("vehicle_gps_position")
        if g is None:
            raise DataFormatError("no vehicle_global_position / vehicle_gps_position topic", path=str(path))
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
    wind = np.array([w["windspeed_north"].mean(), w["windspeed_east"].mean()]) if w is not None else None
    return FlightLog(
        t=t, lat=lat, lon=lon, alt=alt, vel_ned=vel, reached=reached, wind_ne=wind, source=str(path)
    )


@dataclass
class FlownRun:
    """One run of the mission: the waypoint sequence reached, their times and the telemetry."""

    seqs: list[int]
    reached_t: np.ndarray
    plan_ne: np.ndarray
    t: np.ndarray
    pos_ne: np.ndarray
    vel_ne: np.ndarray


def flown_runs(log: FlightLog, origin: tuple[float, float, float] | None = None) -> list[FlownRun]:
    """Cut a log into mission runs between reached navigation waypoints (local NED plan).

    Raises :class:`InputError` if the log has no mission waypoints or no run reaching two of
    them.
    """
    if not log.waypoints:
        raise InputError(f"{log.source}: telemetry has no mission waypoints (give the plan separately)")
    if not log.reached:
        raise InputError(f"{log.source}: telemetry has no waypoint-reached events")
    seqs = sorted(log.waypoints)
    o = origin or log.waypoints[seqs[0]]
    runs: list[list[tuple[float, int]]] = [[]]
    for ev in log.reached:
        if runs[-1] and ev[1] <= runs[-1][-1][1]:
            runs.append([])
        runs[-1].append(ev)
    out = []
    for run in runs:
        nav = [(t, s) for t, s in run if s in log.waypoints]
        if len(nav) < 2:
            continue
        wp = np.array([log.waypoints[s] for _, s in nav])
        plan = geodetic_to_local(wp[:, 0], wp[:, 1], wp[:, 2], origin=o)[:, :2]
        t0, t1 = nav[0][0], nav[-1][0]
        sel = (log.t >= t0) & (log.t <= t1 + 5.0)
        if sel.sum() < 2:
            continue
        pos = geodetic_to_local(log.lat[sel], log.lon[sel], log.alt[sel], origin=o)[:, :2]
        out.append(
            FlownRun(
                seqs=[s for _, s in nav],
                reached_t=np.array([t for t, _ in nav]),
                plan_ne=plan,
                t=log.t[sel],
                pos_ne=pos,
                vel_ne=log.vel_ned[sel, :2],
            )
        )
    if not out:
        raise InputError(f"{log.source}: no mission run reaches two navigation waypoints")
    return out


def run_samples(
    log: FlightLog,
    segment_m: float = DEFAULT_SEGMENT_M,
    cruise_ms: float | None = None,
    wind_ne: np.ndarray | None = None,
    max_gap_s: float = 5.0,
) -> tuple[list[FlownRun], list[ElementSamples]]:
    """Measure the elements of every run of a log (flight index = run index).

    ``cruise_ms`` and ``wind_ne`` override the log's values; without wind in the log and no
    override the wind is taken as calm (zero), and the caller should say so.
    """
    v = cruise_ms if cruise_ms is not None else log.cruise_ms
    if v is None:
        raise InputError(f"{log.source}: no waypoint speed in the log; give the cruise speed")
    w = wind_ne if wind_ne is not None else (log.wind_ne if log.wind_ne is not None else np.zeros(2))
    runs = flown_runs(log)
    samples = []
    for i, r in enumerate(runs):
        # Autopilots accept the last waypoint within a radius and then start the next command
        # (ArduCopter lands where it is, ~7 m short here): the flown plan ends where the vehicle
        # was when the reached event came.
        s_run = arc_length_along(r.plan_ne, r.pos_ne)
        s_reached = float(np.interp(r.reached_t[-1], r.t, s_run))
        tol = max(1.0, plan_length(r.plan_ne) - s_reached)
        _, s = measure_elements(
            r.plan_ne,
            r.t,
            r.pos_ne,
            r.vel_ne,
            w,
            v,
            segment_m=segment_m,
            flight=i,
            end_tolerance_m=tol,
            max_gap_s=max_gap_s,
        )
        samples.append(s)
    return runs, samples


__all__ = [
    "CSV_COLUMNS",
    "FlightLog",
    "FlownRun",
    "flown_runs",
    "read_csv",
    "read_dataflash",
    "read_flight",
    "read_tlog",
    "read_ulog",
    "run_samples",
]
