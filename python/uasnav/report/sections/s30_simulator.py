"""Report section: the MEMS IMU simulator — thermal soak/ramp tests (thesis §4.2.4, Figures
29–30) and the Allan deviation of the static case against the presets' specifications.

Renders :func:`uasnav.experiments.simulator.run`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from uasnav.report import Section, SectionWriter

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from uasnav.experiments.simulator import RampTest, SoakTest, StaticAllan


def _c(x: float) -> str:
    """Temperature with two decimals and a typographic minus."""
    return f"{x:.2f}".replace("-", "−")


def _three_axes() -> tuple[Figure, list[Axes]]:
    from uasnav.plotting import new_figure

    fig, _ = new_figure(9.0, 3.2)
    fig.clear()
    return fig, list(fig.subplots(1, 3, sharex=True))


def _label_axes(axs: list[Axes], legend_size: int) -> None:
    for j, ax in enumerate(axs):
        ax.set_title(f"ω_{'xyz'[j]}")
        ax.set_xlabel("die temperature (°C)")
        ax.grid(alpha=0.3)
    axs[0].set_ylabel("gyro output (deg/s)")
    axs[0].legend(fontsize=legend_size)


def _soak(w: SectionWriter, soak: SoakTest) -> None:
    from uasnav.experiments.thesis import FIG29_SOAK_RANGE_C, FIG29_SOAK_STEP_C

    fig, axs = _three_axes()
    for j, ax in enumerate(axs):
        ax.plot(soak.bin_temp_c, soak.bin_gyro_deg_s[:, j], ".", ms=2, label="output, 10 s means")
        ax.plot(
            soak.grid_c, soak.true_output_deg_s[:, j], "-", lw=1, color="k", label="true bias + Earth rate"
        )
    _label_axes(axs, 7)
    lo, hi = FIG29_SOAK_RANGE_C
    w.figure(
        fig,
        "soak",
        f"Simulated soak test (cf. thesis Figure 29): die {_c(lo)} → {_c(hi)} °C in "
        f"{FIG29_SOAK_STEP_C:g} °C steps, each "
        "held 20 min; the bias curve is smooth but not polynomial (local changes of trend).",
    )
    w.data["soak_samples"] = soak.samples
    w.data["soak_temp_range_c"] = list(soak.temp_range_c)


def _ramp(w: SectionWriter, ramp: RampTest) -> None:
    from uasnav.experiments.thesis import FIG30_RAMP_RANGE_C, FIG30_RAMP_RATE_C_PER_MIN

    fig, axs = _three_axes()
    for br in (ramp.heating, ramp.cooling):
        lab = br.branch
        for j, ax in enumerate(axs):
            (ln,) = ax.plot(
                br.bin_temp_c, br.bin_gyro_deg_s[:, j], "o", ms=3, label=f"{lab}: output, 0.25 °C bins"
            )
            ax.plot(
                ramp.grid_c, br.true_output_deg_s[:, j], "-", lw=1, color=ln.get_color(), label=f"{lab}: true"
            )
    _label_axes(axs, 6)
    lo, hi = FIG30_RAMP_RANGE_C
    w.figure(
        fig,
        "ramp",
        f"Simulated ramp test (cf. thesis Figure 30): {_c(lo)} → {_c(hi)} °C at "
        f"{FIG30_RAMP_RATE_C_PER_MIN:g} °C/min and back; the "
        "cooling branch lies below the heating branch (hysteresis), with nearly the same slope.",
    )
    rows = [
        (f"{t:g}", ramp.hysteresis_configured_deg_s, d_truth, d_out)
        for t, d_truth, d_out in zip(
            ramp.hysteresis_temps_c, ramp.hysteresis_truth_deg_s, ramp.hysteresis_output_deg_s, strict=True
        )
    ]
    w.table(
        ["die T (°C)", "configured offset (deg/s)", "truth heating − cooling", "output heating − cooling"],
        rows,
        caption="Hysteresis at equal temperature (axis mean; output has the known branch-free curve removed)",
        fmt="{:.4f}",
    )
    w.data["hysteresis_configured_deg_s"] = ramp.hysteresis_configured_deg_s
    w.data["hysteresis_output_deg_s"] = list(ramp.hysteresis_output_deg_s)


def _static(w: SectionWriter, static: StaticAllan) -> None:
    from uasnav.allan import plot_adev
    from uasnav.plotting import new_figure

    rows = []
    why_lines = []
    for sp in static.presets:
        for tc in sp.terms:
            fit = float(np.mean(tc.fit))
            rec = tc.recovery
            term = f"{tc.term} ({tc.unit})"
            # Rule: compare with the specification only where the data identify the term on
            # every axis; otherwise say which axes do not and why (the reasons follow the table).
            blind = [] if rec is None else [ax for j, ax in enumerate("xyz") if not rec.identifiable[j]]
            if rec is not None and blind:
                note = f"not identifiable on {', '.join(blind)}"
                for j, ax in enumerate("xyz"):
                    if not rec.identifiable[j]:
                        why_lines.append(f"{sp.preset} {tc.sensor} {ax} {tc.term}: {rec.reasons[j]}")
            elif tc.resolvable or tc.tau_cross_s is None:
                note = f"{(np.mean(tc.fit) / tc.spec - 1) * 100:+.1f} %"
            else:
                note = f"not resolvable (white noise dominates to τ ≈ {tc.tau_cross_s / 3600:.3g} h)"
            if rec is not None:
                note += f"; spec inside the 95 % interval on {int(np.sum(rec.inside))}/3 axes"
            rows.append((sp.preset, tc.sensor, term, tc.spec, fit, float(np.mean(tc.points)), note))
            entry: dict[str, object] = {"spec": tc.spec, "fit": tc.fit, "points": tc.points}
            if rec is not None:
                entry.update(
                    ci_low=rec.ci_low,
                    ci_high=rec.ci_high,
                    spec_inside_ci=rec.inside,
                    identifiable=rec.identifiable,
                )
            w.data[f"{sp.preset}_{tc.sensor}_{tc.term}"] = entry
        if sp.preset == "ax1":
            fig, ax = new_figure()
            plot_adev(sp.gyro_curve, ax=ax, labels=["gyro x", "gyro y", "gyro z"], report=sp.gyro_report)
            ax.set_title("Simulated AX1 (CRS05-02 gyros), static, constant temperature")
            w.figure(
                fig,
                "ax1-gyro-adev",
                "Allan deviation of the simulated static AX1 gyro with the IEEE 952 fit.",
            )
    w.table(
        [
            "preset",
            "sensor",
            "term",
            "specification",
            "recovered (fit)",
            "recovered (slope points)",
            "fit vs spec",
        ],
        rows,
        caption=(
            f"Allan analysis of {static.hours:g} h simulated static logs vs the preset specification "
            "(thesis Tables 3–4 for the AX1 sensors, §4.3.3 for the LSM6DSM; axis means)"
        ),
        fmt="{:.4g}",
    )
    if why_lines:
        w.p(
            "Terms the logs do not identify (95 % profile-likelihood interval of the fit contains 0): "
            + "; ".join(why_lines)
            + "."
        )


def build(w: SectionWriter) -> None:
    from uasnav.experiments import simulator

    w.p(
        "The simulator reproduces the thesis' thermal experiments on the Axitude AX1 AHRS "
        "(CRS05-02 gyros, MS8010 accelerometers, 30 Hz second-order anti-alias filter) with every "
        "error term known: white noise, bias instability (sum of Gauss–Markov processes), rate "
        "random walk, turn-on bias, quantisation, scale factor/misalignment, g-sensitivity, a "
        "non-polynomial bias–temperature curve with heating/cooling hysteresis, thermal "
        "scale-factor drift, temperature-dependent noise and a chamber→die thermal lag."
    )
    res = simulator.run(seed=w.seed, quick=w.quick, progress=w.progress)
    w.heading("Thermal tests (thesis Figures 29–30)")
    _soak(w, res.soak)
    _ramp(w, res.ramp)
    w.heading("Allan deviation of the static case vs specification")
    _static(w, res.static)


SECTION = Section(key="simulator", title="MEMS IMU simulator with thermal effects", order=30, build=build)
