"""Thermal models against synthetic bias curves with known truth (no simulator needed)."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from uasnav import _core
from uasnav.errors import DataFormatError, InputError
from uasnav.thermal import (
    NeuralBiasModel,
    PolynomialBiasModel,
    Px4BiasModel,
    TemperatureRangeWarning,
    branch_from_temperature,
    choose,
    data_derivative,
    fit_hysteresis,
    forward,
    load_model,
    loads_model,
    select_hidden_neurons,
    select_polynomial_order,
    split_uniform,
    sr,
)


def truth(t: np.ndarray) -> np.ndarray:
    """A strongly non-linear bias (rad/s): a tanh knee, a sine and a parabola."""
    return np.stack(
        [1e-3 * np.tanh((t - 10) / 8) + 2e-4, 5e-4 * np.sin(t / 9), 3e-6 * (t - 5) ** 2 - 4e-4], 1
    )


def truth_derivative(t: np.ndarray) -> np.ndarray:
    return np.stack([1e-3 / 8 / np.cosh((t - 10) / 8) ** 2, 5e-4 / 9 * np.cos(t / 9), 6e-6 * (t - 5)], 1)


@pytest.fixture(scope="module")
def data() -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(1)
    t = np.linspace(-20.0, 37.0, 6000)
    return t, truth(t) + rng.normal(0.0, 5e-5, (t.size, 3))


@pytest.fixture(scope="module")
def nn(data: tuple[np.ndarray, np.ndarray]) -> NeuralBiasModel:
    return NeuralBiasModel(3, restarts=2, derivative_network=True).fit(*data)


T_TEST = np.linspace(-19.0, 36.0, 500)


def rms(x: np.ndarray) -> np.ndarray:
    return np.sqrt(np.mean(x**2, axis=0))


def test_polynomial_recovers_exact_cubic() -> None:
    t = np.linspace(-20, 40, 50)
    b = np.stack([1e-4 + 2e-5 * t - 3e-7 * t**2 + 4e-9 * t**3, -t * 1e-5, np.full_like(t, 7e-4)], 1)
    m = PolynomialBiasModel(3).fit(t, b)
    np.testing.assert_allclose(m.predict(t), b, atol=1e-15)
    db = np.stack([2e-5 - 6e-7 * t + 12e-9 * t**2, np.full_like(t, -1e-5), np.zeros_like(t)], 1)
    np.testing.assert_allclose(m.derivative(t), db, atol=1e-15)


def test_polynomial_high_order_is_well_conditioned() -> None:
    # Order 12 on −20…40 °C: a raw T^j basis would lose ~20 digits; the centred basis is exact.
    t = np.linspace(-20, 40, 400)
    b = (np.polynomial.Chebyshev(np.arange(13) * 1e-5, domain=[-20, 40])(t))[:, None]
    m = PolynomialBiasModel(12).fit(t, b)
    assert np.max(np.abs(m.predict(t) - b)) < 1e-15


def test_models_vs_truth(data: tuple[np.ndarray, np.ndarray], nn: NeuralBiasModel) -> None:
    t, b = data
    res_nn = rms(nn.predict(T_TEST) - truth(T_TEST))
    res_p2 = rms(PolynomialBiasModel(2).fit(t, b).predict(T_TEST) - truth(T_TEST))
    res_px4 = rms(Px4BiasModel().fit(t, b).predict(T_TEST) - truth(T_TEST))
    # The network reaches the noise floor / √n; the quadratic cannot follow the knee.
    assert np.all(res_nn < 1e-5)
    assert res_p2[0] > 1e-4 and res_px4[0] > 5e-5
    assert np.all(res_nn < res_px4)


def test_neural_rust_equals_numpy(nn: NeuralBiasModel) -> None:
    v_r, d_r, c_r = _core.mlp_evaluate_model(nn.model_json(), T_TEST, True, False)
    v_n = np.stack([forward(n, T_TEST)[0] for n in nn.networks_], 1)
    d_n = np.stack([forward(n, T_TEST)[1] for n in nn.networks_], 1)
    assert np.max(np.abs(v_r - v_n)) <= 1e-12
    assert np.max(np.abs(d_r - d_n)) <= 1e-12
    assert not c_r.any()


def test_numpy_derivative_matches_finite_difference(nn: NeuralBiasModel) -> None:
    h = 1e-4
    for net in nn.networks_:
        fd = (forward(net, T_TEST + h)[0] - forward(net, T_TEST - h)[0]) / (2 * h)
        np.testing.assert_allclose(forward(net, T_TEST)[1], fd, rtol=1e-6, atol=1e-12)


def test_derivative_models_both_ways(nn: NeuralBiasModel) -> None:
    true_d = truth_derivative(T_TEST)
    analytic = nn.derivative(T_TEST)
    network = nn.derivative(T_TEST, method="network")
    scale = rms(true_d)
    assert np.all(rms(analytic - true_d) < 0.1 * scale)
    # The network on the binned data derivative is noisier (differencing amplifies noise).
    assert np.all(rms(network - true_d) < 0.2 * scale)


def test_clipping_is_flagged_never_extrapolated(nn: NeuralBiasModel) -> None:
    t = np.array([-40.0, 0.0, 60.0])
    for m in (nn, PolynomialBiasModel(3).fit(T_TEST, truth(T_TEST))):
        with pytest.warns(TemperatureRangeWarning, match="2 of 3"):
            v, clipped = m.predict(t, return_clipped=True)
        assert clipped.tolist() == [True, False, True]
        lo, hi = m.range_c_
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            np.testing.assert_allclose(v[[0, 2]], m.predict(np.array([lo, hi])), rtol=0, atol=1e-18)
            assert np.all(m.derivative(t)[[0, 2]] == 0.0)


def test_quantised_temperature_robustness(data: tuple[np.ndarray, np.ndarray]) -> None:
    # A sensor with 1 °C resolution: the error is bounded by max|∂b/∂T|·0.5 °C plus the fit error.
    t, b = data
    m = PolynomialBiasModel(8).fit(np.round(t), b)
    err = np.abs(m.predict(T_TEST) - truth(T_TEST))
    bound = np.max(np.abs(truth_derivative(T_TEST)), axis=0) * 0.5 + 3e-5
    assert np.all(err.max(axis=0) < bound)


def test_split_uniform_fractions_and_coverage() -> None:
    t = np.random.default_rng(0).uniform(-20, 40, 10000)
    tr, va, te = split_uniform(t)
    assert (tr.size, va.size, te.size) == (6500, 2000, 1500)
    assert np.intersect1d(tr, va).size == 0 and np.intersect1d(va, te).size == 0
    for idx in (tr, va, te):  # every subset spans the range with the same density
        h = np.histogram(t[idx], bins=6, range=(-20, 40))[0] / idx.size
        np.testing.assert_allclose(h, 1 / 6, atol=0.01)


def test_order_selection_rule() -> None:
    assert choose((1, 2, 3, 4), np.array([10.0, 5.0, 4.9, 4.8])) == 2  # within 5 % of the minimum
    assert choose((1, 2, 3), np.array([3.0, 1.0, 2.0])) == 2
    assert sr(np.array([[3.0, 4.0, 0.0], [-3.0, -4.0, 0.0]])) == 5.0
    t = np.linspace(-20, 40, 3000)
    b = np.stack([1e-4 * ((t - 10) / 30) ** 3, 2e-4 * (t / 40) ** 2, 1e-5 * t], 1)
    b += np.random.default_rng(2).normal(0, 1e-6, b.shape)
    res = select_polynomial_order(t, b, orders=(1, 2, 3, 4, 5))
    assert res.chosen == 3  # the true order; higher orders only fit noise
    assert res.sr[2] < 0.2 * res.sr[1]
    assert res.sr[2] == pytest.approx(np.sqrt(3) * 1e-6, rel=0.1)  # the noise floor
    ax = res.plot(xlabel="order")  # Figure 31: the curve and the chosen order
    np.testing.assert_array_equal(ax.lines[0].get_ydata(), res.sr)
    assert ax.lines[1].get_xdata()[0] == 3 and ax.get_yscale() == "log"


def test_structure_selection_runs_and_prefers_enough_neurons(data: tuple[np.ndarray, np.ndarray]) -> None:
    t, b = data
    res = select_hidden_neurons(t, b, candidates=(1, 3), restarts=1, max_samples=1500)
    assert res.sr[1] < res.sr[0]
    assert res.chosen == 3
    d = select_hidden_neurons(t, b, candidates=(2,), restarts=1, derivative=True, max_samples=1500)
    assert 0 < d.sr[0] < 2e-5  # rad/s/°C, cf. thesis 1e-7 for its smoother gyro


def test_data_derivative_of_a_line() -> None:
    t = np.linspace(0, 10, 1001)
    tc, d = data_derivative(t, np.stack([2e-5 * t, -t * 1e-6], 1), 1.0)
    np.testing.assert_allclose(d, [[2e-5, -1e-6]] * tc.size, rtol=1e-9)


def test_hysteresis_width_recovered() -> None:
    t = np.concatenate([np.linspace(27, 34, 400), np.linspace(34, 27, 400)])
    time_s = np.arange(t.size) * 1.0
    heating = branch_from_temperature(time_s, t, smooth_s=5)
    assert heating[:390].all() and not heating[410:].any()
    shape = 2e-5 * (t - 30) + 1e-6 * (t - 30) ** 2
    b = np.stack([shape + np.where(heating, -1e-4, 1e-4)] * 3, 1)
    h = fit_hysteresis(t, b, heating, order=2)
    np.testing.assert_allclose(h.width, 2e-4, rtol=1e-9)
    assert np.all(h.width_std < 1e-12)  # noise-free data
    noisy = b + np.random.default_rng(0).normal(0, 1e-5, b.shape)
    hn = fit_hysteresis(t, noisy, heating, order=2)
    # σ_width ≈ σ·√(1/400 + 1/400) for two offsets of 400 samples each (shape adds a little).
    assert 0.9 * 1e-5 * np.sqrt(2 / 400) < hn.width_std[0] < 1.5 * 1e-5 * np.sqrt(2 / 400)
    assert np.all(np.abs(hn.width - 2e-4) < 4 * hn.width_std)
    np.testing.assert_allclose(h.derivative(np.array([30.0]))[0], 2e-5, rtol=1e-9)
    with pytest.raises(InputError, match="only one branch"):
        fit_hysteresis(t, b, np.ones(t.size, bool))


def test_px4_params_export(data: tuple[np.ndarray, np.ndarray]) -> None:
    m = Px4BiasModel().fit(*data)
    p = m.px4_params(instance=1, device_id=2293768)
    assert p["TC_G1_ID"] == 2293768
    assert p["TC_G1_TREF"] == pytest.approx(8.5)
    dt = 30.0 - p["TC_G1_TREF"]
    off = sum(p[f"TC_G1_X{j}_0"] * dt**j for j in range(4))
    assert off == pytest.approx(m.predict(np.array([30.0]))[0, 0], rel=1e-12)
    text = m.px4_param_file(instance=1)
    assert "1\t1\tTC_G1_X3_2\t" in text and "TC_G_ENABLE\t1\t6" in text


@pytest.mark.parametrize("kind", ["polynomial", "neural", "px4"])
def test_model_file_round_trip(tmp_path, data, nn, kind: str) -> None:
    t, b = data
    m = {"polynomial": PolynomialBiasModel(4).fit(t, b), "neural": nn, "px4": Px4BiasModel().fit(t, b)}[kind]
    path = tmp_path / "m.json"
    m.save(str(path), training={"source": "synthetic"})
    back = load_model(path)
    assert type(back) is type(m) and back.range_c_ == m.range_c_
    np.testing.assert_array_equal(back.predict(T_TEST), m.predict(T_TEST))
    assert back.training_meta_["source"] == "synthetic"
    assert not list(tmp_path.glob(".*.tmp"))


def test_model_file_errors(tmp_path, nn: NeuralBiasModel) -> None:
    text = nn.model_json()
    d = json.loads(text)
    d["models"][0]["layers"][0]["biases"][0] += 1e-9
    with pytest.raises(DataFormatError, match="checksum mismatch"):
        loads_model(json.dumps(d))
    with pytest.raises(DataFormatError, match="not valid JSON"):
        loads_model(text[: len(text) // 2])
    d = json.loads(text)
    d["schema_version"] = 2
    with pytest.raises(DataFormatError, match="schema_version 2"):
        loads_model(json.dumps(d))
    with pytest.raises(InputError, match="checksum mismatch"):  # the Rust loader verifies too
        _core.mlp_evaluate_model(json.dumps(d), T_TEST)
    from uasnav.thermal.modelfile import ZEROS, file_checksum

    d["checksum"]["value"] = ZEROS
    resigned = json.dumps(d)
    resigned = resigned.replace(ZEROS, file_checksum(resigned, ZEROS))
    with pytest.raises(InputError, match="schema_version 2"):  # a well-signed file of schema 2
        _core.mlp_evaluate_model(resigned, T_TEST)
    with pytest.raises(DataFormatError, match="schema_version 2"):
        loads_model(resigned)
    with pytest.raises(InputError, match="not a valid model file"):
        _core.mlp_evaluate_model(text[:100], T_TEST)
    from uasnav.thermal import dumps_model

    poly_text = dumps_model(PolynomialBiasModel(2).fit(T_TEST, truth(T_TEST)))
    with pytest.raises(InputError, match='kind "polynomial" holds no network'):
        _core.mlp_evaluate_model(poly_text, T_TEST)
    (tmp_path / "bad.json").write_bytes(b"\xff\xfe")
    with pytest.raises(DataFormatError, match="not a UTF-8"):
        load_model(tmp_path / "bad.json")


def test_bad_inputs() -> None:
    with pytest.raises(InputError, match="non-finite temperature at row 1"):
        PolynomialBiasModel(2).fit([1.0, np.nan, 3.0, 4.0], np.zeros((4, 3)))
    with pytest.raises(InputError, match="all temperatures are equal"):
        PolynomialBiasModel(1).fit(np.ones(10), np.zeros((10, 3)))
    with pytest.raises(InputError, match=r"expected shape \(5, k\)"):
        NeuralBiasModel(2).fit(np.arange(5.0), np.zeros((4, 3)))
    with pytest.raises(InputError, match="hidden"):
        NeuralBiasModel(17).fit(np.arange(50.0), np.zeros((50, 3)))
    with pytest.raises(AttributeError, match="call fit"):
        PolynomialBiasModel(2).predict([1.0])


def test_nguyen_widrow_spreads_the_first_layer() -> None:
    from uasnav.thermal.neural import nguyen_widrow

    p = nguyen_widrow(5, 5, np.random.default_rng(0))
    w1, b1 = p[:5], p[5:10]
    beta = 0.7 * 5
    np.testing.assert_allclose(np.abs(w1), beta)
    assert np.all(np.abs(b1) <= 1.1 * beta) and np.ptp(b1) > beta  # transitions cover [−1, 1]
    w2 = p[10:35].reshape(5, 5)
    np.testing.assert_allclose(np.linalg.norm(w2, axis=1), 0.7 * 5 ** (1 / 5))


def test_apply_subtracts_model_bias_and_counts_clipping(nn: NeuralBiasModel) -> None:
    from uasnav.imu import ImuLog
    from uasnav.thermal import apply

    temp = np.array([-30.0, 0.0, 20.0, 50.0])
    b = truth(np.clip(temp, -20, 37))
    log = ImuLog(t=np.arange(4.0), gyro=b + 1e-3, accel=np.zeros((4, 3)), temp=temp)
    with pytest.warns(TemperatureRangeWarning):
        cal = apply(nn, log)
    np.testing.assert_allclose(cal.gyro, 1e-3, atol=2e-5)
    assert cal.meta["thermal_calibration"]["clipped"] == 2
    with pytest.raises(InputError, match="no temperature"):
        apply(nn, ImuLog(t=np.arange(4.0), gyro=b, accel=np.zeros((4, 3))))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = nn.derivative(temp, method="network")
    assert np.all(d[[0, 3]] == 0.0) and np.all(d[[1, 2]] != 0.0)


def test_models_are_bias_models_registered_by_kind(data, nn: NeuralBiasModel) -> None:
    """The model file reader finds each model class by the file's kind (no import circle)."""
    from uasnav.thermal import BiasModel, dumps_model, model_class, register_model, registered_kinds

    t, b = data
    assert registered_kinds() == ("neural", "polynomial", "px4")
    for m in (PolynomialBiasModel(2).fit(t, b), nn, Px4BiasModel().fit(t, b)):
        assert isinstance(m, BiasModel)
        assert model_class(m.kind) is type(m)
        d = json.loads(dumps_model(m))
        assert set(d) == {
            "format", "schema_version", "kind", "quantity", "axes", "units", "calibrated_range_c",
            "models", "derivative_models", "training", "checksum",
        }  # fmt: skip
    with pytest.raises(InputError, match="unknown model kind 'spline'"):
        model_class("spline")

    class Other:
        kind = "polynomial"

    with pytest.raises(InputError, match="already registered"):
        register_model(Other)
    assert model_class("polynomial") is PolynomialBiasModel
    # A file of an unregistered kind (well signed) is refused by kind.
    from uasnav.thermal.modelfile import ZEROS, file_checksum

    d = json.loads(dumps_model(PolynomialBiasModel(2).fit(t, b)))
    d["kind"] = "spline"
    d["checksum"]["value"] = ZEROS
    text = json.dumps(d)
    with pytest.raises(DataFormatError, match="unknown model kind 'spline'"):
        loads_model(text.replace(ZEROS, file_checksum(text, ZEROS)))


