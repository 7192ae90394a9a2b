"""GPS time in the calendar: a GPS week and time of week as UTC, and a date as a decimal year.

The flight-log readers date a log with these (DataFlash ``GPS`` week/ms, ULog GPS time), and the
magnetic model takes the decimal year (:mod:`uasnav.ins.magnetic`).
"""

from __future__ import annotations

import datetime as _dt

__all__ = ["GPS_UTC_LEAP_S", "decimal_year", "gps_week_ms_to_utc"]

#: GPS time − UTC (leap seconds) since 2017-01-01; a few seconds do not matter to the WMM.
GPS_UTC_LEAP_S = 18


def decimal_year(when: _dt.datetime) -> float:
    """``when`` (naive = UTC) as a decimal year, e.g. 2015-07-02T12:00 → 2015.5."""
    start = _dt.datetime(when.year, 1, 1, tzinfo=when.tzinfo)
    end = _dt.datetime(when.year + 1, 1, 1, tzinfo=when.tzinfo)
    return when.year + (when - start).total_seconds() / (end - start).total_seconds()


def gps_week_ms_to_utc(week: float, time_ms: float) -> _dt.datetime:
    """UTC (naive) of a GPS week number and time of week (ms)."""
    return (
        _dt.datetime(1980, 1, 6)
        + _dt.timedelta(weeks=float(week), milliseconds=float(time_ms))
        - _dt.timedelta(seconds=GPS_UTC_LEAP_S)
    )
