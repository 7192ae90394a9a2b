"""The fleet runner: one analysis, many logs, on a Dask cluster or in this process.

An :class:`Analysis` is a table name, its Arrow schema and one function from a log file to the
rows of that log (:class:`LogRows`). Adding a per-log feature (a GNSS/INS replay, a thermal
calibration) is writing that function and wrapping it::

    def replay(path: str) -> LogRows: ...
    REPLAY = Analysis("replay", REPLAY_SCHEMA, replay)
    run(REPLAY, ["logs/"], "replay.parquet")

:func:`run` finds the logs (:func:`uasnav.fleet.sources.discover`), leaves out those the
manifest lists as finished (``resume=True``), and maps :func:`process_log` over the rest:

- on an existing cluster (``scheduler="tcp://host:8786"`` or ``scheduler_file=``; Kubernetes,
  HPC job queues and cloud deployments all give one), or
- on a ``distributed.LocalCluster`` of ``workers`` processes (default: one per core), one thread
  each, so that each worker holds one log at a time and its memory limit bounds a task's memory, or
- in this process (``workers=0``): the single-process path, the same function in a loop.

A log named by an http(s) URL is downloaded by the worker that processes it (never by the
client) with the project's hardened HTTP transport (:func:`uasnav.httpfetch.download`: total
deadline ``fetch_timeout_s``, redirects to http(s) only, at most ``fetch_max_bytes``, default
:func:`uasnav.limits.max_memory`), streamed to a temporary file on the worker, hashed, analysed
and removed; the rows carry the URL as their ``path``. A URL that cannot be fetched (404,
timeout, too large, refused redirect) is a row of the errors table; it is not committed to the
manifest, so ``resume=True`` tries it again, while a finished URL is skipped by its text.

With a per-log deadline (``log_timeout_s``, the CLI's ``--log-timeout``) each worker analyses its
logs in a child process that is killed at the deadline (:mod:`uasnav.fleet.deadline`): a decoder
stuck in native code cannot hold the run, and the log is recorded as timed out.

Each task reads its log once, writes its rows to one Parquet file named by the log's content
hash (atomically, :mod:`uasnav.fleet.output`) and returns a small :class:`TaskResult`; no
samples travel to the client. A log that cannot be read becomes a row of the errors table and
the run goes on. The client commits each result to the manifest as it arrives, so a run stopped
at any point is continued by ``resume=True``. A task that Dask re-runs after its worker died
writes the same file again (same name, same bytes): each log is in the output exactly once.
"""

from __future__ import annotations

import logging
import math
import os
import re
import shutil
import tempfile
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq

from uasnav._extras import require
from uasnav.errors import InputError
from uasnav.fleet.deadline import LogTimeout, call_with_deadline
from uasnav.fleet.output import (
    ERRORS_SCHEMA,
    MANIFEST,
    Manifest,
    ManifestEntry,
    content_hash,
    error_file,
    error_row,
    stat_key,
    table_file,
    write_table,
)
from uasnav.fleet.sources import discover
from uasnav.httpfetch import FetchError, download, is_url
from uasnav.limits import max_memory

#: Columns the runner adds in front of every analysis' own (the partition columns ``vehicle``
#: and ``day`` come from the directory names).
KEY_FIELDS = (
    pa.field("log_hash", pa.string()),
    pa.field("path", pa.string()),
    pa.field("size_bytes", pa.int64()),
    pa.field("row", pa.int32()),
)

Progress = Callable[[int, int], None] | None
#: Errors listed in a :class:`RunSummary` (and the ``--json`` summary); the errors table in the
#: output holds every one.
MAX_LISTED_ERRORS = 1000
#: Default total deadline of one log's download (s).
FETCH_TIMEOUT_S = 600.0
#: Task statuses that are not committed to the manifest (``--resume`` tries them again).
RETRIED = ("lost", "unfetched")
#: Deadline (s) for an existing scheduler to answer Dask's handshake: a port that accepts the
#: connection and never speaks (another service) would otherwise hold the run indefinitely.
SCHEDULER_CONNECT_S = 5.0
#: Largest scheduler file read (bytes); Dask writes a few hundred.
MAX_SCHEDULER_FILE_BYTES = 1 << 20


