"""ASTM F3548-21 operational intents as JSON, typed with the ``uas-standards`` package.

The types are the field's own (``uas_standards.astm.f3548.v21.api``): an
``OperationalIntentDetails`` (``volumes``, ``off_nominal_volumes``, ``priority``) of
``Volume4D`` (a ``Volume3D`` — one outline, polygon or circle, between ``altitude_lower`` and
``altitude_upper`` — alive from ``time_start`` to ``time_end``). ``ImplicitDict.parse`` checks
the types (numbers, enums such as the ``W84`` altitude reference, RFC 3339 times);
:func:`check_details` then checks what the standard states in words and the types cannot:
exactly one outline per volume, a polygon of at least 3 distinct vertices whose edges do not
cross, a positive radius in metres, finite latitudes/longitudes within range, both altitudes
and both times present, lower ≤ upper and start < end.

Files read (:func:`read_intents`): an ``OperationalIntentDetails`` object, a full
``OperationalIntent`` (``{"reference": …, "details": …}``; only the details are used), or
``{"intents": {name: details, …}}`` holding several; InterUSS flight-intent templates (YAML)
are read by :mod:`uasnav.io.interuss`. Every error names the file and the JSON path.
"""

from __future__ import annotations

import functools
import json
import math
import os
import re
import typing
from dataclasses import dataclass
from datetime import datetime, timedelta, timezone
from types import UnionType
from typing import Any

import numpy as np

from uasnav import jsoncheck as jc
from uasnav._extras import require
from uasnav.atomicfile import atomic_write_text
from uasnav.errors import DataFormatError, InputError

#: Largest intent file read (bytes).
MAX_INTENT_BYTES = 64 * 2**20
#: F3548 ``OiMaxPlanHorizon``: an intent may not start more than 30 days ahead.
MAX_PLAN_HORIZON = timedelta(days=30)
#: F3548 ``TimeSyncMaxDifferentialSeconds``: clocks may differ by 5 s, so an intent whose end
#: is 5 s or more in the past has ended.
TIME_SYNC_TOLERANCE = timedelta(seconds=5)
#: Altitude bounds F3548 data may hold, m (W84).
ALTITUDE_RANGE_M = (-8000.0, 100_000.0)


def _api() -> Any:
    require("utm", "reading or writing ASTM F3548 operational intents")
    from uas_standards.astm.f3548.v21 import api

    return api


@dataclass(frozen=True)
class NamedIntent:
    """An operational intent and the name it goes by in messages (file name, template key).

    ``details`` is a ``uas_standards.astm.f3548.v21.api.OperationalIntentDetails``.
    """

    name: str
    details: Any
    source: str = "<intent>"


