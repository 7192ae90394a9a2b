"""Property/fuzz layer over the whole command line (issue #20, "how to keep it fixed").

Every command is found by walking the click group (so a command added later is fuzzed too) and
run through ``CliRunner`` with hostile option values and hostile small CSV logs drawn by
Hypothesis. The contract, whatever the input:

- the exit code is 0, 1 (an error) or 2 (a usage error);
- on 1, stderr is exactly one line, starting ``error:``, showing values as typed (no
  ``np.float64(…)``, no ``got None``);
- no traceback, no exception escaping the command (``UASNAV_DEBUG`` unset);
- on failure, no file in the working folder was created, changed or removed.

Every test here runs under :data:`FUZZ` (derandomized, a fixed number of examples, no
example database): the examples are the same on every machine and every run, so CI cannot
fail on a fresh random draw, and a failure reproduces from its test name alone. To search
further, run with ``UASNAV_FUZZ_RANDOM=1`` (random draws, 200 examples).

``report`` is left out (it runs the thesis experiments: minutes per valid example), and so is
``serve`` (a server runs until stopped); their options are covered by tests/test_cli_options.py.
"""

from __future__ import annotations

import hashlib
import math
import os
import resource
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import click
import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from uasnav.cli import main
from uasnav.cli._common import OutputPath, Real

#: The fuzz profile of this file (module docs): derandomized in CI and in ``make test``; a
#: random search when ``UASNAV_FUZZ_RANDOM`` is set.
_RANDOM = bool(os.environ.get("UASNAV_FUZZ_RANDOM"))
FUZZ = settings(
    derandomize=not _RANDOM,
    database=None,
    max_examples=200 if _RANDOM else 25,
    deadline=None,
    print_blob=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)

# Commands whose valid runs take minutes: not fuzzed here (see the module docstring). ``serve``
# runs until it is stopped (a valid example would never return): its options are covered by
# tests/test_cli_options.py and its behaviour over HTTP by tests/test_web_serve.py.
_SLOW = {("report",), ("serve",)}
# Options whose valid values start long computations; they are fuzzed with a fast value.
_FAST_FLAGS_OFF = {"simulated"}


def _walk(cmd: click.Command, path: tuple[str, ...] = ()) -> list[tuple[tuple[str, ...], click.Command]]:
    if isinstance(cmd, click.Group):
        out = []
        for name, sub in sorted(cmd.commands.items()):
            out += _walk(sub, (*path, name))
        return out
    return [(path, cmd)]


COMMANDS = [(p, c) for p, c in _walk(main) if p not in _SLOW]
_IDS = [" ".join(p) for p, _ in COMMANDS]

# --- hostile values -------------------------------------------------------------------------

_HOSTILE_NUMBERS = [
    "nan", "inf", "-inf", "-1", "0", "-0", "1e308", "-1e308", "5e-324", "1e400",
    "", " ", "abc", "1e", "0x10", "1,5", "1_0", "١",
]  # fmt: skip
_HOSTILE_INTS = ["-1", "0", str(2**32), str(2**63), "1.5", "", "abc", "1e3"]
_HOSTILE_TEXT = ["", " ", "nan", "x" * 300, "\u00e9\u00e8", "a,b", "=", "a=b", "1@2", ",,", "\t"]

_IMU_COLUMNS = ["t", "gx", "gy", "gz", "ax", "ay", "az", "temp"]
_FLIGHT_COLUMNS = ["t", "lat", "lon", "alt", "v_N", "v_E", "v_D"]
_CELLS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.floats(-1e3, 1e3).map(lambda x: f"{x:.6g}"),
    st.sampled_from(["", "nan", "abc", '"', '"a', "1e999", "-0", " 1", "0x1", "1;2", "\ufeff1", "x" * 2000]),
)


