"""Issue 14, bugs 3–5: what a newcomer hit in the first commands.

3. ``trajectory evaluate`` flooded stderr with scikit-learn warnings; ``report`` printed a
   matplotlib tight_layout warning.
4. ``trajectory evaluate`` printed absurd errors for a method that cannot be fitted from the data
   (LVQ on 0.1 m/s ΔV classes, one class per element): now "not applicable" with the reason.
5. ``calibrate --test`` compared the model (which carries the *training* log's turn-on bias)
   with the test log's thermal truth: now ``thermal_error_vs_truth``, like with like.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.imu import ImuLog
from uasnav.io.formats.csv_v1 import write_csv_v1
from uasnav.trajectory.baselines import MIN_ELEMENTS_PER_CLASS, class_method_reason

TLOG = (
    Path(__file__).resolve().parents[1]
    / ".."
    / "shared"
    / "data"
    / "flights"
    / "phoenix_mission1_arducopter.tlog"
)


# --- bug 3 and 4: trajectory evaluate on the real ArduCopter missions --------------------------


def test_trajectory_evaluate_real_tlog_no_library_warnings_and_not_applicable_reason(
    shared_data: Path,
) -> None:
    # ../shared/data through the fixture: never skipped in CI (the fixture fails there instead).
    assert TLOG.resolve() == (shared_data / "flights" / "phoenix_mission1_arducopter.tlog").resolve()
    # --segment 5 is where scikit-learn warned ("number of unique classes is greater than 50%")
    # five times: the ΔV-class LVQ saw 26 classes in 36 training elements. Run as a user does
    # (a fresh interpreter with the default warning filters), not under pytest's capture.
    env = {k: v for k, v in os.environ.items() if k != "PYTHONWARNINGS"}
    args = ["trajectory", "evaluate", str(TLOG), "--segment", "5", "--json"]
    p = subprocess.run(
        [sys.executable, "-c", "import sys; from uasnav.cli import main; sys.exit(main())", *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )
    assert p.returncode == 0, p.stderr
    # No library warning reaches the user (our own TelemetryGapWarning about unmeasured
    # elements may; it names the flight and the element).
    for line in p.stderr.splitlines():
        assert "sklearn" not in line and "UserWarning" not in line and "matplotlib" not in line, line
    out = json.loads(p.stdout)
    m = out["methods"]
    dv = m["LVQ on ΔV classes"]
    assert dv["applicable"] is False and "element_e_pct_mean" not in dv
    assert "ΔV classes of 0.1 m/s from 36 training elements" in dv["reason"]
    # The methods that can be fitted still get numbers, finite and sane.
    for name in ("LVQ (thesis)", "distance ÷ speed", "kinematic point mass"):
        assert m[name]["applicable"] is True and 0 < m[name]["element_e_pct_mean"] < 100


def test_class_method_rule() -> None:
    assert MIN_ELEMENTS_PER_CLASS == 2.0
    # k classes from n elements: applicable while k ≤ n/2.
    assert class_method_reason(np.repeat(np.arange(10), 2), "cells") is None  # 10 classes, 20 samples
    # 11 classes: from 22 elements (k = n/2) applicable, from 21 (k > n/2) not.
    assert class_method_reason(np.r_[np.repeat(np.arange(10), 2), 99, 99], "c") is None
    assert class_method_reason(np.r_[np.repeat(np.arange(10), 2), 99], "c") is not None
    why = class_method_reason(np.arange(20), "ΔV classes")  # one class per element
    assert why is not None and why.startswith("20 ΔV classes from 20 training elements")
    assert class_method_reason(np.array([], dtype=int), "c") == "no training elements"


def test_report_figures_raise_no_layout_warning(tmp_path) -> None:
    """The trajectory section called tight_layout on a constrained-layout figure, which made
    matplotlib warn on every ``uasnav report`` run; its figures are now built without warnings."""
    from uasnav.report import build_report

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = build_report(tmp_path, quick=True, only=["trajectory"])
    data = r.data["trajectory"]
    # On the simulated experiment both LVQ variants have enough elements per class.
    assert data["methods_not_applicable"] == {}
    assert {"LVQ (thesis)", "LVQ on ΔV classes"} <= set(data["methods"])


# --- bug 5: calibrate --test compares like with like -------------------------------------------


def _thermal(temp: np.ndarray) -> np.ndarray:
    """A quadratic thermal bias (rad/s), exactly representable by a polynomial of order 2."""
    x = temp - 30.0
    return np.stack([2e-5 * x + 1e-6 * x**2, -1e-5 * x, 3e-7 * x**2], axis=1)


def _log(temp: np.ndarray, turn_on: np.ndarray, seed: int) -> ImuLog:
    rng = np.random.default_rng(seed)
    n = temp.size
    b = _thermal(temp)
    return ImuLog(
        t=np.arange(n) * 0.1,
        gyro=b + turn_on + rng.normal(0, 1e-6, (n, 3)),
        accel=np.tile([0.0, 0.0, -9.81], (n, 1)),
        temp=temp,
        truth={"gyro_bias_thermal": b, "gyro_bias": b + turn_on},
    )


def test_calibrate_test_compares_thermal_part_not_training_turn_on_bias(tmp_path) -> None:
    on_train = np.array([3e-3, -2e-3, 1e-3])  # rad/s, 0.17 deg/s: what a MEMS gyro powers up with
    on_test = np.array([-1e-3, 4e-3, 2e-3])
    train, test, model = tmp_path / "train.csv", tmp_path / "test.csv", tmp_path / "m.json"
    write_csv_v1(_log(np.linspace(20.0, 40.0, 4000), on_train, 1), train)
    write_csv_v1(_log(np.linspace(22.0, 38.0, 1500), on_test, 2), test)
    r = CliRunner().invoke(
        main, ["calibrate", str(train), "--method", "poly", "--order", "2", "--out", str(model)]
    )
    assert r.exit_code == 0, r.output
    r = CliRunner().invoke(main, ["calibrate", "--model", str(model), "--test", str(test), "--json"])
    assert r.exit_code == 0, r.output
    out = json.loads(r.output)
    assert "error_vs_truth" not in out  # the old name mixed the two turn-on biases in
    th = out["thermal_error_vs_truth"]
    assert th["truth"] == "gyro_bias_thermal" and "mean" not in th
    # The thermal shape is recovered to the noise level (1e-6 rad/s white, averaged) ...
    assert np.all(np.array(th["rms"]) < 2e-7)
    # ... and the removed offset is minus the training log's turn-on bias, which the old field
    # reported as "error" (about 1e-3 rad/s, 5000× the real thermal error).
    np.testing.assert_allclose(th["offset"], -on_train, atol=2e-7)
    text = CliRunner().invoke(main, ["calibrate", "--model", str(model), "--test", str(test)]).output
    assert "thermal_error_vs_truth" in text and "offset" in text


def test_trajectory_train_says_once_why_classes_are_too_many(tmp_path, monkeypatch) -> None:
    """``trajectory train`` on data with more feature cells than half the elements: one line of
    ours on stderr (the rule of bug 4), not scikit-learn's UserWarning; the model is still written."""
    from uasnav.trajectory import flights
    from uasnav.trajectory.samples import measure_elements
    from uasnav.trajectory.simulator import simulate_flight

    # A 16-leg random zig-zag: 31 elements in 17 cells (scikit-learn warns above 20 samples).
    rng = np.random.default_rng(3)
    ang = np.cumsum(rng.uniform(-2.5, 2.5, 16))
    plan = np.vstack([[0.0, 0.0], np.cumsum(np.c_[25 * np.cos(ang), 25 * np.sin(ang)], axis=0)])
    tel = simulate_flight(plan, seed=5)
    _, s = measure_elements(tel.plan_ne, tel.t, tel.pos_ne, tel.vel_ne, tel.wind_ne, tel.cruise_ms, 10.0)
    assert len(s) > 20 and len(np.unique(s.cell)) > len(s) / 2
    monkeypatch.setattr(
        flights, "flight_samples", lambda *a, **k: flights.FlightSamples((("f", None),), (s,))
    )
    (tmp_path / "f.csv").write_text("t\n")  # --out must differ from an existing input
    model = tmp_path / "m.json"
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # any library warning would fail the command
        # the LVQ network (the default kinematic model has no classes to warn about)
        r = CliRunner().invoke(
            main, ["trajectory", "train", str(tmp_path / "f.csv"), "--method", "lvq", "--out", str(model)]
        )
    assert r.exit_code == 0, (r.output, r.exception)
    assert f"warning: {len(np.unique(s.cell))} populated feature cells from {len(s)} training elements" in (
        r.stderr
    )
    assert "UserWarning" not in r.stderr and model.exists()
