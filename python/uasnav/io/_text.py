"""Reading text files for the CSV readers: bounded, decoded with positions, parsed row by row.

Every numeric CSV reader of :mod:`uasnav.io` (log format v1, x-io, the flight and GNSS CSVs,
numeric tables) reads in chunks of whole lines (:mod:`uasnav.io._csvstream`), each parsed by
the extension's numeric chunk parser on every core (:func:`parse_chunk`), and comes here, chunk
by chunk (:func:`decode_part`, :func:`numeric_rows` with ``offset``), to name an error. So each
hostile input gets one :class:`~uasnav.errors.DataFormatError` naming the file, line and (where
it can be told) column:

- more bytes than the memory limit allows (checked on the bytes read, so ``/dev/zero`` or a
  FIFO cannot exhaust memory; :mod:`uasnav.limits`, ``UASNAV_MAX_MEMORY``);
- bytes that are not UTF-8 (a Latin-1 ``é``, a UTF-16 file), NUL bytes (a binary file);
- a stray ``"`` that opens a quoted cell running over several lines, a cell longer than the
  :mod:`csv` module's field limit (128 KiB), any other :class:`csv.Error`.

A UTF-8 byte-order mark at the start of the file is accepted and removed.
"""

from __future__ import annotations

import csv
import math
import os
import re
from collections.abc import Iterator, Sequence

import numpy as np
from numpy.typing import NDArray

from uasnav import _core
from uasnav.errors import DataFormatError, ResourceLimitError
from uasnav.limits import ENV_MEMORY, format_size, max_memory, read_limited

#: Peak bytes of memory per byte of CSV text while a whole-text reader parses it (text, lines,
#: Python floats, the final arrays; measured ≈ 6 on log format v1). The bytes such a reader
#: accepts are ``max_memory() / TEXT_MEMORY_FACTOR``.
TEXT_MEMORY_FACTOR = 8

_BOMS = {
    b"\xff\xfe\x00\x00": "UTF-32",
    b"\x00\x00\xfe\xff": "UTF-32",
    b"\xff\xfe": "UTF-16",
    b"\xfe\xff": "UTF-16",
}
_UTF8_BOM = b"\xef\xbb\xbf"
_NEWLINE = re.compile(r"\r\n|\r|\n")


def max_text_bytes() -> int:
    """Largest text file (bytes) the CSV readers accept under the current memory limit."""
    return max_memory() // TEXT_MEMORY_FACTOR


def read_text(path: str | os.PathLike[str]) -> str:
    """The text of ``path`` as UTF-8 (a leading byte-order mark removed), read bounded.

    Raises
    ------
    DataFormatError
        Missing file, a directory, an unreadable file, invalid UTF-8 or a NUL byte (names the
        line and column), or more bytes than :func:`max_text_bytes` (a
        :class:`~uasnav.errors.ResourceLimitError` too).
    """
    p = str(path)
    limit = max_text_bytes()
    try:
        with open(p, "rb") as fh:
            raw = read_limited(fh, limit, p)
    except FileNotFoundError:
        raise DataFormatError("no such file", path=p) from None
    except IsADirectoryError:
        raise DataFormatError("is a directory, not a file", path=p) from None
    except ResourceLimitError:
        raise ResourceLimitError(
            f"{p}: larger than {format_size(limit)}, the largest text file read under the memory limit "
            f"of {format_size(max_memory())} (parsing needs about {TEXT_MEMORY_FACTOR} bytes of memory "
            f"per byte of text); raise the limit with {ENV_MEMORY} (e.g. {ENV_MEMORY}=16G)"
        ) from None
    except OSError as e:
        raise DataFormatError(f"cannot read ({e.strerror or e})", path=p) from None
    return decode(raw, p)


def decode(raw: bytes, source: str) -> str:
    """``raw`` decoded as UTF-8 without a leading BOM; errors name line and column (see module)."""
    for bom, name in _BOMS.items():
        if raw.startswith(bom):
            raise DataFormatError(f"a {name} text file; save it as UTF-8", path=source, line=1)
    if raw.startswith(_UTF8_BOM):
        raw = raw[len(_UTF8_BOM) :]
    return decode_part(raw, source)


def decode_part(raw: bytes, source: str, first_line: int = 1, header: Sequence[str] | None = None) -> str:
    """``raw`` (a whole file without its BOM, or the whole lines of a file from line
    ``first_line`` on, below the ``header`` row) decoded as UTF-8; invalid UTF-8 and NUL bytes
    are a :class:`DataFormatError` naming the file line and the column (see module)."""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        line, column, at = _where(raw, e.start, header)
        bad = raw[e.start : e.start + 1].hex()
        raise DataFormatError(
            f"not UTF-8 text: byte 0x{bad}{at} ({e.reason}); save the file as UTF-8",
            path=source,
            line=first_line - 1 + line,
            column=column,
        ) from None
    nul = text.find("\x00")
    if nul >= 0:
        line, column, at = _where(raw, len(text[:nul].encode("utf-8")), header)
        raise DataFormatError(
            f"NUL byte{at}: a binary file, not CSV text",
            path=source,
            line=first_line - 1 + line,
            column=column,
        )
    return text


