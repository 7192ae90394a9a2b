"""The ``uasnav`` group imports a subcommand's module only when that command runs: ``--help``
lists every command from :data:`uasnav.cli.SUBCOMMANDS` with click's own one-line summaries,
and a cold command pays only for the libraries it uses."""

from __future__ import annotations

import json
import pkgutil
import subprocess
import sys

import click
import pytest
from click.testing import CliRunner

import uasnav.cli as cli
from uasnav.cli import SUBCOMMANDS, main

#: Libraries a command listing must never load (each costs 0.3–3 s of a cold start).
HEAVY = ("sklearn", "dask", "distributed", "fastapi", "scipy", "pandas", "matplotlib")


def _modules_after(argv: list[str]) -> dict[str, list[str]]:
    """The top-level packages and ``uasnav.cli.*`` modules loaded by ``uasnav ARGV`` in a fresh
    interpreter, and its exit code."""
    code = (
        "import json, sys\n"
        "from uasnav.cli import main\n"
        "rc = None\n"
        "try:\n"
        f"    main({argv!r})\n"
        "except SystemExit as e:\n"
        "    rc = e.code\n"
        "mods = sorted(sys.modules)\n"
        "top = sorted({m.split('.')[0] for m in mods})\n"
        "cli = [m for m in mods if m.startswith('uasnav.cli.')]\n"
        "sys.__stderr__.write('MODULES ' + json.dumps({'rc': rc, 'top': top, 'cli': cli}) + '\\n')\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=False
    )
    line = next(x for x in proc.stderr.splitlines() if x.startswith("MODULES "))
    return json.loads(line.removeprefix("MODULES "))


def test_help_imports_no_subcommand_and_no_heavy_library() -> None:
    got = _modules_after(["--help"])
    assert got["rc"] == 0
    assert not set(HEAVY) & set(got["top"]), set(HEAVY) & set(got["top"])
    # only the CLI's shared helpers, never a command module
    assert [m for m in got["cli"] if not m.startswith("uasnav.cli._")] == []


def test_a_command_imports_its_own_module_only() -> None:
    got = _modules_after(["plan", "--help"])
    assert got["rc"] == 0
    commands = {m for m in got["cli"] if not m.startswith("uasnav.cli._")}
    # plan shares the selector's options
    assert commands == {"uasnav.cli.plan", "uasnav.cli.select"}
    assert not {"sklearn", "dask", "fastapi"} & set(got["top"])


def test_plan_run_loads_no_learning_cluster_or_web_library(tmp_path) -> None:
    area = tmp_path / "field.geojson"
    # 70 m × 70 m beside (45°, 9°)
    area.write_text(
        json.dumps(
            {
                "type": "Polygon",
                "coordinates": [
                    [
                        [9.0001, 45.0001],
                        [9.001, 45.0001],
                        [9.001, 45.0007],
                        [9.0001, 45.0007],
                        [9.0001, 45.0001],
                    ]
                ],
            }
        )
    )
    argv = ["plan", "--area", str(area), "--resolution", "0.05", "--start", "2026-05-01T10:00:00Z"]
    got = _modules_after([*argv, "--out", str(tmp_path / "out")])
    assert got["rc"] in (0, None)
    assert (tmp_path / "out" / "result.json").is_file()
    assert not {"sklearn", "dask", "distributed", "fastapi", "pandas", "matplotlib"} & set(got["top"])


def test_table_names_every_command_module_with_its_help() -> None:
    modules = {m.name for m in pkgutil.iter_modules(cli.__path__) if not m.name.startswith("_")}
    assert {mod.rpartition(".")[2] for mod, _ in SUBCOMMANDS.values()} == modules
    for name, (module, summary) in SUBCOMMANDS.items():
        cmd = main.commands[name]
        assert cmd.name == name and cmd.callback is not None
        assert sys.modules[module].command is cmd
        first = (cmd.help or "").split("\n\n")[0]
        assert " ".join(first.split()) == summary, name


@pytest.mark.parametrize("width", [50, 80, 200])
def test_lazy_listing_is_clicks_own_at_any_width(width: int) -> None:
    # click's listing built from the imported commands, against the one built from the table
    loaded = click.Group("uasnav", commands={n: main.commands[n] for n in SUBCOMMANDS})
    lazy = cli._Group("uasnav", lazy_subcommands=SUBCOMMANDS)
    for group in (loaded, lazy):
        ctx = click.Context(group, terminal_width=width, max_content_width=width)
        formatter = ctx.make_formatter()
        group.format_commands(ctx, formatter)
        group.listing = formatter.getvalue()  # type: ignore[attr-defined]
    assert lazy.listing == loaded.listing  # type: ignore[attr-defined]
    assert lazy.commands.is_loaded("plan") is False  # type: ignore[attr-defined]
    assert all(f"  {n} " in lazy.listing for n in SUBCOMMANDS)  # type: ignore[attr-defined]


def test_loaded_commands_are_guarded_and_unknown_names_are_usage_errors() -> None:
    # the wrapper that checks inputs and stages outputs is applied on load, once
    cmd = main.commands["select"]
    assert getattr(cmd.callback, "__wrapped__", None) is not None
    assert main.commands["select"] is cmd
    assert "nosuch" not in main.commands and main.commands.get("nosuch") is None
    r = CliRunner().invoke(main, ["nosuch"])
    assert r.exit_code == 2 and "No such command 'nosuch'" in r.output
