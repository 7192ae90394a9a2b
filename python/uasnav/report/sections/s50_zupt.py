"""Report section: ZUPT and TCZUPT filters (thesis §4.2.6.2, Figures 38–45, Tables 9–13)."""

from __future__ import annotations

from typing import Any

import numpy as np

from uasnav.report import Section, SectionWriter

# Thesis Table 9 (rad/s): mean residual of the moving-average reference, calibrated / raw.
TABLE9 = {"x": (1.68e-6, 9.53e-6), "y": (2.98e-6, 6.80e-6), "z": (3.43e-6, 1.03e-5)}
# Table 10 (rad/s): RMS error, (ZUPT, TCZUPT) per axis, nominal and residual 15 deg/h.
TABLE10 = {
    "nominal": {"x": (4.15e-5, 5.33e-5), "y": (7.48e-5, 2.97e-5), "z": (6.07e-5, 3.30e-5)},
    "residual": {"x": (3.98e-5, 4.13e-5), "y": (9.72e-5, 3.88e-5), "z": (8.17e-5, 3.01e-5)},
}
# Table 11 (s): convergence time to 1e-5 rad/s, residual 15 deg/h, (ZUPT, TCZUPT).
TABLE11 = {"x": (140, 65), "y": (345, 127), "z": (85, 53)}
# Tables 12–13 (rad/s): mean and std of the RMS error over 5 × 5 min, (mean, std) per filter.
TABLE12 = {
    "zupt": {"x": (3.42e-5, 0.77e-5), "y": (3.58e-5, 0.89e-5), "z": (4.36e-5, 0.82e-5)},
    "tczupt": {"x": (4.70e-5, 0.61e-5), "y": (2.63e-5, 0.65e-5), "z": (3.89e-5, 0.70e-5)},
}
TABLE13 = {
    "zupt": {"x": (6.49e-5, 0.92e-5), "y": (8.88e-5, 0.92e-5), "z": (7.16e-5, 0.79e-5)},
    "tczupt": {"x": (3.81e-5, 0.54e-5), "y": (4.58e-5, 0.84e-5), "z": (3.36e-5, 0.35e-5)},
}
AXES = "xyz"
STANDIN_NOTE = (
    "Data: the simulator and thermal-model issues had not landed when this section was "
    "written, so the evaluation uses a small STAND-IN generator (`uasnav._zupt_standin`): an "
    "AX1-like static unit with the thesis' CRS05-02 noise (σ_ARW = 3.18 deg/√h), MS8010 "
    "accelerometer noise, a quadratic thermal gyro bias (≈ 2–3e-5 rad/s/°C), the thesis' "
    "ramp test (27.3 ↔ 34.1 °C at 2 °C/min, die lag 20 s, 0.0625 °C sensor resolution) and "
    "a cubic calibration fitted on a stand-in soak (−20.5 … 37.3 °C, heating branch). Its "
    "truth is exact, so we show errors against the true bias beside the thesis' "
    "moving-average reference."
)


