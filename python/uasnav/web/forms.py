"""The mission-selection form, generated from the selector's one option table.

Every entry of :data:`uasnav.mission.request.SELECT_OPTIONS` that a request may carry becomes
one form field, named as the API key, with its label, unit, default and help; the command line
builds its options from the same table, so the form, ``POST /api/select`` and ``uasnav select``
cannot drift apart. Kinds are handled generically: a kind this module does not know is a text
field (its value goes to :func:`~uasnav.mission.request.parse_select_options` as typed), a file
kind is an upload field (the document goes to the parser as bytes, never as a path), and data
sources and output paths are never fields.
"""

from __future__ import annotations

import base64
import binascii
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from uasnav.mission import request as select_request
from uasnav.mission.request import OptionError, SelectOption, parse_select_options, request_options
from uasnav.mission.scoring import PARAMETERS

#: Kinds naming a file the request uploads (the server stores it in a temporary directory).
FILE_KINDS = frozenset({"file", "input_file", "infile", "upload", "path", "input"})
#: Kinds that are never form fields: server-side sources and output files.
NOT_FIELDS = frozenset({"source", "output", "output_file", "outfile", "output_path", "out"})
#: Largest uploaded option file (bytes).
MAX_OPTION_FILE_BYTES = 4 * 2**20

#: The short form an operator fills in; every other field is under "Advanced".
CORE_FIELDS = (
    "mission",
    "area",
    "resolution",
    "image_size",
    "altitude",
    "imagery",
    "wind",
    "range",
)
#: Fields that may not be left empty when the form sends them (an absent field takes its
#: default; an emptied one is a question the operator has not answered). ``range`` is not
#: needed when an area is uploaded: distances are then measured from the area.
REQUIRED_FIELDS = (
    "mission",
    "range",
    "resolution",
    "image_size",
    "altitude",
    "imagery",
    "wind",
    "jurisdiction",
)

#: Help in the operator's words (the option table's help speaks the command line's).
OPERATOR_HELP: dict[str, str] = {
    "mission": "What the flight is for; it sets the equipment the aircraft must carry.",
    "range": "How far from take-off the aircraft must fly. With an area uploaded, distances are "
    "measured from the area instead.",
    "resolution": "Ground size of one image pixel you need (0.05 m = 5 cm per pixel).",
    "image_size": "Ground one image must cover, length × width, e.g. 70x70.",
    "altitude": "Planned height above the ground (the open category allows up to 120 m).",
    "camera_height": "Height at which the cameras' resolution and field of view are checked: the "
    "height you fly (planned), or the highest the rules allow (regulatory-max, the thesis' test).",
    "imagery": "The kind of camera the task needs, or any.",
    "wind": "Strongest wind expected during the flight.",
    "rain": "The aircraft must be able to fly in rain.",
    "speed": "Ground speed the aircraft must hold against the wind; leave empty if none.",
    "order_by": "What matters most when the configurations are ranked.",
    "weights": "Your own importance for each parameter, instead of the order above.",
    "targets": "For each parameter, the value you aim for and the worst you accept (target:limit).",
    "jurisdiction": "Which rules apply: EASA (Europe) or FAA (United States).",
    "category": "Leave on default and the category the operation needs is worked out for you.",
    "gnss_autopilot": "Only aircraft with a GNSS (GPS) autopilot.",
    "max_distance": "Farthest the pilot will be from the aircraft; empty: worked out from the area "
    "or the range.",
    "vlos_distance": "Distance up to which the pilot can still see the aircraft; empty: from each "
    "aircraft's size.",
    "observers": "Airspace observers posted along the route, who extend the pilot's sight.",
    "over_people": "Whether the flight passes over people not involved in it, or over crowds.",
    "population_density": "People per km² under the flight, or a class: controlled, remote, "
    "sparsely, lightly (default), suburban, high.",
    "night": "The flight is at night.",
    "airspace": "The airspace the flight is in; uncontrolled unless you know otherwise.",
    "mitigations": "Ground-risk mitigations you can show for the risk assessment, e.g. M1A=low,M2=medium.",
    "sora_edition": "Edition of the SORA risk assessment to apply.",
    "residual_arc": "Air-risk class you can claim after strategic mitigations; empty: the initial class.",
    "area": "The field or route to fly: a GeoJSON or KML file, a QGroundControl plan or a Mission "
    "Planner waypoints file.",
    "area_buffer": "Safety margin around the area; empty: none around a field, the flight height "
    "around a route.",
    "zones": "Geographical zones from your aviation authority (ED-269 JSON file), to check restrictions.",
    "ground_elevation": "Height of the ground above sea level, to compare with zone limits given "
    "above sea level.",
    "flight_time": "Planned take-off date and time with its time zone, e.g. 2026-05-01T10:00Z.",
    "flight_duration": "How long the flight lasts; empty: the chosen aircraft's own estimate.",
    "top": "How many configurations to list.",
    "takeoff": "Where the aircraft takes off, latitude,longitude in degrees; empty: the first point "
    "of an uploaded plan, else the middle of the area.",
    "pilot": "Where you stand, latitude,longitude in degrees; empty: at the take-off point. The "
    "distance to the area's farthest point is measured from here.",
}


