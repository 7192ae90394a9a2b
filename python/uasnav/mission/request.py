"""The selector's request as a user writes it: one table of options and one parser.

``uasnav select`` (command line), the web form of ``uasnav serve`` and ``POST /api/select``
take the same inputs, with the same names, units, defaults and error messages, because all
three read :data:`SELECT_OPTIONS` and call :func:`parse_select_options`. A new requirement is
one entry in the table (plus the field it fills): the CLI option, the form field and the API
key follow.

Names are snake_case (API keys, form fields); the CLI spells them with dashes
(``image_size`` → ``--image-size``). Values may be typed (numbers, booleans, a mapping of
weights) or text as typed on a command line or in a form (``"70x70"``,
``"range=1,cost=1.25"``). Every refusal is an :class:`OptionError` naming the option.

>>> req = parse_select_options({"range": "300", "image_size": [70, 70]})
>>> req.requirements.range_m, req.requirements.image_size_m, req.weights.cost
(300.0, (70.0, 70.0), 1.25)
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from uasnav.errors import InputError, UasnavError
from uasnav.mission.feasibility import Requirements
from uasnav.mission.operation import OVER_PEOPLE
from uasnav.mission.regulations import DEFAULT_CATEGORY
from uasnav.mission.scoring import PARAMETERS, Targets, Weights
from uasnav.mission.sora import (
    AIRSPACES,
    ARCS,
    DENSITY_CLASSES,
    EDITIONS,
    MITIGATIONS20,
    MITIGATIONS25,
    ROBUSTNESS,
)

if TYPE_CHECKING:
    import datetime as dt

    from uasnav.io.ed269 import Zone
    from uasnav.mission.database import Database
    from uasnav.mission.matrices import Matrices
    from uasnav.mission.regulations import Regulations
    from uasnav.mission.selection import Selection
    from uasnav.mission.zones import MissionArea


class OptionError(InputError):
    """A selector option with a bad value; ``option`` is its snake_case name."""

    def __init__(self, option: str, message: str) -> None:
        super().__init__(message)
        self.option = option


@dataclass(frozen=True)
class SelectOption:
    """One input of the selector.

    ``kind``: ``real`` (a finite number within ``minimum``/``maximum``), ``int``, ``text``,
    ``choice`` (one of ``choices``), ``flag`` (boolean; a ``True`` default is spelt
    ``--name/--no-name`` on the command line), ``size`` (``LENGTHxWIDTH``), ``pairs``
    (``NAME=VALUE,…`` or a mapping), ``density`` (a number of people per km² or a population
    class name), ``mitigations`` (``M1A=low,M2=medium`` or a mapping), ``wind`` (``SPEED[@FROM_DEG]``),
    ``position`` (``LAT,LON`` in degrees), ``datetime`` (ISO 8601
    with a time zone), ``file`` (a document the request carries: the command line reads it from
    a path — or an http(s) URL for zones — the web form uploads it; the parser takes its bytes,
    text, an already parsed JSON object or an :class:`Upload`), ``output`` (a file the command
    line writes: never part of a request, never shown by a web form) or ``source`` (a path or
    URL the *server* opens: command line only, never taken from a web request). ``unit`` is
    shown beside the field and in help.
    """

    name: str
    kind: str
    default: Any
    help: str
    unit: str | None = None
    minimum: float | None = None
    minimum_open: bool = False
    maximum: float | None = None
    choices: tuple[str, ...] | None = None
    #: Thesis table the input comes from, for the form's labels.
    label: str = ""
    #: Where the input sits in the user-input interface (a key of :data:`OPTION_GROUPS`).
    group: str = ""

    @property
    def flag(self) -> str:
        """The command-line spelling, ``--image-size``."""
        return "--" + self.name.replace("_", "-")


#: The groups of the user-input interface (thesis Figure 75: mission, requirements, payload,
#: weather, then the operation and its regulations, and the scoring), key → heading; the last
#: two are command-line only (never form fields).
OPTION_GROUPS: dict[str, str] = {
    "mission": "Mission",
    "requirements": "Requirements",
    "payload": "Payload",
    "weather": "Weather",
    "operation": "Operation and regulations",
    "scoring": "Scoring",
    "output": "Output",
    "sources": "Data sources",
}


#: Every input of ``uasnav select``, in the order of the thesis' user-input interface
#: (Figure 75: mission, requirements, weather, scoring) then the data sources.
SELECT_OPTIONS: tuple[SelectOption, ...] = (
    SelectOption(
        "mission", "text", "precision-agriculture", "Mission id (Table 18).", label="Mission", group="mission"
    ),
    SelectOption(
        # 1 m … 1000 km: below, every aircraft is "open category"; above, no small UAS flies
        "range",
        "real",
        1500.0,
        "Mission range (m).",
        "m",
        1.0,
        False,
        1e6,
        label="Range",
        group="requirements",
    ),
    SelectOption(
        "resolution",
        "real",
        0.05,
        "Ground resolution (m/px).",
        "m/px",
        0.0,
        True,
        label="Resolution",
        group="payload",
    ),
    SelectOption(
        "image_size",
        "size",
        "70x70",
        "Target size LENGTHxWIDTH (m).",
        "m",
        label="Image size",
        group="payload",
    ),
    SelectOption(
        "altitude",
        "real",
        50.0,
        "Flight altitude AGL (m).",
        "m",
        0.0,
        True,
        label="Altitude",
        group="requirements",
    ),
    SelectOption(
        "camera_height",
        "choice",
        "planned",
        "Height at which the cameras' field of view and resolution are tested: planned (the flight "
        "altitude) or regulatory-max (the highest the category allows, the thesis' rule).",
        choices=("planned", "regulatory-max"),
        label="Camera tested at",
        group="payload",
    ),
    SelectOption(
        "imagery", "text", "multispectral", "Camera type, or 'any'.", label="Imagery type", group="payload"
    ),
    SelectOption(
        "wind",
        "wind",
        5.0,
        "Wind speed (m/s), optionally with the direction it blows from: SPEED[@FROM_DEG], e.g. 5@270.",
        "m/s",
        0.0,
        maximum=100.0,
        label="Wind",
        group="weather",
    ),
    SelectOption(
        "rain", "flag", False, "The flight must be possible in rain.", label="Rain", group="weather"
    ),
    SelectOption(
        "speed",
        "real",
        None,
        "Required ground speed against the wind (m/s).",
        "m/s",
        0.0,
        label="Ground speed",
        group="requirements",
    ),
    SelectOption(
        "order_by",
        "choice",
        "cost",
        "Most important parameter: its weight is 1.25 (eq. 61 with cost first).",
        choices=PARAMETERS,
        label="Order by",
        group="scoring",
    ),
    SelectOption(
        "weights",
        "pairs",
        None,
        "Explicit weights, e.g. range=1,weight=0.75,cost=1.25,resolution=1.",
        label="Weights",
        group="scoring",
    ),
    SelectOption(
        "targets",
        "pairs",
        None,
        "TARGET:LIMIT per parameter, e.g. range=5000:1500,weight=800:1600,cost=4000:7000,"
        "resolution=0.01:0.06.",
        label="Targets and limits",
        group="scoring",
    ),
    SelectOption(
        "jurisdiction", "text", "easa", "Regulations: easa | faa.", label="Regulations", group="operation"
    ),
    SelectOption(
        "category",
        "text",
        None,
        "Category (default: derived from the operation — open or specific for easa, part107 for faa).",
        label="Category",
        group="operation",
    ),
    SelectOption(
        "gnss_autopilot",
        "flag",
        True,
        "A GNSS-based autopilot is required (thesis Table 22); UAS without one are rejected.",
        label="GNSS autopilot",
        group="requirements",
    ),
    SelectOption(
        "max_distance",
        "real",
        None,
        "Largest remote pilot–UA distance (m); default: the range.",
        "m",
        0.0,
        True,
        1e6,
        label="Max pilot distance",
        group="requirements",
    ),
    SelectOption(
        "vlos_distance",
        "real",
        None,
        "Distance up to which the UA is kept in sight (m); default: from each UA's size (EASA AMC1 "
        "Art. 11 Annex A A.5.2.5: min(327 CD + 20 m rotorcraft, 490 CD + 30 m fixed wing; 1500 m)).",
        "m",
        0.0,
        True,
        label="VLOS distance",
        group="operation",
    ),
    SelectOption(
        "observers",
        "int",
        0,
        "Airspace observers posted along the route (EVLOS, specific category).",
        minimum=0,
        maximum=100,
        label="Observers",
        group="operation",
    ),
    SelectOption(
        "over_people",
        "choice",
        "none",
        "Flight over people: none | uninvolved | assemblies.",
        choices=OVER_PEOPLE,
        label="Over people",
        group="operation",
    ),
    SelectOption(
        "population_density",
        "density",
        None,
        "Population density of the area (people/km²) or a SORA 2.5 class: "
        + ", ".join(DENSITY_CLASSES)
        + " (default lightly).",
        "1/km²",
        label="Population density",
        group="operation",
    ),
    SelectOption("night", "flag", False, "The flight is at night.", label="Night", group="weather"),
    SelectOption(
        "airspace",
        "choice",
        "uncontrolled",
        "Airspace (SORA ARC): " + " | ".join(AIRSPACES) + ".",
        choices=AIRSPACES,
        label="Airspace",
        group="operation",
    ),
    SelectOption(
        "mitigations",
        "mitigations",
        None,
        "SORA ground-risk mitigations claimed, e.g. M1A=low,M2=medium (2.5) or M1=medium,M3=low (2.0).",
        label="SORA mitigations",
        group="operation",
    ),
    SelectOption(
        "sora_edition",
        "choice",
        "2.5",
        "JARUS SORA edition: 2.5 | 2.0.",
        choices=EDITIONS,
        label="SORA edition",
        group="operation",
    ),
    SelectOption(
        "residual_arc",
        "choice",
        None,
        "Residual ARC claimed after strategic air-risk mitigations (SORA step #5): a | b | c | d; "
        "default the initial ARC. VLOS may lower it one class (not to ARC-a); other claims are "
        "Annex C claims to substantiate.",
        choices=ARCS,
        label="Residual ARC (strategic mitigation)",
        group="operation",
    ),
    SelectOption(
        "area",
        "file",
        None,
        "Mission area: GeoJSON polygon (or take-off point/line, buffered by --area-buffer or the range), "
        "or a mission plan (.plan, .waypoints, .txt, .csv): its route buffered by --area-buffer.",
        label="Mission area (GeoJSON or plan)",
        group="operation",
    ),
    SelectOption(
        "takeoff",
        "position",
        None,
        "Take-off point LAT,LON (deg); default the plan's first point or the area's centroid.",
        label="Take-off point",
        group="operation",
    ),
    SelectOption(
        "pilot",
        "position",
        None,
        "Remote pilot's position LAT,LON (deg); default the take-off point. With an area, the "
        "pilot distance is the farthest point of the area from here.",
        label="Pilot position",
        group="operation",
    ),
    SelectOption(
        "area_buffer",
        "real",
        None,
        "Buffer around the area (m); default 0 for polygons, the max distance for a point or line, "
        "the flight height for a plan's route (1:1 ground-risk-buffer rule).",
        "m",
        0.0,
        label="Area buffer",
        group="operation",
    ),
    SelectOption(
        "zones",
        "file",
        None,
        "ED-269 geographical zones (JSON): path or http(s) URL.",
        label="Zones (ED-269)",
        group="operation",
    ),
    SelectOption(
        "ground_elevation",
        "real",
        None,
        "Ground elevation (m AMSL), to compare AMSL zone limits with the flight.",
        "m",
        -500.0,
        maximum=9000.0,
        label="Ground elevation",
        group="operation",
    ),
    SelectOption(
        "flight_time",
        "datetime",
        None,
        "Take-off time, ISO 8601 with zone (2026-05-01T10:00Z), for zone schedules.",
        label="Flight time",
        group="operation",
    ),
    SelectOption(
        "flight_duration",
        "real",
        None,
        "Flight duration (s) for zone schedules over [take-off, take-off + duration]; default: the "
        "chosen UAS's mission time estimate.",
        "s",
        0.0,
        True,
        maximum=86400.0,
        label="Flight duration",
        group="requirements",
    ),
    SelectOption(
        "top", "int", 10, "Configurations listed.", minimum=1, maximum=1000, label="Top N", group="scoring"
    ),
    SelectOption(
        "summary",
        "output",
        None,
        "Write the authorisation summary: SUMMARY.html or SUMMARY.json.",
        group="output",
    ),
    SelectOption("db", "source", None, "UAS/camera database: path or http(s) URL.", group="sources"),
    SelectOption("regulations", "source", None, "Regulations database: path or URL.", group="sources"),
    SelectOption("matrices", "source", None, "Compliance matrices: path or URL.", group="sources"),
)

_BY_NAME = {o.name: o for o in SELECT_OPTIONS}
_TARGET_FIELDS = {
    "range": "range_m",
    "weight": "weight_g",
    "cost": "cost_usd",
    "resolution": "resolution_deg",
}


@dataclass(frozen=True)
class Upload:
    """A ``file`` option's document: its name (for messages) and its bytes."""

    name: str
    data: bytes


