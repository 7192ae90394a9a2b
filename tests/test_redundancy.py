"""Redundant IMUs (thesis §4.3): geometry vs Table 14, fusion, FDI, Kalman, alignment."""

from __future__ import annotations

import math

import numpy as np
import pytest
from click.testing import CliRunner
from scipy import stats

from uasnav import redundancy as R
from uasnav.cli import main
from uasnav.errors import InputError
from uasnav.io.csv_v1 import read_csv_v1, write_csv_v1
from uasnav.redundancy_standin import standin_array

DEG = math.pi / 180


@pytest.fixture(scope="module")
def cube6() -> R.Configuration:
    return R.configuration("cube", 1, triaxial=True)


@pytest.fixture(scope="module")
def cube_logs(cube6):
    return standin_array(cube6.mountings(), duration=60.0, rate=100.0, seed=7)


def test_table14_exact() -> None:
    for _no, _pf, _total, ref, ours in R.table14():
        assert round(ours, 2) == ref
    # The thesis' six-SensorTile cube (triaxial, one per face) is row 5: 18 axes.
    np.testing.assert_allclose(R.kr("cube", 1, triaxial=True), 1 / math.sqrt(6), rtol=1e-12)


@pytest.mark.parametrize("shape", R.SHAPES)
def test_kr_depends_only_on_the_number_of_axes(shape: str) -> None:
    for per_face in (1, 2, 3):
        c = R.configuration(shape, per_face)
        n = R.FACES[shape] * per_face
        np.testing.assert_allclose(c.k_r(), math.sqrt(3 / n), rtol=1e-12)
        # Platonic normals are isotropic: the LS covariance is diagonal and equals k_r².
        np.testing.assert_allclose(c.ls_covariance(1.0), np.eye(3) * 3 / n, atol=1e-14)
        assert np.allclose(np.linalg.norm(R.face_normals(shape), axis=1), 1.0)


def test_chi2_threshold_matches_scipy() -> None:
    for p in (1e-3, 1e-4, 1e-6):
        for dof in (1, 2):
            assert R.chi2_threshold(dof, p) == pytest.approx(stats.chi2.isf(p, dof), rel=1e-7)
        for dof in range(3, 60):
            assert R.chi2_threshold(dof, p) == pytest.approx(stats.chi2.isf(p, dof), rel=1e-9)


def test_bad_configurations_are_named() -> None:
    m = np.repeat(np.eye(3)[None], 2, axis=0)
    m[1, 0, 1] = 0.2
    with pytest.raises(InputError, match=r"mountings\[1\].*orthonormal"):
        R.from_mountings(m)
    m[1] = np.diag([1.0, 1.0, -1.0])
    with pytest.raises(InputError, match=r"mountings\[1\].*reflection"):
        R.from_mountings(m)
    with pytest.raises(InputError, match="shape"):
        R.configuration("sphere")
    with pytest.raises(InputError, match="per_face"):
        R.configuration("cube", 0.3)
    with pytest.raises(InputError, match="tetrahedron"):
        R.configuration("tetrahedron", 0.5)


def test_too_few_axes_and_nan_never_give_a_fused_value() -> None:
    c = R.configuration("cube", 1)  # six single-axis gyros
    z = np.zeros((4, 6))
    z[1, 0] = np.nan  # one x gyro drops out: still observable, flagged
    z[2, [0, 3]] = np.nan  # both x gyros out: x unobservable → invalid, not a number
    for fdi in (False, True):
        f = R.fuse_axes(c, z, sigma=np.full(6, 0.01), fdi=fdi)
        assert f.valid.tolist() == [True, True, False, True]
        assert np.isnan(f.value[2]).all() and np.isfinite(f.value[[0, 1, 3]]).all()
        assert f.health[1, 0] == R.HEALTH_NON_FINITE and f.health[1, 1:].sum() == 0
    with pytest.raises(InputError, match="one column per sensor axis"):
        R.fuse_axes(c, np.zeros((4, 5)), sigma=np.ones(6))


def test_mismatched_sample_times(cube6, cube_logs) -> None:
    from dataclasses import replace

    logs = list(cube_logs)
    logs[3] = replace(logs[3], t=logs[3].t + 0.004)
    with pytest.raises(InputError, match=r"logs\[3\].*mismatched sample times"):
        R.fuse(logs, cube6)