@dataclass(frozen=True)
class LogRows:
    """What an analysis returns for one log.

    Attributes
    ----------
    rows : list of dict
        The table rows of this log (keys: the analysis schema's column names). May be empty.
    vehicle, day : str, optional
        Partition values (vehicle identifier; day as ``YYYY-MM-DD``); ``unknown`` if None.
    """

    rows: list[dict[str, Any]]
    vehicle: str | None = None
    day: str | None = None


@dataclass(frozen=True)
class Analysis:
    """One per-log analysis: its table name, column schema and function (module docs).

    ``finish(out)``, if given, runs on the client after every log is done (e.g. the
    fleet-relative anomaly scores of the IMU health table, which need the whole fleet).
    """

    name: str
    schema: pa.Schema
    compute: Callable[[str], LogRows]
    finish: Callable[[Path], Any] | None = None
    #: Modules ``compute`` imports when it runs: a run with a per-log deadline imports them in
    #: each analysing process before the deadline starts (:mod:`uasnav.fleet.deadline`).
    imports: tuple[str, ...] = ()

    @property
    def full_schema(self) -> pa.Schema:
        """The schema of the files written: key columns, then the analysis' own."""
        return pa.schema([*KEY_FIELDS, *self.schema])


@dataclass(frozen=True)
class TaskResult:
    """The outcome of one log (small: this is all that travels back to the client)."""

    path: str
    size: int
    mtime_ns: int
    log_hash: str | None
    # "ok", "empty", "error" (a bad log), "timeout" (stopped at the per-log deadline), "lost"
    # (the cluster gave up on the task), "unfetched" (an http(s) log that could not be downloaded)
    status: str
    n_rows: int = 0
    cpu_s: float = 0.0
    error: str | None = None


def _rows_table(analysis: Analysis, rows: list[dict[str, Any]], key: dict[str, Any]) -> pa.Table:
    cols: dict[str, list[Any]] = {f.name: [] for f in analysis.full_schema}
    for i, r in enumerate(rows):
        unknown = set(r) - set(cols)
        if unknown:
            raise InputError(f"analysis {analysis.name!r}: unknown column(s) {sorted(unknown)}")
        for k in cols:
            cols[k].append(i if k == "row" else key[k] if k in key else r.get(k))
    return pa.Table.from_pydict(cols, schema=analysis.full_schema)


def process_log(
    path: str,
    analysis: Analysis,
    out: str,
    *,
    fetch_timeout_s: float = FETCH_TIMEOUT_S,
    fetch_max_bytes: int | None = None,
    log_timeout_s: float | None = None,
) -> TaskResult:
    """Run ``analysis`` on one log and write its rows (or its error row); idempotent.

    Runs on a worker (or in this process). Never raises for a bad log: any exception of the
    reading or the analysis becomes an errors-table row. A log whose content hash already has
    its file in ``out`` is not computed again: logs are identified by content, so two copies of
    one log are stored once (under the path of the copy processed first). An http(s) ``path``
    is downloaded first (module docs), within ``fetch_timeout_s`` seconds and
    ``fetch_max_bytes`` bytes (default :func:`uasnav.limits.max_memory`). The analysis of one
    log stops after ``log_timeout_s`` seconds (an errors-table row).
    """
    cpu0 = time.process_time()
    out_p = Path(out)
    if is_url(path):
        limit = max_memory() if fetch_max_bytes is None else int(fetch_max_bytes)
        return _process_url(path, analysis, out_p, cpu0, fetch_timeout_s, limit, log_timeout_s)
    try:
        size, mtime_ns = stat_key(path)[1:]
    except OSError as e:
        row = error_row(path, None, analysis.name, e)
        write_table(pa.Table.from_pylist([row], schema=ERRORS_SCHEMA), error_file(out_p, _path_key(path)))
        return TaskResult(path, -1, -1, None, "error", error=row["error"])
    return _process_file(path, path, size, mtime_ns, analysis, out_p, cpu0, log_timeout_s)


