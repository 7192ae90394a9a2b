"""Strict readers for model files stored as JSON: every value checked for type, shape,
finiteness and range, every error naming the value by its JSON path (``models[1].weights[0]``).

Python's :mod:`json` is lenient where a model file must not be: it reads ``NaN``/``Infinity``,
turns ``1e999`` into ``inf``, and ``float("27..34"[0])`` makes a string look like a number.
The checkers here accept a number only if JSON holds a number (never a string, a boolean or
``null``), a vector only if it is a flat, non-empty list of such numbers, and so on; the model
readers (:mod:`uasnav.thermal.modelfile`, :mod:`uasnav.trajectory.predictor`) build every value
they keep through them.

Errors are :class:`uasnav.errors.DataFormatError` without a file path: the reader that knows
the file re-raises them with it (:func:`reraise_in`).

>>> number(2.5, "scale", positive=True)
2.5
>>> number("27..34", "calibrated_range_c[0]")
Traceback (most recent call last):
...
uasnav.errors.DataFormatError: calibrated_range_c[0]: expected a number, got the string "27..34"
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uasnav.errors import DataFormatError
from uasnav.limits import read_file_limited

#: Deepest nesting of arrays/objects a model file may have (ours have at most 6 levels; serde_json,
#: which reads the same thermal files in Rust, stops at 128).
MAX_DEPTH = 64
_TOO_DEEP = f"arrays/objects nested deeper than {MAX_DEPTH} levels"


def at(path: str, key: str | int) -> str:
    """The JSON path of ``key`` inside ``path``: ``at("models", 1)`` → ``"models[1]"``."""
    if isinstance(key, int):
        return f"{path}[{key}]"
    return f"{path}.{key}" if path else key


def show(x: object, limit: int = 40) -> str:
    """``x`` as the file spells it (JSON), shortened to about ``limit`` characters."""
    try:
        s = json.dumps(x, allow_nan=True)
    except (TypeError, ValueError, RecursionError):
        s = type(x).__name__
    return s if len(s) <= limit else s[: limit - 1] + "…"


def _kind(x: object) -> str:
    if x is None:
        return "null"
    if isinstance(x, bool):
        return f"the boolean {show(x)}"
    if isinstance(x, str):
        return f"the string {show(x)}"
    if isinstance(x, list):
        return "an array"
    if isinstance(x, dict):
        return "an object"
    return show(x)


def fail(path: str, problem: str) -> DataFormatError:
    """The error for the value at ``path`` (to ``raise``)."""
    return DataFormatError(f"{path}: {problem}")


def obj(x: object, path: str) -> dict[str, Any]:
    """``x`` if it is a JSON object."""
    if not isinstance(x, dict):
        raise fail(path, f"expected an object, got {_kind(x)}")
    return x


def field(d: dict[str, Any], key: str, path: str = "") -> Any:
    """``d[key]``, or an error naming the missing key."""
    if key not in d:
        raise fail(at(path, key), "missing")
    return d[key]


def only(d: dict[str, Any], allowed: tuple[str, ...], path: str = "") -> dict[str, Any]:
    """``d`` if it has no keys beyond ``allowed`` (a misspelt key is an error, not ignored)."""
    extra = [k for k in d if k not in allowed]
    if extra:
        raise fail(at(path, extra[0]), f"unknown key (known: {', '.join(allowed)})")
    return d


def string(x: object, path: str, choices: tuple[str, ...] | None = None) -> str:
    """``x`` if it is a string (one of ``choices`` if given)."""
    if not isinstance(x, str):
        raise fail(path, f"expected a string, got {_kind(x)}")
    if choices is not None and x not in choices:
        raise fail(path, f"expected one of {', '.join(map(show, choices))}, got {show(x)}")
    return x


def number(
    x: object,
    path: str,
    *,
    positive: bool = False,
    lo: float | None = None,
    hi: float | None = None,
    unit: str = "",
) -> float:
    """``x`` as a finite float, if JSON holds a number there (``positive``: > 0; ``lo``/``hi``:
    inclusive bounds, in ``unit``)."""
    if isinstance(x, bool) or not isinstance(x, int | float):
        raise fail(path, f"expected a number, got {_kind(x)}")
    try:
        v = float(x)
    except OverflowError:  # an integer too large for a float
        raise fail(path, f"number {show(x, 20)} is out of range") from None
    if not math.isfinite(v):
        raise fail(path, f"expected a finite number, got {show(x)}")
    u = f" {unit}" if unit else ""
    if positive and not v > 0:
        raise fail(path, f"expected a number > 0{u}, got {show(x)}")
    if (lo is not None and v < lo) or (hi is not None and v > hi):
        if lo is not None and hi is not None:
            raise fail(path, f"{show(x)}{u} is outside the accepted range [{lo:g}, {hi:g}]{u}")
        if hi is not None:
            raise fail(path, f"{show(x)}{u} is above the accepted maximum {hi:g}{u}")
        raise fail(path, f"{show(x)}{u} is below the accepted minimum {lo:g}{u}")
    return v


def integer(x: object, path: str, *, lo: int | None = None, hi: int | None = None) -> int:
    """``x`` if JSON holds an integer there (``lo``/``hi`` inclusive bounds)."""
    if isinstance(x, bool) or not isinstance(x, int):
        raise fail(path, f"expected an integer, got {_kind(x)}")
    if (lo is not None and x < lo) or (hi is not None and x > hi):
        lo_s = "−∞" if lo is None else str(lo)
        hi_s = "∞" if hi is None else str(hi)
        raise fail(path, f"{show(x, 20)} is outside the accepted range [{lo_s}, {hi_s}]")
    return x


def integer_key(key: str, path: str, *, lo: int | None = None, hi: int | None = None) -> int:
    """An object key that must spell an integer in decimal (``"17"``, ``"-3"``)."""
    s = key[1:] if key.startswith("-") else key
    if not (s.isascii() and s.isdigit()) or len(s) > 18:
        raise fail(at(path, key), "key is not an integer")
    return integer(int(key), at(path, key), lo=lo, hi=hi)


def array(x: object, path: str, *, max_len: int = 1_000_000) -> list[Any]:
    """``x`` if it is a non-empty JSON array of at most ``max_len`` entries."""
    if not isinstance(x, list):
        raise fail(path, f"expected an array, got {_kind(x)}")
    if not x:
        raise fail(path, "empty array")
    if len(x) > max_len:
        raise fail(path, f"{len(x)} entries, at most {max_len} accepted")
    return x


def vector(
    x: object, path: str, *, length: int | None = None, max_len: int = 1_000_000, **bounds: Any
) -> NDArray[np.float64]:
    """``x`` as a float vector: a flat, non-empty array of finite numbers (of ``length`` if
    given; ``bounds`` as for :func:`number`)."""
    a = array(x, path, max_len=max_len)
    if length is not None and len(a) != length:
        raise fail(path, f"expected {length} numbers, got {len(a)}")
    return np.array([number(v, at(path, i), **bounds) for i, v in enumerate(a)], dtype=np.float64)


def matrix(
    x: object, path: str, *, rows: int | None = None, cols: int | None = None, **bounds: Any
) -> NDArray[np.float64]:
    """``x`` as a (rows, cols) float matrix: an array of equally long rows of finite numbers
    (``bounds`` as for :func:`number`)."""
    a = array(x, path)
    if rows is not None and len(a) != rows:
        raise fail(path, f"expected {rows} rows, got {len(a)}")
    out = [vector(r, at(path, i), length=cols, **bounds) for i, r in enumerate(a)]
    n = out[0].size
    for i, r in enumerate(out):
        if r.size != n:
            raise fail(at(path, i), f"row has {r.size} numbers, row 0 has {n}")
    return np.vstack(out)


def interval(x: object, path: str, *, lo: float, hi: float, unit: str) -> tuple[float, float]:
    """A range ``[min, max]``: two finite numbers within [``lo``, ``hi``] (``unit``), min < max."""
    if not (isinstance(x, list) and len(x) == 2):
        raise fail(path, f"expected [min, max] as an array of two numbers, got {show(x)}")
    a, b = (number(v, at(path, i), lo=lo, hi=hi, unit=unit) for i, v in enumerate(x))
    if not a < b:
        raise fail(path, f"minimum {show(x[0])} is not below maximum {show(x[1])}")
    return a, b


def depth(x: object) -> int:
    """Nesting depth of arrays/objects in ``x`` (a scalar is 0), without recursion."""
    deepest, stack = 0, [(x, 0)]
    while stack:
        v, d = stack.pop()
        if isinstance(v, dict | list):
            d += 1
            deepest = max(deepest, d)
            if d > MAX_DEPTH:  # enough to refuse; no need to walk the rest
                return d
            stack.extend((c, d) for c in (v.values() if isinstance(v, dict) else v))
    return deepest


def parse(text: str, invalid: str = "not valid JSON") -> Any:
    """JSON ``text`` parsed; :class:`DataFormatError` (with line and column where known) if it is
    not JSON (message starting ``invalid``), nests deeper than :data:`MAX_DEPTH`, or holds an
    integer too long to convert."""
    try:
        d = json.loads(text)
    except json.JSONDecodeError as e:
        raise DataFormatError(f"{invalid} ({e.msg})", line=e.lineno, column=str(e.colno)) from None
    except RecursionError:
        raise DataFormatError(_TOO_DEEP) from None
    except ValueError as e:  # e.g. an integer literal beyond Python's int-conversion limit
        raise DataFormatError(f"{invalid} ({e})") from None
    if depth(d) > MAX_DEPTH:
        raise DataFormatError(_TOO_DEEP)
    return d


def read_text(path: str | os.PathLike[str], max_bytes: int) -> str:
    """UTF-8 text of the file ``path``, reading at most ``max_bytes`` (+1 to detect more,
    :func:`uasnav.limits.read_file_limited`), so a device or a FIFO (``/dev/zero``) cannot make
    the reader exhaust memory."""
    p = os.fspath(path)
    raw = read_file_limited(p, max_bytes, p)
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        raise DataFormatError("not a UTF-8 text file", path=p) from None


@contextmanager
def reraise_in(source: str) -> Iterator[None]:
    """Re-raise a :class:`DataFormatError` of the checkers with ``source`` (the file) named."""
    try:
        yield
    except DataFormatError as e:
        if e.path is not None:
            raise
        # str(e) already holds the line and column, if any; only the file is added.
        err = DataFormatError(str(e), path=source)
        err.line, err.column = e.line, e.column
        raise err from None


__all__ = [
    "MAX_DEPTH",
    "array",
    "at",
    "depth",
    "fail",
    "field",
    "integer",
    "integer_key",
    "interval",
    "matrix",
    "number",
    "obj",
    "only",
    "parse",
    "read_text",
    "reraise_in",
    "show",
    "string",
    "vector",
]
