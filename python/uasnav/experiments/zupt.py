"""ZUPT and TCZUPT filters on a static unit through temperature ramps (thesis §4.2.6.2,
Figures 38–45, Tables 9–13), computed.

The simulated AX1 (CRS05-02 gyros) sits static through the ``cycles`` profile (60 s zeroing,
then the thesis' ramp test repeated with 5-min dwells); the thesis' BPNN, fitted on a simulated
soak test of the same sensor type, calibrates it. ZUPT filters the calibrated gyro, TCZUPT the
raw gyro with the model's ∂b/∂T (eq. 31). Beyond the thesis: errors against the simulator's true
bias, a Monte Carlo over units with and without hysteresis, ablations of the process noise,
NEES consistency, and a per-branch hysteresis study.

:func:`run` returns a :class:`ZuptExperiment`; :mod:`uasnav.report` renders it. The thesis' own
numbers are in :mod:`uasnav.experiments.thesis`.

>>> tuple(round(b, 4) for b in nees_bounds(2))  # 99 % χ² bounds of a 2-run mean 3-dof NEES
(0.3379, 9.2738)
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeAlias

import numpy as np
from numpy.typing import NDArray

from uasnav import sim, zupt
from uasnav.experiments.verdicts import CONFIRMED, Verdict, tczupt_claim
from uasnav.imu import ImuLog
from uasnav.sim.lab import soak_calibration_data
from uasnav.thermal import NeuralBiasModel, branch_from_temperature
from uasnav.zupt import Mode, ZuptConfig, ZuptResult

FloatArray: TypeAlias = NDArray[np.float64]

AXES = "xyz"
MODES: tuple[Mode, ...] = ("zupt", "tczupt")
#: Simulator preset of the unit under test (CRS05-02 gyros, thesis' AX1).
PRESET = "ax1"
#: Attitude of the static unit (roll, pitch, yaw; rad) and its true heading.
EULER = (0.012, -0.021, 0.4)
#: Filter output decimation (the filters run at the full rate and keep every 100th state).
DECIMATION = 100
#: The two scenarios of Tables 10–13: residual gyro bias after alignment (rad/s).
SCENARIOS = {"nominal": 0.0, "residual": zupt.RESIDUAL_BIAS_15DEG_H}
#: Monte-Carlo variants: filter mode and the change to its configuration. σ_GBI = 1.5e-4 deg/s
#: (Table 3), σ'_GBI = 5e-4 deg/s (Table 5); the ablations swap them between the filters.
VARIANTS: dict[str, tuple[Mode, dict[str, object]]] = {
    "ZUPT (σ_GBI, Table 3)": ("zupt", {}),
    "ZUPT with σ'_GBI": ("zupt", {"noise": zupt.THESIS_TCZUPT_NOISE}),
    "TCZUPT (σ'_GBI, Table 5)": ("tczupt", {}),
    "TCZUPT, derivative network": ("tczupt", {"derivative": "network"}),
    "TCZUPT with σ_GBI": ("tczupt", {"noise": zupt.THESIS_ZUPT_NOISE}),
}
#: Names of the two filters as the thesis tunes them, in :data:`VARIANTS`.
ZUPT_THESIS, TCZUPT_THESIS = "ZUPT (σ_GBI, Table 3)", "TCZUPT (σ'_GBI, Table 5)"
#: Keys of the Monte-Carlo data sets.
MC_KEYS = ("with hysteresis", "without hysteresis")


def sensor(hysteresis: bool) -> sim.SensorModel:
    """The simulator's AX1 (CRS05-02 gyros), optionally without its thermal hysteresis."""
    m = sim.load_preset(PRESET)
    if hysteresis or m.gyro.thermal is None:
        return m
    th = dataclasses.replace(m.gyro.thermal, hysteresis=0.0)
    return dataclasses.replace(m, gyro=dataclasses.replace(m.gyro, thermal=th))


def calibration_model(unit: sim.SensorModel, seed: int, quick: bool) -> NeuralBiasModel:
    """The thesis' BPNN (two hidden layers of two neurons, plus the derivative networks of
    eq. 37) fitted on a simulated soak test of the same sensor type (another seed)."""
    cal = soak_calibration_data(unit, seed=seed, rate=1.0 if quick else 10.0)
    return NeuralBiasModel(2, restarts=2 if quick else 4, derivative_network=True, seed=seed).fit(
        cal.temp, cal.gyro_bias
    )


