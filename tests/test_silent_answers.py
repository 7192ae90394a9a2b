"""No silent wrong answer with exit code 0 (issue #20, class 6), and no traceback reaching a
CLI user (class 5/9): each input below used to "succeed" with an empty, NaN or meaningless
result, or to end in a traceback; now it is an error naming what is wrong (or, at the API, a
clearly labelled result)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from uasnav import allan, cli, redundancy
from uasnav.cli import main
from uasnav.errors import InputError, NumericalError


def _run(*argv: str):  # type: ignore[no-untyped-def]
    return CliRunner().invoke(main, list(argv), catch_exceptions=True, env={"UASNAV_DEBUG": None})


def _one_error_line(r) -> str:  # type: ignore[no-untyped-def]
    assert r.exit_code == 1, (r.exit_code, r.stdout, r.stderr)
    lines = r.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), r.stderr
    assert "Traceback" not in r.stderr + r.stdout
    return lines[0]


@pytest.fixture(scope="module")
def cube6(tmp_path_factory) -> list[str]:
    d = tmp_path_factory.mktemp("cube6")
    r = _run("simulate", "--sensors", "cube6", "--duration", "20", "--rate", "50", "--out", str(d / "c.csv"))
    assert r.exit_code == 0, r.stderr
    return sorted(str(p) for p in d.glob("c_s*.csv"))


# --- redundancy ---------------------------------------------------------------------------


def test_fuse_learn_bias_negative_is_refused_at_the_cli_and_the_api(cube6, tmp_path):
    out = tmp_path / "f.csv"
    r = _run("redundancy", "fuse", *cube6, "--fdi", "--learn-bias", "-5", "--out", str(out))
    assert r.exit_code == 2 and "--learn-bias" in r.stderr
    assert not out.exists()
    for bad in (-5.0, math.nan, math.inf):
        with pytest.raises(InputError, match="learn_bias_s"):
            redundancy.fuse_files(cube6, "cube", fdi=True, learn_bias_s=bad)
    with pytest.raises(InputError, match="stuck_samples"):
        redundancy.fuse_files(cube6, "cube", fdi=True, stuck_samples=-1)
    logs = redundancy.load_logs(cube6)
    with pytest.raises(InputError, match="parity_bias_s"):
        redundancy.fuse(logs, redundancy.array_for_logs("cube", logs), parity_bias_s=-1.0)
    with pytest.raises(InputError, match="time_tol_s"):
        redundancy.fuse(logs, redundancy.array_for_logs("cube", logs), time_tol_s=math.nan)


def test_fuse_that_drops_every_sample_fails_and_writes_nothing(cube6, tmp_path):
    out = tmp_path / "f.csv"
    # p_fa close to 1: the χ² threshold is ~0, every sample alarms and nothing can be fused.
    r = _run("redundancy", "fuse", *cube6, "--fdi", "--p-fa", "0.999999", "--out", str(out))
    line = _one_error_line(r)
    assert "no sample could be fused" in line and str(out) in line
    assert not out.exists()


def test_fuse_still_writes_when_samples_survive(cube6, tmp_path):
    out = tmp_path / "f.csv"
    r = _run("redundancy", "fuse", *cube6, "--fdi", "--out", str(out))
    assert r.exit_code == 0, r.stderr
    assert out.stat().st_size > 0


@pytest.mark.parametrize("tol", [math.nan, -1.0, 0.0, 0.5, math.inf])
def test_from_mountings_refuses_a_tolerance_that_accepts_anything(tol):
    m = np.array([np.eye(3), 1.5 * np.eye(3), np.eye(3)])  # mounting 1 is not a rotation
    with pytest.raises(InputError, match="tol"):
        redundancy.from_mountings(m, tol=tol)
    with pytest.raises(InputError, match=r"mountings\[1\]"):
        redundancy.from_mountings(m, tol=1e-6)


def test_configuration_bounds_sensors_per_face():
    with pytest.raises(InputError, match="per_face"):
        redundancy.configuration("cube", 1e300)
    with pytest.raises(InputError, match="per_face"):
        redundancy.configuration("cube", 1001)


# --- ZUPT ---------------------------------------------------------------------------------


def test_zupt_on_a_two_sample_log_is_an_error(cube6, tmp_path):
    lines = Path(cube6[0]).read_text().splitlines()
    head = [x for x in lines if x.startswith("#")]
    rows = [x for x in lines if not x.startswith("#")][:3]  # header + 2 samples
    log = tmp_path / "two.csv"
    log.write_text("\n".join(head + rows) + "\n")
    before = log.read_bytes()
    out = tmp_path / "est.csv"
    line = _one_error_line(_run("zupt", str(log), "--out", str(out)))
    assert "no ZUPT update" in line and str(log) in line
    assert not out.exists() and log.read_bytes() == before


def test_zupt_api_refuses_nonsense_config_numbers(cube6):
    from uasnav import zupt
    from uasnav.io import read_log

    log = read_log(cube6[0])
    for change in (
        {"levelling_s": math.nan},
        {"levelling_s": -1.0},
        {"update_interval_s": 0.0},
        {"latitude_deg": 1e308},
    ):
        with pytest.raises(InputError, match=next(iter(change))):
            zupt.run(log, "zupt", None, zupt.ZuptConfig(**change))


# --- Allan --------------------------------------------------------------------------------


def test_oadev_never_returns_nan_for_huge_data():
    x = np.random.default_rng(1).normal(size=(2000, 2))
    huge = x / np.abs(x).max() * 1e308
    with pytest.raises(NumericalError, match="not representable"):
        allan.oadev(huge, rate=100.0)
    # Large but representable deviations are computed (scaled exactly by a power of two).
    big = allan.oadev(x * 2.0**450, rate=100.0)
    ref = allan.oadev(x, rate=100.0)
    assert np.all(np.isfinite(big.adev)) and np.all(np.isfinite(big.ci_high))
    np.testing.assert_allclose(big.adev, ref.adev * 2.0**450, rtol=1e-12)


@pytest.mark.parametrize("rate", [1e308, 1e13, math.inf, math.nan, 0.0, -1.0])
def test_oadev_refuses_absurd_rates(rate):
    with pytest.raises(InputError, match="rate"):
        allan.oadev(np.random.default_rng(0).normal(size=500), rate=rate)


def test_oadev_results_unchanged_for_ordinary_data():
    # The overflow guard must not move ordinary numbers (the report's Allan values).
    x = np.random.default_rng(3).normal(0, 1e-3, size=(5000, 3))
    r = allan.oadev(x, rate=100.0)
    assert np.all(np.isfinite(r.avar)) and np.array_equal(r.adev, np.sqrt(r.avar))


# --- the CLI's last line of defence ---------------------------------------------------------


def test_unexpected_exception_is_one_internal_error_line(monkeypatch):
    import uasnav.redundancy as red

    def boom(*a, **k):  # type: ignore[no-untyped-def]
        raise KeyError("surprise")

    monkeypatch.setattr(red, "configuration", boom)
    line = _one_error_line(_run("redundancy", "kr"))
    assert line.startswith("error: internal error: KeyError") and "please report" in line
    assert cli.DEBUG_ENV in line
    r = CliRunner().invoke(main, ["redundancy", "kr"], env={cli.DEBUG_ENV: "1"})
    assert isinstance(r.exception, KeyError)  # the traceback is there for the bug report


def test_multi_line_domain_error_is_one_line(monkeypatch):
    import uasnav.redundancy as red

    def boom(*a, **k):  # type: ignore[no-untyped-def]
        raise InputError("first line\nsecond line")

    monkeypatch.setattr(red, "configuration", boom)
    assert _one_error_line(_run("redundancy", "kr")) == "error: first line second line"


def test_a_huge_message_is_cut_to_a_readable_line(monkeypatch):
    import uasnav.redundancy as red

    def boom(*a, **k):  # type: ignore[no-untyped-def]
        raise InputError("cell " + "x" * 128_000 + " END")

    monkeypatch.setattr(red, "configuration", boom)
    line = _one_error_line(_run("redundancy", "kr"))
    assert len(line) < 2100 and line.startswith("error: cell x") and line.endswith(" END")


def test_os_error_names_the_path_once(tmp_path):
    missing = tmp_path / "nope" / "x.csv"
    line = _one_error_line(_run("allan", str(missing)))
    assert line.count(str(missing)) <= 1 and "[Errno" not in line


def test_help_documents_the_exit_codes_and_debug_switch():
    r = _run("--help")
    assert r.exit_code == 0 and cli.DEBUG_ENV in r.stdout and "internal error" in r.stdout


def test_a_rust_panic_is_an_internal_error_line(monkeypatch):
    # pyo3's PanicException derives from BaseException, not Exception: the handler must see it.
    import uasnav.redundancy as red

    class PanicException(BaseException):
        pass

    def boom(*a, **k):  # type: ignore[no-untyped-def]
        raise PanicException("index out of bounds")

    monkeypatch.setattr(red, "configuration", boom)
    line = _one_error_line(_run("redundancy", "kr"))
    assert line.startswith("error: internal error: PanicException: index out of bounds")
