"""Report section: redundant IMUs on regular polyhedra (thesis §4.3, Tables 14–15, Figs. 49–51).

Renders :func:`uasnav.experiments.redundancy.run`.
"""

from __future__ import annotations

from uasnav.experiments.verdicts import within_spread
from uasnav.report import Section, SectionWriter

_T15_HEAD = ["θ (rad)", "t_red thesis (s)", "t_red ours", "t thesis (s)", "t ours", "Δt% thesis", "Δt% ours"]
_IMP_HEAD = ["polyhedron", "per face", "sensors", "k_r theory", "noise ratio", "bias ratio", "time ratio"]


def build(w: SectionWriter) -> None:
    from matplotlib.figure import Figure

    from uasnav.attitude import plot_drift
    from uasnav.experiments import redundancy as X
    from uasnav.plotting import new_figure

    r = X.run(seed=w.seed, quick=w.quick, progress=w.progress)
    w.p(
        "Several MEMS IMUs on the faces of a regular polyhedron are fused into one IMU by "
        "weighted least squares over every sensor axis (weights 1/σ² from each sensor's Allan "
        "white noise). Every number below comes from the project simulator (uasnav.sim."
        f"simulate_array, preset {X.PRESET}: the STMicroelectronics LSM6DSM of the thesis' "
        "SensorTiles, 3.8 mdps/√Hz, 40 µg/√Hz, turn-on bias σ 1 dps / 13.3 mg, 30 Hz anti-alias "
        "filter, quantisation, bias instability and random walks), static, 100 Hz, each sensor "
        "with its own random errors and the simulator's truth to compare with."
    )

    # --- Table 14 and Figure 49 analogue ---------------------------------------------------------
    w.heading("Improvement factor k_r (eqs. 38–40, Table 14)")
    g = r.geometry
    rows14 = [(x.config, x.per_face, x.total, x.arrangement, x.k_r_thesis, x.k_r, x.match) for x in g.table14]
    w.table(
        ["config", "gyros per face", "total gyros", "arrangement (ours)", "k_r thesis", "k_r ours", "match"],
        rows14,
        caption="Table 14: single-axis gyros along the cube's face normals; k_r per IMU axis.",
        fmt="{:.4f}",
    )
    w.data["table14"] = [{"config": x.config, "k_r_thesis": x.k_r_thesis, "k_r": x.k_r} for x in g.table14]
    w.table(
        ["polyhedron", "per face", "k_r single-axis", "k_r triaxial"],
        [(x.shape, x.per_face, x.k_r_single_axis, x.k_r_triaxial) for x in g.polyhedra],
        caption="Every Platonic solid: k_r = √(3/N_axes) depends only on the number of sensor axes.",
        fmt="{:.3f}",
    )
    fig = Figure(figsize=(5.5, 5))
    ax3 = fig.add_subplot(projection="3d")
    for i, m in enumerate(g.cube_mountings):
        n = m[2]
        for j, col in enumerate(("tab:red", "tab:green", "tab:blue")):
            ax3.quiver(*n, *(0.4 * m[j]), color=col, linewidth=1.2)
        ax3.text(*(1.25 * n), f"face {i + 1}", fontsize=8)
    for setter in (ax3.set_xlim, ax3.set_ylim, ax3.set_zlim):
        setter(-1.3, 1.3)
    ax3.set_xlabel("x")
    ax3.set_ylabel("y")
    ax3.set_zlabel("z")
    w.figure(
        fig,
        "fig49-cube",
        "Figure 49 analogue: the six faces of the cube (+x, +y, +z, −x, −y, −z) and each sensor's "
        "x (red), y (green), z = outward normal (blue) axes.",
    )

    # --- Table 15 / Figures 50–51 ----------------------------------------------------------------
    w.heading("Free-inertial attitude from one sensor vs the fused cube (Table 15, Figs. 50–51)")
    t15 = r.table15
    fig, ax = new_figure()
    ax.plot(t15.t, t15.face1_gyro / X.DEG, linewidth=0.5)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("gyro output (deg/s)")
    ax.legend(["x", "y", "z"])
    ax.set_title("Face 1 triaxial gyro output (static)")
    w.figure(fig, "fig50-gyro", "Figure 50 analogue: the triaxial gyro output of face 1 (100 Hz).")
    w.data["table15"] = {}
    for v in t15.variants:
        rows = [
            (f"{x.threshold_rad:.2e}", x.t_red_thesis, x.t_red, x.t_thesis, x.t, x.dt_percent_thesis)
            + (x.dt_percent, x.dt_percent_median)
            for x in v.rows
        ]
        w.table(
            [*_T15_HEAD, "Δt% median"],
            rows,
            caption=f"Table 15 layout, {v.name}: single sensor = face 1; eq. (46) Δt%; the median is "
            f"over all six faces × {t15.n_mc} simulated cubes. — = not reached within the run.",
            fmt="{:.3g}",
        )
        w.data["table15"][v.name] = rows
        if v.name.startswith("raw"):
            fig, ax = new_figure()
            plot_drift([("single gyro (face 1)", v.single), ("cube, 6 fused", v.fused)], ax=ax)
            ax.set_xlim(0, min(t15.duration_s, 5.0))
            ax.set_ylim(0, 0.03)
            ax.set_title("θ(t), raw outputs")
            w.figure(fig, "fig51-theta", "Figure 51 analogue: θ(t) of one gyro vs the fused cube.")
    w.p(
        "Reading: the thesis' times (seconds) imply residual rates of about 0.07–0.27 deg/s, "
        "between our two variants: uncalibrated turn-on biases (σ 1 dps) cross the thresholds in "
        "fractions of a second, a 10 s initialisation leaves only noise and bias instability "
        "(tens of seconds). Fusion averages the six biases, so against a typical face the times "
        "grow by about 1/k_r = √6 (Δt% ≈ +145 %) for bias-dominated, linear θ growth (and 1/k_r² "
        "for noise-dominated √t growth); against one particular face the result can be anything, "
        "including negative when that face happens to have a small bias. "
        + w.verdict(
            "table15_thesis_dt_within_spread",
            within_spread(
                [x.dt_percent_thesis for x in t15.variants[0].rows],
                t15.mc_dt_percent,
                [f"θ = {x.threshold_rad:.2e} rad" for x in t15.variants[0].rows],
                "The thesis' one-face Δt% lies",
            ),
        )
        + "."
    )

    # --- improvement vs theory -------------------------------------------------------------------
    w.heading("Improvement against k_r theory, every polyhedron, 1–3 sensors per face")
    imp = r.improvement
    pts = [
        (x.shape, x.per_face, x.n_sensors, x.k_r, x.noise_ratio, x.bias_ratio, x.time_ratio)
        + (x.dt_percent_theory, x.dt_percent)
        for x in imp.rows
    ]
    w.table(
        [*_IMP_HEAD, "Δt% theory", "Δt% ours"],
        pts,
        caption="Fused/single white-noise σ (Allan deviation at τ₀) and RMS bias, and the time ratio "
        "median t(single sensor)/median t_red(fused) of the Table 15 thresholds (raw outputs, "
        f"averaged over the four thresholds), from {imp.seeds} simulated arrays × {imp.duration_s:.0f} s "
        "per row; all three should equal k_r, and Δt% = 100 (t_red/t − 1) = 100 (1/k_r − 1).",
        fmt="{:.3f}",
    )
    w.data["improvement"] = [p[:7] for p in pts]
    fig, ax = new_figure()
    ax.plot([0, 1], [0, 1], "k:", label="theory (= k_r)")
    kk = [x.k_r for x in imp.rows]
    ax.plot(kk, [x.noise_ratio for x in imp.rows], "o", label="white-noise ratio")
    ax.plot(kk, [x.bias_ratio for x in imp.rows], "s", mfc="none", label="bias ratio")
    ax.plot(kk, [x.time_ratio for x in imp.rows], "^", mfc="none", label="time ratio t/t_red")
    ax.set_xlabel("k_r theory")
    ax.set_ylabel("fused / single")
    ax.legend()
    w.figure(fig, "improvement", "Measured improvement against eq. (40) for every configuration.")

    # --- FDI -------------------------------------------------------------------------------------
    w.heading("One sensor failing mid-run: fusion with and without FDI")
    rows_f = [
        (x.name, x.max_dev_fdi_deg_s, x.max_dev_plain_deg_s, x.envelope_deg_s, x.flagged_fraction)
        for x in r.fdi.rows
    ]
    w.table(
        ["fault on sensor 3", "max dev. FDI (deg/s)", "max dev. no FDI", "5σ envelope", "flagged fraction"],
        rows_f,
        caption="Simulated cube with a known motion; fused rate deviation from the no-fault fusion "
        "after the fault (half-way through, injected by uasnav.sim.inject_fault); p_fa = 1e-6 per "
        "sample, χ² scale and parity biases learned over the first 10 s. Without FDI a dropout "
        "is still excluded (never fused from NaN).",
        fmt="{:.3g}",
    )
    w.data["fdi"] = rows_f
    if r.fdi.theta:
        fig, ax = new_figure()
        plot_drift(list(r.fdi.theta), ax=ax)
        ax.axvline(r.fdi.fault_time_s, color="k", linestyle="--", linewidth=0.8)
        ax.set_title("θ(t) with a 2 deg/s bias step on one sensor (dashed: fault)")
        w.figure(fig, "fdi-theta", "Attitude error with and without FDI after a sensor fault.")

    # --- Kalman ----------------------------------------------------------------------------------
    w.heading("Kalman fusion with per-axis bias states (partial self-calibration)")
    k = r.kalman
    rows_k = [(x.method, x.rate_bias_deg_s, x.worst_bias_error_deg_s) for x in k.rows]
    w.table(
        ["method", "fused rate bias (deg/s)", "worst axis-bias error (deg/s)"],
        rows_k,
        caption=f"{k.duration_s:.0f} s static. Redundancy alone estimates the parity part of the biases "
        f"(worst error vs that part: {k.parity_error_deg_s:.2g} deg/s) but "
        "not the part that looks like a rotation, so its fused rate keeps the averaged bias; a "
        "zero-rate reference makes every bias observable.",
        fmt="{:.3g}",
    )
    w.data["kalman"] = rows_k

    # --- relative alignment ----------------------------------------------------------------------
    w.heading("Relative alignment (eqs. 44–45) with known mounting errors")
    a = r.alignment
    w.table(
        ["face", "true δx (deg)", "true δy", "true δz", "error, ideal sensors (deg)", "error, full preset"],
        [(x.face, *x.true_deg, x.error_ideal_deg, x.error_preset_deg) for x in a.rows],
        caption="Misalignment of each face relative to face 1 (every sensor mounted with σ = 1° per "
        "axis) from the accelerometers' mean specific force in four static attitudes of 5 s; "
        "differences between attitudes cancel the turn-on biases. 'Ideal sensors': the preset "
        "without its own scale-factor, axis-misalignment and thermal errors; with them (5000 ppm, "
        "5 mrad) the sensor's internal misalignment is indistinguishable from a mounting "
        "rotation and limits the estimate.",
        fmt="{:.4f}",
    )
    w.data["alignment_max_error_deg"] = a.max_error_ideal_deg
    w.data["alignment_max_error_preset_deg"] = a.max_error_preset_deg

    # --- real data -------------------------------------------------------------------------------
    w.heading("Real data: the three IMUs of an ArduPilot log")
    w.p(
        "The report runs on simulated data only. The real-data evaluation — fusing the three "
        "IMUs of the ArduPilot DataFlash log of the shared reference data (uasnav.experiments."
        "ardupilot.analyse_log), comparing the fused white noise with each IMU, with the LS "
        "prediction and with a plain average, and checking ArduPilot's consistency gates (gyros "
        "within 5 deg/s, accelerometers within 0.75 m/s²) — is asserted by the test "
        "tests/test_redundancy.py::test_ardupilot_three_imus, and its figures are printed by "
        "`python benches/bench_python.py redundancy_ardupilot`."
    )


SECTION = Section(key="redundancy", title="Redundant IMUs on regular polyhedra", order=60, build=build)
