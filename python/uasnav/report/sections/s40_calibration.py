"""Report section: thermal calibration of gyro bias — polynomial vs BPNN vs the PX4 baseline
(thesis §4.2.5, Figures 31–37, Tables 7–8). Computed by :mod:`uasnav.experiments.calibration`."""

from __future__ import annotations

from typing import Any

import numpy as np

from uasnav.experiments import calibration
from uasnav.experiments.thesis import FIG30_RAMP_RANGE_C, FIG34_DELTA_OMEGA, TABLE7, TABLE8
from uasnav.experiments.verdicts import change
from uasnav.report import Section, SectionWriter


def _structure_figure(ax: Any) -> None:
    """Figure 33: the 1-2-2-1 network."""
    layers = [1, 2, 2, 1]
    names = ["T", "f", "f", "F"]
    pos = {}
    for i, n in enumerate(layers):
        for j in range(n):
            pos[(i, j)] = (i, (j - (n - 1) / 2.0))
    for i in range(len(layers) - 1):
        for j in range(layers[i]):
            for k in range(layers[i + 1]):
                (x0, y0), (x1, y1) = pos[(i, j)], pos[(i + 1, k)]
                ax.plot([x0, x1], [y0, y1], color="0.6", lw=1)
    for (i, _j), (x, y) in pos.items():
        ax.add_patch(__import__("matplotlib").patches.Circle((x, y), 0.15, color="C0" if i else "C2"))
        ax.text(x, y, names[i], ha="center", va="center", color="white")
    ax.set_xlim(-0.5, 3.5)
    ax.set_ylim(-1.2, 1.2)
    ax.set_aspect("equal")
    ax.axis("off")
    ax.set_title("BPNN 1-2-2-1: tanh hidden layers (f), linear output (F)")


