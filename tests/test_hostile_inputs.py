"""Hostile inputs, second pass: corrupt telemetry, YAML bombs, bad limits, FIFOs, failed runs.

Every probe builds its input here (nothing large is committed) and pins the CLI contract: exit
1 or 2 with exactly one ``error:`` line (warnings of the failed run folded into it), no input
changed, and a bounded run: a probe that used to hang is run in a subprocess with a deadline
far above its expected time, so a regression fails instead of stalling CI.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import random
import re
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

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


def _native_sleep(seconds: float) -> str:
    """A call the interpreter cannot interrupt from inside the process (C code, no bytecode)."""
    time.sleep(seconds)
    return "finished"


def _fails(_: object) -> None:
    raise InputError("x.tlog: a bad log")


def test_the_per_log_deadline_kills_a_native_call() -> None:
    from uasnav.fleet.deadline import LogTimeout, call_with_deadline

    t0 = time.perf_counter()
    with pytest.raises(LogTimeout):
        call_with_deadline(_native_sleep, 60.0, 1.0)
    assert time.perf_counter() - t0 < 30  # killed at 1 s (plus the child's start), not after 60 s
    # the next call gets a new process; values and exceptions travel back
    assert call_with_deadline(_native_sleep, 0.0, 30.0) == "finished"
    with pytest.raises(InputError, match="a bad log"):
        call_with_deadline(_fails, None, 30.0)


def _slow_or_quick(path: str) -> object:
    from uasnav.fleet.runner import LogRows

    if "slow" in os.path.basename(path):
        time.sleep(120)  # one native call far past the deadline
    return LogRows([{"n": 1}], vehicle="V1", day="2026-01-01")


@pytest.mark.parametrize("workers", [0, 1])
def test_a_log_past_its_deadline_is_killed_and_the_run_goes_on(tmp_path: Path, workers: int) -> None:
    import pyarrow as pa

    from uasnav.fleet import Analysis, read_errors, run
    from uasnav.fleet.output import MANIFEST

    logs = tmp_path / "logs"
    logs.mkdir()
    for name in ("a_slow.csv", "b_quick.csv"):
        (logs / name).write_text(name)
    out = tmp_path / "out.parquet"
    analysis = Analysis("probe", pa.schema([pa.field("n", pa.int64())]), _slow_or_quick)
    t0 = time.perf_counter()
    s = run(analysis, [str(logs)], str(out), workers=workers, log_timeout_s=2.0)
    assert time.perf_counter() - t0 < 90  # bounded: the 120 s sleep was killed
    assert (s.n_ok, s.n_errors, s.n_timeouts) == (1, 1, 1)
    errors = read_errors(out).to_pylist()
    assert [e["error_type"] for e in errors] == ["LogTimeout"]
    assert "a_slow.csv" in errors[0]["error"] and "--log-timeout" in errors[0]["error"]
    entries = [json.loads(line) for line in (out / MANIFEST).read_text().splitlines()]
    status = {Path(e["path"]).name: e["status"] for e in entries}
    assert status == {"a_slow.csv": "timeout", "b_quick.csv": "ok"}


def test_fleet_stops_a_long_real_log_at_its_deadline(tmp_path: Path) -> None:
    """A 2 MB compressed log of 10⁶ samples (seconds of IMU analysis, mostly in the Rust core)
    beside a small one: ``--log-timeout 1`` stops the first, the second is written."""
    import numpy as np

    logs = tmp_path / "logs"
    logs.mkdir()
    for name, n in (("long.npz", 1_000_000), ("short.npz", 20_000)):
        accel = np.zeros((n, 3))
        accel[:, 2] = -9.80665
        np.savez_compressed(
            logs / name, t=np.arange(n) / 100.0, gyro=np.zeros((n, 3)), accel=accel,
            meta_json=np.array("{}"), format=np.array("uasnav-npz/1"),
        )  # fmt: skip
    out = tmp_path / "health.parquet"
    t0 = time.perf_counter()
    args = ["fleet", "imu-health", str(logs), "--out", str(out), "--workers", "0", "--log-timeout", "1"]
    res = _cli([*args, "--json"], timeout=240)
    assert res.returncode == 0, res.stderr
    assert time.perf_counter() - t0 < 240
    summary = json.loads(res.stdout)
    assert (summary["ok"], summary["errors"], summary["timeouts"]) == (1, 1, 1), summary
    assert "long.npz" in summary["error_list"][0]["error"]
    assert "per-log deadline of 1 s" in summary["error_list"][0]["error"]


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


@pytest.mark.parametrize(
    "var,value", [("UASNAV_MAX_WORK", "nan"), ("UASNAV_MAX_MEMORY", "-1"), ("UASNAV_MAX_WORK", "")]
)
@pytest.mark.parametrize(
    "args",
    [["allan", "{imu}", "--taus", "all"],
     ["fleet", "scan", "{imu}", "--out", "{tmp}/o.parquet", "--workers", "0"],
     ["trajectory", "predict", "--model", "{imu}", "--plan", "{imu}", "--wind", "0@0"]],
    ids=["allan", "fleet", "predict"],
)  # fmt: skip
def test_every_command_refuses_an_invalid_limit_before_working(
    tmp_path: Path, args: list[str], var: str, value: str
) -> None:
    imu = _imu_csv(tmp_path / "imu.csv")
    argv = [a.replace("{imu}", str(imu)).replace("{tmp}", str(tmp_path)) for a in args]
    line = _one_error_line(CliRunner(env={var: value}).invoke(main, argv))
    assert line.startswith(f"error: {var}: expected a ") and repr(value) in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["imu.csv"]


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
        (["simulate", "--profile", "flight", "--duration", "1e308", "--out", "{tmp}/x.csv"], "--duration"),
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


# -- 4. internal errors that are input errors (second pass) -------------------------------------

_GNSS_HEADER = "t,lat,lon,alt,vn,ve,vd,h_acc,v_acc,s_acc\n"


def _imu_csv(p: Path, n: int = 600) -> Path:
    p.write_text("t,gx,gy,gz,ax,ay,az\n" + "".join(f"{i / 100:.2f},0,0,0,0,0,9.81\n" for i in range(n)))
    return p


def _gnss_csv(p: Path, lon: str = "8.0", alt: str = "400") -> Path:
    rows = "".join(f"{i / 5:.1f},47.0,{lon},{alt},0,0,0,1,1,0.1\n" for i in range(30))
    p.write_text(_GNSS_HEADER + rows)
    return p


def _unchanged(paths: list[Path]) -> dict[Path, bytes]:
    return {p: p.read_bytes() for p in paths}


@pytest.mark.parametrize(
    "make,needle",
    [
        (lambda p: p.write_text(_GNSS_HEADER), "no fixes (a header only)"),
        (lambda p: _gnss_csv(p, lon="1000"), "gnss.lon: 1000° is outside -180…360° at row 0"),
        (lambda p: _gnss_csv(p, alt="1e308"), "gnss.alt: 1e+308 m is beyond ±100000 m at row 0"),
    ],
)
def test_a_bad_gnss_csv_is_one_line_naming_the_file(tmp_path: Path, make, needle: str) -> None:  # type: ignore[no-untyped-def]
    imu = _imu_csv(tmp_path / "imu.csv")
    gnss = tmp_path / "gnss.csv"
    make(gnss)
    before = _unchanged([imu, gnss])
    out = tmp_path / "track.csv"
    res = CliRunner().invoke(main, ["nav", str(imu), "--gnss", str(gnss), "--out", str(out)])
    line = _one_error_line(res)
    assert needle in line and "gnss.csv" in line, line
    assert _unchanged([imu, gnss]) == before and not out.exists()


def test_a_parquet_of_another_schema_is_not_an_element_dataset(tmp_path: Path) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    from uasnav.trajectory.element_table import ELEMENT_SCHEMA

    wrong = tmp_path / "wrong.parquet"
    pq.write_table(pa.table({"a": [1, 2], "b": ["x", "y"]}), wrong)
    texts = tmp_path / "texts.parquet"
    pq.write_table(pa.table({f.name: pa.array(["x", "y"]) for f in ELEMENT_SCHEMA}), texts)
    out = tmp_path / "m.json"
    line = _one_error_line(CliRunner().invoke(main, ["trajectory", "train", str(wrong), "--out", str(out)]))
    assert "wrong.parquet: not an element dataset: missing column(s) run, element" in line
    line = _one_error_line(CliRunner().invoke(main, ["trajectory", "train", str(texts), "--out", str(out)]))
    assert "texts.parquet: column 'run' is string, expected int32" in line
    assert not out.exists()


@pytest.mark.parametrize(
    "mounting,needle",
    [
        ("[[1,0", "is not a 3×3 JSON matrix"),
        ('{"a": 1}', "is not a 3×3 JSON matrix"),
        ("[[1,0,0],[0,1,0]]", "got shape (2, 3)"),
        ("[[1e999,0,0],[0,1,0],[0,0,1]]", "non-finite entries"),
        ("[" * 3000 + "]" * 3000, "is not a 3×3 JSON matrix"),
    ],
)
def test_a_malformed_mounting_comment_is_one_line(tmp_path: Path, mounting: str, needle: str) -> None:
    body = _imu_csv(tmp_path / "body.csv", 200).read_text()
    bad = tmp_path / "s1.csv"
    bad.write_text(f"# mounting: {mounting}\n" + body)
    good = tmp_path / "s2.csv"
    good.write_text("# mounting: [[1,0,0],[0,1,0],[0,0,1]]\n" + body)
    out = tmp_path / "fused.csv"
    res = CliRunner().invoke(
        main, ["redundancy", "fuse", "--shape", "meta", str(bad), str(good), str(good), "--out", str(out)]
    )
    line = _one_error_line(res)
    assert "s1.csv: '# mounting:'" in line and needle in line, line
    assert not out.exists()


@pytest.mark.parametrize(
    "text,needle",
    [
        ("", "not a preset: not valid JSON"),
        ("[1, 2]", "not a preset: expected a JSON object, got list"),
        ('{"a":' * 3000 + "1" + "}" * 3000, "nested deeper than 64 levels"),
    ],
)
@pytest.mark.parametrize("profile", ["static", "flight"])
def test_a_bad_preset_json_is_one_line(tmp_path: Path, text: str, needle: str, profile: str) -> None:
    preset = tmp_path / "p.json"
    preset.write_text(text)
    out = tmp_path / "s.csv"
    res = CliRunner().invoke(
        main,
        ["simulate", "--preset", str(preset), "--profile", profile, "--duration", "1", "--out", str(out)],
    )
    line = _one_error_line(res)
    assert "p.json" in line and needle in line, line
    assert not out.exists() and preset.read_text() == text


def _area(tmp_path: Path, ring: list[list[float]]) -> Path:
    import json

    p = tmp_path / "area.geojson"
    p.write_text(json.dumps({"type": "Polygon", "coordinates": [ring]}))
    return p


ZONES = DATA / "utm" / "interuss_ed269_geozone_sample.json"


@pytest.mark.parametrize(
    "ring", [[[8.0, 47.0], [8.01, 47.0]], [[8.0, 47.0], [8.01, 47.0], [8.0, 47.0]]], ids=["two", "closed-two"]
)
def test_a_two_point_area_with_zones_is_a_usage_error(tmp_path: Path, ring: list[list[float]]) -> None:
    res = CliRunner().invoke(main, ["select", "--area", str(_area(tmp_path, ring)), "--zones", str(ZONES)])
    assert res.exit_code == 2, res.output
    assert "a polygon ring needs at least 3 distinct corners, got 2" in res.stderr
    assert "Traceback" not in res.output and "internal error" not in res.output


def test_an_unclosed_area_ring_is_closed_with_a_warning(tmp_path: Path) -> None:
    from uasnav.mission.zones import parse_area

    ring = [[8.0, 47.0], [8.01, 47.0], [8.01, 47.01], [8.0, 47.01]]
    with pytest.warns(UserWarning, match=r"area.coordinates\[0\]: polygon ring not closed"):
        area = parse_area({"type": "Polygon", "coordinates": [ring]})
    closed = parse_area({"type": "Polygon", "coordinates": [[*ring, ring[0]]]})
    assert area.parts == closed.parts


def _fleet_with_manifest(tmp_path: Path) -> tuple[Path, Path]:
    logs = tmp_path / "logs"
    logs.mkdir()
    _imu_csv(logs / "a.csv", 300)
    out = tmp_path / "scan.parquet"
    res = CliRunner().invoke(main, ["fleet", "scan", str(logs), "--out", str(out), "--workers", "0"])
    assert res.exit_code == 0, res.output
    return logs, out


@pytest.mark.parametrize(
    "extra,needle",
    [
        ("junk\n", "line 2: corrupt manifest line"),
        ("[" * 100_000 + "]" * 100_000 + "\n", "nested deeper than 64 levels"),
        ("[1, 2]\n", "expected a JSON object, got list"),
        ('{"path": [1], "size": 1, "mtime_ns": 1, "log_hash": "h", "table": "scan", "status": "ok"}\n',
         "path: [1] is not of the expected type"),
        ('{"path": "p", "size": "x", "mtime_ns": 1, "log_hash": "h", "table": "scan", "status": "ok"}\n',
         'size: "x" is not of the expected type'),
    ],
)  # fmt: skip
def test_fleet_resume_refuses_a_junk_manifest_in_one_line(tmp_path: Path, extra: str, needle: str) -> None:
    logs, out = _fleet_with_manifest(tmp_path)
    manifest = out / "_manifest.jsonl"
    manifest.write_text(manifest.read_text() + extra + "{}\n")  # not the last line: not a torn write
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    res = CliRunner().invoke(
        main, ["fleet", "scan", str(logs), "--out", str(out), "--workers", "0", "--resume"]
    )
    line = _one_error_line(res)
    assert "_manifest.jsonl" in line and needle in line, line
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before


def test_fleet_resume_with_another_analysis_is_refused(tmp_path: Path) -> None:
    logs, out = _fleet_with_manifest(tmp_path)
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    res = CliRunner().invoke(
        main, ["fleet", "imu-health", str(logs), "--out", str(out), "--workers", "0", "--resume"]
    )
    line = _one_error_line(res)
    assert "a dataset of scan, not imu_health" in line
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before


@pytest.mark.parametrize(
    "args,needle",
    [
        (["--scheduler", "xyz://"], "unknown address scheme 'xyz'"),
        (["--scheduler-file", "{garbage}"], "not a Dask scheduler file"),
        (["--scheduler-file", "{noaddress}"], "expected an address like tcp://HOST:8786"),
    ],
)
def test_fleet_refuses_a_bad_scheduler_in_one_line(tmp_path: Path, args: list[str], needle: str) -> None:
    (tmp_path / "garbage.json").write_text("garbage\n")
    (tmp_path / "noaddress.json").write_text('{"address": 5}\n')
    logs = tmp_path / "logs"
    logs.mkdir()
    _imu_csv(logs / "a.csv", 100)
    out = tmp_path / "o.parquet"
    argv = [a.format(garbage=tmp_path / "garbage.json", noaddress=tmp_path / "noaddress.json") for a in args]
    line = _one_error_line(CliRunner().invoke(main, ["fleet", "scan", str(logs), "--out", str(out), *argv]))
    assert needle in line, line
    assert not out.exists()


# -- 5. slow peers (loopback) ------------------------------------------------------------------


class _Loopback:
    """A TCP server on 127.0.0.1 that accepts and then, per connection, either says nothing
    (not a Dask scheduler) or answers an HTTP request one byte per second; it stops by itself."""

    def __init__(self, mode: str, lifetime_s: float = 60.0) -> None:
        import socket

        self.mode, self.end = mode, time.monotonic() + lifetime_s
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.sock.settimeout(0.2)
        self.port = self.sock.getsockname()[1]
        self.conns: list[object] = []
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while time.monotonic() < self.end:
            try:
                c, _ = self.sock.accept()
            except OSError:
                continue
            self.conns.append(c)
            if self.mode == "drip":
                threading.Thread(target=self._drip, args=(c,), daemon=True).start()
        self.close()

    def _drip(self, c) -> None:  # type: ignore[no-untyped-def]
        try:
            c.recv(65536)
            c.sendall(b"HTTP/1.1 200 OK\r\nContent-Length: 1000000\r\n\r\n")
            while time.monotonic() < self.end:
                c.sendall(b"x")
                time.sleep(1.0)
        except OSError:
            pass

    def close(self) -> None:
        self.end = 0.0
        for c in [self.sock, *self.conns]:
            with contextlib.suppress(OSError):
                c.close()  # type: ignore[attr-defined]


def test_a_port_that_never_speaks_dask_is_refused_within_the_deadline(tmp_path: Path) -> None:
    from uasnav.fleet.runner import check_scheduler

    srv = _Loopback("silent")
    try:
        t0 = time.monotonic()
        with pytest.raises(InputError, match=r"no Dask scheduler answered within 1 s"):
            check_scheduler(f"tcp://127.0.0.1:{srv.port}", timeout_s=1.0)
        assert time.monotonic() - t0 < 30  # a hang detector; the deadline is 1 s
    finally:
        srv.close()


def test_a_slow_drip_url_in_a_fleet_list_is_bounded_by_the_log_timeout(tmp_path: Path) -> None:
    srv = _Loopback("drip")
    try:
        urls = tmp_path / "logs.urls"
        urls.write_text(f"http://127.0.0.1:{srv.port}/a.ulg\n")
        out = tmp_path / "u.parquet"
        t0 = time.monotonic()
        res = CliRunner().invoke(
            main,
            ["fleet", "scan", str(urls), "--out", str(out), "--workers", "0", "--log-timeout", "2", "--json"],
        )
        assert time.monotonic() - t0 < 30
        assert res.exit_code == 0, res.output
        import json

        summary = json.loads(res.stdout)
        assert summary["errors"] == 1
        assert "no complete answer within the timeout of 2 s" in summary["error_list"][0]["error"]
    finally:
        srv.close()


# -- 7. progress lines end before the error line -------------------------------------------------


def test_a_fleet_progress_bar_ends_its_line_when_the_run_fails(monkeypatch: pytest.MonkeyPatch) -> None:
    import io

    from uasnav.cli.fleet import _progress

    class Tty(io.StringIO):
        def isatty(self) -> bool:
            return True

    err = Tty()
    monkeypatch.setattr(sys, "stderr", err)
    progress = _progress()
    progress(1, 4)  # the run fails here: the bar is left at 1/4
    assert not err.getvalue().endswith("\n")
    progress.close()  # type: ignore[attr-defined]
    assert err.getvalue().endswith("\n")


def test_a_progress_bar_then_an_error_is_one_clean_error_line(tmp_path: Path) -> None:
    """``trajectory calibrate`` shows its runs on a click progress bar: a failure inside it
    ends with the bar's line and then exactly one ``error:`` line, no library warning folded in."""
    import click

    from uasnav.cli import _Group

    @click.group(cls=_Group)
    def grp() -> None:
        pass

    @grp.command()
    def runs() -> None:
        with click.progressbar(length=10, label="simulated runs", file=sys.stderr) as bar:
            bar.update(3)
            raise InputError("run 4: the model diverged")

    res = CliRunner().invoke(grp, ["runs"])
    assert res.exit_code == 1
    assert res.stderr.endswith("\nerror: run 4: the model diverged\n"), repr(res.stderr)
    assert [ln for ln in res.stderr.splitlines() if ln.startswith("error")] == [
        "error: run 4: the model diverged"
    ]


