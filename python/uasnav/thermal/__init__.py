"""Thermal calibration of gyro bias (thesis §4.2.2.1, §4.2.3.1, §4.2.5, §4.2.6.1).

Models of bias against die temperature, all with the same scikit-learn-like API
(:class:`BiasModel`, :mod:`uasnav.thermal.base`) —
``fit(temp (n,) °C, bias (n, k) rad/s) → self``, ``predict(temp) → (n, k) rad/s``,
``derivative(temp) → (n, k) rad/s/°C``, ``save(path)``:

* :class:`PolynomialBiasModel` — least squares in a centred, scaled basis (eqs. 6–7);
  :func:`select_polynomial_order` by Sr_PF (eq. 32);
* :class:`NeuralBiasModel` — 1-n-n-1 tanh networks trained by Levenberg–Marquardt
  (§4.2.3.1), inference in Rust (``nav_core::mlp``); :func:`select_hidden_neurons` by Sr_NN
  (eq. 33) or Sr_TCZUPT (eq. 37); derivative analytic or by the thesis' derivative network;
* :class:`Px4BiasModel` — the PX4 ``TC_G*`` cubic baseline, exportable as PX4 parameters;
* :func:`fit_hysteresis` — shared shape with heating/cooling offsets, hysteresis width.

Temperatures outside the calibrated range are clipped to it and flagged
(:class:`TemperatureRangeWarning`, ``return_clipped=True``) — never extrapolated silently.
:func:`load_model` reads the one JSON model file format (:mod:`uasnav.thermal.modelfile`),
rebuilding the model registered for the file's kind (:func:`register_model`);
:func:`apply` calibrates a log. :func:`bin_by_temperature` / :func:`bin_by_time` average data
into bins; :mod:`uasnav.thermal.workflow` is the calibration of logged static tests
(``uasnav calibrate``): :func:`load_training_data`, :func:`fit_polynomial`,
:func:`fit_neural`, :func:`evaluate_model`.
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np

from uasnav.errors import InputError
from uasnav.imu import ImuLog, require_log
from uasnav.thermal._common import (
    NotFittedError,
    SelectionResult,
    TemperatureRangeWarning,
    choose,
    split_uniform,
    sr,
)
from uasnav.thermal.base import BiasModel, model_class, register_model, registered_kinds
from uasnav.thermal.binning import bin_by_temperature, bin_by_time, bin_means
from uasnav.thermal.hysteresis import HysteresisFit, branch_from_temperature, fit_hysteresis
from uasnav.thermal.modelfile import dumps_model, load_model, loads_model, save_model
from uasnav.thermal.neural import NeuralBiasModel, data_derivative, forward, select_hidden_neurons, train_lm
from uasnav.thermal.polynomial import PolynomialBiasModel, select_polynomial_order
from uasnav.thermal.px4 import Px4BiasModel
from uasnav.thermal.workflow import (
    FittedModel,
    ModelEvaluation,
    ResidualStats,
    evaluate_model,
    fit_neural,
    fit_polynomial,
    load_training_data,
)


def apply(model: BiasModel, log: ImuLog) -> ImuLog:
    """Calibrated copy of ``log``: gyro minus the model bias at the log's temperature.

    Temperatures outside the calibrated range are clipped (the count goes to
    ``meta["thermal_calibration"]["clipped"]`` and a :class:`TemperatureRangeWarning` is
    issued). Raises :class:`InputError` if the log has no temperature channel.
    """
    log = require_log(log)
    if log.temp is None:
        raise InputError("apply: the log has no temperature channel (temp is None)")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", TemperatureRangeWarning)
        bias, clipped = model.predict(log.temp, return_clipped=True)
    for w in caught:
        warnings.warn(w.message, w.category, stacklevel=2)
    if bias.shape[1] != 3:
        raise InputError(f"apply: model has {bias.shape[1]} axes, the gyro has 3")
    meta = dict(log.meta)
    meta["thermal_calibration"] = {
        "kind": model.kind,
        "range_c": list(model.range_c_),
        "clipped": int(np.count_nonzero(clipped)),
    }
    return replace(log, gyro=log.gyro - bias, meta=meta)


__all__ = [
    "BiasModel",
    "FittedModel",
    "HysteresisFit",
    "ModelEvaluation",
    "NeuralBiasModel",
    "NotFittedError",
    "PolynomialBiasModel",
    "Px4BiasModel",
    "ResidualStats",
    "SelectionResult",
    "TemperatureRangeWarning",
    "apply",
    "bin_by_temperature",
    "bin_by_time",
    "bin_means",
    "branch_from_temperature",
    "choose",
    "data_derivative",
    "dumps_model",
    "evaluate_model",
    "fit_hysteresis",
    "fit_neural",
    "fit_polynomial",
    "forward",
    "load_model",
    "load_training_data",
    "loads_model",
    "model_class",
    "register_model",
    "registered_kinds",
    "save_model",
    "select_hidden_neurons",
    "select_polynomial_order",
    "split_uniform",
    "sr",
    "train_lm",
]
