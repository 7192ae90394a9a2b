"""Every option of every ``uasnav`` command is validated by its type at parse time (issue #20,
class 5): non-finite numbers, values outside the option's domain, negative seeds and empty
output names are usage errors (exit code 2) naming the option, never a traceback or a silent
run. The commands are found by walking the click group, so a new command is covered too."""

from __future__ import annotations

import click
import pytest
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.cli._common import OutputPath, Real


def _walk(cmd: click.Command, path: tuple[str, ...] = ()) -> list[tuple[tuple[str, ...], click.Command]]:
    if isinstance(cmd, click.Group):
        out = []
        for name, sub in sorted(cmd.commands.items()):
            out += _walk(sub, (*path, name))
        return out
    return [(path, cmd)]


COMMANDS = _walk(main)
_IDS = [" ".join(p) for p, _ in COMMANDS]


def _dummy(param: click.Parameter) -> list[str]:
    """A syntactically valid value for a required parameter (parsing stops before it is used)."""
    t = param.type
    if isinstance(t, click.Choice):
        v = str(t.choices[0])
    elif isinstance(t, (Real, click.types.FloatParamType, click.types.IntParamType)):
        v = "1"
    elif param.name == "wind_text":
        v = "1@0"
    else:
        v = "x.csv"
    if isinstance(param, click.Argument):
        return [v]
    return [param.opts[0], v]


def _argv(path: tuple[str, ...], cmd: click.Command, name: str, value: str) -> list[str]:
    argv = list(path)
    for p in cmd.params:
        if p.name == name:
            continue
        if p.required:
            argv += _dummy(p)
    opt = next(p for p in cmd.params if p.name == name)
    return [*argv, opt.opts[0], value]


def _invoke(argv: list[str]):  # type: ignore[no-untyped-def]
    return CliRunner().invoke(main, argv, catch_exceptions=True)


def _usage_error(argv: list[str], option: str) -> str:
    r = _invoke(argv)
    assert r.exit_code == 2, (argv, r.exit_code, r.stdout, r.stderr)
    assert "Traceback" not in r.stderr
    assert r.exception is None or isinstance(r.exception, SystemExit), r.exception
    assert option in r.stderr, r.stderr
    return r.stderr


def test_the_walk_finds_every_command():
    names = set(_IDS)
    assert {"allan", "zupt", "simulate", "redundancy fuse", "trajectory train", "select"} <= names


@pytest.mark.parametrize(("path", "cmd"), COMMANDS, ids=_IDS)
def test_no_option_is_a_bare_float_or_int(path, cmd):
    """A bare ``float``/``int`` accepts nan, inf, negatives and 10³⁰⁰: every numeric option
    must say its domain (``Real``/``POSITIVE``/… or ``click.IntRange``)."""
    bare = [
        p.opts[0]
        for p in cmd.params
        if type(p.type) in (click.types.FloatParamType, click.types.IntParamType)
    ]
    assert not bare, f"{' '.join(path)}: options without a domain: {bare}"


@pytest.mark.parametrize(("path", "cmd"), COMMANDS, ids=_IDS)
def test_numeric_options_refuse_non_finite_values(path, cmd):
    for p in cmd.params:
        if isinstance(p, click.Option) and isinstance(p.type, Real):
            for bad in ("nan", "inf", "-inf", "1e400"):
                err = _usage_error(_argv(path, cmd, p.name, bad), p.opts[0])
                assert bad in err  # the value as typed


@pytest.mark.parametrize(("path", "cmd"), COMMANDS, ids=_IDS)
def test_seeds_are_32_bit_unsigned(path, cmd):
    for p in cmd.params:
        if p.name == "seed":
            assert isinstance(p.type, click.IntRange), (path, p.type)
            assert (p.type.min, p.type.max) == (0, 2**32 - 1), (path, p.type)
            _usage_error(_argv(path, cmd, "seed", "-1"), "--seed")
            _usage_error(_argv(path, cmd, "seed", str(2**32)), "--seed")