def test_trajectory_progress_bars_use_no_deprecated_click_stream() -> None:
    src = (Path(__file__).resolve().parents[1] / "python" / "uasnav" / "cli" / "trajectory.py").read_text()
    assert "get_text_stream" not in src  # deprecated in click 8.2: its warning joined the error line


# -- 8. extreme speeds ----------------------------------------------------------------------------


@pytest.mark.parametrize("speed,needle", [("1e6", "1e6 is not <= 150"), ("1e-300", "1e-300 is not >= 0.1")])
@pytest.mark.parametrize(
    "cmd,option",
    [
        (["trajectory", "predict", "--wind", "0@0"], "--speed"),
        (["trajectory", "intent", "--wind", "0@0"], "--speed"),
        (["trajectory", "intent", "--wind", "0@0"], "--climb-rate"),
        (["trajectory", "intent", "--wind", "0@0"], "--descent-rate"),
    ],
)
def test_an_extreme_speed_is_a_usage_error(
    tmp_path: Path, cmd: list[str], option: str, speed: str, needle: str
) -> None:
    model = tmp_path / "m.json"
    model.write_text("{}")
    plan = tmp_path / "p.csv"
    plan.write_text("lat,lon,alt\n47,8,50\n47.001,8,50\n")
    res = CliRunner().invoke(main, [*cmd, "--model", str(model), "--plan", str(plan), option, speed])
    assert res.exit_code == 2 and needle in res.stderr, res.output


