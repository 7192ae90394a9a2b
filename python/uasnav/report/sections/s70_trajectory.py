"""Report section: trajectory prediction with LVQ networks (thesis §5.1, Table 17, Figures 57–65).

Renders :func:`uasnav.experiments.trajectory.run`.
"""

from __future__ import annotations

import numpy as np

from uasnav.report import Section, SectionWriter


def build(w: SectionWriter) -> None:
    from matplotlib.figure import Figure

    from uasnav.experiments import trajectory
    from uasnav.experiments.thesis import TABLE17
    from uasnav.plotting import new_figure

    res = trajectory.run(seed=w.seed, quick=w.quick, progress=w.progress)
    r, n_train = res.phantom4, res.n_train
    w.p(
        "A plan is cut into elements of two 10 m segments (eq. 47); each element's turn angle θ "
        "(eq. 52), wind direction relative to its first segment θ_w (eq. 56) and wind speed are "
        "folded by the left/right mirror symmetry (Figure 53) and classified by an LVQ network "
        "(256 competitive neurons, LVQ1, learning rate 0.01, MATLAB lvqnet semantics) into the "
        "4×8×4 = 128 cells of eqs. (48)–(50); each class carries the mean speed change ΔV of its "
        "training elements and t = L/(V + ΔV). The thesis' Phantom-4 flights are not public, so "
        "the experiment is reproduced with a simulated multirotor (PI velocity loop, 15° tilt "
        "limit, quadratic drag, waypoint braking, 3.33 m/s, wind 2.78 m/s from NNE with "
        "Ornstein–Uhlenbeck gusts): two trajectories flown "
        f"{res.n_flights} times each, the first {n_train} for training, the rest for testing."
    )

    # Figure 57/58/63 analogue: plans, flown tracks, training/test pieces, wind.
    fig, ax = new_figure(7.0, 5.0)
    for name, fl in r.flights.items():
        plan = fl[0].plan_ne
        for k, tel in enumerate(fl):
            ax.plot(
                tel.pos_ne[:, 1], tel.pos_ne[:, 0], lw=0.5, color="C0" if k < n_train else "C1", alpha=0.6
            )
        ax.plot(plan[:, 1], plan[:, 0], "k--o", ms=3, lw=0.8)
        mid = res.piece_mid_ne[name]
        ax.plot(mid[:, 1], mid[:, 0], "s", color="C3", ms=4)
        ax.annotate(f"trajectory {name}", plan[1, ::-1], fontsize=8)
    ax.annotate(
        "",
        xy=(-20, -20),
        xytext=(-20 + 10 * np.sin(np.radians(22.5)), -20 + 10 * np.cos(np.radians(22.5))),
        arrowprops={"arrowstyle": "->", "color": "C2"},
    )
    ax.text(-19, -16, "wind 2.78 m/s from NNE", color="C2", fontsize=8)
    ax.set_xlabel("east (m)")
    ax.set_ylabel("north (m)")
    ax.set_aspect("equal")
    ax.set_title("Plans, training (blue) and test (orange) flights; Table-17 pieces (red)")
    w.figure(fig, "plans", "Figures 57, 58 and 63 analogue: the two simulated waypoint trajectories.")

    # Figures 59–62 analogue: the four training corner elements with the flown tracks.
    # Constrained layout (like every new_figure): calling tight_layout on top of it is what made
    # matplotlib warn "The figure layout has changed to tight" on every report run.
    fig = Figure(figsize=(7.0, 6.0), layout="constrained")
    axes = fig.subplots(2, 2)
    for ax_i, te in zip(axes.ravel(), res.training_elements, strict=True):
        for v in te.views:
            for track in v.tracks_ne:
                ax_i.plot(track[:, 1], track[:, 0], ".", ms=1.5)
            ax_i.plot(v.corner_ne[:, 1], v.corner_ne[:, 0], "k-", lw=1)
            ax_i.set_title(
                f"{v.trajectory}: θ = {te.theta_deg:.0f}°, θ_w = {te.theta_w_deg:.0f}°", fontsize=9
            )
        ax_i.set_aspect("equal")
    w.figure(
        fig,
        "training_elements",
        "Figures 59–62 analogue: the four training elements (local metres from the "
        "minimum coordinate) with the training flights' telemetry.",
    )
    w.table(
        ["θ (°)", "θ_w (°)", "ΔV thesis (m/s)", "ΔV ours vs cruise", "V_init ours", "ΔV ours vs V_init", "n"],
        [
            (
                e.theta_deg,
                e.theta_w_deg,
                e.dv_thesis_ms,
                e.dv_vs_cruise_ms,
                e.v_init_ms,
                e.dv_vs_v_init_ms,
                e.n,
            )
            for e in res.training_elements
        ],
        caption="Training elements (§5.1.4.2). The thesis' ΔV is relative to the element's initial speed; "
        "we train on ΔV relative to the commanded speed (known for a new plan); both shown. Our simulated "
        "vehicle slows down in corners, so ΔV vs cruise is negative.",
        fmt="{:.2f}",
    )

    t17 = []
    for pc, (th_nn, th_rows) in zip(r.table17, TABLE17, strict=True):
        for k, (tr, ee) in enumerate(zip(pc.t_real_s, pc.error_pct, strict=True)):
            th_real, th_e = th_rows[k] if k < len(th_rows) else (None, None)
            first = k == 0
            t17.append(
                (
                    pc.piece if first else "",
                    th_nn if first else None,
                    th_real,
                    th_e,
                    pc.t_nn_s if first else None,
                    tr,
                    ee,
                )
            )
    w.table(
        [
            "test piece",
            "t_NN thesis (s)",
            "t_Real thesis",
            "e% thesis",
            "t_NN ours (s)",
            "t_Real ours",
            "e% ours",
        ],
        t17,
        caption="Table 17 with our numbers. The thesis' 25–28 s at 3.33 m/s imply ~90 m test pieces, not one "
        "2×10 m element; our pieces are the elements from the corner at waypoint 1 to the corner at "
        "waypoint 3 "
        "(sum of predicted element times).",
        fmt="{:.2f}",
    )
    w.data["table17"] = [
        {"piece": p.piece, "t_nn_s": p.t_nn_s, "t_real_s": list(p.t_real_s)} for p in r.table17
    ]

    fitted = [m for m in res.methods if m.reason is None]
    mrows = [(m.name, m.mean_pct, m.median_pct, m.max_pct) for m in fitted]
    mrows += [(m.name, "not applicable", None, None) for m in res.methods if m.reason is not None]
    na = "".join(f" {m.name} is not applicable: {m.reason}." for m in res.methods if m.reason is not None)
    w.table(
        ["method", "mean e% per element", "median", "max"],
        mrows,
        caption=f"All {len(r.test)} test elements (2×10 m) of the test flights. "
        "The kinematic point mass knows no "
        "wind; the regressors use the same features as the LVQ." + na,
        fmt="{:.2f}",
    )
    w.data["methods"] = {
        m.name: {"mean": m.mean_pct, "median": m.median_pct, "max": m.max_pct} for m in fitted
    }
    w.data["methods_not_applicable"] = {m.name: m.reason for m in res.methods if m.reason is not None}
    fig, ax = new_figure(7.0, 3.5)
    ax.barh([m.name for m in fitted][::-1], [m.mean_pct for m in fitted][::-1], color="C0")
    ax.set_xlabel("mean e% per element (eq. 59)")
    w.figure(
        fig,
        "methods",
        "LVQ against the distance ÷ speed baselines and other predictors (simulated test flights).",
    )

    cross = res.cross
    w.table(
        ["method", *[f"mean e% {k}" for k in cross.results]],
        [(n, *v) for n, v in cross.mean_pct.items()],
        caption="Generalisation to a trajectory never flown in training (train on one trajectory's training "
        "flights, test on the other's test flights). The test set above shares every element with training, "
        "so there the network reduces to the per-cell table; here cells are missing and the network's "
        "nearest-prototype fallback is what it adds.",
        fmt="{:.2f}",
    )
    w.data["cross_trajectory"] = {
        n: dict(zip(cross.results, v, strict=True)) for n, v in cross.mean_pct.items()
    }
    w.p(
        "Real flights are not embedded in the report (their licence forbids redistribution). On the "
        "ArduCopter telemetry of five runs of one straight 100 m leg at 5 m/s (no wind message), "
        "leave-one-run-out, `uasnav trajectory evaluate phoenix_mission1_arducopter.tlog` gives whole-leg "
        "errors of 4.7 % for the LVQ against 15.3 % for distance ÷ speed and 6.4 % for 0.8 × speed; per "
        "element (2×10 m, including the acceleration and braking pieces) 15 % against 20 % and 29 %, and "
        "the kinematic point mass with the log's acceleration limit is best per element (13.1 %) and "
        "per run (median |e%| 2.3 % against the LVQ's 5.2 %): measured on real flights, not on "
        "simulation, it is therefore the default method of `uasnav trajectory train`, the LVQ of this "
        "section staying selectable (`--method lvq`). Only straight elements exist there, so "
        "the network reduces to the per-cell table; the LVQ on 0.1 m/s ΔV classes is reported as not "
        "applicable there (20 training elements fall into 20 ΔV classes, fewer than two per class) "
        "(BENCHMARKS.md lists every method)."
    )


SECTION = Section(key="trajectory", title="Trajectory prediction with LVQ networks", order=70, build=build)
