"""In-flight GNSS/INS experiments on simulated flights with truth (thesis §4.1.4): drift against
GNSS-outage duration, filter consistency (NEES), protection level against true error under a
GNSS fault, and the classic filter against TCZUPT on a warming IMU. Returns dataclasses; the
report section renders them."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from uasnav import ins
from uasnav.geo.frames import ned_to_geodetic
from uasnav.ins import evaluate as ev
from uasnav.sim.core import thermal_bias
from uasnav.sim.flight import FlightErrors, matched_config_values, simulate_flight
from uasnav.thermal.polynomial import PolynomialBiasModel

FloatArray = NDArray[np.float64]
DURATIONS = (10.0, 30.0, 60.0)
NO_THERMAL = FlightErrors(temp_rise_c=0.0)


def matched_config(**kw: object) -> ins.InsConfig:
    """The filter tuned to the simulator's sensor errors (:func:`matched_config_values`)."""
    m = matched_config_values(NO_THERMAL)
    return ins.InsConfig(
        sigma_vrw_m_s_sqrt_s=m["sigma_vrw_m_s_sqrt_s"],
        sigma_arw_rad_sqrt_s=m["sigma_arw_rad_sqrt_s"],
        extra={"mag_heading_std_rad": m["mag_heading_std_rad"], "baro_std_m": m["baro_std_m"]},
        **kw,  # type: ignore[arg-type]
    )


@dataclass(frozen=True)
class OutageStats:
    """Outage-end errors of one duration over many simulated flights (horizontal m)."""

    duration_s: float
    count: int
    median_m: float
    p95_m: float
    max_m: float
    median_vertical_m: float
    fraction_inside_3sigma: float


@dataclass(frozen=True)
class IntegrityTrace:
    """One flight with a GNSS ramp fault: true horizontal error and HPL over time."""

    t: FloatArray
    error_m: FloatArray
    hpl_m: FloatArray
    fault_start_s: float
    ramp_m_s: float
    hal_m: float
    first_exclusion_s: float | None
    alerts: list[dict[str, object]]
    violations: int


@dataclass(frozen=True)
class RampRow:
    """One GNSS position ramp (velocity untouched) on a simulated flight: when it was first
    flagged (separation alert, exclusion or reset), the worst true-error/PL ratio over the
    flight, and the rows where the error exceeded the PL with no flag raised at that epoch."""

    rate_m_s: float
    direction: str
    start_s: float
    first_flag_s: float | None
    worst_error_over_pl: float
    unannounced_rows: int


def unannounced_rows(r: ins.InsResult, truth: ins.Trajectory) -> tuple[int, float]:
    """Rows where the true horizontal error exceeds the HPL or the vertical the VPL while no
    flag is raised at that epoch (no alert, and the latest tested fix was used), and the worst
    error/PL ratio."""
    d = ev.ned_difference(r.lat, r.lon, r.alt, truth, r.t)
    eh, evv = np.hypot(d[:, 0], d[:, 1]), np.abs(d[:, 2])
    tested = np.isin(r.fix_status, (0, 1, 2, 5, 6))
    ft, fs = r.fix_t[tested], r.fix_status[tested]
    i = np.searchsorted(ft, r.t, side="right") - 1
    flag = r.alert | ((i >= 0) & np.isin(fs[np.maximum(i, 0)], (1, 2, 5, 6)))
    bad = ((eh > r.hpl) | (evv > r.vpl)) & ~flag
    return int(bad.sum()), float(max((eh / r.hpl).max(), (evv / r.vpl).max()))


RAMP_RATES = (0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 5.0)
RAMP_DIRECTIONS = {"north": (1.0, 0.0, 0.0), "south-east": (-0.6, 0.8, 0.0), "down": (0.0, 0.0, 1.0)}


