"""Redundant IMUs (thesis §4.3): geometry vs Table 14, fusion, FDI, Kalman, alignment."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from click.testing import CliRunner
from scipy import stats

from uasnav import redundancy as R
from uasnav.cli import main
from uasnav.errors import InputError
from uasnav.experiments import redundancy as X
from uasnav.io.formats.csv_v1 import read_csv_v1, write_csv_v1
from uasnav.sim import array_mountings, inject_fault, load_preset, simulate_array

DEG = math.pi / 180


@pytest.fixture(scope="module")
def cube6() -> R.SensorArray:
    """The simulator's cube: six triaxial sensors, z along the outward face normals."""
    return R.from_mountings(np.array(array_mountings("cube")))


@pytest.fixture(scope="module")
def cube_logs(cube6):
    """Six simulated LSM6DSM on the cube, static, 100 Hz, 60 s."""
    logs = simulate_array("lsm6dsm", shape="cube", duration=60.0, rate=100.0, seed=7)
    np.testing.assert_array_equal(np.array([lg.meta["mounting"] for lg in logs]), cube6.mountings())
    return logs


def test_table14_exact() -> None:
    for _no, _pf, _total, ref, ours in X.table14():
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


def test_array_for_logs_names_the_bad_log() -> None:
    from uasnav.imu import ImuLog

    lg = ImuLog(t=[0.0, 0.01], gyro=np.zeros((2, 3)), accel=np.zeros((2, 3)))
    with pytest.raises(InputError, match=r"b\.csv: no '# mounting:' comment"):
        R.array_for_logs("meta", [replace(lg, meta={"mounting": np.eye(3)}), lg], names=["a.csv", "b.csv"])
    with pytest.raises(InputError, match="do not fill the 6 faces"):
        R.array_for_logs("cube", [lg] * 5)
    with pytest.raises(InputError, match="shape"):
        R.array_for_logs("sphere", [lg] * 6)
    # json text of a '# mounting:' comment is accepted like the matrix itself
    two = [replace(lg, meta={"mounting": "[[1, 0, 0], [0, 1, 0], [0, 0, 1]]"})] * 2
    np.testing.assert_array_equal(R.array_for_logs("meta", two).mountings(), np.eye(3)[None].repeat(2, 0))


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
    zf = inject_fault(z, kind, sensor=2, start=k0, axis=1 if kind == "bias step" else 0, seed=1)
    # The χ² scale: the robust spread of the first 10 s of parity residuals (the simulated
    # sensors low-pass filter their output, so the Allan deviation at τ₀ is too small).
    sigma = R.robust_sigma(cube6, z[:1000], R.white_noise_sigma(z[:1000]))
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
    # The simulated cube re-recorded (noise_seed) in four static attitudes, every sensor
    # mounted 1° (σ per axis) off its nominal face; the sensors' own scale-factor and axis
    # misalignment errors are switched off (they would be indistinguishable from mounting
    # errors for this method, see the report).
    model = load_preset("lsm6dsm").without("scale_factor", "misalignment", "thermal")
    attitudes = [(0.0, 0.0, 0.0), (1.2, 0.0, 0.0), (0.0, -1.0, 0.0), (0.6, 0.5, 0.0)]
    vecs = []
    logs0 = None
    for k, e in enumerate(attitudes):
        logs = simulate_array(
            model, shape="cube", duration=5.0, seed=11, euler_rad=e, mounting_error_rad=1 * DEG, noise_seed=k
        )
        logs0 = logs0 or logs
        vecs.append([lg.accel.mean(axis=0) for lg in logs])
        assert logs[2].meta["mounting_true"] == logs0[2].meta["mounting_true"], k
    v = np.transpose(np.array(vecs), (1, 0, 2))  # (sensors, attitudes, 3)
    al = R.relative_alignment(v, nominal=cube6)
    true = np.array([lg.meta["mounting_true"] for lg in logs0])
    nom = cube6.mountings()
    for i in range(6):
        # true relative rotation (reference → sensor i) against the nominal one
        e = (true[i] @ true[0].T) @ (nom[i] @ nom[0].T).T
        phi = 0.5 * np.array([e[2, 1] - e[1, 2], e[0, 2] - e[2, 0], e[1, 0] - e[0, 1]])
        # residual: bias instability differing between the attitudes (≈ 0.1 mg / 10 m/s²)
        np.testing.assert_allclose(al.misalignment[i], phi, atol=0.03 * DEG)
    assert np.abs(al.misalignment).max() > 1.0 * DEG
    assert al.config is not None
    np.testing.assert_allclose(al.config.mountings(), true @ true[0].T @ nom[0], atol=6e-4)
    # Eq. (45) reproduces the same relative rotation from the sensors' true C_b^n.
    c_imu_n = np.eye(3)
    c_b_n = [c_imu_n @ t.T for t in true]
    np.testing.assert_allclose(R.relative_rotation(c_b_n[3], c_b_n[0]), true[3] @ true[0].T, atol=1e-12)
    # Levelling: roll/pitch of a level IMU seen by the +z-face sensor (its frame = IMU frame).
    np.testing.assert_allclose(R.level([[0.0, 0.0, -9.8]]), [[0.0, 0.0]], atol=1e-12)


