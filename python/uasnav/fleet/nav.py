"""``uasnav fleet nav``: a GNSS/INS replay of every log with IMU and GNSS, scored against its
reference — the per-log feature added to the runner as one function (:func:`nav_log`).

Each log is read once with :func:`uasnav.io.open_log` (its ``nav`` view; a CSV v1 IMU log with its
``X_gnss.csv``, DataFlash, ULog, ``.tlog``) and replayed by :func:`uasnav.ins.run` (the real
logs' snapshot IMU streams with :meth:`~uasnav.ins.InsConfig.for_logged_imu`, as ``uasnav nav``
does), then compared by :func:`uasnav.ins.evaluate.compare` with the log's truth (simulated
flights: the ``truth_*`` columns) or else the autopilot's own estimate. The GNSS-outage drift is
:func:`uasnav.ins.evaluate.outage_experiment`: GNSS masked for 10, 30 and 60 s at
:data:`OUTAGES_PER_DURATION` start times spread over the flight (30 s of GNSS before each), the
median horizontal error at each outage's end against the truth (else the first fix after it);
null where the log is too short for that duration. Logs without an IMU or without GNSS (an IMU
CSV alone, telemetry-only logs) give no row.

Columns (besides the runner's keys):

======================= ============ ===========================================================
column                  type         meaning
======================= ============ ===========================================================
imu                     string       IMU instance replayed (the reader's choice)
imu_rate_hz             float64      its median rate, Hz
duration_s              float64      replayed span, s
gnss_fixes              int32        GNSS fixes in the log
excluded_fixes          int32        fixes the filter's integrity tests excluded
reference               string       ``truth`` or the autopilot estimate's name (null: none)
horizontal_rms_m        float64      RMS horizontal position difference, m (null: no reference)
vertical_rms_m          float64      RMS vertical difference, m
velocity_rms_m_s        float64      RMS 3-D velocity difference, m/s (null: reference has none)
outage_against          string       ``truth`` or ``gnss``
outage_10s_m …          float64      median horizontal error after a 10 / 30 / 60 s outage, m
outage_10s_n …          int32        outages of that length run (0: the log is too short)
======================= ============ ===========================================================
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pyarrow as pa

from uasnav.fleet.logs import format_of, gnss_companion, read_fleet_log
from uasnav.fleet.runner import Analysis, LogRows

#: GNSS outage lengths (s) and outages per length.
OUTAGE_DURATIONS = (10.0, 30.0, 60.0)
OUTAGES_PER_DURATION = 3

_LOGGED = ("ardupilot-dataflash", "px4-ulog", "mavlink-tlog")

NAV_SCHEMA = pa.schema(
    [
        pa.field("imu", pa.string()),
        pa.field("imu_rate_hz", pa.float64()),
        pa.field("duration_s", pa.float64()),
        pa.field("gnss_fixes", pa.int32()),
        pa.field("excluded_fixes", pa.int32()),
        pa.field("reference", pa.string()),
        pa.field("horizontal_rms_m", pa.float64()),
        pa.field("vertical_rms_m", pa.float64()),
        pa.field("velocity_rms_m_s", pa.float64()),
        pa.field("outage_against", pa.string()),
        *[
            f
            for d in OUTAGE_DURATIONS
            for f in (pa.field(f"outage_{d:g}s_m", pa.float64()), pa.field(f"outage_{d:g}s_n", pa.int32()))
        ],
    ]
)


def _truth(flight: Any) -> Any:
    """The simulated truth of a CSV v1 flight (its ``truth_*`` columns) as a Trajectory."""
    from uasnav.io.flight import Trajectory

    tr = flight.imu.truth or {}
    if not {"lat", "lon", "alt"} <= set(tr):
        return None
    return Trajectory(
        flight.imu.t,
        tr["lat"],
        tr["lon"],
        tr["alt"],
        vel=tr.get("vel"),
        euler_deg=tr.get("euler_deg"),
        name="truth",
    )


def nav_log(path: str) -> LogRows:
    """The GNSS/INS replay row of one log (module docs); no row without IMU or GNSS."""
    from uasnav import ins
    from uasnav.ins import evaluate

    fmt = format_of(path)
    companion = gnss_companion(path) if fmt == "csv-v1" else None
    if fmt not in _LOGGED and companion is None:
        return LogRows([])
    log = read_fleet_log(path, need=("nav",), gnss=companion)
    if not log.imus or log.file is None:
        return LogRows([], vehicle=log.vehicle, day=log.day)
    flight = log.file.nav
    truth = flight.truth if flight.truth is not None else _truth(flight)
    if truth is not None:
        flight = dataclasses.replace(flight, truth=truth)
    cfg = ins.InsConfig.for_logged_imu() if fmt in _LOGGED else ins.InsConfig()
    result = ins.run(flight, cfg)
    ref = truth if truth is not None else flight.reference
    row: dict[str, Any] = {
        "imu": str(flight.meta.get("imu", "")),
        "imu_rate_hz": float(flight.imu.sample_rate),
        "duration_s": float(flight.imu.t[-1] - flight.imu.t[0]),
        "gnss_fixes": int(flight.gnss.n),
        "excluded_fixes": len(result.excluded_fixes),
        "reference": None if ref is None else ref.name,
    }
    if ref is not None:
        c = evaluate.compare(result, ref)
        row.update(
            horizontal_rms_m=c.horizontal_rms_m,
            vertical_rms_m=c.vertical_rms_m,
            velocity_rms_m_s=c.velocity_rms_m_s,
        )
    against = "truth" if truth is not None else "gnss"
    table = evaluate.outage_experiment(
        flight, OUTAGE_DURATIONS, config=cfg, per_duration=OUTAGES_PER_DURATION, against=against
    )
    by = table.by_duration()
    row["outage_against"] = against
    for d in OUTAGE_DURATIONS:
        errs = [o.horizontal_error_m for o in by.get(d, [])]
        row[f"outage_{d:g}s_m"] = float(np.median(errs)) if errs else None
        row[f"outage_{d:g}s_n"] = len(errs)
    return LogRows([row], vehicle=log.vehicle, day=log.day)


NAV = Analysis("nav", NAV_SCHEMA, nav_log)

__all__ = ["NAV", "NAV_SCHEMA", "OUTAGES_PER_DURATION", "OUTAGE_DURATIONS", "nav_log"]