def _where(raw: bytes, offset: int, header: Sequence[str] | None = None) -> tuple[int, str | None, str]:
    """Where byte ``offset`` is: (line, CSV column name, " at character k" or "").

    The column is the header name when the offset lies in a data row after a header (``header``
    if given, else the first row of ``raw``); otherwise it is ``None`` and the position within
    the line is given instead.
    """
    # lines end at \n, \r\n or \r, as split_lines counts them
    line_start = max(raw.rfind(b"\n", 0, offset), raw.rfind(b"\r", 0, offset)) + 1
    line = raw.count(b"\n", 0, offset) + raw.count(b"\r", 0, offset) - raw.count(b"\r\n", 0, offset) + 1
    before = raw[line_start:offset].decode("utf-8", errors="replace")
    cell = before.count(",")
    if header is None:
        header = _header_before(raw[:line_start].decode("utf-8", errors="replace"))
    if header is not None and cell < len(header):
        return line, header[cell], ""
    return line, None, f" at character {len(before) + 1}"


def _header_before(text: str) -> list[str] | None:
    """The header cells of CSV ``text`` (first line that is neither blank nor a ``#`` comment)."""
    for ln in text.splitlines():
        if ln.strip() and not ln.startswith("#"):
            return [h.strip() for h in ln.split(",")]
    return None


def split_lines(text: str) -> list[str]:
    """The lines of ``text``, split at ``\\n``, ``\\r\\n`` or ``\\r`` only (unlike
    :meth:`str.splitlines`, which also splits at form feeds and Unicode separators and would
    make line numbers disagree with an editor's)."""
    lines = _NEWLINE.split(text)
    if lines and lines[-1] == "":
        lines.pop()
    return lines


def csv_rows(
    lines: Sequence[str], start: int, source: str, header: Sequence[str] | None = None, *, offset: int = 0
) -> Iterator[tuple[int, list[str]]]:
    """Parse ``lines[start:]`` as CSV: ``(line, cells)`` per row, ``line`` 1-based in the file
    (``lines[0]`` being file line ``offset + 1``).

    ``header`` (the column names, if known) names the column in errors. Blank lines are
    skipped. A row spanning several lines (a ``"`` that opens a quoted cell) and every
    :class:`csv.Error` are a :class:`DataFormatError` naming the line and column.
    """
    # each line with its newline, so a quoted cell running over lines shows where it started
    reader = csv.reader(ln + "\n" for ln in lines[start:])
    while True:
        first = start + reader.line_num + 1  # file line (1-based) of the next row's first line
        try:
            row = next(reader)
        except StopIteration:
            return
        except csv.Error as e:
            line = start + reader.line_num  # the line being read when the error occurred
            text = lines[line - 1] if 0 < line <= len(lines) else ""
            raise _csv_error(e, text, source, offset + line, header) from None
        last = start + reader.line_num
        if last > first:
            quoted = next((j for j, c in enumerate(row) if "\n" in c), len(row) - 1)
            raise DataFormatError(
                f"unbalanced '\"': a quoted cell starts here and runs over {last - first + 1} lines",
                path=source,
                line=offset + first,
                column=_name(header, quoted),
            )
        if not row or all(not c.strip() for c in row):
            continue
        yield offset + first, row


def show_cell(cell: str, limit: int = 40) -> str:
    """A cell for an error message: quoted, shortened if long."""
    return repr(cell) if len(cell) <= limit else f"{cell[:limit]!r}… ({len(cell)} characters)"


def finite_cell(cell: str, *, path: str, line: int, column: str, nan_ok: bool = False) -> float:
    """One CSV cell as a finite float, else :class:`DataFormatError` naming file, line, column
    and the cell as written (the one cell rule of every CSV reader). ``nan_ok``: NaN is a
    missing value of a numeric table, only ±inf is refused."""
    try:
        v = float(cell)
    except ValueError:
        raise DataFormatError(
            f"not a number: {show_cell(cell)}", path=path, line=line, column=column
        ) from None
    if nan_ok:
        if math.isinf(v):
            raise DataFormatError(f"infinite value {show_cell(cell)}", path=path, line=line, column=column)
    elif not math.isfinite(v):
        raise DataFormatError(f"non-finite value {show_cell(cell)}", path=path, line=line, column=column)
    return v


