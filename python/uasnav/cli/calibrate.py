"""``uasnav calibrate``: fit a thermal gyro-bias model to a static log, or test one.

Fit:  ``uasnav calibrate TRAIN.csv --method poly|nn|both [--order N | --hidden N] [--select]
--out MODEL.json``. The static gyro output of TRAIN is the bias target (a constant Earth-rate
term is absorbed by the model). With ``--method both`` two files are written beside
``MODEL.json``: ``MODEL.poly.json`` and ``MODEL.nn.json``.

Test: ``uasnav calibrate --model MODEL.json --test TEST.csv [--json]`` prints the residual
``gyro − model(temp)`` per axis (mean, RMS, max |·|) and Sr (eq. 32/33) over TEST; if TEST
carries ``truth_gyro_bias_thermal`` (or ``truth_gyro_bias``) columns, also the error against
that truth.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import click
import numpy as np

from uasnav.cli._common import echo_json
from uasnav.errors import InputError


def _bin_average(
    t: np.ndarray, temp: np.ndarray, gyro: np.ndarray, seconds: float
) -> tuple[np.ndarray, np.ndarray]:
    if seconds <= 0:
        return temp, gyro
    idx = np.floor((t - t[0]) / seconds).astype(np.int64)
    counts = np.bincount(idx)
    ok = counts > 0
    tm = np.bincount(idx, temp)[ok] / counts[ok]
    gm = np.stack([np.bincount(idx, g)[ok] for g in gyro.T], 1) / counts[ok][:, None]
    return tm, gm


def _residual_stats(res: np.ndarray) -> dict[str, Any]:
    from uasnav.thermal import sr

    return {
        "mean": res.mean(axis=0),
        "rms": np.sqrt(np.mean(res**2, axis=0)),
        "max_abs": np.abs(res).max(axis=0),
        "sr": sr(res),
    }


@click.command("calibrate")
@click.argument("train", required=False, type=click.Path(dir_okay=False))
@click.option("--method", type=click.Choice(["poly", "nn", "both"]), default="both", show_default=True)
@click.option("--order", type=click.IntRange(0, 20), default=None, help="Polynomial order (default 2).")
@click.option(
    "--hidden", type=click.IntRange(1, 16), default=None, help="Neurons per hidden layer (default 2)."
)
@click.option("--select", is_flag=True, help="Choose order / neurons by Sr on held-out data (eqs. 32–33).")
@click.option(
    "--average", type=float, default=1.0, show_default=True, help="Average TRAIN over S-second blocks."
)
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--out", type=click.Path(dir_okay=False), help="Model file to write (JSON).")
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
    from uasnav.io import read_log

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
    from uasnav.thermal import (
        NeuralBiasModel,
        PolynomialBiasModel,
        select_hidden_neurons,
        select_polynomial_order,
    )

    log = read_log(train)
    if log.temp is None:
        raise InputError(f"{train}: no temp column; thermal calibration needs the sensor temperature")
    temp, bias = _bin_average(log.t, log.temp, log.gyro, average)
    if temp.size < 20:
        raise InputError(f"{train}: only {temp.size} samples after {average} s averaging; need at least 20")
    summary: dict[str, Any] = {
        "train": train,
        "n_samples": int(temp.size),
        "range_c": [temp.min(), temp.max()],
    }
    outp = Path(out)
    written = []
    meta = {"train_file": str(train), "average_s": average, "seed": seed}
    if method in ("poly", "both"):
        m = order if order is not None else 2
        if select:
            sel = select_polynomial_order(temp, bias, seed=seed)
            m = sel.chosen
            summary["poly_selection"] = {"orders": sel.candidates, "sr": sel.sr, "chosen": m}
        poly = PolynomialBiasModel(m).fit(temp, bias)
        path = outp if method == "poly" else outp.with_suffix(".poly.json")
        poly.save(str(path), training={**meta, "order": m})
        written.append(str(path))
        summary["poly_order"] = m
    if method in ("nn", "both"):
        n = hidden if hidden is not None else 2
        if select:
            sel = select_hidden_neurons(temp, bias, seed=seed)
            n = sel.chosen
            summary["nn_selection"] = {"neurons": sel.candidates, "sr": sel.sr, "chosen": n}
        nn = NeuralBiasModel(n, seed=seed, derivative_network=True).fit(temp, bias)
        path = outp if method == "nn" else outp.with_suffix(".nn.json")
        nn.save(str(path), training={**meta, "hidden": n})
        written.append(str(path))
        summary["nn_hidden"] = n
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
    from uasnav.thermal import TemperatureRangeWarning, load_model

    model = load_model(model_path)
    log = read_log(test_path)
    if log.temp is None:
        raise InputError(f"{test_path}: no temp column; cannot evaluate a thermal model")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TemperatureRangeWarning)
        pred, clipped = model.predict(log.temp, return_clipped=True)
    out: dict[str, Any] = {
        "model": model_path,
        "kind": model.kind,
        "test": test_path,
        "n_samples": log.n,
        "clipped_samples": int(clipped.sum()),
        "calibrated_range_c": list(model.range_c_),
        "units": "rad/s",
        "residual": _residual_stats(log.gyro - pred),
    }
    key = next((k for k in ("gyro_bias_thermal", "gyro_bias") if k in log.truth), None)
    if key is not None:
        out["error_vs_truth"] = {"truth": key, **_residual_stats(log.truth[key] - pred)}
    if as_json:
        echo_json(out)
        return
    click.echo(
        f"{model_path} ({model.kind}) on {test_path}: {log.n} samples, {out['clipped_samples']} clipped"
    )
    for name in ("residual", "error_vs_truth"):
        if name in out:
            s = out[name]
            click.echo(f"{name} (rad/s)   x            y            z")
            for stat in ("mean", "rms", "max_abs"):
                click.echo(f"  {stat:8s} " + " ".join(f"{v: .5e}" for v in s[stat]))
            click.echo(f"  Sr       {s['sr']:.5e}")