def _local_name(url: str) -> str:
    """A safe file name for the download of ``url`` that keeps its extension (the readers
    recognise formats by it)."""
    from urllib.parse import unquote, urlsplit

    base = os.path.basename(unquote(urlsplit(url).path))
    return re.sub(r"[^A-Za-z0-9._-]", "_", base).lstrip(".")[-120:] or "log"


def _process_url(
    url: str,
    analysis: Analysis,
    out_p: Path,
    cpu0: float,
    timeout_s: float,
    max_bytes: int,
    log_timeout_s: float | None = None,
) -> TaskResult:
    tmpdir = tempfile.mkdtemp(prefix="uasnav-fleet-")
    try:
        local = os.path.join(tmpdir, _local_name(url))
        try:
            with open(local, "wb") as fh:
                size = download(url, fh, timeout_s=timeout_s, max_bytes=max_bytes, user_agent="uasnav-fleet")
        except FetchError as e:
            row = error_row(url, None, analysis.name, e)
            write_table(pa.Table.from_pylist([row], schema=ERRORS_SCHEMA), error_file(out_p, _path_key(url)))
            return TaskResult(
                url, -1, -1, None, "unfetched", cpu_s=time.process_time() - cpu0, error=row["error"]
            )
        # fetched now: an error row left by an earlier failed fetch of this URL no longer holds
        error_file(out_p, _path_key(url)).unlink(missing_ok=True)
        return _process_file(local, url, size, 0, analysis, out_p, cpu0, log_timeout_s)
    finally:
        shutil.rmtree(tmpdir, ignore_errors=True)


def _process_file(
    local: str,
    path: str,
    size: int,
    mtime_ns: int,
    analysis: Analysis,
    out_p: Path,
    cpu0: float,
    log_timeout_s: float | None = None,
) -> TaskResult:
    """Hash, analyse and write the log in the file ``local``, known to the tables as ``path``."""
    log_hash: str | None = None
    try:
        log_hash = content_hash(local)
        done = sorted(out_p.glob(f"vehicle=*/day=*/{log_hash}.parquet"))
        if done:
            # the same content was finished before (a resumed run, a renamed or copied log, or
            # Dask re-running a task whose result was lost): nothing to compute
            n = pq.read_metadata(done[0]).num_rows
            return TaskResult(
                path, size, mtime_ns, log_hash, "ok", n_rows=n, cpu_s=time.process_time() - cpu0
            )
        with warnings.catch_warnings():
            # corrupt-record warnings of the readers: the log is salvaged; the run stays quiet
            warnings.simplefilter("ignore")
            if log_timeout_s is None or not math.isfinite(log_timeout_s):
                result = analysis.compute(local)
            else:
                try:
                    result = call_with_deadline(analysis.compute, local, log_timeout_s, analysis.imports)
                except LogTimeout:
                    raise LogTimeout(
                        f"{path}: analysis stopped after the per-log deadline of {log_timeout_s:g} s "
                        "(--log-timeout)"
                    ) from None
        if not result.rows:
            return TaskResult(path, size, mtime_ns, log_hash, "empty", cpu_s=time.process_time() - cpu0)
        table = _rows_table(analysis, result.rows, {"log_hash": log_hash, "path": path, "size_bytes": size})
        write_table(table, table_file(out_p, log_hash, result.vehicle, result.day))
        return TaskResult(
            path, size, mtime_ns, log_hash, "ok", n_rows=table.num_rows, cpu_s=time.process_time() - cpu0
        )
    except Exception as e:  # a corrupt log must never stop the run: record it
        status = "timeout" if isinstance(e, LogTimeout) else "error"
        row = error_row(path, log_hash, analysis.name, e)
        if local != path:  # the reader names the temporary download: name the URL instead
            row["error"] = row["error"].replace(local, path)
        key = f"{analysis.name}-{log_hash or _path_key(path)}"
        write_table(pa.Table.from_pylist([row], schema=ERRORS_SCHEMA), error_file(out_p, key))
        return TaskResult(
            path, size, mtime_ns, log_hash, status, cpu_s=time.process_time() - cpu0, error=row["error"]
        )


def _path_key(path: str) -> str:
    import hashlib

    name = path if is_url(path) else os.path.abspath(path)
    return "path-" + hashlib.sha256(name.encode()).hexdigest()


