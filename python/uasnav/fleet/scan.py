"""``uasnav fleet scan``: the inventory of a fleet's logs, one row per log.

Columns (besides the runner's ``log_hash``, ``path``, ``size_bytes``, ``row`` and the partition
columns ``vehicle``/``day``):

=============== ========================== ====================================================
column          type                       meaning
=============== ========================== ====================================================
format          string                     :data:`uasnav.fleet.logs.FORMATS`
vehicle_id      string (null)              vehicle identifier written in the log
autopilot       string (null)              PX4, ArduPilot or what the log says
start_time      timestamp[ms, UTC] (null)  start of the recording
duration_s      float64                    longest span of the IMU or telemetry data, s
n_imus          int32                      IMU instances
imus            list<struct>               per IMU: ``name``, ``n_samples``, ``rate_hz``
                                           (median), ``temp_min_c``/``temp_max_c`` (null
                                           without a temperature channel)
gnss            bool                       the log has GNSS fixes (CSV v1: its
                                           ``X_gnss.csv``)
mission         bool                       the log has mission waypoints
n_waypoints     int32                      mission navigation waypoints
=============== ========================== ====================================================
"""

from __future__ import annotations

import pyarrow as pa

from uasnav.errors import UasnavError
from uasnav.fleet.logs import format_of, gnss_companion, read_fleet_log
from uasnav.fleet.runner import Analysis, LogRows

IMU_TYPE = pa.struct(
    [
        pa.field("name", pa.string()),
        pa.field("n_samples", pa.int64()),
        pa.field("rate_hz", pa.float64()),
        pa.field("temp_min_c", pa.float64()),
        pa.field("temp_max_c", pa.float64()),
    ]
)

SCAN_SCHEMA = pa.schema(
    [
        pa.field("format", pa.string()),
        pa.field("vehicle_id", pa.string()),
        pa.field("autopilot", pa.string()),
        pa.field("start_time", pa.timestamp("ms", tz="UTC")),
        pa.field("duration_s", pa.float64()),
        pa.field("n_imus", pa.int32()),
        pa.field("imus", pa.list_(IMU_TYPE)),
        pa.field("gnss", pa.bool_()),
        pa.field("mission", pa.bool_()),
        pa.field("n_waypoints", pa.int32()),
    ]
)

_TELEMETRY = ("px4-ulog", "ardupilot-dataflash", "mavlink-tlog", "flight-csv")


def scan_log(path: str) -> LogRows:
    """The inventory row of one log (module table)."""
    log = read_fleet_log(path, need=("flight",) if format_of(path) in _TELEMETRY else ())
    imus = []
    duration = 0.0
    for name, imu in sorted(log.imus.items()):
        duration = max(duration, imu.duration)
        imus.append(
            {
                "name": name,
                "n_samples": imu.n,
                "rate_hz": imu.sample_rate,
                "temp_min_c": None if imu.temp is None else float(imu.temp.min()),
                "temp_max_c": None if imu.temp is None else float(imu.temp.max()),
            }
        )
    gnss, waypoints = False, 0
    if log.format in _TELEMETRY:
        try:
            fl = log.file.flight if log.file is not None else None
        except UasnavError:
            fl = None  # no (valid) GNSS in this log: that is what the column says
        if fl is not None:
            gnss = fl.t.size > 0
            waypoints = len(fl.waypoints)
            duration = max(duration, float(fl.t[-1] - fl.t[0]) if fl.t.size else 0.0)
    elif log.format == "csv-v1" and (companion := gnss_companion(path)) is not None:
        from uasnav.io.formats.gnss_csv import read_gnss_csv

        gnss = read_gnss_csv(companion).n > 0
    row = {
        "format": log.format,
        "vehicle_id": log.vehicle,
        "autopilot": log.autopilot,
        "start_time": log.start_time,
        "duration_s": duration,
        "n_imus": len(imus),
        "imus": imus,
        "gnss": gnss,
        "mission": waypoints > 0,
        "n_waypoints": waypoints,
    }
    return LogRows([row], vehicle=log.vehicle, day=log.day)


SCAN = Analysis("scan", SCAN_SCHEMA, scan_log)

__all__ = ["IMU_TYPE", "SCAN", "SCAN_SCHEMA", "scan_log"]
