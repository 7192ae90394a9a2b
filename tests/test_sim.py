"""Simulator validation against its configured error model and closed forms."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from uasnav import earth
from uasnav.allan import oadev
from uasnav.errors import DataFormatError, InputError
from uasnav.experiments import simulator as exp
from uasnav.experiments.thesis import FIG29_SOAK_RANGE_C, TABLE3, TABLE4
from uasnav.noise import identify
from uasnav.sim import (
    FAULT_KINDS,
    PRESET_NAMES,
    array_mountings,
    inject_fault,
    load_preset,
    simulate,
    simulate_array,
    thermal_bias,
    thermal_bias_derivative,
)
from uasnav.units import convert

# A gyro whose three noise terms are all visible in a 2e5 s record (lsm6dsm white noise).
N_TEST = float(convert(3.8, "mdps/√Hz", "rad/√s"))
B_TEST = float(convert(0.003, "deg/s", "rad/s"))
K_TEST = 2e-5


def _noise_only(white: float, b: float, k: float):
    m = load_preset("lsm6dsm").without(
        "thermal",
        "turn_on_bias",
        "quantization",
        "scale_factor",
        "misalignment",
        "g_sensitivity",
        "antialias",
    )
    return replace(m, gyro=replace(m.gyro, white=white, bias_instability=b, rate_random_walk=k))


def _identify(model, seed: int):
    log = simulate(model, duration=2e5, rate=10.0, seed=seed)
    curve = oadev(log.gyro - log.truth["rate_true"], 10.0, "octave", unit="rad/s")
    return identify(curve)


def test_presets_load_with_sources_and_thesis_values() -> None:
    for name in PRESET_NAMES:
        m = load_preset(name)
        assert m.name == name and m.sources
    crs = load_preset("crs05-02")
    assert convert(crs.gyro.white, "rad/√s", "deg/√h") == pytest.approx(3.18)
    assert convert(crs.gyro.bias_instability, "rad/s", "deg/s") == pytest.approx(1.5e-4)
    ms = load_preset("ms8010")
    assert convert(ms.accel.white, "m/s/√s", "m/s/√h") == pytest.approx(0.05)
    assert convert(ms.accel.bias_instability, "m/s^2", "m/s/h") == pytest.approx(2.0)
    lsm = load_preset("lsm6dsm")
    assert convert(lsm.gyro.white, "rad/√s", "mdps/√Hz") == pytest.approx(3.8)
    assert convert(lsm.accel.white, "m/s/√s", "µg/√Hz") == pytest.approx(40.0)
    ax1 = load_preset("ax1")
    assert ax1.gyro.white == crs.gyro.white and ax1.accel.white == ms.accel.white
    assert ax1.antialias_hz == 30.0
    with pytest.raises(InputError, match="unknown preset"):
        load_preset("nope")
    with pytest.raises(DataFormatError, match="no such preset file"):
        load_preset("/nonexistent/p.json")


def test_allan_recovers_arw_and_bias_instability_within_10_percent() -> None:
    rep = _identify(_noise_only(N_TEST, B_TEST, 0.0), seed=11)
    np.testing.assert_allclose(rep.fit.random_walk, N_TEST, rtol=0.10)
    b_pooled = math.sqrt(float(np.mean(rep.fit.bias_instability**2)))
    assert b_pooled == pytest.approx(B_TEST, rel=0.10)
    assert np.all(rep.fit.rate_random_walk < 0.05 * K_TEST)  # none configured


def test_allan_recovers_arw_and_rate_random_walk_within_10_percent() -> None:
    rep = _identify(_noise_only(N_TEST, 0.0, K_TEST), seed=12)
    np.testing.assert_allclose(rep.fit.random_walk, N_TEST, rtol=0.10)
    k_pooled = math.sqrt(float(np.mean(rep.fit.rate_random_walk**2)))
    assert k_pooled == pytest.approx(K_TEST, rel=0.10)


def test_static_mean_is_earth_rate_plus_true_bias() -> None:
    lat = 45.0
    log = simulate(
        "ax1", duration=600.0, rate=100.0, seed=3, latitude_deg=lat, euler_rad=(0.0, 0.0, math.pi / 2)
    )
    # yaw 90°: body x east, y south, z down
    w = earth.OMEGA_IE * np.array([0.0, -math.cos(math.radians(lat)), -math.sin(math.radians(lat))])
    np.testing.assert_allclose(log.truth["rate_true"][0], w, atol=1e-18)
    g = earth.normal_gravity(math.radians(lat), 0.0)
    np.testing.assert_allclose(log.truth["specific_force_true"][0], [0.0, 0.0, -g], atol=1e-15)
    m = load_preset("ax1")
    sigma_mean = m.gyro.white * 1.3 / math.sqrt(log.duration)  # ×1.3: noise rises with T (noise_tc)
    resid = (log.gyro - log.truth["rate_true"] - log.truth["gyro_bias"]).mean(axis=0)
    assert np.all(np.abs(resid) < 4 * sigma_mean)
    expected = w + log.truth["gyro_bias"].mean(axis=0)
    np.testing.assert_allclose(log.gyro.mean(axis=0), expected, atol=4 * sigma_mean)
    # the bias is a real, non-trivial part of the output (turn-on 0.05 deg/s 1-σ)
    assert np.max(np.abs(log.truth["gyro_bias"].mean(axis=0))) > 10 * sigma_mean
    sig_a = m.accel.white * 1.3 / math.sqrt(log.duration)
    resid_a = (log.accel - log.truth["specific_force_true"] - log.truth["accel_bias"]).mean(axis=0)
    assert np.all(np.abs(resid_a) < 4 * sig_a)


def test_deterministic_and_seed_dependent() -> None:
    a = simulate("lsm6dsm", duration=5.0, seed=7)
    b = simulate("lsm6dsm", duration=5.0, seed=7)
    c = simulate("lsm6dsm", duration=5.0, seed=8)
    assert np.array_equal(a.gyro, b.gyro) and np.array_equal(a.accel, b.accel)
    assert np.array_equal(a.truth["gyro_bias"], b.truth["gyro_bias"])
    assert not np.array_equal(a.gyro, c.gyro)
    assert a.meta["seed"] == 7 and a.meta["preset"] == "lsm6dsm" and a.meta["profile"] == "static"


def test_quantisation_and_antialias() -> None:
    log = simulate("lsm6dsm", duration=20.0, rate=400.0, seed=1)
    lsb = float(convert(8.75, "mdps", "rad/s"))
    k = log.gyro / lsb
    np.testing.assert_allclose(k, np.round(k), atol=1e-6)
    # 2nd-order 30 Hz low-pass at 400 Hz: white noise variance shrinks to ≈ fc·π/(2·fs/2)·…;
    # compare with the unfiltered run of the same seed
    raw = simulate(load_preset("lsm6dsm").without("antialias"), duration=20.0, rate=400.0, seed=1)
    ratio = np.std(log.gyro - log.truth["gyro_bias"], axis=0) / np.std(
        raw.gyro - raw.truth["gyro_bias"], axis=0
    )
    # Butterworth n=2 equivalent noise bandwidth = fc·π/(2n·sin(π/2n)) = 1.11·fc = 33.3 Hz of 200 Hz
    np.testing.assert_allclose(ratio, math.sqrt(33.32 / 200.0), rtol=0.05)
    assert log.meta["antialias_hz"] == 30.0
    assert simulate("lsm6dsm", duration=2.0, rate=50.0).meta["antialias_hz"] is None


def test_temperature_channel_is_quantised_die_temperature() -> None:
    m = replace(load_preset("ax1"), temperature=replace(load_preset("ax1").temperature, resolution_c=1.0))
    log = simulate(m, profile="ramp", rate=10.0, seed=2)
    assert log.temp is not None
    np.testing.assert_array_equal(log.temp, np.round(log.truth["temp_die"]))
    assert np.max(np.abs(log.temp - log.truth["temp_die"])) <= 0.5
    # die lags the chamber (first order, τ = 90 s) and is self-heated by 6 °C
    die, ch = log.truth["temp_die"], log.truth["temp_chamber"]
    assert die.max() == pytest.approx(34.08, abs=0.05)
    assert die.min() == pytest.approx(27.28, abs=0.05)
    i_top = int(np.argmax(ch))
    assert die[i_top] < ch[i_top] + 6.0 - 1.0


def test_soak_profile_reaches_thesis_temperatures() -> None:
    log = simulate("ax1", profile="soak", rate=1.0, seed=0)
    die = log.truth["temp_die"]
    assert die.min() == pytest.approx(-20.53, abs=0.02)
    assert die.max() == pytest.approx(37.30, abs=0.02)
    assert np.all(np.diff(die) >= -1e-9)  # heating only


def test_hysteresis_branches_differ_by_configured_offset() -> None:
    m = load_preset("ax1")
    h = m.gyro.thermal.hysteresis  # type: ignore[union-attr]
    temps = np.linspace(28.0, 33.0, 11)
    diff = thermal_bias(m, temps, "heating") - thermal_bias(m, temps, "cooling")
    np.testing.assert_allclose(diff, h, rtol=1e-12)
    d_h = thermal_bias_derivative(m, temps, "heating")
    eps = 1e-4
    num = (thermal_bias(m, temps + eps) - thermal_bias(m, temps - eps)) / (2 * eps)
    np.testing.assert_allclose(d_h, num, rtol=1e-6, atol=1e-12)

    log = simulate(m, profile="ramp", rate=50.0, seed=4)
    die = log.truth["temp_die"]
    top = int(np.argmax(die))
    th = log.truth["gyro_bias_thermal"]
    # truth: at equal temperature the cooling branch lies h below the heating branch
    w_c = m.gyro.thermal.hysteresis_width_c  # type: ignore[union-attr]
    for temp in (29.0, 30.0, 31.0, 32.5):
        i_up = int(np.argmin(np.abs(die[:top] - temp)))
        i_dn = top + int(np.argmin(np.abs(die[top:] - temp)))
        # branch state relaxes over the temperature travel since the reversal at the top
        s_dn = -1.0 + 2.0 * math.exp(-(die[top] - die[i_dn]) / w_c)
        np.testing.assert_allclose(th[i_up] - th[i_dn], 0.5 * h * (1.0 - s_dn), rtol=2e-3)
        if temp <= 31.0:
            np.testing.assert_allclose(th[i_up] - th[i_dn], h, rtol=0.01)
        np.testing.assert_allclose(th[i_up], thermal_bias(m, die[i_up : i_up + 1], "heating")[0], rtol=0.01)
    # output: remove the known branch-free curve, the branch means differ by h
    curve = m.gyro.thermal.curve(die)  # type: ignore[union-attr]
    r = log.gyro - log.truth["rate_true"] - curve
    band = (die > 29.0) & (die < 33.0)
    up = band & (np.arange(log.n) < top)
    dn = band & (np.arange(log.n) > top)
    diff_out = r[up].mean(axis=0) - r[dn].mean(axis=0)
    se = m.gyro.white * math.sqrt(50.0) * math.sqrt(1 / up.sum() + 1 / dn.sum())
    assert np.all(np.abs(diff_out - h) < 4 * se)
    # pooled over the three axes (same offset on each): clearly non-zero and equal to h
    se_pooled = se / math.sqrt(3.0)
    assert abs(diff_out.mean() - h) < 4 * se_pooled
    assert diff_out.mean() > 6 * se_pooled


def test_cube_array_has_independent_errors_and_mountings() -> None:
    logs = simulate_array("lsm6dsm", shape="cube", duration=5.0, rate=100.0, seed=5)
    assert len(logs) == 6
    for log in logs:
        c = np.array(log.meta["mounting"])
        np.testing.assert_allclose(c @ c.T, np.eye(3), atol=1e-15)
        assert np.linalg.det(c) == pytest.approx(1.0)
        g = log.truth["specific_force_true"][0]
        np.testing.assert_allclose(c.T @ g, logs[2].truth["specific_force_true"][0], atol=1e-12)
    # faces +x, +y, +z, −x, −y, −z: sensor z along the outward normal
    normals = np.array([np.array(log.meta["mounting"])[2] for log in logs])
    np.testing.assert_array_equal(normals, np.vstack([np.eye(3), -np.eye(3)]))
    assert logs[2].meta["mounting"] == np.eye(3).tolist()
    on = [log.truth["gyro_bias"][0] for log in logs]
    assert len({tuple(np.round(b, 12)) for b in on}) == 6
    with pytest.raises(InputError, match="shape"):
        simulate_array("lsm6dsm", shape="sphere", duration=1.0)


@pytest.mark.parametrize(("shape", "faces"), [("tetrahedron", 4), ("octahedron", 8), ("icosahedron", 20)])
def test_polyhedron_arrays_share_the_fusion_geometry(shape: str, faces: int) -> None:
    from uasnav import redundancy

    logs = simulate_array("lsm6dsm", shape=shape, per_face=2, duration=0.5, seed=1)
    assert len(logs) == 2 * faces
    m = np.array([log.meta["mounting"] for log in logs])
    np.testing.assert_array_equal(m, redundancy.configuration(shape, 2, triaxial=True).mountings())
    # every sensor's z axis is an outward face normal, each normal carries two sensors
    normals = redundancy.face_normals(shape)
    hits = np.isclose(m[:, 2, :] @ normals.T, 1.0)
    assert hits.sum(axis=1).tolist() == [1] * 2 * faces and hits.sum(axis=0).tolist() == [2] * faces


def test_mounting_errors_and_rerecording_the_same_array() -> None:
    mounts = np.array(array_mountings("cube"))
    kw = dict(mountings=mounts, mounting_error_rad=0.01, duration=2.0, seed=3)
    a = simulate_array("lsm6dsm", **kw)
    b = simulate_array("lsm6dsm", noise_seed=1, **kw)
    assert a[0].meta["array_shape"] == "user" and b[0].meta["noise_seed"] == 1
    f_body = -earth.gravity_ned(math.radians(45.0), 0.0)  # level: body = NED
    angles = []
    for la, lb, m in zip(a, b, mounts, strict=True):
        assert la.meta["mounting"] == m.tolist()
        c = np.array(la.meta["mounting_true"])
        np.testing.assert_allclose(c @ c.T, np.eye(3), atol=1e-12)
        assert np.linalg.det(c) == pytest.approx(1.0)
        angles.append(np.arccos(np.clip((np.trace(c @ m.T) - 1) / 2, -1, 1)))
        # truth channels are in the sensor's actual frame
        np.testing.assert_allclose(la.truth["specific_force_true"][0], c @ f_body, atol=1e-12)
        # re-recorded: same hardware (mounting, turn-on bias ~1 deg/s), fresh noise
        assert lb.meta["mounting_true"] == la.meta["mounting_true"]
        assert np.abs(la.truth["gyro_bias"][0] - lb.truth["gyro_bias"][0]).max() < 5e-4
        assert np.abs(la.gyro - lb.gyro).max() > 1e-3
    # rotation angle of a 3-D normal rotation vector with σ = 0.01 rad per axis: RMS √3·σ
    assert 0.005 < float(np.sqrt(np.mean(np.square(angles)))) < 0.03
    with pytest.raises(InputError, match="mountings"):
        simulate_array("lsm6dsm", mountings=np.eye(3), duration=1.0)
    with pytest.raises(InputError, match="mounting_error_rad"):
        simulate_array("lsm6dsm", mounting_error_rad=-1.0, duration=1.0)


def test_bad_arguments_name_the_argument() -> None:
    with pytest.raises(InputError, match="rate"):
        simulate("ax1", duration=1.0, rate=-1.0)
    with pytest.raises(InputError, match="duration"):
        simulate("ax1", duration=float("nan"))
    with pytest.raises(InputError, match="profile"):
        simulate("ax1", profile="boil", duration=1.0)
    with pytest.raises(InputError, match="branch"):
        thermal_bias("ax1", [20.0], "sideways")


def test_warmup_and_user_profiles() -> None:
    from uasnav.sim import TemperatureProfile

    m = load_preset("lsm6dsm")
    tm = m.temperature
    log = simulate(m, profile="warmup", rate=10.0, seed=1)
    die = log.truth["temp_die"]
    assert log.duration == pytest.approx(5 * tm.warmup_tau_s, abs=0.2)
    # chamber constant at ambient; die = ambient + ΔT (1 − e^(−t/τ)) exactly (no lag needed)
    i = round(tm.warmup_tau_s * 10.0)
    assert die[i] - tm.ambient_c == pytest.approx(tm.self_heating_c * (1 - math.exp(-1)), rel=1e-3)
    prof = TemperatureProfile.from_arrays([0.0, 100.0, 200.0], [10.0, 30.0, 30.0])
    log = simulate(m, profile=prof, rate=10.0, seed=1)
    assert log.meta["profile"] == "user" and log.duration == pytest.approx(200.0, abs=0.2)
    np.testing.assert_allclose(log.truth["temp_chamber"][[0, 1000, 1999]], [10.0, 30.0, 30.0], atol=1e-9)
    with pytest.raises(InputError, match="profile t"):
        TemperatureProfile.from_arrays([0.0, 0.0], [1.0, 2.0])


def test_array_thermal_truth_matches_thermal_bias_with_factors() -> None:
    logs = simulate_array("lsm6dsm", shape="planar", per_face=3, profile="ramp", rate=5.0, seed=2)
    assert len(logs) == 3 and all(log.meta["mounting"] == np.eye(3).tolist() for log in logs)
    for log in logs:
        die = log.truth["temp_die"]
        top = int(np.argmax(die))
        f = log.meta["thermal_factors"]
        assert all(0.5 <= abs(v) <= 1.5 for v in f)
        np.testing.assert_allclose(
            log.truth["gyro_bias_thermal"][:top:50],
            thermal_bias("lsm6dsm", die[:top:50], "heating", factors=f),
            rtol=1e-3,
            atol=1e-9,
        )
    assert logs[0].meta["thermal_factors"] != logs[1].meta["thermal_factors"]


def test_rate_table_truth_is_consistent_with_attitude_propagation() -> None:
    from uasnav.attitude import propagate, quat_to_dcm

    lat = math.radians(45.0)
    om = 10.0  # deg/s, 36 s per turn
    log = simulate(
        "lsm6dsm", duration=72.0, rate=100.0, seed=6, table_rate_dps=om, euler_rad=(0.1, -0.05, 0.3)
    )
    q = log.truth["attitude"]
    c = quat_to_dcm(q)
    # ω_nb^b = ω_ib^b − C_n^b ω_ie^n integrates to the truth attitude (independent propagator)
    w_nb = log.truth["rate_true"] - np.einsum("nji,j->ni", c, earth.earth_rate_ned(lat))
    qp = propagate(q[0], w_nb[:-1], 0.01)
    err = np.abs(np.einsum("ni,ni->n", qp[-1:], q[-1:]))
    assert err[0] == pytest.approx(1.0, abs=1e-10)
    # body rate magnitude |ω_ie + Ω e_z|; yaw advances by Ω t
    v = earth.earth_rate_ned(lat) + np.array([0, 0, math.radians(om)])
    np.testing.assert_allclose(np.linalg.norm(log.truth["rate_true"], axis=1), np.linalg.norm(v), rtol=1e-12)
    # output = truth + bias + noise, including the scale-factor error of the 10 deg/s input
    resid = (log.gyro - log.truth["rate_true"] - log.truth["gyro_bias"]).mean(axis=0)
    sigma = load_preset("lsm6dsm").gyro.white * 1.3 / math.sqrt(log.duration)
    assert np.all(np.abs(resid) < 4 * sigma)
    f_from_att = np.einsum("nji,j->ni", c, [0.0, 0.0, -earth.normal_gravity(lat)])
    np.testing.assert_allclose(log.truth["specific_force_true"], f_from_att, atol=1e-12)


def test_progress_is_reported_from_0_to_1() -> None:
    seen: list[float] = []
    simulate("ax1", duration=2.0, progress=seen.append)
    assert seen[0] == 0.0 and seen[-1] == 1.0 and seen == sorted(seen)
    seen.clear()
    simulate_array("lsm6dsm", duration=1.0, progress=seen.append)
    assert seen[-1] == 1.0 and seen == sorted(seen) and len(seen) > 6


@pytest.mark.parametrize("kind", FAULT_KINDS)
def test_inject_fault_touches_only_the_faulty_sensor_after_start(kind: str) -> None:
    z = np.random.default_rng(0).standard_normal((50, 9))
    f = inject_fault(z, kind, sensor=1, start=20, axis=2, magnitude=7.0, duration=10)
    same = np.ones_like(z, dtype=bool)
    same[20:, 3:6] = False
    np.testing.assert_array_equal(f[same], z[same])  # other sensors and earlier samples
    seg, orig = f[20:, 3:6], z[20:, 3:6]
    if kind == "bias step":
        np.testing.assert_allclose(seg - orig, np.tile([0.0, 0.0, 7.0], (30, 1)), atol=1e-12)
    elif kind == "stuck":
        np.testing.assert_array_equal(seg, np.tile(z[19, 3:6], (30, 1)))
    elif kind == "noise burst":
        d = seg - orig
        assert np.all(d[:10] != 0) and np.all(d[10:] == 0)
        assert 3.0 < np.sqrt(np.mean(d[:10] ** 2)) < 12.0
    elif kind == "saturation":
        np.testing.assert_array_equal(seg[:, 2], 7.0)
        np.testing.assert_array_equal(seg[:, :2], orig[:, :2])
    else:
        assert np.isnan(seg).all()
    with pytest.raises(InputError, match="sensor"):
        inject_fault(z, kind, sensor=3, start=20)
    with pytest.raises(InputError, match="start"):
        inject_fault(z, kind, sensor=0, start=0)
    with pytest.raises(InputError, match="kind"):
        inject_fault(z, "gremlins", sensor=0, start=5)


def test_cycles_profile_repeats_the_thesis_ramp_test() -> None:
    log = simulate("ax1", profile="cycles", duration=3000.0, rate=1.0, seed=0)
    die = log.truth["temp_die"]
    assert log.meta["profile"] == "cycles"
    assert np.all(np.abs(die[:60] - 27.28) < 1e-9)  # the 60 s zeroing at the low end
    # With 5-min dwells the die (90 s lag) comes within 0.1 °C of both ends of 27.28 … 34.08 °C.
    assert die.max() == pytest.approx(34.08, abs=0.12) and die[600:].min() == pytest.approx(27.28, abs=0.12)
    reversals = np.sum(np.diff(np.sign(np.round(np.diff(die), 6))[np.round(np.diff(die), 6) != 0]) != 0)
    assert reversals >= 4  # several heating and cooling branches
    chamber_rate = np.diff(log.truth["temp_chamber"])
    assert chamber_rate.max() == pytest.approx(2.0 / 60.0, rel=1e-9)


def test_lab_block_average_and_errors() -> None:
    from uasnav.sim.lab import block_average, soak_calibration_data

    x = np.arange(10.0).reshape(5, 2)
    np.testing.assert_allclose(block_average(x, 2), [[1.0, 2.0], [5.0, 6.0]])
    with pytest.raises(InputError, match="block length"):
        block_average(x, 0)
    with pytest.raises(InputError, match="exceeds"):
        block_average(x, 6)
    cal = soak_calibration_data("ax1", seed=1, rate=1.0, average_s=120.0)
    assert cal.average_s == 120.0 and cal.gyro_bias.shape == (cal.temp.size, 3)


def test_simulator_experiment_quick() -> None:
    """The simulator chapter's experiment (what ``uasnav report --only simulator`` renders)."""
    res = exp.run(quick=True)
    assert res.soak.temp_range_c[0] == pytest.approx(-20.53, abs=0.01)
    assert res.soak.temp_range_c[1] == pytest.approx(37.30, abs=0.01)
    assert res.soak.temp_range_c == pytest.approx(FIG29_SOAK_RANGE_C, abs=0.01)
    terms = {f"{t.preset}_{t.sensor}_{t.term}": t for sp in res.static.presets for t in sp.terms}
    # thesis Table 3 ARW and Table 4 VRW recovered from the simulated static AX1 log
    assert np.mean(terms["ax1_gyro_random_walk"].fit) == pytest.approx(3.18, rel=0.10)
    assert np.mean(terms["ax1_accel_random_walk"].fit) == pytest.approx(0.05, rel=0.10)
    assert terms["ax1_gyro_random_walk"].spec == pytest.approx(TABLE3["arw_deg_sqrt_h"])
    assert terms["ax1_accel_random_walk"].spec == pytest.approx(TABLE4["vrw_m_s_sqrt_h"])
    assert np.mean(terms["lsm6dsm_gyro_bias_instability"].fit) == pytest.approx(10.8, rel=0.25)
    for v in res.ramp.hysteresis_output_deg_s:
        assert v == pytest.approx(res.ramp.hysteresis_configured_deg_s, abs=0.012)
    # the ramp figure's content: both branches binned over the ramp range, three axes each
    for br in (res.ramp.heating, res.ramp.cooling):
        assert br.bin_gyro_deg_s.shape == (br.bin_temp_c.size, 3) and br.bin_temp_c.size > 20
        assert br.true_output_deg_s.shape == (res.ramp.grid_c.size, 3)
