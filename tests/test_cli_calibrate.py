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


def test_report_section_quick(tmp_path) -> None:
    from uasnav.report.sections.s40_calibration import standin_bias, standin_derivative

    r = CliRunner().invoke(main, ["report", "--out", str(tmp_path), "--quick", "--only", "calibration"])
    assert r.exit_code == 0, r.output
    d = json.loads((tmp_path / "report.json").read_text())["sections"]["calibration"]
    res = d["ramp_residuals_rad_s"]
    # The BPNN beats the thesis' quadratic on the whole ramp. Against the PX4 cubic the fair
    # held-out comparison is the heating half: the soak never visits the cooling branch, whose
    # hysteresis offset no single-valued model follows (on the simulator it dominates both).
    assert res["BPNN 2-2 (thesis)"]["sr"] < res["polynomial m=2 (thesis)"]["sr"]
    heat = d["ramp_heating_sr_rad_s"]
    assert heat["BPNN 2-2 (thesis)"] < heat["PX4 TC cubic"]
    assert 27.28 <= d["delta_omega"]["t_max"] <= 34.08 and d["delta_omega"]["max"] > d["delta_omega"]["rms"]
    # Table 7 rows: t_PF is the first crossing of a constant residual: θ = |r|·t.
    assert len(d["table7"]["rows"]) == 4
    assert (tmp_path / "figures" / "calibration-fig34-delta-omega.png").exists()
    # The stand-in's derivative is the derivative of its bias.
    t = np.linspace(-20, 37, 50)
    fd = (standin_bias(t + 1e-4) - standin_bias(t - 1e-4)) / 2e-4
    np.testing.assert_allclose(standin_derivative(t), fd, rtol=1e-6, atol=1e-12)


def test_report_section_uses_simulator_contract(monkeypatch) -> None:
    """The section's simulator path against a fake ``uasnav.sim`` that follows the issue-3
    contract (simulate → ImuLog with truth rate_true / gyro_bias / gyro_bias_thermal,
    thermal_bias, thermal_bias_derivative), built from the stand-in curves."""
    import sys
    import types

    from uasnav.report.sections import s40_calibration as sec

    def simulate(preset, *, profile="static", rate=100.0, seed=0, **_):
        if profile == "soak":
            temp, _ = sec.standin_soak(seed, hold_s=300.0, rate=rate * 10)
            heating = np.ones(temp.size, bool)
        else:
            _, temp, heating, _ = sec.standin_ramp(seed, rate=rate)
        n = temp.size
        earth = np.tile([5e-5, 0.0, -5e-5], (n, 1))
        thermal = sec.standin_bias(temp, heating)
        total = thermal + 1e-4  # turn-on bias
        gyro = earth + total + np.random.default_rng(seed).normal(0, 1e-4, (n, 3))
        return ImuLog(
            t=np.arange(n) / rate,
            gyro=gyro,
            accel=np.tile([0.0, 0.0, -9.81], (n, 1)),
            temp=np.round(temp, 2),
            truth={"rate_true": earth, "gyro_bias": total, "gyro_bias_thermal": thermal, "temp_die": temp},
        )

    fake = types.ModuleType("uasnav.sim")
    fake.simulate = simulate  # type: ignore[attr-defined]
    fake.thermal_bias = lambda preset, t, branch="heating": sec.standin_bias(t, branch == "heating")  # type: ignore[attr-defined]
    fake.thermal_bias_derivative = lambda preset, t, branch="heating": sec.standin_derivative(t)  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "uasnav.sim", fake)
    import uasnav

    monkeypatch.setattr(uasnav, "sim", fake, raising=False)

    class W:
        quick, seed = True, 3

    d = sec._data(W())  # type: ignore[arg-type]
    assert d["source"].startswith("uasnav.sim")
    # Earth rate and turn-on bias are removed: what is left is the thermal bias plus noise.
    assert np.abs(d["ramp_gyro"] - d["ramp_truth"]).mean() < 2e-4
    np.testing.assert_allclose(d["truth_fn"](np.array([30.0]), True), sec.standin_bias(np.array([30.0])))
    assert d["soak_temp"].size == d["soak_bias"].shape[0] > 50
