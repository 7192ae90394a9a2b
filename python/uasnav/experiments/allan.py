"""Allan variance experiments (thesis §4.2.2.2.2, Tables 3–4): the NIST SP 1065 check of the
overlapping Allan deviation and the IEEE 952 noise identification of a simulated gyro.

>>> from uasnav.experiments.allan import nbs14_series, nist_check
>>> nbs14_series(3).round(6).tolist()
[0.57489, 0.184183, 0.563176]
>>> float(nist_check().rel_diff.max()) < 1e-6
True
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from uasnav.allan import AllanResult, oadev
from uasnav.errors import InputError
from uasnav.experiments.thesis import TABLE3
from uasnav.noise import TERMS, NoiseReport
from uasnav.units import convert

#: NIST SP 1065 §12 (p. 107): published overlapping ADEV of the 1000-point NBS-14 test set,
#: cluster size m (= τ in s at 1 Hz) → σ(τ) (dimensionless). A reference of the algorithm, not
#: a thesis number.
NIST_OADEV: dict[int, float] = {1: 2.922319e-01, 10: 9.159953e-02, 100: 3.241343e-02}

#: Rate random walk configured in the simulated gyro (deg/h/√h): a value of ours (not a thesis
#: number), large enough for the +1/2 slope to show within two hours.
RRW_CONFIGURED_DEG_H_SQRT_H = 30.0


def nbs14_series(n: int = 1000) -> NDArray[np.float64]:
    """The NIST SP 1065 test set: Lehmer generator n[i+1] = 16807·n[i] mod (2³¹−1).

    Parameters
    ----------
    n : int
        Number of points (NIST uses 1000).

    Returns
    -------
    ndarray, shape (n,)
        The series scaled to (0, 1) (dimensionless).
    """
    out = np.empty(n)
    s = 1234567890
    for i in range(n):
        out[i] = s / 2147483647.0
        s = (16807 * s) % 2147483647
    return out


def white_plus_rrw(n: int, rate: float, arw: float, rrw: float, seed: int) -> NDArray[np.float64]:
    """Simulated gyro rate: white noise plus a rate random walk.

    Closed-form Allan variance of the result: N²/τ + K²τ/3.

    Parameters
    ----------
    n : int
        Number of samples.
    rate : float
        Sample rate (Hz).
    arw : float
        White-noise density N (rad/√s).
    rrw : float
        Rate random walk K (rad/s/√s).
    seed : int
        Seed of :func:`numpy.random.default_rng` (white noise drawn first, then the walk).

    Returns
    -------
    ndarray, shape (n, 3)
        Gyro rate (rad/s).
    """
    rng = np.random.default_rng(seed)
    dt = 1.0 / rate
    white = rng.normal(0.0, arw / np.sqrt(dt), size=(n, 3))
    walk = np.cumsum(rng.normal(0.0, rrw * np.sqrt(dt), size=(n, 3)), axis=0)
    return white + walk


@dataclass(frozen=True)
class NistCheck:
    """Our overlapping ADEV of the NBS-14 set beside NIST SP 1065's published values.

    Attributes
    ----------
    taus : ndarray, shape (3,)
        Cluster times τ (s) at 1 Hz: 1, 10, 100.
    reference : ndarray, shape (3,)
        NIST SP 1065 values (dimensionless).
    adev : ndarray, shape (3,)
        Ours (dimensionless).
    rel_diff : ndarray, shape (3,)
        |ours − NIST| / NIST.
    """

    taus: NDArray[np.float64]
    reference: NDArray[np.float64]
    adev: NDArray[np.float64]
    rel_diff: NDArray[np.float64]


def nist_check() -> NistCheck:
    """Overlapping ADEV of :func:`nbs14_series` at τ = 1, 10, 100 s against :data:`NIST_OADEV`."""
    r = oadev(nbs14_series(), rate=1.0, taus=[1.0, 10.0, 100.0])
    adev = np.asarray(r.adev, dtype=np.float64)
    ref = np.array([NIST_OADEV[round(tau)] for tau in r.taus])
    return NistCheck(taus=np.asarray(r.taus), reference=ref, adev=adev, rel_diff=np.abs(adev - ref) / ref)


@dataclass(frozen=True)
class GyroIdentification:
    """IEEE 952 identification of a simulated gyro with the CRS05-02 ARW of thesis Table 3.

    Attributes
    ----------
    hours : float
        Length of the simulated record (h).
    rate_hz : float
        Sample rate (Hz).
    arw_configured_deg_sqrt_h : float
        Configured angle random walk (deg/√h; thesis Table 3).
    rrw_configured_deg_h_sqrt_h : float
        Configured rate random walk (deg/h/√h).
    curve : AllanResult
        Octave-spaced Allan deviation of the three axes (rad/s).
    report : NoiseReport
        Noise identification of ``curve``.
    arw_fit_deg_sqrt_h, arw_points_deg_sqrt_h : ndarray, shape (3,)
        ARW per axis from the five-term fit and read at τ = 1 s (deg/√h).
    rrw_fit_deg_h_sqrt_h : ndarray, shape (3,)
        RRW per axis from the fit (deg/h/√h; 0 where the fit does not support the term).
    terms : tuple of TermRecovery
        Every term configured in the simulation (ARW, bias instability = 0, RRW) against the
        fit's 95 % confidence interval, per axis.
    """

    hours: float
    rate_hz: float
    arw_configured_deg_sqrt_h: float
    rrw_configured_deg_h_sqrt_h: float
    curve: AllanResult
    report: NoiseReport
    arw_fit_deg_sqrt_h: NDArray[np.float64]
    arw_points_deg_sqrt_h: NDArray[np.float64]
    rrw_fit_deg_h_sqrt_h: NDArray[np.float64]
    terms: tuple[TermRecovery, ...] = ()

    @property
    def all_recovered(self) -> bool:
        """Every configured term inside its 95 % interval on every axis."""
        return all(bool(np.all(t.inside)) for t in self.terms)


@dataclass(frozen=True)
class TermRecovery:
    """One configured noise term beside the fit's confidence interval, per axis.

    Attributes
    ----------
    term : str
        IEEE 952 term (:data:`uasnav.noise.TERMS`).
    unit : str
        Field unit of the values (deg/√h, deg/h, deg/h/√h).
    configured : float
        Value configured in the simulation (``unit``; 0 for a term not simulated).
    fit, ci_low, ci_high : ndarray, shape (3,)
        Fitted value and its 95 % profile-likelihood interval per axis (``unit``).
    inside : ndarray of bool, shape (3,)
        ``ci_low ≤ configured ≤ ci_high`` per axis: the term is recovered.
    identifiable : ndarray of bool, shape (3,)
        The interval excludes 0 (the data demand the term).
    reasons : tuple of str
        Per axis: why the term is not identifiable (``""`` where it is).
    """

    term: str
    unit: str
    configured: float
    fit: NDArray[np.float64]
    ci_low: NDArray[np.float64]
    ci_high: NDArray[np.float64]
    inside: NDArray[np.bool_]
    identifiable: NDArray[np.bool_]
    reasons: tuple[str, ...]


def term_recovery(report: NoiseReport, term: str, configured: float, unit: str) -> TermRecovery:
    """Compare a configured value (``unit``) with the fit of ``term`` in ``report``.

    Parameters
    ----------
    report : NoiseReport
        Noise identification with confidence intervals.
    term : str
        IEEE 952 term.
    configured : float
        Truth of the simulation, in ``unit``.
    unit : str
        Unit of ``configured`` and of the returned values (dimension-checked).
    """
    if report.ci_low is None or report.ci_high is None:
        raise InputError("term_recovery: the noise report carries no confidence intervals")
    fit = report.fit.to(term, unit)
    lo = report.ci_low.to(term, unit)
    hi = report.ci_high.to(term, unit)
    i = TERMS.index(term)
    # a relative 1e-9 slack: the interval ends come from a bisection, not a closed form
    tol = 1e-9 * max(abs(configured), 1e-300)
    return TermRecovery(
        term=term,
        unit=unit,
        configured=float(configured),
        fit=fit,
        ci_low=lo,
        ci_high=hi,
        inside=(lo - tol <= configured) & (configured <= hi + tol),
        identifiable=report.identifiable[i].copy(),
        reasons=tuple(report.reason(j, term) or "" for j in range(fit.size)),
    )


def gyro_identification(
    *, seed: int = 2024, quick: bool = False, progress: Callable[[str], None] | None = None
) -> GyroIdentification:
    """Simulate 2 h (quick: 0.25 h) of 100 Hz gyro data (white + RRW) and identify its noise."""
    say = progress or (lambda _msg: None)
    rate = 100.0
    hours = 0.25 if quick else 2.0
    n = int(hours * 3600 * rate)
    arw_cfg = TABLE3["arw_deg_sqrt_h"]
    arw_true = float(convert(arw_cfg, "deg/√h", "rad/√s"))
    rrw_true = float(convert(RRW_CONFIGURED_DEG_H_SQRT_H, "deg/h/√h", "rad/s/√s"))
    say(f"  simulating {n} gyro samples (white + rate random walk) …")
    gyro = white_plus_rrw(n, rate, arw_true, rrw_true, seed)
    curve = oadev(gyro, rate, "octave", unit="rad/s")
    rep = curve.identify()
    arw_fit, _ = rep.fit.field("random_walk")
    rrw_fit, _ = rep.fit.field("rate_random_walk")
    arw_pt, _ = rep.points.field("random_walk")
    terms = (
        term_recovery(rep, "random_walk", arw_cfg, "deg/√h"),
        # not simulated: the interval must contain 0
        term_recovery(rep, "bias_instability", 0.0, "deg/h"),
        term_recovery(rep, "rate_random_walk", RRW_CONFIGURED_DEG_H_SQRT_H, "deg/h/√h"),
    )
    return GyroIdentification(
        hours=hours,
        rate_hz=rate,
        arw_configured_deg_sqrt_h=arw_cfg,
        rrw_configured_deg_h_sqrt_h=RRW_CONFIGURED_DEG_H_SQRT_H,
        curve=curve,
        report=rep,
        arw_fit_deg_sqrt_h=arw_fit,
        arw_points_deg_sqrt_h=arw_pt,
        rrw_fit_deg_h_sqrt_h=rrw_fit,
        terms=terms,
    )


@dataclass(frozen=True)
class AllanExperimentResult:
    """Results of the Allan variance chapter: the NIST check and the gyro identification."""

    nist: NistCheck
    gyro: GyroIdentification


def run(
    *, seed: int = 2024, quick: bool = False, progress: Callable[[str], None] | None = None
) -> AllanExperimentResult:
    """Run the NIST SP 1065 check and the simulated-gyro noise identification.

    Parameters
    ----------
    seed : int
        Seed of the simulated gyro.
    quick : bool
        0.25 h instead of 2 h of data (less precise).
    progress : callable, optional
        Receives one-line progress messages.
    """
    return AllanExperimentResult(
        nist=nist_check(), gyro=gyro_identification(seed=seed, quick=quick, progress=progress)
    )


__all__ = [
    "NIST_OADEV",
    "RRW_CONFIGURED_DEG_H_SQRT_H",
    "AllanExperimentResult",
    "GyroIdentification",
    "NistCheck",
    "TermRecovery",
    "gyro_identification",
    "nbs14_series",
    "nist_check",
    "run",
    "term_recovery",
]