@pytest.fixture(scope="module")
def experiment_quick():
    """The report's redundancy experiments, quick mode (a few seconds)."""
    return X.run(quick=True)


def test_experiment_quick(experiment_quick) -> None:
    r = experiment_quick
    assert [round(row.k_r, 2) for row in r.geometry.table14] == [1.0, 0.71, 0.58, 0.5, 0.41]
    assert all(row.match for row in r.geometry.table14)
    # Fused cube vs a typical face: every threshold reached later, by about 1/k_r = √6
    # (Δt% ≈ +145 %) for bias-dominated drift; the median is over faces and runs.
    raw = {v.name: v for v in r.table15.variants}["raw output (no calibration)"]
    assert all(60 < row.dt_percent_median < 300 for row in raw.rows)
    for row in r.improvement.rows:
        assert row.noise_ratio == pytest.approx(row.k_r, rel=0.08)
        # ten simulated arrays in quick mode: bias and time ratios scatter around k_r
        assert (
            0.4 * row.k_r < row.bias_ratio < 2.0 * row.k_r and 0.4 * row.k_r < row.time_ratio < 2.0 * row.k_r
        )
    for f in r.fdi.rows:
        assert f.max_dev_fdi_deg_s < f.envelope_deg_s
        assert f.name.startswith("dropout") or f.max_dev_plain_deg_s > f.envelope_deg_s
    # mounting errors of σ 1°: recovered to the bias-instability limit with ideal sensors; the
    # preset's own 5 mrad axis misalignment and 5000 ppm scale factor limit it to tenths of °
    assert r.alignment.max_error_ideal_deg < 0.03
    assert 0.1 < r.alignment.max_error_preset_deg < 1.5
    # Kalman: with a zero-rate reference every axis bias is estimated to < 0.01 deg/s
    k = r.kalman.rows
    assert k[2].worst_bias_error_deg_s < 0.01 < k[1].worst_bias_error_deg_s


