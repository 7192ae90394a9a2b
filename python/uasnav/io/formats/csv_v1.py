"""Log format v1: CSV with a header row.

======== ======== ==========================================
column   unit     required
======== ======== ==========================================
t        s        yes — strictly increasing
gx gy gz rad/s    yes — body-frame angular rate
ax ay az m/s²     yes — body-frame specific force
temp     °C       no — sensor (die) temperature
mx my mz µT       no — magnetometer
truth_*  SI       no — ground truth of simulated logs, e.g.
                  ``truth_gyro_bias_x`` (rad/s); stored in ``ImuLog.truth`` as
                  ``gyro_bias`` with columns x, y, z (or ``_0 … _k`` for other widths)
======== ======== ==========================================

Lines starting with ``#`` before the header are comments; ``# key: value`` comments become
``ImuLog.meta`` (and :func:`write_csv_v1` writes ``ImuLog.meta`` back as such comments, e.g.
the ``# fused_from:``, ``# shape:``, ``# fdi:``, ``# dropped_samples:`` of a fused log). Any
other column is ignored on reading; :func:`write_csv_v1` can append such columns
(``extra_columns``, e.g. ``chi2_gyro`` and ``health_<i>`` of a fused log). Missing required
columns, non-numeric cells, NaN/inf and non-increasing ``t`` are errors naming the line and
column. Numbers are written with 17 significant digits, so write → read round-trips bit for bit.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav.atomicfile import atomic_open
from uasnav.errors import DataFormatError, InputError
from uasnav.imu import ImuLog, require_log
from uasnav.io._csvstream import NumericCsv, check_read_memory
from uasnav.io._text import csv_rows, numeric_rows, read_text, split_lines
from uasnav.io.flight import Flight, GnssData, MagData
from uasnav.io.formats.base import ImuFileFormat
from uasnav.io.formats.gnss_csv import read_gnss_csv
from uasnav.io.table import as_column, write_rows

REQUIRED = ("t", "gx", "gy", "gz", "ax", "ay", "az")
OPTIONAL = ("temp", "mx", "my", "mz")
_AXES = ("x", "y", "z")
_COMMENT = re.compile(r"#\s*([\w.-]+)\s*:\s*(.*)$")


def read_csv_v1(path: str | os.PathLike[str]) -> ImuLog:
    """Read a CSV v1 log.

    The file is read in chunks by the CSV engine (:class:`CsvV1Stream`,
    :mod:`uasnav.io._csvstream`); memory is about 24 bytes per number of the log's columns plus a
    bounded working set.

    Raises
    ------
    DataFormatError
        On a missing file or required column, a non-numeric or non-finite cell,
        non-increasing time, malformed CSV (a stray ``"``, a cell over 128 KiB) or text that is
        not UTF-8 or holds NUL bytes; the message names the file, line and column. A UTF-8
        byte-order mark is accepted.
    ResourceLimitError
        If the log is larger than the memory limit allows (:mod:`uasnav.limits`,
        ``UASNAV_MAX_MEMORY``).
    """
    with open_csv_v1(path) as stream:
        k = len(stream.columns)
        parts: list[NDArray[np.float64]] = []
        rows = 0
        largest_chunk = 0
        for block, done_bytes in stream.blocks_with_progress():
            parts.append(block)
            rows += block.shape[0]
            largest_chunk = max(largest_chunk, done_bytes[1])
            check_read_memory(
                stream.source, "CSV v1 log", rows, k, done_bytes[0], stream.data_bytes, largest_chunk
            )
        col: dict[str, NDArray[np.float64]] = {}
        for j, c in enumerate(stream.columns):
            col[c] = np.concatenate([b[:, j] for b in parts]) if parts else np.empty(0)
        del parts
        return _log(col, stream.meta, stream.source)


class CsvV1Stream:
    """A CSV v1 log opened for reading in chunks (:func:`open_csv_v1`).

    Attributes
    ----------
    source : str
        The file.
    meta : dict of str → str
        The ``# key: value`` comments before the header.
    columns : list of str
        The columns read, in block order: ``t gx gy gz ax ay az``, then those of ``temp mx my
        mz`` the file has, then its ``truth_*`` columns.
    data_bytes : int or None
        Bytes of data rows (after the header) of a regular file, else None.
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        p = Path(path)
        self.source = str(p)
        self._csv = NumericCsv.open(p)
        self._whole: NDArray[np.float64] | None = None
        self.data_bytes: int | None = None
        if self._csv is None:  # the header lies beyond the first chunk: the whole text decides
            self.meta, self.columns, self._whole, _ = _parse_text(read_text(p), self.source)
            return
        csv = self._csv
        try:
            self.meta = _meta(csv.comments)
            self.columns = _columns(csv.header, csv.header_line, self.source)
        except DataFormatError as e:
            try:
                csv.fail(e)
            finally:
                csv.close()
        if csv.size is not None:
            self.data_bytes = csv.size - csv.data_start

    def close(self) -> None:
        """Close the file."""
        if self._csv is not None:
            self._csv.close()

    def __enter__(self) -> CsvV1Stream:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def blocks(self) -> Iterator[NDArray[np.float64]]:
        """The data rows, chunk by chunk: arrays (m, len(:attr:`columns`)) float64, columns
        contiguous, ``t`` strictly increasing across blocks.

        Raises
        ------
        DataFormatError
            As :func:`read_csv_v1`, after the last block at the latest: the error the whole-text
            reader reports (encoding errors first, then the first bad row, then fewer than 2
            rows, then time), so a consumer must not use what it accumulated before the end.
        """
        for block, _ in self.blocks_with_progress():
            yield block

    def blocks_with_progress(self) -> Iterator[tuple[NDArray[np.float64], tuple[int, int]]]:
        """:meth:`blocks`, each with (bytes of data read so far, bytes of this chunk)."""
        if self._csv is None:
            assert self._whole is not None
            yield self._whole, (0, 0)
            return
        prev: float | None = None
        late: DataFormatError | None = None  # a time error: reported once no other error is found
        rows = 0
        done = 0
        for b in self._csv.blocks(self.columns, exact_width=True):
            m = b.data.shape[0]
            rows += m
            done += len(b.raw)
            if late is not None or m == 0:
                continue
            t = b.data[:, 0]
            d = np.diff(t, prepend=t[0] if prev is None else prev)
            bad = np.flatnonzero(d <= 0)
            if prev is None:
                bad = bad[bad > 0]
            if bad.size:
                r = int(bad[0])
                before = float(t[r - 1]) if r else prev
                late = _time_error(before, float(t[r]), self.source, b.row_lines()[r])
                continue
            prev = float(t[-1])
            yield b.data, (done, len(b.raw))
        if rows < 2:
            raise DataFormatError(f"need at least 2 data rows, got {rows}", path=self.source)
        if late is not None:
            raise late


def open_csv_v1(path: str | os.PathLike[str]) -> CsvV1Stream:
    """Open a CSV v1 log for reading in chunks (for consumers that stream, e.g. block means).

    Raises
    ------
    DataFormatError
        A missing file, or an error in the comment lines or the header (see :func:`read_csv_v1`).
    """
    return CsvV1Stream(path)


def parse_csv_v1(text: str, source: str = "<string>") -> ImuLog:
    """Parse CSV v1 text (see :func:`read_csv_v1`)."""
    if not isinstance(text, str):
        raise InputError(f"text: expected the CSV text as str, got {type(text).__name__}")
    meta, columns, data, _ = _parse_text(text, source)
    return _log({c: data[:, j] for j, c in enumerate(columns)}, meta, source)


def _meta(lines: list[str]) -> dict[str, str]:
    meta: dict[str, str] = {}
    for ln in lines:
        m = _COMMENT.match(ln)
        if m:
            meta[m.group(1)] = m.group(2).strip()
    return meta


def _columns(header: list[str], header_line: int, source: str) -> list[str]:
    """The columns a CSV v1 reader reads, in order; header errors name the line."""
    missing = [c for c in REQUIRED if c not in header]
    if missing:
        raise DataFormatError(
            f"missing required column(s) {', '.join(missing)} (header: {','.join(header)})",
            path=source,
            line=header_line,
        )
    if len(set(header)) != len(header):
        dup = sorted({h for h in header if header.count(h) > 1})
        raise DataFormatError(f"duplicated column(s) {', '.join(dup)}", path=source, line=header_line)
    return [*REQUIRED, *(c for c in OPTIONAL if c in header), *(c for c in header if c.startswith("truth_"))]


def _parse_text(text: str, source: str) -> tuple[dict[str, str], list[str], NDArray[np.float64], list[int]]:
    """The whole-text reader, row by row: (meta, columns, data (n, k), file line of each row)."""
    lines = split_lines(text.removeprefix("\ufeff"))
    i = 0
    while i < len(lines) and (lines[i].startswith("#") or not lines[i].strip()):
        i += 1
    if i >= len(lines):
        raise DataFormatError("empty file (no header row)", path=source)
    first = next(csv_rows(lines, i, source), None)
    if first is None:
        raise DataFormatError("empty file (no header row)", path=source)
    header_line = first[0]
    header = [h.strip() for h in first[1]]
    columns = _columns(header, header_line, source)
    data, row_lines = numeric_rows(lines, header_line, source, header, columns, exact_width=True)
    t = data[:, 0]
    d = np.diff(t)
    bad = np.flatnonzero(d <= 0)
    if bad.size:
        r = int(bad[0]) + 1
        raise _time_error(float(t[r - 1]), float(t[r]), source, row_lines[r])
    return _meta(lines[: header_line - 1]), columns, data, row_lines


def _time_error(before: float | None, after: float, source: str, line: int) -> DataFormatError:
    kind = "duplicated" if before == after else "decreasing"
    return DataFormatError(
        f"{kind} time stamp ({before!r} then {after!r}); t must be strictly increasing",
        path=source,
        line=line,
        column="t",
    )


def _log(col: dict[str, NDArray[np.float64]], meta: dict[str, str], source: str) -> ImuLog:
    truth = _group_truth([c for c in col if c.startswith("truth_")], col)
    return ImuLog(
        t=col["t"],
        gyro=np.column_stack([col["gx"], col["gy"], col["gz"]]),
        accel=np.column_stack([col["ax"], col["ay"], col["az"]]),
        temp=col.get("temp"),
        mag=np.column_stack([col["mx"], col["my"], col["mz"]]) if "mx" in col else None,
        truth=truth,
        meta={**meta, "source": source, "format": "csv-v1"},
    )


def _group_truth(cols: list[str], col: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    groups: dict[str, list[tuple[str, str]]] = {}
    for c in cols:
        base, _, suffix = c[len("truth_") :].rpartition("_")
        if not base or not (suffix in _AXES or suffix.isdigit()):
            # a 1-D channel, possibly with "_" in its name (truth_temp_die)
            base, suffix = c[len("truth_") :], ""
        groups.setdefault(base, []).append((suffix, c))
    out = {}
    for base, items in groups.items():
        if [s for s, _ in items] == [""]:
            out[base] = col[items[0][1]]
        else:
            order = {a: i for i, a in enumerate(_AXES)}
            items.sort(key=lambda sc: order.get(sc[0], 100 + int(sc[0]) if sc[0].isdigit() else 1000))
            out[base] = np.column_stack([col[c] for _, c in items])
    return out


def _truth_columns(name: str, arr: np.ndarray) -> list[tuple[str, np.ndarray]]:
    if arr.ndim == 1:
        return [(f"truth_{name}", arr)]
    k = arr.shape[1]
    suffixes = _AXES if k == 3 else tuple(str(i) for i in range(k))
    return [(f"truth_{name}_{s}", arr[:, j]) for j, s in enumerate(suffixes)]


def write_csv_v1(
    log: ImuLog,
    path: str | os.PathLike[str],
    *,
    extra_columns: Mapping[str, ArrayLike] | None = None,
) -> None:
    """Write ``log`` as CSV v1, atomically (temporary file + rename).

    Parameters
    ----------
    log : ImuLog
        Its ``meta`` (except ``source`` and ``format``) becomes ``# key: value`` comments (first
        line of each value), its ``truth`` channels ``truth_*`` columns.
    path : path-like
        Output file.
    extra_columns : mapping of str → array_like, each shape (n,), optional
        Further columns after the log's own (readers of CSV v1 ignore them), e.g. per-sample
        diagnostics; NaN is written ``nan``.

    Raises
    ------
    InputError
        An extra column that is not 1-D numeric with one value per sample, is infinite, or
        whose name is already a column.
    """
    require_log(log)
    cols: list[tuple[str, np.ndarray]] = [("t", log.t)]
    cols += [(f"g{a}", log.gyro[:, j]) for j, a in enumerate(_AXES)]
    cols += [(f"a{a}", log.accel[:, j]) for j, a in enumerate(_AXES)]
    if log.temp is not None:
        cols.append(("temp", log.temp))
    if log.mag is not None:
        cols += [(f"m{a}", log.mag[:, j]) for j, a in enumerate(_AXES)]
    for name, arr in log.truth.items():
        cols += _truth_columns(name, arr)
    for name, values in (extra_columns or {}).items():
        arr = as_column(name, values)
        if arr.size != log.n:
            raise InputError(f"extra column {name!r}: {arr.size} values for {log.n} samples")
        if name in {c for c, _ in cols}:
            raise InputError(f"extra column {name!r}: already a column of the log")
        cols.append((name, arr))
    with atomic_open(path, "w") as fh:
        fh.write("# uasnav log format v1 (SI units: s, rad/s, m/s^2, degC, uT)\n")
        for k, v in log.meta.items():
            if k in ("source", "format"):
                continue
            fh.write(f"# {k}: {str(v).splitlines()[0] if str(v) else ''}\n")
        fh.write(",".join(c for c, _ in cols) + "\n")
        # 17 significant digits round-trip every float64 exactly.
        write_rows(fh, np.column_stack([a for _, a in cols]))


class CsvV1Format(ImuFileFormat):
    """CSV v1 IMU log (:func:`read_csv_v1`); ``nav`` with the GNSS CSV given as the option
    ``gnss`` (``mx my mz`` become the magnetometer when present)."""

    name = "csv-v1"
    SOURCES: ClassVar[dict[str, tuple[str, ...]]] = {"imus": (), "imu": (), "nav": (), "identity": ()}

    def read_imu(self) -> ImuLog:
        return read_csv_v1(self.path)

    def stream(self) -> CsvV1Stream:
        """The data rows in chunks, for consumers that stream (:func:`open_csv_v1`: block
        means while reading)."""
        return open_csv_v1(self.path)

    def build_nav(self) -> Flight:
        gnss: Any = self.options.get("gnss")
        if gnss is None:
            raise InputError(
                f"{self.path}: a CSV IMU log needs --gnss GNSS.csv (t,lat,lon,alt,vn,ve,vd,h_acc,v_acc,s_acc)"
            )
        if not isinstance(gnss, GnssData):
            gnss = read_gnss_csv(gnss)
        imu = self.build_imu()
        mag = MagData(imu.t, imu.mag) if imu.mag is not None else None
        meta = {"source": str(self.path), "format": "csv-v1", "imu": "IMU"}
        return Flight(imu, gnss, None, mag, imus={"IMU": imu}, meta=meta)


__all__ = [
    "REQUIRED",
    "CsvV1Format",
    "CsvV1Stream",
    "open_csv_v1",
    "parse_csv_v1",
    "read_csv_v1",
    "write_csv_v1",
]
