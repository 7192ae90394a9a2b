"""Report section: quaternion attitude and free-inertial drift (thesis §4.2.5.3, Tables 7–8).

Renders :func:`uasnav.experiments.attitude.run`.
"""

from __future__ import annotations

from uasnav.report import Section, SectionWriter


def build(w: SectionWriter) -> None:
    from uasnav.attitude import plot_drift
    from uasnav.experiments import attitude
    from uasnav.plotting import new_figure

    w.p(
        "θ(t) = 2·acos(|q_s|) (eq. 35) of the attitude error accumulated by integrating a "
        "residual gyro rate with the rotation-vector exponential. The thesis' Tables 7–8 grow "
        "linearly in time, i.e. each column is a constant residual rate |ω| = θ/t. We infer "
        "|ω| from the largest threshold of each column and recompute every crossing time "
        "with the propagator: agreement with the thesis' other rows checks both the tool and "
        "the reading of the tables."
    )
    res = attitude.run(seed=w.seed, quick=w.quick, progress=w.progress)
    for tc in (res.table7, res.table8):
        rows = [
            (f"{th:.2e}", *cols)
            for th, *cols in zip(
                tc.thresholds_rad,
                tc.thesis_t_nn_s,
                tc.t_nn_s,
                tc.thesis_t_pf_s,
                tc.t_pf_s,
                tc.thesis_dt_percent,
                tc.dt_percent,
                strict=True,
            )
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
                f"Table {tc.table} ({tc.residual}): |ω_NN| = {tc.w_nn_rad_s:.3e} rad/s, "
                f"|ω_PF| = {tc.w_pf_rad_s:.3e} rad/s"
            ),
            fmt="{:.2f}",
        )
        w.data[str(tc.table)] = {"w_nn": tc.w_nn_rad_s, "w_pf": tc.w_pf_rad_s, "rows": rows}
        if tc.table == 7:
            fig, ax = new_figure()
            plot_drift([("BPNN residual", tc.drift_nn), ("polynomial residual", tc.drift_pf)], ax=ax)
            ax.set_title("Free-inertial attitude drift (thresholds dotted)")
            w.figure(fig, "drift", "θ(t) for the residual rates implied by Table 7.")


SECTION = Section(key="attitude", title="Quaternion attitude and free-inertial drift", order=20, build=build)
