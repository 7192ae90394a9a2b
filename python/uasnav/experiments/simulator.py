"""The MEMS IMU simulator's experiments: thermal soak/ramp tests (thesis §4.2.4, Figures 29–30)
and the Allan deviation of the static case against the presets' specifications.

All gyro outputs here are in deg/s (the unit of the thesis' figures); the simulator works in SI.

>>> from uasnav.experiments.simulator import soak_test
>>> s = soak_test(seed=2024, rate=1.0)
>>> [round(t, 2) for t in s.temp_range_c], s.bin_gyro_deg_s.shape[1]
([-20.53, 37.3], 3)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from uasnav.allan import AllanResult, oadev
from uasnav.experiments.allan import TermRecovery, term_recovery
from uasnav.noise import NoiseReport
from uasnav.sim import load_preset, simulate, thermal_bias
from uasnav.sim.lab import block_average
from uasnav.units import convert

FloatArray = NDArray[np.float64]

RAD2DEG = 180.0 / math.pi

#: Presets of the static Allan experiment.
STATIC_PRESETS = ("ax1", "lsm6dsm")

#: Hysteresis read-out: die temperatures (°C) and half-width of the band around each (°C).
HYSTERESIS_TEMPS_C = (29.0, 30.5)
HYSTERESIS_BAND_C = 1.0


def _frozen(a: FloatArray) -> FloatArray:
    a.setflags(write=False)
    return a


#: Ramp plot: bin edges of the die temperature (°C, 0.25 °C bins) and the true-curve grid (°C)
#: (read-only: results share them).
RAMP_BIN_EDGES_C = _frozen(np.arange(27.0, 34.5, 0.25))
RAMP_GRID_C = _frozen(np.linspace(27.3, 34.0, 100))

# (noise term, TriadModel attribute, display unit) compared per sensor, with the SI unit of the
# attribute
_TERMS = {
    "gyro": (("random_walk", "white", "deg/√h"), ("bias_instability", "bias_instability", "deg/h")),
    "accel": (("random_walk", "white", "m/s/√h"), ("bias_instability", "bias_instability", "m/s/h")),
}
_SI = {
    "gyro": {"white": "rad/√s", "bias_instability": "rad/s"},
    "accel": {"white": "m/s/√s", "bias_instability": "m/s^2"},
}


def _quiet(_msg: str) -> None:
    pass


@dataclass(frozen=True)
class SoakTest:
    """Simulated soak test of the AX1 (cf. thesis Figure 29).

    Attributes
    ----------
    rate_hz : float
        Sample rate (Hz).
    samples : int
        Number of samples.
    temp_range_c : tuple of float
        (min, max) of the measured die temperature (°C).
    bin_temp_c : ndarray, shape (k,)
        Measured die temperature, 10 s block means (°C).
    bin_gyro_deg_s : ndarray, shape (k, 3)
        Gyro output, 10 s block means (deg/s).
    grid_c : ndarray, shape (200,)
        Temperature grid over the soak range (°C).
    true_output_deg_s : ndarray, shape (200, 3)
        True heating-branch thermal bias on ``grid_c`` plus the mean non-thermal bias and the
        Earth rate: the noise-free output (deg/s).
    """

    rate_hz: float
    samples: int
    temp_range_c: tuple[float, float]
    bin_temp_c: FloatArray
    bin_gyro_deg_s: FloatArray
    grid_c: FloatArray
    true_output_deg_s: FloatArray


def soak_test(*, seed: int = 2024, rate: float = 100.0) -> SoakTest:
    """Simulate the AX1 soak profile at ``rate`` Hz with ``seed`` and average it in 10 s blocks."""
    model = load_preset("ax1")
    soak = simulate(model, profile="soak", rate=rate, seed=seed)
    assert soak.temp is not None
    width = int(10 * rate)
    grid = np.linspace(soak.temp.min(), soak.temp.max(), 200)
    curve = thermal_bias(model, grid, "heating") * RAD2DEG
    offset = (soak.truth["gyro_bias"] - soak.truth["gyro_bias_thermal"]).mean(axis=0) * RAD2DEG
    earth = soak.truth["rate_true"][0] * RAD2DEG
    return SoakTest(
        rate_hz=rate,
        samples=soak.n,
        temp_range_c=(float(soak.temp.min()), float(soak.temp.max())),
        bin_temp_c=block_average(soak.temp, width),
        bin_gyro_deg_s=block_average(soak.gyro * RAD2DEG, width),
        grid_c=grid,
        true_output_deg_s=curve + offset + earth,
    )


@dataclass(frozen=True)
class RampBranch:
    """One branch (heating or cooling) of the simulated ramp test.

    Attributes
    ----------
    branch : str
        ``"heating"`` or ``"cooling"``.
    bin_temp_c : ndarray, shape (k,)
        Mean true die temperature of each occupied 0.25 °C bin (°C).
    bin_gyro_deg_s : ndarray, shape (k, 3)
        Mean gyro output of each bin (deg/s).
    true_output_deg_s : ndarray, shape (100, 3)
        Noise-free output on :data:`RAMP_GRID_C` on this branch (deg/s).
    """

    branch: str
    bin_temp_c: FloatArray
    bin_gyro_deg_s: FloatArray
    true_output_deg_s: FloatArray


@dataclass(frozen=True)
class RampTest:
    """Simulated ramp test of the AX1 (cf. thesis Figure 30) and its hysteresis.

    Attributes
    ----------
    rate_hz : float
        Sample rate (Hz).
    grid_c : ndarray, shape (100,)
        Temperature grid of the true curves (°C).
    heating, cooling : RampBranch
        The two branches.
    hysteresis_temps_c : tuple of float
        Die temperatures of the hysteresis read-out (°C).
    hysteresis_configured_deg_s : float
        Configured offset between the branches (deg/s).
    hysteresis_truth_deg_s, hysteresis_output_deg_s : tuple of float
        Heating − cooling at each temperature (axis mean, deg/s), of the true thermal bias and
        of the output with the true rate and the branch-free curve removed.
    """

    rate_hz: float
    grid_c: FloatArray
    heating: RampBranch
    cooling: RampBranch
    hysteresis_temps_c: tuple[float, ...]
    hysteresis_configured_deg_s: float
    hysteresis_truth_deg_s: tuple[float, ...]
    hysteresis_output_deg_s: tuple[float, ...]


def ramp_test(*, seed: int = 2025, rate: float = 100.0) -> RampTest:
    """Simulate the AX1 ramp profile, bin both branches and read the hysteresis."""
    model = load_preset("ax1")
    h = model.gyro.thermal.hysteresis if model.gyro.thermal else 0.0
    ramp = simulate(model, profile="ramp", rate=rate, seed=seed)
    die = ramp.truth["temp_die"]
    top = int(np.argmax(die))
    offset = (ramp.truth["gyro_bias"] - ramp.truth["gyro_bias_thermal"]).mean(axis=0) * RAD2DEG
    earth = ramp.truth["rate_true"][0] * RAD2DEG
    branches = []
    for part, lab in ((slice(0, top), "heating"), (slice(top, ramp.n), "cooling")):
        dp = die[part]
        k = np.digitize(dp, RAMP_BIN_EDGES_C)
        occupied = np.unique(k)
        tb = np.array([dp[k == i].mean() for i in occupied])
        gb = np.array([ramp.gyro[part][k == i].mean(axis=0) for i in occupied]) * RAD2DEG
        true = thermal_bias(model, RAMP_GRID_C, lab) * RAD2DEG + offset + earth
        branches.append(RampBranch(branch=lab, bin_temp_c=tb, bin_gyro_deg_s=gb, true_output_deg_s=true))
    # hysteresis: truth and output (branch-free curve removed) at equal temperature
    curve_die = model.gyro.thermal.curve(die) if model.gyro.thermal else np.zeros((ramp.n, 3))
    resid = ramp.gyro - ramp.truth["rate_true"] - curve_die
    th = ramp.truth["gyro_bias_thermal"]
    d_truth, d_out = [], []
    for temp in HYSTERESIS_TEMPS_C:
        up = (np.abs(die - temp) < HYSTERESIS_BAND_C) & (np.arange(ramp.n) < top)
        dn = (np.abs(die - temp) < HYSTERESIS_BAND_C) & (np.arange(ramp.n) > top)
        d_truth.append(float((th[up].mean(axis=0) - th[dn].mean(axis=0)).mean() * RAD2DEG))
        d_out.append(float((resid[up].mean(axis=0) - resid[dn].mean(axis=0)).mean() * RAD2DEG))
    return RampTest(
        rate_hz=rate,
        grid_c=RAMP_GRID_C,
        heating=branches[0],
        cooling=branches[1],
        hysteresis_temps_c=HYSTERESIS_TEMPS_C,
        hysteresis_configured_deg_s=h * RAD2DEG,
        hysteresis_truth_deg_s=tuple(d_truth),
        hysteresis_output_deg_s=tuple(d_out),
    )


@dataclass(frozen=True)
class TermCheck:
    """One noise term recovered from a static log beside the preset's specification.

    Attributes
    ----------
    preset, sensor, term, unit : str
        Preset name, ``"gyro"``/``"accel"``, IEEE 952 term (``"random_walk"``,
        ``"bias_instability"``) and the display unit of the values.
    spec : float
        Specified value (``unit``).
    fit, points : ndarray, shape (3,)
        Recovered per axis by the five-term fit and by slope points (``unit``).
    tau_cross_s : float or None
        For the bias instability: the τ (s) where the white-noise line meets the flicker
        floor, N²/τ = (0.664·B)² (inf if B = 0); None for other terms.
    resolvable : bool
        False if the floor is reached only beyond a tenth of the record (then the fit cannot
        see it and ``fit`` is not comparable with ``spec``); a prior from the specification.
    recovery : TermRecovery or None
        What the data say: the fit's 95 % interval per axis, whether it contains ``spec``,
        whether the term is identifiable and why not.
    """

    preset: str
    sensor: str
    term: str
    unit: str
    spec: float
    fit: FloatArray
    points: FloatArray
    tau_cross_s: float | None
    resolvable: bool
    recovery: TermRecovery | None = None


@dataclass(frozen=True)
class StaticPreset:
    """Allan analysis of one preset's static, constant-temperature log (100 Hz).

    Attributes
    ----------
    preset : str
        Preset name.
    gyro_curve, accel_curve : AllanResult
        Allan deviation of output − truth (rad/s, m/s²).
    gyro_report, accel_report : NoiseReport
        Their noise identification.
    terms : tuple of TermCheck
        Gyro then accelerometer: random walk and bias instability.
    """

    preset: str
    gyro_curve: AllanResult
    accel_curve: AllanResult
    gyro_report: NoiseReport
    accel_report: NoiseReport
    terms: tuple[TermCheck, ...]


@dataclass(frozen=True)
class StaticAllan:
    """Static Allan analyses of :data:`STATIC_PRESETS` (``hours`` of data each)."""

    hours: float
    presets: tuple[StaticPreset, ...]


def static_allan(
    *, seed: int = 2026, hours: float = 2.0, progress: Callable[[str], None] | None = None
) -> StaticAllan:
    """Simulate ``hours`` of static 100 Hz data per preset (same ``seed``) and identify the noise."""
    say = progress or _quiet
    record_s = hours * 3600.0
    out = []
    for preset in STATIC_PRESETS:
        model = load_preset(preset)
        say(f"  static {preset}, {hours:g} h at 100 Hz …")
        log = simulate(model, duration=record_s, rate=100.0, seed=seed)
        # octave τ from 0.08 s: shorter τ are shaped by the 30 Hz anti-alias low-pass
        taus = [0.08 * 2.0**k for k in range(int(math.log2(record_s / 10.0 / 0.08)) + 1)]
        g = oadev(log.gyro - log.truth["rate_true"], 100.0, taus, unit="rad/s")
        a = oadev(log.accel - log.truth["specific_force_true"], 100.0, taus, unit="m/s^2")
        rg, ra = g.identify(), a.identify()
        terms = []
        for kind, rep, tri in (("gyro", rg, model.gyro), ("accel", ra, model.accel)):
            for term, attr, unit in _TERMS[kind]:
                tau_cross: float | None = None
                resolvable = True
                if term == "bias_instability":
                    # the floor is resolvable only if it is reached within a tenth of the record
                    n_si, b_si = tri.white, tri.bias_instability
                    tau_cross = (n_si / (0.664 * b_si)) ** 2 if b_si > 0 else math.inf
                    resolvable = not tau_cross > record_s / 10.0
                spec = float(convert(getattr(tri, attr), _SI[kind][attr], unit))
                terms.append(
                    TermCheck(
                        preset=preset,
                        sensor=kind,
                        term=term,
                        unit=unit,
                        spec=spec,
                        fit=rep.fit.to(term, unit),
                        points=rep.points.to(term, unit),
                        tau_cross_s=tau_cross,
                        resolvable=resolvable,
                        recovery=term_recovery(rep, term, spec, unit),
                    )
                )
        out.append(
            StaticPreset(
                preset=preset,
                gyro_curve=g,
                accel_curve=a,
                gyro_report=rg,
                accel_report=ra,
                terms=tuple(terms),
            )
        )
    return StaticAllan(hours=hours, presets=tuple(out))


@dataclass(frozen=True)
class SimulatorResult:
    """The simulator chapter: soak and ramp tests, static Allan analyses."""

    soak: SoakTest
    ramp: RampTest
    static: StaticAllan


def run(
    *, seed: int = 2024, quick: bool = False, progress: Callable[[str], None] | None = None
) -> SimulatorResult:
    """Run the soak (seed), ramp (seed + 1) and static (seed + 2) experiments.

    Parameters
    ----------
    seed : int
        Base seed.
    quick : bool
        Thermal tests at 10 Hz instead of 100 Hz, static logs of 0.25 h instead of 2 h.
    progress : callable, optional
        Receives one-line progress messages.
    """
    say = progress or _quiet
    rate = 10.0 if quick else 100.0
    say(f"  soak test (ax1, {rate:g} Hz) …")
    soak = soak_test(seed=seed, rate=rate)
    say("  ramp test (ax1) …")
    ramp = ramp_test(seed=seed + 1, rate=rate)
    static = static_allan(seed=seed + 2, hours=0.25 if quick else 2.0, progress=say)
    return SimulatorResult(soak=soak, ramp=ramp, static=static)


__all__ = [
    "HYSTERESIS_BAND_C",
    "HYSTERESIS_TEMPS_C",
    "RAMP_BIN_EDGES_C",
    "RAMP_GRID_C",
    "STATIC_PRESETS",
    "RampBranch",
    "RampTest",
    "SimulatorResult",
    "SoakTest",
    "StaticAllan",
    "StaticPreset",
    "TermCheck",
    "ramp_test",
    "run",
    "soak_test",
    "static_allan",
]
