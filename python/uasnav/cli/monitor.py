"""``uasnav monitor``: ASTM F3548 conformance monitoring of live MAVLink telemetry."""

from __future__ import annotations

import json
import time
from typing import Any

import click

from uasnav.cli._common import POSITIVE, OutputPath, Real, check_outputs


def _vehicle_map(values: tuple[str, ...]) -> dict[int, str] | None:
    if not values:
        return None
    out: dict[int, str] = {}
    for v in values:
        sysid, _, name = v.partition("=")
        if not sysid.strip().isdigit() or not name or not 1 <= int(sysid) <= 255:
            raise click.BadParameter(
                f"expected SYSID=INTENT (SYSID 1…255), got {v!r}", param_hint="--vehicle"
            )
        out[int(sysid)] = name
    return out


def _text(ev: dict[str, Any]) -> str:
    t = ev.get("time_utc") or (f"boot+{ev['time_boot_s']:.1f}s" if ev.get("time_boot_s") is not None else "-")
    where = ""
    if ev.get("lat") is not None:
        where = f" at {ev['lat']:.6f},{ev['lon']:.6f} {ev['alt_w84_m']:.1f} m W84"
    margin = f" margin {ev['margin_m']:+.1f} m" if ev.get("margin_m") is not None else ""
    what = ev["state"] if ev["event"] == "state" else ev["event"].replace("_", " ")
    return f"{t} vehicle {ev['vehicle']} ({ev['intent']}): {what}{where}{margin} — {ev['reason']}"


@click.command("monitor")
@click.argument("connection")
@click.option(
    "--intent",
    "intent_paths",
    multiple=True,
    required=True,
    type=click.Path(dir_okay=False),
    help="Operational intent JSON (F3548 OperationalIntentDetails); repeat for several vehicles.",
)
@click.option(
    "--vehicle",
    "vehicle_opts",
    multiple=True,
    help="SYSID=INTENT: which MAVLink system flies which intent (by file name without .json). "
    "Default: system 1 flies the first intent, 2 the second …",
)
@click.option("--json-lines", "json_lines", is_flag=True, help="Print each event as one JSON line.")
@click.option("--out", "out_path", type=OutputPath(), help="Also write the events to EVENTS.jsonl.")
@click.option(
    "--contingent-after-outside",
    type=Real(0.0, None),
    default=30.0,
    show_default=True,
    help="Contingent after this long nonconforming (s, vehicle time).",
)
@click.option(
    "--contingent-after-loss",
    type=Real(0.0, None),
    default=10.0,
    show_default=True,
    help="Contingent after this long without telemetry (s, vehicle time).",
)
@click.option(
    "--telemetry-timeout",
    type=POSITIVE,
    default=3.0,
    show_default=True,
    help="Silence (s, vehicle time) that is a telemetry loss.",
)
@click.option("--exit-when-ended", is_flag=True, help="Stop once every vehicle's intent has Ended.")
@click.option("--idle-exit", type=POSITIVE, help="Stop after this many wall-clock seconds without a message.")
def command(  # type: ignore[no-untyped-def]
    connection, intent_paths, vehicle_opts, json_lines, out_path, contingent_after_outside,
    contingent_after_loss, telemetry_timeout, exit_when_ended, idle_exit,
):  # fmt: skip
    """Follow each vehicle on CONNECTION (udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT,
    tcpin:HOST:PORT, /dev/ttyX,BAUD) and report its F3548 conformance state changes (Accepted, Activated,
    Nonconforming, Contingent, Ended) and telemetry losses."""
    from uasnav.io.operational_intent import read_intents
    from uasnav.live.conformance import ENDED, ConformanceMonitor, ContingencyRule
    from uasnav.live.stream import kernel_drops, open_connection, receive, stop_on_signals

    check_outputs(list(intent_paths), {"--out": out_path})
    intents = [it for p in intent_paths for it in read_intents(p)]
    monitor = ConformanceMonitor(
        intents,
        _vehicle_map(vehicle_opts),
        ContingencyRule(after_outside_s=contingent_after_outside, after_loss_s=contingent_after_loss),
        telemetry_timeout_s=telemetry_timeout,
    )
    conn = open_connection(connection)
    out = open(out_path, "w", encoding="utf-8") if out_path else None
    latencies: list[float] = []

    def emit(events: list[dict[str, Any]], received: float | None) -> None:
        for ev in events:
            if received is not None:
                ev["latency_ms"] = round((time.monotonic() - received) * 1e3, 3)
                latencies.append(ev["latency_ms"])
            line = json.dumps(ev, ensure_ascii=False)
            click.echo(line if json_lines else _text(ev))
            if out is not None:
                out.write(line + "\n")
                out.flush()

    def done() -> bool:
        return exit_when_ended and all(s == ENDED for s in monitor.states().values())

    queue_dropped, kernel_dropped = 0, None
    try:
        with stop_on_signals() as stop:
            queue_dropped = receive(
                conn,
                lambda msg, wall: emit(monitor.on_message(msg, wall), wall),
                lambda wall: emit(monitor.on_tick(wall), None),
                stop=stop,
                idle_timeout_s=idle_exit,
                done=done,
            )
        kernel_dropped = kernel_drops(conn)
    finally:
        if out is not None:
            out.close()
        conn.close()
    end = getattr(conn, "end", None)  # why a stream that can end (TCP) ended
    line = summary(monitor.stats, queue_dropped, kernel_dropped, latencies, ended=done(), end=end)
    click.echo(line, err=True)


def summary(
    s: Any,
    queue_dropped: int,
    kernel_dropped: int | None,
    latencies: list[float],
    *,
    ended: bool,
    end: str | None = None,
) -> str:
    """The closing line: what was received and what was lost where. Losses ``by sequence
    number`` are gaps in each sender's MAVLink sequence, so they include what the link lost
    before this receiver (a recorded tlog carries its radio link's gaps); packets dropped on this
    machine are counted apart (a full kernel receive buffer, a full queue)."""
    here = f"{queue_dropped} dropped by a full queue"
    if kernel_dropped is not None:
        here = f"{kernel_dropped} dropped by a full kernel receive buffer, {here}"
    worst = f", latency ≤ {max(latencies):.1f} ms" if latencies else ""
    stop = "; stopped once every intent had Ended" if ended else f"; {end}" if end else ""
    return (
        f"{s.messages} messages received ({here}), {s.position_reports} position reports "
        f"({s.stale_reports} duplicated/late skipped, {s.seq_lost} lost by sequence number), "
        f"{s.events} events{worst}{stop}"
    )