def ramp_sweep(f: ins.Flight, start_s: float, rates: tuple[float, ...] = RAMP_RATES) -> list[RampRow]:
    """Every rate × direction of a GNSS position ramp from ``start_s`` on flight ``f``."""
    rows = []
    g = f.gnss
    for rate in rates:
        for name, u in RAMP_DIRECTIONS.items():
            a = np.clip(g.t - start_s, 0.0, None) * rate
            # each fix moved by the ramp's NED vector on the WGS-84 ellipsoid
            lat, lon, alt = ned_to_geodetic(a * u[0], a * u[1], a * u[2], g.lat, g.lon, g.alt)
            gg = dataclasses.replace(g, lat=lat, lon=lon, alt=alt)
            r = ins.run(dataclasses.replace(f, gnss=gg), matched_config(hal_m=40.0, val_m=50.0, decimation=5))
            flagged = r.fix_t[np.isin(r.fix_status, (1, 2, 5, 6))]
            bad, worst = unannounced_rows(r, f.truth)  # type: ignore[arg-type]
            first = float(flagged[0]) if flagged.size else None
            rows.append(RampRow(rate, name, start_s, first, worst, bad))
    return rows


@dataclass(frozen=True)
class InsExperiment:
    """Results of :func:`run`."""

    runs: int
    outages: list[OutageStats]
    nees_mean: dict[str, float]
    nees_bounds: tuple[float, float]
    integrity: IntegrityTrace
    classic_vs_tczupt: dict[str, float]
    accuracy: dict[str, float]
    ramps: list[RampRow]
    #: Fault-free flights: flagged fixes (separation alerts + exclusions), fixes tested,
    #: median HPL and VPL (m).
    fault_free: dict[str, float]


def _outage_stats(d: float, items: list[ev.Outage]) -> OutageStats:
    h = np.array([o.horizontal_error_m for o in items])
    return OutageStats(
        duration_s=d,
        count=len(items),
        median_m=float(np.median(h)),
        p95_m=float(np.percentile(h, 95)),
        max_m=float(h.max()),
        median_vertical_m=float(np.median([o.vertical_error_m for o in items])),
        fraction_inside_3sigma=float(np.mean([o.inside_3sigma for o in items])),
    )


