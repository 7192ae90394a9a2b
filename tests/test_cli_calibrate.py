"""``uasnav calibrate``: fit and test through the CLI on synthetic static logs."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.imu import ImuLog
from uasnav.io.csv_v1 import write_csv_v1


def bias(temp: np.ndarray) -> np.ndarray:
    return np.stack([1e-3 * np.tanh((temp - 10) / 8), 4e-4 * np.sin(temp / 9), 2e-6 * (temp - 5) ** 2], 1)


def static_log(temp: np.ndarray, seed: int) -> ImuLog:
    rng = np.random.default_rng(seed)
    n = temp.size
    t = np.arange(n) * 0.1
    b = bias(temp)
    return ImuLog(
        t=t,
        gyro=b + rng.normal(0, 2e-5, (n, 3)),
        accel=np.tile([0.0, 0.0, -9.81], (n, 1)),
        temp=temp,
        truth={"gyro_bias_thermal": b},
    )


@pytest.fixture(scope="module")
def logs(tmp_path_factory) -> tuple:
    d = tmp_path_factory.mktemp("cal")
    train, test = d / "train.csv", d / "test.csv"
    write_csv_v1(static_log(np.linspace(-20, 37, 6000), 1), train)
    write_csv_v1(static_log(np.concatenate([np.linspace(27, 34, 600), np.linspace(34, 27, 600)]), 2), test)
    return d, train, test


def test_fit_both_and_test(logs) -> None:
    d, train, test = logs
    r = CliRunner().invoke(main, ["calibrate", str(train), "--method", "both", "--out", str(d / "m.json")])
    assert r.exit_code == 0, r.output
    assert (d / "m.poly.json").exists() and (d / "m.nn.json").exists()
    rms = {}
    for kind in ("poly", "nn"):
        r = CliRunner().invoke(
            main, ["calibrate", "--model", str(d / f"m.{kind}.json"), "--test", str(test), "--json"]
        )
        assert r.exit_code == 0, r.output
        out = json.loads(r.output)
        assert out["clipped_samples"] == 0 and out["n_samples"] == 1200
        rms[kind] = np.array(out["error_vs_truth"]["rms"])
        # residual vs the measured output = truth error + white noise 2e-5
        assert out["residual"]["sr"] > out["error_vs_truth"]["sr"]
    assert np.all(rms["nn"] < 1e-5)
    assert rms["nn"][0] < rms["poly"][0] / 5


def test_select_poly_and_text_output(logs) -> None:
    d, train, test = logs
    out = d / "p.json"
    r = CliRunner().invoke(
        main, ["calibrate", str(train), "--method", "poly", "--select", "--out", str(out), "--json"]
    )
    assert r.exit_code == 0, r.output
    s = json.loads(r.output)
    assert s["poly_order"] == s["poly_selection"]["chosen"] >= 3
    r = CliRunner().invoke(main, ["calibrate", "--model", str(out), "--test", str(test)])
    assert r.exit_code == 0 and "Sr" in r.output and "error_vs_truth" in r.output


def test_usage_and_domain_errors(logs, tmp_path) -> None:
    _, train, test = logs
    r = CliRunner().invoke(main, ["calibrate", str(train)])
    assert r.exit_code == 2 and "--out" in r.output
    r = CliRunner().invoke(main, ["calibrate", "--model", str(train)])
    assert r.exit_code == 2
    r = CliRunner().invoke(
        main, ["calibrate", str(train), "--method", "poly", "--hidden", "3", "--out", "x.json"]
    )
    assert r.exit_code == 2
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "uasnav.thermal-model"}')
    r = CliRunner().invoke(main, ["calibrate", "--model", str(bad), "--test", str(test)])
    assert r.exit_code == 1 and "error:" in r.output and "schema_version" in r.output