def build(w: SectionWriter) -> None:
    from uasnav.attitude import plot_drift
    from uasnav.plotting import new_figure

    r = calibration.run(seed=w.seed, quick=w.quick, progress=w.progress)
    d = r.data
    w.data["source"] = d.source
    w.p(
        f"Data: {d.source}. Calibration on the soak test ({d.soak_temp.size} samples of "
        f"{d.average_s}-s means, "
        f"{d.soak_temp.min():.2f} … {d.soak_temp.max():.2f} °C), evaluation on the ramp test "
        f"({FIG30_RAMP_RANGE_C[0]} → {FIG30_RAMP_RANGE_C[1]} °C at 2 °C/min and back; heating and cooling "
        "branches differ by a hysteresis offset the soak never sees). Residuals are against the true "
        "thermal bias, not against noisy output."
    )
    temp, bias = d.soak_temp, d.soak_bias

    # Figures 31–33: polynomial order and BPNN structure selection, the structure used.
    sel_p, sel_n = r.sel_poly, r.sel_nn
    ax = sel_p.plot(xlabel="polynomial order m", ylabel="Sr_PF (rad/s)")
    w.figure(
        ax.figure, "fig31-sr-pf", "Figure 31: Sr_PF (eq. 32) on held-out soak data vs order (thesis chose 2)."
    )
    w.data["sr_pf"] = {"orders": sel_p.candidates, "sr": sel_p.sr.tolist(), "chosen": sel_p.chosen}
    ax = sel_n.plot(xlabel="neurons per hidden layer n", ylabel="Sr_NN (rad/s)")
    w.figure(
        ax.figure, "fig32-sr-nn", "Figure 32: Sr_NN (eq. 33) vs neurons per hidden layer (thesis chose 2-2)."
    )
    w.data["sr_nn"] = {"neurons": sel_n.candidates, "sr": sel_n.sr.tolist(), "chosen": sel_n.chosen}
    fig, ax = new_figure(6, 3)
    _structure_figure(ax)
    w.figure(fig, "fig33-structure", "Figure 33: the BPNN structure used (thesis Figure 33).")

    tab = r.residuals
    w.table(
        ["model", "RMS x", "RMS y", "RMS z", "max x", "max y", "max z", "Sr"],
        [(name, *(x.rms * 1e6), *(x.max * 1e6), x.sr * 1e6) for name, x in tab.items()],
        caption="Ramp test: residual bias (truth − model) per axis, µrad/s (thesis: Sr_NN ~1e-5 rad/s)",
        fmt="{:.2f}",
    )
    w.p(
        "The soak only visits the heating branch, so the cooling half of the ramp carries the "
        "hysteresis offset no single-valued model can follow. Sr on the heating half alone: "
        + "; ".join(f"{k} {v.sr:.3g} rad/s" for k, v in r.residuals_heating.items())
        + "."
    )
    w.data["ramp_heating_sr_rad_s"] = {k: v.sr for k, v in r.residuals_heating.items()}
    w.data["ramp_residuals_rad_s"] = {
        k: {"rms": x.rms.tolist(), "max": x.max.tolist(), "sr": x.sr} for k, x in tab.items()
    }

    fig, ax = new_figure()
    sub = slice(None, None, max(1, temp.size // 3000))
    for a in range(3):
        ax.plot(temp[sub], bias[sub, a], ".", ms=1, color=f"C{a}", alpha=0.3)
        ax.plot(r.fit_grid, r.fit_nn[:, a], color=f"C{a}", label=f"BPNN {'xyz'[a]}")
        ax.plot(r.fit_grid, r.fit_pf[:, a], color=f"C{a}", ls="--", label=f"poly m=2 {'xyz'[a]}")
    ax.set_xlabel("temperature (°C)")
    ax.set_ylabel("bias (rad/s)")
    ax.legend(fontsize=7, ncol=3)
    w.figure(fig, "fits", "Soak data and fitted models (thesis Figure 29 with fits).")

    # Figure 34: Δω(T) on the ramp range.
    dw = r.delta_omega
    fig, ax = new_figure()
    ax.plot(dw.temp_c, dw.delta)
    ax.axhline(dw.rms_value, color="C1", ls="--", label=f"RMS {dw.rms_value:.3g} at {dw.t_rms_c:.2f} °C")
    ax.plot([dw.t_max_c], [dw.max_value], "rv", label=f"max {dw.max_value:.3g} at {dw.t_max_c:.2f} °C")
    ax.set_xlabel("temperature (°C)")
    ax.set_ylabel("Δω (rad/s)")
    ax.legend()
    w.figure(fig, "fig34-delta-omega", "Figure 34: Δω(T) = ‖ω_NN − ω_PF‖ (eq. 34) over the ramp range.")
    ours = {"max": dw.max_value, "t_max": dw.t_max_c, "rms": dw.rms_value, "t_rms": dw.t_rms_c}
    w.table(
        ["quantity", "thesis", "ours"],
        [
            (label, FIG34_DELTA_OMEGA[k], ours[k])
            for label, k in (
                ("Δω_MAX (rad/s)", "max"),
                ("T at Δω_MAX (°C)", "t_max"),
                ("Δω_RMS (rad/s)", "rms"),
                ("T at Δω_RMS (°C)", "t_rms"),
            )
        ],
        caption="Δω extremes (eq. 34)",
        fmt="{:.4g}",
    )
    w.data["delta_omega"] = ours

    # Figures 35–36 and Tables 7–8.
    for label, dc, table, fig_no, no in (
        ("Δω_MAX", r.drift_max, TABLE7, 35, 7),
        ("Δω_RMS", r.drift_rms, TABLE8, 36, 8),
    ):
        t_pt = dc.temp_c
        fig, ax = new_figure()
        plot_drift([("BPNN residual", dc.drift_nn), ("polynomial residual", dc.drift_pf)], ax=ax)
        ax.set_title(f"θ(t) at T = {t_pt:.2f} °C ({label})")
        w.figure(
            fig, f"fig{fig_no}-drift", f"Figure {fig_no}: θ(t) from the residual bias at the {label} point."
        )
        rows = [
            (f"{th:.2e}", table[th][0], t_nn, table[th][1], t_pf, table[th][2], dtp)
            for th, t_nn, t_pf, dtp in dc.rows
        ]
        w.table(
            [
                "θ (rad)",
                "t_NN thesis (s)",
                "t_NN ours",
                "t_PF thesis (s)",
                "t_PF ours",
                "Δt% thesis",
                "Δt% ours",
            ],
            rows,
            caption=(
                f"Table {no} ({label}, T = {t_pt:.2f} °C): |residual| "
                f"NN {np.linalg.norm(dc.residual_nn):.3g}, PF {np.linalg.norm(dc.residual_pf):.3g} rad/s; "
                "— = not reached within the run"
            ),
            fmt="{:.2f}",
        )
        w.data[f"table{no}"] = {"temp_c": t_pt, "rows": rows}

    # Derivative models: analytic vs derivative network (eq. 37), Figure 37.
    w.table(
        ["derivative model", "RMS x", "RMS y", "RMS z", "Sr_TCZUPT"],
        [(x.name, *(x.rms * 1e6), x.sr * 1e6) for x in r.derivatives],
        caption="∂b/∂T on the ramp vs the true derivative, µrad/s/°C (thesis: Sr_TCZUPT ~1e-7 rad/s/°C)",
        fmt="{:.3f}",
    )
    w.data["derivative_sr"] = {x.name: x.sr * 1e6 for x in r.derivatives}
    sel_d = r.sel_derivative
    ax = sel_d.plot(xlabel="neurons per hidden layer n", ylabel="Sr_TCZUPT (rad/s/°C)")
    w.figure(ax.figure, "fig37-sr-tczupt", "Figure 37: Sr_TCZUPT (eq. 37) of the derivative network vs n.")
    w.data["sr_tczupt"] = {"neurons": sel_d.candidates, "sr": sel_d.sr.tolist(), "chosen": sel_d.chosen}

    # Hysteresis-aware fit on the ramp (both branches).
    hy, true_w = r.hysteresis, d.hysteresis_true
    w.table(
        ["axis", "width fitted (µrad/s)", "± 1σ (µrad/s)", "width true (µrad/s)"],
        [("xyz"[a], hy.width[a] * 1e6, hy.width_std[a] * 1e6, true_w[a] * 1e6) for a in range(3)],
        caption="Hysteresis-aware fit on the ramp: shared shape, heating/cooling offsets",
        fmt="{:.2f}",
    )
    w.data["hysteresis_width"] = hy.width.tolist()
    w.data["hysteresis_width_std"] = hy.width_std.tolist()

    w.p(
        "Robustness: with the ramp temperature quantised to 1 °C the BPNN's Sr (rad/s) "
        + w.verdict("quantised_sr", change(tab[calibration.BPNN_THESIS].sr, r.quantised_sr))
        + f". Evaluated over "
        f"{r.wide_range_c[0]:.1f} … {r.wide_range_c[1]:.1f} °C, {r.n_clipped} of {r.n_wide} temperatures "
        "fall outside the calibrated range: they are clipped to it, flagged (return_clipped) and warned "
        "about (TemperatureRangeWarning); the model never extrapolates."
    )
    w.data["quantised_sr"] = r.quantised_sr
    w.data["px4_params"] = r.px4_params


SECTION = Section(
    key="calibration", title="Thermal calibration of gyro bias: polynomial vs BPNN", order=40, build=build
)
