"""The on-disk layout of a fleet run: Parquet datasets, the errors table and the manifest.

One run writes one dataset directory ``OUT`` (the ``--out`` of ``uasnav fleet …``)::

    OUT/vehicle=V01/day=2026-11-24/<sha256>.parquet   one file per (log content hash, table)
    OUT/_errors/<sha256>.parquet                      one row per log that could not be read
    OUT/_manifest.jsonl                               the client's record of finished logs

The rows of a table are partitioned by vehicle and day (hive layout, read back by
``pyarrow.dataset`` with the partition columns). Each file is written by the worker that
processed the log, under a temporary name beside it and renamed into place
(:func:`uasnav.atomicfile.atomic_open`): a file that exists is complete, and its name depends
only on the log's content, so a task that Dask runs twice (after a worker died) writes the same
bytes to the same name — outputs are idempotent and each log appears exactly once.

The manifest is appended to by the *client* only, one JSON line per finished log (hash, path,
size, modification time, status), flushed and fsynced; a torn last line (a client killed while
writing) is ignored on reading. ``--resume`` skips the logs whose (path, size, mtime) it lists.
Files whose names start with ``_`` or ``.`` are ignored by ``pyarrow.dataset`` discovery, so the
errors table, the manifest and temporary files never mix with the rows.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
from collections.abc import Iterable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.dataset as pads
import pyarrow.parquet as pq

from uasnav.atomicfile import atomic_open
from uasnav.errors import DataFormatError, InputError

MANIFEST = "_manifest.jsonl"
ERRORS_DIR = "_errors"
#: Partition value of logs that do not tell their vehicle or day.
UNKNOWN = "unknown"

ERRORS_SCHEMA = pa.schema(
    [
        pa.field("path", pa.string()),
        pa.field("log_hash", pa.string()),
        pa.field("table", pa.string()),
        pa.field("error_type", pa.string()),
        pa.field("error", pa.string()),
    ]
)

_CHUNK = 1 << 20
_SAFE = re.compile(r"[^A-Za-z0-9._-]+")


def content_hash(path: str | os.PathLike[str]) -> str:
    """SHA-256 (hex) of the file's bytes, read in 1 MiB chunks (bounded memory)."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while chunk := fh.read(_CHUNK):
            h.update(chunk)
    return h.hexdigest()


def partition_value(text: str | None) -> str:
    """A partition directory value: letters, digits, ``.``, ``_``, ``-`` (others become ``_``)."""
    if not text:
        return UNKNOWN
    v = _SAFE.sub("_", str(text)).strip("._") or UNKNOWN
    return v[:64]


def table_file(out: Path, log_hash: str, vehicle: str | None, day: str | None) -> Path:
    """Where the rows of one log go (see the module layout)."""
    return out / f"vehicle={partition_value(vehicle)}" / f"day={partition_value(day)}" / f"{log_hash}.parquet"


def error_file(out: Path, key: str) -> Path:
    """Where the error row of one log goes."""
    return out / ERRORS_DIR / f"{key}.parquet"


