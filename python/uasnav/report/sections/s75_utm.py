"""Report section: trajectory prediction for UTM — calibrated time bounds, an ASTM F3548
operational intent of a 3D mission, and strategic deconfliction with a resolved conflict.

Renders :func:`uasnav.experiments.utm.run`.
"""

from __future__ import annotations

from uasnav.report import Section, SectionWriter


def build(w: SectionWriter) -> None:
    from matplotlib.patches import Polygon as PolygonPatch
    from matplotlib.patches import Rectangle

    from uasnav.experiments import utm
    from uasnav.experiments.trajectory import run_phantom4
    from uasnav.plotting import new_figure
    from uasnav.trajectory.models import DEFAULT_METHOD, make_predictor, method_of

    w.progress("utm: training the predictor")
    # the default method (kinematic point mass with the autopilot's limits: the most accurate
    # by leave-one-run-out on the real flights), trained on the Phantom-4 experiment's flights
    train = run_phantom4(n_flights=5 if w.quick else 10, n_train=3 if w.quick else 7, seed=w.seed).train
    model = make_predictor(DEFAULT_METHOD).fit(train)
    w.progress("utm: calibrating the time bounds on simulated runs")
    res = utm.run(model, seed=w.seed, quick=w.quick)
    c = res.coverage
    w.p(
        "Every predicted waypoint time and the ETA carry a band at a chosen coverage (95 % here), "
        "calibrated by split-conformal prediction: each calibration run scores the largest "
        "|true − predicted| time over all element boundaries, relative to (predicted time + 10 s + "
        "the time of elements the predictor flags as outside its training data); the ⌈(n+1)·0.95⌉-th "
        "smallest score scales the band. The guarantee is simultaneous over the whole trajectory, "
        "which is what an operational intent needs, and it holds for runs drawn like the calibration "
        "runs: random 3D routes (vertical take-off, legs that climb or descend, holds, vertical "
        "landing) and winds flown by the simulator within the vehicle's vertical limits, scored at "
        "every 3D element boundary (legs, turns, climbs, descents, hovers). The predictor is the "
        f"default method ({method_of(model)}: point mass with the autopilot's limits, the most "
        "accurate by leave-one-run-out on the real flights; the thesis' LVQ stays selectable). "
        f"{c.n_cal} runs calibrate; {c.n} held-out runs test."
    )
    w.table(
        [
            "coverage",
            "calibration runs",
            "held-out runs covered",
            "Clopper–Pearson 95 %",
            "relative half-width",
            "median ETA half-width",
        ],
        [
            (
                f"{c.coverage:.0%}",
                c.n_cal,
                f"{c.k}/{c.n}",
                f"{c.ci[0]:.3f}–{c.ci[1]:.3f}",
                c.quantile,
                f"{c.eta_halfwidth_pct:.1f} %",
            )
        ],
        caption="Coverage of the time bounds on held-out simulated runs with ground truth (every element "
        "boundary of a run inside its band counts as covered).",
        fmt="{:.3f}",
    )
    w.data["time_bounds"] = {
        "method": method_of(model),
        "coverage": c.coverage, "n_cal": c.n_cal, "covered": c.k, "n_test": c.n, "ci95": list(c.ci),
        "quantile": c.quantile, "eta_halfwidth_pct": c.eta_halfwidth_pct,
    }  # fmt: skip
    w.p(
        "The report runs on simulated data only. On real flights the bounds are checked by "
        "uasnav.experiments.utm.real_coverage (bounds calibrated on simulated runs at the log's "
        "commanded speed; runs covered k of n with a Clopper–Pearson interval; exercised by "
        "tests/test_utm_experiment.py on the ArduCopter telemetry of the shared reference data); "
        "its figures are in BENCHMARKS.md. The guarantee is for runs like the calibration runs: "
        "the simulator is not a given vehicle, so real coverage is a separate check, not a promise."
    )

    b = res.intent
    w.p(
        f"A 3D mission (take-off to 40 m, a four-leg survey with a 10 s hold and a climb to 60 m, "
        f"return and landing) becomes an ASTM F3548 operational intent of {len(b.details.volumes)} "
        "Volume4D (uas-standards types, validated): each piece of at most 100 m of the path grown by "
        "15 m laterally, ±10 m vertically, alive from the lower time bound at its start to the upper "
        "bound at its end; altitudes are WGS-84 ellipsoidal (home 450 m AMSL + geoid height 47.3 m). "
        f"Predicted ETA {b.eta_s:.0f} s, bounds {b.eta_bounds_s[0]:.0f}–{b.eta_bounds_s[1]:.0f} s. "
        "The simulated 3D flight of the survey (take-off, climb, hold and landing flown with "
        "the vertical limits) "
        + ("stays inside a live volume at every sample." if res.contained else "leaves the volumes.")
    )
    fig, ax = new_figure(10.0, 4.5)
    fig.delaxes(ax)
    ax, ax2 = fig.subplots(1, 2)
    for o in b.volume_outline_en:
        ax.add_patch(PolygonPatch(o, closed=True, fc="C0", ec="C0", alpha=0.15))
    ax.plot(res.truth_en[:, 0], res.truth_en[:, 1], "k-", lw=0.8, label="simulated flight")
    ax.plot(b.route_en[:, 0], b.route_en[:, 1], "C3o--", ms=3, lw=0.8, label="plan")
    ax.set_aspect("equal")
    ax.set_xlabel("east (m)")
    ax.set_ylabel("north (m)")
    ax.legend(fontsize=7)
    ax.set_title("Plan view: intent volumes (blue)")
    for (t0, t1), (z0, z1) in zip(b.volume_time_s, b.volume_alt_w84, strict=True):
        ax2.add_patch(Rectangle((t0, z0), t1 - t0, z1 - z0, fc="C0", ec="C0", alpha=0.15))
    ax2.plot(b.t_arrive_s, b.route_alt_w84, "C3o-", ms=3, lw=0.8, label="predicted")
    if res.truth_alt_w84 is not None:
        ax2.plot(res.truth_t, res.truth_alt_w84, "k-", lw=0.8, label="simulated flight")
    ax2.fill_betweenx(b.route_alt_w84, b.t_lo_s, b.t_hi_s, color="C1", alpha=0.3, label="time bounds")
    ax2.set_xlabel("time after departure (s)")
    ax2.set_ylabel("altitude (m, W84)")
    ax2.autoscale()
    ax2.legend(fontsize=7)
    ax2.set_title("Altitude/time view")
    w.figure(
        fig, "intent", "The survey mission's F3548 volumes with the simulated flight and the time bounds."
    )

    cf = res.conflict
    if cf is not None:
        delay = "none within a day" if cf.delay_s is None else f"{cf.delay_s:.0f} s"
        w.p(
            f"Deconfliction: a transit crossing the survey, departing 30 s later, conflicts with it in "
            f"{len(cf.volumes)} volume pair(s) between {cf.overlap[0]:%H:%M:%S} and {cf.overlap[1]:%H:%M:%S} "
            f"UTC. The smallest departure delay of the later intent ({cf.later}) that frees it of every "
            f"conflict is {delay}; delayed by it, {res.conflicts_after_delay} conflicts remain. The search "
            "is the utm-index crate's space-time grid (not all pairs), tested against brute force and a "
            "shapely STRtree implementation; BENCHMARKS.md gives its speed on 10⁵ intents."
        )
        fig, ax = new_figure(6.0, 4.5)
        for o in b.volume_outline_en:
            ax.add_patch(PolygonPatch(o, closed=True, fc="C0", ec="C0", alpha=0.12))
        for o in res.other_intent.volume_outline_en:
            ax.add_patch(PolygonPatch(o, closed=True, fc="C1", ec="C1", alpha=0.12))
        ax.autoscale()
        ax.set_aspect("equal")
        ax.set_xlabel("east (m)")
        ax.set_ylabel("north (m)")
        ax.set_title("Survey (blue) and crossing transit (orange)")
        w.figure(
            fig, "deconfliction", "Two intents whose volumes meet in space; the delay separates them in time."
        )
    w.data["deconfliction"] = {
        "conflict": cf is not None,
        "delay_s": None if cf is None else cf.delay_s,
        "conflicts_after_delay": res.conflicts_after_delay,
        "n_volumes": res.n_volumes,
    }


SECTION = Section(
    key="utm",
    title="Trajectory prediction for UTM: time bounds, F3548 intents, deconfliction",
    order=75,
    build=build,
)
