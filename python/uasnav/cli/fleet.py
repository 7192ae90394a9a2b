"""``uasnav fleet``: fleet-scale inventory, IMU health and trajectory elements on Dask."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import click

from uasnav.cli._common import POSITIVE, SEED, UAS_SPEED, OutputPath, echo_json
from uasnav.errors import InputError


@click.group("fleet")
def command() -> None:
    """Process a fleet's logs on a Dask cluster (a local one by default).

    SOURCE is a directory (scanned recursively for .ulg .bin .tlog .csv .txt .npz), a glob
    pattern, a list file (.list/.urls: one path, file:// or http(s):// URL per line; each worker
    downloads its URL logs itself) or a log file. The
    output is a Parquet dataset directory (partitioned by vehicle and day, one file per log);
    unreadable logs go to its errors table and never stop the run.
    """


# A run commits each log's table as it finishes and reads its dataset back at the end (scores,
# report): its outputs are not one staged set (the manifest makes a run resumable instead).
command.incremental_outputs = True  # type: ignore[attr-defined]


def _check_scheduler(ctx: click.Context, param: click.Parameter, value: str | None) -> str | None:
    if value is not None and "://" not in value:
        raise click.BadParameter(f"expected an address like tcp://HOST:8786, got {value!r}")
    return value


def _check_memory_limit(ctx: click.Context, param: click.Parameter, value: str | None) -> str | int | None:
    if value is None or value.strip().lower() == "auto":
        return value and "auto"
    from uasnav.limits import parse_size

    try:
        n = parse_size(value, "--memory-limit")
    except InputError as e:
        raise click.BadParameter(str(e)) from None
    if n < 64 * 1024**2:
        raise click.BadParameter(f"expected at least 64M per worker process, got {value!r}")
    return n


def _run_options(f: Any) -> Any:
    opts = [
        click.argument("sources", nargs=-1, required=True, type=click.Path()),
        click.option(
            "--out", "out", required=True, type=OutputPath(dir_okay=True),
            help="Output dataset directory, NAME.parquet.",
        ),
        click.option(
            "--scheduler", callback=_check_scheduler,
            help="Address of an existing Dask scheduler (tcp://HOST:8786); default a local cluster.",
        ),
        click.option(
            "--scheduler-file", type=click.Path(exists=True, dir_okay=False),
            help="Scheduler file of an existing Dask cluster (dask-scheduler --scheduler-file).",
        ),
        click.option(
            "--workers", type=click.IntRange(0, 4096),
            help="Worker processes of the local cluster (default one per core; 0 = in this process).",
        ),
        click.option(
            "--memory-limit", callback=_check_memory_limit, metavar="SIZE",
            help="Memory limit of each local worker process (e.g. 2G; default auto: memory ÷ workers).",
        ),
        click.option(
            "--log-timeout", type=POSITIVE, default=600.0, show_default=True, metavar="SECONDS",
            help="Deadline of one log (its download, then its analysis, run in a process that is killed "
            "at the deadline); a log past it is an error row and the run goes on.",
        ),
        click.option("--resume", is_flag=True, help="Continue a run in --out: only logs not yet finished."),
        click.option("--json", "as_json", is_flag=True, help="Print the run summary as JSON."),
    ]  # fmt: skip
    for o in reversed(opts):
        f = o(f)
    return f


def _check_out(out: str, suffix: str, option: str = "--out") -> None:
    if Path(out).suffix.lower() != suffix:
        raise InputError(f"{option} {out}: expected a name ending in {suffix}")


def _progress() -> Any:
    """A tqdm bar on stderr when it is a terminal (nothing otherwise), as a (done, total) callback."""
    from tqdm import tqdm

    bar: list[Any] = []

    def update(done: int, total: int) -> None:
        if not bar:
            bar.append(tqdm(total=total, unit="log", file=sys.stderr, disable=None, dynamic_ncols=True))
        bar[0].n = done
        bar[0].refresh()
        if done >= total:
            bar[0].close()

    def close() -> None:
        # a run that fails mid-way ends the bar's line, so its "error: …" starts a line of its own
        if bar:
            bar[0].close()

    update.close = close  # type: ignore[attr-defined]
    return update


def _execute(analysis: Any, sources: tuple[str, ...], out: str, scheduler: str | None,
             scheduler_file: str | None, workers: int | None, resume: bool,
             memory_limit: str | int | None = None, log_timeout: float | None = None) -> Any:  # fmt: skip
    from uasnav.fleet.runner import run

    _check_out(out, ".parquet")
    if scheduler is not None and scheduler_file is not None:
        raise click.UsageError("give --scheduler or --scheduler-file, not both")
    if workers is not None and (scheduler or scheduler_file):
        raise click.UsageError("--workers sizes the local cluster; it does not apply with --scheduler")
    if memory_limit is not None and (scheduler or scheduler_file or workers == 0):
        raise click.UsageError("--memory-limit applies to the local cluster's workers only")
    progress = _progress()
    try:
        return run(
            analysis, list(sources), out, scheduler=scheduler, scheduler_file=scheduler_file,
            workers=workers, resume=resume, progress=progress, memory_limit=memory_limit or "auto",
            **({} if log_timeout is None else {"fetch_timeout_s": log_timeout, "log_timeout_s": log_timeout}),
        )  # fmt: skip
    finally:
        progress.close()  # type: ignore[attr-defined]


def _print(summary: Any, as_json: bool) -> None:
    info = {
        "table": summary.table,
        "out": summary.out,
        "logs": summary.n_logs,
        "skipped_finished": summary.n_skipped,
        "ok": summary.n_ok,
        "empty": summary.n_empty,
        "errors": summary.n_errors,
        "timeouts": summary.n_timeouts,
        "rows": summary.n_rows,
        "bytes_read": summary.bytes_read,
        "wall_s": summary.wall_s,
        "cpu_s": summary.cpu_s,
        "logs_per_s": summary.logs_per_s,
        "workers": summary.workers,
        "scheduler": summary.scheduler,
        "worker_memory_limit": summary.worker_memory_limit,
        "error_list": summary.errors,
        **summary.extra,
    }
    if as_json:
        echo_json(info)
        return
    click.echo(
        f"{summary.table}: {summary.n_logs} log(s), {summary.n_ok} written, {summary.n_empty} without rows, "
        f"{summary.n_errors} error(s), {summary.n_skipped} already finished; {summary.n_rows} row(s) → "
        f"{summary.out} ({summary.wall_s:.1f} s, {summary.workers} worker(s))"
    )
    for e in summary.errors[:20]:
        click.echo(f"  error: {e['error']}")
    for o in summary.extra.get("outliers", [])[:20]:
        click.echo(f"  outlier: {o['path']} {o['imu']} (score {o['score']:.1f}, {o['driver']})")


@command.command("scan")
@_run_options
def scan(sources, out, scheduler, scheduler_file, workers, resume, memory_limit, log_timeout, as_json):  # type: ignore[no-untyped-def]
    """Inventory: one row per log (format, vehicle, start, duration, IMUs, GNSS, mission, hash)."""
    from uasnav.fleet.scan import SCAN

    _print(
        _execute(SCAN, sources, out, scheduler, scheduler_file, workers, resume, memory_limit, log_timeout),
        as_json,
    )


@command.command("imu-health")
@_run_options
@click.option(
    "--report", "report_path", type=OutputPath(), help="Write an HTML page (FLEET.html) of the fleet."
)
def imu_health(
    sources, out, scheduler, scheduler_file, workers, resume, memory_limit, log_timeout, as_json, report_path
):  # type: ignore[no-untyped-def]
    """Per log and IMU: noise terms, turn-on bias, temperature slope, vibration, clipping, anomaly score."""
    from uasnav.fleet.imu_health import IMU_HEALTH

    if report_path is not None:
        _check_out(report_path, ".html", "--report")
    summary = _execute(
        IMU_HEALTH, sources, out, scheduler, scheduler_file, workers, resume, memory_limit, log_timeout
    )
    if report_path is not None:
        from uasnav.fleet.html import write_health_report

        write_health_report(out, report_path)
        summary.extra["report"] = report_path
    _print(summary, as_json)


@command.command("elements")
@_run_options
@click.option("--segment", type=POSITIVE, default=10.0, show_default=True, help="Segment length L (m).")
@click.option("--speed", type=UAS_SPEED, help="Commanded speed (m/s); default each log's waypoint speed.")
@click.option(
    "--max-gap",
    type=POSITIVE,
    default=5.0,
    show_default=True,
    help="Largest telemetry gap in an element (s).",
)
def elements(
    sources,
    out,
    scheduler,
    scheduler_file,
    workers,
    resume,
    memory_limit,
    log_timeout,
    as_json,
    segment,
    speed,
    max_gap,
):  # type: ignore[no-untyped-def]
    """Trajectory elements (features, measured times) of every log that flew a mission."""
    from uasnav.fleet.elements import elements_analysis

    analysis = elements_analysis(segment, speed, max_gap)
    _print(
        _execute(
            analysis, sources, out, scheduler, scheduler_file, workers, resume, memory_limit, log_timeout
        ),
        as_json,
    )


@command.command("nav")
@_run_options
def nav(sources, out, scheduler, scheduler_file, workers, resume, memory_limit, log_timeout, as_json):  # type: ignore[no-untyped-def]
    """GNSS/INS replay of every log with IMU and GNSS: RMS against its reference, outage drift."""
    from uasnav.fleet.nav import NAV

    _print(
        _execute(NAV, sources, out, scheduler, scheduler_file, workers, resume, memory_limit, log_timeout),
        as_json,
    )


@command.command("simulate")
@click.option("--vehicles", type=click.IntRange(1, 1000), required=True, help="Number of vehicles N.")
@click.option("--flights", type=click.IntRange(1, 1000), required=True, help="Flights per vehicle M.")
@click.option(
    "--out", "out", required=True, type=OutputPath(dir_okay=True, file_okay=False), help="Folder to write."
)
@click.option("--seed", type=SEED, default=0, show_default=True)
@click.option("--duration", type=POSITIVE, default=120.0, show_default=True, help="Length of each log (s).")
@click.option("--rate", type=POSITIVE, default=100.0, show_default=True, help="IMU sample rate (Hz).")
@click.option(
    "--nav-flights",
    type=click.IntRange(0, 100),
    default=0,
    show_default=True,
    help="GNSS/INS flights per vehicle (IMU CSV v1 + GNSS CSV + .tlog with the mission).",
)
@click.option("--json", "as_json", is_flag=True, help="Print the fleet's truth as JSON.")
def simulate(vehicles, flights, out, seed, duration, rate, nav_flights, as_json):  # type: ignore[no-untyped-def]
    """Write a synthetic fleet: N vehicles × M flights (CSV v1), a few faulty IMUs and corrupt files;
    with --nav-flights, missions flown in the GNSS/INS flight format."""
    from uasnav.fleet.simulate import simulate_fleet

    if Path(out).exists() and any(Path(out).iterdir()):
        raise InputError(f"--out {out}: exists and is not empty")
    if rate > 10_000:
        raise InputError(f"--rate {rate:g}: at most 10000 Hz")
    fl = simulate_fleet(
        out, vehicles, flights, seed=seed, duration_s=duration, rate_hz=rate, nav_flights=nav_flights
    )
    if as_json:
        echo_json({"out": fl.out, "files": len(fl.files), "faulty": fl.faulty, "corrupt": fl.corrupt})
    else:
        click.echo(
            f"{len(fl.files)} file(s) in {out}: {len(fl.faulty)} with a faulty IMU, "
            f"{len(fl.corrupt)} corrupt (truth in fleet.json)"
        )
