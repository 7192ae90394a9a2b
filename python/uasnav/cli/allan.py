"""``uasnav allan``: Allan deviation and noise table of a log."""

from __future__ import annotations

import click

from uasnav.cli._common import echo_json, parse_float_list


@click.command("allan")
@click.argument("log", type=click.Path(dir_okay=False))
@click.option("--rate", type=float, default=None, help="Sample rate (Hz); default: from t.")
@click.option(
    "--taus",
    default="octave",
    show_default=True,
    help="octave | decade | all | comma-separated cluster times in seconds (T1,T2,…).",
)
@click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False), help="Write a PNG plot.")
def command(log: str, rate: float | None, taus: str, as_json: bool, plot_path: str | None) -> None:
    """Allan deviation of the gyro and accelerometer axes of LOG, and their noise terms.

    LOG is any log the data layer reads (CSV format v1: t, gx gy gz, ax ay az [, temp]).
    Prints, per axis, the IEEE 952 terms from a five-term fit (field units: deg/√h, deg/h,
    m/s/√h, m/s/h …) with the slope-line readings as a cross-check.
    """
    from uasnav.allan import oadev
    from uasnav.io import read_log

    spec = taus if taus in ("octave", "decade", "all") else parse_float_list(taus, "--taus")
    data = read_log(log)
    if rate is None:
        rate = data.uniform_rate()
    gyro = oadev(data.gyro, rate, spec, unit="rad/s")
    accel = oadev(data.accel, rate, spec, unit="m/s^2")
    reports = {"gyro": gyro.identify(), "accel": accel.identify()}
    if plot_path:
        _plot(reports, plot_path)
    if as_json:
        echo_json(
            {
                "log": log,
                "rate_hz": rate,
                "n_samples": data.n,
                **{
                    kind: {
                        "taus_s": r.curve.taus,
                        "adev": r.curve.adev.T,
                        "adev_unit": r.curve.unit,
                        "ci_low": r.curve.ci_low.T,
                        "ci_high": r.curve.ci_high.T,
                        "n_terms": r.curve.n_terms,
                        "noise": r.table(),
                        "fit_rms_rel_residual": r.fit_rms_rel_residual,
                    }
                    for kind, r in reports.items()
                },
            }
        )
        return
    click.echo(f"{log}: {data.n} samples at {rate:g} Hz ({data.duration:.1f} s)")
    for kind, r in reports.items():
        click.echo(
            f"\n{kind} (fit rms rel. residual per axis: "
            + ", ".join(f"{x:.3f}" for x in r.fit_rms_rel_residual)
            + ")"
        )
        click.echo(f"  {'term':<18}{'unit':<12}{'x':>12}{'y':>12}{'z':>12}   point readings x/y/z")
        rows = r.table()
        for term in ("quantization", "random_walk", "bias_instability", "rate_random_walk", "rate_ramp"):
            sel = [row for row in rows if row["term"] == term]
            vals = "".join(f"{row['fit_field']:>12.4g}" for row in sel)
            pts = "/".join("-" if row["point_field"] is None else f"{row['point_field']:.3g}" for row in sel)
            click.echo(f"  {term:<18}{sel[0]['field_unit']:<12}{vals}   {pts}")


def _plot(reports: dict, path: str) -> None:
    from uasnav.allan import plot_adev
    from uasnav.plotting import new_figure, save_png

    fig, ax = new_figure(11, 4.5)
    ax.remove()
    axes = fig.subplots(1, 2)
    for a, (kind, r) in zip(axes, reports.items(), strict=True):
        plot_adev(r.curve, ax=a, labels=[f"{kind} x", f"{kind} y", f"{kind} z"], report=r)
        a.set_title(f"{kind}: Allan deviation, fit (dashed), slope guides")
    save_png(fig, path)
