"""Report section: Allan variance and noise identification (thesis §4.2.2.2.2, Tables 3–4).

Renders :func:`uasnav.experiments.allan.run`.
"""

from __future__ import annotations

from uasnav.report import Section, SectionWriter


def build(w: SectionWriter) -> None:
    from uasnav.allan import plot_adev
    from uasnav.experiments import allan
    from uasnav.experiments.thesis import TABLE3
    from uasnav.plotting import new_figure

    arw_thesis = TABLE3["arw_deg_sqrt_h"]
    w.p(
        "Overlapping Allan deviation (eqs. 26–28) computed in nav-core, one O(N) pass per "
        "cluster time. Checked first against the NIST SP 1065 reference values, then used to "
        "identify the IEEE 952 noise terms of a gyro with the CRS05-02 specification of the "
        f"thesis' Table 3 (ARW {arw_thesis:g} deg/√h)."
    )
    res = allan.run(seed=w.seed, quick=w.quick, progress=w.progress)
    nist = res.nist
    rows = [
        (f"{tau:g}", float(ref), float(ours), f"{d:.1e}")
        for tau, ref, ours, d in zip(nist.taus, nist.reference, nist.adev, nist.rel_diff, strict=True)
    ]
    w.table(
        ["τ (s)", "NIST SP 1065", "uasnav", "rel. diff"],
        rows,
        caption="Overlapping ADEV of the NIST SP 1065 1000-point test set",
        fmt="{:.6e}",
    )
    # the largest relative difference as printed in the table (one significant digit)
    w.data["nist_max_rel_diff"] = max(float(x[3]) for x in rows)

    g = res.gyro
    id_rows = [
        (
            ax,
            g.arw_configured_deg_sqrt_h,
            float(g.arw_fit_deg_sqrt_h[j]),
            float(g.arw_points_deg_sqrt_h[j]),
            g.rrw_configured_deg_h_sqrt_h,
            float(g.rrw_fit_deg_h_sqrt_h[j]),
        )
        for j, ax in enumerate("xyz")
    ]
    w.table(
        [
            "axis",
            "ARW configured (deg/√h)",
            "ARW fit",
            "ARW at τ=1 s",
            "RRW configured (deg/h/√h)",
            "RRW fit",
        ],
        id_rows,
        caption=(
            f"Noise identification on {g.hours:g} h of simulated {g.rate_hz:g} Hz gyro data "
            f"(thesis Table 3: σ_ARW = {arw_thesis:g} deg/√h)"
        ),
        fmt="{:.3f}",
    )
    w.data["arw_fit_deg_sqrt_h"] = g.arw_fit_deg_sqrt_h
    w.data["rrw_fit_deg_h_sqrt_h"] = g.rrw_fit_deg_h_sqrt_h

    # Rule: a configured term is recovered on an axis when the configured value lies inside the
    # fit's 95 % profile-likelihood interval; it is identified when that interval excludes 0.
    ci_rows = []
    why = []
    for t in g.terms:
        for j, ax in enumerate("xyz"):
            ident = "yes" if t.identifiable[j] else "no"
            ci_rows.append(
                (
                    f"{t.term} ({t.unit})",
                    ax,
                    t.configured,
                    float(t.fit[j]),
                    f"[{t.ci_low[j]:.3g}, {t.ci_high[j]:.3g}]",
                    "yes" if t.inside[j] else "NO",
                    ident,
                )
            )
            if not t.identifiable[j]:
                why.append(f"{ax} {t.term}: {t.reasons[j]}")
        w.data[f"{t.term}_recovery"] = {
            "unit": t.unit,
            "configured": t.configured,
            "fit": t.fit,
            "ci95_low": t.ci_low,
            "ci95_high": t.ci_high,
            "configured_inside_ci95": t.inside,
            "identifiable": t.identifiable,
        }
    w.table(
        ["term", "axis", "configured", "fit", "95 % interval", "configured inside", "identifiable"],
        ci_rows,
        caption="Every configured term against the fit's 95 % profile-likelihood interval",
        fmt="{:.4g}",
    )
    n_in = sum(int(t.inside.sum()) for t in g.terms)
    n_all = sum(t.inside.size for t in g.terms)
    w.data["all_terms_recovered"] = g.all_recovered
    w.data["all_terms_recovered_rule"] = "configured value inside the fit's 95 % interval on every axis"
    w.p(
        f"Configured value inside the 95 % interval for {n_in} of {n_all} axis × term pairs"
        + (" (every term recovered on every axis)." if g.all_recovered else ".")
        + (" Not identifiable from this log: " + "; ".join(why) + "." if why else "")
    )
    fig, ax = new_figure()
    plot_adev(g.curve, ax=ax, labels=["gyro x", "gyro y", "gyro z"], report=g.report)
    ax.set_title("Simulated CRS05-02-like gyro: Allan deviation, IEEE 952 fit (dashed)")
    w.figure(fig, "gyro-adev", "Allan deviation with χ² 68 % intervals, fitted model and slope guides.")


SECTION = Section(key="allan", title="Allan variance and IMU noise identification", order=10, build=build)