# -- 8. silent wrong answers -----------------------------------------------------------------------


def test_the_link_range_is_tested_against_the_pilot_distance() -> None:
    """A Phantom 4 Pro's link does not reach 50 km: --max-distance, not only --range, is what the
    C2 link must cover."""
    res = CliRunner().invoke(main, ["select", "--max-distance", "50000", "--json"])
    assert res.exit_code == 0, res.output
    import json

    out = json.loads(res.stdout)
    text = json.dumps(out)
    assert "link-range" in text
    feasible = out.get("feasible_uas") or out.get("feasible") or []
    assert not any("Phantom 4 Pro" in json.dumps(u) for u in feasible)


@pytest.mark.parametrize(
    "args,needle",
    [
        (["--range", "1e-320"], "1e-320 is not >= 1"),
        (["--range", "1e308"], "1e308 is not <= 1e+06"),
        (["--max-distance", "1e308"], "1e308 is not <= 1e+06"),
    ],
)
def test_absurd_ranges_are_usage_errors(args: list[str], needle: str) -> None:
    res = CliRunner().invoke(main, ["select", *args])
    assert res.exit_code == 2 and needle in res.stderr, res.output


def test_limits_from_a_log_without_limits_is_refused(tmp_path: Path) -> None:
    empty = tmp_path / "empty.tlog"
    empty.write_bytes(b"")
    rnd = tmp_path / "random.bin"
    rnd.write_bytes(random.Random(3).randbytes(5000))
    model = tmp_path / "m.json"
    out = tmp_path / "i.json"
    res = CliRunner().invoke(
        main, ["trajectory", "train", str(TLOG), "--method", "kinematic", "--out", str(model)]
    )
    assert res.exit_code == 0, res.output
    plan = DATA / "missions" / "mavsdk_qgroundcontrol_sample.plan"
    for bad in (empty, rnd):
        res = CliRunner().invoke(
            main,
            ["trajectory", "intent", "--model", str(model), "--plan", str(plan), "--wind", "0@0",
             "--start", "2026-01-01T10:00:00Z", "--limits-from", str(bad), "--out", str(out)],
        )  # fmt: skip
        line = _one_error_line(res)
        assert f"--limits-from {bad}: no vehicle limits in this log" in line, line
        assert not out.exists()