def build(w: SectionWriter) -> None:
    from uasnav import _zupt_standin as standin
    from uasnav import zupt
    from uasnav.plotting import new_figure

    quick = w.quick
    seg_s = 60.0 if quick else 300.0
    duration = 60.0 + 5 * seg_s
    dec = 100
    w.p(
        "The 15-state error-state Kalman filter of eq. (8) (δr, δv, ψ, accelerometer and gyro "
        "bias) on a local-level NED strapdown solution with Earth rate and WGS-84 gravity; "
        "Φ = I + F·Ts, Γ = G·Q·Gᵀ·Ts, Q from σ_VRW, σ_ARW, σ_ABI, σ_GBI (eqs. 22–25, Tables 3–6); "
        "nine ZUPT measurements (frozen position, zero velocity, frozen attitude) once per "
        "second, Joseph form; 60 s coarse levelling and zeroing. TCZUPT propagates the bias "
        "with (∂b/∂T)·(dT/dt)·Ts (eq. 31), dT/dt from a 30 s sliding least-squares slope."
    )
    w.p(STANDIN_NOTE)
    w.progress("simulating the ramp test")
    log = standin.static_log(duration, seed=w.seed)
    model = standin.soak_calibration(seed=w.seed + 1)
    heading = 0.4  # the stand-in's true heading (an external input in the thesis)
    truth_raw = log.truth["gyro_bias"]
    truth_cal = truth_raw - model.predict(log.temp)
    base = zupt.ZuptConfig(decimation=dec, heading_rad=heading)

    # Figures 38–39: the filters' input data (1 Hz low-pass for display, as in the thesis).
    from scipy.signal import butter, sosfiltfilt

    sos = butter(2, 1.0, fs=log.sample_rate, output="sos")
    for name, data, fig_no in (
        ("calibrated", log.gyro - model.predict(log.temp), 38),
        ("raw", log.gyro, 39),
    ):
        fig, ax = new_figure(7.0, 4.0)
        lp = sosfiltfilt(sos, data, axis=0)
        for j in range(3):
            ax.plot(log.t[::dec], lp[::dec, j], lw=0.8, label=f"ω{AXES[j]}")
        ax2 = ax.twinx()
        ax2.plot(log.t[::dec], log.temp[::dec], "k:", lw=0.8, label="temperature")
        ax2.set_ylabel("die temperature (°C)")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("gyro output (rad/s)")
        ax.legend(fontsize=8, loc="upper left")
        ax.grid(True, alpha=0.3)
        filt = "standard ZUPT" if fig_no == 38 else "TCZUPT"
        w.figure(
            fig,
            f"fig{fig_no}_input_{name}",
            f"Figure {fig_no}: input data of the {filt} filter ({name} gyro, 1 Hz low-pass for display).",
        )

    runs: dict[str, Any] = {}
    w.progress("running ZUPT and TCZUPT")
    for scen, resid in (("nominal", 0.0), ("residual", zupt.RESIDUAL_BIAS_15DEG_H)):
        cfg = base.replace(residual_gyro_bias_rad_s=resid)
        runs[scen] = {
            "zupt": zupt.run(log, "zupt", model, cfg),
            "tczupt": zupt.run(log, "tczupt", model, cfg),
            # Ablation: TCZUPT with the standard σ_GBI, to separate eq. 31 from the larger Q.
            "tczupt_sgbi": zupt.run(log, "tczupt", model, cfg.replace(noise=zupt.THESIS_ZUPT_NOISE)),
        }
    q0 = runs["nominal"]["zupt"].initial_attitude
    ref_cal = zupt.moving_average_reference(log, q0, model=model)
    ref_raw = zupt.moving_average_reference(log, q0)
    refs = {"zupt": (ref_cal, truth_cal), "tczupt": (ref_raw, truth_raw), "tczupt_sgbi": (ref_raw, truth_raw)}

    # Table 9.
    res_cal = zupt.reference_residual(log, ref_cal, q0, model=model)
    res_raw = zupt.reference_residual(log, ref_raw, q0)
    w.table(
        ["axis", "calibrated thesis", "calibrated ours", "raw thesis", "raw ours"],
        [(a, TABLE9[a][0], res_cal[j], TABLE9[a][1], res_raw[j]) for j, a in enumerate(AXES)],
        caption="Table 9: mean residual of the 30 s moving-average reference (rad/s).",
        fmt="{:.2e}",
    )
    ma_noise = zupt.THESIS_ZUPT_NOISE.sigma_arw_rad_sqrt_s / np.sqrt(zupt.REFERENCE_WINDOW_S)
    w.p(
        f"The mean residual is small by construction, but the moving average itself carries "
        f"white noise σ_ARW/√30 s = {ma_noise:.1e} rad/s for this gyro, larger than the "
        "filters' errors below; so against the moving average the RMS errors are dominated by "
        "the reference. We therefore also report errors against the stand-in's true bias."
    )

    # Figures 40–45.
    for scen, first in (("nominal", 40), ("residual", 43)):
        for j in range(3):
            fig, ax = new_figure(7.0, 4.0)
            for mode, label in (("zupt", "ZUPT (calibrated data)"), ("tczupt", "TCZUPT (raw data)")):
                r = runs[scen][mode]
                r.plot_bias(j, ax=ax, label=label)
                ax.plot(
                    r.t,
                    refs[mode][0][::dec, j],
                    lw=0.6,
                    alpha=0.6,
                    label=f"moving average ({mode.upper()} input)",
                )
                ax.plot(r.t, refs[mode][1][::dec, j], "k--", lw=0.8)
            ax.set_title(
                ("nominal" if scen == "nominal" else "residual 15 deg/h")
                + f", {AXES[j]} axis (dashed: true bias)"
            )
            ax.legend(fontsize=7)
            title = "nominal condition" if scen == "nominal" else "residual error of 15 degrees/h"
            w.figure(
                fig,
                f"fig{first + j}_{scen}_{AXES[j]}",
                f"Figure {first + j}: gyro bias ({title}, {AXES[j]}-axis).",
            )

    # Table 10.
    data: dict[str, Any] = {"table10": {}, "table11": {}, "table12": {}, "table13": {}}
    rows = []
    for scen in ("nominal", "residual"):
        for j, a in enumerate(AXES):
            row: list[Any] = [scen, a]
            for mode in ("zupt", "tczupt"):
                r = runs[scen][mode]
                rms_ma = zupt.rms_error(r.gyro_bias, refs[mode][0][::dec])[j]
                rms_tr = zupt.rms_error(r.gyro_bias, refs[mode][1][::dec])[j]
                row += [TABLE10[scen][a][0 if mode == "zupt" else 1], rms_ma, rms_tr]
                data["table10"].setdefault(scen, {}).setdefault(mode, {})[a] = {
                    "vs_moving_average": rms_ma,
                    "vs_truth": rms_tr,
                }
            rows.append(tuple(row))
    w.table(
        [
            "scenario",
            "axis",
            "ZUPT thesis",
            "ZUPT vs MA",
            "ZUPT vs truth",
            "TCZUPT thesis",
            "TCZUPT vs MA",
            "TCZUPT vs truth",
        ],
        rows,
        caption="Table 10: RMS error (rad/s) over the whole run; MA = 30 s moving-average reference.",
        fmt="{:.2e}",
    )

    # Table 11. Two starts: after the 60 s zeroing (as in the thesis; its own error is
    # σ_ARW/√60 s ≈ 1.2e-4 rad/s per axis, larger than 15 deg/h), and from the exact initial
    # bias + 15 deg/h (zeroing off), which isolates the scenario.
    exact = {}
    for mode in ("zupt", "tczupt", "tczupt_sgbi"):
        tru0 = (truth_cal if mode == "zupt" else truth_raw)[0]
        cfg = base.replace(
            zeroing=False,
            gyro_bias0_rad_s=tuple(float(v) for v in tru0),
            residual_gyro_bias_rad_s=zupt.RESIDUAL_BIAS_15DEG_H,
        )
        if mode == "tczupt_sgbi":
            cfg = cfg.replace(noise=zupt.THESIS_ZUPT_NOISE)
        exact[mode] = zupt.run(log, "zupt" if mode == "zupt" else "tczupt", model, cfg)
    rows = []
    for j, a in enumerate(AXES):
        row: list[Any] = [a]
        for mode in ("zupt", "tczupt", "tczupt_sgbi"):
            tru = refs[mode][1][::dec]
            r = runs["residual"][mode]
            ct = zupt.convergence_time(r.t, r.gyro_bias, tru)[j]
            ce = zupt.convergence_time(exact[mode].t, exact[mode].gyro_bias, tru)[j]
            if mode != "tczupt_sgbi":
                row.append(TABLE11[a][0 if mode == "zupt" else 1])
            row += [_fmt_t(ct), _fmt_t(ce)]
            data["table11"].setdefault(mode, {})[a] = {"after_zeroing": ct, "exact_start": ce}
        rows.append(tuple(row))
    w.table(
        [
            "axis",
            "ZUPT thesis (s)",
            "ZUPT zeroed",
            "ZUPT exact+15°/h",
            "TCZUPT thesis (s)",
            "TCZUPT zeroed",
            "TCZUPT exact+15°/h",
            "TCZUPT σ_GBI zeroed",
            "TCZUPT σ_GBI exact+15°/h",
        ],
        rows,
        caption="Table 11: convergence time (first |error vs true bias| < 1e-5 rad/s), residual "
        "15 deg/h. 'zeroed': start after the 60 s zeroing + 15 deg/h; 'exact+15°/h': start at the "
        "true bias + 15 deg/h. 'TCZUPT σ_GBI': ablation with the standard-ZUPT σ_GBI. Against "
        "the moving average (noise 1.7e-4 rad/s) a 1e-5 threshold is met only by chance.",
    )

    # Tables 12–13: five consecutive segments.
    w.progress("segment statistics")
    for tab_no, scen, thesis in ((12, "nominal", TABLE12), (13, "residual", TABLE13)):
        resid = 0.0 if scen == "nominal" else zupt.RESIDUAL_BIAS_15DEG_H
        cfg = base.replace(residual_gyro_bias_rad_s=resid, decimation=10)
        rows = []
        for mode in ("zupt", "tczupt"):
            truth = truth_cal if mode == "zupt" else truth_raw
            piece_log = log.slice(int(60 * log.sample_rate), log.n)
            _, mean, std = zupt.segment_rms(
                piece_log, mode, truth[int(60 * log.sample_rate) :], model=model, config=cfg, segment_s=seg_s
            )
            for j, a in enumerate(AXES):
                rows.append((mode.upper(), a, thesis[mode][a][0], mean[j], thesis[mode][a][1], std[j]))
                data[f"table{tab_no}"].setdefault(mode, {})[a] = {"mean": mean[j], "std": std[j]}
        w.table(
            ["filter", "axis", "mean thesis", "mean ours", "std thesis", "std ours"],
            rows,
            caption=f"Table {tab_no}: mean and standard deviation of the RMS error vs truth over "
            f"5 × {seg_s:g} s segments "
            f"({'nominal' if scen == 'nominal' else 'residual 15 deg/h'}), rad/s.",
            fmt="{:.2e}",
        )

    # NEES consistency (beyond the thesis): Monte Carlo over seeds.
    w.progress("NEES Monte Carlo")
    n_mc = 3 if quick else 8
    nees_rows = []
    for mode in ("zupt", "tczupt"):
        acc = []
        for s in range(n_mc):
            lg = standin.static_log(duration, seed=1000 + s)
            md = standin.soak_calibration(seed=2000 + s)
            r = zupt.run(lg, mode, md, base)
            tru = (lg.truth["gyro_bias"] - (md.predict(lg.temp) if mode == "zupt" else 0.0))[::dec]
            acc.append(r.nees(tru))
        nees = np.mean(np.array(acc), axis=0)  # average over runs at each time
        from scipy.stats import chi2

        lo, hi = chi2.ppf([0.005, 0.995], 3 * n_mc) / n_mc
        inside = float(np.mean((nees >= lo) & (nees <= hi)))
        nees_rows.append((mode.upper(), n_mc, float(np.mean(nees)), lo, hi, inside * 100))
        data.setdefault("nees", {})[mode] = {
            "mean": float(np.mean(nees)),
            "lo": lo,
            "hi": hi,
            "inside_pct": inside * 100,
        }
    w.table(
        ["filter", "runs", "mean NEES (3 dof)", "99 % lower", "99 % upper", "% of time inside"],
        nees_rows,
        caption="Gyro-bias NEES averaged over Monte-Carlo runs against its χ² bounds "
        "(consistent: mean ≈ 3, ~99 % inside).",
        fmt="{:.3g}",
    )

    # Claim check, from the numbers above.
    faster = 0
    for a in AXES:
        tz_, tt_ = data["table11"]["zupt"][a]["exact_start"], data["table11"]["tczupt"][a]["exact_start"]
        faster += int(tt_ is not None and (tz_ is None or tt_ < tz_))
    rms = {
        m: np.array([zupt.rms_error(runs["residual"][m].gyro_bias, refs[m][1][::dec])[j] for j in range(3)])
        for m in ("zupt", "tczupt", "tczupt_sgbi")
    }
    not_worse = int(np.sum(rms["tczupt"] <= 1.1 * rms["zupt"]))
    ratio = float(np.mean(rms["tczupt"] / rms["zupt"]))
    ratio_abl = float(np.mean(rms["tczupt_sgbi"] / rms["zupt"]))
    verdict = "confirmed" if faster >= 2 and not_worse >= 2 else "not confirmed"
    data["claim"] = {
        "tczupt_faster_axes_exact_start": faster,
        "tczupt_not_worse_rms_axes": not_worse,
        "mean_rms_ratio_tczupt_over_zupt": ratio,
        "mean_rms_ratio_tczupt_standard_sgbi_over_zupt": ratio_abl,
        "verdict": verdict,
    }
    w.p(
        "Thesis claim — TCZUPT converges faster in the 15 deg/h scenario and is not worse in "
        f"RMS over the whole run: {verdict.upper()} on our data. From the exact start + 15 deg/h, "
        f"TCZUPT converged first on {faster}/3 axes; its whole-run RMS error vs truth is within "
        f"10 % of ZUPT's on {not_worse}/3 axes (mean ratio TCZUPT/ZUPT {ratio:.2f}; with the "
        f"standard σ_GBI instead of Table 5's σ'_GBI the ratio is {ratio_abl:.2f}). Analysis: both "
        "filters have the same bias observability (the frozen-attitude measurement observes ψ "
        "directly, so the bias estimate is a P-weighted average of the gyro output minus the "
        "propagated drift). TCZUPT's larger σ'_GBI keeps its gain higher: faster reaction, but "
        "more of the σ_ARW white noise passes into the estimate, which raises the RMS. Eq. 31 "
        "moves the estimate along ∂b/∂T·dT/dt between updates, so on raw data it tracks the "
        "thermal drift that ZUPT only sees after calibration; with an accurate calibration (as "
        "here) ZUPT on calibrated data has no drift left to track, and the smaller σ_GBI wins. "
        "The thesis' advantage may come from a calibration residual larger than in this "
        "stand-in, or from a different noise/zeroing set-up; we cannot reproduce it. Note on "
        "Table 11's metric: with σ_ARW = 3.18 deg/√h the 1σ of any bias estimate after t s of "
        "data is ≈ σ_ARW/√t, above 1e-5 rad/s until t ≈ 8 500 s, so the first crossing of "
        "1e-5 rad/s is a chance event of the noise (here within seconds to minutes, equal for "
        "both filters), not a convergence time in the sense of the error staying below it."
    )

    # Hysteresis study.
    w.progress("hysteresis study")
    h = 4e-5
    hlog = standin.static_log(duration, seed=w.seed + 7, hysteresis_rad_s=h)
    hmodel = standin.soak_calibration(seed=w.seed + 8, hysteresis_rad_s=h)  # heating-branch reference
    hz = zupt.run(hlog, "zupt", hmodel, base)
    ht = zupt.run(hlog, "tczupt", hmodel, base)
    dtemp = np.gradient(hlog.truth["temp_die"], 1.0 / hlog.sample_rate)[::dec]
    heating, cooling = dtemp > 1e-3, dtemp < -1e-3
    tz = (hlog.truth["gyro_bias"] - hmodel.predict(hlog.temp))[::dec]
    tt = hlog.truth["gyro_bias"][::dec]
    hrows = []
    for label, mask in (("heating", heating), ("cooling", cooling)):
        ez = zupt.rms_error(hz.gyro_bias[mask], tz[mask])
        et = zupt.rms_error(ht.gyro_bias[mask], tt[mask])
        cal_off = np.mean(tz[mask], axis=0) - np.mean(tz[heating], axis=0)
        hrows.append((label, *ez, *et, float(np.linalg.norm(cal_off))))
        data.setdefault("hysteresis", {})[label] = {"zupt_rms": ez.tolist(), "tczupt_rms": et.tolist()}
    w.table(
        ["branch", "ZUPT x", "ZUPT y", "ZUPT z", "TCZUPT x", "TCZUPT y", "TCZUPT z", "|calibration offset|"],
        hrows,
        caption=f"Hysteresis (bias +{h:.0e} rad/s heating, −{h:.0e} cooling; calibration on the "
        "heating branch): RMS error vs truth (rad/s) per branch.",
        fmt="{:.2e}",
    )
    fig, ax = new_figure(7.0, 4.0)
    hz.plot_bias(0, ax=ax, reference=tz, reference_label="true residual (ZUPT)", label="ZUPT", sigma=False)
    ht.plot_bias(0, ax=ax, reference=tt, reference_label="true bias (TCZUPT)", label="TCZUPT", sigma=False)
    w.figure(
        fig,
        "hysteresis_x",
        "Hysteresis study, x axis: the fixed-reference calibration leaves a −2h offset on the "
        "cooling branch for ZUPT to absorb.",
    )
    w.p(
        "With hysteresis the fixed calibration curve is right on one branch only: the ZUPT "
        "filter on calibrated data must absorb a 2h step every time the temperature turns. "
        "TCZUPT uses only the slope ∂b/∂T, equal on both branches in this model, so its "
        "propagation is right on both; the step at the turn itself is still left to the "
        "stochastic bias model in both filters."
    )

    w.p(
        "Real data (not read by the report, which runs on simulated data only): the test "
        "suite runs ZUPT on the 2.78 h ADIS16405 static recording and checks that the "
        "estimated turn-on gyro bias agrees with the long-term mean output minus the Earth "
        "rate (tests/test_zupt.py)."
    )
    w.data.update(data)


def _fmt_t(v: float | None) -> str:
    return "never" if v is None else f"{v:.0f}"


SECTION = Section(key="zupt", title="ZUPT and TCZUPT filters", order=50, build=build)
