"""Numeric CSV tables that are not IMU logs (filter estimates, per-sample diagnostics …).

Layout written by :func:`write_csv_table` and read by :func:`read_csv_table`::

    # key: value          optional comment lines (e.g. units, provenance)
    name_1,name_2,…       header row: the column names
    0.10000000000000001,3 one row per sample, 17 significant digits

Numbers are written with 17 significant digits (like log format v1), so write → read
round-trips every float64 bit for bit. NaN is allowed and written ``nan`` (a missing value:
it reads back as NaN); ±inf is refused. The file is written atomically (temporary file +
rename): on an error nothing is left behind and an existing file is untouched.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from typing import IO, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav.atomicfile import atomic_open
from uasnav.errors import DataFormatError, InputError
from uasnav.io._csvstream import read_table

_KEY = re.compile(r"[\w.-]+")
_COMMENT = re.compile(r"#\s*([\w.-]+)\s*:\s*(.*)$")
#: ``%.17g`` round-trips every float64 exactly.
FLOAT_FORMAT = "%.17g"


def write_rows(fh: IO[Any], block: NDArray[np.float64]) -> None:
    """Write the rows of ``block`` (n, k) as CSV lines, 17 significant digits (``nan`` for NaN)."""
    if block.shape[0]:
        np.savetxt(fh, block, fmt=FLOAT_FORMAT, delimiter=",")


def as_column(name: str, values: ArrayLike) -> NDArray[np.float64]:
    """``values`` as a float64 column named ``name``, checked for writing (see the module docs).

    Raises
    ------
    InputError
        A name that is empty or not plain CSV, values that are not 1-D numeric, or ±inf.
    """
    if not isinstance(name, str) or not name or name != name.strip() or any(c in name for c in ',"\r\n#'):
        raise InputError(
            f"column name {name!r}: must be non-empty, without spaces at its ends, ',', '\"', '#' "
            "or a newline"
        )
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise InputError(f"column {name!r}: not numeric ({e})") from None
    if arr.ndim != 1:
        raise InputError(f"column {name!r}: expected a 1-D array, got shape {arr.shape}")
    inf = np.flatnonzero(np.isinf(arr))
    if inf.size:
        raise InputError(f"column {name!r}: infinite value at row {int(inf[0])} (NaN is allowed, inf is not)")
    return arr


def write_csv_table(
    path: str | os.PathLike[str],
    columns: Mapping[str, ArrayLike],
    *,
    comments: Mapping[str, str] | None = None,
) -> None:
    """Write numeric ``columns`` (name → 1-D array, all of one length) as a CSV table, atomically.

    Parameters
    ----------
    path : path-like
        Output file; its directory is created if missing.
    columns : mapping of str → array_like, each shape (n,)
        Column name → values, in column order. Booleans and integers are written as numbers.
    comments : mapping of str → str, optional
        Written first as ``# key: value`` lines. Keys are words (letters, digits, ``_ . -``);
        values are one line.

    Raises
    ------
    InputError
        No column, a bad column name or comment, a column that is not 1-D numeric, columns of
        different lengths, or an infinite value (names the column and row). NaN is written as
        ``nan``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "est.csv"
    >>> write_csv_table(p, {"t": [0.0, 0.1], "bias": [1e-3, float("nan")]}, comments={"unit": "rad/s"})
    >>> print(p.read_text(), end="")
    # unit: rad/s
    t,bias
    0,0.001
    0.10000000000000001,nan
    >>> cols, notes = read_csv_table(p)
    >>> cols["t"].tolist() == [0.0, 0.1], notes
    (True, {'unit': 'rad/s'})
    """
    if not columns:
        raise InputError("columns: need at least one column")
    arrays = [as_column(name, v) for name, v in columns.items()]
    lengths = {name: a.size for name, a in zip(columns, arrays, strict=True)}
    if len(set(lengths.values())) > 1:
        raise InputError(f"columns: different lengths {lengths}")
    lines = []
    for key, value in (comments or {}).items():
        if not isinstance(key, str) or not _KEY.fullmatch(key):
            raise InputError(f"comment key {key!r}: use letters, digits, '_', '.', '-'")
        text = str(value)
        if "\n" in text or "\r" in text:
            raise InputError(f"comment {key!r}: the value must be one line")
        lines.append(f"# {key}: {text}\n")
    block = np.column_stack(arrays)
    with atomic_open(path, "w") as fh:
        fh.writelines(lines)
        fh.write(",".join(columns) + "\n")
        write_rows(fh, block)


def check_header(header: list[str], header_line: int, source: str) -> None:
    """Refuse a header row that names a column twice (the line named)."""
    if len(set(header)) != len(header):
        raise DataFormatError(f"duplicated column name in {header}", path=source, line=header_line)


def read_csv_table(path: str | os.PathLike[str]) -> tuple[dict[str, NDArray[np.float64]], dict[str, str]]:
    """Read a table written by :func:`write_csv_table`: (columns, comments).

    The file is read in chunks by the CSV engine (:mod:`uasnav.io._csvstream`): memory is about
    24 bytes per number plus a bounded working set.

    Raises
    ------
    DataFormatError
        Missing file, no header, duplicated column name, a row of the wrong width, a cell that
        is not a number or is infinite, malformed CSV or text that is not UTF-8 (names the line
        and column).
    ResourceLimitError
        If the table would need more memory than the limit (``UASNAV_MAX_MEMORY``).
    """
    source = str(path)

    def select(header: list[str], header_line: int) -> list[str]:
        check_header(header, header_line, source)
        return header

    table = read_table(path, select, what="CSV table", exact_width=True, nan_ok=True)
    comments: dict[str, str] = {}
    for line in table.comments:
        m = _COMMENT.match(line)
        if m:
            comments[m.group(1)] = m.group(2).strip()
    return table.columns, comments


__all__ = ["FLOAT_FORMAT", "as_column", "check_header", "read_csv_table", "write_csv_table", "write_rows"]