@dataclass(frozen=True)
class SelectRequest:
    """A parsed selector request: what :func:`uasnav.mission.select` takes."""

    requirements: Requirements
    weights: Weights
    targets: Targets
    top: int
    area: MissionArea | None = None
    zones: tuple[Zone, ...] | None = None
    zones_source: str = "zones"
    when: dt.datetime | None = None
    #: Direction the wind blows from (deg from north), when given as SPEED@FROM_DEG.
    wind_from_deg: float | None = None
    #: Take-off and pilot positions (lat, lon deg) used for the distances, and how they were set.
    takeoff: tuple[float, float] | None = None
    pilot: tuple[float, float] | None = None
    distances: dict[str, Any] | None = None


def request_options() -> tuple[SelectOption, ...]:
    """The options a request may carry (every option but the data sources and outputs)."""
    return tuple(o for o in SELECT_OPTIONS if o.kind not in ("source", "output"))


def _density(opt: SelectOption, value: Any) -> tuple[float | None, str | None]:
    """(density, None) for a number, (None, class) for a class name."""
    if isinstance(value, str) and value.strip() in DENSITY_CLASSES:
        return None, value.strip()
    x = (
        _real(
            SelectOption(opt.name, "real", None, "", minimum=0.0),
            value,
        )
        if not (isinstance(value, str) and not _is_number(value))
        else None
    )
    if x is None:
        raise OptionError(
            opt.name,
            f"{opt.name}: {value!r} is neither a number >= 0 nor one of {', '.join(DENSITY_CLASSES)}",
        )
    return x, None


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def parse_mitigations(value: Any, edition: str) -> tuple[tuple[str, str], ...]:
    """``"M1A=low,M2=medium"`` or a mapping → ((name, robustness), …), checked against the
    edition's mitigation table (SORA 2.5 Table 5: M1A M1B M1C M2; 2.0 Table 3: M1 M2 M3)."""
    if value is None or value == "":
        return ()
    table = MITIGATIONS25 if edition == "2.5" else MITIGATIONS20
    if isinstance(value, Mapping):
        items = [(str(k), v) for k, v in value.items()]
    elif isinstance(value, str):
        items = []
        for item in value.split(","):
            if not item.strip():
                continue
            k, sep, v = item.partition("=")
            if not sep:
                raise OptionError("mitigations", f"mitigations: expected NAME=ROBUSTNESS, got {item!r}")
            items.append((k.strip(), v.strip()))
    else:
        raise OptionError("mitigations", f"mitigations: expected NAME=ROBUSTNESS,… got {value!r}")
    out = []
    for k, v in items:
        if k.upper() not in table:
            raise OptionError(
                "mitigations", f"mitigations: {k!r} is not a SORA {edition} mitigation ({', '.join(table)})"
            )
        if not isinstance(v, str) or v.strip().lower() not in ROBUSTNESS:
            raise OptionError(
                "mitigations", f"mitigations: {k}={v!r}: robustness is one of {', '.join(ROBUSTNESS)}"
            )
        rob = v.strip().lower()
        if table[k.upper()][rob] is None:
            raise OptionError(
                "mitigations", f"mitigations: {k} cannot be claimed at {rob} robustness in SORA {edition}"
            )
        out.append((k.upper(), rob))
    got = dict(out)
    if edition == "2.5" and got.get("M1A") == "medium" and got.get("M1B", "none") != "none":
        raise OptionError(
            "mitigations",
            "mitigations: M1A=medium cannot be combined with M1B (EASA AMC1 Art. 11 Annex B B.2, p. 85)",
        )
    return tuple(out)


