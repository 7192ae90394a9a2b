"""Hostile inputs, second pass: corrupt telemetry, YAML bombs, bad limits, FIFOs, failed runs.

Every probe builds its input here (nothing large is committed) and pins the CLI contract: exit
1 or 2 with exactly one ``error:`` line (warnings of the failed run folded into it), no input
changed, and a bounded run: a probe that used to hang is run in a subprocess with a deadline
far above its expected time, so a regression fails instead of stalling CI.
"""

from __future__ import annotations

import os
import random
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.errors import DataFormatError, InputError

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
TLOG = DATA / "flights" / "phoenix_mission1_arducopter.tlog"
BIN = DATA / "logs" / "ardupilot_log171.bin"


def _one_error_line(res, code: int = 1) -> str:  # type: ignore[no-untyped-def]
    lines = [ln for ln in (res.stderr or "").splitlines() if ln.strip()]
    assert res.exit_code == code, (res.exit_code, res.output)
    assert len(lines) == 1 and lines[0].startswith("error: "), lines
    assert "Traceback" not in res.output
    return lines[0]


def _flipped(src: Path, dst: Path, n: int, seed: int = 1) -> Path:
    data = bytearray(src.read_bytes())
    rng = random.Random(seed)
    for _ in range(n):
        i = rng.randrange(len(data))
        data[i] ^= 1 << rng.randrange(8)
    dst.write_bytes(bytes(data))
    return dst


