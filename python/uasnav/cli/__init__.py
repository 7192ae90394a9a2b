"""The ``uasnav`` command line: one click group, one module per subcommand.

Each subcommand is a module in this package that defines a module-level ``command`` (a
``click.Command`` or ``click.Group``), named with the first paragraph of its help in
:data:`SUBCOMMANDS`. A module is imported only when its command runs (or shows its own
``--help``): ``uasnav --help`` lists every command from the table and imports none of them, so
the start-up of one command does not pay for the libraries of all the others.

Exit codes: 0 success; 1 a domain error (bad input file, invalid data, numerical failure) with a
one-line ``error: …`` message on stderr; 2 a usage error (unknown option, missing argument, an
option value outside its domain), as click does. An unexpected exception (a bug) is also one line,
``error: internal error: …, please report it``, exit code 1; ``UASNAV_DEBUG=1`` shows its traceback.
"""

from __future__ import annotations

import functools
import importlib
import os
import sys
import warnings
from collections.abc import Iterator, Mapping, MutableMapping
from typing import Any

import click

from uasnav import __version__
from uasnav.errors import UasnavError
from uasnav.limits import check_environment, check_input_file

#: Longest error line printed (characters); longer messages are cut in the middle.
_MAX_MESSAGE = 2000
#: Set to 1 to let unexpected exceptions through with their traceback (for bug reports).
DEBUG_ENV = "UASNAV_DEBUG"

#: The subcommands: name → (the module that defines it as ``command``, the first paragraph of
#: its help, which ``uasnav --help`` shortens to its one-line summary). A test checks it against
#: the modules; a new subcommand is a module here and a line in this table.
SUBCOMMANDS: Mapping[str, tuple[str, str]] = {
    "allan": (
        "uasnav.cli.allan",
        "Allan deviation of the gyro and accelerometer axes of LOG, and their noise terms.",
    ),
    "calibrate": (
        "uasnav.cli.calibrate",
        "Fit a thermal gyro-bias model to TRAIN (static log with temp), or test --model on --test.",
    ),
    "db": ("uasnav.cli.db", "Inspect and validate the mission selector's XML databases."),
    "fleet": ("uasnav.cli.fleet", "Process a fleet's logs on a Dask cluster (a local one by default)."),
    "monitor": (
        "uasnav.cli.monitor",
        "Follow each vehicle on CONNECTION (udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT, "
        "tcpin:HOST:PORT, /dev/ttyX,BAUD) and report its F3548 conformance state changes "
        "(Accepted, Activated, Nonconforming, Contingent, Ended) and telemetry losses.",
    ),
    "nav": (
        "uasnav.cli.nav",
        "Replay LOG (.ulg, .bin, .tlog, .csv with --gnss, or an ALFA ROS-topic CSV folder) through "
        "the loosely coupled GNSS/INS filter, compare it with the autopilot's own estimate, and "
        "optionally mask GNSS to measure dead-reckoning drift.",
    ),
    "plan": ("uasnav.cli.plan", "Plan the survey of an --area and everything its authorisation needs."),
    "redundancy": (
        "uasnav.cli.redundancy",
        "Redundant IMUs on regular polyhedra (thesis §4.3): k_r, fusion, FDI.",
    ),
    "replay": (
        "uasnav.cli.replay",
        "Send LOG (.tlog as recorded; .bin/.ulg converted to the MAVLink messages a ground station "
        "receives) over UDP, TCP or a serial port in its recorded timing, scaled by --speed.",
    ),
    "report": (
        "uasnav.cli.report",
        "Reproduce the thesis' experiments on embedded, simulated data and write OUT/report.html "
        "(self-contained, with figures) and OUT/report.json.",
    ),
    "select": (
        "uasnav.cli.select",
        "Equipment, feasible UAS and cameras, and ranked UAS/camera configurations for a mission.",
    ),
    "serve": (
        "uasnav.cli.serve",
        "Start the web application: mission selection, trajectory prediction, database pages, the "
        "live telemetry page (/live) and the JSON API (/api, /openapi.json), fully offline.",
    ),
    "simulate": (
        "uasnav.cli.simulate",
        "Simulate a static IMU with every error term and write it (with ground truth) to OUT.",
    ),
    "trajectory": (
        "uasnav.cli.trajectory",
        "Trajectory prediction (kinematic point mass with the autopilot's limits, or the thesis' "
        "LVQ networks): element times, ETA, 4D waypoint times, time bounds, operational intents.",
    ),
    "utm": ("uasnav.cli.utm", "UTM: deconfliction of ASTM F3548 operational intents."),
    "zupt": (
        "uasnav.cli.zupt",
        "Estimate the gyro and accelerometer biases of a stationary LOG with the 15-state ZUPT "
        "filter (calibrated gyro data) or the thermally compensated TCZUPT filter (raw gyro data "
        "and a thermal model's derivative).",
    ),
}


