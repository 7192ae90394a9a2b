"""Issue #14 bugs 1, 2 and 6: Allan with short τ lists, noise-free axes, and noise terms either
recovered within their 95 % interval or declared not identifiable with the reason."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from uasnav.allan import AllanResult, oadev
from uasnav.cli import main
from uasnav.experiments.allan import RRW_CONFIGURED_DEG_H_SQRT_H, gyro_identification, white_plus_rrw
from uasnav.noise import TERMS, identify
from uasnav.units import convert

ARW = float(convert(3.18, "deg/√h", "rad/√s"))
RRW = float(convert(RRW_CONFIGURED_DEG_H_SQRT_H, "deg/h/√h", "rad/s/√s"))


@pytest.fixture(scope="module")
def gyro_only_log(tmp_path_factory: pytest.TempPathFactory) -> str:
    """A crs05-02 static log: noisy gyros, constant (noise-free) accelerometer columns."""
    path = str(tmp_path_factory.mktemp("f") / "s.csv")
    res = CliRunner().invoke(
        main, ["simulate", "--preset", "crs05-02", "--profile", "static", "--duration", "210", "--out", path]
    )
    assert res.exit_code == 0, res.output
    return path


# --- bug 1: explicit τ lists shorter than the fit needs ------------------------------------


def test_short_tau_list_gives_deviations_and_skips_the_fit_api() -> None:
    y = np.random.default_rng(1).normal(0.0, 0.01, (30_000, 3))
    curve = oadev(y, 100.0, [1.0, 10.0, 100.0], unit="rad/s")
    rep = identify(curve)  # used to raise "Allan curve: too short (3 samples, need at least 5)"
    assert curve.adev.shape == (3, 3) and np.all(curve.adev > 0)
    assert np.all(curve.ci_low < curve.adev) and np.all(curve.adev < curve.ci_high)
    assert len(rep.fit_skipped) == 3
    for why in rep.fit_skipped:
        assert "3 τ points" in why and "at least 5" in why and "samples" not in why
    assert not rep.identifiable.any()
    assert all(rep.reason(j, t) == rep.fit_skipped[j] for j in range(3) for t in TERMS)
    assert np.all(rep.fit.random_walk == 0)  # no fitted value is made up


def test_short_tau_list_cli_text_and_json(gyro_only_log: str) -> None:
    runner = CliRunner()
    res = runner.invoke(main, ["allan", gyro_only_log, "--taus", "1,10,100"])
    assert res.exit_code == 0, res.output
    assert "only 3 τ points; the five-term fit needs at least 5" in res.output
    assert "samples, need" not in res.output
    # the deviations are printed with their intervals, one row per τ
    gyro_rows = [ln for ln in res.output.splitlines() if ln.strip().startswith(("1 ", "10 ", "100 "))]
    assert len(gyro_rows) == 6 and all(ln.count("[") == 3 for ln in gyro_rows)
    res = runner.invoke(main, ["allan", gyro_only_log, "--taus", "1,10,100", "--json"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.output)
    g = d["gyro"]
    np.testing.assert_allclose(g["taus_s"], [1.0, 10.0, 100.0], rtol=1e-9)
    adev, lo, hi = (np.asarray(g[k]) for k in ("adev", "ci_low", "ci_high"))
    assert adev.shape == (3, 3) and np.all(adev > 0) and np.all((lo < adev) & (adev < hi))
    assert all("3 τ points" in why for why in g["fit_skipped"])
    assert all(
        row["identifiable"] is False and "τ points" in row["not_identifiable_reason"] for row in g["noise"]
    )


# --- bug 2: a constant or quantisation-limited axis ------------------------------------------


def test_constant_axis_has_adev_zero_and_the_others_are_analysed_api() -> None:
    rng = np.random.default_rng(2)
    y = np.column_stack(
        [rng.normal(0.0, 0.01, 50_000), np.full(50_000, 9.80665), rng.normal(0, 0.02, 50_000)]
    )
    curve = oadev(y, 100.0, unit="m/s^2")
    # exactly 0 (not float rounding of the summed constant, ~1e-25 before the fix)
    assert np.all(curve.adev[:, 1] == 0.0) and np.all(curve.ci_high[:, 1] == 0.0)
    assert np.all(curve.adev[:, [0, 2]] > 0)
    rep = identify(curve)  # used to raise "non-finite value (NaN or inf) at index 0"
    assert "no noise above resolution" in rep.fit_skipped[1]
    assert rep.fit_skipped[0] == "" and rep.fit_skipped[2] == ""
    np.testing.assert_allclose(rep.fit.random_walk[[0, 2]], [0.01 / 10, 0.02 / 10], rtol=0.05)
    assert rep.fit.random_walk[1] == 0 and not rep.identifiable[:, 1].any()
    assert "no noise above resolution" in (rep.reason(1, "random_walk") or "")


def test_mostly_quantised_axis_is_skipped_with_the_reason() -> None:
    """σ² > 0 at fewer than five τ: the fit is skipped and says so (no traceback)."""
    taus = 0.01 * 2.0 ** np.arange(8)
    avar = np.zeros((8, 1))
    avar[:3, 0] = [1e-6, 5e-7, 2.5e-7]
    curve = _curve(taus, avar)
    rep = identify(curve)
    assert "only 3 of 8 τ points have σ(τ) > 0" in rep.fit_skipped[0]


def test_noise_free_columns_cli(gyro_only_log: str) -> None:
    runner = CliRunner()
    res = runner.invoke(main, ["allan", gyro_only_log, "--json"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.output)
    assert np.all(np.asarray(d["accel"]["adev"]) == 0.0)
    assert all("no noise above resolution" in why for why in d["accel"]["fit_skipped"])
    assert d["gyro"]["fit_skipped"] == [None, None, None]
    arw = [r["fit_field"] for r in d["gyro"]["noise"] if r["term"] == "random_walk"]
    np.testing.assert_allclose(arw, 3.18, rtol=0.1)
    res = runner.invoke(main, ["allan", gyro_only_log])
    assert res.exit_code == 0, res.output
    assert res.output.count("no noise above resolution") == 3
    assert "random_walk" in res.output  # the gyro table is printed


# --- bug 6: every configured term recovered within its interval, or declared unidentifiable ----


def test_report_ax1_log_recovers_every_configured_term_on_every_axis() -> None:
    """The report's simulated CRS05-02/AX1 gyro (seed 2024, 2 h): ARW, bias instability (not
    simulated: 0) and RRW inside the fit's 95 % interval on all three axes. Before the fix the
    RRW was identified as 36 / 0 / 0 deg/h/√h against 30 configured."""
    g = gyro_identification(seed=2024)
    assert g.all_recovered, [(t.term, t.fit, t.ci_low, t.ci_high) for t in g.terms]
    by = {t.term: t for t in g.terms}
    assert np.all(by["random_walk"].identifiable)
    # the intervals are informative, not trivially wide
    assert np.all(by["random_walk"].ci_high / by["random_walk"].ci_low < 1.1)
    assert np.all(by["rate_random_walk"].ci_high < 3 * RRW_CONFIGURED_DEG_H_SQRT_H)
    assert np.all(g.rrw_fit_deg_h_sqrt_h > 0)  # no axis reads 0 any more
    # every term the data do not demand says why
    for t in g.terms:
        for j in range(3):
            assert bool(t.reasons[j]) == (not t.identifiable[j])


def test_interval_coverage_against_simulator_truth() -> None:
    """Over independent logs (2 h, white + RRW, 6 seeds × 3 axes) the 95 % intervals contain
    the configured ARW and RRW on at least 16 of 18 axes each and the (absent) bias instability,
    quantisation and ramp (0) on all; a mis-calibrated interval (too narrow) fails this."""
    inside = {t: 0 for t in TERMS}
    identified_rrw = 0
    truth = {"quantization": 0.0, "random_walk": ARW, "bias_instability": 0.0, "rate_random_walk": RRW}
    truth["rate_ramp"] = 0.0
    for seed in range(6):
        y = white_plus_rrw(720_000, 100.0, ARW, RRW, seed=100 + seed)
        rep = identify(oadev(y, 100.0, unit="rad/s"))
        for t in TERMS:
            lo, hi = getattr(rep.ci_low, t), getattr(rep.ci_high, t)
            inside[t] += int(np.sum((lo <= truth[t] * (1 + 1e-9)) & (truth[t] <= hi * (1 + 1e-9))))
        identified_rrw += int(rep.identifiable[TERMS.index("rate_random_walk")].sum())
    assert inside["random_walk"] >= 16 and inside["rate_random_walk"] >= 16, inside
    assert inside["bias_instability"] == inside["quantization"] == inside["rate_ramp"] == 18, inside
    # the +½ rise is demanded by the data on a good share of 2 h logs (9 of 18 with these seeds)
    assert identified_rrw >= 6


def test_short_log_declares_terms_not_identifiable_with_the_reason() -> None:
    """10 min of white + RRW: the RRW rise would show only beyond the longest τ."""
    y = white_plus_rrw(60_000, 100.0, ARW, RRW, seed=7)
    rep = identify(oadev(y, 100.0, unit="rad/s"))
    k = TERMS.index("rate_random_walk")
    assert np.all(rep.identifiable[TERMS.index("random_walk")])
    for j in range(3):
        why = rep.reason(j, "rate_random_walk")
        assert not rep.identifiable[k, j] and why is not None
        assert "consistent with 0" in why and "95 % upper bound" in why
        assert rep.ci_high.rate_random_walk[j] >= RRW  # the truth is not excluded
    rows = [r for r in rep.table() if r["term"] == "rate_random_walk"]
    assert all(r["identifiable"] is False and r["not_identifiable_reason"] for r in rows)


def _curve(taus: np.ndarray, avar: np.ndarray, n: int = 10_000_000, rate: float = 100.0) -> AllanResult:
    m = np.round(taus * rate).astype(np.int64)
    adev = np.sqrt(avar)
    rel = 1.0 / np.sqrt(2.0 * (n / m - 1.0))
    return AllanResult(
        taus=taus,
        m=m,
        adev=adev,
        avar=avar,
        n_terms=n - 2 * m,
        rel_error=rel,
        edf=np.full(taus.size, 100.0),
        ci_low=adev,
        ci_high=adev,
        rate=rate,
        n_samples=n,
        unit="rad/s",
        confidence=0.683,
        noise="white",
    )


@pytest.mark.parametrize("rising", ["rate_random_walk", "rate_ramp"])
def test_exact_curves_rrw_and_ramp_are_told_apart(rising: str) -> None:
    """On noise-free model curves over a long τ range the fit keeps the rising term that is
    there (the ramp is dropped only when the data do not demand it) and reads it exactly."""
    taus = 0.01 * 2.0 ** np.arange(24)
    n2, k2, r2 = 1e-6, 1e-12, 1e-16
    rise = k2 * taus / 3.0 if rising == "rate_random_walk" else r2 * taus**2 / 2.0
    avar = (n2 / taus + rise)[:, None]
    rep = identify(_curve(taus, avar), min_tau=None)
    other = "rate_ramp" if rising == "rate_random_walk" else "rate_random_walk"
    want = np.sqrt(k2 if rising == "rate_random_walk" else r2)
    np.testing.assert_allclose(getattr(rep.fit, rising), want, rtol=1e-3)
    assert getattr(rep.fit, other)[0] < 1e-3 * want
    assert rep.identifiable[TERMS.index(rising), 0]
    np.testing.assert_allclose(rep.fit.random_walk, 1e-3, rtol=1e-3)


def test_plot_with_a_noise_free_axis_warns_nothing(tmp_path) -> None:
    """A σ = 0 column is left off the log axes (and named in the legend), without the
    matplotlib 'no positive values' warning reaching the user."""
    import warnings

    from uasnav.allan import plot_adev
    from uasnav.plotting import new_figure

    rng = np.random.default_rng(3)
    y = np.column_stack([rng.normal(0.0, 0.01, 20_000), np.full(20_000, 1.5)])
    curve = oadev(y, 100.0, unit="rad/s")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _, ax = new_figure()
        plot_adev(curve, ax=ax, report=identify(curve))
        _, ax0 = new_figure()
        plot_adev(oadev(np.full((1000, 2), 2.0), 100.0, unit="rad/s"), ax=ax0)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("σ(τ) = 0" in lab for lab in labels)


def test_filter_noise_refuses_a_sensor_without_a_fit() -> None:
    from uasnav.errors import InputError
    from uasnav.noise import FilterNoise

    rng = np.random.default_rng(4)
    gyro = identify(oadev(rng.normal(0, 0.01, (30_000, 3)), 100.0, unit="rad/s"))
    accel = identify(oadev(np.full((30_000, 3), 9.8), 100.0, unit="m/s^2"))
    with pytest.raises(InputError, match=r"no accel noise fit.*no noise above resolution"):
        FilterNoise.from_reports(gyro, accel)


def test_dense_tau_spacing_is_thinned_to_octaves_for_the_fit() -> None:
    """taus="all" (10⁴ strongly correlated points) gives the octave fit's intervals, not ones
    100× too narrow, and in well under a second instead of minutes."""
    import time

    y = np.random.default_rng(5).normal(0.0, 0.01, (40_000, 1))
    dense = oadev(y, 100.0, "all", unit="rad/s")
    t0 = time.perf_counter()
    rd = identify(dense)
    assert time.perf_counter() - t0 < 10.0
    ro = identify(oadev(y, 100.0, "octave", unit="rad/s"))
    np.testing.assert_allclose(rd.fit.random_walk, ro.fit.random_walk, rtol=1e-9)
    np.testing.assert_allclose(rd.ci_low.random_walk, ro.ci_low.random_walk, rtol=1e-6)
    assert rd.ci_low.random_walk[0] <= 0.001 <= rd.ci_high.random_walk[0]
    # τ points closer than an octave alone are not enough for the fit, and it says so
    close = identify(oadev(y, 100.0, [0.1, 0.11, 0.12, 0.13, 0.14, 0.15], unit="rad/s"))
    assert "at least an octave apart" in close.fit_skipped[0]