@dataclass
class RunSummary:
    """What a run did (the ``--json`` summary of ``uasnav fleet …``)."""

    table: str
    out: str
    n_logs: int
    n_skipped: int = 0
    n_ok: int = 0
    n_empty: int = 0
    n_errors: int = 0
    #: Logs stopped at the per-log deadline (counted in ``n_errors`` too).
    n_timeouts: int = 0
    n_rows: int = 0
    bytes_read: int = 0
    wall_s: float = 0.0
    cpu_s: float = 0.0
    workers: int = 0
    scheduler: str = "in-process"
    #: Smallest memory limit of the cluster's workers (bytes; None in process or unlimited).
    worker_memory_limit: int | None = None
    errors: list[dict[str, str | None]] = field(default_factory=list)
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def logs_per_s(self) -> float:
        """Processed logs (not skipped) per wall-clock second."""
        n = self.n_ok + self.n_empty + self.n_errors
        return n / self.wall_s if self.wall_s > 0 else 0.0


def _prepare_out(out: Path, resume: bool) -> None:
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out}: exists and is not a dataset directory")
    if out.is_dir() and any(out.iterdir()) and not resume:
        raise InputError(f"--out {out}: exists; pass --resume to continue that run, or remove it")


def local_cluster(workers: int | None = None, memory_limit: str | float = "auto") -> Any:
    """A ``distributed.LocalCluster`` of ``workers`` processes (default one per core), one thread
    each, no dashboard, quiet logs."""
    require("fleet", "fleet processing on a Dask cluster")
    from distributed import LocalCluster

    n = workers or os.cpu_count() or 1
    return LocalCluster(
        n_workers=n,
        threads_per_worker=1,
        processes=True,
        memory_limit=memory_limit,
        dashboard_address=None,
        silence_logs=logging.ERROR,
    )


def run(
    analysis: Analysis,
    sources: Sequence[str | os.PathLike[str]],
    out: str | os.PathLike[str],
    *,
    client: Any = None,
    scheduler: str | None = None,
    scheduler_file: str | None = None,
    workers: int | None = None,
    resume: bool = False,
    progress: Progress = None,
    fetch_timeout_s: float = FETCH_TIMEOUT_S,
    fetch_max_bytes: int | None = None,
    memory_limit: str | int = "auto",
    log_timeout_s: float | None = None,
) -> RunSummary:
    """Run ``analysis`` over every log of ``sources`` and write the dataset ``out``.

    Parameters
    ----------
    analysis : Analysis
    sources : sequence of str
        Directories, glob patterns, list files or log files (:func:`~uasnav.fleet.sources.discover`).
    out : path
        Output dataset directory (module :mod:`uasnav.fleet.output`).
    client : distributed.Client, optional
        Use this client (its cluster) as it is; it is not closed.
    scheduler, scheduler_file : str, optional
        Connect to an existing scheduler by address or scheduler file.
    workers : int, optional
        Size of the local cluster (default one process per core); 0 runs in this process.
    resume : bool
        Continue a run: logs the manifest lists as finished are skipped. Without it an
        existing, non-empty ``out`` is refused.
    progress : callable(done, total), optional
        Called after each log.
    fetch_timeout_s, fetch_max_bytes : optional
        Total deadline (s) and size limit (bytes, default :func:`uasnav.limits.max_memory` on
        the worker) of the download of each http(s) log.
    log_timeout_s : float, optional
        Deadline of one log's analysis (s). With a deadline each log is analysed in a child
        process of the worker (:mod:`uasnav.fleet.deadline`), killed at the deadline whatever
        it is doing (a long call into native code included); the log is an errors-table row and
        a ``timeout`` entry of the manifest, and the run goes on. Default: no deadline beyond
        the decoders' own bounds, the analysis in the worker itself.
    memory_limit : str or int
        Memory limit of each worker process of the local cluster (bytes, or Dask's ``"auto"``:
        the machine's memory ÷ workers); a worker above it is restarted by its nanny.

    Returns
    -------
    RunSummary
    """
    out_p = Path(out)
    _prepare_out(out_p, resume)
    paths = discover(sources)
    t0 = time.perf_counter()
    manifest = Manifest(out_p) if out_p.is_dir() else None
    if manifest is not None and (other := manifest.tables() - {analysis.name}):
        raise InputError(
            f"--out {out_p}: a dataset of {', '.join(sorted(other))}, not {analysis.name}; "
            "--resume continues the same analysis (give another --out)"
        )
    todo, skipped = [], 0
    for p in paths:
        try:
            if is_url(p):
                done = manifest is not None and manifest.done_url(analysis.name, p)
            else:
                done = manifest is not None and manifest.done(analysis.name, stat_key(p))
        except OSError:
            done = False  # unreadable: the task records the error
        if done:
            skipped += 1
        else:
            todo.append(p)
    created = not out_p.exists()
    out_p.mkdir(parents=True, exist_ok=True)
    fetch = {
        "fetch_timeout_s": fetch_timeout_s,
        "fetch_max_bytes": fetch_max_bytes,
        "log_timeout_s": log_timeout_s,
    }
    try:
        return _run(analysis, out_p, todo, len(paths), skipped, manifest or Manifest(out_p), t0,
                    client, scheduler, scheduler_file, workers, progress, fetch, memory_limit)  # fmt: skip
    except BaseException:
        # a run that failed before committing anything (e.g. no scheduler at that address)
        # leaves nothing behind
        if created and not (out_p / MANIFEST).exists():
            shutil.rmtree(out_p, ignore_errors=True)
        raise