# click's own control flow (usage errors → exit 2, --help, ctx.exit) and the interpreter's
# (Ctrl-C, sys.exit) pass through the handler untouched.
_PASS_THROUGH = (click.exceptions.ClickException, click.exceptions.Exit, click.exceptions.Abort)


def _one_line(text: str) -> str:
    """A message as one stderr line: the contract is exactly one ``error: …`` line."""
    line = " ".join(str(text).split()) or "(no message)"
    # a message quoting a hostile input (a 128 KB CSV cell) stays readable
    if len(line) > _MAX_MESSAGE:
        half = _MAX_MESSAGE // 2
        line = f"{line[:half]} … [{len(line) - 2 * half} characters] … {line[-half:]}"
    return line


def _os_error_message(e: OSError) -> str:
    """``strerror: filename`` once (``str(e)`` repeats the path, ``[Errno n]`` is noise)."""
    if not e.strerror:
        return str(e)
    names = [str(f) for f in (e.filename, e.filename2) if f is not None]
    return f"{e.strerror}: {' -> '.join(names)}" if names else e.strerror


def _show_warning(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: Any = None,
    line: str | None = None,
) -> None:
    click.echo(f"warning: {_one_line(str(message))}", err=True)


def _is_debug() -> bool:
    return os.environ.get(DEBUG_ENV, "").strip() not in ("", "0")


def _show_held(caught: list[warnings.WarningMessage]) -> None:
    for text in dict.fromkeys(_one_line(str(w.message)) for w in caught):
        click.echo(f"warning: {text}", err=True)


class _LazyCommands(MutableMapping[str, click.Command]):
    """The group's commands, each imported from its module the first time it is looked up.

    Names and membership come from the table without importing anything; ``[name]``, ``get``,
    ``values()`` and ``items()`` import what they return, so code that walks every command
    (completion, the option tests) sees them all, loaded."""

    def __init__(self, table: Mapping[str, tuple[str, str]]) -> None:
        self._table = table
        self._loaded: dict[str, click.Command] = {}

    def __getitem__(self, name: str) -> click.Command:
        if name not in self._loaded:
            if name not in self._table:
                raise KeyError(name)
            self._loaded[name] = _load_command(name, self._table[name][0])
        return self._loaded[name]

    def __setitem__(self, name: str, cmd: click.Command) -> None:
        self._loaded[name] = cmd

    def __delitem__(self, name: str) -> None:
        if name not in self:
            raise KeyError(name)
        self._loaded.pop(name, None)
        self._table = {k: v for k, v in self._table.items() if k != name}

    def __contains__(self, name: object) -> bool:
        return name in self._loaded or name in self._table

    def __iter__(self) -> Iterator[str]:
        return iter(dict.fromkeys([*self._table, *self._loaded]))

    def __len__(self) -> int:
        return len(dict.fromkeys([*self._table, *self._loaded]))

    def is_loaded(self, name: str) -> bool:
        return name in self._loaded

    def summary(self, name: str) -> str:
        """The first paragraph of ``name``'s help, from the table (nothing imported)."""
        return self._table[name][1]


def _load_command(name: str, module: str) -> click.Command:
    cmd = getattr(importlib.import_module(module), "command", None)
    if not isinstance(cmd, click.Command) or cmd.name != name:
        raise RuntimeError(f"{module} does not define the click command {name!r} as `command`")
    _guarded(cmd)
    return cmd