def _file_bytes(name: str, value: Any) -> tuple[Any, str]:
    """(content, where) of a ``file`` option's value."""
    if isinstance(value, Upload):
        return value.data, value.name
    if isinstance(value, bytes | str | Mapping):
        return value, name
    raise OptionError(name, f"{name}: expected the document's content, got {type(value).__name__}")


def read_file_option(name: str, source: str) -> Upload:
    """Read a ``file`` option given on the command line: a path (bounded read), or for
    ``zones`` also an http(s) URL (the hardened fetcher)."""
    from uasnav.io.ed269 import MAX_BYTES
    from uasnav.limits import read_file_limited
    from uasnav.mission.loading import fetch, is_url

    if is_url(source):
        if name != "zones":
            raise OptionError(name, f"{name}: give a file path")
        from uasnav.io.ed269 import parse_zones

        return Upload(source, fetch(source, check=parse_zones, accept="application/json").data)
    import os

    if os.path.isdir(source):
        raise InputError(f"{source}: is a directory, not a file")
    return Upload(source, read_file_limited(source, MAX_BYTES, source))


def parse_wind(value: Any) -> tuple[float, float | None]:
    """``5``, ``"5"`` or ``"5@270"`` → (speed m/s, from-direction deg or None); speed in
    [0, 100] m/s, direction finite (taken modulo 360)."""
    if isinstance(value, bool):
        raise OptionError("wind", f"wind: expected SPEED[@FROM_DEG], got {value!r}")
    if isinstance(value, int | float):
        speed_text, direction_text = repr(value), None
    elif isinstance(value, str):
        speed_text, sep, d = value.strip().partition("@")
        direction_text = d if sep else None
    else:
        raise OptionError("wind", f"wind: expected SPEED[@FROM_DEG], got {value!r}")
    try:
        speed = float(speed_text)
        direction = None if direction_text is None else float(direction_text)
    except ValueError:
        raise OptionError(
            "wind", f"wind: expected SPEED[@FROM_DEG] (m/s @ degrees the wind blows from), got {value!r}"
        ) from None
    if not (math.isfinite(speed) and 0.0 <= speed <= 100.0):
        raise OptionError("wind", f"wind: speed must be in [0, 100] m/s, got {value!r}")
    if direction is not None and not math.isfinite(direction):
        raise OptionError("wind", f"wind: direction must be a finite number of degrees, got {value!r}")
    return speed, None if direction is None else direction % 360.0


