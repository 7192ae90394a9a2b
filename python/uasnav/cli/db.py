"""``uasnav db``: the mission selector's XML databases."""

from __future__ import annotations

import click

from uasnav.cli._common import POSITIVE, echo_json


@click.group("db")
def command() -> None:
    """Inspect and validate the mission selector's XML databases."""


@command.command("validate")
@click.argument("source")
@click.option(
    "--timeout",
    type=POSITIVE,
    default=10.0,
    show_default=True,
    help="Time limit (s) for a URL, in total: connect, headers, body.",
)
@click.option(
    "--max-bytes",
    type=click.IntRange(1),
    default=8 * 1024 * 1024,
    show_default=True,
    help="Size limit (bytes).",
)
@click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")
def validate_cmd(source: str, timeout: float, max_bytes: int, as_json: bool) -> None:
    """Parse SOURCE (path or http(s) URL) safely and validate it against its shipped schema.

    The schema is chosen from the root element (<database>, <regulations>, <matrices>). On a
    violation the message gives the line and the schema rule; exit code 1.
    """
    from uasnav.mission.loading import load_document

    tree, where = load_document(source, None, timeout_s=timeout, max_bytes=max_bytes)
    root = tree.getroot()
    counts = {child.tag: len(child) for child in root if isinstance(child.tag, str)}
    if as_json:
        echo_json({"source": where, "kind": root.tag, "valid": True, "counts": counts})
        return
    detail = ", ".join(f"{k}: {v}" for k, v in counts.items())
    click.echo(f"{where}: valid <{root.tag}> ({detail})")
