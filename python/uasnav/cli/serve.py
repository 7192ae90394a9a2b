"""``uasnav serve``: the mission planner's web application, served locally (thesis §5.2.3.2)."""

from __future__ import annotations

import ipaddress

import click

from uasnav.web.security import LOOPBACK_HOSTS


def is_loopback(host: str) -> bool:
    """Whether ``host`` binds to loopback only (127.0.0.0/8, ::1, localhost)."""
    if host.strip().lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


@click.command("serve")
@click.option("--host", default="127.0.0.1", show_default=True, help="Address to bind (loopback by default).")
@click.option("--port", type=click.IntRange(1, 65535), default=8000, show_default=True, help="TCP port.")
@click.option("--db", help="UAS/camera database: path or http(s) URL (default: the shipped copy).")
@click.option("--regulations", help="Regulations database: path or URL (default: the shipped copy).")
@click.option("--matrices", help="Compliance matrices: path or URL (default: the shipped copy).")
@click.option(
    "--allow-host",
    "allow_hosts",
    multiple=True,
    help="Further Host name the server answers to (repeatable; the loopback names always are).",
)
def command(
    host: str,
    port: int,
    db: str | None,
    regulations: str | None,
    matrices: str | None,
    allow_hosts: tuple[str, ...],
) -> None:
    """Start the web application: mission selection, trajectory prediction, database pages and
    the JSON API (/api, /openapi.json), fully offline.

    The documents are loaded once, at start; requests never name a file or URL. Requests whose
    Host is not this server, or cross-site form posts, are refused (DNS rebinding, CSRF).
    """
    import uvicorn

    from uasnav.web.app import create_app, load_documents

    docs = load_documents(db, matrices, regulations)
    extra = tuple(allow_hosts)
    if host.strip("[]").lower() not in LOOPBACK_HOSTS and host not in ("0.0.0.0", "::"):
        extra += (host.strip("[]"),)
    if not is_loopback(host):
        bar = "!" * 78
        click.echo(
            f"{bar}\nwarning: uasnav serve is bound to {host}, not loopback: anyone who can reach this "
            f"machine on port {port} can use it (no authentication). Bind to 127.0.0.1 unless you "
            f"mean it.\n{bar}",
            err=True,
        )
    shown = f"[{host}]" if ":" in host else host
    click.echo(f"uasnav serve: http://{shown}:{port}/  (Ctrl-C to stop)", err=True)
    uvicorn.run(create_app(docs, extra), host=host, port=port, log_level="warning", server_header=False)
