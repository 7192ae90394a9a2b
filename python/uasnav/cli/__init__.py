"""The ``uasnav`` command line: one click group, one module per subcommand.

Each module in this package that defines a module-level ``command`` (a ``click.Command`` or
``click.Group``) is registered automatically, so a capability adds its subcommand by adding a
file here and nothing else.

Exit codes: 0 success; 1 a domain error (bad input file, invalid data, numerical failure) with a
one-line ``error: …`` message on stderr; 2 a usage error (unknown option, missing argument),
as click does.
"""

from __future__ import annotations

import importlib
import pkgutil
import sys
from typing import Any

import click

from uasnav import __version__
from uasnav.errors import UasnavError


class _Group(click.Group):
    """Turns uasnav's domain errors into one line on stderr and exit code 1."""

    def invoke(self, ctx: click.Context) -> Any:
        try:
            return super().invoke(ctx)
        except UasnavError as e:
            click.echo(f"error: {e}", err=True)
            ctx.exit(1)
        except OSError as e:
            click.echo(f"error: {e.strerror or e}: {e.filename or ''}".rstrip(": "), err=True)
            ctx.exit(1)


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, "--version", prog_name="uasnav")
def main() -> None:
    """Navigation and mission management for small unmanned aircraft.

    Units are SI (s, rad/s, m/s², °C) and frames NED / body (x fwd, y right, z down) unless an
    option says otherwise. Every subcommand takes --help; most take --json.
    """


def _register() -> None:
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        mod = importlib.import_module(f"{__name__}.{info.name}")
        cmd = getattr(mod, "command", None)
        if isinstance(cmd, click.Command):
            main.add_command(cmd)


_register()


def run() -> None:  # pragma: no cover - console entry point alias
    sys.exit(main())


__all__ = ["main"]
