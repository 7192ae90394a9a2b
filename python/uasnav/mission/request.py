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

from uasnav.errors import InputError
from uasnav.mission.feasibility import Requirements
from uasnav.mission.regulations import DEFAULT_CATEGORY
from uasnav.mission.scoring import PARAMETERS, Targets, Weights

if TYPE_CHECKING:
    from uasnav.mission.database import Database
    from uasnav.mission.matrices import Matrices
    from uasnav.mission.regulations import Regulations
    from uasnav.mission.selection import Selection


class OptionError(InputError):
    """A selector option with a bad value; ``option`` is its snake_case name."""

    def __init__(self, option: str, message: str) -> None:
        super().__init__(message)
        self.option = option


@dataclass(frozen=True)
class SelectOption:
    """One input of the selector.

    ``kind``: ``real`` (a finite number within ``minimum``/``maximum``), ``int``, ``text``,
    ``choice`` (one of ``choices``), ``flag`` (boolean), ``size`` (``LENGTHxWIDTH``), ``pairs``
    (``NAME=VALUE,…`` or a mapping) or ``source`` (a path or URL the *server* opens: command
    line only, never taken from a web request). ``unit`` is shown beside the field and in help.
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

    @property
    def flag(self) -> str:
        """The command-line spelling, ``--image-size``."""
        return "--" + self.name.replace("_", "-")


#: Every input of ``uasnav select``, in the order of the thesis' user-input interface
#: (Figure 75: mission, requirements, weather, scoring) then the data sources.
SELECT_OPTIONS: tuple[SelectOption, ...] = (
    SelectOption("mission", "text", "precision-agriculture", "Mission id (Table 18).", label="Mission"),
    SelectOption("range", "real", 1500.0, "Mission range (m).", "m", 0.0, True, label="Range"),
    SelectOption(
        "resolution", "real", 0.05, "Ground resolution (m/px).", "m/px", 0.0, True, label="Resolution"
    ),
    SelectOption("image_size", "size", "70x70", "Target size LENGTHxWIDTH (m).", "m", label="Image size"),
    SelectOption("altitude", "real", 50.0, "Flight altitude AGL (m).", "m", 0.0, True, label="Altitude"),
    SelectOption("imagery", "text", "multispectral", "Camera type, or 'any'.", label="Imagery type"),
    SelectOption("wind", "real", 5.0, "Wind speed (m/s).", "m/s", 0.0, label="Wind"),
    SelectOption("rain", "flag", False, "The flight must be possible in rain.", label="Rain"),
    SelectOption(
        "speed",
        "real",
        None,
        "Required ground speed against the wind (m/s).",
        "m/s",
        0.0,
        label="Ground speed",
    ),
    SelectOption(
        "order_by",
        "choice",
        "cost",
        "Most important parameter: its weight is 1.25 (eq. 61 with cost first).",
        choices=PARAMETERS,
        label="Order by",
    ),
    SelectOption(
        "weights",
        "pairs",
        None,
        "Explicit weights, e.g. range=1,weight=0.75,cost=1.25,resolution=1.",
        label="Weights",
    ),
    SelectOption(
        "targets",
        "pairs",
        None,
        "TARGET:LIMIT per parameter, e.g. range=5000:1500,weight=800:1600,cost=4000:7000,"
        "resolution=0.01:0.06.",
        label="Targets and limits",
    ),
    SelectOption("jurisdiction", "text", "easa", "Regulations: easa | faa.", label="Regulations"),
    SelectOption(
        "category", "text", None, "Category (default: open for easa, part107 for faa).", label="Category"
    ),
    SelectOption("top", "int", 10, "Configurations listed.", minimum=1, maximum=1000, label="Top N"),
    SelectOption("db", "source", None, "UAS/camera database: path or http(s) URL."),
    SelectOption("regulations", "source", None, "Regulations database: path or URL."),
    SelectOption("matrices", "source", None, "Compliance matrices: path or URL."),
)

_BY_NAME = {o.name: o for o in SELECT_OPTIONS}
_TARGET_FIELDS = {
    "range": "range_m",
    "weight": "weight_g",
    "cost": "cost_usd",
    "resolution": "resolution_deg",
}


@dataclass(frozen=True)
class SelectRequest:
    """A parsed selector request: what :func:`uasnav.mission.select` takes."""

    requirements: Requirements
    weights: Weights
    targets: Targets
    top: int


def request_options() -> tuple[SelectOption, ...]:
    """The options a request may carry (every option but the data sources)."""
    return tuple(o for o in SELECT_OPTIONS if o.kind != "source")


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
        elif opt.kind == "int":
            v[opt.name] = _int(opt, raw)
        elif opt.kind == "flag":
            v[opt.name] = _flag(opt, raw)
        elif opt.kind in ("text", "choice"):
            v[opt.name] = _text(opt, raw)
        else:  # size, pairs: parsed below with their own messages
            v[opt.name] = raw
    size = parse_image_size(v["image_size"])
    weights = parse_weights(v["weights"], v["order_by"])
    targets = parse_targets(v["targets"])
    category = v["category"]
    if category is None:
        category = DEFAULT_CATEGORY.get(v["jurisdiction"])
        if category is None:
            raise OptionError("category", f"jurisdiction {v['jurisdiction']!r}: give the category too")
    req = Requirements(
        mission=v["mission"],
        range_m=v["range"],
        resolution_m=v["resolution"],
        image_size_m=size,
        altitude_m=v["altitude"],
        imagery=None if v["imagery"] == "any" else v["imagery"],
        wind_ms=v["wind"],
        rain=v["rain"],
        speed_ms=v["speed"],
        jurisdiction=v["jurisdiction"],
        category=category,
    )
    return SelectRequest(req, weights, targets, v["top"])


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
    )
