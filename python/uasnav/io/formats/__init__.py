"""One class per log format, and each format's rules only there.

:class:`~uasnav.io.formats.base.LogFormat` is the base: which message types each view needs, one
decoding pass for the union of them, the view builders. The formats:

======================================= ==========================================
module                                  format
======================================= ==========================================
:mod:`~uasnav.io.formats.ulog`          PX4 ULog
:mod:`~uasnav.io.formats.dataflash`     ArduPilot DataFlash ``.bin``
:mod:`~uasnav.io.formats.tlog`          MAVLink telemetry ``.tlog``
:mod:`~uasnav.io.formats.alfa`          ALFA ROS-topic CSV folders
:mod:`~uasnav.io.formats.csv_v1`        uasnav log format v1 (CSV IMU log)
:mod:`~uasnav.io.formats.gnss_csv`      GNSS CSV (the fixes beside a CSV v1 log)
:mod:`~uasnav.io.formats.xio`           x-io Technologies CSV
:mod:`~uasnav.io.formats.flight_csv`    flight CSV (a telemetry track)
:mod:`~uasnav.io.formats.npz`           uasnav / ADIS ``.npz`` arrays
======================================= ==========================================

Open a log with :func:`uasnav.io.open_log`, which picks the class.
"""

from uasnav.io.formats.base import ImuFileFormat, LogFormat, ScannedFormat, WholeFileFormat

__all__ = ["ImuFileFormat", "LogFormat", "ScannedFormat", "WholeFileFormat"]
