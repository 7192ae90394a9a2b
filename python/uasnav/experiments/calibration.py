"""Thermal calibration of gyro bias (thesis §4.2.5, Figures 31–37, Tables 7–8), computed.

Calibrate on a simulated soak test of the AX1 (CRS05-02 gyros), evaluate on the simulated ramp
test: order / structure selection by Sr (eqs. 32, 33, 37), residuals of the polynomial, neural
and PX4 models against the true thermal bias, Δω(T) between the neural and polynomial models
(eq. 34), the attitude drift at the temperatures of Δω's maximum and RMS (Tables 7–8), the
derivative models (eq. 37), a hysteresis-aware fit and two robustness checks.

:func:`run` returns a :class:`CalibrationResult`; :mod:`uasnav.report` renders it. The thesis'
own numbers are in :mod:`uasnav.experiments.thesis`.

>>> t = np.linspace(0.0, 10.0, 11)
>>> zero = PolynomialBiasModel(1).fit(t, np.zeros((11, 3)))
>>> one = PolynomialBiasModel(1).fit(t, np.full((11, 3), 1e-3))
>>> dw = delta_omega(one, zero, np.array([2.0, 5.0]))
>>> round(dw.max_value, 12), round(dw.rms_value, 12)
(0.001732050808, 0.001732050808)
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TypeAlias

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav import sim
from uasnav.attitude import DriftResult, crossing_table, drift
from uasnav.experiments.thesis import FIG30_RAMP_RANGE_C
from uasnav.sim.lab import soak_calibration_data
from uasnav.thermal import (
    BiasModel,
    HysteresisFit,
    NeuralBiasModel,
    PolynomialBiasModel,
    Px4BiasModel,
    SelectionResult,
    TemperatureRangeWarning,
    branch_from_temperature,
    fit_hysteresis,
    select_hidden_neurons,
    select_polynomial_order,
    sr,
)

FloatArray: TypeAlias = NDArray[np.float64]

#: Simulator preset of the unit under test (CRS05-02 gyros, thesis' AX1).
PRESET = "ax1"
#: Block length of the soak means (s). The thesis' Sr values (~1e-5 rad/s) are far below the
#: CRS05-02's white noise at any usable rate, so its soak data must have been heavily smoothed;
#: we average the soak over 60 s blocks (quick mode: 10 s).
AVERAGE_S = 60


@dataclass(frozen=True)
class SoakRampData:
    """Soak (calibration) and ramp (test) data of the simulated AX1, with their truth.

    Attributes
    ----------
    source : str
        Where the data come from.
    average_s : int
        Block length of the soak means (s).
    soak_temp : ndarray, shape (m,)
        Mean die temperature of each soak block (°C).
    soak_bias : ndarray, shape (m, 3)
        Mean thermal gyro bias plus white noise of each soak block (rad/s).
    ramp_t : ndarray, shape (n,)
        Ramp test time (s).
    ramp_temp : ndarray, shape (n,)
        Measured die temperature on the ramp (°C).
    ramp_heating : ndarray of bool, shape (n,)
        True on the heating branch of the ramp.
    ramp_gyro : ndarray, shape (n, 3)
        Ramp gyro output minus the true rate and the non-thermal bias: thermal bias plus white
        noise (rad/s), what the models predict.
    ramp_truth : ndarray, shape (n, 3)
        True thermal bias on the ramp (rad/s).
    hysteresis_true : ndarray, shape (3,)
        True cooling − heating bias at the middle of the ramp range (rad/s).
    """

    source: str
    average_s: int
    soak_temp: FloatArray
    soak_bias: FloatArray
    ramp_t: FloatArray
    ramp_temp: FloatArray
    ramp_heating: NDArray[np.bool_]
    ramp_gyro: FloatArray
    ramp_truth: FloatArray
    hysteresis_true: FloatArray


def soak_and_ramp(*, seed: int = 2024, quick: bool = False) -> SoakRampData:
    """Simulate the soak test (calibration, ``seed``) and the ramp test (evaluation,
    ``seed + 1``) of the AX1; quick mode samples both ten times more coarsely."""
    # The soak lasts hours: 1 Hz (quick) or 10 Hz keeps it to a few 10⁵ samples.
    average_s = AVERAGE_S // (6 if quick else 1)
    cal = soak_calibration_data(
        PRESET, seed=seed, rate=1.0 if quick else 10.0, average_s=AVERAGE_S / (6 if quick else 1)
    )
    ramp = sim.simulate(PRESET, profile="ramp", rate=10.0 if quick else 100.0, seed=seed + 1)
    if ramp.temp is None:  # every preset has a temperature channel
        raise RuntimeError(f"{PRESET}: the ramp test has no temperature channel")
    # The ramp output minus the true rate (Earth rate) and the non-thermal bias (turn-on,
    # instability, random walk) is the thermal bias plus white noise: what the models predict.
    heating = branch_from_temperature(ramp.t, ramp.truth["temp_die"])
    turn_on = ramp.truth["gyro_bias"] - ramp.truth["gyro_bias_thermal"]
    mid = np.array([0.5 * (FIG30_RAMP_RANGE_C[0] + FIG30_RAMP_RANGE_C[1])])
    hysteresis = sim.thermal_bias(PRESET, mid, "cooling") - sim.thermal_bias(PRESET, mid, "heating")
    return SoakRampData(
        source=f"uasnav.sim preset {PRESET}, profiles soak and ramp",
        average_s=average_s,
        soak_temp=cal.temp,
        soak_bias=cal.gyro_bias,
        ramp_t=ramp.t,
        ramp_temp=ramp.temp,
        ramp_heating=heating,
        ramp_gyro=ramp.gyro - ramp.truth["rate_true"] - turn_on,
        ramp_truth=ramp.truth["gyro_bias_thermal"],
        hysteresis_true=hysteresis[0],
    )


@dataclass(frozen=True)
class ResidualStats:
    """Residual (truth − model) of one model over a test set.

    Attributes
    ----------
    rms, max : ndarray, shape (3,)
        Per-axis RMS and maximum of |residual| (rad/s).
    sr : float
        Sr of the residuals (eqs. 32–33, rad/s).
    """

    rms: FloatArray
    max: FloatArray
    sr: float


def residual_table(
    models: Mapping[str, BiasModel], temp_c: ArrayLike, truth: ArrayLike
) -> dict[str, ResidualStats]:
    """RMS and max |truth − model| per axis (rad/s) and Sr for each named model.

    Parameters
    ----------
    models : mapping of name to fitted model
    temp_c : array_like, shape (n,)
        Temperatures (°C).
    truth : array_like, shape (n, 3)
        True bias (rad/s).
    """
    out = {}
    for name, m in models.items():
        res = np.asarray(truth) - m.predict(temp_c)
        out[name] = ResidualStats(
            rms=np.sqrt(np.mean(res**2, axis=0)), max=np.max(np.abs(res), axis=0), sr=sr(res)
        )
    return out


@dataclass(frozen=True)
class DeltaOmega:
    """Δω(T) of eq. (34) over a temperature grid.

    Attributes
    ----------
    temp_c : ndarray, shape (m,)
        Temperatures (°C).
    delta : ndarray, shape (m,)
        ‖ω_NN(T) − ω_PF(T)‖ (rad/s) per temperature (the summand of eq. 34).
    max_value, rms_value : float
        Maximum and RMS of ``delta`` (rad/s).
    t_max_c, t_rms_c : float
        Temperature of the maximum, and of the point where ``delta`` is closest to its RMS (°C).
    """

    temp_c: FloatArray
    delta: FloatArray
    max_value: float
    rms_value: float
    t_max_c: float
    t_rms_c: float


def delta_omega(nn: BiasModel, pf: BiasModel, temp_c: FloatArray) -> DeltaOmega:
    """Δω(T) = ‖ω_NN(T) − ω_PF(T)‖ on ``temp_c`` (°C) and its max / RMS points (eq. 34)."""
    d = np.linalg.norm(nn.predict(temp_c) - pf.predict(temp_c), axis=1)
    i_max = int(np.argmax(d))
    rms = float(np.sqrt(np.mean(d**2)))
    i_rms = int(np.argmin(np.abs(d - rms)))
    return DeltaOmega(temp_c, d, float(d[i_max]), rms, float(temp_c[i_max]), float(temp_c[i_rms]))


@dataclass(frozen=True)
class DriftComparison:
    """Attitude drift of two calibrations' residual rates at one temperature.

    Attributes
    ----------
    temp_c : float
        Temperature (°C).
    residual_nn, residual_pf : ndarray, shape (3,)
        Truth − model of the neural and polynomial models (rad/s).
    drift_nn, drift_pf : DriftResult
        θ(t) from integrating each residual as a constant rate.
    rows : tuple of (threshold rad, t_NN s, t_PF s, Δt %)
        Tables 7–8 rows; None where a threshold is not reached within the run.
    """

    temp_c: float
    residual_nn: FloatArray
    residual_pf: FloatArray
    drift_nn: DriftResult
    drift_pf: DriftResult
    rows: tuple[tuple[float, float | None, float | None, float | None], ...]


def drift_at(
    nn: BiasModel,
    pf: BiasModel,
    truth_bias: FloatArray,
    temp_c: float,
    *,
    dt: float = 0.01,
    duration: float = 60.0,
) -> DriftComparison:
    """θ(t) from integrating each model's residual (truth − model) at ``temp_c`` as a constant
    rate (step ``dt`` s over ``duration`` s), and the Table 7/8 rows (threshold, t_NN, t_PF, Δt%)."""
    t = np.array([temp_c])
    r_nn = truth_bias - nn.predict(t)[0]
    r_pf = truth_bias - pf.predict(t)[0]
    d_nn = drift(r_nn, dt, duration)
    d_pf = drift(r_pf, dt, duration)
    return DriftComparison(temp_c, r_nn, r_pf, d_nn, d_pf, tuple(crossing_table(d_nn, d_pf)))


@dataclass(frozen=True)
class DerivativeStats:
    """One derivative model against the true ∂b/∂T on the ramp.

    Attributes
    ----------
    name : str
    rms : ndarray, shape (3,)
        Per-axis RMS error (rad/s/°C).
    sr : float
        Sr_TCZUPT of eq. (37) (rad/s/°C).
    """

    name: str
    rms: FloatArray
    sr: float


@dataclass(frozen=True)
class CalibrationResult:
    """Everything the calibration chapter reports.

    Attributes
    ----------
    quick : bool
        Whether the quick (coarser, shorter) settings were used.
    data : SoakRampData
    sel_poly, sel_nn, sel_derivative : SelectionResult
        Figures 31, 32, 37: Sr_PF vs order, Sr_NN vs neurons, Sr_TCZUPT vs neurons.
    residuals, residuals_heating : dict of str to ResidualStats
        Ramp residual per model (names in table order) on the whole ramp and on its heating half.
    fit_grid : ndarray, shape (400,)
        Temperatures (°C) over the soak range for the fitted curves.
    fit_nn, fit_pf : ndarray, shape (400, 3)
        BPNN 2-2 and polynomial m=2 on ``fit_grid`` (rad/s).
    delta_omega : DeltaOmega
        Figure 34 over the ramp range.
    drift_max, drift_rms : DriftComparison
        Figures 35–36 / Tables 7–8 at the temperatures of Δω_MAX and Δω_RMS.
    derivatives : tuple of DerivativeStats
        Analytic ∂/∂T of the BPNN, the derivative network, ∂/∂T of the selected polynomial.
    hysteresis : HysteresisFit
        Hysteresis-aware fit on the ramp (both branches).
    quantised_sr : float
        Sr (rad/s) of the BPNN 2-2 on the ramp with the temperature rounded to 1 °C.
    wide_range_c : tuple of float
        Range (°C) of the out-of-range check: the soak range ± 15 °C.
    n_wide, n_clipped : int
        Temperatures evaluated there, and how many fell outside the calibrated range.
    px4_params : dict
        The PX4 cubic as ``TC_G0_*`` parameters.
    """

    quick: bool
    data: SoakRampData
    sel_poly: SelectionResult
    sel_nn: SelectionResult
    sel_derivative: SelectionResult
    residuals: dict[str, ResidualStats]
    residuals_heating: dict[str, ResidualStats]
    fit_grid: FloatArray
    fit_nn: FloatArray
    fit_pf: FloatArray
    delta_omega: DeltaOmega
    drift_max: DriftComparison
    drift_rms: DriftComparison
    derivatives: tuple[DerivativeStats, ...]
    hysteresis: HysteresisFit
    quantised_sr: float
    wide_range_c: tuple[float, float]
    n_wide: int
    n_clipped: int
    px4_params: dict[str, float | int]


#: Name of the thesis' BPNN in :attr:`CalibrationResult.residuals`.
BPNN_THESIS = "BPNN 2-2 (thesis)"


def run(
    *, seed: int = 2024, quick: bool = False, progress: Callable[[str], None] | None = None
) -> CalibrationResult:
    """Run the calibration chapter's experiments (thesis §4.2.5).

    Parameters
    ----------
    seed : int
        Seed of the soak simulation and of the model fits (the ramp uses ``seed + 1``).
    quick : bool
        Coarser data, fewer candidates and restarts, shorter drift runs.
    progress : callable, optional
        Called with a short label before each long step.
    """
    say = progress or (lambda _msg: None)
    d = soak_and_ramp(seed=seed, quick=quick)
    temp, bias = d.soak_temp, d.soak_bias

    say("polynomial order selection")
    sel_p = select_polynomial_order(temp, bias, orders=tuple(range(1, 11)), seed=seed)
    say("BPNN structure selection")
    sel_n = select_hidden_neurons(
        temp,
        bias,
        candidates=(1, 2, 3) if quick else tuple(range(1, 11)),
        restarts=1 if quick else 2,
        max_samples=1500 if quick else 4000,
        seed=seed,
    )

    # Models as in the thesis (order 2, 2-2) plus the selected ones and the PX4 baseline.
    say("training models")
    pf = PolynomialBiasModel(2).fit(temp, bias)
    pf_sel = PolynomialBiasModel(sel_p.chosen).fit(temp, bias)
    nn = NeuralBiasModel(2, restarts=2 if quick else 4, derivative_network=True, seed=seed).fit(temp, bias)
    nn_sel = nn if sel_n.chosen == 2 else NeuralBiasModel(sel_n.chosen, restarts=2, seed=seed).fit(temp, bias)
    px4 = Px4BiasModel().fit(temp, bias)
    models: dict[str, BiasModel] = {
        "polynomial m=2 (thesis)": pf,
        f"polynomial m={sel_p.chosen} (selected)": pf_sel,
        BPNN_THESIS: nn,
        f"BPNN {sel_n.chosen}-{sel_n.chosen} (selected)": nn_sel,
        "PX4 TC cubic": px4,
    }
    rtemp, rtruth, heat = d.ramp_temp, d.ramp_truth, d.ramp_heating
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TemperatureRangeWarning)
        tab = residual_table(models, rtemp, rtruth)
        # The soak only visits the heating branch: the cooling half carries the hysteresis offset.
        tab_h = residual_table(models, rtemp[heat], rtruth[heat])
    fit_grid = np.linspace(temp.min(), temp.max(), 400)

    # Figures 34–36, Tables 7–8: Δω over the ramp range, drift at its max and RMS points.
    dw = delta_omega(nn, pf, np.linspace(*FIG30_RAMP_RANGE_C, 681))
    drifts = [
        drift_at(
            nn,
            pf,
            sim.thermal_bias(PRESET, np.array([t_pt]), "heating")[0],
            t_pt,
            dt=0.01,
            duration=60.0 if quick else 300.0,
        )
        for t_pt in (dw.t_max_c, dw.t_rms_c)
    ]

    # Derivative models: analytic vs derivative network (eq. 37), Figure 37.
    say("derivative models")
    dtrue = sim.thermal_bias_derivative(PRESET, rtemp)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TemperatureRangeWarning)
        d_an = nn.derivative(rtemp)
        d_net = nn.derivative(rtemp, method="network")
        d_poly = pf_sel.derivative(rtemp)
    derivatives = tuple(
        DerivativeStats(name, np.sqrt(np.mean((dtrue - x) ** 2, axis=0)), sr(dtrue - x))
        for name, x in (
            ("analytic ∂/∂T of BPNN 2-2", d_an),
            ("BPNN 2-2 trained on data derivative (thesis)", d_net),
            (f"∂/∂T of polynomial m={sel_p.chosen}", d_poly),
        )
    )
    sel_d = select_hidden_neurons(
        temp,
        bias,
        candidates=(1, 2, 3) if quick else tuple(range(1, 11)),
        restarts=1 if quick else 2,
        derivative=True,
        seed=seed,
    )

    # Hysteresis-aware fit on the ramp (both branches).
    hy = fit_hysteresis(rtemp, d.ramp_gyro, d.ramp_heating, order=3)

    # Robustness: 1 °C quantised temperature; outside the calibrated range.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TemperatureRangeWarning)
        q = residual_table({"BPNN 2-2, temp quantised to 1 °C": nn}, np.round(rtemp), rtruth)
        wide = np.linspace(temp.min() - 15, temp.max() + 15, 200)
        _, clipped = nn.predict(wide, return_clipped=True)

    return CalibrationResult(
        quick=quick,
        data=d,
        sel_poly=sel_p,
        sel_nn=sel_n,
        sel_derivative=sel_d,
        residuals=tab,
        residuals_heating=tab_h,
        fit_grid=fit_grid,
        fit_nn=nn.predict(fit_grid),
        fit_pf=pf.predict(fit_grid),
        delta_omega=dw,
        drift_max=drifts[0],
        drift_rms=drifts[1],
        derivatives=derivatives,
        hysteresis=hy,
        quantised_sr=q["BPNN 2-2, temp quantised to 1 °C"].sr,
        wide_range_c=(float(wide.min()), float(wide.max())),
        n_wide=int(wide.size),
        n_clipped=int(clipped.sum()),
        px4_params=px4.px4_params(),
    )


__all__ = [
    "AVERAGE_S",
    "BPNN_THESIS",
    "PRESET",
    "CalibrationResult",
    "DeltaOmega",
    "DerivativeStats",
    "DriftComparison",
    "ResidualStats",
    "SoakRampData",
    "delta_omega",
    "drift_at",
    "residual_table",
    "run",
    "soak_and_ramp",
]