def numeric_rows(
    lines: list[str],
    header_line: int,
    source: str,
    header: Sequence[str],
    columns: Sequence[str],
    *,
    exact_width: bool = False,
    offset: int = 0,
    min_rows: int = 2,
    nan_ok: bool = False,
) -> tuple[NDArray[np.float64], list[int]]:
    """The data rows of a CSV table as an (n, len(columns)) float array of ``columns`` (names in
    ``header``), with the file line of each row; every cell must be a finite number.

    ``exact_width`` refuses a row whose cell count differs from the header's (log format v1);
    otherwise only a row too short for a wanted column is refused. Fewer than ``min_rows`` rows
    is an error (a log or a track needs at least two samples). ``lines[0]`` is file line
    ``offset + 1`` (a chunk of a file). ``nan_ok`` accepts NaN (a missing value of a numeric
    table, :func:`finite_cell`) and refuses only ±inf."""
    idx = [header.index(c) for c in columns]
    fast = _numeric_rows_fast(lines, header_line, len(header), idx, exact_width, nan_ok)
    if fast is not None:
        return fast[0], [offset + ln for ln in fast[1]]
    rows: list[list[float]] = []
    row_lines: list[int] = []
    for line, row in csv_rows(lines, header_line, source, header, offset=offset):
        if exact_width and len(row) != len(header):
            raise DataFormatError(f"expected {len(header)} cells, got {len(row)}", path=source, line=line)
        vals = []
        for c, j in zip(columns, idx, strict=True):
            if j >= len(row):
                raise DataFormatError(f"missing cell (row has {len(row)})", path=source, line=line, column=c)
            vals.append(finite_cell(row[j].strip(), path=source, line=line, column=c, nan_ok=nan_ok))
        rows.append(vals)
        row_lines.append(line)
    if len(rows) < min_rows:
        raise DataFormatError(f"need at least {min_rows} data rows, got {len(rows)}", path=source)
    return np.array(rows, dtype=np.float64).reshape(len(rows), len(columns)), row_lines


def parse_chunk(
    raw: bytes,
    width: int,
    idx: Sequence[int],
    *,
    exact_width: bool,
    nan_ok: bool = False,
    end: int | None = None,
) -> NDArray[np.float64] | None:
    """The numeric engine of every CSV reader: ``raw[:end]`` (bytes of whole data lines, empty
    lines skipped; read in place) parsed by the extension (the ``csv-chunk`` crate: one part per core, the GIL
    released) into an (m, len(idx)) Fortran-order float array of the columns at ``idx``, or
    ``None`` when some line needs the row-by-row reader's judgement: a ``"`` (quoting), a NUL,
    control or non-ASCII byte, a line longer than 64 KiB, a line of spaces, a row of the wrong
    width (any width other than ``width`` if ``exact_width``, else one too short for a wanted
    column), a wanted cell that is not plain decimal syntax (``[+-]``, digits, ``.``, an
    exponent; spaces and tabs around it) or is ±inf (NaN too unless ``nan_ok``). The row-by-row
    reader then names the first offending cell, or accepts what ``float`` accepts beyond plain
    syntax (``1_0``, non-ASCII digits). Both parse correctly rounded, so both paths return the
    same values bit for bit for every input."""
    return _core.csv_parse_chunk(raw, width, list(idx), exact_width, nan_ok, 0, end)


def _numeric_rows_fast(
    lines: list[str], start: int, width: int, idx: Sequence[int], exact_width: bool, nan_ok: bool = False
) -> tuple[NDArray[np.float64], list[int]] | None:
    """:func:`numeric_rows` in one pass of :func:`parse_chunk`, or ``None``."""
    body = lines[start:]
    keep = [k for k, ln in enumerate(body) if ln.strip()]
    if len(keep) < 2:
        return None
    try:
        raw = "\n".join([body[k] for k in keep]).encode("ascii")
    except UnicodeEncodeError:
        return None  # the row-by-row reader judges non-ASCII text
    data = parse_chunk(raw, width, idx, exact_width=exact_width, nan_ok=nan_ok)
    if data is None or data.shape[0] != len(keep):
        return None
    return data, [start + k + 1 for k in keep]


def _name(header: Sequence[str] | None, j: int) -> str:
    if header is not None and 0 <= j < len(header):
        return header[j]
    return f"#{j + 1}"


def _csv_error(
    e: csv.Error, text: str, source: str, line: int, header: Sequence[str] | None
) -> DataFormatError:
    msg = str(e)
    if "field larger than field limit" in msg:
        limit = csv.field_size_limit()
        cells = text.split(",")
        j = next((k for k, c in enumerate(cells) if len(c) > limit), len(cells) - 1)
        return DataFormatError(
            f"a cell of more than {limit} characters (not a number; a stray '\"' or binary data?)",
            path=source,
            line=line,
            column=_name(header, j),
        )
    return DataFormatError(f"malformed CSV ({msg})", path=source, line=line)


__all__ = [
    "TEXT_MEMORY_FACTOR",
    "csv_rows",
    "decode",
    "decode_part",
    "finite_cell",
    "max_text_bytes",
    "numeric_rows",
    "parse_chunk",
    "read_text",
    "show_cell",
    "split_lines",
]
