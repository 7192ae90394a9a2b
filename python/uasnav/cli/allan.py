"""``uasnav allan``: Allan deviation and noise table of a log."""

from __future__ import annotations

from typing import TYPE_CHECKING

import click

from uasnav.cli._common import POSITIVE, OutputPath, check_outputs, echo_json, parse_float_list

if TYPE_CHECKING:
    from uasnav.noise import NoiseReport

# the five IEEE 952 terms, in the order of uasnav.noise.TERMS (not imported at start-up)
TERMS = ("quantization", "random_walk", "bias_instability", "rate_random_walk", "rate_ramp")


@click.command("allan")
@click.argument("log", type=click.Path(dir_okay=False))
@click.option("--rate", type=POSITIVE, default=None, help="Sample rate (Hz); default: from t.")
@click.option(
    "--taus",
    default="octave",
    show_default=True,
    help="octave | decade | all | comma-separated cluster times in seconds (T1,T2,…).",
)
@click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")
@click.option("--plot", "plot_path", type=OutputPath(), help="Write a PNG plot.")
def command(log: str, rate: float | None, taus: str, as_json: bool, plot_path: str | None) -> None:
    """Allan deviation of the gyro and accelerometer axes of LOG, and their noise terms.

    LOG is any log the data layer reads (CSV format v1: t, gx gy gz, ax ay az [, temp]).
    Prints, per axis, the IEEE 952 terms from a five-term fit (field units: deg/√h, deg/h,
    m/s/√h, m/s/h …) with the slope-line readings as a cross-check.
    """
    from uasnav.allan import oadev
    from uasnav.errors import NumericalError
    from uasnav.io import read_log

    spec = taus if taus in ("octave", "decade", "all") else parse_float_list(taus, "--taus")
    check_outputs([log], {"--plot": plot_path})
    data = read_log(log)
    if rate is None:
        rate = data.uniform_rate()
    curves = {}
    for kind, x, unit in (("gyro", data.gyro, "rad/s"), ("accel", data.accel, "m/s^2")):
        try:
            curves[kind] = oadev(x, rate, spec, unit=unit)
        except NumericalError as e:  # name the file and the sensor
            raise NumericalError(f"{log}: {kind}: {e}") from None
    gyro, accel = curves["gyro"], curves["accel"]
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
                        "noise_ci_level": r.confidence,
                        # per axis: null if the five-term fit was made, else why not
                        "fit_skipped": [why or None for why in r.fit_skipped],
                        "fit_rms_rel_residual": r.fit_rms_rel_residual,
                    }
                    for kind, r in reports.items()
                },
            }
        )
        return
    click.echo(f"{log}: {data.n} samples at {rate:g} Hz ({data.duration:.1f} s)")
    for kind, r in reports.items():
        _echo_report(kind, r)


def _echo_report(kind: str, r: NoiseReport) -> None:
    """Text output of one sensor: the Allan deviations with their intervals, then the noise
    terms with 95 % intervals, or why the fit or a term could not be made."""
    c = r.curve
    adev = c.adev if c.adev.ndim == 2 else c.adev[:, None]
    lo = c.ci_low if c.ci_low.ndim == 2 else c.ci_low[:, None]
    hi = c.ci_high if c.ci_high.ndim == 2 else c.ci_high[:, None]
    names = "xyz" if adev.shape[1] == 3 else [str(j) for j in range(adev.shape[1])]
    click.echo(f"\n{kind}: Allan deviation σ(τ) ({c.unit}) [{c.confidence:.0%} interval]")
    click.echo(f"  {'τ (s)':>10}" + "".join(f"{n:>34}" for n in names))
    for i, tau in enumerate(c.taus):
        cells = "".join(
            f"{f'{adev[i, j]:.4g} [{lo[i, j]:.3g}, {hi[i, j]:.3g}]':>34}" for j in range(adev.shape[1])
        )
        click.echo(f"  {tau:>10.4g}{cells}")
    for j, why in enumerate(r.fit_skipped):
        if why:
            click.echo(f"  {kind} {names[j]}: noise-term fit skipped: {why}")
    if all(r.fit_skipped):
        return
    click.echo(
        f"  noise terms, IEEE 952 fit [{r.confidence:.0%} interval] (fit rms rel. residual per axis: "
        + ", ".join(f"{x:.3f}" for x in r.fit_rms_rel_residual)
        + ")"
    )
    click.echo(f"  {'term':<18}{'unit':<12}" + "".join(f"{n:>26}" for n in names) + "   point readings")
    rows = r.table()
    for term in TERMS:
        sel = [row for row in rows if row["term"] == term]
        vals = "".join(f"{_fit_cell(row, bool(r.fit_skipped[row['axis']])):>26}" for row in sel)
        pts = "/".join("-" if row["point_field"] is None else f"{row['point_field']:.3g}" for row in sel)
        click.echo(f"  {term:<18}{sel[0]['field_unit']:<12}{vals}   {pts}")
    for row in rows:
        if row["not_identifiable_reason"] and not r.fit_skipped[row["axis"]]:
            click.echo(
                f"  not identifiable: {names[row['axis']]} {row['term']}: {row['not_identifiable_reason']}"
            )


def _fit_cell(row: dict, skipped: bool) -> str:
    if skipped:
        return "-"
    return f"{row['fit_field']:.4g} [{row['ci_low_field']:.3g}, {row['ci_high_field']:.3g}]"


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
