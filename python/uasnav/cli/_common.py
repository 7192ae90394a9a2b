"""Helpers shared by the subcommands: JSON output and option parsing."""

from __future__ import annotations

import json
from typing import Any

import click

from uasnav.errors import InputError
from uasnav.jsonable import to_jsonable
from uasnav.units import parse_quantity


def echo_json(obj: Any) -> None:
    """Print ``obj`` as indented JSON on stdout."""
    click.echo(json.dumps(to_jsonable(obj), indent=2, ensure_ascii=False))


def parse_float_list(text: str, what: str) -> list[float]:
    """Parse ``"1,2.5,10"`` into floats, raising a click error naming ``what``."""
    try:
        vals = [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise click.BadParameter(f"{what}: expected comma-separated numbers, got {text!r}") from None
    if not vals:
        raise click.BadParameter(f"{what}: empty list")
    return vals


class Quantity(click.ParamType):
    """A click option type for a quantity with its unit (``"15deg/h"``, ``"7e-5 rad/s"``),
    converted to a float in ``unit`` by :func:`uasnav.units.parse_quantity`.

    A malformed value or a unit of another dimension is a usage error (exit code 2) naming
    the option and the text, e.g.
    ``@click.option("--residual-bias", type=Quantity("rad/s"), default="0 rad/s")``.
    """

    name = "quantity"

    def __init__(self, unit: str) -> None:
        self.unit = unit

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> float:
        if isinstance(value, float):  # already converted (a default given as a number)
            return value
        try:
            return parse_quantity(value, self.unit)
        except InputError as e:
            self.fail(str(e), param, ctx)

    def __repr__(self) -> str:
        return f"Quantity({self.unit!r})"