def _cli(
    args: list[str], timeout: float, env: dict[str, str] | None = None
) -> subprocess.CompletedProcess[str]:
    """Run ``uasnav ARGS`` in a subprocess; a run past ``timeout`` fails the test (a hang)."""
    full_env = {**os.environ, **(env or {})}
    return subprocess.run(
        [sys.executable, "-c", _ENTRY, *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=full_env,
    )


_ENTRY = "import sys; from uasnav.cli import main; sys.exit(main())"


# -- 1. decoder runaways ---------------------------------------------------------------------


def test_a_tlog_of_flipped_bits_is_decoded_in_bounded_work(tmp_path: Path) -> None:
    """10 000 flipped bits in a 1.2 MB tlog: pymavlink's byte-wise resync and its seeks back to
    every indexed message made this a ten-minute read; the pass is now bounded by the file size."""
    from uasnav.io._mavlink import scan_file

    bad = _flipped(TLOG, tmp_path / "bad.tlog", 10_000)
    before = bad.read_bytes()
    t0 = time.perf_counter()
    msgs, decoder = scan_file(bad, ["RAW_IMU", "SCALED_PRESSURE", "GPS_RAW_INT", "ATTITUDE"])
    took = time.perf_counter() - t0
    assert decoder.problems and decoder.summary()
    assert len(msgs) > 0  # what decodes is kept
    assert bad.read_bytes() == before
    assert took < 120, took  # a hang detector (the bound is measured in the report), not a benchmark


def test_the_bounded_reader_stops_at_its_budget(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import uasnav.io._mavlink as mv

    monkeypatch.setattr(mv, "SCAN_BYTES_PER_FILE_BYTE", 0)
    monkeypatch.setattr(mv, "SCAN_SLACK", 4096)
    msgs, decoder = mv.scan_file(TLOG, ["RAW_IMU"])
    assert len(msgs) < 100  # stopped after about 4 KiB of the file
    assert "decoding stopped at byte" in decoder.summary()
    assert "too corrupt to resynchronise" in decoder.summary()


def test_block_resync_matches_pymavlink_on_the_clean_log() -> None:
    """The block timestamp search decodes a clean log exactly as pymavlink does."""
    from pymavlink import mavutil

    from uasnav.io._mavlink import scan_file

    ref = mavutil.mavlink_connection(str(TLOG))
    want = []
    while (m := ref.recv_match(type=["GPS_RAW_INT"])) is not None:
        want.append((m._timestamp, m.lat, m.lon))
    got, _ = scan_file(TLOG, ["GPS_RAW_INT"])
    assert [(m._timestamp, m.lat, m.lon) for m in got] == want


def test_allan_on_a_corrupt_tlog_ends_quickly(tmp_path: Path) -> None:
    bad = _flipped(TLOG, tmp_path / "bad.tlog", 10_000)
    res = _cli(["allan", str(bad), "--json"], timeout=240)
    assert res.returncode in (0, 1), res.stderr
    assert "Traceback" not in res.stderr
    if res.returncode == 1:
        assert len(res.stderr.strip().splitlines()) == 1 and res.stderr.startswith("error: ")


def test_fleet_has_a_log_timeout() -> None:
    res = CliRunner().invoke(main, ["fleet", "scan", "--help"])
    assert "--log-timeout" in res.output
    res = CliRunner().invoke(main, ["fleet", "scan", "x", "--out", "o.parquet", "--log-timeout", "0"])
    assert res.exit_code == 2


def test_the_per_log_deadline_stops_a_python_loop() -> None:
    from uasnav.fleet.runner import LogTimeout, _deadline

    t0 = time.perf_counter()
    with pytest.raises(LogTimeout), _deadline(0.2):
        while True:
            pass
    assert time.perf_counter() - t0 < 30
    with _deadline(5.0):  # a block that ends in time is untouched, and nothing fires later
        pass
    time.sleep(0.05)


# -- 2. YAML bombs -----------------------------------------------------------------------------

_LAUGHS = "\n".join(
    ["a0: &a0 [lol, lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    + [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 10)}]" for i in range(1, 9)]
    + ["intents: *a8"]
)


def test_a_billion_laughs_intent_file_is_refused_before_expansion(tmp_path: Path) -> None:
    p = tmp_path / "bomb.yaml"
    p.write_text(_LAUGHS)
    t0 = time.perf_counter()
    res = CliRunner().invoke(main, ["utm", "deconflict", str(p)])
    line = _one_error_line(res)
    assert "aliases expand to more than" in line and "bomb.yaml" in line
    assert time.perf_counter() - t0 < 30


def test_deeply_nested_yaml_is_one_line(tmp_path: Path) -> None:
    p = tmp_path / "deep.yaml"
    p.write_text("intents: " + "[" * 5000 + "]" * 5000 + "\n")
    line = _one_error_line(CliRunner().invoke(main, ["utm", "deconflict", str(p)]))
    assert "nested deeper than" in line and "internal error" not in line
    q = tmp_path / "deep_block.yaml"
    q.write_text("intents:\n" + "".join(" " * i + "- \n" for i in range(1, 400)))
    line = _one_error_line(CliRunner().invoke(main, ["utm", "deconflict", str(q)]))
    assert "internal error" not in line


def test_a_small_shared_alias_is_still_fine() -> None:
    from uasnav.io.interuss import load_yaml

    assert load_yaml("a: &x {k: 1}\nb: *x\nc: *x\n", "t.yaml") == {
        "a": {"k": 1},
        "b": {"k": 1},
        "c": {"k": 1},
    }
    with pytest.raises(DataFormatError, match="not valid YAML"):
        load_yaml("a: [", "t.yaml")


# -- 3. limits from the environment ------------------------------------------------------------


@pytest.mark.parametrize("var", ["UASNAV_MAX_WORK", "UASNAV_MAX_MEMORY"])
@pytest.mark.parametrize("value", ["abc", "-1", "0", "nan", "inf", ""])
def test_an_invalid_limit_is_refused_in_one_line(var: str, value: str) -> None:
    res = CliRunner(env={var: value}).invoke(main, ["simulate", "--help"])
    assert res.exit_code == 0  # --help needs no limit
    res = CliRunner(env={var: value}).invoke(
        main, ["simulate", "--profile", "static", "--duration", "1", "--out", "never.csv"]
    )
    line = _one_error_line(res)
    assert var in line and repr(value) in line


def test_allan_honours_the_work_limit(tmp_path: Path) -> None:
    import numpy as np

    p = tmp_path / "imu.csv"
    t = np.arange(20_000) / 100.0
    rows = "\n".join(f"{x:.2f},0,0,0,0,0,9.81" for x in t)
    p.write_text("t,gx,gy,gz,ax,ay,az\n" + rows + "\n")
    res = CliRunner(env={"UASNAV_MAX_WORK": "1000"}).invoke(main, ["allan", str(p), "--taus", "all"])
    line = _one_error_line(res)
    assert "UASNAV_MAX_WORK" in line and "operations" in line


def test_simulated_runs_are_refused_up_front_with_their_estimate(tmp_path: Path) -> None:
    from uasnav.errors import ResourceLimitError
    from uasnav.trajectory.calibration import simulated_route_runs, simulated_runs

    for fn in (simulated_runs, simulated_route_runs):
        with pytest.raises(ResourceLimitError, match=r"100000 simulated calibration runs needs about 4e\+12"):
            fn(None, 100_000)  # type: ignore[arg-type]
    model = tmp_path / "m.json"
    model.write_text("{}")
    out = tmp_path / "o.json"
    t0 = time.perf_counter()
    res = CliRunner().invoke(
        main, ["trajectory", "calibrate", "--model", str(model), "--runs", "100000", "--out", str(out)]
    )
    line = _one_error_line(res)
    assert "--runs + --test-runs" in line and "UASNAV_MAX_WORK" in line
    assert not out.exists() and time.perf_counter() - t0 < 30


def test_fleet_simulate_is_refused_up_front_with_its_estimate(tmp_path: Path) -> None:
    out = tmp_path / "fleet"
    res = CliRunner().invoke(
        main,
        [
            "fleet",
            "simulate",
            "--vehicles",
            "100",
            "--flights",
            "1",
            "--nav-flights",
            "100",
            "--out",
            str(out),
        ],
    )
    line = _one_error_line(res)
    assert "100 GNSS/INS flight(s) needs about" in line and "--nav-flights" in line
    assert not out.exists()


# -- 5. FIFOs and special files ----------------------------------------------------------------


def _fifo(tmp_path: Path, name: str) -> Path:
    p = tmp_path / name
    os.mkfifo(p)
    return p


@pytest.mark.parametrize(
    "args",
    [
        ["allan", "{fifo}"],
        ["zupt", "{fifo}"],
        ["calibrate", "{fifo}"],
        ["utm", "deconflict", "{fifo}"],
        ["trajectory", "predict", "--model", "{fifo}", "--plan", "{fifo}", "--wind", "0@0"],
    ],
)
def test_a_fifo_input_is_refused_before_opening(tmp_path: Path, args: list[str]) -> None:
    fifo = _fifo(tmp_path, "in.csv")
    argv = [a.replace("{fifo}", str(fifo)) for a in args]
    done: list[object] = []
    th = threading.Thread(target=lambda: done.append(CliRunner().invoke(main, argv)), daemon=True)
    th.start()
    th.join(timeout=30)
    if th.is_alive():  # unblock the reader so the test process can end, then fail
        with open(fifo, "wb"):
            pass
        pytest.fail(f"{argv} blocked on a FIFO")
    line = _one_error_line(done[0])
    assert "FIFO" in line and str(fifo) in line


def test_fleet_skips_a_fifo_among_the_logs_with_a_warning(tmp_path: Path) -> None:
    from uasnav.fleet.sources import discover

    (tmp_path / "logs").mkdir()
    _fifo(tmp_path / "logs", "stuck.ulg")
    (tmp_path / "logs" / "a.csv").write_text("t,gx,gy,gz,ax,ay,az\n0,0,0,0,0,0,9.81\n")
    with pytest.warns(UserWarning, match="stuck.ulg: a FIFO"):
        found = discover([tmp_path / "logs"])
    assert [Path(f).name for f in found] == ["a.csv"]


def test_check_input_file() -> None:
    from uasnav.limits import check_input_file

    check_input_file("/nonexistent/x")  # left to the reader
    check_input_file(__file__)
    with pytest.raises(InputError):
        import tempfile

        with tempfile.TemporaryDirectory() as d:
            check_input_file(_fifo(Path(d), "p"))


# -- 7. one line for a failed run --------------------------------------------------------------


def test_warnings_of_a_failed_run_fold_into_its_error_line() -> None:
    import warnings

    import click

    from uasnav.cli import _Group

    @click.group(cls=_Group)
    def grp() -> None:
        pass

    @grp.command()
    def bad() -> None:
        warnings.warn("corrupt data skipped", stacklevel=1)
        raise InputError("the input is wrong")

    @grp.command()
    def good() -> None:
        warnings.warn("corrupt data skipped", stacklevel=1)

    line = _one_error_line(CliRunner().invoke(grp, ["bad"]))
    assert line == "error: the input is wrong (warnings: corrupt data skipped)"
    res = CliRunner().invoke(grp, ["good"])
    assert res.exit_code == 0 and res.stderr.strip() == "warning: corrupt data skipped"


def test_a_failed_command_changes_no_output(tmp_path: Path) -> None:
    """Every command's outputs are one set: the first file of a command that fails on its second
    (``trajectory intent --out i.json --geojson BAD``) is not written and the old one is kept."""
    import click

    from uasnav.atomicfile import atomic_write_text
    from uasnav.cli import _Group, _guarded

    @click.group(cls=_Group)
    def grp() -> None:
        pass

    @grp.command()
    @click.option("--out")
    @click.option("--geojson")
    def two(out: str, geojson: str) -> None:
        atomic_write_text(out, "new\n")
        atomic_write_text(geojson, "{}\n")

    _guarded(grp)
    first = tmp_path / "i.json"
    first.write_text("old\n")
    bad = tmp_path / "x.geojson"
    bad.mkdir()  # a directory where the second file should go
    line = _one_error_line(CliRunner().invoke(grp, ["two", "--out", str(first), "--geojson", str(bad)]))
    assert "x.geojson" in line
    assert first.read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["i.json", "x.geojson"]  # nothing staged left
    res = CliRunner().invoke(grp, ["two", "--out", str(first), "--geojson", str(tmp_path / "ok.geojson")])
    assert res.exit_code == 0 and first.read_text() == "new\n"


@pytest.mark.parametrize(
    "args,needle",
    [
        (["db", "validate", "http://[::1"], "not a valid URL"),
        (["simulate", "--profile", "flight", "--duration", "1e308", "--out", "{tmp}/x.csv"], "range"),
    ],
)
def test_internal_errors_become_input_errors(tmp_path: Path, args: list[str], needle: str) -> None:
    argv = [a.replace("{tmp}", str(tmp_path)) for a in args]
    line = _one_error_line(CliRunner().invoke(main, argv))
    assert needle in line and "internal error" not in line
    assert not (tmp_path / "x.csv").exists()


def test_an_outage_sweep_of_thousands_is_refused_up_front() -> None:
    from types import SimpleNamespace

    import numpy as np

    from uasnav.errors import ResourceLimitError
    from uasnav.ins.evaluate import outage_experiment

    flight = SimpleNamespace(imu=SimpleNamespace(t=np.zeros(60_000)), gnss=SimpleNamespace(t=np.arange(2.0)),
                             airborne=(0.0, 600.0))  # fmt: skip
    with pytest.raises(ResourceLimitError, match=r"outage sweep of 5000 duration\(s\) × 5 start\(s\)"):
        outage_experiment(flight, list(np.linspace(1, 100, 5000)))  # type: ignore[arg-type]


# -- 8/9. silent answers and the Python API's limits --------------------------------------------


def test_drift_of_a_huge_duration_is_refused_in_the_api() -> None:
    from uasnav.attitude import drift
    from uasnav.errors import ResourceLimitError

    with pytest.raises(ResourceLimitError, match="attitude drift over 1e\\+09 s"):
        drift([1e-5, 0, 0], 0.01, 1e9)
    assert drift([1e-5, 0, 0], 0.01, 10.0).theta.shape == (1000,)


def test_quantities_beyond_the_float_range_are_refused() -> None:
    from uasnav.units import parse_quantity

    with pytest.raises(InputError, match="not a finite quantity"):
        parse_quantity("1e999 m", "m")
    with pytest.raises(InputError, match="not a finite quantity"):
        parse_quantity("1e308 km", "m")


def test_an_output_name_ending_in_a_separator_is_a_usage_error(tmp_path: Path) -> None:
    out = str(tmp_path / "m.json") + "/"
    res = CliRunner().invoke(main, ["simulate", "--profile", "static", "--duration", "1", "--out", out])
    assert res.exit_code == 2 and "names a directory" in res.stderr
    assert not (tmp_path / "m.json").exists()