def test_a_die_temperature_below_absolute_zero_is_refused(tmp_path: Path) -> None:
    p = tmp_path / "cold.csv"
    rows = "".join(f"{i / 100:.2f},0,0,0,0,0,9.81,{-300 if i == 50 else 25}\n" for i in range(300))
    p.write_text("t,gx,gy,gz,ax,ay,az,temp\n" + rows)
    line = _one_error_line(CliRunner().invoke(main, ["allan", str(p)]))
    assert "cold.csv: temp: -300 °C at row 50 is outside -273.15…1000 °C" in line


@pytest.mark.parametrize("kw", [{"window_s": -1.0}, {"window_s": float("nan")}, {"min_duration_s": -1.0}])
def test_detect_static_refuses_a_negative_or_nan_duration(kw: dict[str, float]) -> None:
    import numpy as np

    from uasnav.imu import ImuLog
    from uasnav.stationary import detect_static

    log = ImuLog(t=np.arange(500) / 100, gyro=np.zeros((500, 3)), accel=np.tile([0, 0, 9.81], (500, 1)))
    with pytest.raises(ValueError, match=next(iter(kw))):
        detect_static(log, **kw)


# -- 6. a plan's prediction work, estimated before it is accepted -----------------------------------


def _big_plan_csv(n: int) -> bytes:
    return ("north,east\n" + "".join(f"{(i % 2) * 50.0:.1f},{i * 10.0:.1f}\n" for i in range(n))).encode()


