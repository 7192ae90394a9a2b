"""Helpers shared by the subcommands: JSON output and option parsing."""

from __future__ import annotations

import json
import math
from typing import Any

import click
import numpy as np


def to_jsonable(obj: Any) -> Any:
    """Convert numpy scalars/arrays (recursively) to plain JSON types; non-finite → None."""
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        return to_jsonable(obj.item())
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


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
