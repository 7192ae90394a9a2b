"""``uasnav select``: mission selector (thesis §5.2, Figures 69–70)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import click

from uasnav.cli._common import OutputPath, Real, check_outputs, echo_json
from uasnav.mission.readable import metres
from uasnav.mission.request import (
    SELECT_OPTIONS,
    OptionError,
    SelectOption,
    parse_select_options,
    read_file_option,
)
from uasnav.mission.selection import select

#: Kinds whose bad values are usage errors (exit 2), like the typed options; the other refusals
#: (a combination the regulations cannot resolve) stay domain errors (exit 1).
_USAGE_KINDS = ("size", "pairs", "density", "mitigations", "datetime", "file", "wind", "position")


def _click_type(opt: SelectOption) -> Any:
    """The click type of a selector option: typed options are checked at parse time (exit 2)."""
    if opt.kind == "real":
        return Real(opt.minimum, opt.maximum, lo_open=opt.minimum_open)
    if opt.kind == "int":
        return click.IntRange(
            None if opt.minimum is None else int(opt.minimum),
            None if opt.maximum is None else int(opt.maximum),
        )
    if opt.kind == "choice":
        return click.Choice(opt.choices or ())
    if opt.kind == "output":
        return OutputPath()
    if opt.kind in ("wind", "position"):
        return click.STRING  # SPEED[@FROM_DEG], LAT,LON: checked by the request parser
    return None


def _options(f: Callable[..., None]) -> Callable[..., None]:
    """One click option per entry of :data:`SELECT_OPTIONS` (the web form reads the same table)."""
    for opt in reversed(SELECT_OPTIONS):
        if opt.kind == "flag":
            # A flag on by default needs its negative spelling to be switched off.
            spelling = f"{opt.flag}/--no-{opt.flag[2:]}" if opt.default else opt.flag
            f = click.option(spelling, opt.name, is_flag=True, default=bool(opt.default), help=opt.help)(f)
            continue
        f = click.option(
            opt.flag,
            opt.name,
            type=_click_type(opt),
            default=opt.default,
            show_default=opt.default is not None,
            help=opt.help,
        )(f)
    return f


@click.command("select")
@_options
@click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")
def command(as_json: bool, **options: Any) -> None:
    """Equipment, feasible UAS and cameras, and ranked UAS/camera configurations for a mission.

    Lists the equipment the mission needs (necessary marked *), the UAS and cameras passing the
    feasibility tests (wind, endurance, link range, altitude, speed, regulations, rain; imagery,
    HFOV eq. 60, ground resolution at the regulatory height; payload), the rejections with the
    failed test and the margin, and the configurations ranked by the weighted score (eq. 61,
    lower is better).
    """
    from uasnav.mission import load_database, load_matrices, load_regulations

    sources = {o.name: options.pop(o.name) for o in SELECT_OPTIONS if o.kind == "source"}
    outputs = {o.name: options.pop(o.name) for o in SELECT_OPTIONS if o.kind == "output"}
    files = [o for o in SELECT_OPTIONS if o.kind == "file" and options.get(o.name) is not None]
    summary = outputs["summary"]
    if summary is not None:
        check_outputs([options[o.name] for o in files] + list(sources.values()), {"--summary": summary})
        if not str(summary).lower().endswith((".html", ".htm", ".json")):
            raise click.BadParameter("expected a file ending in .html or .json", param_hint="'--summary'")
    try:
        for o in files:
            options[o.name] = read_file_option(o.name, options[o.name])
        request = parse_select_options(options)
    except OptionError as e:
        # A malformed value is a usage error, like the typed options; a combination the
        # regulations cannot resolve (no default category) stays a domain error (exit 1).
        opt = next((o for o in SELECT_OPTIONS if o.name == e.option), None)
        if opt is None or opt.kind not in _USAGE_KINDS:
            raise
        raise click.BadParameter(str(e), param_hint=f"'{opt.flag}'") from None
    sel = select(
        request.requirements,
        database=load_database(sources["db"]),
        matrices=load_matrices(sources["matrices"]),
        regulations=load_regulations(sources["regulations"]),
        targets=request.targets,
        weights=request.weights,
        top=request.top,
        area=request.area,
        zones=request.zones,
        zones_source=request.zones_source,
        when=request.when,
    )
    if summary is not None:
        from uasnav.mission.summary import write_summary

        write_summary(sel, summary)
    req, w = request.requirements, request.weights
    op = sel.operation
    jurisdiction, category = req.jurisdiction, op.category if op else req.category
    if as_json:
        echo_json(sel.to_dict())
        return
    click.echo(
        f"Mission: {sel.mission_name}  ({jurisdiction}/{category}, max height {sel.regulatory_height_m:g} m)"
    )
    if request.distances is not None:
        d = request.distances
        click.echo(
            f"Distances: pilot {metres(d['pilot_distance_m'])} from the farthest point of the area "
            f"(pilot at {d['pilot_from']}), range {metres(d['range_m'])} from the take-off point "
            f"({d['takeoff_from']})"
        )
    if op is not None:
        click.echo(
            f"Operation: {op.visibility}, {metres(op.max_distance_m, against=op.vlos_distance_m)} from the "
            f"pilot (in sight up to {metres(op.vlos_distance_m)}), {metres(op.height_m)} AGL, "
            f"{'urban' if op.urban else 'rural'} "
            f"({op.population}), over people: {op.over_people}, {'night' if op.night else 'day'}, "
            f"airspace {op.airspace}"
        )
        click.echo(f"  category: {op.legal_basis}")
        if len(sel.operations) > 1:
            # The operation follows from each UA's own VLOS distance: list every one implied.
            for o in sel.operations:
                best = (
                    f"best {o.best.uas} + {o.best.camera} ({o.best.score:.2f})" if o.best else "none feasible"
                )
                click.echo(
                    f"  {o.visibility}/{o.category} for {len(o.uas)} UAS "
                    f"(in sight up to {metres(o.vlos_distance_m)}): {best}"
                )
    if sel.sora is not None:
        s = sel.sora
        click.echo(
            f"SORA {s.edition} (best configuration): iGRC {s.igrc}, final GRC {s.final_grc}, "
            f"ARC-{s.initial_arc} -> ARC-{s.residual_arc}, TMPR {s.tmpr}, SAIL {s.sail or 'none (certified)'}"
        )
    for x in sel.scenarios:
        click.echo(f"  {x.id}: {'applies' if x.applies else 'no'} ({'; '.join(x.reasons)})")
    if sel.zones is not None:
        click.echo(f"Zones ({sel.zones.n_zones} read from {sel.zones.source}): {len(sel.zones.hits)} entered")
        if sel.flight_window is not None:
            fw = sel.flight_window
            click.echo(
                f"  schedules checked over {fw['start']} - {fw['end']} "
                f"({fw['duration_s']:.0f} s: {fw['from']})"
            )
    auth = sel.authorisation
    click.echo(f"Verdict: {auth['verdict']}")
    for n in auth["requirements"]:
        click.echo(f"  requires: {n}")
    for n in sel.notes:
        click.echo(f"  note: {n}")
    click.echo("\nEquipment (* necessary):")
    for group in ("navigation", "data-link", "situational-awareness", "decision-making"):
        items = [e for e in sel.equipment if e.group == group]
        if items:
            click.echo(f"  {group}: " + "; ".join(("* " if e.necessary else "") + e.name for e in items))
    for e in sel.equipment:
        if e.necessary:
            click.echo(f"    * {e.name}: {e.reason}")
    click.echo(f"\nFeasible UAS ({len(sel.feasible_uas)}): " + ", ".join(sel.feasible_uas))
    rule = "planned height" if req.camera_height == "planned" else "regulatory maximum height"
    click.echo(
        f"Feasible cameras ({len(sel.feasible_cameras)}, HFOV >= {sel.required_hfov_deg:.1f} deg and "
        f"<= {req.resolution_m:g} m/px at {sel.camera_height_m:g} m, the {rule}): "
        + ", ".join(sel.feasible_cameras)
    )
    click.echo(f"\nRejections ({len(sel.rejections)}):")
    for r in sel.rejections:
        click.echo(f"  - {r.message}")
    click.echo(
        f"\nRanked configurations (weights range {w.range:g}, weight {w.weight:g}, cost {w.cost:g}, "
        f"resolution {w.resolution:g}; lower is better):"
    )
    click.echo(
        f"  {'#':>2} {'UAS':<30} {'camera':<26} {'score':>6} {'mass g':>7} {'cost $':>7}  open  operation"
    )
    for rank_no, pair in enumerate(sel.ranking, 1):
        click.echo(
            f"  {rank_no:>2} {pair.uas:<30} {pair.camera:<26} {pair.score:6.2f} {pair.mass_g:7.0f}"
            f" {pair.cost_usd:7.0f}  {pair.open_subcategory or '-':<4}  {pair.visibility}/{pair.category}"
        )
    if sel.ranking:
        from uasnav.mission.scoring import explain

        click.echo("  scores:")
        for line in explain(sel.targets or request.targets, w):
            click.echo(f"    {line}")
    if not sel.ranking and sel.withheld:
        click.echo("  (none flyable: the area enters a PROHIBITED zone)")
        click.echo("\nWithheld — would rank only if the zone authority exempted the flight:")
        for rank_no, pair in enumerate(sel.withheld, 1):
            click.echo(f"  {rank_no:>2} {pair.uas:<30} {pair.camera:<26} {pair.score:6.2f}")
    elif not sel.ranking:
        click.echo("  (no feasible configuration)")
    if summary is not None:
        click.echo(f"\nAuthorisation summary written to {summary}")
