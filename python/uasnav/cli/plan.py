"""``uasnav plan``: from a field to a filed authorisation (selection → survey → times → intents
→ zones and deconfliction → authorisation summary)."""

from __future__ import annotations

from typing import Any

import click

from uasnav.cli._common import OutputPath, Real, echo_json
from uasnav.cli.select import _USAGE_KINDS, _options
from uasnav.errors import InputError
from uasnav.mission.planner import PLAN_OPTIONS
from uasnav.mission.readable import metres
from uasnav.mission.request import SELECT_OPTIONS, OptionError, read_file_option


@click.command("plan")
@_options
@click.option("--overlap", default="75,65", show_default=True, help=PLAN_OPTIONS["overlap"])
@click.option(
    "--intents",
    "intents",
    multiple=True,
    type=click.Path(dir_okay=False),
    help=PLAN_OPTIONS["intents"] + " Repeat for several files.",
)
@click.option("--start", "start", help=PLAN_OPTIONS["start"] + " Default: the next full hour.")
@click.option(
    "--turnaround", type=Real(0.0, 86400.0), default=600.0, show_default=True, help=PLAN_OPTIONS["turnaround"]
)
@click.option(
    "--out",
    "out",
    required=True,
    type=OutputPath(dir_okay=True, file_okay=False),
    help="Directory to write the plan's files into (created if missing).",
)
@click.option("--json", "as_json", is_flag=True, help="Print result.json.")
def command(
    overlap: str,
    intents: tuple[str, ...],
    start: str | None,
    turnaround: float,
    out: str,
    as_json: bool,
    **options: Any,
) -> None:
    """Plan the survey of an --area and everything its authorisation needs.

    Ranks UAS + camera for the area, lays boustrophedon lines at the height that gives
    --resolution (or --altitude if lower), with camera triggers per line and the speed the
    camera allows, split into flights within the UAS's endurance; predicts each flight's time
    with bounds, writes one F3548 intent per flight, checks the ED-269 --zones over the
    predicted window and deconflicts against --intents. Writes flight-NN.plan (QGroundControl),
    flight-NN.waypoints (Mission Planner), flight-NN.intent.json, summary.html, summary.json and
    result.json into --out, all or nothing. When no UAS/camera can fly it (none meets the
    requirements, or a PROHIBITED zone covers the area over the flight's window) it exits
    with one error line giving the verdict and writes nothing.
    """
    from uasnav.mission.planner import plan, write_outputs

    for o in SELECT_OPTIONS:
        if o.kind in ("source", "output"):
            if options.pop(o.name, None) is not None:
                raise click.BadParameter("not used by plan", param_hint=f"'{o.flag}'")
    if options.get("area") is None:
        raise click.BadParameter("give the field to survey (GeoJSON, KML or a plan)", param_hint="'--area'")
    if start is not None and options.get("flight_time") is not None:
        raise click.BadParameter("give --start only (it is the take-off time)", param_hint="'--flight-time'")
    explicit = {k: v for k, v in options.items() if v is not None}
    # the selector's defaults are filled by the request parser; plan needs to know what was typed
    ctx = click.get_current_context()
    for name in list(explicit):
        src = ctx.get_parameter_source(name)
        if src is not None and src.name == "DEFAULT":
            del explicit[name]
    try:
        for o in SELECT_OPTIONS:
            if o.kind == "file" and explicit.get(o.name) is not None:
                explicit[o.name] = read_file_option(o.name, explicit[o.name])
        res = plan(explicit, overlap=overlap, intents=list(intents), start=start, turnaround=turnaround)
    except OptionError as e:
        opt = next((o for o in SELECT_OPTIONS if o.name == e.option), None)
        if e.option in ("overlap", "start", "turnaround"):
            raise click.BadParameter(str(e), param_hint=f"'--{e.option}'") from None
        if opt is None or opt.kind not in _USAGE_KINDS:
            raise
        raise click.BadParameter(str(e), param_hint=f"'{opt.flag}'") from None
    r = res.result
    auth = r["authorisation"]
    if r["survey"] is None:
        # nothing ranks: no flight to write; the verdict says why (no UAS/camera meets the
        # requirements, or a zone forbids the area over the flight's window)
        raise InputError(f"no survey plan for {options['area']}: {auth['verdict']}")
    written = write_outputs(res, out)
    g = r["ground"]
    if as_json:
        echo_json(res.result)
        _warn_assumed_ground(g)
        return
    c, s, op = r["configuration"], r["survey"], r["operation"]
    d = r.get("distances") or {}
    click.echo(f"Configuration: {c['uas']} + {c['camera']} (score {c['score']:.2f})")
    if op:
        click.echo(
            f"Operation: {op['visibility']}, {op['category']}; the pilot ({d.get('pilot_from')}) is "
            f"{metres(d.get('pilot_distance_m', 0))} from the farthest point of "
            f"{d.get('pilot_distance_on', 'the area')}"
        )
    click.echo(f"Survey: {s['altitude_m']:.1f} m {s['altitude_datum']} — {s['height_reason']}")
    click.echo(
        f"Ground at take-off: {g['elevation_m']:.1f} m {g['datum']} ({g['source']}); geoid height "
        f"{g['geoid_height_m']:.1f} m ({g['geoid']}), so {g['ellipsoidal_height_m']:.1f} m WGS-84"
    )
    click.echo(
        f"  {s['gsd_m'] * 100:.2f} cm/px, {s['lines']} lines, {s['photos']} photos, {s['length_m']:.0f} m, "
        f"{s['flights']} flight(s), {s['speed_ms']:.1f} m/s ({s['speed_reason']})"
    )
    for f in r["flights"]:
        click.echo(
            f"  {f['name']}: take-off {f['start']}, {f['eta_s']:.0f} s "
            f"({f['eta_bounds_s'][0]:.0f}–{f['eta_bounds_s'][1]:.0f} s at {r['eta_s']['coverage']:.0%}), "
            f"{f['photos']} photos"
        )
    if r["zones"] is not None:
        z = r["zones"]
        click.echo(f"Zones: {len(z.get('hits', []))} entered")
    for k in r["conflicts"]:
        click.echo(
            f"Conflict: {k['flight']} with {k['intent']} {k['overlap_start']} – {k['overlap_end']}: "
            f"{k['resolution']}"
        )
    click.echo(f"Verdict: {auth['verdict']}")
    for n in auth["requirements"]:
        click.echo(f"  requires: {n}")
    for a in s["assumptions"]:
        click.echo(f"  assumption: {a}")
    click.echo(f"wrote {len(written)} files to {out}")
    _warn_assumed_ground(g)


def _warn_assumed_ground(g: dict[str, Any]) -> None:
    """One warning line when the intents' heights stand on an assumed ground elevation."""
    if g["assumed"]:
        click.echo(
            f"warning: the intents' WGS-84 altitudes assume the take-off ground at {g['elevation_m']:g} m "
            f"AMSL ({g['source'].removeprefix('assumed: ')}): give --ground-elevation (m AMSL) before "
            "filing them",
            err=True,
        )
