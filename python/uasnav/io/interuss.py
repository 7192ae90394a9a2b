"""InterUSS flight-intent collections (YAML templates of the InterUSS uss_qualifier test suite).

A collection (``intents:``) maps names to either ``full:`` intents or ``delta:`` intents that
apply a ``mutation`` to another intent (``source``). Mutations merge recursively: objects key
by key, lists element by element; a key written ``+name`` replaces ``name`` whole instead of
merging, and ``null`` removes a key. An intent's ``basic_information.area`` is a list of
volumes: ``outline_polygon`` / ``outline_circle``, ``altitude_lower`` / ``altitude_upper``
(``value``, ``reference`` W84, ``units`` M) and times given as offsets (``-1s``, ``45m``,
``32d``) from a moment of the test (``StartOfScenario``, ``TimeOfEvaluation`` …), with
``end_time`` or ``duration``. Every such moment is taken as ``now``, the evaluation time.

:func:`read_flight_intents` resolves every template into an F3548
``OperationalIntentDetails`` (:mod:`uasnav.io.operational_intent`), checked as any intent is;
``astm_f3548_21.priority`` becomes the priority. ``$ref`` entries (flight authorisation data)
are not followed: they carry nothing F3548 uses.

The YAML is composed by a loader that refuses, before any Python object is built, nesting
deeper than :data:`MAX_YAML_DEPTH` and a document whose aliases expand to more than
:data:`MAX_YAML_NODES` nodes ("billion laughs": a few lines of anchors that name each other ten
times over stand for 10⁹ nodes once merged or copied).
"""

from __future__ import annotations

import copy
import os
import re
from datetime import datetime, timedelta
from typing import Any

from uasnav import jsoncheck as jc
from uasnav.errors import DataFormatError, InputError
from uasnav.io.operational_intent import MAX_INTENT_BYTES, NamedIntent, parse_details, rfc3339

#: Deepest nesting of YAML collections accepted (the JSON readers' limit).
MAX_YAML_DEPTH = jc.MAX_DEPTH
#: Most nodes a document may stand for with every alias expanded (a real collection: a few thousand).
MAX_YAML_NODES = 200_000

_OFFSET = re.compile(r"^\s*([+-]?\d+(?:\.\d+)?)\s*(ms|s|m|h|d)\s*$")
_UNIT_S = {"ms": 1e-3, "s": 1.0, "m": 60.0, "h": 3600.0, "d": 86400.0}


def parse_offset(text: object, path: str) -> timedelta:
    """``"-1s"``, ``"45m"``, ``"2h"``, ``"32d"`` → timedelta (error naming ``path``)."""
    m = _OFFSET.match(str(text)) if isinstance(text, str | int | float) else None
    if m is None:
        raise jc.fail(path, f"expected a duration such as -1s, 45m, 2h or 32d, got {jc.show(text)}")
    return timedelta(seconds=float(m.group(1)) * _UNIT_S[m.group(2)])


def merge(base: Any, mutation: Any) -> Any:
    """``mutation`` applied to ``base`` (see module); neither is modified."""
    if isinstance(base, dict) and isinstance(mutation, dict):
        out = copy.deepcopy(base)
        for k, v in mutation.items():
            if isinstance(k, str) and k.startswith("+"):
                out[k[1:]] = copy.deepcopy(v)
            elif v is None:
                out.pop(k, None)
            elif k in out:
                out[k] = merge(out[k], v)
            else:
                out[k] = copy.deepcopy(v)
        return out
    if isinstance(base, list) and isinstance(mutation, list):
        out_l = [merge(b, m) for b, m in zip(base, mutation, strict=False)]
        longer = base if len(base) > len(mutation) else mutation
        return out_l + copy.deepcopy(longer[len(out_l) :])
    return copy.deepcopy(mutation)


def _resolve(name: str, intents: dict[str, Any], seen: tuple[str, ...] = ()) -> dict[str, Any]:
    path = f"intents.{name}"
    if name in seen:
        raise jc.fail(path, f"delta sources form a loop: {' → '.join((*seen, name))}")
    if name not in intents:
        raise jc.fail(f"intents.{seen[-1]}.delta.source" if seen else path, f"no intent named {name!r}")
    entry = jc.obj(intents[name], path)
    if "full" in entry:
        return jc.obj(entry["full"], f"{path}.full")
    delta = jc.obj(jc.field(entry, "delta", path), f"{path}.delta")
    src = jc.string(jc.field(delta, "source", f"{path}.delta"), f"{path}.delta.source")
    base = _resolve(src, intents, (*seen, name))
    return merge(base, delta.get("mutation") or {})


def _time(d: object, path: str, now: datetime) -> datetime:
    obj = jc.obj(d, path)
    off = jc.obj(jc.field(obj, "offset_from", path), f"{path}.offset_from")
    jc.obj(jc.field(off, "starting_from", f"{path}.offset_from"), f"{path}.offset_from.starting_from")
    return now + parse_offset(off.get("offset", "0s"), f"{path}.offset_from.offset")