def test_the_web_refuses_a_plan_too_costly_to_predict_with_its_estimate() -> None:
    from uasnav.web.prediction import FieldError, read_uploaded_plan

    t0 = time.perf_counter()
    with pytest.raises(FieldError, match=r"plan: 100000 plan points need about 1\.5e\+10 operations") as e:
        read_uploaded_plan("big.csv", _big_plan_csv(100_000))
    assert e.value.field == "plan" and "split the plan" in str(e.value)
    assert time.perf_counter() - t0 < 30  # refused before any prediction
    assert read_uploaded_plan("small.csv", _big_plan_csv(50)).route_ne.shape == (50, 2)


def test_the_cli_estimates_a_prediction_before_running_it(tmp_path: Path) -> None:
    plan = tmp_path / "big.csv"
    plan.write_bytes(_big_plan_csv(1000))
    model = tmp_path / "m.json"
    model.write_text("{}")
    res = CliRunner(env={"UASNAV_MAX_WORK": "1e6"}).invoke(
        main, ["trajectory", "predict", "--model", str(model), "--plan", str(plan), "--wind", "0@0"]
    )
    line = _one_error_line(res)
    assert (
        "a prediction of 1000 plan points needs about 1.5e+08 operations" in line
        and "UASNAV_MAX_WORK" in line
    )


# -- 4. numbers at the edge of the range name their option -----------------------------------------


@pytest.fixture(scope="module")
def kinematic_model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    model = tmp_path_factory.mktemp("model") / "m.json"
    res = CliRunner().invoke(
        main, ["trajectory", "train", str(TLOG), "--method", "kinematic", "--out", str(model)]
    )
    assert res.exit_code == 0, res.output
    return model


def _hold_plan(tmp_path: Path, hold_s: str) -> Path:
    rows = [
        (0, 1, 0, 16, "0", 47.0, 8.0, 400),
        (1, 0, 3, 22, "0", 47.0, 8.0, 30),
        (2, 0, 3, 16, hold_s, 47.001, 8.0, 30),
        (3, 0, 3, 16, "0", 47.002, 8.0, 30),
    ]
    p = tmp_path / "hold.waypoints"
    lines = ["\t".join(map(str, (*r[:5], 0, 0, 0, *r[5:], 1))) for r in rows]
    p.write_text("QGC WPL 110\n" + "\n".join(lines) + "\n")
    return p