# RFC 3339 with a zone and at most microseconds: what datetime.fromisoformat reads exactly as
# arrow does (other spellings take the library's own path)
_RFC3339 = re.compile(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d(?:\.\d{1,6})?(?:Z|[+-]\d\d:\d\d)\Z")


class _LibraryPath(Exception):
    """The fast parser met something it does not handle itself."""


def _library_path(value: Any) -> Any:
    raise _LibraryPath


@functools.cache
def _reader(vt: Any) -> Any:
    """A function reading JSON data as type ``vt`` the way ``ImplicitDict.parse`` does (one
    per type, built once), raising :class:`_LibraryPath` where it would not be sure to."""
    from enum import Enum

    from implicitdict import ImplicitDict, StringBasedDateTime

    origin = typing.get_origin(vt)
    if origin is not None:
        args = typing.get_args(vt)
        if origin is list:
            item = _reader(args[0])

            def read_list(value: Any) -> Any:
                if type(value) is not list:
                    raise _LibraryPath
                return [item(v) for v in value]

            return read_list
        if origin in (typing.Union, UnionType) and len(args) >= 2 and type(None) in args:
            first = _reader(args[0])
            return lambda value: None if value is None else first(value)
        return _library_path
    if vt is StringBasedDateTime:

        def read_time(value: Any) -> Any:
            if type(value) is not str or not _RFC3339.match(value):
                raise _LibraryPath
            out = str.__new__(StringBasedDateTime, value)
            out.datetime = datetime.fromisoformat(value)
            return out

        return read_time
    if isinstance(vt, type):
        if issubclass(vt, ImplicitDict):
            fields: dict[str, Any] = {}

            def read_obj(value: Any) -> Any:
                if type(value) is not dict:
                    raise _LibraryPath
                if not fields:  # filled on first use: the hints may refer to this very type
                    fields.update({k: _reader(h) for k, h in typing.get_type_hints(vt).items()})
                return vt(**{k: fields[k](v) if k in fields else v for k, v in value.items()})

            return read_obj
        if vt is float:

            def read_float(value: Any) -> Any:
                if type(value) not in (int, float):
                    raise _LibraryPath
                return float(value)

            return read_float
        if vt in (int, str):

            def read_exact(value: Any) -> Any:
                if type(value) is not vt:
                    raise _LibraryPath
                return value

            return read_exact
        if issubclass(vt, Enum) and not getattr(vt, "__orig_bases__", None):
            return vt
    return _library_path


def parse_f3548(source: object, parse_type: type) -> Any:
    """``ImplicitDict.parse(source, parse_type)`` (a ``uas-standards`` type), faster.

    The library's parser evaluates every class's type hints again for every object it builds
    (≈ 60 % of its time) and reads times with ``arrow``. This walks the same type hints, cached
    per class, builds the same ``ImplicitDict`` objects and reads strict RFC 3339 times with
    ``datetime.fromisoformat``. Anything else — any error, or a value spelled otherwise
    than JSON spells it (a number as a string, a time without a zone) — is handed to the
    library's own parser, so accepted inputs, results and error messages are the library's.
    """
    from implicitdict import ImplicitDict

    try:
        return _reader(parse_type)(source)
    except Exception:  # the library decides, and words the error
        return ImplicitDict.parse(source, parse_type)  # type: ignore[arg-type]


def parse_details(d: object, where: str = "") -> Any:
    """An ``OperationalIntentDetails`` from JSON data, type- and rule-checked (see module).

    Raises :class:`DataFormatError` naming the JSON path below ``where``.
    """
    api = _api()
    obj = jc.obj(d, where or "intent")
    try:
        details = parse_f3548(obj, api.OperationalIntentDetails)
    except (ValueError, TypeError, KeyError, OverflowError) as e:
        msg = str(e)
        if msg.startswith("At "):  # ImplicitDict names the path: "At volumes[0].…: problem"
            path, _, problem = msg[3:].partition(": ")
            raise jc.fail(f"{where}.{path}" if where else path, problem) from None
        raise jc.fail(
            where or "intent", f"not an F3548 OperationalIntentDetails ({type(e).__name__}: {msg})"
        ) from None
    except Exception as e:  # dateutil's ParserError etc.: a malformed value
        msg = str(e)
        path, _, problem = msg[3:].partition(": ") if msg.startswith("At ") else ("", "", msg)
        raise jc.fail(f"{where}.{path}".strip(".") or "intent", problem or type(e).__name__) from None
    check_details(details, where)
    return details


def _finite(x: float, path: str, lo: float, hi: float, unit: str) -> float:
    v = float(x)
    if not (math.isfinite(v) and lo <= v <= hi):
        raise jc.fail(path, f"{x!r} {unit} outside [{lo:g}, {hi:g}] {unit}")
    return v


_Deferred = list[tuple[str, list[tuple[float, float]]]]


def check_volume(v: Any, path: str, deferred: _Deferred | None = None) -> None:
    """The F3548 rules of one ``Volume4D`` that its types do not enforce (see module).

    With ``deferred``, the polygon's crossing-edges test is not run but appended there as
    (path, vertices) for :func:`_check_edges` (one vectorised shapely call per intent).
    """
    vol = v.volume
    poly, circ = vol.get("outline_polygon"), vol.get("outline_circle")
    if (poly is None) == (circ is None):
        raise jc.fail(f"{path}.volume", "exactly one of outline_polygon and outline_circle must be given")
    if poly is not None:
        verts = poly.vertices
        if len(verts) < 3:
            raise jc.fail(
                f"{path}.volume.outline_polygon.vertices", f"{len(verts)} vertices, a polygon needs 3"
            )
        pts = []
        for k, p in enumerate(verts):
            vp = f"{path}.volume.outline_polygon.vertices[{k}]"
            pts.append(
                (_finite(p.lng, vp + ".lng", -180, 180, "°"), _finite(p.lat, vp + ".lat", -90, 90, "°"))
            )
        if len(set(pts)) != len(pts):
            raise jc.fail(
                f"{path}.volume.outline_polygon.vertices",
                "duplicated vertex (F3548: vertices may not be duplicated)",
            )
        if deferred is not None:
            deferred.append((path, pts))
        else:
            _check_edges([(path, pts)])
    else:
        cp = f"{path}.volume.outline_circle"
        if circ.get("center") is None or circ.get("radius") is None:
            raise jc.fail(cp, "a circle needs center and radius")
        _finite(circ.center.lat, cp + ".center.lat", -90, 90, "°")
        _finite(circ.center.lng, cp + ".center.lng", -180, 180, "°")
        r = _finite(circ.radius.value, cp + ".radius.value", 0, 1e6, "m")
        if not r > 0:
            raise jc.fail(cp + ".radius.value", "radius must be > 0 m")
    lo, hi = vol.get("altitude_lower"), vol.get("altitude_upper")
    for name, a in (("altitude_lower", lo), ("altitude_upper", hi)):
        if a is None:
            raise jc.fail(f"{path}.volume.{name}", "missing (F3548: required in an operational intent)")
        _finite(a.value, f"{path}.volume.{name}.value", *ALTITUDE_RANGE_M, "m")
    if lo.value > hi.value:
        raise jc.fail(f"{path}.volume", f"altitude_lower {lo.value} m is above altitude_upper {hi.value} m")
    for name in ("time_start", "time_end"):
        if v.get(name) is None:
            raise jc.fail(f"{path}.{name}", "missing (F3548: required in an operational intent)")
    if not v.time_start.value.datetime < v.time_end.value.datetime:
        raise jc.fail(path, "time_start is not before time_end")


def _check_edges(polygons: _Deferred) -> None:
    """Raise for the first polygon whose edges cross (shapely validity, vectorised)."""
    if not polygons:
        return
    import shapely

    lens = [len(p) for _, p in polygons]
    rings = shapely.linearrings(
        np.array([xy for _, p in polygons for xy in p], dtype=float),
        indices=np.repeat(np.arange(len(polygons)), lens),
    )
    bad = np.flatnonzero(~shapely.is_valid(shapely.polygons(rings)))
    if bad.size:
        path = polygons[bad[0]][0]
        raise jc.fail(f"{path}.volume.outline_polygon", "edges cross (F3548: edges may not cross)")


def check_details(details: Any, where: str = "") -> None:
    """Check every volume of an ``OperationalIntentDetails`` (:func:`check_volume`); at least
    one volume in ``volumes``. The first problem in volume order is the one reported."""
    pre = f"{where}." if where else ""
    vols = details.get("volumes") or []
    if not vols:
        raise jc.fail(f"{pre}volumes", "an operational intent needs at least one volume")
    deferred: _Deferred = []
    try:
        for key in ("volumes", "off_nominal_volumes"):
            for k, v in enumerate(details.get(key) or []):
                check_volume(v, f"{pre}{key}[{k}]", deferred)
    except DataFormatError:
        _check_edges(deferred)  # a crossing in an earlier volume comes first
        raise
    _check_edges(deferred)


def check_times(intent: NamedIntent, now: datetime) -> None:
    """The F3548 time rules at ``now``: no volume may end more than
    :data:`TIME_SYNC_TOLERANCE` in the past, none may start beyond :data:`MAX_PLAN_HORIZON`.

    Raises :class:`InputError` naming the intent and volume.
    """
    for k, v in enumerate(intent.details.volumes):
        t0, t1 = v.time_start.value.datetime, v.time_end.value.datetime
        if t1 <= now - TIME_SYNC_TOLERANCE:
            raise InputError(
                f"{intent.name}: volumes[{k}] ended at {t1.isoformat()}, before now ({now.isoformat()}): "
                "F3548 intents may not end in the past"
            )
        if t0 > now + MAX_PLAN_HORIZON:
            raise InputError(
                f"{intent.name}: volumes[{k}] starts at {t0.isoformat()}, more than 30 days after now "
                f"({now.isoformat()}): beyond the F3548 planning horizon (OiMaxPlanHorizon)"
            )


def parse_intents(d: object, source: str, name: str) -> list[NamedIntent]:
    """Intents from the JSON data of one file (see module for the accepted shapes)."""
    with jc.reraise_in(source):
        obj = jc.obj(d, "")
        if "intents" in obj:
            group = jc.obj(obj["intents"], "intents")
            if not group:
                raise jc.fail("intents", "no intents")
            return [
                NamedIntent(str(k), _one(jc.obj(v, f"intents.{k}"), f"intents.{k}"), source)
                for k, v in group.items()
            ]
        return [NamedIntent(name, _one(obj, ""), source)]


def _one(obj: dict[str, Any], where: str) -> Any:
    if "details" in obj:
        return parse_details(obj["details"], f"{where}.details".lstrip("."))
    return parse_details(obj, where)


def read_intents(path: str | os.PathLike[str]) -> list[NamedIntent]:
    """Read the operational intent(s) of a JSON file (named by the file's stem, or by their
    keys under ``"intents"``)."""
    p = os.fspath(path)
    if not os.path.exists(p):
        raise InputError(f"no such intent file: {p}")
    if os.path.isdir(p):
        raise InputError(f"{p}: is a directory, not an intent file")
    with jc.reraise_in(p):
        d = jc.parse(jc.read_text(p, MAX_INTENT_BYTES), "not an operational intent: not valid JSON")
    return parse_intents(d, p, os.path.splitext(os.path.basename(p))[0])


def to_json(details: Any) -> dict[str, Any]:
    """The JSON data of an ``OperationalIntentDetails`` (re-parsed and checked first, so a
    file written is a file :func:`read_intents` accepts)."""
    data = json.loads(json.dumps(details))
    parse_details(data)
    return data


def write_intent(details: Any, path: str | os.PathLike[str]) -> None:
    """Write an ``OperationalIntentDetails`` as JSON, checked (:func:`to_json`), atomically."""
    try:
        text = json.dumps(to_json(details), indent=1, allow_nan=False)
    except DataFormatError as e:
        raise InputError(f"refusing to write an invalid operational intent: {e}") from None
    atomic_write_text(path, text + "\n")


def intent_geojson(details: Any, route: list[tuple[float, float, float]] | None = None) -> dict[str, Any]:
    """A GeoJSON FeatureCollection of an intent's volumes (Polygon features; circles as
    64-gons, with their centre and radius kept in the properties) and, if given, the route
    (a LineString of (lon, lat, alt W84)). Properties: ``altitude_lower_w84_m``,
    ``altitude_upper_w84_m``, ``time_start``, ``time_end``, ``index``."""
    from uasnav.geo import frames

    feats: list[dict[str, Any]] = []
    for k, v in enumerate(details.volumes):
        vol = v.volume
        props: dict[str, Any] = {
            "index": k,
            "altitude_lower_w84_m": float(vol.altitude_lower.value),
            "altitude_upper_w84_m": float(vol.altitude_upper.value),
            "time_start": str(v.time_start.value),
            "time_end": str(v.time_end.value),
        }
        if vol.get("outline_polygon") is not None:
            ring = [[float(p.lng), float(p.lat)] for p in vol.outline_polygon.vertices]
        else:
            c = vol.outline_circle
            r = float(c.radius.value)
            props["circle"] = {"center": [float(c.center.lng), float(c.center.lat)], "radius_m": r}
            a = np.linspace(0.0, 2 * np.pi, 65)[:-1]
            la, lo, _ = frames.enu_to_geodetic(
                r * np.cos(a), r * np.sin(a), 0.0, c.center.lat, c.center.lng, 0.0
            )
            ring = [[float(x), float(y)] for x, y in zip(lo, la, strict=True)]
        feats.append(
            {
                "type": "Feature",
                "properties": props,
                "geometry": {"type": "Polygon", "coordinates": [[*ring, ring[0]]]},
            }
        )
    if route is not None:
        feats.append(
            {
                "type": "Feature",
                "properties": {"kind": "route"},
                "geometry": {"type": "LineString", "coordinates": [[lo, la, al] for la, lo, al in route]},
            }
        )
    return {"type": "FeatureCollection", "features": feats}


def write_intent_geojson(
    details: Any, path: str | os.PathLike[str], route: list[tuple[float, float, float]] | None = None
) -> None:
    """Write :func:`intent_geojson` atomically."""
    atomic_write_text(path, json.dumps(intent_geojson(details, route), indent=1, allow_nan=False) + "\n")


def rfc3339(t: datetime) -> str:
    """``t`` as F3548 wants it: RFC 3339 in UTC with a ``Z``."""
    if t.tzinfo is None:
        raise InputError(f"time {t.isoformat()} has no time zone")
    return t.astimezone(timezone.utc).isoformat(timespec="microseconds").replace("+00:00", "Z")


__all__ = [
    "MAX_PLAN_HORIZON",
    "TIME_SYNC_TOLERANCE",
    "NamedIntent",
    "check_details",
    "check_times",
    "check_volume",
    "intent_geojson",
    "parse_details",
    "parse_intents",
    "read_intents",
    "rfc3339",
    "to_json",
    "write_intent",
    "write_intent_geojson",
]
