"""ArduPilot logs: DataFlash (``.bin``) and MAVLink telemetry (``.tlog``).

The readers live in :mod:`uasnav.io.dataflash` and :mod:`uasnav.io.tlog`; this module keeps
the documented names ``uasnav.io.ardupilot.read_dataflash`` (every IMU of a DataFlash log,
keyed ``"IMU"``, ``"IMU2"``, ``"IMU3"`` or ``"IMU[i]"``) and ``read_tlog`` (every IMU stream
of a telemetry log, split at autopilot reboots).
"""

from __future__ import annotations

from uasnav.io.dataflash import read_dataflash, read_dataflash_flight
from uasnav.io.tlog import read_tlog, read_tlog_flight

__all__ = ["read_dataflash", "read_dataflash_flight", "read_tlog", "read_tlog_flight"]