def _run(
    analysis: Analysis,
    out_p: Path,
    todo: list[str],
    n_logs: int,
    skipped: int,
    manifest: Manifest,
    t0: float,
    client: Any,
    scheduler: str | None,
    scheduler_file: str | None,
    workers: int | None,
    progress: Progress,
    fetch: dict[str, Any],
    memory_limit: str | int = "auto",
) -> RunSummary:
    summary = RunSummary(analysis.name, str(out_p), n_logs, n_skipped=skipped)
    if progress is not None:
        progress(0, len(todo))

    def record(res: TaskResult) -> None:
        if res.status not in RETRIED:
            manifest.commit(
                [
                    ManifestEntry(
                        res.path if is_url(res.path) else os.path.abspath(res.path),
                        res.size,
                        res.mtime_ns,
                        res.log_hash,
                        analysis.name,
                        res.status,
                    )
                ]
            )
        summary.cpu_s += res.cpu_s
        if res.status == "timeout":
            summary.n_timeouts += 1
        if res.status == "ok":
            summary.n_ok += 1
            summary.n_rows += res.n_rows
        elif res.status == "empty":
            summary.n_empty += 1
        else:
            summary.n_errors += 1
            if len(summary.errors) < MAX_LISTED_ERRORS:  # the errors table has them all
                summary.errors.append({"path": res.path, "error": res.error})
        summary.bytes_read += max(res.size, 0)
        if progress is not None:
            progress(summary.n_ok + summary.n_empty + summary.n_errors, len(todo))

    if workers == 0 and client is None and scheduler is None and scheduler_file is None:
        summary.workers, summary.scheduler = 0, "in-process"
        for p in todo:
            record(process_log(p, analysis, str(out_p), **fetch))
    elif todo:
        _run_distributed(
            analysis,
            todo,
            out_p,
            record,
            summary,
            client,
            scheduler,
            scheduler_file,
            workers,
            fetch,
            memory_limit,
        )
    if analysis.finish is not None:
        summary.extra = analysis.finish(out_p) or {}
    summary.wall_s = time.perf_counter() - t0
    return summary


def scheduler_address(scheduler: str | None, scheduler_file: str | None) -> str:
    """The address of an existing scheduler, from ``scheduler`` or the ``address`` of the JSON
    ``scheduler_file`` (``dask scheduler --scheduler-file``).

    Raises
    ------
    InputError
        A scheduler file that is not Dask's (not JSON, no ``address`` text), naming the file.
    """
    if scheduler is not None:
        return scheduler
    from uasnav import jsoncheck

    src = os.fspath(scheduler_file or "")
    with jsoncheck.reraise_in(src):
        d = jsoncheck.parse(jsoncheck.read_text(src, MAX_SCHEDULER_FILE_BYTES), "not a Dask scheduler file")
        address = d.get("address") if isinstance(d, dict) else None
        if not isinstance(address, str) or "://" not in address:
            raise jsoncheck.fail(
                "address", "not a Dask scheduler file: expected an address like tcp://HOST:8786"
            )
    return address