def ramp_log(unit: sim.SensorModel, duration: float, seed: int) -> ImuLog:
    """The static unit through the ``cycles`` profile for ``duration`` s."""
    return sim.simulate(unit, profile="cycles", duration=duration, seed=seed, euler_rad=EULER)


def nees_bounds(n_runs: int) -> tuple[float, float]:
    """99 % two-sided bounds of the 3-dof NEES averaged over ``n_runs`` runs (χ²₃ₙ / n)."""
    from scipy.stats import chi2

    lo, hi = chi2.ppf([0.005, 0.995], 3 * n_runs) / n_runs
    return float(lo), float(hi)


@dataclass(frozen=True)
class FilterInput:
    """Figures 38–39: the filters' input, 1 Hz low-pass for display, decimated.

    Attributes
    ----------
    t : ndarray, shape (m,)
        Time (s).
    temp : ndarray, shape (m,)
        Measured die temperature (°C).
    calibrated, raw : ndarray, shape (m, 3)
        Calibrated (ZUPT's input) and raw (TCZUPT's input) gyro output (rad/s).
    """

    t: FloatArray
    temp: FloatArray
    calibrated: FloatArray
    raw: FloatArray


@dataclass(frozen=True)
class SegmentStats:
    """Tables 12–13: mean and std (3,) of the RMS error vs truth over the segments (rad/s)."""

    mean: FloatArray
    std: FloatArray


@dataclass(frozen=True)
class NeesStats:
    """Gyro-bias NEES averaged over the Monte-Carlo runs.

    Attributes
    ----------
    mean : float
        Time mean of the run-averaged NEES (3 for a consistent filter).
    lo, hi : float
        Its 99 % χ² bounds (:func:`nees_bounds`).
    inside_pct : float
        Percentage of the time steps within the bounds.
    """

    mean: float
    lo: float
    hi: float
    inside_pct: float

    @property
    def consistent(self) -> bool:
        """Whether the time-mean NEES is within the bounds."""
        return self.lo <= self.mean <= self.hi


@dataclass(frozen=True)
class MonteCarlo:
    """Whole-run RMS error vs truth over simulated units, residual 15 deg/h.

    Attributes
    ----------
    n_runs : int
        Units per data set (own seeds and calibrations).
    rms : dict
        ``rms[key][variant]`` (n_runs, 3) per-run, per-axis RMS (rad/s); keys :data:`MC_KEYS`,
        variants :data:`VARIANTS`.
    nees : dict
        ``nees[key][mode]`` NEES statistics of the unmodified filters.
    """

    n_runs: int
    rms: dict[str, dict[str, FloatArray]]
    nees: dict[str, dict[Mode, NeesStats]]

    def mean_rms(self, key: str, variant: str) -> FloatArray:
        """Per-axis RMS (3,) averaged over the runs (rad/s)."""
        return np.asarray(np.mean(self.rms[key][variant], axis=0), dtype=np.float64)


@dataclass(frozen=True)
class ClaimCheck:
    """The thesis' claim — TCZUPT converges faster in the 15 deg/h scenario and is not worse in
    RMS over the whole run — checked on the numbers above.

    Attributes
    ----------
    faster_axes : int
        Axes on which TCZUPT reached 1e-5 rad/s first from the exact start + 15 deg/h.
    ratio_with_hysteresis, ratio_without_hysteresis : float
        Monte-Carlo RMS of TCZUPT over ZUPT's, as the thesis tunes them.
    ratio_zupt_sgbi_prime : float
        ZUPT given σ'_GBI over TCZUPT (with hysteresis).
    ratio_tczupt_sgbi : float
        TCZUPT given σ_GBI over ZUPT (with hysteresis).
    verdict : Verdict
        :func:`uasnav.experiments.verdicts.tczupt_claim` on the per-axis convergence and the
        per-run, per-axis Monte-Carlo RMS with hysteresis: confirmed only if the claim holds on
        every axis beyond the Monte-Carlo spread.
    """

    faster_axes: int
    ratio_with_hysteresis: float
    ratio_without_hysteresis: float
    ratio_zupt_sgbi_prime: float
    ratio_tczupt_sgbi: float
    verdict: Verdict

    @property
    def confirmed(self) -> bool:
        """Whether the verdict is "confirmed" (on every axis)."""
        return self.verdict.verdict == CONFIRMED


@dataclass(frozen=True)
class BranchRms:
    """Hysteresis study: RMS error vs truth (3,) rad/s of each filter on one branch (nominal run)
    and the mean calibrated-bias shift on it relative to the heating branch (rad/s)."""

    zupt: FloatArray
    tczupt: FloatArray
    offset: float