def test_fusion_noise_and_bias_follow_kr(cube6, cube_logs) -> None:
    res = R.fuse(cube_logs, cube6, fdi=False)
    assert res.valid.all()
    w_true = cube6.mountings()[0].T @ cube_logs[0].truth["rate_true"][0]
    err = res.gyro.value - w_true
    # White noise: fused σ = σ_single·k_r (k_r = 1/√6), from the Allan deviation at τ₀.
    single = np.mean([R.white_noise_sigma(lg.gyro) for lg in cube_logs])
    fused = R.white_noise_sigma(err)
    np.testing.assert_allclose(fused / single, 1 / math.sqrt(6), rtol=0.05)
    # Bias: the fused bias is exactly the average of the sensors' biases projected on the IMU
    # axes (eq. 38), i.e. H⁺·b.
    b = np.stack([m.T @ lg.truth["gyro_bias"][0] for m, lg in zip(cube6.mountings(), cube_logs, strict=True)])
    noise0 = np.mean(err[:1], axis=0) - b.mean(axis=0)
    assert np.abs(noise0).max() < 5 * single / math.sqrt(6)


def _fault(z: np.ndarray, kind: str, cols: slice, k0: int, rng) -> np.ndarray:
    z = z.copy()
    if kind == "bias step":
        z[k0:, cols.start + 1] += 2.0 * DEG
    elif kind == "stuck":
        z[k0:, cols] = z[k0 - 1, cols]
    elif kind == "noise burst":
        z[k0 : k0 + 300, cols] += 1.0 * DEG * rng.standard_normal((300, 3))
    elif kind == "saturation":
        z[k0:, cols.start] = 4.36  # ±250 dps full scale
    else:  # dropout
        z[k0:, cols] = np.nan
    return z


@pytest.mark.parametrize("kind", ["bias step", "stuck", "noise burst", "saturation", "dropout"])
def test_fdi_isolates_each_fault_and_stays_in_the_no_fault_envelope(cube6, cube_logs, kind) -> None:
    t, z, _ = R.stack_logs(cube_logs)
    # Remove each sensor's turn-on bias as a ZUPT initialisation would (first 10 s).
    truth = np.concatenate([lg.truth["rate_true"] for lg in cube_logs], axis=1)
    z = z - (z[:1000] - truth[:1000]).mean(axis=0)
    # Then move: a known IMU rate profile seen by every sensor through its mounting, so that
    # a stuck output is wrong (at rest it would be harmless).
    w = np.column_stack([0.5 * np.sin(0.5 * t), 0.3 * np.cos(0.3 * t), 0.2 * np.sin(0.7 * t)])
    z = z + w @ cube6.axes.T
    k0 = 3000
    zf = _fault(z, kind, slice(6, 9), k0, np.random.default_rng(1))
    sigma = R.white_noise_sigma(z[:1000])
    opts = {"sigma": sigma, "saturation": 4.3, "stuck_samples": 10, "parity_bias_samples": 1000}
    ref = R.fuse_axes(cube6, z, fdi=True, **opts)
    with_fdi = R.fuse_axes(cube6, zf, fdi=True, **opts)
    without = R.fuse_axes(cube6, zf, fdi=False, **opts)
    seg = slice(k0 + 20, None)
    assert with_fdi.valid[seg].all()
    envelope = 5 * np.sqrt(ref.variance[seg].max() * 6 / 5)  # 5σ with one sensor fewer
    dev = np.nanmax(np.abs(with_fdi.value[seg] - ref.value[seg]))
    assert dev < envelope, (kind, dev, envelope)
    if kind != "dropout":  # without FDI a dropout is still excluded (never fused from NaN)
        assert np.nanmax(np.abs(without.value[seg] - ref.value[seg])) > envelope
    flagged = with_fdi.health[seg, 2] != 0
    assert flagged.mean() > (0.05 if kind == "noise burst" else 0.99)
    # Healthy sensors are (almost) never blamed: p_fa = 1e-6 per sample.
    assert (with_fdi.health[:, [0, 1, 3, 4, 5]] != 0).mean() < 1e-3