def parse_position(name: str, value: Any) -> tuple[float, float]:
    """``"LAT,LON"`` (or a pair of numbers) → (lat, lon) deg, within ±90 / ±180."""
    parts: Any = value.split(",") if isinstance(value, str) else value
    try:
        if not isinstance(parts, list | tuple) or len(parts) != 2 or any(isinstance(p, bool) for p in parts):
            raise ValueError
        lat, lon = float(parts[0]), float(parts[1])
    except (TypeError, ValueError):
        raise OptionError(name, f"{name}: expected LAT,LON in degrees, got {value!r}") from None
    if not (math.isfinite(lat) and math.isfinite(lon) and abs(lat) <= 90.0 and abs(lon) <= 180.0):
        raise OptionError(name, f"{name}: LAT,LON must be within ±90°, ±180°, got {value!r}")
    return lat, lon


#: Where the operation's pilot distance comes from when an area is given and no distance typed.
AREA_DISTANCE_WORDS = "the area's farthest point from the pilot position"


def area_distances(
    area: MissionArea, takeoff: tuple[float, float] | None, pilot: tuple[float, float] | None
) -> dict[str, Any]:
    """Take-off point (default the plan's first point, else the area's centroid), pilot position
    (default the take-off point) and the largest distances (m) from each to the area: the
    pilot distance of the operation and the range the UA flies from the take-off point."""
    from uasnav.geo import frames

    lon0, lat0 = area.centre()
    g = area.local(lon0, lat0)
    how_t = "--takeoff"
    if takeoff is None:
        first = next((data[0] for kind, data in area.parts if kind in ("line", "point")), None)
        if area.plan_altitudes and first is not None:
            takeoff, how_t = (float(first[1]), float(first[0])), "the plan's first point"
        else:
            c = g.centroid
            la, lo, _ = frames.enu_to_geodetic(c.x, c.y, 0.0, lat0, lon0, 0.0)
            takeoff, how_t = (float(la), float(lo)), "the area's centroid"
    how_p = "--pilot"
    if pilot is None:
        pilot, how_p = takeoff, "the take-off point"
    hull = g.convex_hull
    coords = np.asarray(hull.exterior.coords if hull.geom_type == "Polygon" else hull.coords, dtype=float)

    def farthest(p: tuple[float, float]) -> float:
        e, n, _ = frames.geodetic_to_enu(p[0], p[1], 0.0, lat0, lon0, 0.0)
        return float(np.hypot(coords[:, 0] - float(e), coords[:, 1] - float(n)).max())

    return {
        "takeoff": list(takeoff),
        "takeoff_from": how_t,
        "pilot": list(pilot),
        "pilot_from": how_p,
        "pilot_distance_m": max(farthest(pilot), 1.0),
        "range_m": max(farthest(takeoff), 1.0),
    }


