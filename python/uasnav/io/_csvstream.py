"""Numeric CSV read in chunks through pyarrow's CSV reader, with the row-by-row reader's errors.

:class:`NumericCsv` reads a CSV file (``#`` comment lines, a header row, numeric data rows) in
chunks of whole lines (:func:`chunk_bytes`, at most 16 MiB), each parsed by
:func:`pyarrow.csv.read_csv` into float64 columns, so memory stays bounded by the chunk size
whatever the file's length, and a consumer can stream (block means while reading) or
concatenate.

pyarrow accepts a subset of what the row-by-row reader of :mod:`uasnav.io._text` accepts, never
more: no quoting (a ``"`` anywhere sends the chunk row by row), no null markers, cells of at
most 64 KiB, UTF-8 checked, NUL bytes, NaN and ±inf handed over. Any chunk pyarrow refuses is
parsed by the row-by-row reader, which either names the first bad cell (file, line, column:
the same :class:`~uasnav.errors.DataFormatError` as reading the whole text) or accepts what
``float`` accepts and pyarrow does not (``1_0``, non-ASCII digits). Both paths return the same
values bit for bit (``tests/test_io_csv_stream.py``).

The errors come in the order the whole-text reader finds them: an encoding error anywhere in
the file (not UTF-8, a NUL byte) wins over any other error, so after the first other error the
rest of the file is scanned for one (:meth:`NumericCsv.fail`).
"""

from __future__ import annotations

import os
import re
import stat
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import BinaryIO, NoReturn

import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv
from numpy.typing import NDArray

from uasnav.errors import DataFormatError
from uasnav.io._text import csv_rows, decode, decode_part, numeric_rows, split_lines
from uasnav.limits import max_memory

#: Largest chunk (bytes of text) parsed at once.
MAX_CHUNK_BYTES = 16 * 1024**2
#: Peak bytes of memory per byte of a chunk while it is parsed (pyarrow's buffers and columns,
#: or the row-by-row reader's Python objects when it takes over: ≈ 6, see ``_text``).
CHUNK_MEMORY_FACTOR = 8
#: A chunk whose lines are all shorter than this is parsed by pyarrow; a longer line may hold a
#: cell beyond the :mod:`csv` module's field limit (128 KiB), which only the row-by-row reader
#: reports as such.
_MAX_FAST_LINE = 64 * 1024
#: Text after a chunk given to the row-by-row reader with it when a ``"`` may open a quoted
#: cell running on: the :mod:`csv` module stops such a cell at its field limit (128 KiB).
_LOOKAHEAD = 1024**2
_LINE_BREAKS = re.compile(rb"\r\n|\r|\n")


