"""Bounded memory and time from small inputs (issue #20, class 2): uasnav.limits and its users.

Each example of the issue (a plan with a 10⁹ m leg, ``--segment 1e-6``, ``--prototypes 10⁷``,
``simulate --duration 1e6`` / ``1e12``) must be refused up front: exit 1 with one line naming
the limit and how to raise it, in well under 5 s and 500 MB (measured here in-process with
tracemalloc, which sees numpy's buffers).
"""

from __future__ import annotations

import io
import math
import time
import tracemalloc
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from uasnav import limits
from uasnav.cli import main
from uasnav.errors import InputError, ResourceLimitError
from uasnav.sim import array_mountings, simulate, simulate_array
from uasnav.trajectory.geometry import arc_length_along, discretise, element_count_bound
from uasnav.trajectory.lvq import LVQClassifier

MB = 1 << 20


@pytest.fixture(autouse=True)
def _default_limits(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(limits.ENV_MEMORY, raising=False)
    monkeypatch.delenv(limits.ENV_WORK, raising=False)


def _bounded(fn: Callable[[], object], seconds: float = 5.0, peak_mb: float = 500.0) -> object:
    """Run ``fn``; assert it took < ``seconds`` and traced < ``peak_mb``; return its result or
    the exception it raised."""
    tracemalloc.start()
    t0 = time.monotonic()
    try:
        out: object = fn()
    except Exception as exc:  # returned to the caller to assert on
        out = exc
    finally:
        took = time.monotonic() - t0
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    assert took < seconds, f"took {took:.1f} s"
    assert peak < peak_mb * MB, f"peak {peak / MB:.0f} MB"
    return out


# -- the limits themselves ------------------------------------------------------------------------


def test_parse_size_and_format() -> None:
    assert limits.parse_size("2G") == 2 * 1024**3
    assert limits.parse_size("512 MiB") == 512 * MB
    assert limits.parse_size("1.5k") == 1536
    assert limits.parse_size("4096") == 4096
    assert limits.parse_size("1e9") == 10**9
    for bad in ("", "-1G", "nan", "2X", "G", "1e999"):
        with pytest.raises(InputError, match="byte count"):
            limits.parse_size(bad, "X")
    assert limits.format_size(1536) == "1.5 KiB"


def test_memory_limit_default_env_and_message(monkeypatch: pytest.MonkeyPatch) -> None:
    assert 0 < limits.max_memory() <= limits.DEFAULT_MAX_MEMORY
    monkeypatch.setenv(limits.ENV_MEMORY, "1M")
    assert limits.max_memory() == MB
    limits.check_memory(MB, "fits")
    with pytest.raises(ResourceLimitError) as exc:
        limits.check_memory(MB + 1, "the thing", option="--size")
    msg = str(exc.value)
    assert "the thing needs about 1.0 MiB" in msg and "limit of 1.0 MiB" in msg
    assert "reduce --size" in msg and "UASNAV_MAX_MEMORY=" in msg
    for nbytes in (math.inf, math.nan):
        with pytest.raises(ResourceLimitError, match="unbounded memory"):
            limits.check_memory(nbytes, "x")
    monkeypatch.setenv(limits.ENV_MEMORY, "lots")
    with pytest.raises(InputError, match="UASNAV_MAX_MEMORY: expected a byte count"):
        limits.max_memory()


def test_work_limit_env(monkeypatch: pytest.MonkeyPatch) -> None:
    limits.check_work(1e9, "small")
    with pytest.raises(ResourceLimitError, match=r"UASNAV_MAX_WORK"):
        limits.check_work(1e15, "big")
    monkeypatch.setenv(limits.ENV_WORK, "1e16")
    limits.check_work(1e15, "big")
    for bad in ("0", "-5", "nan", "many"):
        monkeypatch.setenv(limits.ENV_WORK, bad)
        with pytest.raises(InputError, match="UASNAV_MAX_WORK: expected"):
            limits.max_work()


@given(size=st.integers(0, 5000), limit=st.integers(0, 3000), chunk=st.integers(1, 700))
@settings(max_examples=40, deadline=None)
def test_read_limited_reads_at_most_limit_plus_one(size: int, limit: int, chunk: int) -> None:
    fh = io.BytesIO(b"x" * size)
    if size <= limit:
        assert limits.read_limited(fh, limit, "s", chunk=chunk) == b"x" * size
    else:
        with pytest.raises(ResourceLimitError, match=f"s: larger than the size limit of {limit} bytes"):
            limits.read_limited(fh, limit, "s", chunk=chunk)
        assert fh.tell() == limit + 1


def test_read_file_limited_on_an_endless_device() -> None:
    exc = _bounded(lambda: limits.read_file_limited("/dev/zero", 10 * MB), peak_mb=40)
    assert isinstance(exc, ResourceLimitError)
    with pytest.raises(InputError, match="cannot read"):
        limits.read_file_limited("/nonexistent/x", 10)


# -- plans and elements ---------------------------------------------------------------------------


def test_plan_with_a_1e9_m_leg_is_refused_up_front() -> None:
    plan = np.array([[0.0, 0.0], [1e9, 0.0]])
    assert element_count_bound(plan, 10.0) > 5e7
    exc = _bounded(lambda: discretise(plan, 10.0), seconds=1.0, peak_mb=5)
    assert isinstance(exc, ResourceLimitError), exc
    assert "plan: about 5e+07 elements" in str(exc) and "UASNAV_MAX_MEMORY" in str(exc)
    exc = _bounded(lambda: discretise(np.array([[0.0, 0.0], [1e3, 0.0]]), 1e-9), seconds=1.0, peak_mb=5)
    assert isinstance(exc, ResourceLimitError)
    exc = _bounded(lambda: discretise(np.array([[0.0, 0.0], [1e300, 1e300]]), 10.0), seconds=1.0)
    assert isinstance(exc, ResourceLimitError) and "PiB" in str(exc) and len(str(exc)) < 300
    exc = _bounded(lambda: discretise(np.array([[-1.5e308, 0.0], [1.5e308, 0.0]]), 10.0), seconds=1.0)
    assert isinstance(exc, ResourceLimitError) and "unbounded" in str(exc)


def test_ordinary_plans_still_discretise(monkeypatch: pytest.MonkeyPatch) -> None:
    plan = np.array([[0.0, 0.0], [500.0, 0.0], [500.0, 300.0]])
    el = discretise(plan, 10.0)
    assert len(el) <= element_count_bound(plan, 10.0)
    assert np.isclose(el.length_m.sum(), 800.0)
    monkeypatch.setenv(limits.ENV_MEMORY, "1K")  # the limit is read at each call
    with pytest.raises(ResourceLimitError, match=r"limit of 1\.0 KiB"):
        discretise(plan, 10.0)


def test_arc_length_along_memory_is_bounded_in_blocks() -> None:
    """Before: whole (positions × legs) arrays, here ≈ 12 000 × 300 × 80 B ≈ 290 MB at peak."""
    rng = np.random.default_rng(3)
    plan = np.cumsum(rng.uniform(-100, 100, (301, 2)), axis=0)
    pos = plan[0] + np.cumsum(rng.normal(0, 1.0, (12_000, 2)), axis=0)
    s = _bounded(lambda: arc_length_along(plan, pos), seconds=30.0, peak_mb=120)
    assert isinstance(s, np.ndarray) and s.shape == (12_000,) and np.all(np.diff(s) >= 0)
    # Same answer as the whole-array projection on a size where that is cheap.
    small = pos[:2000]
    a, d = plan[:-1], np.diff(plan, axis=0)
    u = np.clip(((small[:, None] - a) * d).sum(-1) / (d**2).sum(-1), 0, 1)
    assert np.allclose(arc_length_along(plan, small)[:1], [u[0, 0] * np.hypot(*d[0])])


# -- LVQ ------------------------------------------------------------------------------------------


def test_lvq_with_1e7_prototypes_is_refused_before_allocating(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(0)
    x, y = rng.normal(size=(200, 5)), np.repeat([0, 1], 100)
    exc = _bounded(lambda: LVQClassifier(n_prototypes=10_000_000).fit(x, y), seconds=2.0, peak_mb=20)
    assert isinstance(exc, ResourceLimitError) and "n_prototypes (--prototypes)" in str(exc)
    exc = _bounded(lambda: LVQClassifier(n_prototypes=20_000).fit(x, y), seconds=2.0, peak_mb=20)
    assert isinstance(exc, ResourceLimitError) and "UASNAV_MAX_WORK" in str(exc)
    assert LVQClassifier(n_prototypes=16, random_state=0).fit(x, y).prototypes_.shape == (16, 5)


# -- simulator ------------------------------------------------------------------------------------


@pytest.mark.parametrize("duration", [1e6, 1e12, 1e308])
def test_simulate_absurd_durations_are_refused(duration: float) -> None:
    exc = _bounded(lambda: simulate("ax1", duration=duration), seconds=1.0, peak_mb=5)
    assert isinstance(exc, ResourceLimitError), exc
    assert "simulate:" in str(exc) and "UASNAV_MAX_MEMORY" in str(exc)


def test_simulate_array_counts_every_sensor(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(limits.ENV_MEMORY, "64M")
    assert simulate("ax1", duration=1000.0, rate=100.0).n == 100_000  # ≈ 56 MB estimated: fits
    with pytest.raises(ResourceLimitError, match="× 6 sensors"):
        simulate_array("ax1", shape="cube", duration=1000.0, rate=100.0)
    with pytest.raises(ResourceLimitError, match="sensors per face"):
        array_mountings("planar", 1e9)
    with pytest.raises(InputError, match="finite number > 0"):
        array_mountings("planar", math.inf)


# -- the CLI examples of the issue ----------------------------------------------------------------


#: How the simulated flight was flown (a CSV flight carries neither).
_FLOWN = ["--speed", "3.33", "--wind", "2.78@22.5"]


@pytest.fixture(scope="module")
def flight(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Path, Path, Path]]:
    """A simulated CSV flight of plan A, its plan CSV and a model trained on it."""
    import pymap3d

    from uasnav.trajectory.simulator import phantom4_plans, simulate_flight

    d = tmp_path_factory.mktemp("flight")
    plan = phantom4_plans()["A"]
    lat0, lon0, h0 = 40.85, 14.27, 12.0
    tel = simulate_flight(plan, seed=5)
    lat, lon, h = pymap3d.ned2geodetic(tel.pos_ne[:, 0], tel.pos_ne[:, 1], 0 * tel.t, lat0, lon0, h0)
    csv = d / "f.csv"
    csv.write_text(
        "t,lat,lon,alt,v_N,v_E,v_D\n"
        + "".join(
            f"{a},{b:.9f},{c:.9f},{e:.3f},{f},{g},0\n"
            for a, b, c, e, f, g in zip(tel.t, lat, lon, h, *tel.vel_ne.T, strict=True)
        )
    )
    plat, plon, ph = pymap3d.ned2geodetic(plan[:, 0], plan[:, 1], 0 * plan[:, 0], lat0, lon0, h0)
    plan_csv = d / "plan.csv"
    plan_csv.write_text(
        "lat,lon,alt\n"
        + "".join(f"{a:.9f},{b:.9f},{c:.3f}\n" for a, b, c in zip(plat, plon, ph, strict=True))
    )
    model = d / "m.json"
    r = CliRunner().invoke(
        main, ["trajectory", "train", str(csv), *_FLOWN, "--plan", str(plan_csv), "--out", str(model)]
    )
    assert r.exit_code == 0, r.output
    yield csv, plan_csv, model


def _refused(args: list[str], pattern: str) -> None:
    res = _bounded(lambda: CliRunner().invoke(main, args))
    lines = res.stderr.strip().splitlines()  # type: ignore[attr-defined]
    assert res.exit_code == 1, res.output  # type: ignore[attr-defined]
    # Warnings about the training data may precede it; the error is one line, and the last.
    errors = [ln for ln in lines if ln.startswith("error: ")]
    assert len(errors) == 1 and lines[-1] == errors[0] and pattern in errors[0], lines
    assert "Traceback" not in res.output  # type: ignore[attr-defined]


@pytest.mark.parametrize("duration", ["1e6", "1e12"])
def test_cli_simulate_duration(tmp_path: Path, duration: str) -> None:
    out = tmp_path / "s.csv"
    _refused(["simulate", "--duration", duration, "--out", str(out)], "UASNAV_MAX_MEMORY")
    assert not out.exists()


def test_cli_trajectory_train_tiny_segment_and_huge_prototypes(
    flight: tuple[Path, Path, Path], tmp_path: Path
) -> None:
    csv, plan_csv, _ = flight
    base = [
        "trajectory",
        "train",
        str(csv),
        *_FLOWN,
        "--plan",
        str(plan_csv),
        "--out",
        str(tmp_path / "m.json"),
    ]
    _refused([*base, "--segment", "1e-6"], "elements of 2 × 1e-06 m")
    _refused([*base, "--prototypes", "10000000"], "n_prototypes")
    assert not (tmp_path / "m.json").exists()


def test_cli_trajectory_predict_three_line_plan_with_a_1e9_m_leg(
    flight: tuple[Path, Path, Path], tmp_path: Path
) -> None:
    _, _, model = flight
    plan = tmp_path / "huge.csv"
    plan.write_text("north,east\n0,0\n1e9,0\n")
    _refused(
        ["trajectory", "predict", "--model", str(model), "--plan", str(plan), "--wind", "0@0"],
        "UASNAV_MAX_MEMORY",
    )


def test_plan_files_are_read_within_a_byte_limit(tmp_path: Path) -> None:
    import functools

    from uasnav.errors import DataFormatError
    from uasnav.io.plans import MAX_PLAN_BYTES, read_plan_route

    read_plan = functools.partial(read_plan_route, other_as_csv=True)

    if Path("/dev/zero").exists():  # before: read to the end of an endless device
        exc = _bounded(lambda: read_plan("/dev/zero"), peak_mb=4 * MAX_PLAN_BYTES / MB)
        assert isinstance(exc, ResourceLimitError) and f"size limit of {MAX_PLAN_BYTES} bytes" in str(exc)
    bom = tmp_path / "bom.csv"
    bom.write_bytes(b"\xef\xbb\xbfnorth,east\n0,0\n100,0\n")  # spreadsheet export with a BOM
    assert read_plan(bom)[0].tolist() == [[0.0, 0.0], [100.0, 0.0]]
    huge_cell = tmp_path / "cell.csv"
    huge_cell.write_text('north,east\n"' + "x" * 200_000 + "\n")
    with pytest.raises(DataFormatError, match=r"cell\.csv, line 2: malformed CSV"):
        read_plan(huge_cell)
    with pytest.raises(InputError, match="is a directory"):
        read_plan(tmp_path)
