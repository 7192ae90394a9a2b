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
    fig, ax = new_figure()
    plot_adev(g.curve, ax=ax, labels=["gyro x", "gyro y", "gyro z"], report=g.report)
    ax.set_title("Simulated CRS05-02-like gyro: Allan deviation, IEEE 952 fit (dashed)")
    w.figure(fig, "gyro-adev", "Allan deviation with χ² 68 % intervals, fitted model and slope guides.")


SECTION = Section(key="allan", title="Allan variance and IMU noise identification", order=10, build=build)