@dataclass(frozen=True)
class ZuptExperiment:
    """Everything the ZUPT chapter reports.

    Attributes
    ----------
    duration, segment_s : float
        Run length and the segment length of Tables 12–13 (s).
    decimation : int
        Rows of the filter histories are every ``decimation``-th sample.
    filter_input : FilterInput
        Figures 38–39.
    runs : dict
        ``runs[scenario][mode]``: the filter runs of :data:`SCENARIOS`.
    reference : dict
        ``reference[mode]`` (m, 3): the 30 s moving-average reference of the mode's input
        (calibrated for ZUPT, raw for TCZUPT), decimated (rad/s).
    truth : dict
        ``truth[mode]`` (m, 3): the true bias of the mode's input, decimated (rad/s).
    table9_calibrated, table9_raw : ndarray, shape (3,)
        Table 9: mean residual of the moving-average reference (rad/s).
    ma_noise : float
        White noise σ_ARW/√30 s of the moving average (rad/s).
    rms_vs_ma, rms_vs_truth : dict
        Table 10: ``[scenario][mode]`` whole-run RMS error (3,) against the moving average and
        against the truth (rad/s).
    convergence_zeroed, convergence_exact : dict
        Table 11: ``[mode]`` per-axis convergence time (s, None = never), residual 15 deg/h,
        starting after the 60 s zeroing or from the true bias + 15 deg/h.
    segments : dict
        Tables 12–13: ``[scenario][mode]``.
    monte_carlo : MonteCarlo
    claim : ClaimCheck
    branches : dict
        ``branches[label]`` for "heating" and "cooling"; None if the run has no such branch.
    """

    duration: float
    segment_s: float
    decimation: int
    filter_input: FilterInput
    runs: dict[str, dict[Mode, ZuptResult]]
    reference: dict[Mode, FloatArray]
    truth: dict[Mode, FloatArray]
    table9_calibrated: FloatArray
    table9_raw: FloatArray
    ma_noise: float
    rms_vs_ma: dict[str, dict[Mode, FloatArray]]
    rms_vs_truth: dict[str, dict[Mode, FloatArray]]
    convergence_zeroed: dict[Mode, list[float | None]]
    convergence_exact: dict[Mode, list[float | None]]
    segments: dict[str, dict[Mode, SegmentStats]]
    monte_carlo: MonteCarlo
    claim: ClaimCheck
    branches: dict[str, BranchRms | None]


def _filter_input(log: ImuLog, model: NeuralBiasModel, dec: int) -> FilterInput:
    """Figures 38–39: 1 Hz low-pass (2nd-order Butterworth, zero phase) of both inputs."""
    from scipy.signal import butter, sosfiltfilt

    assert log.temp is not None  # the cycles profile always has a temperature channel
    sos = butter(2, 1.0, fs=log.sample_rate, output="sos")
    cal = sosfiltfilt(sos, log.gyro - model.predict(log.temp), axis=0)
    raw = sosfiltfilt(sos, log.gyro, axis=0)
    return FilterInput(log.t[::dec], log.temp[::dec], cal[::dec], raw[::dec])


def monte_carlo(
    log: ImuLog,
    model: NeuralBiasModel,
    base: ZuptConfig,
    *,
    duration: float,
    seed: int,
    quick: bool,
) -> MonteCarlo:
    """Whole-run RMS error vs truth over simulated units (the first unit with hysteresis is
    ``log`` / ``model``), with and without hysteresis, for every variant of :data:`VARIANTS`,
    and the NEES of the unmodified filters."""
    n_mc = 2 if quick else 6
    dec = base.decimation
    lo, hi = nees_bounds(n_mc)
    rms: dict[str, dict[str, FloatArray]] = {}
    nees: dict[str, dict[Mode, NeesStats]] = {}
    for hyst in (True, False):
        unit = sensor(hyst)
        key = MC_KEYS[0] if hyst else MC_KEYS[1]
        acc: dict[str, list[FloatArray]] = {v: [] for v in VARIANTS}
        nees_runs: dict[Mode, list[FloatArray]] = {"zupt": [], "tczupt": []}
        for s in range(n_mc):
            lg = log if (hyst and s == 0) else ramp_log(unit, duration, seed + 1000 + s)
            md = model if (hyst and s == 0) else calibration_model(unit, seed + 2000 + s, quick)
            assert lg.temp is not None
            tr_raw = lg.truth["gyro_bias"][::dec]
            tr_cal = (lg.truth["gyro_bias"] - md.predict(lg.temp))[::dec]
            cfg0 = base.replace(residual_gyro_bias_rad_s=zupt.RESIDUAL_BIAS_15DEG_H)
            for v, (mode, change) in VARIANTS.items():
                r = zupt.run(lg, mode, md, cfg0.replace(**change))
                tru = tr_cal if mode == "zupt" else tr_raw
                acc[v].append(zupt.rms_error(r.gyro_bias, tru))
                if not change:
                    nees_runs[mode].append(r.nees(tru))
        rms[key] = {v: np.array(acc[v]) for v in VARIANTS}
        nees[key] = {}
        for mode in MODES:
            curve = np.mean(np.array(nees_runs[mode]), axis=0)  # average over runs per time
            inside = float(np.mean((curve >= lo) & (curve <= hi))) * 100
            nees[key][mode] = NeesStats(float(np.mean(curve)), lo, hi, inside)
    return MonteCarlo(n_mc, rms, nees)


