"""``uasnav nav``: replay a flight log through the GNSS/INS filter."""

from __future__ import annotations

import math
from typing import Any

import click

from uasnav.cli._common import FINITE, POSITIVE, OutputPath, Real, check_outputs, echo_json


def _outages(values: tuple[str, ...]) -> tuple[tuple[float, float], ...]:
    out = []
    for v in values:
        try:
            a, b = v.split("+")
            start, dur = float(a), float(b)
        except ValueError:
            raise click.BadParameter(
                f"expected START+DURATION in seconds (e.g. 120+30), got {v!r}", param_hint="--gnss-outage"
            ) from None
        if not (math.isfinite(start) and math.isfinite(dur) and dur > 0):
            raise click.BadParameter(
                f"expected finite START and DURATION > 0, got {v!r}", param_hint="--gnss-outage"
            )
        out.append((start, dur))
    return tuple(out)


def _durations(text: str | None) -> list[float]:
    if text is None:
        return []
    try:
        vals = [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise click.BadParameter(
            f"expected comma-separated seconds, got {text!r}", param_hint="--outage-sweep"
        ) from None
    if not vals or not all(math.isfinite(v) and v > 0 for v in vals):
        raise click.BadParameter(f"expected durations > 0, got {text!r}", param_hint="--outage-sweep")
    return vals


@click.command("nav")
@click.argument("log", type=click.Path(exists=False), required=False)
@click.option(
    "--live",
    "live",
    metavar="CONNECTION",
    help="Run causally on a live MAVLink stream (udpin:HOST:PORT, tcp:HOST:PORT, tcpin:HOST:PORT, "
    "/dev/ttyX,BAUD) instead of LOG, writing --out as it goes and a status line per second.",
)
@click.option(
    "--causal",
    is_flag=True,
    help="Run LOG's MAVLink messages (a .tlog as recorded, .bin/.ulg as uasnav replay sends them) "
    "through the causal filter of --live.",
)
@click.option(
    "--idle-exit", type=POSITIVE, help="With --live: stop after this many seconds without a message."
)
@click.option(
    "--gnss",
    "gnss_path",
    type=click.Path(dir_okay=False),
    help="GNSS CSV (t,lat,lon,alt,vn,ve,vd,h_acc,v_acc,s_acc); required for a CSV log.",
)
@click.option(
    "--imu",
    "imu_sel",
    default=None,
    help="Which IMU: its index N (0-based, in the log's order) or 'fused' (redundant-IMU fusion).",
)
@click.option(
    "--model",
    "model_path",
    type=click.Path(dir_okay=False),
    help="Thermal model JSON (`uasnav calibrate`): TCZUPT in flight.",
)
@click.option(
    "--gnss-outage",
    "outages",
    multiple=True,
    metavar="START+DURATION",
    help="Mask GNSS from START for DURATION seconds (log time); repeatable.",
)
@click.option(
    "--outage-sweep",
    "sweep",
    default=None,
    metavar="D1,D2,…",
    help="GNSS-outage experiment: durations (s) at start times spread over the flight.",
)
@click.option(
    "--start", "t_start", type=FINITE, default=None, help="Use the log from this time (s, log clock)."
)
@click.option(
    "--end", "t_end", type=FINITE, default=None, help="Use the log up to this time (s), e.g. before a crash."
)
@click.option(
    "--declination",
    "declination",
    type=Real(-180.0, 180.0),
    default=None,
    metavar="DEG",
    help="Magnetic declination (degrees, east positive) for the magnetometer heading; default: "
    "the log's (COMPASS_DEC / EKF2_MAG_DECL), else the World Magnetic Model on the log's date.",
)
@click.option("--hal", "hal", type=POSITIVE, default=None, help="Horizontal alert limit (m).")
@click.option("--val", "val", type=POSITIVE, default=None, help="Vertical alert limit (m).")
@click.option("--out", "out_path", type=OutputPath(), help="Write TRACK.csv.")
@click.option("--geojson", "geojson_path", type=OutputPath(), help="Write the track as GeoJSON.")
@click.option("--kml", "kml_path", type=OutputPath(), help="Write the track as KML.")
@click.option(
    "--json",
    "as_json",
    is_flag=True,
    help="Print the comparison with the autopilot's estimate and the outage table as JSON.",
)
@click.option("--plot", "plot_path", type=OutputPath(), help="Write a PNG of the track.")
def command(
    log: str | None,
    live: str | None,
    causal: bool,
    idle_exit: float | None,
    gnss_path: str | None,
    imu_sel: str | None,
    model_path: str | None,
    outages: tuple[str, ...],
    sweep: str | None,
    t_start: float | None,
    t_end: float | None,
    declination: float | None,
    hal: float | None,
    val: float | None,
    out_path: str | None,
    geojson_path: str | None,
    kml_path: str | None,
    as_json: bool,
    plot_path: str | None,
) -> None:
    """Replay LOG (.ulg, .bin, .tlog, .csv with --gnss, or an ALFA ROS-topic CSV folder) through
    the loosely coupled GNSS/INS filter, compare it with the autopilot's own estimate, and
    optionally mask GNSS to measure dead-reckoning drift.

    Logged IMU streams (DataFlash, ULog, ROS) use the logged-IMU noise preset; a CSV log uses
    the consumer-MEMS defaults.
    """
    if live is not None or causal:
        if live is not None and (causal or log is not None):
            raise click.UsageError("--live reads CONNECTION: give no LOG and no --causal")
        if causal and log is None:
            raise click.UsageError("--causal needs LOG")
        if live is not None:
            run_live(live, out_path, hal, val, idle_exit)
        else:
            run_causal(str(log), out_path, hal, val)
        return
    if log is None:
        raise click.UsageError("missing LOG (or --live CONNECTION)")
    from uasnav import ins
    from uasnav.atomicfile import output_set
    from uasnav.errors import InputError
    from uasnav.ins import evaluate as ev
    from uasnav.io import read_nav

    outage_list = _outages(outages)
    durations = _durations(sweep)
    check_outputs(
        [log, gnss_path, model_path],
        {"--out": out_path, "--geojson": geojson_path, "--kml": kml_path, "--plot": plot_path},
    )
    flight = read_nav(log, gnss_csv=gnss_path)
    if t_start is not None or t_end is not None:
        lo = float(flight.imu.t[0]) if t_start is None else t_start
        hi = float(flight.imu.t[-1]) if t_end is None else t_end
        if not (math.isfinite(lo) and math.isfinite(hi) and hi > lo):
            raise click.BadParameter(
                f"expected finite --start < --end, got {lo!r} and {hi!r}", param_hint="--start/--end"
            )
        flight = flight.between(lo, hi)
    if imu_sel is not None:
        flight = _select_imu(flight, imu_sel)
    model = None
    if model_path is not None:
        from uasnav.thermal import load_model

        model = load_model(model_path)
    logged = flight.meta.get("format") in ("ardupilot-dataflash", "px4-ulog", "alfa-ros-csv", "mavlink-tlog")
    base: dict[str, Any] = {
        "mode": "tczupt" if model is not None else "classic",
        "model": model,
        "hal_m": hal,
        "val_m": val,
        "declination_deg": declination,
    }
    cfg = ins.InsConfig.for_logged_imu(**base) if logged else ins.InsConfig(**base)
    result = ins.run(flight, cfg.replace(gnss_outages=outage_list))
    report: dict[str, Any] = {
        "log": str(log),
        "imu": flight.meta.get("imu"),
        "imu_rate_hz": flight.imu.sample_rate,
        "declination": {
            "deg": result.summary["declination_deg"],
            "source": result.summary["declination_source"],
        },
        "summary": result.summary,
        # the datum of the heights the filter flew on and compared in (uasnav.geo.datum)
        "height_datum": str(flight.gnss.alt_datum),
        "excluded_fixes": result.excluded_fixes,
        "alerts": result.alerts,
        "gnss_outages": [{"start_s": s, "duration_s": d} for s, d in outage_list],
    }
    if "note" in flight.meta:
        report["note"] = flight.meta["note"]
    if flight.reference is not None:
        try:
            report["reference"] = ev.compare(result, flight.reference).as_dict()
        except InputError as e:
            report["reference"] = {"error": str(e)}
    if outage_list:
        report["outages"] = [
            ev.outage_end_error(result, flight, s, d, imu=str(flight.meta.get("imu", ""))).__dict__
            for s, d in outage_list
            if s + d < flight.gnss.t[-1]
        ]
    if durations:
        table = ev.outage_experiment(
            flight, durations, config=cfg, per_duration=5, imu_name=str(flight.meta.get("imu", ""))
        )
        report["outage_sweep"] = {"outages": [o.__dict__ for o in table.outages], "summary": table.summary()}
    with output_set():  # every output of the run, or none
        if out_path:
            result.to_csv(out_path)
        if geojson_path:
            result.write_geojson(geojson_path)
        if kml_path:
            result.to_kml(kml_path)
        if plot_path:
            _plot(result, flight, plot_path)
    if as_json:
        echo_json(report)
        return
    _print_text(log, flight, result, report)


def _print_text(log: str, flight: Any, result: Any, report: dict[str, Any]) -> None:
    s = result.summary
    click.echo(
        f"{log}: {flight.imu.n} IMU samples at {flight.imu.sample_rate:.1f} Hz, {flight.gnss.n} GNSS fixes"
    )
    click.echo(
        f"fixes used {s['fixes_used']}, excluded {s['fixes_excluded']}, masked {s['fixes_masked']}, "
        f"resets {s['gnss_resets']}; ZUPT {s['static_updates']}, baro {s['baro_updates']}, "
        f"alerts {s['alerts']}"
    )
    click.echo(f"magnetic declination {s['declination_deg']:+.2f}° ({s['declination_source']})")
    ref = report.get("reference")
    if isinstance(ref, dict) and "horizontal_rms_m" in ref:
        nan = float("nan")
        vel = ref["velocity_rms_m_s"] if ref["velocity_rms_m_s"] is not None else nan
        rp = ref["roll_pitch_rms_deg"] if ref["roll_pitch_rms_deg"] is not None else nan
        click.echo(
            f"vs {ref['reference']}: horizontal RMS {ref['horizontal_rms_m']:.2f} m, "
            f"vertical RMS {ref['vertical_rms_m']:.2f} m, velocity RMS {vel:.2f} m/s, "
            f"roll/pitch RMS {rp:.2f}°"
        )
    for o in report.get("outages", []):
        click.echo(
            f"outage {o['start']:g}+{o['duration']:g} s: horizontal error {o['horizontal_error_m']:.1f} m, "
            f"vertical {o['vertical_error_m']:.1f} m"
        )
    for d, row in report.get("outage_sweep", {}).get("summary", {}).items():
        click.echo(
            f"outage {d} s: {row['count']} outages, "
            f"median horizontal error {row['median_horizontal_m']:.1f} m, "
            f"max {row['max_horizontal_m']:.1f} m"
        )


def _select_imu(flight: Any, sel: str) -> Any:
    from uasnav.errors import InputError

    names = list(flight.imus)
    if sel == "fused":
        if len(names) < 2:
            raise InputError(
                f"--imu fused: the log has {len(names)} IMU ({', '.join(names)}); fusion needs at least 2"
            )
        from uasnav import redundancy

        logs = [flight.imus[n] for n in names]
        fused = redundancy.fuse(logs, redundancy.array_for_logs("aligned", logs)).to_log()
        return flight.with_imu(fused, "fused(" + "+".join(names) + ")")
    try:
        k = int(sel)
    except ValueError:
        if sel in flight.imus:
            return flight.with_imu(flight.imus[sel], sel)
        raise InputError(
            f"--imu: expected an index, an IMU name ({', '.join(names)}) or 'fused', got {sel!r}"
        ) from None
    if not 0 <= k < len(names):
        raise InputError(
            f"--imu {k}: the log has {len(names)} IMU(s) ({', '.join(names)}), indices 0..{len(names) - 1}"
        )
    return flight.with_imu(flight.imus[names[k]], names[k])


def _plot(result: Any, flight: Any, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from uasnav.atomicfile import atomic_open

    fig, ax = plt.subplots(figsize=(6, 6))
    result.plot(ax, reference=flight.reference)
    with atomic_open(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=100)
    plt.close(fig)


def _nav_config(hal: float | None, val: float | None) -> Any:
    from uasnav.ins.core import InsConfig

    return InsConfig.for_logged_imu(hal_m=hal, val_m=val)


class _TrackWriter:
    """TRACK.csv written as the solution comes (staged beside the target, flushed every second,
    renamed into place on a clean exit) and a one-line status per second on stderr."""

    def __init__(self, fh: Any, hal: float | None, val: float | None, status: bool) -> None:
        import time

        from uasnav.io.track import TRACK_COLUMNS

        self.fh, self.hal, self.val, self.status = fh, hal, val, status
        self.rows = 0
        self.last = None
        self._next = time.monotonic() + 1.0
        if fh is not None:
            fh.write(",".join(TRACK_COLUMNS) + "\n")

    def add(self, batch: Any, nav: Any) -> None:
        import time

        from uasnav.live.nav import format_rows, track_rows

        rows = track_rows(batch)
        if rows.shape[0]:
            self.rows += rows.shape[0]
            self.last = rows[-1]
            if self.fh is not None:
                self.fh.write(format_rows(rows))
        now = time.monotonic()
        if now >= self._next:
            self._next = now + 1.0
            if self.fh is not None:
                self.fh.flush()
            if self.status:
                click.echo(self.line(nav), err=True)

    def line(self, nav: Any) -> str:
        c = nav.counts()
        if self.last is None:
            return f"levelling: {nav.imu_messages} IMU samples, {nav.gnss_messages} fixes received"
        r = self.last
        hpl, vpl = r[16], r[17]
        alerts = []
        if self.hal is not None and hpl > self.hal:
            alerts.append("HPL>HAL")
        if self.val is not None and vpl > self.val:
            alerts.append("VPL>VAL")
        return (
            f"t {r[0]:.2f} s  {r[1]:.7f} {r[2]:.7f} {r[3]:.1f} m  v {math.hypot(r[4], r[5]):.1f} m/s  "
            f"HPL {hpl:.1f} m VPL {vpl:.1f} m  fixes {c['fixes_used']} used {c['fixes_excluded']} excluded  "
            f"IMU {c['imu_samples']} ({c['imu_refused']} refused, {c['imu_gaps']} gaps)"
            + (f"  ALERT {' '.join(alerts)}" if alerts else "")
        )


def _run(feed: Any, out_path: str | None, hal: float | None, val: float | None, status: bool) -> None:
    import contextlib

    from uasnav.atomicfile import atomic_open
    from uasnav.live.nav import LiveNav

    nav = LiveNav(_nav_config(hal, val))
    with atomic_open(out_path, "w") if out_path else contextlib.nullcontext() as fh:
        w = _TrackWriter(fh, hal, val, status)
        feed(nav, w)
        w.add(nav.flush(), nav)
    c = nav.counts()
    click.echo(
        f"{w.rows} solutions from {nav.imu_messages} IMU samples "
        f"({c['imu_refused']} refused, {c['imu_gaps']} gaps), "
        f"{nav.gnss_messages} fixes ({c['fixes_used']} used, {c['fixes_excluded']} excluded)"
        + (f"; wrote {out_path}" if out_path else ""),
        err=True,
    )


#: Messages collected before one call of the filter (offline); live batches also end every 50 ms.
_BATCH = 256


def run_causal(log: str, out_path: str | None, hal: float | None, val: float | None) -> None:
    """``nav --causal LOG``: the log's messages (as ``uasnav replay`` sends them) through the
    causal filter."""
    from uasnav.live.source import log_packets

    def feed(nav: Any, w: _TrackWriter) -> None:
        for pk in log_packets(log):
            nav.on_message(pk.msg)
            if nav.pending >= _BATCH:
                w.add(nav.flush(), nav)

    _run(feed, out_path, hal, val, status=False)


def run_live(
    connection: str, out_path: str | None, hal: float | None, val: float | None, idle_exit: float | None
) -> None:
    """``nav --live CONNECTION``: the causal filter on a live stream until interrupted."""
    from uasnav.live.stream import open_connection, receive, stop_on_signals

    conn = open_connection(connection)

    def feed(nav: Any, w: _TrackWriter) -> None:
        last = [0.0]

        def on_message(msg: Any, wall: float) -> None:
            nav.on_message(msg)
            if nav.pending >= _BATCH:
                last[0] = wall
                w.add(nav.flush(), nav)

        def on_tick(wall: float) -> None:
            if wall - last[0] >= 0.05:
                last[0] = wall
                w.add(nav.flush(), nav)

        with stop_on_signals() as stop:
            receive(conn, on_message, on_tick, stop=stop, idle_timeout_s=idle_exit)

    try:
        _run(feed, out_path, hal, val, status=True)
    finally:
        conn.close()