def test_non_finite_model_is_not_saved(data) -> None:
    from uasnav.thermal import dumps_model

    m = PolynomialBiasModel(2).fit(*data)
    m.coef_[1, 2] = np.nan
    with pytest.raises(DataFormatError, match="non-finite"):
        dumps_model(m)


def test_bin_means_by_temperature_and_by_time() -> None:
    from uasnav.thermal import bin_by_temperature, bin_by_time

    rng = np.random.default_rng(3)
    temp = rng.uniform(-10.0, 30.0, 4000)
    vals = rng.normal(size=(4000, 3))
    tm, vm = bin_by_temperature(temp, vals, 0.5)
    # Every sample lands in one bin of 0.5 °C from the minimum (the maximum in the last one).
    edges = temp.min() + 0.5 * np.arange(tm.size + 1)
    for i in (0, tm.size // 2, tm.size - 1):
        m = (temp >= edges[i]) & (temp < edges[i + 1]) if i < tm.size - 1 else temp >= edges[i]
        assert tm[i] == pytest.approx(temp[m].mean(), rel=1e-12)
        np.testing.assert_allclose(vm[i], vals[m].mean(axis=0), rtol=1e-10, atol=1e-14)
    assert np.all(np.diff(tm) > 0)
    # data_derivative differentiates exactly these bin means.
    td, dd = data_derivative(temp, vals, 0.5)
    np.testing.assert_array_equal(td, tm)
    np.testing.assert_array_equal(dd, np.gradient(vm, tm, axis=0))
    # Time blocks: 10 samples at 10 Hz per 1 s block; a gap leaves no empty block behind.
    t = np.concatenate([np.arange(30) * 0.1, 10.0 + np.arange(10) * 0.1])
    tb, vb = bin_by_time(t, temp[:40], vals[:40], 1.0)
    assert tb.shape == (4,) and vb.shape == (4, 3)
    np.testing.assert_allclose(vb, vals[:40].reshape(4, 10, 3).mean(axis=1), rtol=1e-12)
    np.testing.assert_allclose(tb, temp[:40].reshape(4, 10).mean(axis=1), rtol=1e-12)
    same_t, same_v = bin_by_time(t, temp[:40], vals[:40], 0.0)
    assert np.array_equal(same_t, temp[:40]) and np.array_equal(same_v, vals[:40])
    with pytest.raises(InputError, match="width_c"):
        bin_by_temperature(temp, vals, 0.0)


def test_workflow_fit_and_evaluate(tmp_path, data) -> None:
    """The ``uasnav calibrate`` pipeline as library calls: load, fit, evaluate."""
    from uasnav.imu import ImuLog
    from uasnav.io.formats.csv_v1 import write_csv_v1
    from uasnav.thermal import evaluate_model, fit_polynomial, load_training_data

    t, b = data
    n = t.size
    log = ImuLog(
        t=np.arange(n) * 0.1, gyro=b, accel=np.tile([0.0, 0.0, -9.81], (n, 1)), temp=t,
        truth={"gyro_bias_thermal": truth(t)},
    )  # fmt: skip
    path = tmp_path / "train.csv"
    write_csv_v1(log, path)
    temp, bias = load_training_data(path, average_s=1.0)
    assert temp.shape == (n // 10,) and bias.shape == (n // 10, 3)
    np.testing.assert_allclose(bias, b.reshape(-1, 10, 3).mean(axis=1), rtol=1e-9, atol=1e-15)
    with pytest.raises(InputError, match=r"only 6 samples after 100\.0 s averaging"):
        load_training_data(path, average_s=100.0)
    fit = fit_polynomial(temp, bias, select=True)
    assert fit.selection is not None and fit.size == fit.selection.chosen == fit.model.order  # type: ignore[attr-defined]
    assert fit_polynomial(temp, bias, order=3).size == 3 and fit_polynomial(temp, bias).selection is None
    ev = evaluate_model(fit.model, log)
    # The block means span slightly less than the raw temperatures: the ends are clipped.
    lo, hi = fit.model.range_c_
    assert ev.n_samples == n and ev.clipped_samples == np.count_nonzero((t < lo) | (t > hi)) > 0
    assert ev.truth_key == "gyro_bias_thermal"
    res = b - fit.model.predict(np.clip(t, lo, hi))
    np.testing.assert_allclose(ev.residual.rms, rms(res), rtol=1e-12)
    assert ev.residual.sr == pytest.approx(sr(res), rel=1e-12)
    assert ev.error_vs_truth is not None and ev.error_vs_truth.sr < ev.residual.sr
    assert list(ev.residual.to_dict()) == ["mean", "rms", "max_abs", "sr"]
    bare = ImuLog(t=log.t, gyro=b, accel=log.accel, temp=t + 100.0)
    ev = evaluate_model(fit.model, bare)
    assert ev.clipped_samples == n and ev.truth_key is None and ev.error_vs_truth is None
    with pytest.raises(InputError, match=r"x\.csv: no temp column"):
        evaluate_model(fit.model, ImuLog(t=log.t, gyro=b, accel=log.accel), source="x.csv")