class _Group(click.Group):
    """Turns every error into one ``error: …`` line on stderr and exit code 1: uasnav's domain
    errors and OS errors as they are, anything else as an internal error to report (with the
    traceback only when ``UASNAV_DEBUG=1``). With ``lazy_subcommands`` (see :data:`SUBCOMMANDS`)
    each subcommand is imported when it runs; without, it is an ordinary group."""

    def __init__(
        self, *args: Any, lazy_subcommands: Mapping[str, tuple[str, str]] | None = None, **kwargs: Any
    ) -> None:
        super().__init__(*args, **kwargs)
        if lazy_subcommands is not None:
            self.commands: MutableMapping[str, click.Command] = _LazyCommands(lazy_subcommands)  # type: ignore[assignment]

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        # click's own listing, except that a command not yet imported is shown by the summary in
        # the table: the same line click would make from its help, at any terminal width
        commands = self.commands
        if not isinstance(commands, _LazyCommands):
            return super().format_commands(ctx, formatter)
        names = self.list_commands(ctx)
        rows = []
        if names:
            limit = formatter.width - 6 - max(len(n) for n in names)
            for name in names:
                if commands.is_loaded(name):
                    cmd = commands[name]
                    if cmd.hidden:
                        continue
                    rows.append((name, cmd.get_short_help_str(limit)))
                else:
                    rows.append(
                        (name, click.Command(name, help=commands.summary(name)).get_short_help_str(limit))
                    )
        if rows:
            with formatter.section("Commands"):
                formatter.write_dl(rows)

    def invoke(self, ctx: click.Context) -> Any:
        # A warning (ours, e.g. CorruptDataWarning, or a library's that we let through on
        # purpose) is one ``warning: …`` line, like errors: never a file path and source line.
        # Warnings are held until the command ends: shown after a success, folded into the one
        # ``error:`` line of a failure.
        warnings.showwarning = _show_warning
        held: list[str] = []
        try:
            with warnings.catch_warnings(record=True) as caught:
                try:
                    result = super().invoke(ctx)
                except click.exceptions.Exit:
                    _show_held(caught)
                    raise
                except BaseException:
                    held = list(dict.fromkeys(_one_line(str(w.message)) for w in caught))
                    raise
            _show_held(caught)
            return result
        except _PASS_THROUGH:
            raise
        except UasnavError as e:
            message = str(e)
        except OSError as e:
            message = _os_error_message(e)
        except OverflowError as e:
            # only numbers the user gave reach the float/int/date range: an input error
            message = f"a value is outside the representable range ({e}); check the options and inputs"
        except RecursionError:
            message = "input nested too deeply to process"
        except MemoryError:
            message = "out of memory (the input or the options ask for more than this machine has)"
        except (KeyboardInterrupt, SystemExit, GeneratorExit):
            raise
        except BaseException as e:  # also a Rust panic: PanicException is a BaseException
            if _is_debug():
                raise
            message = (
                f"internal error: {type(e).__name__}: {e} - please report it "
                f"(run again with {DEBUG_ENV}=1 for the traceback)"
            )
        if held:
            message = _with_warnings(message, held)
        click.echo(f"error: {_one_line(message)}", err=True)
        ctx.exit(1)


def _with_warnings(message: str, held: list[str]) -> str:
    """The error line with the warnings held back during the run; a warning that starts with
    what the error already names (``log.bin: corrupt data skipped …``) drops that prefix, so
    each file is named once."""
    parts = []
    for w in held:
        head, sep, rest = w.partition(": ")
        parts.append(rest if sep and head and head in message else w)
    return f"{message} (warnings: {'; '.join(parts)})"


@click.group(
    cls=_Group, lazy_subcommands=SUBCOMMANDS, context_settings={"help_option_names": ["-h", "--help"]}
)
@click.version_option(__version__, "--version", prog_name="uasnav")
def main() -> None:
    """Navigation and mission management for small unmanned aircraft.

    Units are SI (s, rad/s, m/s², °C) and frames NED / body (x fwd, y right, z down) unless an
    option says otherwise. Every subcommand takes --help; most take --json.

    Exit codes: 0 success; 1 an error, reported as one "error: …" line on stderr; 2 a usage
    error (unknown option, bad option value). An "internal error" is a bug: please report it,
    with the traceback that UASNAV_DEBUG=1 shows.
    """


def _input_paths(cmd: click.Command) -> list[str]:
    """Names of ``cmd``'s parameters that are files to read (``click.Path``, not an output)."""
    from uasnav.cli._common import OutputPath

    return [
        p.name
        for p in cmd.params
        if p.name
        and isinstance(p.type, click.Path)
        and not isinstance(p.type, OutputPath)
        and not (p.name.startswith("out") or "output" in p.name)
    ]


def _guarded(cmd: click.Command, staged: bool = True) -> None:
    """Wrap ``cmd`` (and its subcommands) so that, before the command opens anything, the
    resource limits of the environment are valid (:func:`uasnav.limits.check_environment`) and
    every input path is checked by :func:`uasnav.limits.check_input_file`: one check for every
    subcommand, so a FIFO never blocks a reader. ``--help`` needs neither. The files the
    command writes form one :func:`uasnav.atomicfile.output_set`: all written, or none —
    except under a command marked ``incremental_outputs`` (the fleet's datasets, committed log
    by log and read back by the same run, keep their own manifest)."""
    staged = staged and not getattr(cmd, "incremental_outputs", False)
    if isinstance(cmd, click.Group):
        for sub in cmd.commands.values():
            _guarded(sub, staged)
    names = _input_paths(cmd)
    callback = cmd.callback
    if callback is None or isinstance(cmd, click.Group):
        return  # a group's callback runs before its subcommand's, which is guarded itself

    def checked(*args: Any, **kwargs: Any) -> Any:
        from uasnav.atomicfile import output_set

        check_environment()
        for name in names:
            value = kwargs.get(name)
            for v in value if isinstance(value, list | tuple) else [value]:
                if isinstance(v, str | os.PathLike):
                    check_input_file(v)
        # every file the command writes is committed together when it succeeds: a failure
        # (a bad second output, an error after the first file) leaves every output as it was
        if not staged:
            return callback(*args, **kwargs)
        with output_set():
            return callback(*args, **kwargs)

    cmd.callback = functools.update_wrapper(checked, callback)


def run() -> None:  # pragma: no cover - console entry point alias
    sys.exit(main())


__all__ = ["main"]