def _real(opt: SelectOption, value: Any) -> float:
    if isinstance(value, bool):
        raise OptionError(opt.name, f"{opt.name}: expected a number, got {value!r}")
    text = value.strip() if isinstance(value, str) else repr(value)
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise OptionError(opt.name, f"{opt.name}: {text!r} is not a number") from None
    if not math.isfinite(x):
        raise OptionError(opt.name, f"{opt.name}: {text} is not a finite number")
    if opt.minimum is not None and (x <= opt.minimum if opt.minimum_open else x < opt.minimum):
        op = ">" if opt.minimum_open else ">="
        raise OptionError(opt.name, f"{opt.name}: {text} is not {op} {opt.minimum:g}")
    if opt.maximum is not None and x > opt.maximum:
        raise OptionError(opt.name, f"{opt.name}: {text} is not <= {opt.maximum:g}")
    return x


def _int(opt: SelectOption, value: Any) -> int:
    if isinstance(value, bool) or (isinstance(value, float) and not value.is_integer()):
        raise OptionError(opt.name, f"{opt.name}: expected an integer, got {value!r}")
    try:
        n = int(value.strip() if isinstance(value, str) else value)
    except (TypeError, ValueError, OverflowError):
        raise OptionError(opt.name, f"{opt.name}: {value!r} is not an integer") from None
    lo, hi = opt.minimum, opt.maximum
    if (lo is not None and n < lo) or (hi is not None and n > hi):
        raise OptionError(opt.name, f"{opt.name}: {n} is not in the range {lo:g}<=x<={hi:g}")
    return n


