"""``uasnav report``: run the thesis experiments and write the HTML report (the main job)."""

from __future__ import annotations

import click

from uasnav.cli._common import SEED, OutputPath, echo_json


@click.command("report")
@click.option(
    "--out",
    "out_dir",
    default="build/report",
    show_default=True,
    type=OutputPath(file_okay=False, dir_okay=True),
    help="Output folder.",
)
@click.option("--seed", type=SEED, default=2024, show_default=True, help="Seed of every simulation.")
@click.option("--quick", is_flag=True, help="Smaller experiments (seconds instead of minutes).")
@click.option("--only", default=None, help="Comma-separated section keys to run.")
@click.option("--json", "as_json", is_flag=True, help="Print the report's numbers as JSON.")
def command(out_dir: str, seed: int, quick: bool, only: str | None, as_json: bool) -> None:
    """Reproduce the thesis' experiments on embedded, simulated data and write
    OUT/report.html (self-contained, with figures) and OUT/report.json."""
    from uasnav.report import build_report

    keys = [k.strip() for k in only.split(",") if k.strip()] if only is not None else None
    if keys == []:  # `--only ""` or `--only ,` would silently run every section
        raise click.BadParameter("no section key given", param_hint="'--only'")
    res = build_report(out_dir, seed=seed, quick=quick, only=keys, progress=lambda m: click.echo(m, err=True))
    if as_json:
        echo_json({"html": str(res.html_path), "json": str(res.json_path), "sections": res.data})
    else:
        click.echo(f"report written to {res.html_path}")


# The report writes its own files as one output set (`build_report`), and its experiments write
# scratch files (the simulated fleet in a temporary folder) that they read back within the run:
# those must not be staged by the command-level output set.
command.incremental_outputs = True  # type: ignore[attr-defined]