def check_scheduler(
    address: str, option: str = "--scheduler", timeout_s: float = SCHEDULER_CONNECT_S
) -> None:
    """Refuse, within ``timeout_s``, an address where no Dask scheduler answers: an unknown
    scheme, nothing listening, or a peer that accepts and never completes Dask's handshake
    (``distributed``'s own connect bounds the TCP connection, not the handshake after it).

    Raises
    ------
    InputError
        Naming ``option``, the address and what went wrong.
    """
    import asyncio

    from distributed.comm import connect

    async def probe() -> None:
        comm = await asyncio.wait_for(connect(address, timeout=timeout_s), timeout_s)
        await comm.close()

    try:
        asyncio.run(probe())
    except TimeoutError:
        raise InputError(
            f"{option} {address}: no Dask scheduler answered within {timeout_s:g} s "
            "(nothing listening, or another service on that port)"
        ) from None
    except (OSError, ValueError, TypeError) as e:  # CommClosedError is an OSError; ValueError: scheme
        raise InputError(
            f"{option} {address}: not a reachable Dask scheduler ({' '.join(str(e).split())})"
        ) from None


def _run_distributed(
    analysis: Analysis,
    todo: list[str],
    out: Path,
    record: Callable[[TaskResult], None],
    summary: RunSummary,
    client: Any,
    scheduler: str | None,
    scheduler_file: str | None,
    workers: int | None,
    fetch: dict[str, Any],
    memory_limit: str | int = "auto",
) -> None:
    require("fleet", "fleet processing on a Dask cluster")
    from distributed import Client, as_completed

    cluster = None
    own = client is None
    if own:
        if scheduler is not None or scheduler_file is not None:
            address = scheduler_address(scheduler, scheduler_file)
            check_scheduler(
                address, "--scheduler" if scheduler is not None else f"--scheduler-file {scheduler_file}:"
            )
            client = Client(address=address, timeout=f"{SCHEDULER_CONNECT_S:g}s")
        else:
            cluster = local_cluster(workers, memory_limit)
            client = Client(cluster)
    try:
        summary.scheduler = str(client.scheduler.address)
        summary.workers = len(client.nthreads())
        limits = [w.get("memory_limit") for w in client.scheduler_info().get("workers", {}).values()]
        summary.worker_memory_limit = min((int(m) for m in limits if m), default=None)
        # Keys name the analysis and the log: a task is identified by what it computes, so a
        # resubmission (after a lost worker) is the same task.
        futures = client.map(process_log, todo, analysis=analysis, out=str(out), pure=False, **fetch)
        by_key = {f.key: p for f, p in zip(futures, todo, strict=True)}
        for fut in as_completed(futures):
            try:
                res = fut.result()
            except Exception as e:  # infrastructure failure (e.g. KilledWorker after retries)
                path = by_key[fut.key]
                row = error_row(path, None, analysis.name, e)
                write_table(
                    pa.Table.from_pylist([row], schema=ERRORS_SCHEMA), error_file(out, _path_key(path))
                )
                try:
                    size, mtime = stat_key(path)[1:]
                except OSError:
                    size, mtime = -1, -1
                # "lost": in the errors table, but not committed, so --resume tries it again
                res = TaskResult(path, size, mtime, None, "lost", error=row["error"])
            record(res)
            fut.release()
    finally:
        if own:
            client.close()
            if cluster is not None:
                cluster.close()


__all__ = [
    "FETCH_TIMEOUT_S",
    "KEY_FIELDS",
    "Analysis",
    "LogRows",
    "LogTimeout",
    "RunSummary",
    "TaskResult",
    "check_scheduler",
    "local_cluster",
    "process_log",
    "run",
    "scheduler_address",
]
