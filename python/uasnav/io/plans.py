"""Mission plans: read and write every plan format into one typed :class:`MissionPlan`.

Usage (``survey.plan`` being any plan file)::

    from uasnav.io.plans import read_plan, plan_route
    plan = read_plan("survey.plan")
    route_ne, origin = plan_route(plan)

The format follows the extension (:data:`PLAN_READERS`): QGroundControl ``.plan`` (JSON),
Mission Planner ``.waypoints`` / ``.txt`` (``QGC WPL 110``), uasnav's plan ``.csv``
(``lat,lon[,alt]`` or ``north,east``), KML (``.kml``: a LineString or Point placemarks) and
GeoJSON (``.geojson``: a LineString or Points, with an explicit ``altitude_frame``), and the
plan embedded in a log (``.tlog`` MISSION_ITEM(_INT), ``.bin`` DataFlash CMD, ``.ulg`` PX4
``navigator_mission_item``). Writers
are atomic and round-trip their own format item for item (KML and GeoJSON: the positioned
waypoints only). The model (items, altitude frames, command kinds, home position, speed changes,
loiter times) is :mod:`uasnav.io.mission_plan`; :func:`plan_route` turns a plan into the
horizontal route (north/east m) that :class:`~uasnav.trajectory.predictor.TrajectoryPredictor`
predicts, and :func:`plan_cruise_speed` gives the speed the plan commands.

Hostile files: reads are bounded (:data:`MAX_PLAN_BYTES`), and every malformed value is a
:class:`~uasnav.errors.DataFormatError` naming the file and the line (text formats) or the JSON
path (``mission.items[3].params[4]``); impossible values (latitude beyond ±90°, altitudes
outside −1 … 20 km, unknown altitude frames) are refused the same way.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from uasnav.errors import InputError
from uasnav.io.logfile import open_log
from uasnav.io.mission_plan import (
    AltitudeFrame,
    HomePosition,
    ItemKind,
    MissionItem,
    MissionPlan,
    flight_sequence,
    plan_cruise_speed,
    plan_route,
)
from uasnav.io.plan_formats.csv_plan import read_plan_csv, write_plan_csv
from uasnav.io.plan_formats.geojson import read_geojson, write_geojson
from uasnav.io.plan_formats.kml import read_kml, write_kml
from uasnav.io.plan_formats.qgc import read_qgc_plan, write_qgc_plan
from uasnav.io.plan_formats.source import MAX_PLAN_BYTES
from uasnav.io.plan_formats.wpl import read_wpl, write_wpl

#: Extension → reader.
PLAN_READERS: dict[str, Callable[[str | os.PathLike[str]], MissionPlan]] = {
    ".plan": read_qgc_plan,
    ".waypoints": read_wpl,
    ".txt": read_wpl,
    ".csv": read_plan_csv,
    ".kml": read_kml,
    ".geojson": read_geojson,
    ".tlog": lambda p: _log_plan(p),
    ".bin": lambda p: _log_plan(p),
    ".ulg": lambda p: _log_plan(p),
}
#: Extension → writer.
PLAN_WRITERS: dict[str, Callable[[MissionPlan, str | os.PathLike[str]], None]] = {
    ".plan": write_qgc_plan,
    ".waypoints": write_wpl,
    ".txt": write_wpl,
    ".csv": write_plan_csv,
    ".kml": write_kml,
    ".geojson": write_geojson,
}
PLAN_EXTENSIONS = tuple(PLAN_READERS)


def read_plan(path: str | os.PathLike[str]) -> MissionPlan:
    """Read a mission plan; the format follows the extension (:data:`PLAN_EXTENSIONS`).

    Raises
    ------
    InputError
        Unknown extension, no such file, a directory.
    DataFormatError
        Malformed content (names the file and the line or JSON path).
    ResourceLimitError
        A file larger than :data:`MAX_PLAN_BYTES`.
    """
    p = Path(path)
    reader = PLAN_READERS.get(p.suffix.lower())
    if reader is None:
        raise InputError(f"{p}: unknown plan format {p.suffix!r} (supported: {', '.join(PLAN_EXTENSIONS)})")
    return reader(p)


def write_plan(plan: MissionPlan, path: str | os.PathLike[str]) -> None:
    """Write ``plan`` atomically; the format follows the extension (:data:`PLAN_EXTENSIONS`)."""
    p = Path(path)
    writer = PLAN_WRITERS.get(p.suffix.lower())
    if writer is None:
        raise InputError(
            f"{p}: cannot write plan format {p.suffix!r} (supported: {', '.join(PLAN_EXTENSIONS)})"
        )
    writer(plan, p)


def read_plan_route(
    path: str | os.PathLike[str], *, other_as_csv: bool = False
) -> tuple[np.ndarray, tuple[float, float, float] | None]:
    """``plan_route(read_plan(path))``: the horizontal route (north/east m, shape (n, 2)) in
    flown order and its geodetic origin (the first waypoint: lat °, lon °, alt m; None for a
    local ``north,east`` plan). With ``other_as_csv`` a file of another extension is read as a
    plan CSV (the predictor's route files), at most :data:`MAX_PLAN_BYTES`."""
    p = Path(path)
    if other_as_csv and p.suffix.lower() not in PLAN_READERS:
        return plan_route(read_plan_csv(p))
    return plan_route(read_plan(p))


def _log_plan(path: str | os.PathLike[str]) -> MissionPlan:
    """The plan a flight log carries (``open_log(path).plan``)."""
    return open_log(path, need=("plan",)).plan  # type: ignore[no-any-return]


__all__ = [
    "MAX_PLAN_BYTES",
    "PLAN_EXTENSIONS",
    "PLAN_READERS",
    "PLAN_WRITERS",
    "AltitudeFrame",
    "HomePosition",
    "ItemKind",
    "MissionItem",
    "MissionPlan",
    "flight_sequence",
    "plan_cruise_speed",
    "plan_route",
    "read_plan",
    "read_plan_route",
    "write_plan",
]