def operator_help(opt: SelectOption) -> str:
    """``opt``'s help in the operator's words: what the page, ``/api/options`` and the OpenAPI
    description show (the command line keeps the option table's own)."""
    return OPERATOR_HELP.get(opt.name, opt.help)


def is_field(opt: SelectOption) -> bool:
    """Whether ``opt`` is a form field (and an API key)."""
    return opt.kind not in NOT_FIELDS and not opt.kind.startswith("output")


def widget(opt: SelectOption) -> str:
    """The field's widget: number, text, select, checkbox, file or pairs."""
    if opt.kind in FILE_KINDS or opt.kind.endswith("file"):
        return "file"
    return {
        "real": "number",
        "int": "number",
        "flag": "checkbox",
        "choice": "select",
        "pairs": "pairs",
    }.get(opt.kind, "text")


@dataclass(frozen=True)
class FormField:
    """One rendered field: the option plus the choices the loaded documents offer."""

    option: SelectOption
    widget: str
    choices: tuple[tuple[str, str], ...] | None
    default_text: str

    @property
    def name(self) -> str:
        return self.option.name

    @property
    def help(self) -> str:
        """The field's help in the operator's words (the option's own help otherwise)."""
        return operator_help(self.option)

    @property
    def core(self) -> bool:
        """Whether the field is in the short form (else under "Advanced")."""
        return self.name in CORE_FIELDS

    @property
    def required(self) -> bool:
        return self.name in REQUIRED_FIELDS


#: The survey plan's options that are not selector options (``uasnav plan`` adds them): shown
#: under "Advanced", used when an area is uploaded. Name → (label, unit, help, widget).
PLAN_FIELDS: dict[str, tuple[str, str, str, str]] = {
    "overlap": (
        "Photo overlap",
        "%",
        "Front and side overlap of neighbouring photos, e.g. 75,65 (the default).",
        "text",
    ),
    "intents": (
        "Other operators' flights",
        "",
        "Their operational intents (F3548 JSON or flight-intent YAML), to check for conflicts.",
        "file",
    ),
}


def plan_values(form: Mapping[str, Any]) -> dict[str, str]:
    """The plan's own text fields as typed (blank ones left out: they take defaults)."""
    out = {}
    for name, (_, _, _, w) in PLAN_FIELDS.items():
        v = form.get(name)
        if w != "file" and isinstance(v, str) and v.strip():
            out[name] = v.strip()
    return out


def default_text(opt: SelectOption) -> str:
    """The option's default as typed in a form ("" for none)."""
    d = opt.default
    if d is None or isinstance(d, bool):
        return ""
    if isinstance(d, float):
        return f"{d:g}"
    return str(d)


def form_fields(choices: Mapping[str, tuple[tuple[str, str], ...]]) -> list[FormField]:
    """The form's fields in the table's order; ``choices`` maps an option name to the
    (value, label) pairs the loaded documents offer (missions, imagery types, jurisdictions)."""
    out = []
    for opt in request_options():
        if not is_field(opt):
            continue
        w = widget(opt)
        ch = None
        if opt.name in choices:
            ch, w = choices[opt.name], "select"
        elif opt.choices is not None:
            ch = tuple((c, c) for c in opt.choices)
            if opt.default is None:  # an empty choice, or the form would submit the first one
                ch = (("", "— (not set)"), *ch)
        out.append(FormField(opt, w, ch, default_text(opt)))
    return out


def field_names() -> set[str]:
    """The option names the form (and the API) take."""
    return {o.name for o in request_options() if is_field(o)}


