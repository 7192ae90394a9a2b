"""The CSV engine of every numeric CSV reader: chunks of whole lines through the extension's
numeric parser, on every core, with the row-by-row reader's errors.

:class:`NumericCsv` reads a CSV file (``#`` comment lines, a header row, numeric data rows) in
chunks of whole lines (:func:`chunk_bytes`, at most 16 MiB), each parsed by
:func:`~uasnav.io._text.parse_chunk` (the ``csv-chunk`` crate: the chunk cut at line breaks into
one part per core, parsed with the GIL released) into float64 columns, so memory stays bounded
by the chunk size whatever the file's length, and a consumer can stream (block means while
reading, :class:`~uasnav.io.formats.csv_v1.CsvV1Stream`) or concatenate (:func:`read_table`:
numeric tables, the GNSS, x-io and flight CSVs).

The parser accepts a subset of what the row-by-row reader of :mod:`uasnav.io._text` accepts,
never more: printable ASCII only (a ``"`` anywhere, a NUL, control or non-ASCII byte sends the
chunk row by row), lines of at most 64 KiB (below the :mod:`csv` module's field limit of 128
KiB), no lines of spaces, cells in plain decimal syntax, ±inf (and NaN where it is refused)
handed over. Any chunk it refuses is parsed by the row-by-row reader, which either names the
first bad cell (file, line, column: the same :class:`~uasnav.errors.DataFormatError` as reading
the whole text) or accepts what ``float`` accepts beyond plain syntax (``1_0``, non-ASCII
digits). Both parse correctly rounded and return the same values bit for bit
(``tests/test_io_csv_stream.py``).

The errors come in the order the whole-text reader finds them: an encoding error anywhere in
the file (not UTF-8, a NUL byte) wins over any other error, so after the first other error the
rest of the file is scanned for one (:meth:`NumericCsv.fail`).
"""

from __future__ import annotations

import os
import re
import stat
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import BinaryIO, NoReturn

import numpy as np
from numpy.typing import NDArray

from uasnav import _core
from uasnav.errors import DataFormatError
from uasnav.io._text import csv_rows, decode, decode_part, numeric_rows, parse_chunk, read_text, split_lines
from uasnav.limits import check_memory, max_memory

#: Largest chunk (bytes of text) parsed at once.
MAX_CHUNK_BYTES = 16 * 1024**2
#: Peak bytes of memory per byte of a chunk while it is parsed (the bytes and the columns, once
#: per part and once joined: ≈ 2; or the row-by-row reader's Python objects when it takes over:
#: ≈ 6, see ``_text``).
CHUNK_MEMORY_FACTOR = 8
#: Text after a chunk given to the row-by-row reader with it when a ``"`` may open a quoted
#: cell running on: the :mod:`csv` module stops such a cell at its field limit (128 KiB).
_LOOKAHEAD = 1024**2
_LINE_BREAKS = re.compile(rb"\r\n|\r|\n")


