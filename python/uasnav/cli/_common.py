"""Helpers shared by the subcommands: JSON output and option parsing."""

from __future__ import annotations

import contextlib
import json
import math
import os
import warnings
from collections.abc import Iterator
from typing import Any

import click

from uasnav.errors import InputError
from uasnav.jsonable import to_jsonable
from uasnav.units import parse_quantity


@contextlib.contextmanager
def warnings_after_success() -> Iterator[None]:
    """Hold the warnings raised inside the block and show them only once it succeeded: a failed
    command prints its one ``error: …`` line and nothing else (the CLI contract)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        yield
    for w in caught:
        warnings.showwarning(w.message, w.category, w.filename, w.lineno)


#: Largest ``--json`` document (characters) printed indented. Python's indenting JSON encoder is
#: pure Python (only the compact one is in C): a 10⁵-point prediction took longer to indent
#: than to compute. Larger documents are printed compact: the same JSON, one line.
MAX_INDENTED_JSON = 1 << 20


def echo_json(obj: Any) -> None:
    """Print ``obj`` as JSON on stdout: indented, or compact beyond :data:`MAX_INDENTED_JSON`."""
    doc = to_jsonable(obj)
    text = json.dumps(doc, ensure_ascii=False)
    if len(text) <= MAX_INDENTED_JSON:
        text = json.dumps(doc, indent=2, ensure_ascii=False)
    click.echo(text)


def parse_float_list(text: str, what: str) -> list[float]:
    """Parse ``"1,2.5,10"`` into floats, raising a click error naming ``what``."""
    try:
        vals = [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise click.BadParameter(f"{what}: expected comma-separated numbers, got {text!r}") from None
    if not vals:
        raise click.BadParameter(f"{what}: empty list")
    if not all(math.isfinite(v) for v in vals):
        raise click.BadParameter(f"{what}: expected finite numbers, got {text!r}")
    return vals


class Real(click.ParamType):
    """A click option type for a finite float, optionally within bounds.

    ``nan``, ``inf`` and values outside ``[lo, hi]`` (open at an end with ``lo_open`` /
    ``hi_open``) are usage errors (exit code 2) naming the option and the value as typed, e.g.
    ``@click.option("--rate", type=POSITIVE)`` rejects ``--rate 0`` with
    ``Invalid value for '--rate': 0 is not > 0``.
    """

    name = "float"

    def __init__(
        self,
        lo: float | None = None,
        hi: float | None = None,
        *,
        lo_open: bool = False,
        hi_open: bool = False,
    ) -> None:
        self.lo, self.hi, self.lo_open, self.hi_open = lo, hi, lo_open, hi_open

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> float:
        text = value if isinstance(value, str) else repr(value)
        try:
            x = float(value)
        except (TypeError, ValueError):
            self.fail(f"{text!r} is not a number", param, ctx)
        if not math.isfinite(x):
            self.fail(f"{text} is not a finite number", param, ctx)
        if self.lo is not None and (x <= self.lo if self.lo_open else x < self.lo):
            self.fail(f"{text} is not {'>' if self.lo_open else '>='} {self.lo:g}", param, ctx)
        if self.hi is not None and (x >= self.hi if self.hi_open else x > self.hi):
            self.fail(f"{text} is not {'<' if self.hi_open else '<='} {self.hi:g}", param, ctx)
        return x

    def __repr__(self) -> str:
        return f"Real({self.lo!r}, {self.hi!r}, lo_open={self.lo_open}, hi_open={self.hi_open})"


#: Any finite float.
FINITE = Real()
#: A finite float > 0 (rates, durations, lengths, speeds that divide).
POSITIVE = Real(0.0, lo_open=True)
#: A finite float >= 0.
NON_NEGATIVE = Real(0.0)
#: Geodetic latitude (deg).
LATITUDE = Real(-90.0, 90.0)
#: A probability strictly between 0 and 1.
PROBABILITY = Real(0.0, 1.0, lo_open=True, hi_open=True)
#: A small UAS's commanded speed or vertical rate (m/s): 0.1 m/s (slower is a hover, and makes
#: elements of 10¹⁰ s) to 150 m/s (above any small UAS; a model asked for 10⁶ m/s returns
#: negative times).
UAS_SPEED = Real(0.1, 150.0)
#: A separation buffer around a flight's volumes (m): 0 to 100 km. Far wider than any airspace
#: buffer, and small enough that the geometry stays finite (a buffer of 1e308 m turns GEOS's
#: coordinates into inf).
BUFFER_M = Real(0.0, 1e5)
#: A random seed: what every generator of the package (numpy, Rust) accepts.
SEED = click.IntRange(0, 2**32 - 1)


class OutputPath(click.Path):
    """``click.Path(dir_okay=False)`` for a file to write, refusing an empty name (``--out ''``),
    which would otherwise fail later with a confusing message or write a hidden file."""

    def __init__(self, **kwargs: Any) -> None:
        kwargs.setdefault("dir_okay", False)
        super().__init__(**kwargs)

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        if isinstance(value, str) and not value.strip():
            self.fail("an empty file name", param, ctx)
        if isinstance(value, str) and not self.dir_okay and value.endswith(("/", os.sep)):
            # "m.json/" names a directory: writing "m.json" instead would be a silent surprise
            self.fail(f"{value!r} ends with a path separator: it names a directory, not a file", param, ctx)
        return super().convert(value, param, ctx)


def check_outputs(inputs: Any, outputs: dict[str, Any]) -> None:
    """Refuse, before any work, outputs that would overwrite an input or each other.

    ``inputs``: the paths the command reads (``None`` entries skipped); ``outputs``: what the
    command writes, by option name (``{"--out": path, "--plot": path}``; a value may also be a
    list of paths, e.g. one file per sensor). Files are compared by (device, inode), so a hard
    link, a symbolic link or another spelling of an input is caught; devices and pipes
    (``/dev/null``) may take any number of outputs.
    """
    import os

    from uasnav.atomicfile import same_file

    ins = [str(p) for p in inputs if p is not None]
    outs = [
        (opt, str(p))
        for opt, v in outputs.items()
        if v is not None
        for p in (v if isinstance(v, list | tuple) else [v])
    ]
    for opt, out in outs:
        for inp in ins:
            if same_file(out, inp):
                what = "the input" if os.path.abspath(out) == os.path.abspath(inp) else f"the input {inp}"
                raise InputError(f"{opt} {out} is {what}; refusing to overwrite an input file")
    seen: dict[str, tuple[str, str]] = {}
    for opt, out in outs:
        if os.path.exists(out) and not os.path.isfile(out):
            continue  # /dev/null, a pipe: the writer decides (several outputs are fine there)
        key = os.path.realpath(out)
        if key in seen or any(same_file(out, o) for _, o in seen.values()):
            other_opt, other = seen.get(key) or next(v for v in seen.values() if same_file(out, v[1]))
            raise InputError(f"{opt} {out} and {other_opt} {other} are the same file")
        seen[key] = (opt, out)


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
            x = parse_quantity(value, self.unit)
        except InputError as e:
            self.fail(str(e), param, ctx)
        if not math.isfinite(x):  # e.g. 1e400 rad/s overflows to inf
            self.fail(f"{value} is not a finite quantity", param, ctx)
        return x

    def __repr__(self) -> str:
        return f"Quantity({self.unit!r})"
