"""The selector's one option table: CLI, web form and JSON API read the same names, units,
defaults and refusals (``uasnav.mission.request``)."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.cli.select import command as select_command
from uasnav.jsonable import to_jsonable
from uasnav.mission import Requirements, Weights, select
from uasnav.mission.request import (
    OPTION_GROUPS,
    SELECT_OPTIONS,
    OptionError,
    parse_select_options,
    request_options,
    run_select,
)


def test_cli_options_are_the_table() -> None:
    cli = {o for p in select_command.params for o in p.opts} - {"--json", "--help"}
    assert cli == {o.flag for o in SELECT_OPTIONS}


def test_every_option_has_a_group() -> None:
    """Each option sits in one group of the input interface; request options never in the
    command-line-only groups, sources and outputs only there; every group is used."""
    assert all(o.group in OPTION_GROUPS for o in SELECT_OPTIONS), [
        o.name for o in SELECT_OPTIONS if o.group not in OPTION_GROUPS
    ]
    cli_only = {"output", "sources"}
    assert all(o.group not in cli_only for o in request_options())
    assert all(o.group in cli_only for o in SELECT_OPTIONS if o.kind in ("output", "source"))
    assert {o.group for o in SELECT_OPTIONS} == set(OPTION_GROUPS)
    by = {o.name: o.group for o in SELECT_OPTIONS}
    assert (by["mission"], by["resolution"], by["wind"], by["weights"]) == (
        "mission",
        "payload",
        "weather",
        "scoring",
    )


def test_defaults_are_the_thesis_case() -> None:
    r = parse_select_options({})
    assert r.requirements == Requirements()
    assert r.weights == Weights.order_by("cost") == Weights()
    assert r.top == 10


def test_text_and_typed_values_agree() -> None:
    text = parse_select_options(
        {
            "range": "300",
            "image_size": "60x40",
            "rain": "on",
            "weights": "range=2,cost=1",
            "top": "3",
            "targets": "cost=3000:6000",
        }
    )
    typed = parse_select_options(
        {
            "range": 300,
            "image_size": [60, 40],
            "rain": True,
            "weights": {"range": 2, "cost": 1},
            "top": 3,
            "targets": {"cost": [3000, 6000]},
        }
    )
    assert text == typed
    assert typed.requirements.range_m == 300.0 and typed.requirements.image_size_m == (60.0, 40.0)
    assert typed.weights.range == 2.0 and typed.weights.weight == 0.75
    assert typed.targets.cost_usd == (3000.0, 6000.0)


@pytest.mark.parametrize(
    ("values", "option"),
    [
        ({"range": -1}, "range"),
        ({"range": "nan"}, "range"),
        ({"range": True}, "range"),
        ({"wind": "fast"}, "wind"),
        ({"image_size": "0x70"}, "image_size"),
        ({"image_size": [1, 2, 3]}, "image_size"),
        ({"weights": "range=-1"}, "weights"),
        ({"weights": {"range": 0, "weight": 0, "cost": 0, "resolution": 0}}, "weights"),
        ({"weights": {"speed": 1}}, "weights"),
        ({"targets": "cost=5:5"}, "targets"),
        ({"top": 0}, "top"),
        ({"top": 2.5}, "top"),
        ({"order_by": "speed"}, "order_by"),
        ({"rain": "maybe"}, "rain"),
        ({"db": "/etc/passwd"}, "db"),
        ({"colour": "red"}, "colour"),
        ({"jurisdiction": "mars"}, "category"),
    ],
)
def test_refusals_name_the_option(values, option) -> None:
    with pytest.raises(OptionError) as e:
        parse_select_options(values)
    assert e.value.option == option
    assert isinstance(e.value, ValueError)


def test_sources_are_not_request_options() -> None:
    # data sources (opened by the server) and outputs (written by the command line) are never
    # taken from a request
    assert {o.name for o in SELECT_OPTIONS} - {o.name for o in request_options()} == {
        "db",
        "regulations",
        "matrices",
        "summary",
    }


def test_run_select_is_what_the_cli_prints() -> None:
    argv = ["select", "--range", "300", "--order-by", "weight", "--top", "4", "--json"]
    res = CliRunner().invoke(main, argv)
    assert res.exit_code == 0, res.output
    api = run_select({"range": 300, "order_by": "weight", "top": 4}).to_dict()
    # the CLI prints through to_jsonable (non-finite → null); an API answers the same way
    assert json.loads(res.output) == json.loads(json.dumps(to_jsonable(api)))
    assert run_select({}).to_dict()["ranking"] == select(Requirements()).to_dict()["ranking"]