def _flag(opt: SelectOption, value: Any) -> bool:
    if isinstance(value, bool):
        return value
    if isinstance(value, str) and value.strip().lower() in ("true", "yes", "on", "1"):
        return True
    if isinstance(value, str) and value.strip().lower() in ("false", "no", "off", "0", ""):
        return False
    raise OptionError(opt.name, f"{opt.name}: expected true or false, got {value!r}")


def _text(opt: SelectOption, value: Any) -> str:
    if not isinstance(value, str) or not value.strip():
        raise OptionError(opt.name, f"{opt.name}: expected a non-empty text, got {value!r}")
    value = value.strip()
    if opt.choices is not None and value not in opt.choices:
        raise OptionError(opt.name, f"{opt.name}: {value!r} is not one of {', '.join(opt.choices)}")
    return value


def parse_image_size(value: Any) -> tuple[float, float]:
    """``"70x70"`` (or ``70×70``, or a pair of numbers) → (length, width) in m, both finite > 0."""
    if isinstance(value, str):
        parts: Any = value.lower().replace("×", "x").split("x")
    elif isinstance(value, list | tuple):
        parts = list(value)
    else:
        parts = None
    try:
        if parts is None or len(parts) != 2 or any(isinstance(p, bool) for p in parts):
            raise ValueError
        size = (float(parts[0]), float(parts[1]))
    except (TypeError, ValueError):
        raise OptionError(
            "image_size", f"image_size: expected LENGTHxWIDTH in metres (e.g. 70x70), got {value!r}"
        ) from None
    if not all(math.isfinite(v) and v > 0 for v in size):
        raise OptionError(
            "image_size", f"image_size: expected a finite LENGTHxWIDTH > 0 in metres, got {value!r}"
        )
    return size


def _pairs(name: str, value: Any) -> dict[str, Any]:
    """``"a=1,b=2"`` or ``{"a": 1}`` → dict with keys among the scored parameters."""
    if isinstance(value, Mapping):
        items = [(str(k), v) for k, v in value.items()]
    elif isinstance(value, str):
        items = []
        for item in value.split(","):
            if not item.strip():
                continue
            key, sep, val = item.partition("=")
            if not sep:
                raise OptionError(
                    name, f"{name}: expected NAME=VALUE with NAME in {', '.join(PARAMETERS)}, got {item!r}"
                )
            items.append((key.strip(), val.strip()))
    else:
        raise OptionError(name, f"{name}: expected NAME=VALUE,… or an object, got {value!r}")
    out = {}
    for key, val in items:
        if key not in PARAMETERS:
            raise OptionError(
                name, f"{name}: expected NAME=VALUE with NAME in {', '.join(PARAMETERS)}, got {key!r}"
            )
        out[key] = val
    return out


def parse_weights(value: Any, order_by: str) -> Weights:
    """Eq. 61's weights: ``order_by``'s defaults overridden by ``value`` (text or mapping).

    Negative, non-finite or all-zero weights are refused: they would rank every configuration
    the same (or backwards) and still print a ranking.
    """
    base = Weights.order_by(order_by).__dict__
    if value is None or value == "":
        return Weights(**base)
    vals = {}
    for k, v in _pairs("weights", value).items():
        try:
            if isinstance(v, bool):
                raise ValueError
            vals[k] = float(v)
        except (TypeError, ValueError):
            raise OptionError("weights", f"weights: not numbers in {value!r}") from None
    ws = {**base, **vals}
    if not all(math.isfinite(x) and x >= 0 for x in ws.values()) or not any(x > 0 for x in ws.values()):
        raise OptionError(
            "weights", f"weights: expected finite weights >= 0, at least one > 0, got {value!r}"
        )
    return Weights(**ws)


