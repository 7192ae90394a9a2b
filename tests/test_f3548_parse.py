"""The fast F3548 reader (``uasnav.io.operational_intent.parse_f3548``) against the library's
own ``ImplicitDict.parse``: same objects (types, values, times) for valid intents, the same
exception and message for invalid ones, and the intent checks report the first problem in
volume order."""

from __future__ import annotations

import copy
import json
from typing import Any

import pytest
from implicitdict import ImplicitDict, StringBasedDateTime
from uas_standards.astm.f3548.v21 import api

from uasnav.errors import DataFormatError
from uasnav.io.interuss import read_flight_intents
from uasnav.io.operational_intent import parse_details, parse_f3548
from uasnav.io.operational_intent import to_json as intent_json

SETS = (
    "interuss_flight_intents_conflicting.yaml",
    "interuss_flight_intents_non_conflicting.yaml",
    "interuss_flight_intents_invalid.yaml",
)


def _same(a: Any, b: Any, path: str = "") -> None:
    """``a`` and ``b`` are the same parsed objects: types, values and times, recursively."""
    assert type(a) is type(b), f"{path}: {type(a).__name__} vs {type(b).__name__}"
    if isinstance(a, StringBasedDateTime):
        assert str(a) == str(b) and a.datetime == b.datetime, path
        assert a.datetime.utcoffset() == b.datetime.utcoffset(), path
    elif isinstance(a, dict):
        assert a.keys() == b.keys(), path
        for k in a:
            _same(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for k, (x, y) in enumerate(zip(a, b, strict=True)):
            _same(x, y, f"{path}[{k}]")
    else:
        assert a == b, path


@pytest.fixture(scope="module")
def intents(shared_data) -> list[dict[str, Any]]:
    from datetime import datetime, timezone

    now = datetime(2026, 11, 24, 12, 0, tzinfo=timezone.utc)
    out = []
    for name in SETS:
        for it in read_flight_intents(shared_data / "utm" / name, now):
            out.append(json.loads(json.dumps(it.details)))
    assert len(out) >= 8
    return out


def _vol(d: dict[str, Any]) -> dict[str, Any]:
    return d["volumes"][0]


# spellings JSON allows that the fast reader hands to the library, and ones it reads itself
VARIANTS = {
    "as written": lambda d: None,
    "time with offset": lambda d: _vol(d)["time_start"].update(value="2026-11-24T14:00:00.5+02:00"),
    "time without zone": lambda d: _vol(d)["time_start"].update(value="2026-11-24T12:00:00"),
    "time in nanoseconds": lambda d: _vol(d)["time_end"].update(value="2099-11-24T12:00:00.123456789Z"),
    "number as a string": lambda d: _vol(d)["volume"]["altitude_lower"].update(value="12.5"),
    "integer altitude": lambda d: _vol(d)["volume"]["altitude_upper"].update(value=900),
    "unknown member": lambda d: _vol(d).update(note={"x": [1, 2]}),
    "explicit null": lambda d: _vol(d)["volume"].update(outline_circle=None),
}


@pytest.mark.parametrize("variant", list(VARIANTS))
def test_fast_reader_builds_the_library_objects(intents, variant):
    for d in intents:
        d = copy.deepcopy(d)
        VARIANTS[variant](d)
        want = ImplicitDict.parse(copy.deepcopy(d), api.OperationalIntentDetails)
        got = parse_f3548(copy.deepcopy(d), api.OperationalIntentDetails)
        _same(got, want)
        assert isinstance(got.volumes[0], api.Volume4D)


BAD = {
    "altitude not a number": lambda d: _vol(d)["volume"]["altitude_lower"].update(value="high"),
    "bad reference": lambda d: _vol(d)["volume"]["altitude_lower"].update(reference="AMSL"),
    "bad time": lambda d: _vol(d)["time_start"].update(value="yesterday"),
    "volumes not a list": lambda d: d.update(volumes=5),
    "volume not an object": lambda d: d["volumes"].__setitem__(0, [1]),
    "vertex missing lat": lambda d: _vol(d)["volume"].update(
        outline_polygon={"vertices": [{"lng": 8.0}, {"lat": 1.0, "lng": 2.0}, {"lat": 2, "lng": 2}]}
    ),
    "priority a string": lambda d: d.update(priority="high"),
}


@pytest.mark.parametrize("bad", list(BAD))
def test_fast_reader_fails_as_the_library_does(intents, bad):
    d = copy.deepcopy(intents[0])
    BAD[bad](d)
    with pytest.raises(Exception) as want:
        ImplicitDict.parse(copy.deepcopy(d), api.OperationalIntentDetails)
    with pytest.raises(Exception) as got:
        parse_f3548(copy.deepcopy(d), api.OperationalIntentDetails)
    assert type(got.value) is type(want.value) and str(got.value) == str(want.value)


def _square(d: dict[str, Any], k: int, bowtie: bool) -> None:
    a, b = 47.0 + 0.001 * k, 8.0
    pts = [(a, b), (a, b + 0.001), (a + 0.001, b + 0.001), (a + 0.001, b)]
    if bowtie:
        pts[1], pts[2] = pts[2], pts[1]
    d["volumes"][k]["volume"].pop("outline_circle", None)
    d["volumes"][k]["volume"]["outline_polygon"] = {"vertices": [{"lat": x, "lng": y} for x, y in pts]}


def test_first_problem_in_volume_order_is_reported(intents):
    """The crossing-edges test runs once per intent, vectorised; its error must still come in
    volume order with the other checks."""
    d0 = copy.deepcopy(intents[0])
    d0["volumes"] = [copy.deepcopy(d0["volumes"][0]) for _ in range(4)]
    for k in range(4):
        _square(d0, k, bowtie=False)
    parse_details(copy.deepcopy(d0))  # valid as built
    d = copy.deepcopy(d0)
    _square(d, 1, bowtie=True)
    d["volumes"][2]["volume"]["altitude_lower"]["value"] = 1e9
    with pytest.raises(DataFormatError, match=r"volumes\[1\]\.volume\.outline_polygon: edges cross"):
        parse_details(d)
    d = copy.deepcopy(d0)
    _square(d, 2, bowtie=True)
    d["volumes"][1]["volume"]["altitude_lower"]["value"] = 1e9
    with pytest.raises(DataFormatError, match=r"volumes\[1\]\.volume\.altitude_lower"):
        parse_details(d)
    d = copy.deepcopy(d0)
    _square(d, 3, bowtie=True)
    with pytest.raises(DataFormatError, match=r"volumes\[3\]\.volume\.outline_polygon: edges cross"):
        parse_details(d)
    # a written intent reads back as the same objects
    _same(parse_details(intent_json(parse_details(copy.deepcopy(d0)))), parse_details(copy.deepcopy(d0)))


def test_valid_intents_do_not_need_the_library_parser(intents, monkeypatch):
    """The speed-up is real: written intents are read without ``ImplicitDict.parse``."""

    def library(*a: Any, **k: Any) -> Any:
        raise AssertionError("library parser called")

    want = [parse_details(copy.deepcopy(d)) for d in intents]
    monkeypatch.setattr(ImplicitDict, "parse", library)
    for d, w in zip(intents, want, strict=True):
        _same(parse_details(copy.deepcopy(d)), w)
    d = copy.deepcopy(intents[0])
    VARIANTS["number as a string"](d)
    with pytest.raises(DataFormatError, match="library parser called"):  # that one needs it
        parse_details(d)