def test_kalman_partial_self_calibration(cube6, cube_logs) -> None:
    _, z, _ = R.stack_logs(cube_logs)
    z = z[:2000]
    b_true = np.concatenate([lg.truth["gyro_bias"][:2000] for lg in cube_logs], axis=1).mean(axis=0)
    H = cube6.axes
    parity = b_true - H @ np.linalg.lstsq(H, b_true, rcond=None)[0]
    kf = R.kalman_fuse(cube6, z, 0.01, bias_psd=0.0)
    # Redundancy alone observes the parity part of the biases.
    assert np.abs(kf.bias[-1] - parity).max() < 0.02 * DEG
    assert np.abs(b_true).max() > 1 * DEG  # so the full biases were not estimated
    # A zero-rate (static) reference makes all of them observable; compare with the truth
    # (Earth rate is the only true rate, 1e-4 rad/s class, inside the 1e-4 σ reference).
    kz = R.kalman_fuse(cube6, z, 0.01, bias_psd=0.0, zero_rate=np.ones(2000, bool))
    assert np.abs(kz.bias[-1] - b_true).max() < 0.01 * DEG
    # Plain averaging keeps the full averaged bias; the statically-calibrated filter does not.
    avg = R.fuse_axes(cube6, z, fdi=False).value.mean(axis=0)
    assert np.abs(kz.rate[-1]).max() < 0.1 * np.abs(avg).max()


def test_relative_alignment_recovers_known_mounting_errors(cube6) -> None:
    attitudes = [(0.0, 0.0, 0.0), (1.2, 0.0, 0.0), (0.0, -1.0, 0.0), (0.6, 0.5, 0.0)]
    vecs = []
    logs0 = None
    for k, e in enumerate(attitudes):
        logs = standin_array(
            cube6.mountings(), duration=5.0, seed=11, euler_rad=e, mounting_error_rad=1 * DEG, noise_seed=k
        )
        logs0 = logs0 or logs
        vecs.append([lg.accel.mean(axis=0) for lg in logs])
        assert logs[2].meta["mounting_true"] == logs0[2].meta["mounting_true"], k
    v = np.transpose(np.array(vecs), (1, 0, 2))  # (sensors, attitudes, 3)
    al = R.relative_alignment(v, nominal=cube6)
    true = np.array([lg.meta["mounting_true"] for lg in logs0])
    for i in range(6):
        e = true[i] @ np.array(cube6.mountings()[i]).T
        phi = 0.5 * np.array([e[2, 1] - e[1, 2], e[0, 2] - e[2, 0], e[1, 0] - e[0, 1]])
        np.testing.assert_allclose(al.misalignment[i], phi, atol=0.02 * DEG)
    assert np.abs(al.misalignment).max() > 0.5 * DEG
    assert al.config is not None
    np.testing.assert_allclose(al.config.mountings(), true, atol=5e-4)
    # Eq. (45) reproduces the same relative rotation from the sensors' true C_b^n.
    c_imu_n = np.eye(3)
    c_b_n = [c_imu_n @ t.T for t in true]
    np.testing.assert_allclose(R.relative_rotation(c_b_n[3], c_b_n[0]), true[3] @ true[0].T, atol=1e-12)
    # Levelling: roll/pitch of a level IMU seen by the +z-face sensor (its frame = IMU frame).
    np.testing.assert_allclose(R.level([[0.0, 0.0, -9.8]]), [[0.0, 0.0]], atol=1e-12)


def test_report_section_quick(tmp_path) -> None:
    import json

    r = CliRunner().invoke(main, ["report", "--out", str(tmp_path), "--quick", "--only", "redundancy"])
    assert r.exit_code == 0, r.output
    data = json.loads((tmp_path / "report.json").read_text())["sections"]["redundancy"]
    assert [round(row["k_r"], 2) for row in data["table14"]] == [1.0, 0.71, 0.58, 0.5, 0.41]
    # Fused cube vs a typical face: every threshold reached later, by about 1/k_r = √6
    # (Δt% ≈ +145 %) for bias-dominated drift; the median is over faces and runs.
    raw = data["table15"]["raw output (no calibration)"]
    assert all(60 < row[-1] < 300 for row in raw)
    for _shape, _pf, _n, k_r, noise_ratio, _bias in data["improvement"]:
        assert noise_ratio == pytest.approx(k_r, rel=0.08)
    for name, dev_fdi, dev_plain, envelope, _flag in data["fdi"]:
        assert dev_fdi < envelope
        assert name.startswith("dropout") or dev_plain > envelope
    assert data["alignment_max_error_deg"] < 0.02