@pytest.mark.parametrize(
    "extra,plan_hold,needle",
    [
        (
            ["--start", "9999-12-31T23:59:59Z"],
            "0",
            "--start: '9999-12-31T23:59:59Z' is outside the years 1970–9000",
        ),
        (["--start", "2026-01-01T00:00:00Z"], "1e12", "a hold of 1e+12 s is beyond the 65535 s"),
    ],
)
def test_intent_times_beyond_the_calendar_name_their_cause(
    tmp_path: Path, kinematic_model: Path, extra: list[str], plan_hold: str, needle: str
) -> None:
    out = tmp_path / "i.json"
    plan = _hold_plan(tmp_path, plan_hold)
    args = ["trajectory", "intent", "--model", str(kinematic_model), "--plan", str(plan), "--wind", "0@0",
            "--out", str(out), *extra]  # fmt: skip
    t0 = time.perf_counter()
    line = _one_error_line(CliRunner().invoke(main, args))  # refused before the calibration runs
    assert needle in line and "representable range" not in line
    assert time.perf_counter() - t0 < 60
    assert not out.exists()
    ok = (
        CliRunner().invoke(main, [*args[:-2], "--start", "2026-01-01T00:00:00Z", "--calibration-runs", "20"])
        if plan_hold == "0"
        else None
    )
    assert ok is None or ok.exit_code == 0, ok.output if ok else ""


@pytest.mark.parametrize("now", ["0001-01-01T00:00:00Z", "0001-01-01T00:00:00+01:00", "9999-12-31T23:59:59Z"])
def test_deconflict_at_an_absurd_now_names_the_option(now: str) -> None:
    intents = DATA / "utm" / "interuss_flight_intents_conflicting.yaml"
    line = _one_error_line(CliRunner().invoke(main, ["utm", "deconflict", str(intents), "--now", now]))
    assert line == f"error: --now: {now!r} is outside the years 1970–9000"


@pytest.mark.parametrize(
    "cmd,option",
    [
        (["trajectory", "intent", "--wind", "0@0", "--start", "2026-01-01T00:00:00Z"], "--lateral-buffer"),
        (["trajectory", "intent", "--wind", "0@0", "--start", "2026-01-01T00:00:00Z"], "--vertical-buffer"),
        (
            ["utm", "deconflict", str(DATA / "utm" / "interuss_flight_intents_conflicting.yaml")],
            "--horizontal-buffer",
        ),
        (
            ["utm", "deconflict", str(DATA / "utm" / "interuss_flight_intents_conflicting.yaml")],
            "--vertical-buffer",
        ),
    ],
)
def test_a_buffer_of_1e308_is_a_usage_error(
    tmp_path: Path, kinematic_model: Path, cmd: list[str], option: str
) -> None:
    plan = _hold_plan(tmp_path, "0")
    extra = [] if cmd[0] == "utm" else ["--model", str(kinematic_model), "--plan", str(plan), "--out",
                                         str(tmp_path / "i.json")]  # fmt: skip
    res = CliRunner().invoke(main, [*cmd, *extra, option, "1e308"])
    assert res.exit_code == 2 and f"'{option}': 1e308 is not <= 100000" in res.stderr, res.output
    assert "GEOS" not in res.output and not (tmp_path / "i.json").exists()


def test_a_csv_cell_at_the_float_limit_names_the_file_and_sensor(tmp_path: Path) -> None:
    log = _imu_csv(tmp_path / "imu.csv", n=2000)
    lines = log.read_text().splitlines()
    cells = lines[500].split(",")
    cells[1] = "1.79e308"
    lines[500] = ",".join(cells)
    log.write_text("\n".join(lines) + "\n")
    before = log.read_bytes()
    line = _one_error_line(CliRunner().invoke(main, ["allan", str(log), "--json"]))
    assert line.startswith(f"error: {log}: gyro: ") and "not representable as a float" in line
    assert log.read_bytes() == before


@pytest.mark.parametrize(
    "where", [("layers", 0, "weights", 0, 0), ("layers", 1, "biases", 0), ("layers", 1, "weights", 0, 1)]
)
def test_thermal_network_weights_of_1e308_are_refused(tmp_path: Path, where: tuple[object, ...]) -> None:
    """A hidden weight of 1e308 saturates its tanh and the model still predicts finite numbers:
    silently a step function. The file is refused naming the value's JSON path."""
    import copy

    import numpy as np

    from uasnav.thermal import NeuralBiasModel, dumps_model, loads_model
    from uasnav.thermal.modelfile import ZEROS, file_checksum

    t = np.linspace(-10.0, 40.0, 200)
    b = np.stack([1e-3 * np.tanh((t - 15) / 10), 2e-4 * np.sin(t / 9), 3e-6 * (t - 5) ** 2], 1)
    d = json.loads(dumps_model(NeuralBiasModel(2, restarts=1, max_epochs=20).fit(t, b)))

    def signed(doc: dict) -> str:  # type: ignore[type-arg]
        doc = copy.deepcopy(doc)
        doc["checksum"] = {"algorithm": "sha256", "value": ZEROS}
        text = json.dumps(doc)
        return text.replace(ZEROS, file_checksum(text, ZEROS), 1)

    loads_model(signed(d), "m.json")  # the harness loads the file as trained
    node = d["models"][0]
    for k in where[:-1]:
        node = node[k]
    node[where[-1]] = 1e308
    path = "models[0]." + ".".join(f"{k}" if isinstance(k, str) else f"[{k}]" for k in where).replace(
        ".[", "["
    )
    with pytest.raises(
        DataFormatError, match=re.escape(f"m.json: {path}: 1e+308 is outside the accepted range")
    ):
        loads_model(signed(d), "m.json")


# -- 3. the kinematic profile is linear in the plan's points ---------------------------------------


