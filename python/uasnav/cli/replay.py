"""``uasnav replay``: send a recorded flight as a live MAVLink stream."""

from __future__ import annotations

import click

from uasnav.cli._common import POSITIVE, SEED, Real


@click.command("replay")
@click.argument("log", type=click.Path(dir_okay=False))
@click.option(
    "--to",
    "target",
    required=True,
    help="Where to send: udp:HOST:PORT (or udpout:HOST:PORT) as datagrams; tcp:HOST:PORT to a "
    "listening receiver (retried until it listens, 30 s at most); tcpin:HOST:PORT to the first "
    "receiver that connects (waits 30 s at most); /dev/ttyX,BAUD to a serial port (a telemetry "
    "radio) at BAUD (default 57600).",
)
@click.option("--speed", type=POSITIVE, default=1.0, show_default=True, help="Times real time.")
@click.option("--loop", is_flag=True, help="Start again at the end, until interrupted.")
@click.option(
    "--offset-after",
    "offset_text",
    help="T:NORTH,EAST — from T s after the first message on, shift every reported position by "
    "NORTH, EAST metres.",
)
@click.option(
    "--offset-until", type=Real(0.0, None), help="End the --offset-after shift T s after the first message."
)
@click.option("--drop", type=Real(0.0, 1.0, hi_open=True), default=0.0, help="Fraction of packets to lose.")
@click.option(
    "--duplicate", type=Real(0.0, 1.0, hi_open=True), default=0.0, help="Fraction of packets to send twice."
)
@click.option(
    "--from",
    "start_s",
    type=Real(0.0, None),
    default=0.0,
    help="Start T s (log time) after the first message.",
)
@click.option(
    "--stop-after", type=Real(0.0, None), help="Stop sending T s (log time) after the first message."
)
@click.option("--seed", type=SEED, default=0, show_default=True, help="Seed of --drop/--duplicate.")
def command(log, target, speed, loop, offset_text, offset_until, drop, duplicate, start_s, stop_after, seed):  # type: ignore[no-untyped-def]
    """Send LOG (.tlog as recorded; .bin/.ulg converted to the MAVLink messages a ground station
    receives) over UDP, TCP or a serial port in its recorded timing, scaled by --speed."""
    from uasnav.live.replay import open_sender, parse_offset, parse_target, replay
    from uasnav.live.source import log_packets

    to = parse_target(target)
    if offset_until is not None and not offset_text:
        raise click.UsageError("--offset-until needs --offset-after")
    offset = parse_offset(offset_text, offset_until) if offset_text else None
    first = iter(log_packets(log))  # open (and check) the log before the first packet leaves
    send, sock = open_sender(to, on_wait=lambda text: click.echo(text, err=True))
    passes = [first]

    def packets():  # type: ignore[no-untyped-def]
        return passes.pop() if passes else log_packets(log)

    try:
        stats = replay(
            packets, send, speed=speed, loop=loop, offset=offset, drop=drop, duplicate=duplicate,
            start_s=start_s, stop_after_s=stop_after, seed=seed,
        )  # fmt: skip
    except KeyboardInterrupt:
        return
    finally:
        sock.close()
    click.echo(
        f"sent {stats.packets} packets ({stats.bytes} bytes, {stats.log_s:.1f} s of log at {speed:g}×; "
        f"{stats.dropped} dropped, {stats.duplicated} duplicated; "
        f"sender at most {stats.max_late_s * 1e3:.0f} ms late)",
        err=True,
    )
