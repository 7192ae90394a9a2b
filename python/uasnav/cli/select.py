"""``uasnav select``: mission selector (thesis §5.2, Figures 69–70)."""

from __future__ import annotations

import math

import click

from uasnav.cli._common import NON_NEGATIVE, POSITIVE, echo_json

_PARAMS = ("range", "weight", "cost", "resolution")


def _parse_size(text: str) -> tuple[float, float]:
    parts = text.lower().replace("×", "x").split("x")
    try:
        if len(parts) != 2:
            raise ValueError
        size = (float(parts[0]), float(parts[1]))
    except ValueError:
        raise click.BadParameter(
            f"expected LENGTHxWIDTH in metres (e.g. 70x70), got {text!r}", param_hint="'--image-size'"
        ) from None
    if not all(math.isfinite(v) and v > 0 for v in size):
        raise click.BadParameter(
            f"expected a finite LENGTHxWIDTH > 0 in metres, got {text!r}", param_hint="'--image-size'"
        )
    return size


def _parse_pairs(text: str, what: str, allowed: tuple[str, ...]) -> dict[str, str]:
    out = {}
    for item in text.split(","):
        if not item.strip():
            continue
        key, sep, val = item.partition("=")
        key = key.strip()
        if not sep or key not in allowed:
            raise click.BadParameter(
                f"{what}: expected NAME=VALUE with NAME in {', '.join(allowed)}, got {item!r}"
            )
        out[key] = val.strip()
    return out


