"""``uasnav simulate`` end to end."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.io import read_log
from uasnav.sim import simulate


def test_simulate_writes_the_same_log_as_the_api(tmp_path: Path) -> None:
    out = tmp_path / "s.csv"
    args = ["simulate", "--preset", "lsm6dsm", "--profile", "ramp", "--duration", "5", "--rate", "200"]
    r = CliRunner().invoke(main, [*args, "--seed", "4", "--out", str(out), "--json"])
    assert r.exit_code == 0, r.output
    summary = json.loads(r.stdout)
    assert summary["samples"] == 1000 and summary["files"] == [str(out)]
    log = read_log(out)
    ref = simulate("lsm6dsm", profile="ramp", duration=5.0, rate=200.0, seed=4)
    assert log.gyro.tobytes() == ref.gyro.tobytes()
    np.testing.assert_array_equal(log.truth["gyro_bias_thermal"], ref.truth["gyro_bias_thermal"])


def test_simulate_cube6_writes_six_files(tmp_path: Path) -> None:
    out = tmp_path / "cube.npz"
    r = CliRunner().invoke(
        main, ["simulate", "--preset", "lsm6dsm", "--duration", "2", "--sensors", "cube6", "--out", str(out)]
    )
    assert r.exit_code == 0, r.output
    files = sorted(tmp_path.glob("cube_s*.npz"))
    assert len(files) == 6
    mounts = [np.array(read_log(f).meta["mounting"]) for f in files]
    normals = np.array([m[2] for m in mounts])
    np.testing.assert_array_equal(np.abs(normals).sum(axis=0), [2, 2, 2])


def test_simulate_errors(tmp_path: Path) -> None:
    r = CliRunner().invoke(
        main, ["simulate", "--preset", "nope", "--duration", "1", "--out", str(tmp_path / "a.csv")]
    )
    assert r.exit_code == 1 and "unknown preset" in r.output
    r = CliRunner().invoke(main, ["simulate", "--duration", "1", "--out", str(tmp_path / "a.txt")])
    assert r.exit_code == 2
    r = CliRunner().invoke(main, ["simulate", "--profile", "boil", "--out", str(tmp_path / "a.csv")])
    assert r.exit_code == 2


def test_report_simulator_section_quick(tmp_path: Path) -> None:
    r = CliRunner().invoke(main, ["report", "--out", str(tmp_path), "--quick", "--only", "simulator"])
    assert r.exit_code == 0, r.output
    data = json.loads((tmp_path / "report.json").read_text())
    sec = data["sections"]["simulator"] if "sections" in data else data["simulator"]
    assert sec["soak_temp_range_c"][0] == pytest.approx(-20.53, abs=0.01)
    assert sec["soak_temp_range_c"][1] == pytest.approx(37.30, abs=0.01)
    # thesis Table 3 ARW and Table 4 VRW recovered from the simulated static AX1 log
    assert np.mean(sec["ax1_gyro_random_walk"]["fit"]) == pytest.approx(3.18, rel=0.10)
    assert np.mean(sec["ax1_accel_random_walk"]["fit"]) == pytest.approx(0.05, rel=0.10)
    assert np.mean(sec["lsm6dsm_gyro_bias_instability"]["fit"]) == pytest.approx(10.8, rel=0.25)
    for v in sec["hysteresis_output_deg_s"]:
        assert v == pytest.approx(sec["hysteresis_configured_deg_s"], abs=0.012)
    assert (tmp_path / "figures" / "simulator-ramp.png").stat().st_size > 10_000