def chunk_bytes() -> int:
    """Bytes of text per chunk: 1/64 of the memory limit, within [256 KiB, 16 MiB]."""
    return int(min(MAX_CHUNK_BYTES, max(256 * 1024, max_memory() // 64)))


def _line_count(raw: bytes, end: int | None = None) -> int:
    """Line breaks in ``raw[:end]`` (``\\n``, ``\\r\\n`` or ``\\r``, like :func:`split_lines`)."""
    return _core.csv_line_breaks(raw, end)


def _cut(buf: bytes) -> int:
    """Length of the longest prefix of ``buf`` that ends with a whole line (0: none)."""
    n = buf.rfind(b"\n") + 1
    if n:
        return n
    r = buf.rfind(b"\r", 0, len(buf) - 1)  # a final \r may be the first half of \r\n
    return r + 1


@dataclass
class Block:
    """Rows of one chunk: ``data`` (m, k) float64 (columns contiguous), in the order of the
    columns asked for; ``first_line`` is the file line (1-based) the chunk starts at, ``raw``
    its bytes (a view of the bytes read)."""

    data: NDArray[np.float64]
    first_line: int
    raw: memoryview
    header: Sequence[str]
    source: str

    def row_lines(self) -> list[int]:
        """The file line of every row (blank lines skipped), told by the row-by-row reader."""
        text = decode_part(bytes(self.raw), self.source, self.first_line, self.header)
        return [
            ln
            for ln, _ in csv_rows(split_lines(text), 0, self.source, self.header, offset=self.first_line - 1)
        ]


class NumericCsv:
    """A numeric CSV file opened for reading in chunks (see the module docs).

    ``NumericCsv.open(path)`` reads the first chunk: its comment lines (``comments``, the
    lines before the header), ``header`` (names, stripped) and ``header_line``. It returns
    ``None`` when the header does not lie within the first chunk (then read the whole text).
    :meth:`blocks` then yields the data rows chunk by chunk.
    """

    def __init__(self, fh: BinaryIO, source: str, size: int | None, chunk: int) -> None:
        self._fh = fh
        self.source = source
        #: Bytes of the file if it is a regular file, else None.
        self.size = size
        self._chunk = chunk
        self.comments: list[str] = []
        self.header: list[str] = []
        self.header_line = 0
        self._carry = b""  # bytes read and not yet yielded (just before the reading position)
        self._line = 1  # file line of self._carry's first byte
        # a regular file is read again after each cut instead of carrying the cut line over, so
        # a chunk is the bytes object read, never a copy
        self._seekable = size is not None
        self._eof = False
        self.data_start = 0  # byte offset of the data (after the header row)

    @classmethod
    def open(cls, path: str | os.PathLike[str]) -> NumericCsv | None:
        """Open ``path`` and read its header (see the class docs); None: read the whole text.

        Raises
        ------
        DataFormatError
            Missing file, a directory, an unreadable file, an encoding error in the first chunk.
        """
        p = str(path)
        try:
            fh = open(p, "rb")
        except FileNotFoundError:
            raise DataFormatError("no such file", path=p) from None
        except IsADirectoryError:
            raise DataFormatError("is a directory, not a file", path=p) from None
        except OSError as e:
            raise DataFormatError(f"cannot read ({e.strerror or e})", path=p) from None
        try:
            st = os.fstat(fh.fileno())
            size = st.st_size if stat.S_ISREG(st.st_mode) else None
            self = cls(fh, p, size, chunk_bytes())
            if self._read_head():
                return self
        except IsADirectoryError:
            fh.close()
            raise DataFormatError("is a directory, not a file", path=p) from None
        except OSError as e:
            fh.close()
            raise DataFormatError(f"cannot read ({e.strerror or e})", path=p) from None
        except BaseException:
            fh.close()
            raise
        fh.close()
        return None

    def close(self) -> None:
        """Close the file."""
        self._fh.close()

    def __enter__(self) -> NumericCsv:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _read_head(self) -> bool:
        raw = self._fh.read(self._chunk)
        self._eof = len(raw) < self._chunk
        bom = 3 if raw.startswith(b"\xef\xbb\xbf") else 0
        # the comment lines and the header row, found in bytes: only they are decoded here (the
        # data rows are checked chunk by chunk)
        end = bom
        for m in _LINE_BREAKS.finditer(raw, bom):
            line = raw[end : m.start()]
            end = m.end()
            if not (line.startswith(b"#") or not line.strip()):
                break
        else:
            if not self._eof:
                return False  # no header in the first chunk: the whole text decides
            end = len(raw)
        head = raw[:end]
        if b'"' in head:
            return False  # quoting in the comments or header: the whole text decides
        lines = split_lines(decode(head, self.source))  # BOM, UTF-8, NUL: as for the whole text
        i = 0
        while i < len(lines) and (lines[i].startswith("#") or not lines[i].strip()):
            i += 1
        first = next(csv_rows(lines, i, self.source), None) if i < len(lines) else None
        if first is None or first[0] != len(lines):
            return False  # an empty file, a header row told otherwise: the whole text decides
        self.header_line, cells = first
        self.header = [h.strip() for h in cells]
        self.comments = lines[: self.header_line - 1]
        self.data_start = end
        if self._seekable:
            self._fh.seek(end)
            self._eof = False
        else:
            self._carry = raw[end:]
        self._line = self.header_line + 1
        return True

    def _chunks(self) -> Iterator[tuple[int, bytes, int]]:
        """(first line, bytes read, n): the first n bytes are a chunk of whole lines. The
        reading position is kept on ``self`` before each chunk is yielded, so a second iterator
        (:meth:`fail`) goes on after the chunk the first one yielded last."""
        while True:
            buf = self._carry
            if not self._eof and len(buf) < self._chunk:
                more = self._fh.read(self._chunk - len(buf))
                self._eof = len(more) < self._chunk - len(buf)
                buf = buf + more if buf else more
            if not buf:
                return
            n = len(buf) if self._eof else _cut(buf)
            while n == 0 and not self._eof and len(buf) < 4 * self._chunk:  # a very long line
                more = self._fh.read(self._chunk)
                self._eof = len(more) < self._chunk
                buf += more
                n = len(buf) if self._eof else _cut(buf)
            n = n or len(buf)  # a line of more than 4 chunks: the row-by-row reader judges it
            if n < len(buf) and self._seekable:
                self._fh.seek(n - len(buf), os.SEEK_CUR)  # the cut line is read with the next chunk
                self._carry = b""
            else:
                self._carry = buf[n:]
            first = self._line
            self._line += _line_count(buf, n)
            yield first, buf, n

    def _lookahead(self) -> bytes:
        """The whole lines of up to :data:`_LOOKAHEAD` bytes after the last chunk yielded
        (read now, yielded later)."""
        if not self._eof and len(self._carry) < _LOOKAHEAD:
            more = self._fh.read(_LOOKAHEAD)
            self._eof = len(more) < _LOOKAHEAD
            self._carry += more
        after = self._carry[:_LOOKAHEAD]
        if self._eof and len(after) == len(self._carry):
            return after
        return after[: _cut(after)]

    def blocks(
        self, columns: Sequence[str], *, exact_width: bool = False, nan_ok: bool = False
    ) -> Iterator[Block]:
        """The data rows, chunk by chunk, as :class:`Block` s of ``columns`` (names in
        :attr:`header`). ``exact_width`` refuses a row whose cell count differs from the
        header's; otherwise only a row too short for a wanted column is refused. Every cell
        must be finite, or with ``nan_ok`` a number or NaN (a missing value), not ±inf.

        Raises
        ------
        DataFormatError
            The first bad row's error (file, line, column), or an encoding error further on.
        """
        idx = [self.header.index(c) for c in columns]
        for line, buf, n in self._chunks():
            try:
                data = parse_chunk(buf, len(self.header), idx, exact_width=exact_width, nan_ok=nan_ok, end=n)
                if data is None:
                    data = self._row_by_row(buf[:n], line, columns, exact_width, nan_ok)
            except DataFormatError as e:
                self.fail(e)
            yield Block(data, line, memoryview(buf)[:n], self.header, self.source)

    def fail(self, error: DataFormatError) -> NoReturn:
        """Raise ``error``, or an encoding error (not UTF-8, NUL) in the rest of the file, which
        the whole-text reader finds first."""
        for first, buf, n in self._chunks():
            raw = buf[:n]
            if not raw.isascii() or b"\x00" in raw:
                decode_part(raw, self.source, first, self.header)
        raise error

    def _row_by_row(
        self, raw: bytes, line: int, columns: Sequence[str], exact_width: bool, nan_ok: bool
    ) -> NDArray[np.float64]:
        # A '"' may open a quoted cell that runs into the next chunk: the csv module reads on to
        # its field limit, so the text after the chunk is given too (and its rows dropped).
        after = self._lookahead() if b'"' in raw else b""
        text = decode_part(raw + after, self.source, line, self.header)
        lines = split_lines(text)
        data, row_lines = numeric_rows(
            lines,
            0,
            self.source,
            self.header,
            columns,
            exact_width=exact_width,
            offset=line - 1,
            min_rows=0,
            nan_ok=nan_ok,
        )
        keep = int(np.searchsorted(np.asarray(row_lines), line + _line_count(raw)))
        return np.asfortranarray(data[:keep].reshape(-1, len(columns)))


#: Copies of the numbers alive at once while a reader assembles what it read: the chunks'
#: columns, the joined columns, the arrays the reader builds from them (8 bytes each).
READ_COPIES = 3


def check_read_memory(
    source: str, what: str, rows: int, k: int, done: int, total: int | None, chunk: int
) -> None:
    """Refuse a read as soon as it is known to need more than the memory limit: ``rows`` rows of
    ``k`` numbers read from the first ``done`` of ``total`` bytes of data (None: a pipe), the
    largest chunk ``chunk`` bytes (the rows per byte so far project the file's rows).

    Raises
    ------
    ResourceLimitError
        With the file and the projected size named.
    """
    scale = total / done if total and done else 1.0
    expect = rows * max(scale, 1.0)
    check_memory(
        expect * k * 8 * READ_COPIES + chunk * CHUNK_MEMORY_FACTOR,
        f"{source}: a {what} of about {expect:.3g} rows × {k} columns",
    )


@dataclass
class NumericTable:
    """A numeric CSV read whole by :func:`read_table`.

    Attributes
    ----------
    source : str
        The file.
    comments : list of str
        The lines before the header (``#`` comments, blank lines).
    header : list of str
        The column names of the header row, stripped.
    header_line : int
        The file line (1-based) of the header row.
    columns : dict of str → ndarray, shape (n,)
        The columns read, float64.
    """

    source: str
    comments: list[str]
    header: list[str]
    header_line: int
    columns: dict[str, NDArray[np.float64]]
    _row_lines: list[int] | None = None
    _exact_width: bool = False
    _nan_ok: bool = False

    @property
    def rows(self) -> int:
        """Data rows read."""
        return next(iter(self.columns.values())).size if self.columns else 0

    def row_line(self, row: int) -> int:
        """The file line (1-based) of data row ``row`` (0-based), for an error message: the rows
        of a file read in chunks are found again by reading up to the chunk that holds it."""
        if self._row_lines is not None:
            return self._row_lines[row]
        csv = NumericCsv.open(self.source)
        assert csv is not None
        with csv:
            first = 0
            for b in csv.blocks(list(self.columns), exact_width=self._exact_width, nan_ok=self._nan_ok):
                m = b.data.shape[0]
                if row < first + m:
                    return b.row_lines()[row - first]
                first += m
        raise IndexError(row)


def read_table(
    path: str | os.PathLike[str],
    select: Callable[[list[str], int], list[str]],
    *,
    what: str,
    empty: str = "empty file (no header row)",
    exact_width: bool = False,
    nan_ok: bool = False,
    min_rows: int = 0,
) -> NumericTable:
    """Read a numeric CSV file whole, in chunks (see the module docs).

    Parameters
    ----------
    path : path-like
        The file.
    select : callable (header, header_line) → list of str
        The columns to read, in order; raises :class:`DataFormatError` for a header the reader
        refuses (a missing or duplicated column, named).
    what : str
        What the file is, for the memory-limit message (``"GNSS CSV"``).
    empty : str
        The message for a file without a header row.
    exact_width, nan_ok : bool
        As :meth:`NumericCsv.blocks`.
    min_rows : int
        Fewer data rows is an error.

    Raises
    ------
    DataFormatError
        The first error of the file (file, line, column; see the module docs).
    ResourceLimitError
        If the columns would need more memory than the limit (``UASNAV_MAX_MEMORY``).
    """
    source = str(path)
    csv = NumericCsv.open(path)
    if csv is None:  # the header lies beyond the first chunk (or is quoted): the whole text decides
        return _read_whole(source, select, empty, exact_width, nan_ok, min_rows)
    with csv:
        try:
            columns = select(csv.header, csv.header_line)
        except DataFormatError as e:
            csv.fail(e)
        total = csv.size - csv.data_start if csv.size is not None else None
        parts: list[NDArray[np.float64]] = []
        rows = done = largest = 0
        for b in csv.blocks(columns, exact_width=exact_width, nan_ok=nan_ok):
            parts.append(b.data)
            rows += b.data.shape[0]
            done += len(b.raw)
            largest = max(largest, len(b.raw))
            check_read_memory(source, what, rows, len(columns), done, total, largest)
        if rows < min_rows:
            raise DataFormatError(f"need at least {min_rows} data rows, got {rows}", path=source)
        cols = {
            c: np.concatenate([p[:, j] for p in parts]) if parts else np.empty(0)
            for j, c in enumerate(columns)
        }
        return NumericTable(
            source, csv.comments, csv.header, csv.header_line, cols, None, exact_width, nan_ok
        )


def _read_whole(
    source: str,
    select: Callable[[list[str], int], list[str]],
    empty: str,
    exact_width: bool,
    nan_ok: bool,
    min_rows: int,
) -> NumericTable:
    """:func:`read_table` of the whole text, row by row (a header beyond the first chunk)."""
    lines = split_lines(read_text(source))
    i = 0
    while i < len(lines) and (lines[i].startswith("#") or not lines[i].strip()):
        i += 1
    first = next(csv_rows(lines, i, source), None) if i < len(lines) else None
    if first is None:
        raise DataFormatError(empty, path=source)
    header_line, cells = first
    header = [h.strip() for h in cells]
    columns = select(header, header_line)
    data, row_lines = numeric_rows(
        lines, header_line, source, header, columns, exact_width=exact_width, min_rows=min_rows, nan_ok=nan_ok
    )
    cols = {c: np.ascontiguousarray(data[:, j]) for j, c in enumerate(columns)}
    return NumericTable(source, lines[: header_line - 1], header, header_line, cols, row_lines)


__all__ = [
    "CHUNK_MEMORY_FACTOR",
    "MAX_CHUNK_BYTES",
    "READ_COPIES",
    "Block",
    "NumericCsv",
    "NumericTable",
    "check_read_memory",
    "chunk_bytes",
    "read_table",
]