def values_from_form(form: Mapping[str, Any], getlist: Any) -> dict[str, Any]:
    """Form data → option values as text (blank fields are left out: they take defaults).

    ``pairs`` options come as one sub-field per scored parameter (``weights.cost``), joined
    into ``cost=1.25,…``; a checkbox is preceded by a hidden ``false`` so the last value wins.
    """
    values: dict[str, Any] = {}
    for opt in request_options():
        if not is_field(opt) or widget(opt) == "file":
            continue
        w = widget(opt)
        if w == "pairs":
            parts = []
            for p in PARAMETERS:
                v = form.get(f"{opt.name}.{p}")
                if isinstance(v, str) and v.strip():
                    parts.append(f"{p}={v.strip()}")
            if parts:
                values[opt.name] = ",".join(parts)
            elif isinstance(form.get(opt.name), str) and form[opt.name].strip():
                values[opt.name] = form[opt.name]
            continue
        got = [v for v in getlist(opt.name) if isinstance(v, str)]
        if not got:
            continue
        v = got[-1]
        if w == "checkbox" or v.strip():
            values[opt.name] = v
    return values


def empty_required(form: Mapping[str, Any], has_area: bool = False) -> dict[str, str]:
    """Required fields the form sent empty, each with a message in the operator's words."""
    errors: dict[str, str] = {}
    for opt in request_options():
        if opt.name not in REQUIRED_FIELDS or opt.name not in form:
            continue
        if opt.name == "range" and has_area:
            continue
        v = form.get(opt.name)
        if isinstance(v, str) and not v.strip():
            what = (opt.label or opt.name).lower()
            unit = f" ({opt.unit})" if opt.unit else ""
            errors[opt.name] = f"{opt.name}: enter the {what}{unit}" + (
                ", or upload an area" if opt.name == "range" else ""
            )
    return errors


#: Form fields carrying a document of the last run, by file field: its name and its content.
KEPT_NAME, KEPT_DATA = "kept-name.{}", "kept-data.{}"


def kept_file(filename: str, data: bytes) -> tuple[str, str]:
    """An uploaded document as the page keeps it for the next run: (file name, base64)."""
    return filename, base64.b64encode(data).decode("ascii")


def read_kept(name: str, form: Mapping[str, Any]) -> tuple[str, bytes] | None:
    """The document of file field ``name`` kept by the page from the last run, if any."""
    text = form.get(KEPT_DATA.format(name))
    if not isinstance(text, str) or not text:
        return None
    try:
        data = base64.b64decode(text, validate=True)
    except (binascii.Error, ValueError):
        raise OptionError(name, f"{name}: the kept file is damaged; choose the file again") from None
    label = form.get(KEPT_NAME.format(name))
    return (label if isinstance(label, str) and label else name), data


def pair_values(text: str | None) -> dict[str, str]:
    """``"range=1,cost=2"`` → {"range": "1", "cost": "2"} for re-filling the sub-fields."""
    out: dict[str, str] = {}
    for item in (text or "").split(","):
        k, sep, v = item.partition("=")
        if sep and k.strip() in PARAMETERS:
            out[k.strip()] = v.strip()
    return out


def field_errors(values: Mapping[str, Any]) -> dict[str, str]:
    """Every field's own error, so the form shows them all at once.

    Some options depend on others (``mitigations`` on ``sora_edition``): a field is checked
    together with every other field that is valid on its own, and nothing is reported when the
    whole request parses."""

    def error_of(v: Mapping[str, Any]) -> OptionError | None:
        try:
            parse_select_options(v)
        except OptionError as e:
            return e
        return None

    whole = error_of(values)
    if whole is None:
        return {}
    valid_alone = {k: v for k, v in values.items() if error_of({k: v}) is None}
    errors: dict[str, str] = {}
    for name, value in values.items():
        err = error_of({**{k: v for k, v in valid_alone.items() if k != name}, name: value})
        if err is not None:
            errors[err.option] = str(err)
    return errors or {whole.option: str(whole)}


def file_value(option: str, filename: str, data: bytes) -> Any:
    """A file option's uploaded document as the parser takes it: an ``Upload(name, data)``
    where :mod:`uasnav.mission.request` defines one, else the bytes. Never written to disk,
    never a path."""
    if len(data) > MAX_OPTION_FILE_BYTES:
        raise OptionError(option, f"{option}: file over {MAX_OPTION_FILE_BYTES} bytes")
    upload = getattr(select_request, "Upload", None)
    # the client's file name is only a label for messages: its last part, printable
    base = filename.replace("\\", "/").rsplit("/", 1)[-1]
    label = "".join(ch for ch in base if ch.isprintable())[:100]
    return upload(label or option, data) if upload is not None else data


__all__ = [
    "CORE_FIELDS",
    "FILE_KINDS",
    "NOT_FIELDS",
    "OPERATOR_HELP",
    "PLAN_FIELDS",
    "REQUIRED_FIELDS",
    "FormField",
    "empty_required",
    "field_errors",
    "field_names",
    "file_value",
    "form_fields",
    "is_field",
    "kept_file",
    "operator_help",
    "pair_values",
    "plan_values",
    "read_kept",
    "values_from_form",
    "widget",
]