def run(seed: int = 0, quick: bool = False, progress: Callable[[str], None] | None = None) -> InsExperiment:
    """Run the experiments (``quick``: 10 flights instead of 100)."""
    runs = 10 if quick else 100
    say = progress or (lambda s: None)
    ends: dict[float, list[ev.Outage]] = {d: [] for d in DURATIONS}
    nees: dict[str, list[FloatArray]] = {"position": [], "velocity": [], "attitude": []}
    acc: list[ev.Comparison] = []
    ff = {"flagged": 0.0, "fixes": 0.0}
    pls: list[tuple[float, float]] = []
    start = 90.0
    for k in range(runs):
        if k % 10 == 0:
            say(f"ins: simulated flight {k + 1}/{runs}")
        f = simulate_flight(
            duration_s=start + max(DURATIONS) + 10.0, seed=seed * 100_003 + k, errors=NO_THERMAL
        )
        base = ins.run(f, matched_config(decimation=20))
        acc.append(ev.compare(base, f.truth))  # type: ignore[arg-type]
        ff["flagged"] += base.summary["separation_alerts"] + base.summary["fixes_excluded"]
        ff["fixes"] += base.summary["fixes_used"] + base.summary["fixes_excluded"]
        pls.append((float(np.median(base.hpl)), float(np.median(base.vpl))))
        n = ev.nees(base, f.truth)  # type: ignore[arg-type]
        for key in nees:
            nees[key].append(n[key][150:])
        for d in DURATIONS:
            r = ins.run(f, matched_config(decimation=20, gnss_outages=((start, d),)))
            ends[d].append(ev.outage_end_error(r, f, start, d, against="truth"))
    lo, hi = ev.chi2_bounds(3, runs)
    nees_mean = {k: float(np.mean(np.mean(v, axis=0))) for k, v in nees.items()}
    # Integrity: a slow (0.1 m/s) ramp on the GNSS north position from 100 s, which the
    # innovation tests never flag: the solution separation does.
    f = simulate_flight(duration_s=400.0, seed=seed + 7, errors=NO_THERMAL)
    fault = np.clip(f.gnss.t - 100.0, 0.0, None) * 0.1
    lat, lon, alt = ned_to_geodetic(fault, 0.0 * fault, 0.0 * fault, f.gnss.lat, f.gnss.lon, f.gnss.alt)
    g = dataclasses.replace(f.gnss, lat=lat, lon=lon, alt=alt)
    r = ins.run(dataclasses.replace(f, gnss=g), matched_config(hal_m=40.0, val_m=50.0, decimation=5))
    d = ev.ned_difference(r.lat, r.lon, r.alt, f.truth, r.t)  # type: ignore[arg-type]
    err = np.hypot(d[:, 0], d[:, 1])
    flagged = r.fix_t[np.isin(r.fix_status, (1, 2, 5, 6))]
    first = float(flagged[0]) if flagged.size else None
    violations, _ = unannounced_rows(r, f.truth)  # type: ignore[arg-type]
    trace = IntegrityTrace(r.t, err, r.hpl, 100.0, 0.1, 40.0, first, r.alerts, violations)
    say("ins: GNSS ramp sweep")
    long = simulate_flight(duration_s=300.0 if quick else 600.0, seed=seed + 5, errors=NO_THERMAL)
    ramps = ramp_sweep(long, 60.0, (0.05, 1.0) if quick else RAMP_RATES)
    # Classic vs TCZUPT on a warming IMU (the lsm6dsm thermal curve, +20 °C).
    temps = np.linspace(15.0, 45.0, 61)
    model = PolynomialBiasModel(order=3).fit(temps, thermal_bias("lsm6dsm", temps))
    cmp: dict[str, list[float]] = {"classic": [], "tczupt": []}
    bias_err: dict[str, list[float]] = {"classic": [], "tczupt": []}
    for k in range(3 if quick else 10):
        f = simulate_flight(
            duration_s=300.0, seed=seed * 7 + 900 + k, errors=FlightErrors(temp_rise_c=20.0, temp_tau_s=200.0)
        )
        for mode in cmp:
            cfg = ins.InsConfig(
                mode=mode,  # type: ignore[arg-type]
                model=model if mode == "tczupt" else None,
                decimation=10,
                gnss_outages=((240.0, 30.0),),
            )
            rr = ins.run(f, cfg)
            cmp[mode].append(ev.outage_end_error(rr, f, 240.0, 30.0, against="truth").horizontal_error_m)
            i = int(np.searchsorted(rr.t, 239.0))
            j = int(np.searchsorted(f.truth.t, rr.t[i]))  # type: ignore[union-attr]
            true_bg = f.truth.extra["gyro_bias"][j]  # type: ignore[union-attr]
            bias_err[mode].append(float(np.degrees(np.linalg.norm(rr.gyro_bias[i] - true_bg)) * 3600.0))
    return InsExperiment(
        runs=runs,
        outages=[_outage_stats(dd, ends[dd]) for dd in DURATIONS],
        nees_mean=nees_mean,
        nees_bounds=(lo, hi),
        integrity=trace,
        classic_vs_tczupt={
            "classic_median_30s_m": float(np.median(cmp["classic"])),
            "tczupt_median_30s_m": float(np.median(cmp["tczupt"])),
            "classic_gyro_bias_error_deg_h": float(np.median(bias_err["classic"])),
            "tczupt_gyro_bias_error_deg_h": float(np.median(bias_err["tczupt"])),
            "flights": float(len(cmp["classic"])),
        },
        ramps=ramps,
        fault_free={
            **ff,
            "median_hpl_m": float(np.median([p[0] for p in pls])),
            "median_vpl_m": float(np.median([p[1] for p in pls])),
        },
        accuracy={
            "horizontal_rms_m": float(np.median([c.horizontal_rms_m for c in acc])),
            "vertical_rms_m": float(np.median([c.vertical_rms_m for c in acc])),
            "velocity_rms_m_s": float(np.median([c.velocity_rms_m_s or 0.0 for c in acc])),
            "roll_pitch_rms_deg": float(np.median([c.roll_pitch_rms_deg or 0.0 for c in acc])),
            "yaw_rms_deg": float(np.median([c.yaw_rms_deg or 0.0 for c in acc])),
        },
    )
