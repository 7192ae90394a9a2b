"""``uasnav calibrate``: fit a thermal gyro-bias model to a static log, or test one.

Fit:  ``uasnav calibrate TRAIN.csv --method poly|nn|both [--order N | --hidden N] [--select]
--out MODEL.json``. The static gyro output of TRAIN is the bias target (a constant Earth-rate
term is absorbed by the model). With ``--method both`` two files are written beside
``MODEL.json``: ``MODEL.poly.json`` and ``MODEL.nn.json``.

Test: ``uasnav calibrate --model MODEL.json --test TEST.csv [--json]`` prints the residual
``gyro − model(temp)`` per axis (mean, RMS, max |·|) and Sr (eq. 32/33) over TEST; if TEST
carries ``truth_gyro_bias_thermal`` (or ``truth_gyro_bias``) columns, also
``thermal_error_vs_truth``: ``truth − model(temp)`` with its mean over TEST removed (reported as
``offset``). The model carries the training log's turn-on bias, which no truth of another log
contains, so only the temperature-dependent part is compared like with like.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from uasnav.cli._common import POSITIVE, SEED, OutputPath, check_outputs, echo_json


@click.command("calibrate")
@click.argument("train", required=False, type=click.Path(dir_okay=False))
@click.option("--method", type=click.Choice(["poly", "nn", "both"]), default="both", show_default=True)
@click.option("--order", type=click.IntRange(0, 20), default=None, help="Polynomial order (default 2).")
@click.option(
    "--hidden", type=click.IntRange(1, 16), default=None, help="Neurons per hidden layer (default 2)."
)
@click.option("--select", is_flag=True, help="Choose order / neurons by Sr on held-out data (eqs. 32–33).")
@click.option(
    "--average", type=POSITIVE, default=1.0, show_default=True, help="Average TRAIN over S-second blocks."
)
@click.option("--seed", type=SEED, default=0, show_default=True)
@click.option("--out", type=OutputPath(), help="Model file to write (JSON).")
@click.option("--model", "model_path", type=click.Path(dir_okay=False), help="Model file to test.")
@click.option("--test", "test_path", type=click.Path(dir_okay=False), help="Static log to test the model on.")
@click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")
def command(
    train: str | None,
    method: str,
    order: int | None,
    hidden: int | None,
    select: bool,
    average: float,
    seed: int,
    out: str | None,
    model_path: str | None,
    test_path: str | None,
    as_json: bool,
) -> None:
    """Fit a thermal gyro-bias model to TRAIN (static log with temp), or test --model on --test."""
    if model_path or test_path:
        if train is not None or out is not None:
            raise click.UsageError(
                "use either TRAIN … --out MODEL.json or --model MODEL.json --test TEST.csv"
            )
        if not (model_path and test_path):
            raise click.UsageError("testing needs both --model and --test")
        _test(model_path, test_path, as_json)
        return
    if train is None or out is None:
        raise click.UsageError("fitting needs TRAIN and --out MODEL.json")
    if (method == "poly" and hidden is not None) or (method == "nn" and order is not None):
        raise click.UsageError("--order goes with --method poly, --hidden with --method nn")
    from uasnav.atomicfile import output_set
    from uasnav.thermal import fit_neural, fit_polynomial, load_training_data

    outp = Path(out)
    targets = {
        "poly": [outp],
        "nn": [outp],
        "both": [outp.with_suffix(".poly.json"), outp.with_suffix(".nn.json")],
    }[method]
    check_outputs([train], {"--out": targets})
    temp, bias = load_training_data(train, average)
    summary: dict[str, Any] = {
        "train": train,
        "n_samples": int(temp.size),
        "range_c": [temp.min(), temp.max()],
    }
    written = []
    saves = []  # written together at the end: both models, or neither
    meta = {"train_file": str(train), "average_s": average, "seed": seed}
    if method in ("poly", "both"):
        poly = fit_polynomial(temp, bias, order=order, select=select, seed=seed)
        if poly.selection is not None:
            sel = poly.selection
            summary["poly_selection"] = {"orders": sel.candidates, "sr": sel.sr, "chosen": sel.chosen}
        path = outp if method == "poly" else outp.with_suffix(".poly.json")
        saves.append((poly.model, path, {**meta, "order": poly.size}))
        written.append(str(path))
        summary["poly_order"] = poly.size
    if method in ("nn", "both"):
        nn = fit_neural(temp, bias, hidden=hidden, select=select, seed=seed)
        if nn.selection is not None:
            sel = nn.selection
            summary["nn_selection"] = {"neurons": sel.candidates, "sr": sel.sr, "chosen": sel.chosen}
        path = outp if method == "nn" else outp.with_suffix(".nn.json")
        saves.append((nn.model, path, {**meta, "hidden": nn.size}))
        written.append(str(path))
        summary["nn_hidden"] = nn.size
    with output_set():
        for model, path, training in saves:
            model.save(str(path), training=training)
    summary["written"] = written
    if as_json:
        echo_json(summary)
    else:
        lo, hi = summary["range_c"]
        click.echo(f"{train}: {temp.size} samples, {lo:.2f} … {hi:.2f} °C")
        for w in written:
            click.echo(f"wrote {w}")


def _test(model_path: str, test_path: str, as_json: bool) -> None:
    from uasnav.io import read_log
    from uasnav.thermal import evaluate_model, load_model

    model = load_model(model_path)
    ev = evaluate_model(model, read_log(test_path), source=test_path)
    out: dict[str, Any] = {
        "model": model_path,
        "kind": model.kind,
        "test": test_path,
        "n_samples": ev.n_samples,
        "clipped_samples": ev.clipped_samples,
        "calibrated_range_c": list(model.range_c_),
        "units": "rad/s",
        "residual": ev.residual.to_dict(),
    }
    if ev.thermal_error_vs_truth is not None:
        # Not truth − model itself: that includes the training log's turn-on bias.
        d = ev.thermal_error_vs_truth.to_dict()
        del d["mean"]  # zero by construction; the removed mean is "offset"
        out["thermal_error_vs_truth"] = {"truth": ev.truth_key, "offset": ev.truth_offset, **d}
    if as_json:
        echo_json(out)
        return
    click.echo(
        f"{model_path} ({model.kind}) on {test_path}: {ev.n_samples} samples, {ev.clipped_samples} clipped"
    )
    for name in ("residual", "thermal_error_vs_truth"):
        if name in out:
            s = out[name]
            click.echo(f"{name} (rad/s)   x            y            z")
            for stat in ("mean", "offset", "rms", "max_abs"):
                if stat not in s:
                    continue
                click.echo(f"  {stat:8s} " + " ".join(f"{v: .5e}" for v in s[stat]))
            click.echo(f"  Sr       {s['sr']:.5e}")
