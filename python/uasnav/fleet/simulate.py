"""``uasnav fleet simulate``: a synthetic fleet of flight logs with known faults and corrupt files.

N vehicles × M flights, each flight one CSV v1 IMU log (IMU only: the fleet's health numbers
need no GNSS), made with :func:`uasnav.sim.simulate`:

- every vehicle carries one IMU part (``lsm6dsm`` or ``ax1``, alternating), with its own
  hardware (turn-on biases from the vehicle's seed) and a white-noise level scaled by a
  per-vehicle factor (log-normal, ±15 %): the varied quality of real parts;
- each flight starts at its own ambient temperature (0–35 °C) and warms up on the ground
  (self-heating): a static ground segment (the first ``static_fraction`` of the log), then
  the flight, where manoeuvre rates (sinusoids up to 1 rad/s) and airframe vibration (white,
  ``vibration_m_s2`` rms) are added to the sensor outputs — not a consistent trajectory, but
  what the health numbers (static noise, bias, vibration, clipping) look at;
- about 10 % of the flights (at least one) have a faulty IMU: white noise ×8 from power-on;
- about 5 % of the files (at least one) are corrupt: a CSV cut mid-line with a stray cell, or a
  ``.ulg`` of random bytes;
- with ``nav_flights`` > 0, each vehicle also flies that many missions in the GNSS/INS flight
  format (:func:`uasnav.sim.flight.simulate_flight`, the vehicle's IMU part): ``nav_NNN.csv``
  (CSV v1: IMU, magnetometer and ``truth_*`` columns, as ``uasnav simulate --profile flight``
  writes it), ``nav_NNN_gnss.csv`` (the GNSS fixes) and ``nav_NNN.tlog``, the ground station's
  telemetry (:func:`uasnav.io.tlog_write.write_tlog_flight`: position fixes from the truth at the
  GNSS rate, the mission it flew — a per-vehicle circuit of four waypoints, flown lap after lap
  — and the waypoint-reached events), which is what carries the plan: the flight format has
  no mission of its own.

``fleet.json`` in the output folder is the ground truth: per file, vehicle, IMU model, noise
factor, whether faulty or corrupt. Everything is a deterministic function of the arguments.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from uasnav.atomicfile import atomic_write_text, output_set
from uasnav.errors import InputError
from uasnav.imu import ImuLog

FloatArray = NDArray[np.float64]

IMU_MODELS = ("lsm6dsm", "ax1")
FAULT_NOISE_FACTOR = 8.0
TRUTH_FILE = "fleet.json"


@dataclass(frozen=True)
class FleetFile:
    """Ground truth of one simulated file."""

    file: str
    vehicle: str
    imu_model: str
    flight: int
    noise_factor: float
    faulty: bool
    corrupt: bool


@dataclass(frozen=True)
class SimulatedFleet:
    """What :func:`simulate_fleet` wrote: the folder and the truth of every file."""

    out: str
    files: tuple[FleetFile, ...]

    @property
    def faulty(self) -> list[str]:
        """Files whose IMU is faulty."""
        return [f.file for f in self.files if f.faulty]

    @property
    def corrupt(self) -> list[str]:
        """Files that are corrupt."""
        return [f.file for f in self.files if f.corrupt]


def _flight_log(
    model_name: str, vehicle: int, flight: int, noise: float, faulty: bool, duration_s: float,
    rate_hz: float, static_fraction: float, vibration_m_s2: float, seed: int, start: dt.datetime,
    vehicle_id: str,
) -> ImuLog:  # fmt: skip
    from uasnav.sim import load_preset, simulate

    rng = np.random.default_rng([seed, vehicle, flight, 7])
    model = load_preset(model_name)
    k = noise * (FAULT_NOISE_FACTOR if faulty else 1.0)
    ambient = float(rng.uniform(0.0, 35.0))
    model = dataclasses.replace(
        model,
        gyro=dataclasses.replace(model.gyro, white=model.gyro.white * k),
        accel=dataclasses.replace(model.accel, white=model.accel.white * k),
        temperature=dataclasses.replace(model.temperature, ambient_c=ambient),
    )
    # the vehicle's seed fixes its hardware (turn-on biases …); the flight's draws the noise
    sim = simulate(
        model, profile="warmup", duration=duration_s, rate=rate_hz, seed=seed * 1000 + vehicle,
        noise_seed=seed * 1_000_000 + vehicle * 1000 + flight,
    )  # fmt: skip
    t = sim.t - sim.t[0]
    fly = t >= static_fraction * duration_s
    gyro, accel = sim.gyro.copy(), sim.accel.copy()
    m = int(fly.sum())
    if m:
        tf = t[fly] - t[fly][0]
        freqs = rng.uniform(0.05, 0.5, 3)
        amps = rng.uniform(0.2, 1.0, 3)
        phases = rng.uniform(0, 2 * np.pi, 3)
        ramp = np.minimum(tf / 2.0, 1.0)[:, None]  # take-off: rates grow over 2 s
        gyro[fly] += ramp * amps * np.sin(2 * np.pi * freqs * tf[:, None] + phases)
        accel[fly] += ramp * rng.normal(0.0, vibration_m_s2, (m, 3))
    meta = {
        "vehicle": vehicle_id,
        "autopilot": "uasnav-sim",
        "imu_model": model_name,
        "start_time": start.isoformat().replace("+00:00", "Z"),
        "rate_hz": f"{rate_hz:g}",
    }
    return ImuLog(t=t, gyro=gyro, accel=accel, temp=sim.temp, meta=meta)


def _circuit(rng: np.random.Generator) -> tuple[tuple[float, float, float], ...]:
    """A rectangle of 120–200 m × 80–140 m at 30–45 m (north, east, up from the start; m)."""
    a, b = float(rng.uniform(120.0, 200.0)), float(rng.uniform(80.0, 140.0))
    up = float(rng.uniform(30.0, 45.0))
    return ((a, 0.0, up), (a, b, up + 5.0), (0.0, b, up), (0.0, 0.0, up))


def _reached(
    n: FloatArray,
    e: FloatArray,
    u: FloatArray,
    t: FloatArray,
    circuit: tuple[tuple[float, float, float], ...],
) -> list[tuple[float, int]]:
    """Waypoint-reached events: every pass of the track within 2 m of waypoint ``seq`` (1-based,
    the closest sample of the pass), sorted by time."""
    events = []
    for s, (wn, we, wu) in enumerate(circuit, start=1):
        d = np.sqrt((n - wn) ** 2 + (e - we) ** 2 + (u - wu) ** 2)
        near = d < 2.0
        edges = np.flatnonzero(np.diff(np.concatenate([[0], near.astype(np.int8), [0]])))
        for i0, i1 in zip(edges[::2], edges[1::2], strict=True):
            k = i0 + int(np.argmin(d[i0:i1]))
            events.append((float(t[k]), s))
    return sorted(events)


def _nav_flight(
    out_p: Path, name: str, model_name: str, vehicle: int, flight: int, duration_s: float, rate_hz: float,
    seed: int, start: dt.datetime, vehicle_id: str,
) -> None:  # fmt: skip
    """Write one GNSS/INS flight: ``name``.csv, ``name``_gnss.csv and ``name``.tlog (module docs)."""
    from uasnav.io import write_csv_v1
    from uasnav.io.formats.gnss_csv import write_gnss_csv
    from uasnav.io.tlog_write import write_tlog_flight
    from uasnav.sim.flight import imu_log_with_truth, simulate_flight
    from uasnav.trajectory.geometry import geodetic_to_local

    rng = np.random.default_rng([seed, vehicle, flight, 15])
    circuit = _circuit(np.random.default_rng([seed, vehicle, 15]))
    lat0, lon0 = 45.0 + 0.01 * vehicle, 7.0 + 0.01 * flight
    speed = 8.0
    f = simulate_flight(
        waypoints=circuit, duration_s=duration_s, speed_m_s=speed, rate_hz=rate_hz, latitude_deg=lat0,
        longitude_deg=lon0, height_m=300.0, preset=model_name, seed=int(rng.integers(2**31)),
    )  # fmt: skip
    log_with_truth = imu_log_with_truth(f)
    tr = f.truth
    assert tr is not None and tr.vel is not None  # imu_log_with_truth checked it
    meta = {
        "vehicle": vehicle_id,
        "autopilot": "uasnav-sim",
        "imu_model": model_name,
        "start_time": start.isoformat().replace("+00:00", "Z"),
        "rate_hz": f"{rate_hz:g}",
    }
    log = dataclasses.replace(log_with_truth, meta={**f.imu.meta, **meta})
    write_csv_v1(log, out_p / f"{name}.csv")
    write_gnss_csv(out_p / f"{name}_gnss.csv", f.gnss)
    # telemetry: the true track at the GNSS instants, on the wall clock of the flight's start
    g = f.gnss.t
    lat, lon, alt = (np.interp(g, tr.t, x) for x in (tr.lat, tr.lon, tr.alt))
    vel = np.column_stack([np.interp(g, tr.t, tr.vel[:, i]) for i in range(3)])
    ned = geodetic_to_local(lat, lon, alt, origin=(float(lat[0]), float(lon[0]), float(alt[0])))
    reached = _reached(ned[:, 0], ned[:, 1], -ned[:, 2], g, circuit)
    wall = start.timestamp()
    wps = {}
    for s in range(1, len(circuit) + 1):
        hits = [tt for tt, ss in reached if ss == s]
        if not hits:
            continue
        k = int(np.argmin(np.abs(g - hits[0])))
        wps[s] = (float(lat[k]), float(lon[k]), float(alt[k]))
    write_tlog_flight(
        out_p / f"{name}.tlog", t_unix=wall + g, lat=lat, lon=lon, alt=alt, vel_ned=vel, waypoints=wps,
        reached=[(wall + tt, s) for tt, s in reached if s in wps], cruise_ms=speed,
    )  # fmt: skip


#: Elementary operations per IMU sample written (simulation and CSV text), for the work estimate.
OPS_PER_IMU_SAMPLE = 2e3
#: Elementary operations per sample of a GNSS/INS flight (trajectory, IMU, GNSS, tlog messages).
OPS_PER_NAV_SAMPLE = 2e4


def simulate_fleet(
    out: str | Path,
    vehicles: int = 5,
    flights: int = 4,
    *,
    seed: int = 0,
    duration_s: float = 120.0,
    rate_hz: float = 100.0,
    static_fraction: float = 0.5,
    vibration_m_s2: float = 0.5,
    corrupt: bool = True,
    nav_flights: int = 0,
    nav_duration_s: float = 180.0,
) -> SimulatedFleet:
    """Write a synthetic fleet into the folder ``out`` (module docs); all files or none.

    Parameters
    ----------
    out : path
        Folder to write (created; files ``V01/flight_001.csv`` …, ``fleet.json``).
    vehicles, flights : int
        N vehicles × M flights per vehicle.
    seed : int
    duration_s, rate_hz : float
        Length (s) and rate (Hz) of each log.
    static_fraction : float
        Fraction of each log on the ground, static, before the flight.
    vibration_m_s2 : float
        Airframe vibration in flight (m/s² rms per axis).
    corrupt : bool
        Also write the corrupt files.
    nav_flights : int
        GNSS/INS flights per vehicle (module docs), each three files.
    nav_duration_s : float
        Length of each GNSS/INS flight (s; 20 s on the ground, then laps of the circuit).
    """
    from uasnav.io import write_csv_v1

    if nav_flights < 0 or not nav_duration_s > 20.0:
        raise InputError(
            f"nav_flights must be >= 0 and nav_duration_s > 20 s, got {nav_flights}, {nav_duration_s}"
        )
    if vehicles < 1 or flights < 1:
        raise InputError(f"vehicles and flights must be >= 1, got {vehicles} and {flights}")
    if not (duration_s > 0 and rate_hz > 0 and 0 <= static_fraction <= 1):
        raise InputError("duration_s and rate_hz must be > 0 and static_fraction within 0 … 1")
    from uasnav.limits import check_count, check_work

    check_count(vehicles * flights * duration_s * rate_hz, 8 * 8, "fleet simulation", option="flights")
    imu_samples = vehicles * flights * duration_s * rate_hz
    nav_samples = vehicles * nav_flights * nav_duration_s * rate_hz
    check_work(
        OPS_PER_IMU_SAMPLE * imu_samples + OPS_PER_NAV_SAMPLE * nav_samples,
        f"fleet simulation of {vehicles} vehicle(s) × {flights} flight(s) + {nav_flights} GNSS/INS flight(s)",
        option="--vehicles, --flights or --nav-flights",
    )
    out_p = Path(out)
    rng = np.random.default_rng([seed, 19])
    n_total = vehicles * flights
    faulty = set(rng.choice(n_total, size=max(1, round(0.1 * n_total)), replace=False).tolist())
    n_bad = max(1, round(0.05 * n_total)) if corrupt else 0
    noise = np.exp(rng.normal(0.0, 0.15, vehicles))
    day0 = dt.datetime(2026, 11, 2, 8, 0, tzinfo=dt.timezone.utc)
    files: list[FleetFile] = []
    with output_set():
        for v in range(vehicles):
            vid = f"V{v + 1:02d}"
            model = IMU_MODELS[v % len(IMU_MODELS)]
            for f in range(flights):
                k = v * flights + f
                start = day0 + dt.timedelta(days=f // 2, hours=3 * (f % 2), minutes=7 * v)
                log = _flight_log(
                    model, v, f, float(noise[v]), k in faulty, duration_s, rate_hz, static_fraction,
                    vibration_m_s2, seed, start, vid,
                )  # fmt: skip
                name = f"{vid}/flight_{f + 1:03d}.csv"
                write_csv_v1(log, out_p / name)
                files.append(FleetFile(name, vid, model, f, float(noise[v]), k in faulty, False))
            for f in range(nav_flights):
                start = day0 + dt.timedelta(days=f // 2, hours=3 * (f % 2) + 1, minutes=7 * v)
                name = f"{vid}/nav_{f + 1:03d}"
                _nav_flight(out_p, name, model, v, f, nav_duration_s, rate_hz, seed, start, vid)
                for ext in (".csv", "_gnss.csv", ".tlog"):
                    files.append(FleetFile(name + ext, vid, model, f, 1.0, False, False))
        for b in range(n_bad):
            if b % 2 == 0:
                name = f"corrupt/broken_{b + 1:03d}.csv"
                text = "# vehicle: VX\nt,gx,gy,gz,ax,ay,az\n0,0,0,0,0,0,9.8\n0.01,0,0,0,0,0,9.8\n0.02,0,abc,0"
                atomic_write_text(out_p / name, text)
            else:
                name = f"corrupt/broken_{b + 1:03d}.ulg"
                junk = np.random.default_rng([seed, b]).integers(0, 256, 4096, dtype=np.uint8).tobytes()
                from uasnav.atomicfile import atomic_write_bytes

                atomic_write_bytes(out_p / name, junk)
            files.append(FleetFile(name, "unknown", "unknown", -1, 1.0, False, True))
        truth = {
            "seed": seed,
            "vehicles": vehicles,
            "flights": flights,
            "files": [dataclasses.asdict(f) for f in files],
        }
        atomic_write_text(out_p / TRUTH_FILE, json.dumps(truth, indent=1) + "\n")
    return SimulatedFleet(str(out_p), tuple(files))


def load_truth(out: str | Path) -> SimulatedFleet:
    """The truth of a simulated fleet folder (its ``fleet.json``)."""
    d = json.loads((Path(out) / TRUTH_FILE).read_text(encoding="utf-8"))
    return SimulatedFleet(str(out), tuple(FleetFile(**f) for f in d["files"]))


__all__ = ["FleetFile", "SimulatedFleet", "load_truth", "simulate_fleet"]
