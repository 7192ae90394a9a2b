"""Thermal calibration of logged static tests: the pipeline behind ``uasnav calibrate``.

* :func:`load_training_data` — a static log's gyro output (the bias target: a constant
  Earth-rate term is absorbed by the model) averaged over time blocks, against temperature;
* :func:`fit_polynomial`, :func:`fit_neural` — fit one model, its order / neurons given or
  selected by Sr on held-out data (eqs. 32–33);
* :func:`evaluate_model` — residual ``gyro − model(temp)`` of a model on a static log per axis
  (mean, RMS, max |·|) and Sr, and the error against the log's true thermal bias if it has one.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from uasnav.errors import DataFormatError, InputError
from uasnav.imu import ImuLog, require_log
from uasnav.io import open_log, read_log
from uasnav.io.formats.csv_v1 import CsvV1Format
from uasnav.thermal._common import (
    TEMP_MAX_C,
    TEMP_MIN_C,
    FloatArray,
    SelectionResult,
    TemperatureRangeWarning,
    check_training_temp,
    sr,
    temp_range_error,
)
from uasnav.thermal.base import BiasModel
from uasnav.thermal.binning import TimeBlockMeans, bin_by_time
from uasnav.thermal.neural import NeuralBiasModel, select_hidden_neurons
from uasnav.thermal.polynomial import PolynomialBiasModel, select_polynomial_order

#: Fewest averaged samples a model is fitted to.
MIN_TRAINING_SAMPLES = 20

#: Truth columns :func:`evaluate_model` compares against, in order of preference.
TRUTH_KEYS = ("gyro_bias_thermal", "gyro_bias")


def load_training_data(path: str | os.PathLike[str], average_s: float = 1.0) -> tuple[FloatArray, FloatArray]:
    """Calibration data of a static log: block means of temperature and gyro output.

    A CSV v1 log is averaged while it is read, chunk by chunk (:meth:`CsvV1Format.stream`,
    :class:`~uasnav.thermal.binning.TimeBlockMeans`): memory grows with the number of blocks,
    not with the log (a day-long 100 Hz soak log of 1 GB is averaged in about 100 MB). Other
    formats are read whole.

    Parameters
    ----------
    path : str or PathLike
        Static IMU log with a ``temp`` column (any format :func:`uasnav.io.read_log` reads).
    average_s : float
        Block length (s) of the means (:func:`uasnav.thermal.binning.bin_by_time`); ≤ 0: no
        averaging.

    Returns
    -------
    temp : ndarray, shape (m,)
        Mean die temperature per block (°C).
    bias : ndarray, shape (m, 3)
        Mean gyro output per block (rad/s): the bias target.

    Raises
    ------
    InputError
        The log has no temperature, or fewer than 20 blocks.
    """
    fmt = _format(path) if average_s > 0 and np.isfinite(average_s) else None
    if isinstance(fmt, CsvV1Format):
        temp, bias = _csv_block_means(fmt, path, average_s)
    else:
        log = read_log(path)
        if log.temp is None:
            raise InputError(f"{path}: no temp column; thermal calibration needs the sensor temperature")
        # Checked before averaging: the row named is the log's, and 1e308 °C cannot overflow a mean.
        check_training_temp(log.temp, f"{path}: temp")
        temp, bias = bin_by_time(log.t, log.temp, log.gyro, average_s)
    if temp.size < MIN_TRAINING_SAMPLES:
        raise InputError(
            f"{path}: only {temp.size} samples after {average_s} s averaging; "
            f"need at least {MIN_TRAINING_SAMPLES}"
        )
    return temp, bias


def _format(path: str | os.PathLike[str]) -> object | None:
    """The format :func:`uasnav.io.open_log` recognises (extension, CSV header), or None when it
    cannot tell: :func:`uasnav.io.read_log` then names the problem."""
    try:
        return open_log(path).format
    except (InputError, DataFormatError):
        return None


def _csv_block_means(
    fmt: CsvV1Format, path: str | os.PathLike[str], average_s: float
) -> tuple[FloatArray, FloatArray]:
    """:func:`load_training_data` of a CSV v1 log, averaged chunk by chunk while it is read,
    with the checks and errors of the whole-log path in the same order."""
    with fmt.stream() as stream:
        if "temp" not in stream.columns:
            for _ in stream.blocks():  # an error in the data rows is reported first, as read_log does
                pass
            raise InputError(f"{path}: no temp column; thermal calibration needs the sensor temperature")
        cols = stream.columns
        jt, jg = cols.index("temp"), cols.index("gx")
        means = TimeBlockMeans(average_s)
        first_bad: tuple[float, int] | None = None
        n_bad = 0
        row = 0
        for block in stream.blocks():
            temp = block[:, jt]
            out = np.flatnonzero((temp < TEMP_MIN_C) | (temp > TEMP_MAX_C))
            if out.size:
                n_bad += int(out.size)
                if first_bad is None:
                    first_bad = (float(temp[out[0]]), row + int(out[0]))
            elif first_bad is None:
                means.add(block[:, 0], temp, block[:, jg : jg + 3])
            row += block.shape[0]
    if first_bad is not None:
        raise temp_range_error(f"{path}: temp", first_bad[0], first_bad[1], n_bad)
    return means.result()


@dataclass(frozen=True)
class FittedModel:
    """A fitted model, its size and the selection that chose it.

    Attributes
    ----------
    model : BiasModel
        The fitted model.
    size : int
        Polynomial order, or neurons per hidden layer.
    selection : SelectionResult or None
        Sr per candidate size when the size was selected (eqs. 32–33), else ``None``.
    """

    model: BiasModel
    size: int
    selection: SelectionResult | None


def fit_polynomial(
    temp: ArrayLike, bias: ArrayLike, *, order: int | None = None, select: bool = False, seed: int = 0
) -> FittedModel:
    """Fit a :class:`PolynomialBiasModel` to ``temp`` (n,) °C and ``bias`` (n, k) rad/s.

    ``select``: the order is chosen by Sr_PF on held-out data (:func:`select_polynomial_order`,
    eq. 32, split seed ``seed``); otherwise it is ``order`` (default 2).
    """
    m = order if order is not None else 2
    sel = None
    if select:
        sel = select_polynomial_order(temp, bias, seed=seed)
        m = sel.chosen
    return FittedModel(PolynomialBiasModel(m).fit(temp, bias), m, sel)


def fit_neural(
    temp: ArrayLike, bias: ArrayLike, *, hidden: int | None = None, select: bool = False, seed: int = 0
) -> FittedModel:
    """Fit a :class:`NeuralBiasModel` (with derivative networks, eq. 37) to ``temp`` (n,) °C and
    ``bias`` (n, k) rad/s.

    ``select``: the neurons per hidden layer are chosen by Sr_NN on held-out data
    (:func:`select_hidden_neurons`, eq. 33); otherwise ``hidden`` (default 2). ``seed`` seeds the
    split and the initial weights.
    """
    n = hidden if hidden is not None else 2
    sel = None
    if select:
        sel = select_hidden_neurons(temp, bias, seed=seed)
        n = sel.chosen
    return FittedModel(NeuralBiasModel(n, seed=seed, derivative_network=True).fit(temp, bias), n, sel)


@dataclass(frozen=True)
class ResidualStats:
    """Per-axis statistics of residuals (rad/s).

    Attributes
    ----------
    mean, rms, max_abs : ndarray, shape (k,)
        Mean, RMS and maximum absolute residual per axis (rad/s).
    sr : float
        Sr of eqs. (32)–(33): √(Σ RMS²) over the axes (rad/s).
    """

    mean: FloatArray
    rms: FloatArray
    max_abs: FloatArray
    sr: float

    @classmethod
    def of(cls, residuals: FloatArray) -> ResidualStats:
        """Statistics of ``residuals`` (n, k) rad/s."""
        return cls(
            mean=residuals.mean(axis=0),
            rms=np.sqrt(np.mean(residuals**2, axis=0)),
            max_abs=np.abs(residuals).max(axis=0),
            sr=sr(residuals),
        )

    def to_dict(self) -> dict[str, FloatArray | float]:
        """``{"mean", "rms", "max_abs", "sr"}`` (the ``uasnav calibrate --test`` JSON keys)."""
        return {"mean": self.mean, "rms": self.rms, "max_abs": self.max_abs, "sr": self.sr}


@dataclass(frozen=True)
class ModelEvaluation:
    """A thermal model on a static log (see :func:`evaluate_model`).

    Attributes
    ----------
    n_samples : int
        Samples of the log.
    clipped_samples : int
        Samples whose temperature lay outside the calibrated range (clipped to it).
    residual : ResidualStats
        ``gyro − model(temp)`` (rad/s).
    truth_key : str or None
        The truth column compared against (``"gyro_bias_thermal"`` or ``"gyro_bias"``), if any.
    error_vs_truth : ResidualStats or None
        ``truth − model(temp)`` (rad/s), if the log has a truth column. Not like with like: the
        model was fitted to the *training* log's static output, so it carries that log's turn-on
        bias (and Earth rate), which no truth column of another log contains. Use
        ``thermal_error_vs_truth``.
    thermal_error_vs_truth : ResidualStats or None
        The temperature-dependent part compared like with like: ``truth − model(temp)`` minus its
        mean over the log (rad/s; ``mean`` is therefore 0). The constant the model carries cannot
        be told from a constant thermal error without the training log's truth, so it is removed
        and reported as ``truth_offset``.
    truth_offset : ndarray, shape (3,), or None
        The removed mean of ``truth − model(temp)`` per axis (rad/s): minus the training log's
        turn-on bias and Earth rate, plus any constant thermal error.
    """

    n_samples: int
    clipped_samples: int
    residual: ResidualStats
    truth_key: str | None
    error_vs_truth: ResidualStats | None
    thermal_error_vs_truth: ResidualStats | None = None
    truth_offset: FloatArray | None = None


def evaluate_model(model: BiasModel, log: ImuLog, source: str = "log") -> ModelEvaluation:
    """Residuals of ``model`` on the static ``log``: its gyro output minus the model's bias at the
    log's temperature, and the error against the true thermal bias (truth column
    ``gyro_bias_thermal``, else ``gyro_bias``) if the log has one.

    Temperatures outside the calibrated range are clipped (counted, no warning). ``source`` names
    the log in errors. Raises :class:`InputError` if the log has no temperature.
    """
    log = require_log(log)
    if log.temp is None:
        raise InputError(f"{source}: no temp column; cannot evaluate a thermal model")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TemperatureRangeWarning)
        pred, clipped = model.predict(log.temp, return_clipped=True)
    key = next((k for k in TRUTH_KEYS if k in log.truth), None)
    err = None if key is None else log.truth[key] - pred
    offset = None if err is None else err.mean(axis=0)
    return ModelEvaluation(
        n_samples=log.n,
        clipped_samples=int(clipped.sum()),
        residual=ResidualStats.of(log.gyro - pred),
        truth_key=key,
        error_vs_truth=None if err is None else ResidualStats.of(err),
        thermal_error_vs_truth=None if err is None else ResidualStats.of(err - offset),
        truth_offset=offset,
    )


__all__ = [
    "FittedModel",
    "ModelEvaluation",
    "ResidualStats",
    "evaluate_model",
    "fit_neural",
    "fit_polynomial",
    "load_training_data",
]
