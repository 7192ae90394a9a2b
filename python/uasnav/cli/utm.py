"""``uasnav utm``: strategic deconfliction of ASTM F3548 operational intents."""

from __future__ import annotations

from datetime import datetime, timezone
from pathlib import Path

import click

from uasnav.cli._common import BUFFER_M, NON_NEGATIVE, echo_json
from uasnav.errors import InputError

#: Years a flight time may take (the POSIX epoch to far beyond any flight plan).
FIRST_YEAR, LAST_YEAR = 1970, 9000


def parse_time(text: str, option: str) -> datetime:
    """An ISO 8601 time with a zone (``2026-05-01T09:30:00Z``) → aware datetime (UTC)."""
    try:
        t = datetime.fromisoformat(text.strip().replace("Z", "+00:00").replace("z", "+00:00"))
    except ValueError:
        raise InputError(
            f"{option}: expected an ISO 8601 time such as 2026-05-01T09:30:00Z, got {text!r}"
        ) from None
    if t.tzinfo is None:
        raise InputError(f"{option}: {text!r} has no time zone (add Z for UTC)")
    if not FIRST_YEAR <= t.year <= LAST_YEAR:
        # a flight's times, its delays and the intent's 30-day window must stay representable
        raise InputError(f"{option}: {text!r} is outside the years {FIRST_YEAR}–{LAST_YEAR}")
    return t.astimezone(timezone.utc)


@click.group("utm")
def command() -> None:
    """UTM: deconfliction of ASTM F3548 operational intents."""


@command.command("deconflict")
@click.argument("intents", nargs=-1, required=True, type=click.Path(dir_okay=False))
@click.option(
    "--now",
    "now_text",
    help="Evaluation time (ISO 8601, default the current UTC time): F3548 intents may not end "
    "before it nor start more than 30 days after it; InterUSS template offsets count from it.",
)
@click.option(
    "--horizontal-buffer",
    type=BUFFER_M,
    default=0.0,
    show_default=True,
    help="Report near misses closer than this horizontally (m).",
)
@click.option(
    "--vertical-buffer",
    type=BUFFER_M,
    default=0.0,
    show_default=True,
    help="… and closer than this vertically (m).",
)
@click.option(
    "--max-delay",
    type=NON_NEGATIVE,
    default=86_400.0,
    show_default=True,
    help="Longest departure delay searched (s).",
)
@click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")
def deconflict(intents, now_text, horizontal_buffer, vertical_buffer, max_delay, as_json):  # type: ignore[no-untyped-def]
    """Every pair of INTENTS (F3548 JSON files, or InterUSS flight-intent YAML collections)
    whose volumes intersect in space and time, the overlap interval, and the smallest departure
    delay of the later intent that frees it of conflict with every other intent.

    Exit code 0 whether or not there are conflicts (see "conflicts" in the output).
    """
    from uasnav.io.interuss import read_flight_intents
    from uasnav.io.operational_intent import check_times, read_intents
    from uasnav.utm.deconflict import deconflict as run

    now = parse_time(now_text, "--now") if now_text else datetime.now(timezone.utc)
    found = []
    for path in intents:
        if Path(path).suffix.lower() in (".yaml", ".yml"):
            found += read_flight_intents(path, now)
        else:
            found += read_intents(path)
    for it in found:
        check_times(it, now)
    res = run(found, horizontal_buffer, vertical_buffer, max_delay)
    if as_json:
        echo_json(
            {
                "n_intents": res.n_intents,
                "n_volumes": res.n_volumes,
                "conflicts": [
                    {
                        "intents": list(c.intents),
                        "volumes": [list(p) for p in c.volumes],
                        "overlap_start": c.overlap[0].isoformat(),
                        "overlap_end": c.overlap[1].isoformat(),
                        "min_separation_m": 0.0,
                        "later": c.later,
                        "delay_s": c.delay_s,
                    }
                    for c in res.conflicts
                ],
                "near_misses": [
                    {
                        "intents": list(m.intents),
                        "volumes": [list(p) for p in m.volumes],
                        "horizontal_m": m.horizontal_m,
                        "vertical_m": m.vertical_m,
                    }
                    for m in res.near_misses
                ],
            }
        )
        return
    click.echo(f"{res.n_intents} intents, {res.n_volumes} volumes: {len(res.conflicts)} conflict(s)")
    for c in res.conflicts:
        delay = (
            "no delay within --max-delay frees it"
            if c.delay_s is None
            else f"delay {c.later} by {c.delay_s:.0f} s"
        )
        click.echo(
            f"  {c.intents[0]} × {c.intents[1]}: {len(c.volumes)} volume pair(s), "
            f"{c.overlap[0]:%Y-%m-%dT%H:%M:%SZ} – {c.overlap[1]:%H:%M:%SZ}; {delay}"
        )
    if horizontal_buffer or vertical_buffer:
        click.echo(f"{len(res.near_misses)} near miss(es)")
        for m in res.near_misses:
            click.echo(
                f"  {m.intents[0]} × {m.intents[1]}: {m.horizontal_m:.1f} m horizontally, "
                f"{m.vertical_m:.1f} m vertically"
            )