def run(
    *, seed: int = 2024, quick: bool = False, progress: Callable[[str], None] | None = None
) -> ZuptExperiment:
    """Run the ZUPT chapter's experiments (thesis §4.2.6.2).

    Parameters
    ----------
    seed : int
        Seed of the ramp-test simulation (the calibration soak uses ``seed + 1``, the
        Monte-Carlo units ``seed + 1000 + i`` and ``seed + 2000 + i``).
    quick : bool
        1-min instead of 5-min segments, 2 instead of 6 Monte-Carlo units, coarser soak.
    progress : callable, optional
        Called with a short label before each long step.
    """
    say = progress or (lambda _msg: None)
    seg_s = 60.0 if quick else 300.0
    duration = 60.0 + 5 * seg_s
    dec = DECIMATION

    say("simulating the ramp test")
    unit = sensor(True)
    log = ramp_log(unit, duration, seed)
    model = calibration_model(unit, seed + 1, quick)
    assert log.temp is not None
    heading = EULER[2]  # the unit's true heading (an external input in the thesis)
    truth_raw = log.truth["gyro_bias"]
    truth_cal = truth_raw - model.predict(log.temp)
    base = ZuptConfig(decimation=dec, heading_rad=heading)
    filter_input = _filter_input(log, model, dec)

    say("running ZUPT and TCZUPT")
    runs = {
        scen: {
            mode: zupt.run(log, mode, model, base.replace(residual_gyro_bias_rad_s=resid)) for mode in MODES
        }
        for scen, resid in SCENARIOS.items()
    }
    q0 = runs["nominal"]["zupt"].initial_attitude
    ref_cal = zupt.moving_average_reference(log, q0, model=model)
    ref_raw = zupt.moving_average_reference(log, q0)
    refs = {"zupt": (ref_cal, truth_cal), "tczupt": (ref_raw, truth_raw)}

    # Table 9 and the noise of the moving average itself.
    res_cal = zupt.reference_residual(log, ref_cal, q0, model=model)
    res_raw = zupt.reference_residual(log, ref_raw, q0)
    ma_noise = zupt.THESIS_ZUPT_NOISE.sigma_arw_rad_sqrt_s / np.sqrt(zupt.REFERENCE_WINDOW_S)

    # Table 10.
    rms_ma = {
        scen: {m: zupt.rms_error(runs[scen][m].gyro_bias, refs[m][0][::dec]) for m in MODES} for scen in runs
    }
    rms_tr = {
        scen: {m: zupt.rms_error(runs[scen][m].gyro_bias, refs[m][1][::dec]) for m in MODES} for scen in runs
    }

    # Table 11. Two starts: after the 60 s zeroing (as in the thesis; its own error is
    # σ_ARW/√60 s ≈ 1.2e-4 rad/s per axis, larger than 15 deg/h), and from the exact initial
    # bias + 15 deg/h (zeroing off), which isolates the scenario.
    conv_zeroed: dict[Mode, list[float | None]] = {}
    conv_exact: dict[Mode, list[float | None]] = {}
    for mode in MODES:
        cfg = base.replace(
            zeroing=False,
            gyro_bias0_rad_s=tuple(float(v) for v in refs[mode][1][0]),
            residual_gyro_bias_rad_s=zupt.RESIDUAL_BIAS_15DEG_H,
        )
        exact = zupt.run(log, mode, model, cfg)
        tru = refs[mode][1][::dec]
        r = runs["residual"][mode]
        conv_zeroed[mode] = zupt.convergence_time(r.t, r.gyro_bias, tru)
        conv_exact[mode] = zupt.convergence_time(exact.t, exact.gyro_bias, tru)

    # Tables 12–13: five consecutive segments after the zeroing.
    say("segment statistics")
    skip = int(60 * log.sample_rate)
    piece_log = log.slice(skip, log.n)
    segments: dict[str, dict[Mode, SegmentStats]] = {}
    for scen, resid in SCENARIOS.items():
        cfg = base.replace(residual_gyro_bias_rad_s=resid, decimation=10)
        segments[scen] = {}
        for mode in MODES:
            _, mean, std = zupt.segment_rms(
                piece_log, mode, refs[mode][1][skip:], model=model, config=cfg, segment_s=seg_s
            )
            segments[scen][mode] = SegmentStats(mean, std)

    # What makes the difference: Monte Carlo over seeds, with and without hysteresis, and
    # ablations that separate eq. 31 from TCZUPT's larger σ'_GBI.
    say("Monte Carlo: hysteresis and ablations")
    mc = monte_carlo(log, model, base, duration=duration, seed=seed, quick=quick)

    # Claim check, from the numbers above.
    faster_axis = []
    for j in range(3):
        tz_, tt_ = conv_exact["zupt"][j], conv_exact["tczupt"][j]
        faster_axis.append(tt_ is not None and (tz_ is None or tt_ < tz_))
    faster = sum(faster_axis)
    mean_rms = {k: {v: float(np.mean(mc.rms[k][v])) for v in VARIANTS} for k in MC_KEYS}
    hy, nh = mean_rms["with hysteresis"], mean_rms["without hysteresis"]
    ratio_h = hy[TCZUPT_THESIS] / hy[ZUPT_THESIS]
    claim = ClaimCheck(
        faster_axes=faster,
        ratio_with_hysteresis=ratio_h,
        ratio_without_hysteresis=nh[TCZUPT_THESIS] / nh[ZUPT_THESIS],
        ratio_zupt_sgbi_prime=hy["ZUPT with σ'_GBI"] / hy[TCZUPT_THESIS],
        ratio_tczupt_sgbi=hy["TCZUPT with σ_GBI"] / hy[ZUPT_THESIS],
        verdict=tczupt_claim(faster_axis, mc.rms[MC_KEYS[0]][TCZUPT_THESIS], mc.rms[MC_KEYS[0]][ZUPT_THESIS]),
    )

    # Hysteresis study, per branch (the thesis' first future development).
    say("hysteresis study")
    heating = branch_from_temperature(log.t, log.truth["temp_die"])[::dec]
    rz, rt = runs["nominal"]["zupt"], runs["nominal"]["tczupt"]
    tz, tt = truth_cal[::dec], truth_raw[::dec]
    settled = rz.t > 60.0
    branches: dict[str, BranchRms | None] = {}
    for label, mask in (("heating", heating & settled), ("cooling", ~heating & settled)):
        if not mask.any():
            branches[label] = None
            continue
        off = np.mean(tz[mask], axis=0) - np.mean(tz[heating & settled], axis=0)
        branches[label] = BranchRms(
            zupt.rms_error(rz.gyro_bias[mask], tz[mask]),
            zupt.rms_error(rt.gyro_bias[mask], tt[mask]),
            float(np.linalg.norm(off)),
        )

    return ZuptExperiment(
        duration=duration,
        segment_s=seg_s,
        decimation=dec,
        filter_input=filter_input,
        runs=runs,
        reference={m: refs[m][0][::dec] for m in MODES},
        truth={m: refs[m][1][::dec] for m in MODES},
        table9_calibrated=res_cal,
        table9_raw=res_raw,
        ma_noise=float(ma_noise),
        rms_vs_ma=rms_ma,
        rms_vs_truth=rms_tr,
        convergence_zeroed=conv_zeroed,
        convergence_exact=conv_exact,
        segments=segments,
        monte_carlo=mc,
        claim=claim,
        branches=branches,
    )


__all__ = [
    "AXES",
    "DECIMATION",
    "EULER",
    "MC_KEYS",
    "MODES",
    "PRESET",
    "SCENARIOS",
    "TCZUPT_THESIS",
    "VARIANTS",
    "ZUPT_THESIS",
    "BranchRms",
    "ClaimCheck",
    "FilterInput",
    "MonteCarlo",
    "NeesStats",
    "SegmentStats",
    "ZuptExperiment",
    "calibration_model",
    "monte_carlo",
    "nees_bounds",
    "ramp_log",
    "run",
    "sensor",
]