def test_cli_kr_and_fuse(tmp_path, cube6) -> None:
    import json

    r = CliRunner().invoke(main, ["redundancy", "kr", "--shape", "cube", "--per-face", "1", "--json"])
    assert r.exit_code == 0, r.output
    assert json.loads(r.output)["k_r"] == pytest.approx([1 / math.sqrt(2)] * 3)
    # `uasnav simulate --sensors cube6` writes the multi-sensor log the fusion reads.
    base = tmp_path / "cube.csv"
    r = CliRunner().invoke(
        main,
        ["simulate", "--preset", "lsm6dsm", "--sensors", "cube6", "--duration", "20", "--seed", "3"]
        + ["--out", str(base)],
    )
    assert r.exit_code == 0, r.output
    paths = [str(tmp_path / f"cube_s{i}.csv") for i in range(6)]
    logs = [read_csv_v1(p) for p in paths]
    truth = simulate_array("lsm6dsm", shape="cube", duration=20.0, seed=3)
    out = tmp_path / "fused.csv"
    for shape in ("cube", "meta"):  # the shape's geometry is the simulator's cube
        r = CliRunner().invoke(main, ["redundancy", "fuse", *paths, "--shape", shape, "--out", str(out)])
        assert r.exit_code == 0, r.output
        fused = read_csv_v1(out)
        assert fused.n == 2000
        # The output layout: CSV v1 header, the fusion's metadata, extra χ² and health columns.
        head = out.read_text().splitlines()[:6]
        assert head == [
            "# uasnav log format v1 (SI units: s, rad/s, m/s^2, degC, uT)",
            f"# fused_from: {' '.join(paths)}",
            f"# shape: {shape}",
            "# fdi: False",
            "# dropped_samples: 0",
            "t,gx,gy,gz,ax,ay,az,chi2_gyro,chi2_accel," + ",".join(f"health_{i}" for i in range(6)),
        ]
        # The library pipeline behind the command gives the same fused log.
        ff = R.fuse_files(paths, shape)
        np.testing.assert_array_equal(ff.fused_log().gyro, fused.gyro)
        assert ff.result.config.n_sensors == 6 and ff.summary()["written"] == 2000
        # Independent reference (simulator truth, numpy LS): the fused rate is the true IMU
        # rate plus the sensors' mean biases through the weighted LS (HᵀWH)⁻¹HᵀW (eq. 38),
        # W from each axis' Allan white noise, ± the averaged noise.
        h = cube6.axes
        wgt = 1 / np.concatenate([R.white_noise_sigma(lg.gyro) for lg in logs]) ** 2
        b = np.concatenate([lg.truth["gyro_bias"].mean(axis=0) for lg in truth])
        b_imu = np.linalg.solve(h.T @ (wgt[:, None] * h), h.T @ (wgt * b))
        w_imu = cube6.mountings()[0].T @ truth[0].truth["rate_true"][0]
        sigma_mean = R.white_noise_sigma(logs[0].gyro).max() / math.sqrt(6 * 2000)
        np.testing.assert_allclose(fused.gyro.mean(axis=0), w_imu + b_imu, atol=10 * sigma_mean)
        assert np.abs(b_imu).max() > 100 * sigma_mean  # the biases are what is being checked
    # A bias step on sensor 4 after 15 s: flagged by --fdi, dropped neither sample.
    for i in (4,):
        g = logs[i].gyro.copy()
        g[1500:, 0] += 1.0 * DEG
        write_csv_v1(replace(logs[i], gyro=g, truth={}), paths[i])
    r = CliRunner().invoke(
        main, ["redundancy", "fuse", *paths, "--shape", "cube", "--fdi", "--out", str(out), "--json"]
    )
    assert r.exit_code == 0, r.output
    s = json.loads(r.output)
    assert s["written"] == 2000
    assert s["flagged_samples_per_sensor"]["4"] > 450
    assert max(v for k, v in s["flagged_samples_per_sensor"].items() if k != "4") < 20
    r = CliRunner().invoke(main, ["redundancy", "fuse", *paths[:5], "--shape", "cube", "--out", str(out)])
    assert r.exit_code == 1 and "do not fill" in r.output
    # Three IMUs sharing the IMU frame (an autopilot's), no FDI: the fused rate is the
    # inverse-variance weighted mean of the three, weights from each axis' white noise.
    r = CliRunner().invoke(main, ["redundancy", "fuse", *paths[:3], "--shape", "aligned", "--out", str(out)])
    assert r.exit_code == 0, r.output
    fused = read_csv_v1(out)
    g3 = np.stack([read_csv_v1(p).gyro for p in paths[:3]])
    w = 1 / np.stack([R.white_noise_sigma(g) for g in g3]) ** 2
    np.testing.assert_allclose(fused.gyro, (g3 * w[:, None, :]).sum(0) / w.sum(0), rtol=1e-9, atol=1e-15)


def test_cli_simulate_every_polyhedron_fuses_in_glob_order(tmp_path) -> None:
    # 20 sensors: zero-padded file names keep a sorted glob in sensor order, and the face
    # order is the one `redundancy fuse --shape icosahedron` assumes.
    out = tmp_path / "ico.npz"
    r = CliRunner().invoke(
        main,
        [
            "simulate",
            "--preset",
            "lsm6dsm",
            "--sensors",
            "icosahedron20",
            "--duration",
            "2",
            "--out",
            str(out),
        ],
    )
    assert r.exit_code == 0, r.output
    files = sorted(tmp_path.glob("ico_s*.npz"))
    assert [f.name for f in files[:3]] == ["ico_s00.npz", "ico_s01.npz", "ico_s02.npz"] and len(files) == 20
    from uasnav.io import read_log

    mounts = np.array([read_log(f).meta["mounting"] for f in files], dtype=float)
    np.testing.assert_allclose(
        mounts, R.configuration("icosahedron", 1, triaxial=True).mountings(), atol=1e-15
    )


def test_ardupilot_three_imus(shared_data) -> None:
    from uasnav.experiments.ardupilot import analyse_log

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