@pytest.mark.parametrize(("path", "cmd"), COMMANDS, ids=_IDS)
def test_output_options_refuse_an_empty_name(path, cmd):
    outs = [
        p
        for p in cmd.params
        if isinstance(p, click.Option) and p.name in ("out", "out_path", "plot_path", "out_dir")
    ]
    for p in outs:
        assert isinstance(p.type, OutputPath), (path, p.opts[0])
        assert "empty" in _usage_error(_argv(path, cmd, p.name, ""), p.opts[0])
        _usage_error(_argv(path, cmd, p.name, "  "), p.opts[0])


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (["zupt", "x.csv", "--levelling-s", "nan"], "--levelling-s"),
        (["zupt", "x.csv", "--levelling-s", "0"], "--levelling-s"),
        (["zupt", "x.csv", "--latitude-deg", "91"], "--latitude-deg"),
        (["redundancy", "kr", "--per-face", "1e300"], "--per-face"),
        (["redundancy", "kr", "--per-face", "0"], "--per-face"),
        (["redundancy", "fuse", "a.csv", "b.csv", "--out", "f.csv", "--stuck", "-1"], "--stuck"),
        (["redundancy", "fuse", "a.csv", "b.csv", "--out", "f.csv", "--learn-bias", "-5"], "--learn-bias"),
        (["redundancy", "fuse", "a.csv", "b.csv", "--out", "f.csv", "--p-fa", "0"], "--p-fa"),
        (["redundancy", "fuse", "a.csv", "b.csv", "--out", "f.csv", "--p-fa", "1"], "--p-fa"),
        (
            ["trajectory", "predict", "--model", "m", "--plan", "p", "--wind", "1@0", "--tolerance", "-1"],
            "--tolerance",
        ),
        (
            ["trajectory", "predict", "--model", "m", "--plan", "p", "--wind", "1@0", "--speed", "0"],
            "--speed",
        ),
        (["trajectory", "train", "f.csv", "--out", "m.json", "--prototypes", "0"], "--prototypes"),
        (["trajectory", "train", "f.csv", "--out", "m.json", "--segment", "-1"], "--segment"),
        (["calibrate", "t.csv", "--out", "m.json", "--average", "0"], "--average"),
        (["simulate", "--out", "s.csv", "--duration", "-1"], "--duration"),
        (["simulate", "--out", "s.csv", "--rate", "0"], "--rate"),
        (["simulate", "--out", "s.csv", "--latitude", "-90.5"], "--latitude"),
        (["select", "--range", "-1"], "--range"),
        (["select", "--wind", "nan"], "--wind"),
        (["db", "validate", "x.xml", "--timeout", "0"], "--timeout"),
        (["db", "validate", "x.xml", "--max-bytes", "0"], "--max-bytes"),
        (["allan", "x.csv", "--rate", "-100"], "--rate"),
        (["allan", "x.csv", "--taus", "1,nan,10"], "--taus"),
        (["zupt", "x.csv", "--residual-bias", "1e400 rad/s"], "--residual-bias"),
        (["select", "--image-size", "0x70"], "--image-size"),
        (["report", "--only", ","], "--only"),
        (["report", "--only", ""], "--only"),
        (["select", "--image-size", "nanx70"], "--image-size"),
    ],
)
def test_issue_examples_are_usage_errors(argv, option):
    _usage_error(argv, option)


@pytest.mark.parametrize(
    "weights",
    ["range=0,weight=0,cost=0,resolution=0", "cost=-1", "cost=nan", "range=inf"],
)
def test_select_refuses_weights_that_rank_nothing(weights):
    _usage_error(["select", "--weights", weights], "--weights")


@pytest.mark.parametrize("targets", ["cost=nan:7000", "range=5000:inf", "cost=4000:4000"])
def test_select_refuses_degenerate_targets(targets):
    _usage_error(["select", "--targets", targets], "--targets")


@pytest.mark.parametrize("wind", ["1e308@0", "nan@0", "5@inf", "-3@0"])
def test_trajectory_wind_is_finite_and_sane(tmp_path, wind):
    r = _invoke(["trajectory", "predict", "--model", "m.json", "--plan", "p.csv", "--wind", wind])
    # parse_wind runs before any file is read: one error line, exit 1
    assert r.exit_code == 1, (r.stdout, r.stderr)
    assert r.stderr.startswith("error: --wind") and r.stderr.count("\n") == 1, r.stderr


def test_values_are_shown_as_typed():
    err = _usage_error(["simulate", "--out", "s.csv", "--rate", "-0.50"], "--rate")
    assert "-0.50" in err and "np.float64" not in err