def _kinematic_times_full_grid(plan, s0, s1, cruise, accel=1.0, ds=0.1, leg_speed=None):  # type: ignore[no-untyped-def]
    """The profile with every waypoint's ramp evaluated over the whole grid (quadratic work)."""
    import numpy as np

    p = np.asarray(plan, dtype=float)[:, :2]
    d = np.diff(p, axis=0)
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(d[:, 0], d[:, 1]))])
    total = float(np.hypot(*d.T).sum())  # as trajectory.geometry.plan_length sums it
    s = np.arange(0.0, total + ds, ds)
    s[-1] = min(s[-1], total)
    v_leg = np.full(d.shape[0], float(cruise)) if leg_speed is None else np.asarray(leg_speed, dtype=float)
    v = v_leg[np.clip(np.searchsorted(cum, s, side="right") - 1, 0, v_leg.size - 1)]
    for k in range(p.shape[0]):
        vk = 0.0
        if 0 < k < p.shape[0] - 1:
            c = d[k - 1] @ d[k] / (np.hypot(*d[k - 1]) * np.hypot(*d[k]))
            vk = min(v_leg[k - 1], v_leg[k]) * max(np.cos(np.arccos(np.clip(c, -1.0, 1.0)) / 2.0), 0.1)
        v = np.minimum(v, np.sqrt(vk**2 + 2.0 * accel * np.abs(s - cum[k])))
    tau = np.concatenate([[0.0], np.cumsum(2.0 * np.diff(s) / np.maximum(v[1:] + v[:-1], 1e-9))])
    return np.interp(s1, s, tau) - np.interp(s0, s, tau)


@pytest.mark.parametrize("seed", range(6))
def test_the_windowed_kinematic_profile_equals_the_full_grid(seed: int) -> None:
    import numpy as np

    from uasnav.trajectory.baselines import kinematic_times

    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 60))
    plan = np.cumsum(rng.uniform(-40, 40, (n, 2)) * rng.choice([0.05, 1.0, 5.0]), axis=0)
    legs = np.where(rng.random(n - 1) < 0.3, np.nan, rng.uniform(0.5, 20.0, n - 1))
    total = float(np.hypot(*np.diff(plan, axis=0).T).sum())
    s0 = np.sort(rng.uniform(0, total, 20))
    s1 = np.minimum(s0 + rng.uniform(0, total / 3, 20), total)
    cruise, accel = float(rng.uniform(1, 15)), float(rng.uniform(0.3, 4))
    got = kinematic_times(plan, s0, s1, cruise, accel, leg_speed_ms=legs)
    want = _kinematic_times_full_grid(
        plan, s0, s1, cruise, accel, leg_speed=np.where(np.isnan(legs), cruise, legs)
    )
    np.testing.assert_array_equal(got, want)  # the same numbers, bit for bit


# -- 8/9. the Python API: negative, NaN and infinite arguments (a table) ----------------------------


def _api_table() -> list[tuple[str, Any, str]]:
    import numpy as np

    from uasnav import allan, attitude, stationary, zupt
    from uasnav.imu import ImuLog
    from uasnav.io import open_log
    from uasnav.trajectory import baselines, route3d

    n = 2000
    rng = np.random.default_rng(0)
    log = ImuLog(t=np.arange(n) / 100.0, gyro=rng.normal(0, 1e-3, (n, 3)),
                 accel=rng.normal(0, 1e-2, (n, 3)) + [0, 0, -9.81])  # fmt: skip
    x = rng.normal(size=200)
    plan = np.array([[0.0, 0.0], [100.0, 0.0], [100.0, 100.0]])
    kin = lambda *a: lambda: baselines.kinematic_times(plan, np.zeros(1), np.full(1, 50.0), *a)  # noqa: E731
    nan, inf = math.nan, math.inf
    z = np.zeros((5, 3))
    cs, sd, ma, ct = allan.cluster_sizes, stationary.detect_static, zupt.moving_average, zupt.convergence_time
    return [
        ("allan.oadev rate -1", lambda: allan.oadev(x, -1.0), "rate: must be finite and > 0"),
        ("allan.oadev rate nan", lambda: allan.oadev(x, nan), "rate: must be finite and > 0"),
        ("allan.oadev rate inf", lambda: allan.oadev(x, inf), "rate: must be finite and > 0"),
        ("allan.oadev tau -1", lambda: allan.oadev(x, 1.0, [-1.0]), "cluster times must be finite and > 0"),
        ("allan.oadev tau nan", lambda: allan.oadev(x, 1.0, [nan]), "cluster times must be finite and > 0"),
        ("allan.oadev all-NaN data", lambda: allan.oadev(np.full(100, nan), 1.0), "non-finite value"),
        ("allan.oadev confidence 2", lambda: allan.oadev(x, 1.0, confidence=2.0), "confidence"),
        ("allan.oadev confidence nan", lambda: allan.oadev(x, 1.0, confidence=nan), "confidence"),
        ("allan.cluster_sizes n -1", lambda: cs(-1, 1.0, "octave"), "n: expected an integer"),
        ("allan.cluster_sizes rate 0", lambda: cs(100, 0.0, "octave"), "rate: must be finite"),
        ("allan.cluster_sizes rate nan", lambda: cs(100, nan, [1.0]), "rate: must be finite"),
        ("attitude.drift dt -1", lambda: attitude.drift([1e-3, 0, 0], -1.0, 10.0), "dt: must be finite"),
        ("attitude.drift duration -1", lambda: attitude.drift([1e-3, 0, 0], 0.01, -1.0), "duration"),
        ("attitude.drift duration inf", lambda: attitude.drift([1e-3, 0, 0], 0.01, inf), "duration"),
        ("attitude.drift NaN rate", lambda: attitude.drift([nan, 0, 0], 0.01, 1.0), "non-finite"),
        ("attitude.propagate dt nan", lambda: attitude.propagate([1, 0, 0, 0], np.zeros((5, 3)), nan), "dt"),
        ("attitude.propagate |q0| 2", lambda: attitude.propagate([2, 0, 0, 0], np.zeros((5, 3)), 0.01),
         "q0[0]: a quaternion of norm 2"),
        ("attitude.rotation_angle |q| 2", lambda: attitude.rotation_angle([2, 0, 0, 0]), "norm 2, not a"),
        ("attitude.quat_to_euler |q| 1.1", lambda: attitude.quat_to_euler([[1, 0, 0, 0], [1.1, 0, 0, 0]]),
         "q[1]: a quaternion of norm 1.1"),
        ("attitude.quat_to_dcm NaN", lambda: attitude.quat_to_dcm([nan, 0, 0, 0]), "non-finite"),
        ("attitude.euler_to_quat inf", lambda: attitude.euler_to_quat([inf, 0, 0]), "non-finite"),
        ("stationary window -1", lambda: sd(log, window_s=-1.0), "window_s"),
        ("stationary threshold -1", lambda: sd(log, threshold=-1.0), "threshold: must be"),
        ("stationary threshold inf", lambda: sd(log, threshold=inf), "threshold: must be"),
        ("stationary sigma_a -1", lambda: sd(log, sigma_a=-1.0), "sigma_a"),
        ("stationary min_duration -1", lambda: sd(log, min_duration_s=-1.0), "min_duration"),
        ("stationary false_alarm 2", lambda: sd(log, false_alarm=2.0), "false_alarm"),
        ("zupt.moving_average rate -1", lambda: ma(np.ones((10, 3)), -1.0), "rate_hz"),
        ("zupt.moving_average window nan", lambda: ma(np.ones((10, 3)), 100.0, nan), "window_s"),
        ("zupt.convergence_time threshold -1", lambda: ct(np.arange(5.0), z, z, -1.0), "threshold"),
        ("io.open_log missing", lambda: open_log("/nonexistent/x.ulg").imus, "no such file"),
        ("io.open_log unknown view", lambda: open_log(str(BIN), need=("bogus",)), "unknown view 'bogus'"),
        ("trajectory kinematic cruise -1", kin(-1.0), "cruise_ms: must be finite and > 0"),
        ("trajectory kinematic cruise nan", kin(nan), "cruise_ms: must be finite and > 0"),
        ("trajectory kinematic accel 0", kin(5.0, 0.0), "accel_ms2: must be finite and > 0"),
        ("trajectory kinematic step -1", kin(5.0, 1.0, -1.0), "ds_m: must be finite and > 0"),
        ("trajectory kinematic step 1e-9", kin(5.0, 1.0, 1e-9), "raise the limit with UASNAV_MAX_MEMORY"),
        ("trajectory vertical_time speed 0", lambda: route3d.vertical_time(50.0, 0.0, 1.0), "must be > 0"),
        ("trajectory vertical_time accel nan", lambda: route3d.vertical_time(50.0, 2.0, nan), "must be > 0"),
        ("trajectory route hold 1e12", lambda: route3d.Route3D(plan, np.zeros(3), np.array([0, 1e12, 0]),
                                                               np.full(3, np.nan)), "a hold of 1e+12 s"),
    ]  # fmt: skip