@click.command("select")
@click.option("--mission", default="precision-agriculture", show_default=True, help="Mission id (Table 18).")
@click.option(
    "--range", "range_m", type=POSITIVE, default=1500.0, show_default=True, help="Mission range (m)."
)
@click.option(
    "--resolution", type=POSITIVE, default=0.05, show_default=True, help="Ground resolution (m/px)."
)
@click.option("--image-size", default="70x70", show_default=True, help="Target size LENGTHxWIDTH (m).")
@click.option("--altitude", type=POSITIVE, default=50.0, show_default=True, help="Flight altitude AGL (m).")
@click.option("--imagery", default="multispectral", show_default=True, help="Camera type, or 'any'.")
@click.option("--wind", type=NON_NEGATIVE, default=5.0, show_default=True, help="Wind speed (m/s).")
@click.option("--rain", is_flag=True, help="The flight must be possible in rain.")
@click.option(
    "--speed", type=NON_NEGATIVE, default=None, help="Required ground speed against the wind (m/s)."
)
@click.option(
    "--order-by",
    type=click.Choice(_PARAMS),
    default="cost",
    show_default=True,
    help="Most important parameter: its weight is 1.25 (eq. 61 with cost first).",
)
@click.option(
    "--weights", default=None, help="Explicit weights, e.g. range=1,weight=0.75,cost=1.25,resolution=1."
)
@click.option(
    "--targets",
    default=None,
    help="TARGET:LIMIT per parameter, e.g. range=5000:1500,weight=800:1600,cost=4000:7000,"
    "resolution=0.01:0.06.",
)
@click.option("--jurisdiction", default="easa", show_default=True, help="Regulations: easa | faa.")
@click.option("--category", default=None, help="Category (default: open for easa, part107 for faa).")
@click.option("--db", "db", default=None, help="UAS/camera database: path or http(s) URL.")
@click.option("--regulations", "regs", default=None, help="Regulations database: path or URL.")
@click.option("--matrices", default=None, help="Compliance matrices: path or URL.")
@click.option(
    "--top", type=click.IntRange(1, 1000), default=10, show_default=True, help="Configurations listed."
)
@click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")
def command(
    mission: str,
    range_m: float,
    resolution: float,
    image_size: str,
    altitude: float,
    imagery: str,
    wind: float,
    rain: bool,
    speed: float | None,
    order_by: str,
    weights: str | None,
    targets: str | None,
    jurisdiction: str,
    category: str | None,
    db: str | None,
    regs: str | None,
    matrices: str | None,
    top: int,
    as_json: bool,
) -> None:
    """Equipment, feasible UAS and cameras, and ranked UAS/camera configurations for a mission.

    Lists the equipment the mission needs (necessary marked *), the UAS and cameras passing the
    feasibility tests (wind, endurance, link range, altitude, speed, regulations, rain; imagery,
    HFOV eq. 60, ground resolution at the regulatory height; payload), the rejections with the
    failed test and the margin, and the configurations ranked by the weighted score (eq. 61,
    lower is better).
    """
    from uasnav.errors import InputError
    from uasnav.mission import (
        Requirements,
        Targets,
        Weights,
        load_database,
        load_matrices,
        load_regulations,
        select,
    )
    from uasnav.mission.regulations import DEFAULT_CATEGORY

    size = _parse_size(image_size)
    if weights:
        vals = _parse_pairs(weights, "--weights", _PARAMS)
        try:
            w = Weights(**{**Weights.order_by(order_by).__dict__, **{k: float(v) for k, v in vals.items()}})
        except ValueError:
            raise click.BadParameter(f"--weights: not numbers in {weights!r}") from None
        ws = [w.range, w.weight, w.cost, w.resolution]
        # Negative or all-zero weights would rank every configuration the same (or backwards)
        # and still print a ranking.
        if not all(math.isfinite(x) and x >= 0 for x in ws) or not any(x > 0 for x in ws):
            raise click.BadParameter(
                f"--weights: expected finite weights >= 0, at least one > 0, got {weights!r}"
            )
    else:
        w = Weights.order_by(order_by)
    t = Targets()
    if targets:
        names = {"range": "range_m", "weight": "weight_g", "cost": "cost_usd", "resolution": "resolution_deg"}
        kw = {}
        for k, v in _parse_pairs(targets, "--targets", _PARAMS).items():
            a, sep, b = v.partition(":")
            try:
                kw[names[k]] = (float(a), float(b))
            except ValueError:
                raise click.BadParameter(f"--targets: {k}={v!r} is not TARGET:LIMIT") from None
            if not sep or not all(math.isfinite(x) for x in kw[names[k]]) or a.strip() == b.strip():
                raise click.BadParameter(f"--targets: {k}={v!r} is not TARGET:LIMIT")
        t = Targets(**{**t.__dict__, **kw})
    if category is None:
        category = DEFAULT_CATEGORY.get(jurisdiction)
        if category is None:
            raise InputError(f"--jurisdiction {jurisdiction!r}: give --category too")
    req = Requirements(
        mission=mission,
        range_m=range_m,
        resolution_m=resolution,
        image_size_m=size,
        altitude_m=altitude,
        imagery=None if imagery == "any" else imagery,
        wind_ms=wind,
        rain=rain,
        speed_ms=speed,
        jurisdiction=jurisdiction,
        category=category,
    )
    sel = select(
        req,
        database=load_database(db),
        matrices=load_matrices(matrices),
        regulations=load_regulations(regs),
        targets=t,
        weights=w,
        top=top,
    )
    if as_json:
        echo_json(sel.to_dict())
        return
    click.echo(
        f"Mission: {sel.mission_name}  ({jurisdiction}/{category}, max height {sel.regulatory_height_m:g} m)"
    )
    for n in sel.notes:
        click.echo(f"  note: {n}")
    click.echo("\nEquipment (* necessary):")
    for group in ("navigation", "data-link", "situational-awareness", "decision-making"):
        items = [e for e in sel.equipment if e.group == group]
        if items:
            click.echo(f"  {group}: " + "; ".join(("* " if e.necessary else "") + e.name for e in items))
    click.echo(f"\nFeasible UAS ({len(sel.feasible_uas)}): " + ", ".join(sel.feasible_uas))
    click.echo(
        f"Feasible cameras ({len(sel.feasible_cameras)}, HFOV >= {sel.required_hfov_deg:.1f} deg): "
        + ", ".join(sel.feasible_cameras)
    )
    click.echo(f"\nRejections ({len(sel.rejections)}):")
    for r in sel.rejections:
        click.echo(f"  - {r.message}")
    click.echo(
        f"\nRanked configurations (weights range {w.range:g}, weight {w.weight:g}, cost {w.cost:g}, "
        f"resolution {w.resolution:g}; lower is better):"
    )
    click.echo(f"  {'#':>2} {'UAS':<30} {'camera':<26} {'score':>6} {'mass g':>7} {'cost $':>7}  open")
    for rank_no, pair in enumerate(sel.ranking, 1):
        click.echo(
            f"  {rank_no:>2} {pair.uas:<30} {pair.camera:<26} {pair.score:6.2f} {pair.mass_g:7.0f}"
            f" {pair.cost_usd:7.0f}  {pair.open_subcategory or '-'}"
        )
    if not sel.ranking:
        click.echo("  (no feasible configuration)")
