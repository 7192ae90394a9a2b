"""The element table: measured trajectory elements as Arrow/Parquet rows — one schema for
:mod:`uasnav.trajectory` and the fleet (``uasnav fleet elements``).

One row per measured element (:class:`~uasnav.trajectory.samples.ElementSamples`):

=============== ========= ==============================================================
column          type      meaning
=============== ========= ==============================================================
run             int32     mission run within its log (0, 1, …)
element         int32     element index within its plan
segment_m       float64   segment length L the elements were cut with (m)
theta_deg       float64   folded turn angle, [0, 180] deg
theta_w_deg     float64   folded relative wind direction, [0, 360) deg
wind_ms         float64   wind speed |V_w| (m/s)
kind            int8      index into :data:`uasnav.trajectory.geometry.KINDS`
mirrored        bool      the element was mirrored when folded
length_m        float64   element length (m)
t_real_s        float64   measured time (s)
v_init_ms       float64   measured entry speed (m/s)
v_ref_ms        float64   commanded (cruise) speed (m/s)
dv_ms           float64   ΔV = L/t − V_ref (m/s)
element_kind    string    3D element kind (:data:`uasnav.trajectory.route3d.ELEMENT_KINDS`):
                          ``leg`` or ``turn`` for the measured horizontal elements
climb_rate_ms   float64   measured climb rate Δaltitude / t (m/s, up; NaN without altitude)
=============== ========= ==============================================================

The last two columns are optional when reading (tables written before they existed).

:func:`to_rows` / :func:`from_table` convert both ways exactly (float64 throughout);
:func:`read_element_dataset` reads a Parquet file or dataset directory of such rows (e.g. the
output of ``uasnav fleet elements``, whose extra key columns are ignored) back into samples for
``uasnav trajectory train``.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from uasnav._extras import require
from uasnav.errors import InputError
from uasnav.trajectory.features import Features
from uasnav.trajectory.samples import ElementSamples

if TYPE_CHECKING:
    import pyarrow as pa


@functools.cache
def _schema() -> pa.Schema:
    """The element table's Arrow schema (pyarrow, from the fleet extra, is imported here: training
    from flight logs alone needs none of it)."""
    require("fleet", "reading or writing element datasets (Parquet)")
    import pyarrow as pa

    return pa.schema(
        [
            pa.field("run", pa.int32()),
            pa.field("element", pa.int32()),
            pa.field("segment_m", pa.float64()),
            pa.field("theta_deg", pa.float64()),
            pa.field("theta_w_deg", pa.float64()),
            pa.field("wind_ms", pa.float64()),
            pa.field("kind", pa.int8()),
            pa.field("mirrored", pa.bool_()),
            pa.field("length_m", pa.float64()),
            pa.field("t_real_s", pa.float64()),
            pa.field("v_init_ms", pa.float64()),
            pa.field("v_ref_ms", pa.float64()),
            pa.field("dv_ms", pa.float64()),
            pa.field("element_kind", pa.string()),
            pa.field("climb_rate_ms", pa.float64()),
        ]
    )


def __getattr__(name: str) -> Any:
    # ELEMENT_SCHEMA is built on first use, so importing this module needs no pyarrow
    if name == "ELEMENT_SCHEMA":
        return _schema()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


#: Columns a table may lack (written before they existed).
OPTIONAL_COLUMNS = ("element_kind", "climb_rate_ms")


def to_rows(samples: ElementSamples, segment_m: float) -> list[dict[str, Any]]:
    """Rows of the element table (``run`` is the samples' ``flight`` index)."""
    f = samples.features
    cols = {
        "run": samples.flight, "element": samples.element, "theta_deg": f.theta_deg,
        "theta_w_deg": f.theta_w_deg, "wind_ms": f.wind_ms, "kind": f.kind, "mirrored": f.mirrored,
        "length_m": samples.length_m, "t_real_s": samples.t_real_s, "v_init_ms": samples.v_init_ms,
        "v_ref_ms": samples.v_ref_ms, "dv_ms": samples.dv_ms,
    }  # fmt: skip
    # 3D element kind of the horizontal elements: corners are turns (geometry.KINDS index 0)
    cols["element_kind"] = np.where(f.kind == 0, "turn", "leg")
    cols["climb_rate_ms"] = (
        np.full(len(samples), np.nan) if samples.climb_rate_ms is None else samples.climb_rate_ms
    )
    lists = {k: np.asarray(v).tolist() for k, v in cols.items()}
    return [{"segment_m": float(segment_m), **{k: lists[k][i] for k in lists}} for i in range(len(samples))]


def from_table(table: pa.Table, run_key: Sequence[str] = ("run",)) -> tuple[ElementSamples, float]:
    """Samples and segment length of an element table; runs numbered 0… by ``run_key`` (e.g.
    ``("log_hash", "run")`` for a fleet dataset, where ``run`` repeats across logs).

    Raises
    ------
    InputError
        Missing columns, no rows, or elements cut with different segment lengths.
    """
    missing = [n for n in _schema().names if n not in table.column_names and n not in OPTIONAL_COLUMNS]
    if missing:
        raise InputError(f"element table: missing column(s) {', '.join(missing)}")
    if table.num_rows == 0:
        raise InputError("element table: no elements")
    seg = np.unique(table.column("segment_m").to_numpy())
    if seg.size != 1:
        raise InputError(f"element table: elements cut with different segment lengths {seg.tolist()} m")

    def col(name: str, dtype: Any = np.float64) -> np.ndarray:
        return np.asarray(table.column(name).to_numpy(zero_copy_only=False), dtype=dtype)

    keys = list(zip(*(table.column(k).to_pylist() for k in run_key), strict=True))
    index = {k: i for i, k in enumerate(sorted(set(keys), key=lambda k: tuple(map(str, k))))}
    flight = np.array([index[k] for k in keys], dtype=int)
    samples = ElementSamples(
        features=Features(
            col("theta_deg"), col("theta_w_deg"), col("wind_ms"), col("kind", int), col("mirrored", bool)
        ),
        length_m=col("length_m"),
        t_real_s=col("t_real_s"),
        v_init_ms=col("v_init_ms"),
        v_ref_ms=col("v_ref_ms"),
        dv_ms=col("dv_ms"),
        flight=flight,
        element=col("element", int),
        climb_rate_ms=col("climb_rate_ms") if "climb_rate_ms" in table.column_names else None,
    )
    return samples, float(seg[0])


def is_element_dataset(path: str | os.PathLike[str]) -> bool:
    """True for a Parquet file or a directory (a Parquet dataset) — not a flight log."""
    p = Path(path)
    return p.is_dir() or p.suffix.lower() == ".parquet"


def _conform(table: pa.Table, path: Path) -> pa.Table:
    """``table`` with the element columns cast to :data:`ELEMENT_SCHEMA`'s types; a file of
    another schema (missing columns, text where numbers belong) is an :class:`InputError`
    naming the file and the column."""
    missing = [n for n in _schema().names if n not in table.column_names and n not in OPTIONAL_COLUMNS]
    if missing:
        raise InputError(f"{path}: not an element dataset: missing column(s) {', '.join(missing)}")
    import pyarrow as pa

    for field in _schema():
        if field.name not in table.column_names:
            continue
        i = table.schema.get_field_index(field.name)
        if table.schema.field(i).type == field.type:
            continue
        try:
            table = table.set_column(i, field, table.column(i).cast(field.type))
        except (pa.ArrowInvalid, pa.ArrowNotImplementedError):
            raise InputError(
                f"{path}: column {field.name!r} is {table.schema.field(i).type}, expected {field.type}"
            ) from None
    return table


def read_element_dataset(path: str | os.PathLike[str]) -> tuple[ElementSamples, float, int]:
    """Samples, segment length (m) and number of runs of a Parquet element file or dataset.

    Rows are ordered by (log_hash, run, element) when the fleet's ``log_hash`` column is there,
    so the result does not depend on the order files were written in.
    """
    p = Path(path)
    if not p.exists():
        raise InputError(f"{p}: no such element dataset")
    _schema()  # the fleet extra (pyarrow), named in one line when missing
    import pyarrow as pa
    import pyarrow.dataset as pads

    if p.is_dir():
        files = sorted(
            str(f)
            for f in p.rglob("*.parquet")
            if not any(part.startswith((".", "_")) for part in f.relative_to(p).parts)
        )
        if not files:
            raise InputError(f"{p}: no Parquet file in this directory (not an element dataset)")
    else:
        files = [str(p)]
    try:
        ds = pads.dataset(files, format="parquet", partitioning="hive", partition_base_dir=str(p))
        table = ds.to_table()
    except (pa.ArrowInvalid, OSError):
        # Arrow's message repeats the path; one line naming the input is what the user needs
        raise InputError(f"{p}: not a Parquet element dataset (unreadable or not Parquet)") from None
    table = _conform(table, p)
    key = ("log_hash", "run") if "log_hash" in table.column_names else ("run",)
    table = table.sort_by([(k, "ascending") for k in (*key, "element")])
    samples, seg = from_table(table, key)
    return samples, seg, int(samples.flight.max()) + 1


def training_samples(
    inputs: Sequence[str | os.PathLike[str]],
    plan: str | None = None,
    cruise_ms: float | None = None,
    wind_ne: np.ndarray | None = None,
    segment_m: float = 10.0,
    max_gap_s: float = 5.0,
    opened: dict[str, Any] | None = None,
) -> tuple[ElementSamples, int]:
    """Training samples and number of runs from flight logs and/or element datasets (what
    ``uasnav trajectory train`` accepts); logs go through
    :func:`uasnav.trajectory.flights.flight_samples` (``opened``, when given, receives the
    logs as opened there, path → LogFile, for further views from the same decoding pass).

    Raises
    ------
    InputError
        A dataset cut with another segment length than ``segment_m``.
    """
    from uasnav.trajectory.flights import flight_samples

    logs = [os.fspath(x) for x in inputs if not is_element_dataset(x)]
    parts: list[ElementSamples] = []
    n_runs = 0
    if logs:
        fs = flight_samples(logs, plan, cruise_ms, wind_ne, segment_m, max_gap_s)
        parts.append(fs.concat())
        n_runs = len(fs)
        if opened is not None:
            opened.update(fs.logs)
    for d in (x for x in inputs if is_element_dataset(x)):
        s, seg, k = read_element_dataset(d)
        if not np.isclose(seg, segment_m):
            raise InputError(f"{d}: elements cut with {seg:g} m segments, but --segment is {segment_m:g} m")
        s.flight[:] += n_runs
        parts.append(s)
        n_runs += k
    return ElementSamples.concat(parts), n_runs


__all__ = [
    "ELEMENT_SCHEMA",  # noqa: F822 (module __getattr__)
    "from_table",
    "is_element_dataset",
    "read_element_dataset",
    "to_rows",
    "training_samples",
]
