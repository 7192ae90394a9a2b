"""ZUPT / TCZUPT: the Rust filter against filterpy (same model, dense matrices), against the
simulator's ground truth (``uasnav.sim``, AX1 preset), against the Earth model, error
handling, the CLI contract and the report's experiment. (The Rust stationarity detector
against the Python SHOE reference: tests/test_stationary.py.)"""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from uasnav import _core, earth, sim, zupt
from uasnav.cli import main
from uasnav.errors import InputError
from uasnav.imu import ImuLog
from uasnav.io import write_csv_v1

LAT = np.deg2rad(45.0)
W_IE = 7.292115e-5 * np.array([np.cos(LAT), 0.0, -np.sin(LAT)])
G45 = 9.806197769373233  # Somigliana at 45°, h = 0


def _skew(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


EULER = (0.012, -0.021, 0.4)  # roll, pitch, heading of the simulated static unit (rad)


class TrueCurve:
    """The simulator's own AX1 thermal curve (heating branch) as a calibration model: a
    perfect calibration, so the calibrated truth holds only the stochastic bias."""

    th = sim.thermal_model("ax1")

    def predict(self, temp):
        return self.th.branch_bias(temp, "heating")

    def derivative(self, temp):
        return self.th.derivative(temp)


@pytest.fixture(scope="module")
def ramp():
    # 60 s zeroing, then the first heating ramp of the thesis' ramp test (no reversal yet).
    log = sim.simulate("ax1", profile="cycles", duration=420.0, seed=4, euler_rad=EULER)
    return log, TrueCurve()


def test_covariance_matches_filterpy_with_the_same_dense_model():
    from filterpy.kalman import KalmanFilter

    n, dt = 350, 0.01
    gyro = np.tile(W_IE, (n, 1))  # noiseless static unit, level, heading north
    accel = np.tile([0.0, 0.0, -G45], (n, 1))
    cfg = zupt.ZuptConfig()
    core = cfg.filter_config("classic")
    out = _core.zupt_run(gyro, accel, dt, config=core, levelling_samples=100, heading_rad=0.0)
    # The same model in dense form (Groves ch. 14 as documented in nav_core::zupt).
    F = np.zeros((15, 15))
    F[0:3, 3:6] = np.eye(3)
    F[5, 2] = 2 * G45 / 6367489.5438  # 2g/r_eS at 45°
    F[3:6, 3:6] = -2 * _skew(W_IE)
    F[3:6, 6:9] = -_skew(np.array([0.0, 0.0, -G45]))
    F[3:6, 9:12] = -np.eye(3)
    F[6:9, 6:9] = -_skew(W_IE)
    F[6:9, 12:15] = -np.eye(3)
    sig = [
        core.sigma_vrw_m_s_sqrt_s,
        core.sigma_arw_rad_sqrt_s,
        core.sigma_abi_m_s2,
        core.sigma_gbi_rad_s,
    ]
    kf = KalmanFilter(dim_x=15, dim_z=9)
    kf.F = np.eye(15) + F * dt
    kf.Q = np.diag(np.r_[np.zeros(3), np.repeat(np.square(sig), 3)]) * dt
    kf.H = np.hstack([np.eye(9), np.zeros((9, 6))])
    kf.R = np.diag(
        np.repeat([cfg.meas_std_position_m, cfg.meas_std_velocity_m_s, cfg.meas_std_attitude_rad], 3) ** 2
    )
    kf.P = np.diag(
        np.repeat(
            [
                cfg.init_std_position_m,
                cfg.init_std_velocity_m_s,
                cfg.init_std_attitude_rad,
                cfg.init_std_accel_bias_m_s2,
                cfg.init_std_gyro_bias_rad_s,
            ],
            3,
        )
        ** 2
    )
    for k in range(n):
        kf.predict()
        if (k + 1) % 100 == 0:
            kf.update(np.zeros(9))
    np.testing.assert_allclose(out["cov_diag"][-1], np.diag(kf.P), rtol=2e-5)
    assert out["updates"] == 3
    np.testing.assert_allclose(out["gyro_bias"][-1], 0.0, atol=1e-12)


def test_bias_estimates_track_the_simulated_truth(ramp):
    log, model = ramp
    cfg = zupt.ZuptConfig(heading_rad=0.4, decimation=10)
    truth_cal = (log.truth["gyro_bias"] - model.predict(log.temp))[::10]
    r = zupt.run(log, "zupt", model, cfg)
    assert r.updates == 420
    e = np.abs(r.gyro_bias - truth_cal)[r.t > 200]
    # σ_ARW/√200 s ≈ 6.5e-5 rad/s; the filter's own 1σ is of that size: errors within 4σ.
    assert np.all(e < 4 * r.gyro_bias_std[r.t > 200]), e.max()
    assert 2e-5 < r.gyro_bias_std[-1, 0] < 8e-5
    # Accelerometer bias: z is observable through the zero-velocity measurement.
    assert abs(r.accel_bias[-1, 2] - log.truth["accel_bias"][0, 2]) < 4 * r.accel_bias_std[-1, 2]
    # TCZUPT on raw data estimates the total bias, and its dT/dt follows the 2 °C/min ramp.
    rt = zupt.run(log, "tczupt", model, cfg)
    et = np.abs(rt.gyro_bias - log.truth["gyro_bias"][::10])[rt.t > 200]
    assert np.all(et < 4 * rt.gyro_bias_std[rt.t > 200]), et.max()
    # The trailing 30 s least-squares slope is the true die-temperature rate 15 s earlier
    # (the die follows the 2 °C/min chamber ramp through its 90 s lag).
    true_rate = np.gradient(log.truth["temp_die"], log.t)
    lagged = np.interp(rt.t - 15.0, log.t, true_rate)
    ramping = (rt.t > 150) & (rt.t < 260)
    assert np.median(lagged[ramping]) > 0.01
    assert np.max(np.abs(rt.temp_rate[ramping] - lagged[ramping])) < 0.05 * np.median(lagged[ramping])
    assert np.all(r.temp_rate == 0.0)


def test_zeroing_starts_from_mean_minus_earth_rate(ramp):
    log, _ = ramp
    cfg = zupt.ZuptConfig(heading_rad=0.4, update_interval_s=1e6)  # no update: pure prediction
    r = zupt.run(log, "zupt", None, cfg)
    w_b = zupt._earth_rate_body(r.initial_attitude, 45.0)
    np.testing.assert_allclose(r.gyro_bias[0], log.gyro[:6000].mean(axis=0) - w_b, atol=1e-15)
    assert r.updates == 0
    res = zupt.run(log, "zupt", None, cfg.replace(residual_gyro_bias_rad_s=zupt.RESIDUAL_BIAS_15DEG_H))
    np.testing.assert_allclose(res.gyro_bias[0] - r.gyro_bias[0], zupt.RESIDUAL_BIAS_15DEG_H, atol=1e-15)


def test_stationary_mask_and_magnetic_heading(ramp):
    log, _ = ramp
    still = np.ones(log.n, dtype=bool)
    still[: log.n // 2] = False
    r = zupt.run(log, "zupt", None, zupt.ZuptConfig(), stationary=still)
    assert r.updates == 210
    # Magnetic heading: with 0.1 rad east declination the horizontal field points 0.1 rad east
    # of true north; a unit at true heading 0.4 reads magnetic heading 0.3, + D → 0.4.
    from uasnav.attitude import quat_to_dcm

    c_bn = quat_to_dcm(zupt.run(log, "zupt", None, zupt.ZuptConfig(heading_rad=0.4)).initial_attitude[None])[
        0
    ].T
    rot = np.array([[np.cos(0.1), -np.sin(0.1), 0], [np.sin(0.1), np.cos(0.1), 0], [0, 0, 1]])
    mag = np.tile(c_bn @ rot @ np.array([20.0, 0.0, 40.0]), (log.n, 1))
    log_m = ImuLog(t=log.t, gyro=log.gyro, accel=log.accel, temp=log.temp, mag=mag)
    rm = zupt.run(log_m, "zupt", None, zupt.ZuptConfig(declination_rad=0.1))
    from uasnav.attitude import quat_to_euler

    assert quat_to_euler(rm.initial_attitude[None])[0, 2] == pytest.approx(0.4, abs=1e-9)


def test_errors_name_what_is_wrong(ramp):
    log, _model = ramp
    with pytest.raises(InputError, match="model"):
        zupt.run(log, "tczupt")
    with pytest.raises(InputError, match="mode"):
        zupt.run(log, "kalman")  # type: ignore[arg-type]
    with pytest.raises(InputError, match="stationary"):
        zupt.run(log, stationary=np.ones(3, dtype=bool))
    g = np.zeros((100, 3))
    a = np.tile([0.0, 0.0, -9.8], (100, 1))
    g[57, 1] = np.nan
    with pytest.raises(InputError, match=r"gyro_rad_s.*57"):
        _core.zupt_run(g, a, 0.01, levelling_samples=10)
    with pytest.raises(InputError, match=r"config: .*no attribute 'mode'"):
        _core.zupt_run(np.zeros((100, 3)), a, 0.01, config={"sigma_arw": 1.0})  # not a config object
    with pytest.raises(InputError, match=r"config: .*sigma_arw_rad_sqrt_s"):
        _core.zupt_run(np.zeros((100, 3)), a, 0.01, config=zupt.FilterConfig(sigma_arw_rad_sqrt_s="x"))
    with pytest.raises(InputError, match="meas_std_velocity_m_s"):
        _core.zupt_run(np.zeros((100, 3)), a, 0.01, config=zupt.FilterConfig(meas_std_velocity_m_s=-1.0))
    with pytest.raises(InputError, match="accel"):
        _core.zupt_run(np.zeros((100, 3)), a[:50], 0.01)
    with pytest.raises(InputError, match="temp"):
        _core.zupt_run(np.zeros((100, 3)), a, 0.01, config=zupt.FilterConfig(mode="tczupt"))


def test_cli_writes_the_est_csv_contract(tmp_path):
    log = sim.simulate("ax1", profile="static", duration=120.0, seed=2, euler_rad=EULER)
    path = tmp_path / "static.csv"
    write_csv_v1(log, path)
    est, png = tmp_path / "EST.csv", tmp_path / "bias.png"
    r = CliRunner().invoke(
        main,
        ["zupt", str(path), "--residual-bias", "15deg/h", "--out", str(est), "--json", "--plot", str(png)],
    )
    assert r.exit_code == 0, r.output
    out = json.loads(r.output)
    assert out["updates"] == 120 and out["mode"] == "zupt"
    assert out["residual_bias_rad_s"] == pytest.approx(zupt.RESIDUAL_BIAS_15DEG_H)
    header = est.read_text().splitlines()[0].split(",")
    assert header[:7] == ["t", "bgx", "bgy", "bgz", "bax", "bay", "baz"]
    arr = np.loadtxt(est, delimiter=",", skiprows=1)
    assert arr.shape == (log.n, len(zupt.CSV_COLUMNS))
    np.testing.assert_allclose(arr[-1, 1:4], out["gyro_bias_rad_s"], rtol=1e-9)
    assert png.stat().st_size > 1000
    r = CliRunner().invoke(main, ["zupt", str(path), "--mode", "tczupt"])
    assert r.exit_code == 2 and "--model is required" in r.output
    # "classic" is the package's name of the same filter: same estimates, the mode echoed
    r = CliRunner().invoke(
        main, ["zupt", str(path), "--residual-bias", "15deg/h", "--json", "--mode", "classic"]
    )
    assert r.exit_code == 0, r.output
    classic = json.loads(r.output)
    assert classic["mode"] == "classic" and classic["gyro_bias_rad_s"] == out["gyro_bias_rad_s"]
    r = CliRunner().invoke(main, ["zupt", str(path), "--residual-bias", "15 m/s"])
    assert r.exit_code == 2 and "dimension" in r.output


def test_to_csv_is_an_io_table_with_the_csv_columns(tmp_path):
    """EST.csv is written by uasnav.io.write_csv_table: the CSV_COLUMNS in order, every float
    back bit for bit."""
    from uasnav.io import read_csv_table

    log = sim.simulate("ax1", profile="static", duration=65.0, seed=2, euler_rad=EULER)
    res = zupt.run(log, "zupt", None, zupt.ZuptConfig(decimation=50))
    res.to_csv(tmp_path / "EST.csv")
    cols, comments = read_csv_table(tmp_path / "EST.csv")
    assert tuple(cols) == zupt.CSV_COLUMNS and comments == {}
    np.testing.assert_array_equal(cols["t"], res.t)
    np.testing.assert_array_equal(np.column_stack([cols[c] for c in ("bgx", "bgy", "bgz")]), res.gyro_bias)
    np.testing.assert_array_equal(np.column_stack([cols[f"q{j}"] for j in range(4)]), res.attitude)
    np.testing.assert_array_equal(cols["sbaz"], res.accel_bias_std[:, 2])


def test_zupt_experiment_quick():
    """The ZUPT chapter's experiment (what ``uasnav report --only zupt`` renders)."""
    from uasnav.experiments import zupt as experiment

    r = experiment.run(quick=True)
    assert set(r.rms_vs_truth["nominal"]) == {"zupt", "tczupt"}
    assert set(r.rms_vs_ma["nominal"]) == {"zupt", "tczupt"}
    assert 0 < r.rms_vs_truth["nominal"]["zupt"][0] < 5e-4


def test_adis16405_turn_on_bias_matches_mean_minus_earth_rate(shared_data):
    """Real 2.78 h static ADIS16405 log: the ZUPT bias estimate (averaged after convergence)
    agrees with the long-term mean output minus the Earth rate."""
    from uasnav.noise import FilterNoise

    z = np.load(shared_data / "imu" / "adis16405_static_imu1.npz")
    gyro = np.deg2rad(z["gyro_dps"])
    n = gyro.shape[0]
    log = ImuLog(t=np.arange(n) / float(z["rate_hz"]), gyro=gyro, accel=z["accel_g"] * 9.80665)
    noise = FilterNoise.from_datasheet(arw="2.4 deg/√h", gbi="1.5e-4 deg/s", vrw="0.2 m/s/√h", abi="2 m/s/h")
    cfg = zupt.ZuptConfig(noise=noise, latitude_deg=51.08, heading_rad=0.0, decimation=100)
    r = zupt.run(log, "zupt", None, cfg)
    expected = gyro.mean(axis=0) - zupt._earth_rate_body(r.initial_attitude, 51.08)
    est = r.gyro_bias[r.t > 600].mean(axis=0)
    # Turn-on biases are ≈ 7e-3 rad/s (0.4 deg/s); agreement to 1e-4 rad/s (1.5 %) or better.
    assert np.all(np.abs(expected) > 4e-3)
    np.testing.assert_allclose(est, expected, atol=1e-4)


def test_xio_stationary_intervals_detected_and_used(shared_data):
    """Real x-IMU log (handled, about half at rest): the GLRT detector finds the rest periods,
    and ZUPT on them estimates the bias of the first rest period as the mean gyro output."""
    d = np.genfromtxt(shared_data / "imu" / "xio_fusion_sensor_data.csv", delimiter=",", skip_header=1)
    t = d[:, 0]
    tu = np.arange(t[0], t[-1], 0.01)  # the recording has gaps: resample to a uniform 100 Hz

    def interp(x):
        return np.column_stack([np.interp(tu, t, x[:, j]) for j in range(x.shape[1])])

    log = ImuLog(t=tu, gyro=interp(np.deg2rad(d[:, 1:4])), accel=interp(d[:, 4:7] * 9.80665))
    s = zupt.detect_stationary(log)
    assert 0.35 < s.mask.mean() < 0.55
    first = s.intervals[0]
    assert first[0] == pytest.approx(tu[0]) and first[1] - first[0] > 10.0
    r = zupt.run(log, "zupt", None, zupt.ZuptConfig(levelling_s=10.0), stationary="auto")
    assert 0 < r.updates <= int(s.mask.sum() / 100) + len(s.intervals)
    end = int(np.searchsorted(tu, first[1])) - 1
    w_b = zupt._earth_rate_body(r.initial_attitude, 45.0)
    mean_rest = log.gyro[: end + 1].mean(axis=0) - w_b
    assert np.all(np.abs(r.gyro_bias[end] - mean_rest) < 3 * r.gyro_bias_std[end])
    assert np.all(np.isfinite(r.gyro_bias)) and np.all(r.cov_diag > 0)
    # The Rust detector's statistic is the GLRT formula evaluated directly (centred window).
    k = 3000
    win = slice(k - 12, k + 13)  # the default 0.25 s window: 25 samples centred on k
    a, g = log.accel[win], log.gyro[win]
    u = a.mean(axis=0) / np.linalg.norm(a.mean(axis=0))
    direct = np.mean(np.sum((a - 9.80665 * u) ** 2, axis=1) / 0.05**2 + np.sum(g**2, axis=1) / 0.01**2)
    assert s.statistic[k] == pytest.approx(direct, rel=1e-9)


def test_rust_earth_model_matches_closed_forms():
    """nav_core::earth (what the filter uses) against the WGS-84 closed forms written out here
    (Somigliana, Groves eq. 2.139 free-air factor, radii of curvature)."""
    a, e2, f = 6378137.0, 6.69437999014e-3, 1 / 298.257223563
    b, mu, w = 6356752.31425, 3.986004418e14, 7.292115e-5
    for lat_deg, h in ((0.0, 0.0), (45.0, 0.0), (51.08, 1100.0), (-89.0, 50.0), (90.0, 0.0)):
        lat = np.deg2rad(lat_deg)
        s2 = np.sin(lat) ** 2
        g0 = 9.7803253359 * (1 + 0.00193185265241 * s2) / np.sqrt(1 - e2 * s2)
        g = g0 * (1 - 2 * h / a * (1 + f * (1 - 2 * s2) + w * w * a * a * b / mu) + 3 * h * h / a**2)
        assert _core.earth_normal_gravity(lat, h) == pytest.approx(g, rel=1e-14)
        np.testing.assert_allclose(
            _core.earth_rate_ned(lat), w * np.array([np.cos(lat), 0, -np.sin(lat)]), atol=1e-20
        )
        rn, re = _core.earth_radii(lat)
        assert rn == pytest.approx(a * (1 - e2) / (1 - e2 * s2) ** 1.5, rel=1e-14)
        assert re == pytest.approx(a / np.sqrt(1 - e2 * s2), rel=1e-14)
    with pytest.raises(InputError, match="latitude_rad"):
        _core.earth_normal_gravity(float("nan"), 0.0)


def test_rust_earth_model_matches_uasnav_earth():
    """The filter's Earth model (nav_core::earth) and the simulator's (uasnav.earth) agree, so
    a simulated static unit is static for the filter."""
    for lat_deg, h in ((0.0, 0.0), (45.0, 0.0), (51.08, 1100.0), (-33.9, 20.0), (89.5, 3000.0)):
        lat = np.deg2rad(lat_deg)
        assert _core.earth_normal_gravity(lat, h) == pytest.approx(earth.normal_gravity(lat, h), rel=1e-12)
        np.testing.assert_allclose(_core.earth_rate_ned(lat), earth.earth_rate_ned(lat), rtol=1e-15, atol=0)
        np.testing.assert_allclose(
            [0.0, 0.0, _core.earth_normal_gravity(lat, h)], earth.gravity_ned(lat, h), rtol=1e-12
        )


def test_tczupt_cli_with_a_model_file_and_the_derivative_network(tmp_path):
    """`uasnav zupt --mode tczupt --model M.json` on a simulated ramp: the model comes from a
    simulated soak (the calibration issue's file format); the CLI result equals the API's, and
    the estimate agrees with the simulator's true bias."""
    from uasnav.sim.lab import soak_calibration_data
    from uasnav.thermal import NeuralBiasModel, PolynomialBiasModel, load_model, save_model

    cal = soak_calibration_data("ax1", seed=11, rate=1.0)
    nn = NeuralBiasModel(2, restarts=2, derivative_network=True, seed=0).fit(cal.temp, cal.gyro_bias)
    mpath = tmp_path / "M.json"
    save_model(nn, mpath)
    log = sim.simulate("ax1", profile="cycles", duration=300.0, rate=50.0, seed=12, euler_rad=EULER)
    lpath, est = tmp_path / "ramp.csv", tmp_path / "EST.csv"
    write_csv_v1(log, lpath)
    r = CliRunner().invoke(
        main,
        ["zupt", str(lpath), "--mode", "tczupt", "--model", str(mpath), "--heading-deg", "22.918",
         "--json", "--out", str(est)],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    out = json.loads(r.output)
    api = zupt.run(log, "tczupt", load_model(mpath), zupt.ZuptConfig(heading_rad=np.deg2rad(22.918)))
    np.testing.assert_allclose(out["gyro_bias_rad_s"], api.gyro_bias[-1], rtol=1e-9)
    assert out["mode"] == "tczupt" and out["updates"] == 300
    err = np.abs(api.gyro_bias[-1] - log.truth["gyro_bias"][-1])
    assert np.all(err < 4 * api.gyro_bias_std[-1]), (err, api.gyro_bias_std[-1])
    assert np.loadtxt(est, delimiter=",", skiprows=1).shape == (log.n, len(zupt.CSV_COLUMNS))

    # ∂b/∂T from the derivative networks (eq. 37) instead of the analytic derivative.
    class NetworkDerivative:
        def predict(self, temp):
            return nn.predict(temp)

        def derivative(self, temp):
            return nn.derivative(temp, method="network")

    cfg = zupt.ZuptConfig(derivative="network", decimation=50)
    via_option = zupt.run(log, "tczupt", nn, cfg)
    r = CliRunner().invoke(
        main,
        ["zupt", str(lpath), "--mode", "tczupt", "--model", str(mpath), "--heading-deg", "22.918",
         "--derivative", "network", "--json"],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    via_cli = json.loads(r.output)
    assert via_cli["derivative"] == "network"
    np.testing.assert_allclose(
        via_cli["gyro_bias_rad_s"],
        zupt.run(
            log, "tczupt", nn, zupt.ZuptConfig(heading_rad=np.deg2rad(22.918), derivative="network")
        ).gyro_bias[-1],
        rtol=1e-9,
    )
    assert not np.allclose(via_cli["gyro_bias_rad_s"], out["gyro_bias_rad_s"], rtol=1e-9, atol=0)
    via_wrapper = zupt.run(log, "tczupt", NetworkDerivative(), cfg.replace(derivative="analytic"))
    np.testing.assert_array_equal(via_option.gyro_bias, via_wrapper.gyro_bias)
    assert not np.array_equal(
        via_option.gyro_bias, zupt.run(log, "tczupt", nn, cfg.replace(derivative="analytic")).gyro_bias
    )
    poly = PolynomialBiasModel(3).fit(cal.temp, cal.gyro_bias)
    with pytest.raises(InputError, match="derivative network"):
        zupt.run(log, "tczupt", poly, cfg)
    with pytest.raises(InputError, match=r"config\.derivative"):
        zupt.run(log, "tczupt", nn, cfg.replace(derivative="numeric"))


def test_eq31_with_the_calibration_derivative_is_equivalent_to_calibrating_first():
    """The report's finding as an identity: with the same Q, TCZUPT on raw data (bias
    propagated by ∂b/∂T·dT/dt) and ZUPT on data calibrated by the same model estimate the same
    total bias, up to the lag of the 30 s dT/dt slope — over a run with a temperature
    reversal and the preset's hysteresis step."""
    log = sim.simulate("ax1", profile="cycles", duration=900.0, seed=5, euler_rad=EULER)
    model = TrueCurve()
    cfg = zupt.ZuptConfig(heading_rad=EULER[2], decimation=10, noise=zupt.THESIS_TCZUPT_NOISE)
    rz = zupt.run(log, "zupt", model, cfg)
    rt = zupt.run(log, "tczupt", model, cfg)
    total_z = rz.gyro_bias + model.predict(log.temp)[::10]
    assert np.abs(rt.gyro_bias - total_z).max() < 0.35 * rz.gyro_bias_std[-1].min()
    truth = log.truth["gyro_bias"][::10]
    np.testing.assert_allclose(zupt.rms_error(rt.gyro_bias, truth), zupt.rms_error(total_z, truth), rtol=0.1)
    assert np.ptp(log.truth["temp_die"]) > 6.0  # the run really crosses the ramp range
