"""``uasnav zupt``: run the ZUPT or TCZUPT filter over a static log."""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal

import click

from uasnav.cli._common import FINITE, LATITUDE, POSITIVE, OutputPath, Quantity, check_outputs, echo_json

if TYPE_CHECKING:
    from uasnav.zupt import ZuptResult


@click.command("zupt")
@click.argument("log", type=click.Path(dir_okay=False))
@click.option(
    "--mode",
    type=click.Choice(["zupt", "classic", "tczupt"]),
    default="zupt",
    show_default=True,
    help="zupt and classic name the same filter (calibrated gyro, random-walk bias).",
)
@click.option(
    "--model",
    "model_path",
    type=click.Path(dir_okay=False),
    help="Thermal model JSON (required for tczupt; for zupt it calibrates the gyro first).",
)
@click.option(
    "--derivative",
    type=click.Choice(["analytic", "network"]),
    default="analytic",
    show_default=True,
    help="TCZUPT's ∂b/∂T: the model's analytic derivative, or its derivative network (eq. 37).",
)
@click.option(
    "--residual-bias",
    type=Quantity("rad/s"),
    default="0 rad/s",
    show_default=True,
    help="Error added to the initial gyro-bias estimate on every axis, e.g. 15deg/h.",
)
@click.option("--latitude-deg", type=LATITUDE, default=45.0, show_default=True, help="Latitude of the unit.")
@click.option("--heading-deg", type=FINITE, default=0.0, show_default=True, help="True heading of the unit.")
@click.option("--levelling-s", type=POSITIVE, default=60.0, show_default=True, help="Zeroing window (s).")
@click.option("--out", "out_path", type=OutputPath(), help="Write EST.csv (t,bgx,…,baz,…).")
@click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")
@click.option("--plot", "plot_path", type=OutputPath(), help="Write a PNG of the gyro bias.")
def command(
    log: str,
    mode: Literal["zupt", "classic", "tczupt"],
    model_path: str | None,
    derivative: Literal["analytic", "network"],
    residual_bias: float,
    latitude_deg: float,
    heading_deg: float,
    levelling_s: float,
    out_path: str | None,
    as_json: bool,
    plot_path: str | None,
) -> None:
    """Estimate the gyro and accelerometer biases of a stationary LOG with the 15-state
    ZUPT filter (calibrated gyro data) or the thermally compensated TCZUPT filter (raw gyro
    data and a thermal model's derivative).

    LOG is any log the data layer reads (CSV v1). Without --model, zupt takes the gyro data as
    already calibrated.
    """
    import math

    from uasnav import zupt
    from uasnav.atomicfile import output_set
    from uasnav.errors import InputError
    from uasnav.io import read_log
    from uasnav.thermal import load_model

    if mode == "tczupt" and model_path is None:
        raise click.UsageError("--model is required for --mode tczupt")
    check_outputs([log, model_path], {"--out": out_path, "--plot": plot_path})
    data = read_log(log)
    model = load_model(model_path) if model_path else None
    cfg = zupt.ZuptConfig(
        latitude_deg=latitude_deg,
        heading_rad=math.radians(heading_deg),
        levelling_s=levelling_s,
        residual_gyro_bias_rad_s=residual_bias,
        derivative=derivative,
    )
    res = zupt.run(data, mode, model, cfg)
    if res.updates == 0:
        # Without a single update the "estimates" are the initial guesses (the API allows
        # that deliberately, labelled by `updates`; a CLI user would take them for a result).
        raise InputError(
            f"{log}: no ZUPT update in {data.n} samples ({data.duration:g} s; one update every "
            f"{cfg.update_interval_s:g} s): too short to estimate anything"
        )
    with output_set():  # EST.csv and the plot together, or neither
        if out_path:
            res.to_csv(out_path)
        if plot_path:
            _plot(res, plot_path)
    summary = {
        "log": log,
        "mode": mode,
        "derivative": derivative,
        "n_samples": data.n,
        "rate_hz": res.meta["rate_hz"],
        "updates": res.updates,
        "mean_nis": res.mean_nis,
        "residual_bias_rad_s": residual_bias,
        "gyro_bias_rad_s": res.gyro_bias[-1],
        "gyro_bias_std_rad_s": res.gyro_bias_std[-1],
        "accel_bias_m_s2": res.accel_bias[-1],
        "accel_bias_std_m_s2": res.accel_bias_std[-1],
        "initial_attitude": res.initial_attitude,
    }
    if as_json:
        echo_json(summary)
        return
    click.echo(
        f"{log}: {data.n} samples at {res.meta['rate_hz']:g} Hz, {mode.upper()}, {res.updates} updates"
    )
    for j, ax in enumerate("xyz"):
        click.echo(
            f"  gyro bias {ax}: {res.gyro_bias[-1, j]: .4e} ± {res.gyro_bias_std[-1, j]:.1e} rad/s   "
            f"accel bias {ax}: {res.accel_bias[-1, j]: .4e} ± {res.accel_bias_std[-1, j]:.1e} m/s²"
        )


def _plot(res: ZuptResult, path: str) -> None:
    from uasnav.plotting import new_figure, save_png

    fig, _ = new_figure(7.0, 7.5)
    fig.clear()
    axes = fig.subplots(3, 1, sharex=True)
    for j in range(3):
        res.plot_bias(j, ax=axes[j])
    save_png(fig, path)
