"""``uasnav fleet elements``: trajectory elements of every log that flew a mission.

The rows are :mod:`uasnav.trajectory.element_table`'s schema (the one definition used by
``uasnav.trajectory`` too), measured by the same pipeline as ``uasnav trajectory train``
(:func:`uasnav.trajectory.flights.flight_samples`: mission runs cut from the log's waypoints,
cruise speed and wind from the log, else calm). A log without telemetry (CSV v1, x-io, npz) or
without mission waypoints gives no rows (it is listed as finished, ``empty``); a log whose
mission cannot be measured is an error row. ``uasnav trajectory train ELEMENTS.parquet``
trains on the result.
"""

from __future__ import annotations

from typing import Any

from uasnav.fleet.logs import format_of
from uasnav.fleet.runner import Analysis, LogRows
from uasnav.trajectory.element_table import ELEMENT_SCHEMA, to_rows
from uasnav.trajectory.geometry import DEFAULT_SEGMENT_M

_TELEMETRY = ("px4-ulog", "ardupilot-dataflash", "mavlink-tlog")


def elements_log(
    path: str, segment_m: float = DEFAULT_SEGMENT_M, cruise_ms: float | None = None, max_gap_s: float = 5.0
) -> LogRows:
    """Element rows of every mission run of one log (empty without a mission); ``cruise_ms``
    overrides the log's waypoint speed (m/s), ``max_gap_s`` is the largest telemetry gap in a
    measured element (s)."""
    from uasnav.io import read_flight
    from uasnav.io.logfile import open_log
    from uasnav.trajectory.flights import flight_samples

    if format_of(path) not in _TELEMETRY:
        return LogRows([])
    if format_of(path) == "flight-csv":
        if not read_flight(path).waypoints:
            return LogRows([])
        source: Any = path
    else:
        source = open_log(path, need=("flight",))
        if not source.flight.waypoints:
            return LogRows([])
    fs = flight_samples([source], cruise_ms=cruise_ms, segment_m=segment_m, max_gap_s=max_gap_s)
    rows = []
    for run, s in enumerate(fs.samples):
        s.flight[:] = run
        rows += to_rows(s, segment_m)
    return LogRows(rows)


ELEMENTS = Analysis("elements", ELEMENT_SCHEMA, elements_log)


def elements_analysis(
    segment_m: float = DEFAULT_SEGMENT_M, cruise_ms: float | None = None, max_gap_s: float = 5.0
) -> Analysis:
    """:data:`ELEMENTS` with other measuring options (a partial of :func:`elements_log`, which
    pickles by reference to the workers)."""
    from functools import partial

    return Analysis(
        "elements",
        ELEMENT_SCHEMA,
        partial(elements_log, segment_m=segment_m, cruise_ms=cruise_ms, max_gap_s=max_gap_s),
    )


__all__ = ["ELEMENTS", "elements_analysis", "elements_log"]