@st.composite
def _csv_log(draw: st.DrawFn) -> str:
    """A small CSV log, often nearly valid: the IMU or flight columns (maybe with a UTF-8 BOM,
    a missing or duplicated column, comment lines), 0–8 rows of hostile cells."""
    cols = list(draw(st.sampled_from([_IMU_COLUMNS, _IMU_COLUMNS[:7], _FLIGHT_COLUMNS])))
    if draw(st.booleans()):
        cols = draw(st.permutations(cols))
    if draw(st.integers(0, 4)) == 0 and cols:
        del cols[draw(st.integers(0, len(cols) - 1))]
    if draw(st.integers(0, 6)) == 0:
        cols.append(cols[0] if cols else "t")
    lines = []
    if draw(st.booleans()):
        lines.append(
            draw(st.sampled_from(["# rate_hz: 100", "# mounting: 1 0 0", "# uasnav log format v1", "#"]))
        )
    lines.append(("\ufeff" if draw(st.integers(0, 5)) == 0 else "") + ",".join(cols))
    n = draw(st.integers(0, 8))
    regular = draw(st.booleans())
    for i in range(n):
        if regular:  # well-formed numbers on a 100 Hz grid: reaches the numerics
            row = [f"{i * 0.01:.2f}"] + [f"{draw(st.floats(-2, 2)):.5g}" for _ in cols[1:]]
        else:
            row = [draw(_CELLS) for _ in cols]
        lines.append(",".join(row))
    if draw(st.integers(0, 5)) == 0 and lines:
        lines[-1] = lines[-1][: len(lines[-1]) // 2]  # a truncated last line
    return "\n".join(lines) + ("\n" if draw(st.booleans()) else "")


def _number(param: click.Parameter, hostile: bool) -> st.SearchStrategy[str]:
    valid = st.sampled_from(["1", "2", "0.5", "10", "45"])
    if param.name in ("duration",):
        valid = st.sampled_from(["1", "2.5"])  # a fast simulation
    elif param.name == "rate":
        valid = st.sampled_from(["10", "50", "100"])
    elif param.name in ("segment", "max_gap", "per_face", "prototypes"):
        valid = st.sampled_from(["1", "5", "10"])
    elif param.name in ("vehicles", "flights"):
        valid = st.sampled_from(["1", "2"])  # fleet simulate: a small fleet
    elif param.name == "nav_flights":
        valid = st.just("0")  # a simulated mission takes seconds (tested in tests/test_fleet.py)
    if not hostile:
        return valid
    bad = _HOSTILE_INTS if isinstance(param.type, click.types.IntParamType) else _HOSTILE_NUMBERS
    return st.one_of(valid, st.sampled_from(bad))


def _text(param: click.Parameter, inputs: list[str], hostile: bool) -> st.SearchStrategy[str]:
    name = param.name or ""
    # option name -> (valid values, hostile values)
    special = {
        "wind_text": (["5@270", "0@0", "12.5@90"], ["1e308@0", "nan@0", "5", "5@", "@", "-1@0", "5@1e400"]),
        "taus": (["octave", "decade", "all", "0.01,0.02"], ["1,nan", "0", "-1", "1e308", ""]),
        "required": (["0,10", "0,5,10"], ["nan", "0,-1", "1e308", ""]),
        "weights": (
            ["cost=1", "range=2,cost=0"],
            ["range=0,weight=0,cost=0,resolution=0", "cost=nan", "x=1"],
        ),
        "targets": (["cost=4000:7000"], ["cost=nan:1", "cost=1:1", "cost=1", "range=inf:0"]),
        "image_size": (["70x70", "1x2"], ["0x0", "-1x5", "nanx1", "1e308x1e308", "70", "x"]),
        "preset": (["ax1", "crs05-02", *inputs], ["nope"]),
        "mission": (["precision-agriculture"], ["nope", ""]),
        "jurisdiction": (["easa", "faa"], ["mars"]),
        "category": (["open"], ["specific", "nope"]),
        "imagery": (["multispectral", "any"], ["rgb", "nope"]),
        "only": ([], ["nope", "", ","]),
    }
    if name in ("db", "regs", "matrices", "source"):
        return st.sampled_from(["missing.xml", *inputs])  # never a URL: no network here
    valid, bad = special.get(name, (["x"], []))
    return st.sampled_from(valid + bad + _HOSTILE_TEXT if hostile or not valid else valid)


def _value(param: click.Parameter, inputs: list[str], hostile: bool) -> st.SearchStrategy[str]:
    t = param.type
    if isinstance(t, click.Choice):
        choices = st.sampled_from([str(c) for c in t.choices])
        return st.one_of(choices, st.just("bogus")) if hostile else choices
    if isinstance(t, OutputPath):
        # fresh names, a missing folder, an input file (must be refused or left unchanged)
        fresh = ["out.csv", "out.json", "out.npz", "out.png"]
        return st.sampled_from([*fresh, "nodir/out.csv", "out", *inputs[:1]] if hostile else fresh)
    if isinstance(t, click.Path):
        return st.sampled_from([*inputs, "missing.csv", "."] if hostile else inputs)
    if isinstance(t, (Real, click.types.FloatParamType, click.types.IntParamType)):
        return _number(param, hostile)
    return _text(param, inputs, hostile)


@st.composite
def _invocation(draw: st.DrawFn, path: tuple[str, ...], cmd: click.Command, inputs: list[str]) -> list[str]:
    argv = list(path)
    # Half the examples have hostile option values; the other half valid ones, so that the
    # hostile files reach the readers and the numerics instead of stopping at option parsing.
    hostile = draw(st.booleans())
    if path == ("calibrate",) and not hostile:
        # its valid form is TRAIN --out MODEL [--method … --order|--hidden …]: the generic
        # draw below almost never finds it
        method = draw(st.sampled_from(["poly", "nn", "both"]))
        argv += [draw(st.sampled_from(inputs)), "--out", "out.json", "--method", method]
        if method != "nn" and draw(st.booleans()):
            argv += ["--order", draw(st.sampled_from(["0", "1", "3"]))]
        if method != "poly" and draw(st.booleans()):
            argv += ["--hidden", draw(st.sampled_from(["1", "2"]))]
        if draw(st.booleans()):
            argv += ["--average", draw(st.sampled_from(["0.01", "0.05", "1"]))]
        return argv + (["--select"] if draw(st.booleans()) else [])
    for p in cmd.params:
        if isinstance(p, click.Argument):
            if p.nargs == -1:
                k = draw(st.integers(1 if p.required or not hostile else 0, 6))
                argv += [draw(_value(p, inputs, hostile)) for _ in range(k)]
            elif p.required or draw(st.booleans()):
                argv.append(draw(_value(p, inputs, hostile)))
            continue
        assert isinstance(p, click.Option)
        if p.is_flag:
            if p.name not in _FAST_FLAGS_OFF and draw(st.booleans()):
                argv.append(p.opts[0])
            continue
        # simulate without --duration runs the profile's natural length (an hour): keep it fast
        forced = path == ("simulate",) and p.name == "duration"
        if p.required or forced or draw(st.integers(0, 2)) == 0:
            argv += [p.opts[0], draw(_value(p, inputs, hostile))]
    return argv


# --- the contract -----------------------------------------------------------------------------


def _snapshot(root: Path) -> dict[str, str]:
    out = {}
    for dirpath, _, files in os.walk(root):
        for f in files:
            p = Path(dirpath) / f
            out[str(p.relative_to(root))] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


@pytest.fixture(scope="module", autouse=True)
def _bounded_memory() -> Iterator[None]:
    """A hostile option that asks for tens of GB must fail with an error, not take the machine
    down: cap this process' address space for the fuzz run (restored afterwards)."""
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    with open("/proc/self/status") as fh:
        vm = next(int(x.split()[1]) * 1024 for x in fh if x.startswith("VmSize:"))
    cap = vm + 3 * 2**30
    if hard != resource.RLIM_INFINITY:
        cap = min(cap, hard)
    resource.setrlimit(resource.RLIMIT_AS, (cap, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def _check_contract(argv: list[str], inputs: list[str], root: Path, before: dict[str, str]) -> None:
    r = CliRunner().invoke(main, argv, catch_exceptions=True, env={"UASNAV_DEBUG": None})
    where = f"uasnav {' '.join(map(repr, argv))}"
    event(f"exit {r.exit_code}")  # --hypothesis-show-statistics: how far the examples get
    assert r.exit_code in (0, 1, 2), f"{where}: exit {r.exit_code}\n{r.stderr}"
    assert r.exception is None or isinstance(r.exception, SystemExit), f"{where}: {r.exception!r}"
    assert "Traceback" not in r.stderr and "Traceback" not in r.stdout, f"{where}:\n{r.stderr}"
    if r.exit_code == 1:
        lines = r.stderr.splitlines()
        assert len(lines) == 1 and lines[0].startswith("error: "), f"{where}: stderr\n{r.stderr}"
        assert "np.float64(" not in lines[0] and "got None" not in lines[0], f"{where}: {lines[0]}"
        for name in inputs:  # the user's file named once (not the path twice, not a temp file)
            assert lines[0].count(name) <= 1 or argv.count(name) > 1, f"{where}: {lines[0]}"
        assert ".tmp" not in lines[0], f"{where}: {lines[0]}"
    if r.exit_code == 2:
        assert "Error" in r.stderr, f"{where}: {r.stderr}"
    if r.exit_code != 0:
        after = _snapshot(root)
        assert after == before, f"{where}: files changed on failure: {set(after) ^ set(before) or 'content'}"


@pytest.mark.parametrize(("path", "cmd"), COMMANDS, ids=_IDS)
@FUZZ
@given(data=st.data())
def test_every_command_keeps_the_contract(path, cmd, data, tmp_path_factory):
    root = tmp_path_factory.mktemp("fuzz")
    inputs = []
    for i in range(data.draw(st.integers(1, 3), label="n_logs")):
        f = root / f"in{i}.csv"
        f.write_text(data.draw(_csv_log(), label=f"log{i}"), encoding="utf-8")
        inputs.append(f.name)
    if data.draw(st.booleans(), label="existing out.csv"):
        (root / "out.csv").write_text("a file the user owns\n")  # a failed run must not touch it
    argv = data.draw(_invocation(path, cmd, inputs), label="argv")
    before = _snapshot(root)
    cwd = os.getcwd()
    os.chdir(root)
    try:
        _check_contract(argv, inputs, root, before)
    finally:
        os.chdir(cwd)


# --- YAML intents, corrupt binary logs, the Python API ----------------------------------------

_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
#: Time budget of one example of the byte-mutation and YAML fuzzers (s): a reader that
#: resynchronises without bound, or a YAML bomb that expands, overruns it and fails the test.
_EXAMPLE_BUDGET_S = 30.0

_YAML_ATOMS = ["intents:", "full:", "delta:", "source: a", "mutation:", "basic_information:", "area:",
               "- outline_circle: {center: {lat: 47, lng: 8}, radius: {value: 100, units: M}}",
               "altitude_lower: {value: 0, reference: W84, units: M}", "start_time:", "duration: 5m",
               "offset_from: {starting_from: {time_during_test: StartOfTestRun}, offset: -1s}",
               "&a [x, x, x, x, x, x, x, x]", "*a", "[*a, *a, *a, *a, *a, *a, *a, *a]", "[[[[[[[[", "{",
               "!!python/object:os.system", "? complex", "- - - -", "1e999", "~", "'", '"\\x00"']  # fmt: skip


@st.composite
def _yaml_text(draw: st.DrawFn) -> str:
    lines = []
    for _ in range(draw(st.integers(1, 30))):
        indent = " " * draw(st.integers(0, 8))
        key = draw(st.sampled_from(["", "a: ", "b: ", "c: &c ", "d: *c ", "- "]))
        lines.append(indent + key + draw(st.sampled_from(_YAML_ATOMS)))
    if draw(st.booleans()):  # a billion-laughs tower of some height
        h = draw(st.integers(1, 9))
        lines = (
            ["l0: &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
            + [f"l{i}: &l{i} [{', '.join([f'*l{i - 1}'] * 10)}]" for i in range(1, h)]
            + [f"intents: {{x: {{full: *l{h - 1}}}}}"]
            + lines
        )
    return "\n".join(lines) + "\n"


@FUZZ
@given(text=_yaml_text())
def test_yaml_intents_keep_the_contract(text, tmp_path_factory):
    root = tmp_path_factory.mktemp("yaml")
    (root / "i.yaml").write_text(text, encoding="utf-8")
    before = _snapshot(root)
    cwd = os.getcwd()
    os.chdir(root)
    try:
        t0 = time.monotonic()
        _check_contract(
            ["utm", "deconflict", "i.yaml", "--now", "2026-01-01T00:00:00Z"], ["i.yaml"], root, before
        )
        assert time.monotonic() - t0 < _EXAMPLE_BUDGET_S
    finally:
        os.chdir(cwd)


_LOGS = {
    ".tlog": (_DATA / "flights" / "phoenix_mission1_arducopter.tlog", 200_000),
    ".bin": (_DATA / "logs" / "ardupilot_log171.bin", 300_000),
    ".ulg": (_DATA / "logs" / "px4_sample_log_small.ulg", 300_000),
}


@st.composite
def _mutated_log(draw: st.DrawFn) -> tuple[str, bytes]:
    ext = draw(st.sampled_from(sorted(_LOGS)), label="format")
    src, keep = _LOGS[ext]
    with open(src, "rb") as fh:
        data = bytearray(fh.read(keep))
    rng_seed = draw(st.integers(0, 2**32 - 1), label="seed")
    import random

    rng = random.Random(rng_seed)
    for _ in range(draw(st.sampled_from([0, 1, 10, 1000, 10_000]), label="flips")):
        i = rng.randrange(len(data))
        data[i] ^= 1 << rng.randrange(8)
    cut = draw(st.sampled_from([len(data), len(data) // 2, 17, 0]), label="truncate at")
    return ext, bytes(data[:cut])


_BYTE_COMMANDS = {
    "allan": ["allan"],
    "zupt": ["zupt"],
    "nav": ["nav", "--json"],
    "train": ["trajectory", "train", "--method", "kinematic", "--out", "m.json"],
    "fleet": ["fleet", "scan", "--out", "o.parquet", "--workers", "0", "--log-timeout", "20", "--json"],
}


@pytest.mark.parametrize("command", list(_BYTE_COMMANDS.values()), ids=list(_BYTE_COMMANDS))
@settings(FUZZ, max_examples=30 if _RANDOM else 6)
@given(log=_mutated_log())
def test_corrupt_binary_logs_keep_the_contract(command, log, tmp_path_factory):
    ext, blob = log
    root = tmp_path_factory.mktemp("bytes")
    (root / f"log{ext}").write_bytes(blob)
    before = _snapshot(root)
    cwd = os.getcwd()
    os.chdir(root)
    try:
        t0 = time.monotonic()
        _check_contract([*command, f"log{ext}"], [f"log{ext}"], root, before)
        took = time.monotonic() - t0
        event(f"{command[0]} {ext}: {'<1' if took < 1 else '<5' if took < 5 else '>=5'} s")
        assert took < _EXAMPLE_BUDGET_S, f"{command} on a mutated {ext}: {took:.1f} s"
    finally:
        os.chdir(cwd)


_API_NUMBERS = st.sampled_from(
    [0.0, -0.0, -1.0, 1.0, 1e-300, 5e-324, 1e308, -1e308, math.inf, -math.inf, math.nan, 100.0]
)


def _api_calls() -> list[tuple[str, Any]]:
    """Public API functions, each with a strategy of hostile (and some ordinary) arguments."""
    import numpy as np

    from uasnav import allan, attitude, limits, stationary, units, zupt
    from uasnav.imu import ImuLog
    from uasnav.trajectory import baselines, route3d

    arrays = st.sampled_from(
        [
            np.zeros(0),
            np.full(10, np.nan),
            np.ones((5, 3)),
            np.arange(1000.0),
            np.full(4, 1.79e308),
            np.ones((2, 2, 2)),
        ]
    )
    nan, big, num, w = np.nan, 1e308, _API_NUMBERS, np.full((4, 3), 1e-3)
    quats = st.sampled_from([[1, 0, 0, 0], [0.5, 0.5, 0.5, 0.5], [2, 0, 0, 0], [0, 0, 0, 0], [nan, 0, 0, 0],
                             [[1, 0, 0, 0], [big, 0, 0, 0]], [1, 0, 0]])  # fmt: skip
    rng = np.random.default_rng(0)
    n = 600
    log = ImuLog(t=np.arange(n) / 100.0, gyro=rng.normal(0, 1e-3, (n, 3)),
                 accel=rng.normal(0, 1e-2, (n, 3)) + [0, 0, -9.81])  # fmt: skip
    plans = st.sampled_from([np.array([[0.0, 0.0], [100.0, 0.0], [100.0, 100.0]]), np.zeros((2, 2)),
                             np.array([[0.0, 0.0], [nan, 1.0]]), np.array([[0, 0], [big, 0]])])  # fmt: skip
    kw = st.fixed_dictionaries({}, optional={"window_s": num, "threshold": num, "min_duration_s": num,
                                             "false_alarm": num})  # fmt: skip
    return [
        ("allan.oadev", st.builds(lambda d, r, t: lambda: allan.oadev(d, r, t), arrays, _API_NUMBERS,
                                 st.sampled_from(["octave", "all", "bogus", [0.0], [-1.0], [1e308]]))),
        ("allan.cluster_sizes", st.builds(lambda k, r: lambda: allan.cluster_sizes(k, r, "octave"),
                                         st.sampled_from([-1, 0, 3, 1000, 2**70]), _API_NUMBERS)),
        ("units.parse_quantity", st.builds(lambda t: lambda: units.parse_quantity(t, "m"), st.sampled_from(
            ["1e999 m", "nan m", "-inf km", "1 s", "", "m", "1e308 km", "15 m"]))),
        ("limits.parse_size", st.builds(lambda t: lambda: limits.parse_size(t), st.sampled_from(
            ["abc", "-1", "1e999", "nan", "inf", "", "1Q", "2G"]))),
        ("limits.check_work", st.builds(lambda n: lambda: limits.check_work(n, "probe"), _API_NUMBERS)),
        ("attitude.drift", st.builds(lambda r, dt, d: lambda: attitude.drift(r, dt, d),
                                    st.sampled_from([[1e-3, 0, 0], [nan, 0, 0], [big, 0, 0], w]),
                                    num, num)),
        ("attitude.propagate", st.builds(lambda q, dt: lambda: attitude.propagate(q, w, dt),
                                        quats, num)),
        ("attitude.quat_to_euler", st.builds(lambda q: lambda: attitude.quat_to_euler(q), quats)),
        ("attitude.rotation_angle", st.builds(lambda q: lambda: attitude.rotation_angle(q), quats)),
        ("stationary.detect_static", st.builds(lambda k: lambda: stationary.detect_static(log, **k), kw)),
        ("zupt.moving_average", st.builds(lambda x, r, w: lambda: zupt.moving_average(x, r, w),
                                         st.sampled_from([np.ones((10, 3)), np.zeros(5)]), num, num)),
        ("trajectory.kinematic_times", st.builds(
            lambda p, v, a: lambda: baselines.kinematic_times(p, np.zeros(1), np.full(1, 20.0), v, a),
            plans, _API_NUMBERS, _API_NUMBERS)),
        ("trajectory.vertical_time", st.builds(lambda dz, v, a: lambda: route3d.vertical_time(dz, v, a),
                                              _API_NUMBERS, _API_NUMBERS, _API_NUMBERS)),
    ]  # fmt: skip


def _non_finite(out: Any, depth: int = 0) -> str | None:
    """Where ``out`` (a result: arrays, numbers, dataclasses, named tuples, lists) holds a NaN
    or an infinity, or None."""
    import dataclasses

    import numpy as np

    if depth > 4 or out is None or isinstance(out, bool | str):
        return None
    if isinstance(out, float | np.floating):
        return None if math.isfinite(out) else repr(out)
    if isinstance(out, np.ndarray):
        if out.dtype.kind == "f" and not np.isfinite(out).all():
            return f"array {np.asarray(out).ravel()[~np.isfinite(out.ravel())][:3]}"
        return None
    if dataclasses.is_dataclass(out):
        items = [(f.name, getattr(out, f.name)) for f in dataclasses.fields(out)]
    elif isinstance(out, tuple) and hasattr(out, "_fields"):
        items = list(zip(out._fields, out, strict=True))
    elif isinstance(out, list | tuple):
        items = list(enumerate(out))
    else:
        return None
    for k, v in items:
        if (where := _non_finite(v, depth + 1)) is not None:
            return f"{k}: {where}"
    return None


@pytest.mark.parametrize("name,calls", _api_calls(), ids=[n for n, _ in _api_calls()])
@settings(FUZZ, max_examples=60 if _RANDOM else 15)
@given(data=st.data())
def test_public_api_functions_answer_or_raise_input_errors(name, calls, data):
    """A public function given hostile values returns finite numbers or raises a uasnav error
    (an ``InputError`` is also a ``ValueError``): never a bare numpy/Python exception, never inf
    or NaN presented as a result."""
    from uasnav.errors import UasnavError

    call = data.draw(calls)
    try:
        out = call()
    except UasnavError as e:
        event("refused")
        assert "\n" not in str(e), f"{name}: {e}"
        return
    event("answered")
    where = _non_finite(out)
    assert where is None, f"{name}: a non-finite result ({where})"


def test_the_api_fuzz_can_fail() -> None:
    """The finiteness check finds what it must (so the property above is not vacuous)."""
    import numpy as np

    from uasnav.attitude import drift

    assert _non_finite(np.array([1.0, np.inf])) is not None
    assert _non_finite([(1.0, {"x": 1}), float("nan")]) is not None
    assert _non_finite(drift([1e-3, 0, 0], 0.01, 10.0)) is None  # an ordinary answer passes