@pytest.mark.parametrize("name,call,needle", _api_table(), ids=[n for n, _, _ in _api_table()])
def test_public_api_refuses_negative_nan_and_infinite_arguments(name: str, call: Any, needle: str) -> None:
    """Each call raises an :class:`InputError` (also a ``ValueError``) whose one-line message
    names the argument: never numbers computed from a meaningless value, never a bare numpy or
    Python exception."""
    with pytest.raises(InputError) as e:
        call()
    assert isinstance(e.value, ValueError)
    msg = str(e.value)
    assert needle in msg and "\n" not in msg, msg


def test_the_api_table_controls_answer() -> None:
    """The same functions with ordinary values return finite numbers (so the table can fail)."""
    import numpy as np

    from uasnav import allan, attitude, zupt
    from uasnav.trajectory import baselines, route3d

    plan = np.array([[0.0, 0.0], [100.0, 0.0], [100.0, 100.0]])
    assert np.isfinite(allan.oadev(np.random.default_rng(0).normal(size=200), 1.0).adev).all()
    assert np.isfinite(attitude.quat_to_euler([[1, 0, 0, 0], [1 + 5e-5, 0, 0, 0]])).all()
    assert np.isfinite(zupt.moving_average(np.ones((10, 3)), 100.0)).all()
    assert np.isfinite(baselines.kinematic_times(plan, np.zeros(1), np.full(1, 50.0), 5.0)).all()
    assert np.isfinite(route3d.vertical_time(50.0, 2.0, 1.0)).all()
    assert zupt.convergence_time(np.arange(5.0), np.zeros((5, 3)), np.zeros((5, 3))) == [0.0, 0.0, 0.0]


def test_a_large_json_document_is_printed_compact_and_the_same(capsys: pytest.CaptureFixture[str]) -> None:
    """``--json`` of a 10⁵-element answer: Python's indenting encoder is pure Python (seconds per
    10⁵ rows); beyond a megabyte the same JSON is printed on one line."""
    import numpy as np

    from uasnav.cli._common import MAX_INDENTED_JSON, echo_json

    small = {"a": [1.0, float("nan")], "b": np.arange(3)}
    echo_json(small)
    out = capsys.readouterr().out
    assert out == json.dumps({"a": [1.0, None], "b": [0, 1, 2]}, indent=2) + "\n"
    big = {"rows": [{"i": i, "t": i * 0.5} for i in range(60_000)]}
    echo_json(big)
    out = capsys.readouterr().out
    assert len(out) > MAX_INDENTED_JSON and out.count("\n") == 1
    assert json.loads(out) == big
