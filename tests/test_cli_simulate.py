"""``uasnav simulate`` end to end."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
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