def chunk_bytes() -> int:
    """Bytes of text per chunk: 1/64 of the memory limit, within [256 KiB, 16 MiB]."""
    return int(min(MAX_CHUNK_BYTES, max(256 * 1024, max_memory() // 64)))


def _line_count(raw: bytes) -> int:
    """Line breaks in ``raw`` (``\\n``, ``\\r\\n`` or ``\\r``, like :func:`split_lines`)."""
    n = raw.count(b"\n")
    if raw.find(b"\r") >= 0:
        n += raw.count(b"\r") - raw.count(b"\r\n")
    return n


def _cut(buf: bytes) -> int:
    """Length of the longest prefix of ``buf`` that ends with a whole line (0: none)."""
    n = buf.rfind(b"\n") + 1
    if n:
        return n
    r = buf.rfind(b"\r", 0, len(buf) - 1)  # a final \r may be the first half of \r\n
    return r + 1


def _short_lines(raw: bytes) -> bool:
    """True if every aligned window of :data:`_MAX_FAST_LINE` bytes of ``raw`` holds a line
    break: then no line is as long as 2 × 64 KiB, the :mod:`csv` module's field limit."""
    w = _MAX_FAST_LINE
    for a in range(0, len(raw), w):
        if raw.find(b"\n", a, a + w) < 0 and raw.find(b"\r", a, a + w) < 0 and a + w < len(raw):
            return False
    return True


@dataclass
class Block:
    """Rows of one chunk: ``data`` (m, k) float64 (columns contiguous), in the order of the
    columns asked for; ``first_line`` is the file line (1-based) the chunk starts at."""

    data: NDArray[np.float64]
    first_line: int
    raw: bytes
    header: Sequence[str]
    source: str

    def row_lines(self) -> list[int]:
        """The file line of every row (blank lines skipped), told by the row-by-row reader."""
        text = decode_part(self.raw, self.source, self.first_line, self.header)
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
        self._carry = b""  # bytes read and not yet yielded
        self._line = 1  # file line of self._carry's first byte
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
        self._carry = raw[end:]
        self._line = self.header_line + 1
        return True

    def _chunks(self) -> Iterator[tuple[int, bytes]]:
        """(first line, chunk of whole lines). The reading position is kept on ``self`` before
        each chunk is yielded, so a second iterator (:meth:`fail`) goes on after the chunk the
        first one yielded last."""
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
            part = buf if n == len(buf) else buf[:n]
            self._carry = buf[n:]
            first = self._line
            self._line += _line_count(part)
            yield first, part

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

    def blocks(self, columns: Sequence[str], *, exact_width: bool = False) -> Iterator[Block]:
        """The data rows, chunk by chunk, as :class:`Block` s of ``columns`` (names in
        :attr:`header`). ``exact_width`` refuses a row whose cell count differs from the
        header's; otherwise only a row too short for a wanted column is refused.

        Raises
        ------
        DataFormatError
            The first bad row's error (file, line, column), or an encoding error further on.
        """
        for line, raw in self._chunks():
            try:
                data = self._fast(raw, columns)
                if data is None:
                    data = self._row_by_row(raw, line, columns, exact_width)
            except DataFormatError as e:
                self.fail(e)
            yield Block(data, line, raw, self.header, self.source)

    def fail(self, error: DataFormatError) -> NoReturn:
        """Raise ``error``, or an encoding error (not UTF-8, NUL) in the rest of the file, which
        the whole-text reader finds first."""
        for first, raw in self._chunks():
            if not raw.isascii() or b"\x00" in raw:
                decode_part(raw, self.source, first, self.header)
        raise error

    def _fast(self, raw: bytes, columns: Sequence[str]) -> NDArray[np.float64] | None:
        if b'"' in raw or b"\x00" in raw or not _short_lines(raw):
            return None
        if not raw.isascii():
            try:
                raw.decode("utf-8")
            except UnicodeDecodeError:
                return None  # the row-by-row reader names the line and column
        try:
            table = pacsv.read_csv(
                pa.py_buffer(raw),
                read_options=pacsv.ReadOptions(column_names=self.header),
                parse_options=pacsv.ParseOptions(
                    quote_char=False, double_quote=False, escape_char=False, ignore_empty_lines=True
                ),
                convert_options=pacsv.ConvertOptions(
                    column_types=dict.fromkeys(columns, pa.float64()),
                    include_columns=list(columns),
                    null_values=[],
                    strings_can_be_null=False,
                    quoted_strings_can_be_null=False,
                    check_utf8=False,
                ),
            )
        except (pa.ArrowInvalid, pa.ArrowTypeError):
            return None
        out = np.empty((table.num_rows, len(columns)), dtype=np.float64, order="F")
        for j, c in enumerate(columns):
            col = table.column(c)
            if col.null_count:
                return None
            out[:, j] = col.to_numpy()
        if not np.isfinite(out).all():
            return None
        return out

    def _row_by_row(
        self, raw: bytes, line: int, columns: Sequence[str], exact_width: bool
    ) -> NDArray[np.float64]:
        # A '"' may open a quoted cell that runs into the next chunk: the csv module reads on to
        # its field limit, so the text after the chunk is given too (and its rows dropped).
        after = self._lookahead() if b'"' in raw else b""
        text = decode_part(raw + after, self.source, line, self.header)
        lines = split_lines(text)
        data, row_lines = numeric_rows(
            lines, 0, self.source, self.header, columns, exact_width=exact_width, offset=line - 1, min_rows=0
        )
        keep = int(np.searchsorted(np.asarray(row_lines), line + _line_count(raw)))
        return np.asfortranarray(data[:keep].reshape(-1, len(columns)))


__all__ = ["CHUNK_MEMORY_FACTOR", "MAX_CHUNK_BYTES", "Block", "NumericCsv", "chunk_bytes"]
