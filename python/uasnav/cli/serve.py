"""``uasnav serve``: the mission planner's web application, served locally (thesis §5.2.3.2)."""

from __future__ import annotations

import ipaddress
from typing import Any

import click

from uasnav._extras import require
from uasnav.errors import InputError


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
@click.option(
    "--live",
    "live_connection",
    metavar="CONNECTION",
    help="Receive live MAVLink telemetry for the /live page on CONNECTION (udpin:HOST:PORT, "
    "udpout:HOST:PORT, tcp:HOST:PORT, tcpin:HOST:PORT, /dev/ttyX,BAUD), from the start. Without it, the "
    "UASNAV_LIVE_CONNECTION and UASNAV_LIVE_INTENTS (paths separated by the OS path separator) "
    "environment variables are used, if set.",
)
@click.option(
    "--live-intent",
    "live_intents",
    multiple=True,
    type=click.Path(dir_okay=False),
    help="Operational intent JSON flown on the --live stream; repeat for several vehicles "
    "(system 1 flies the first, 2 the second …).",
)
def command(
    host: str,
    port: int,
    db: str | None,
    regulations: str | None,
    matrices: str | None,
    allow_hosts: tuple[str, ...],
    live_connection: str | None,
    live_intents: tuple[str, ...],
) -> None:
    """Start the web application: mission selection, trajectory prediction, database pages,
    the live telemetry page (/live) and the JSON API (/api, /openapi.json), fully offline.

    The documents are loaded once, at start; requests never name a file or URL. Requests whose
    Host is not this server, or cross-site form posts, are refused (DNS rebinding, CSRF).
    """
    if live_intents and not live_connection:
        raise click.UsageError("--live-intent needs --live CONNECTION")
    if live_connection and not live_intents:
        raise click.UsageError("--live needs at least one --live-intent INTENT.json")
    require("web", "uasnav serve")
    import uvicorn

    from uasnav.web.app import create_app, load_documents
    from uasnav.web.security import LOOPBACK_HOSTS
    from uasnav.web.server_limits import harden, uvicorn_settings

    settings = uvicorn_settings()  # invalid deadlines in the environment: refused first
    addr = _address(host, port)
    docs = load_documents(db, matrices, regulations)
    _check_bindable(host, port, addr)
    if live_connection:
        from uasnav.web.live import configure

        configure(live_connection, list(live_intents))
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
    uvicorn.run(
        harden(create_app(docs, extra)),
        host=host,
        port=port,
        log_level="warning",
        server_header=False,
        **settings,
    )


def _address(host: str, port: int) -> tuple[int, int, int, Any]:
    """``(family, type, proto, sockaddr)`` of ``host``; one-line error for a name or address
    that does not resolve (``256.256.256.256``), before anything is loaded."""
    import socket

    try:
        infos = socket.getaddrinfo(host.strip("[]"), port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
    except (OSError, UnicodeError) as e:
        raise InputError(f"--host {host}: not an address this machine can bind ({e})") from None
    family, kind, proto, _, sockaddr = infos[0]
    return family, kind, proto, sockaddr


def _check_bindable(host: str, port: int, addr: tuple[int, int, int, Any]) -> None:
    """Refuse, in one line, an address this machine does not have or a port that is taken
    (uvicorn would log a multi-line failure and exit 3)."""
    import socket

    family, kind, proto, sockaddr = addr
    with socket.socket(family, kind, proto) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind(sockaddr)
        except OSError as e:
            raise InputError(f"--host {host} --port {port}: cannot bind ({e.strerror or e})") from None