def _volume(v: object, path: str, now: datetime) -> dict[str, Any]:
    obj = jc.obj(v, path)
    vol: dict[str, Any] = {}
    for key in ("outline_polygon", "outline_circle", "altitude_lower", "altitude_upper"):
        if obj.get(key) is not None:
            vol[key] = obj[key]
    if "start_time" not in obj:
        raise jc.fail(f"{path}.start_time", "missing")
    t0 = _time(obj["start_time"], f"{path}.start_time", now)
    if obj.get("end_time") is not None:
        t1 = _time(obj["end_time"], f"{path}.end_time", now)
    elif obj.get("duration") is not None:
        t1 = t0 + parse_offset(obj["duration"], f"{path}.duration")
    else:
        raise jc.fail(path, "needs end_time or duration")
    return {
        "volume": vol,
        "time_start": {"value": rfc3339(t0), "format": "RFC3339"},
        "time_end": {"value": rfc3339(t1), "format": "RFC3339"},
    }


def resolve_flight_intents(data: object, source: str, now: datetime) -> list[NamedIntent]:
    """Every intent of a parsed collection, resolved at ``now`` (see module)."""
    with jc.reraise_in(source):
        intents = jc.obj(jc.field(jc.obj(data, ""), "intents"), "intents")
        out = []
        for name in intents:
            flight = _resolve(str(name), intents)
            info = jc.obj(
                jc.field(flight, "basic_information", f"intents.{name}"), f"intents.{name}.basic_information"
            )
            apath = f"intents.{name}.basic_information.area"
            area = jc.array(jc.field(info, "area", f"intents.{name}.basic_information"), apath)
            vols = [_volume(v, f"{apath}[{k}]", now) for k, v in enumerate(area)]
            prio = (flight.get("astm_f3548_21") or {}).get("priority", 0)
            details = parse_details(
                {"volumes": vols, "off_nominal_volumes": [], "priority": prio}, f"intents.{name}"
            )
            out.append(NamedIntent(str(name), details, source))
        return out


def _bounded_loader(source: str) -> type:
    """A ``yaml.SafeLoader`` subclass that checks depth while composing and the alias-expanded
    size of the node graph before constructing (see module)."""
    import yaml

    class BoundedLoader(yaml.SafeLoader):
        _depth = 0

        def compose_node(self, parent: Any, index: Any) -> Any:
            self._depth += 1
            try:
                if self._depth > MAX_YAML_DEPTH:
                    mark = self.peek_event().start_mark
                    raise DataFormatError(
                        f"YAML nested deeper than {MAX_YAML_DEPTH} levels", path=source, line=mark.line + 1
                    )
                return super().compose_node(parent, index)
            finally:
                self._depth -= 1

        def construct_document(self, node: Any) -> Any:
            _check_expanded_size(node, source)
            return super().construct_document(node)

    return BoundedLoader


def _check_expanded_size(root: Any, source: str) -> None:
    """Refuse a node graph that stands for more than :data:`MAX_YAML_NODES` nodes (aliases
    counted once per use), computed bottom-up on the shared graph, without expanding it."""
    import yaml

    size: dict[int, int] = {}
    stack: list[tuple[Any, bool]] = [(root, False)]
    while stack:
        node, done = stack.pop()
        if id(node) in size:
            continue
        kids: list[Any] = []
        if isinstance(node, yaml.SequenceNode):
            kids = list(node.value)
        elif isinstance(node, yaml.MappingNode):
            kids = [n for pair in node.value for n in pair]
        if done or not kids:
            total = 1 + sum(size.get(id(k), 0) for k in kids)
            if total > MAX_YAML_NODES:
                raise DataFormatError(
                    f"YAML aliases expand to more than {MAX_YAML_NODES} nodes (alias bomb)",
                    path=source,
                    line=node.start_mark.line + 1,
                )
            size[id(node)] = total
            continue
        stack.append((node, True))
        stack.extend((k, False) for k in kids if id(k) not in size)


def load_yaml(text: str, source: str) -> Any:
    """Parse one YAML document with the bounded safe loader (see module).

    Raises
    ------
    DataFormatError
        Invalid YAML, nesting deeper than :data:`MAX_YAML_DEPTH`, or aliases expanding
        beyond :data:`MAX_YAML_NODES` nodes; the line where it was found is named.
    """
    import yaml

    try:
        return yaml.load(text, Loader=_bounded_loader(source))
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        line = None if mark is None else mark.line + 1
        raise DataFormatError(
            f"not valid YAML ({getattr(e, 'problem', None) or e})", path=source, line=line
        ) from None
    except RecursionError:
        raise DataFormatError(f"YAML nested deeper than {MAX_YAML_DEPTH} levels", path=source) from None


def read_flight_intents(path: str | os.PathLike[str], now: datetime) -> list[NamedIntent]:
    """Read an InterUSS flight-intent collection (YAML), resolved at ``now`` (aware datetime)."""
    p = os.fspath(path)
    if not os.path.exists(p):
        raise InputError(f"no such flight-intent file: {p}")
    text = jc.read_text(p, MAX_INTENT_BYTES)
    data = load_yaml(text, p)
    if jc.depth(data) > jc.MAX_DEPTH:
        raise DataFormatError(f"nested deeper than {jc.MAX_DEPTH} levels", path=p)
    return resolve_flight_intents(data, p, now)


__all__ = [
    "MAX_YAML_DEPTH",
    "MAX_YAML_NODES",
    "load_yaml",
    "merge",
    "parse_offset",
    "read_flight_intents",
    "resolve_flight_intents",
]
