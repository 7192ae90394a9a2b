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
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from uasnav.atomicfile import atomic_open
from uasnav.errors import DataFormatError, InputError
from uasnav.imu import ImuLog, require_log
from uasnav.io._text import csv_rows, numeric_rows, read_text, split_lines
from uasnav.io.table import as_column, write_rows

REQUIRED = ("t", "gx", "gy", "gz", "ax", "ay", "az")
_AXES = ("x", "y", "z")


def read_csv_v1(path: str | os.PathLike[str]) -> ImuLog:
    """Read a CSV v1 log.

    Raises
    ------
    DataFormatError
        On a missing file or required column, a non-numeric or non-finite cell,
        non-increasing time, malformed CSV (a stray ``"``, a cell over 128 KiB) or text that is
        not UTF-8 or holds NUL bytes; the message names the file, line and column. A UTF-8
        byte-order mark is accepted.
    ResourceLimitError
        If the file is larger than the memory limit allows (see :mod:`uasnav.io._text`).
    """
    p = Path(path)
    return parse_csv_v1(read_text(p), source=str(p))


def parse_csv_v1(text: str, source: str = "<string>") -> ImuLog:
    """Parse CSV v1 text (see :func:`read_csv_v1`)."""
    if not isinstance(text, str):
        raise InputError(f"text: expected the CSV text as str, got {type(text).__name__}")
    lines = split_lines(text.removeprefix("\ufeff"))
    meta: dict[str, str] = {}
    i = 0
    while i < len(lines) and (lines[i].startswith("#") or not lines[i].strip()):
        m = re.match(r"#\s*([\w.-]+)\s*:\s*(.*)$", lines[i])
        if m:
            meta[m.group(1)] = m.group(2).strip()
        i += 1
    if i >= len(lines):
        raise DataFormatError("empty file (no header row)", path=source)
    first = next(csv_rows(lines, i, source), None)
    if first is None:
        raise DataFormatError("empty file (no header row)", path=source)
    header_line = first[0]
    header = [h.strip() for h in first[1]]
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
    optional = [c for c in ("temp", "mx", "my", "mz") if c in header]
    truth_cols = [c for c in header if c.startswith("truth_")]
    wanted = list(REQUIRED) + optional + truth_cols
    data, row_lines = numeric_rows(lines, header_line, source, header, wanted, exact_width=True)
    col = {c: data[:, j] for j, c in enumerate(wanted)}
    t = col["t"]
    d = np.diff(t)
    bad = np.flatnonzero(d <= 0)
    if bad.size:
        r = int(bad[0]) + 1
        kind = "duplicated" if d[bad[0]] == 0 else "decreasing"
        raise DataFormatError(
            f"{kind} time stamp ({float(t[r - 1])!r} then {float(t[r])!r}); t must be strictly increasing",
            path=source,
            line=row_lines[r],
            column="t",
        )
    truth = _group_truth(truth_cols, col)
    return ImuLog(
        t=t,
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


__all__ = ["REQUIRED", "parse_csv_v1", "read_csv_v1", "write_csv_v1"]