def parse_targets(value: Any) -> Targets:
    """Table 23's targets and limits overridden by ``value`` (``range=5000:1500,…`` or a mapping
    of ``[target, limit]`` pairs); target and limit must be finite and differ."""
    t = Targets()
    if value is None or value == "":
        return t
    kw = {}
    for k, v in _pairs("targets", value).items():
        if isinstance(v, str):
            a, sep, b = v.partition(":")
            pair: Any = (a, b) if sep and a.strip() != b.strip() else None
        elif isinstance(v, list | tuple) and len(v) == 2:
            pair = tuple(v)
        else:
            pair = None
        try:
            if pair is None or any(isinstance(p, bool) for p in pair):
                raise ValueError
            x = (float(pair[0]), float(pair[1]))
        except (TypeError, ValueError):
            raise OptionError("targets", f"targets: {k}={v!r} is not TARGET:LIMIT") from None
        if not all(math.isfinite(c) for c in x) or x[0] == x[1]:
            raise OptionError("targets", f"targets: {k}={v!r} is not TARGET:LIMIT")
        kw[_TARGET_FIELDS[k]] = x
    return Targets(**{**t.__dict__, **kw})


def parse_select_options(values: Mapping[str, Any]) -> SelectRequest:
    """Parse a selector request written as options (missing or ``None`` values take defaults).

    Parameters
    ----------
    values : mapping
        Option name (snake_case, see :data:`SELECT_OPTIONS`) → value, typed or as text. Data
        sources (``db``, ``regulations``, ``matrices``) are not part of a request.

    Returns
    -------
    SelectRequest

    Raises
    ------
    OptionError
        Unknown option, or a value outside its option's domain; ``.option`` names it.
    """
    allowed = {o.name for o in request_options()}
    for key in values:
        if key not in allowed:
            hint = " (data sources are set when the server starts)" if key in _BY_NAME else ""
            raise OptionError(str(key), f"{key}: unknown option{hint}; expected {', '.join(sorted(allowed))}")
    v: dict[str, Any] = {}
    for opt in request_options():
        raw = values.get(opt.name)
        if raw is None or (isinstance(raw, str) and not raw.strip() and opt.kind not in ("flag",)):
            v[opt.name] = opt.default
            continue
        if opt.kind == "real":
            v[opt.name] = _real(opt, raw)
        elif opt.kind == "density":
            v[opt.name] = _density(opt, raw)
        elif opt.kind == "int":
            v[opt.name] = _int(opt, raw)
        elif opt.kind == "flag":
            v[opt.name] = _flag(opt, raw)
        elif opt.kind in ("text", "choice"):
            v[opt.name] = _text(opt, raw)
        else:  # size, pairs, mitigations, datetime, file: parsed below with their own messages
            v[opt.name] = raw
    size = parse_image_size(v["image_size"])
    weights = parse_weights(v["weights"], v["order_by"])
    targets = parse_targets(v["targets"])
    category = v["category"]
    if category is None and v["jurisdiction"] not in DEFAULT_CATEGORY:
        raise OptionError("category", f"jurisdiction {v['jurisdiction']!r}: give the category too")
    density, pop_class = v["population_density"] if v["population_density"] is not None else (None, None)
    mitigations = parse_mitigations(v["mitigations"], v["sora_edition"])
    when = None
    if v["flight_time"] is not None:
        from uasnav.mission.zones import parse_when

        try:
            when = parse_when(str(v["flight_time"]))
        except InputError as e:
            raise OptionError("flight_time", str(e)) from None
    wind_ms, wind_from = parse_wind(v["wind"])
    takeoff = parse_position("takeoff", v["takeoff"]) if v["takeoff"] is not None else None
    pilot = parse_position("pilot", v["pilot"]) if v["pilot"] is not None else None
    req = Requirements(
        mission=v["mission"],
        range_m=v["range"],
        resolution_m=v["resolution"],
        image_size_m=size,
        altitude_m=v["altitude"],
        imagery=None if v["imagery"] == "any" else v["imagery"],
        wind_ms=wind_ms,
        rain=v["rain"],
        speed_ms=v["speed"],
        jurisdiction=v["jurisdiction"],
        category=category,
        max_distance_m=v["max_distance"],
        vlos_distance_m=v["vlos_distance"],
        over_people=v["over_people"],
        population_density=density,
        population_class=pop_class,
        night=v["night"],
        airspace=v["airspace"],
        gnss_autopilot=v["gnss_autopilot"],
        mitigations=mitigations,
        sora_edition=v["sora_edition"],
        ground_elevation_m=v["ground_elevation"],
        observers=v["observers"],
        residual_arc=v["residual_arc"],
        flight_duration_s=v["flight_duration"],
        camera_height=v["camera_height"],
    )
    area = zones = None
    zones_where = "zones"
    if v["area"] is not None:
        from uasnav.mission.zones import is_plan_document, parse_area, parse_area_document

        content, where = _file_bytes("area", v["area"])
        buffer = v["area_buffer"]
        try:
            if where.lower().endswith(".kml") and not isinstance(content, Mapping):
                from uasnav.mission.zones import kml_area_geojson

                content = kml_area_geojson(content, where)
            if is_plan_document(where, content):
                # A plan's footprint: the route widened by the buffer, by default the flight
                # height (the 1:1 ground-risk-buffer rule, EASA AMC1 Art. 11 Annex A A.5.2.4).
                # An explicit --area-buffer is the user's (an explicit 0 is refused there).
                default = req.altitude_m
                area = parse_area_document(content, where, buffer_m=default if buffer is None else buffer)
                if buffer is None:
                    # ... by the height the plan itself flies when that is higher.
                    from dataclasses import replace

                    from uasnav.mission.zones import plan_height

                    try:
                        got = plan_height(area, ground_elevation_m=req.ground_elevation_m)
                    except InputError:
                        got = None  # select() refuses the plan with the reason
                    if got is not None and got[0] > area.buffer_m:
                        area = replace(area, buffer_m=got[0])
            elif buffer is None:
                # A polygon is the area itself; a point (take-off) or a line is widened by the
                # largest pilot distance, the farthest the UA goes from it.
                area = parse_area(content, where, buffer_m=0.0)
                if any(kind != "poly" for kind, _ in area.parts):
                    area = parse_area(content, where, buffer_m=req.max_distance_m or req.range_m)
            else:
                area = parse_area(content, where, buffer_m=buffer)
        except UasnavError as e:
            raise OptionError("area", f"area: {e}") from None
    distances = None
    if area is not None and (area.plan_altitudes or all(kind == "poly" for kind, _ in area.parts)):
        # The pilot distance is where the UA goes from the pilot, not the mission range; the
        # range is the farthest the UA flies from the take-off point.
        from dataclasses import replace

        distances = area_distances(area, takeoff, pilot)
        changes: dict[str, Any] = {}
        if v["max_distance"] is None:
            changes["max_distance_m"] = distances["pilot_distance_m"]
            changes["max_distance_source"] = AREA_DISTANCE_WORDS
        if values.get("range") in (None, ""):
            changes["range_m"] = distances["range_m"]
        if changes:
            req = replace(req, **changes)
        takeoff, pilot = tuple(distances["takeoff"]), tuple(distances["pilot"])
    elif takeoff is not None or pilot is not None:
        raise OptionError(
            "pilot" if pilot is not None else "takeoff",
            f"{'pilot' if pilot is not None else 'takeoff'}: a position needs a polygon area or a plan "
            "(--area) to measure the distances from",
        )
    if v["zones"] is not None:
        from uasnav.io.ed269 import parse_zones, zones_from_json

        content, zones_where = _file_bytes("zones", v["zones"])
        try:
            if isinstance(content, Mapping):
                zones = zones_from_json(dict(content))
            else:
                zones = parse_zones(content.encode() if isinstance(content, str) else content, zones_where)
        except UasnavError as e:
            raise OptionError("zones", f"zones: {e}") from None
    return SelectRequest(
        req,
        weights,
        targets,
        v["top"],
        area,
        zones,
        zones_where,
        when,
        wind_from_deg=wind_from,
        takeoff=takeoff,  # type: ignore[arg-type]
        pilot=pilot,  # type: ignore[arg-type]
        distances=distances,
    )


def run_select(
    values: Mapping[str, Any],
    *,
    database: Database | None = None,
    matrices: Matrices | None = None,
    regulations: Regulations | None = None,
) -> Selection:
    """Parse ``values`` (:func:`parse_select_options`) and run the selection on the loaded
    documents (the shipped copies by default). ``select(...).to_dict()`` of the result is what
    ``uasnav select --json`` prints and ``POST /api/select`` answers."""
    from uasnav.mission.selection import select

    r = parse_select_options(values)
    return select(
        r.requirements,
        database=database,
        matrices=matrices,
        regulations=regulations,
        targets=r.targets,
        weights=r.weights,
        top=r.top,
        area=r.area,
        zones=r.zones,
        zones_source=r.zones_source,
        when=r.when,
    )