def write_table(table: pa.Table, path: Path) -> None:
    """Write ``table`` to ``path`` atomically (temporary file + rename)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_open(path, "wb") as fh:
        pq.write_table(table, fh, compression="zstd")


def read_dataset(out: str | os.PathLike[str], schema: pa.Schema | None = None) -> pa.Table:
    """Every row of a fleet output dataset (partition columns ``vehicle`` and ``day`` included),
    sorted by ``log_hash`` and then the table's own order (``row`` column), so that two runs on
    the same logs compare equal whatever the order the logs finished in."""
    p = Path(out)
    if not p.is_dir():
        raise InputError(f"{p}: not a fleet dataset directory")
    files = sorted(str(f) for f in p.glob("vehicle=*/day=*/*.parquet"))
    if not files:
        if schema is None:
            raise InputError(f"{p}: the dataset holds no rows")
        return _with_partitions(schema).empty_table()
    ds = pads.dataset(files, format="parquet", partitioning="hive", partition_base_dir=str(p))
    table = ds.to_table()
    return table.sort_by([("log_hash", "ascending"), ("row", "ascending")])


def _with_partitions(schema: pa.Schema) -> pa.Schema:
    return schema.append(pa.field("vehicle", pa.string())).append(pa.field("day", pa.string()))


def read_errors(out: str | os.PathLike[str]) -> pa.Table:
    """The errors table of a fleet output (one row per unreadable log), sorted by path."""
    files = sorted((Path(out) / ERRORS_DIR).glob("*.parquet"))
    if not files:
        return ERRORS_SCHEMA.empty_table()
    t = pa.concat_tables([pq.read_table(f, schema=ERRORS_SCHEMA) for f in files])
    return t.sort_by([("path", "ascending"), ("table", "ascending")])


@dataclass(frozen=True)
class ManifestEntry:
    """One finished log, as the client recorded it."""

    path: str
    size: int
    mtime_ns: int
    log_hash: str | None
    table: str
    # "ok", "error", "timeout" (stopped at the per-log deadline: --resume with the same deadline
    # would stop it again) or "empty" (read, but nothing to write for this table)
    status: str


def stat_key(path: str) -> tuple[str, int, int]:
    """(absolute path, size, mtime_ns): how ``--resume`` recognises a log without reading it."""
    st = os.stat(path)
    return (os.path.abspath(path), int(st.st_size), int(st.st_mtime_ns))


#: The manifest's fields and their JSON types (``log_hash`` may also be null).
_ENTRY_TYPES: dict[str, type | tuple[type, ...]] = {
    "path": str, "size": int, "mtime_ns": int, "log_hash": (str, type(None)), "table": str, "status": str,
}  # fmt: skip


def _entry(line: str) -> ManifestEntry:
    """One manifest line, every field checked (a hand-edited or foreign line is refused, never
    half-read: a list where a path belongs would otherwise surface far from its cause)."""
    from uasnav import jsoncheck

    d = jsoncheck.parse(line, "not JSON")
    if not isinstance(d, dict):
        raise DataFormatError(f"expected a JSON object, got {type(d).__name__}")
    if set(d) != set(_ENTRY_TYPES):
        raise DataFormatError(f"expected the keys {', '.join(sorted(_ENTRY_TYPES))}")
    for k, want in _ENTRY_TYPES.items():
        if not isinstance(d[k], want) or isinstance(d[k], bool):
            raise DataFormatError(f"{k}: {jsoncheck.show(d[k])} is not of the expected type")
    return ManifestEntry(**d)


class Manifest:
    """The append-only record of finished logs in ``OUT/_manifest.jsonl`` (client side only)."""

    def __init__(self, out: Path) -> None:
        self.path = out / MANIFEST
        self.entries: dict[tuple[str, str, int, int], ManifestEntry] = {}
        self._paths: set[tuple[str, str]] = set()
        if self.path.exists():
            for e in self._read():
                self.entries[(e.table, e.path, e.size, e.mtime_ns)] = e
                self._paths.add((e.table, e.path))

    def _read(self) -> Iterable[ManifestEntry]:
        with open(self.path, encoding="utf-8") as fh:
            lines = fh.read().split("\n")
        for i, line in enumerate(lines, 1):
            if not line.strip():
                continue
            try:
                yield _entry(line)
            except DataFormatError as e:
                if i == len(lines) or (i == len(lines) - 1 and not lines[-1]):
                    continue  # a torn last line: the client died while appending it
                raise DataFormatError(f"corrupt manifest line ({e})", path=str(self.path), line=i) from None

    def tables(self) -> set[str]:
        """The analyses (``table`` names) this manifest records."""
        return {t for t, _ in self._paths}

    def done(self, table: str, key: tuple[str, int, int]) -> bool:
        """True if the log with this :func:`stat_key` was finished for ``table``."""
        return (table, *key) in self.entries

    def done_url(self, table: str, url: str) -> bool:
        """True if the log at the http(s) ``url`` was finished for ``table`` (the client never
        downloads, so a URL is recognised by its text; its content hash is in the entry)."""
        return (table, url) in self._paths

    def commit(self, entries: list[ManifestEntry]) -> None:
        """Append ``entries`` and fsync (the client commits as results arrive)."""
        if not entries:
            return
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with open(self.path, "a", encoding="utf-8") as fh:
            for e in entries:
                fh.write(json.dumps(asdict(e), sort_keys=True) + "\n")
                self.entries[(e.table, e.path, e.size, e.mtime_ns)] = e
                self._paths.add((e.table, e.path))
            fh.flush()
            os.fsync(fh.fileno())


def error_row(path: str, log_hash: str | None, table: str, exc: BaseException) -> dict[str, Any]:
    """The errors-table row of a log that failed."""
    return {
        "path": path,
        "log_hash": log_hash,
        "table": table,
        "error_type": type(exc).__name__,
        "error": " ".join(str(exc).split()) or type(exc).__name__,
    }


__all__ = [
    "ERRORS_SCHEMA",
    "MANIFEST",
    "Manifest",
    "ManifestEntry",
    "content_hash",
    "error_file",
    "error_row",
    "partition_value",
    "read_dataset",
    "read_errors",
    "stat_key",
    "table_file",
    "write_table",
]