def test_cli_kr_and_fuse(tmp_path, cube6) -> None:
    r = CliRunner().invoke(main, ["redundancy", "kr", "--shape", "cube", "--per-face", "1", "--json"])
    assert r.exit_code == 0, r.output
    import json

    assert json.loads(r.output)["k_r"] == pytest.approx([1 / math.sqrt(2)] * 3)
    logs = standin_array(cube6.mountings(), duration=20.0, seed=3)
    paths = []
    for i, lg in enumerate(logs):
        g = lg.gyro.copy()
        if i == 4:
            g[1500:, 0] += 1.0 * DEG  # a bias step after 15 s
        from dataclasses import replace

        p = tmp_path / f"s{i}.csv"
        write_csv_v1(replace(lg, gyro=g, truth={}), p)
        paths.append(str(p))
    out = tmp_path / "fused.csv"
    r = CliRunner().invoke(
        main, ["redundancy", "fuse", *paths, "--shape", "cube", "--fdi", "--out", str(out), "--json"]
    )
    assert r.exit_code == 0, r.output
    s = json.loads(r.output)
    assert s["written"] == 2000
    assert s["flagged_samples_per_sensor"]["4"] > 450
    fused = read_csv_v1(out)
    assert fused.n == 2000
    r = CliRunner().invoke(main, ["redundancy", "fuse", *paths[:5], "--shape", "cube", "--out", str(out)])
    assert r.exit_code == 1 and "do not fill" in r.output
    # Three IMUs sharing the IMU frame (an autopilot's), no FDI: the fused rate is the
    # noise-weighted mean of the three.
    r = CliRunner().invoke(main, ["redundancy", "fuse", *paths[:3], "--shape", "aligned", "--out", str(out)])
    assert r.exit_code == 0, r.output
    fused = read_csv_v1(out)
    three = np.mean([read_csv_v1(p).gyro for p in paths[:3]], axis=0)
    assert np.abs(fused.gyro - three).max() < 0.02 * np.abs(three).max()


def test_ardupilot_three_imus(shared_data) -> None:
    from uasnav.redundancy_ardupilot import analyse_log

    res = analyse_log(shared_data / "logs" / "ardupilot_log171.bin")
    assert res.n_samples > 5000
    # Fused white noise (static window) is below every single IMU's and matches the LS
    # prediction from the per-IMU Allan noise; IMU2 is ~10x noisier, so Allan weighting beats
    # the plain average by a wide margin.
    assert np.all(res.fused_noise_gyro < res.single_noise_gyro.min(axis=0))
    assert np.all(res.fused_noise_accel < res.single_noise_accel.min(axis=0))
    np.testing.assert_allclose(res.fused_noise_gyro, res.predicted_noise_gyro, rtol=0.1)
    np.testing.assert_allclose(res.fused_noise_accel, res.predicted_noise_accel, rtol=0.1)
    assert np.all(res.average_noise_gyro > 2.5 * res.fused_noise_gyro)
    # ArduPilot's consistency gates (5 deg/s, 0.75 m/s²) hold at rest but fail on about a
    # third of this log (handling and flight vibration the IMUs see differently).
    assert res.static_gates_ok
    assert 0.6 < res.gyro_gate_ok_fraction < 0.75 and 0.6 < res.accel_gate_ok_fraction < 0.75
    # In-flight disagreement is not white noise: the static-σ parity test fires on most
    # samples, the robust σ brings it down to a minority that overlaps the gate failures.
    assert res.fdi_alarm_fraction > 0.5
    assert res.robust_fdi_alarm_fraction < 0.3 and res.robust_alarm_gate_overlap > 0.5


def test_weights_are_the_allan_deviation_at_tau0(cube_logs) -> None:
    from uasnav.allan import oadev

    g = cube_logs[2].gyro
    ref = oadev(g, rate=100.0, taus=[0.01]).adev[0]
    np.testing.assert_allclose(R.white_noise_sigma(g), ref, rtol=1e-9)
