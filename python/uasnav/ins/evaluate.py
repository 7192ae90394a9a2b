"""Compare a GNSS/INS solution with a reference (the autopilot's estimate or a simulation's truth),
check its consistency (NEES), and run GNSS-outage experiments.

Differences are estimate − reference, position in metres NED (north/east from the latitude and
longitude differences with the WGS-84 radii of curvature at the reference point,
:func:`uasnav.geo.frames.radii_of_curvature`; heights subtracted in the one datum both carry).
Statistics: RMS and the 95th percentile of the magnitude. Yaw differences are wrapped to ±180°.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy import stats

from uasnav.errors import InputError
from uasnav.geo.frames import radii_of_curvature
from uasnav.ins.core import InsConfig, InsResult, run
from uasnav.io.navdata import Flight, Trajectory
from uasnav.limits import check_work

FloatArray = NDArray[np.float64]


def ned_difference(
    lat: FloatArray, lon: FloatArray, alt: FloatArray, ref: Trajectory, t: FloatArray
) -> FloatArray:
    """(n, 3) NED difference (m) of positions (deg, deg, m) at times ``t`` from ``ref``
    interpolated to ``t``."""
    rlat = np.interp(t, ref.t, ref.lat)
    rlon = np.interp(t, ref.t, ref.lon)
    ralt = np.interp(t, ref.t, ref.alt)
    phi = np.radians(rlat)
    rn, re = radii_of_curvature(phi, degrees=False)
    dn = np.radians(lat - rlat) * (rn + ralt)
    de = np.radians(lon - rlon) * (re + ralt) * np.cos(phi)
    return np.column_stack([dn, de, -(alt - ralt)])


@dataclass(frozen=True)
class Comparison:
    """Differences of an INS solution from a reference over their common time span.

    Attributes are RMS and 95th percentiles (p95) of the magnitudes: horizontal and vertical
    position (m), velocity (m/s, 3-D), roll/pitch (deg, RMS per axis and of both) and yaw
    (deg; p95 of roll/pitch over both axes' magnitudes). ``vertical_bias_m`` is the mean
    vertical difference; ``n`` the number of compared samples; ``reference`` its name;
    ``datum`` the height datum both heights were compared in (:class:`~uasnav.geo.datum.HeightDatum`
    value: the readers give the autopilot's estimate in the datum of the GNSS fixes the filter
    flew on).
    """

    horizontal_rms_m: float
    horizontal_p95_m: float
    vertical_rms_m: float
    vertical_p95_m: float
    vertical_bias_m: float
    velocity_rms_m_s: float | None
    velocity_p95_m_s: float | None
    roll_rms_deg: float | None
    pitch_rms_deg: float | None
    roll_pitch_rms_deg: float | None
    yaw_rms_deg: float | None
    n: int
    reference: str
    t_span: tuple[float, float] = (0.0, 0.0)
    roll_pitch_p95_deg: float | None = None
    yaw_p95_deg: float | None = None
    datum: str = "ellipsoid"

    def as_dict(self) -> dict[str, Any]:
        """Plain dict for JSON."""
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def _rms(x: FloatArray) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def compare(result: InsResult, ref: Trajectory, *, t_range: tuple[float, float] | None = None) -> Comparison:
    """Compare ``result`` with ``ref`` at the result's rows inside the common span (and
    ``t_range`` if given).

    Raises
    ------
    InputError
        No overlap between the two.
    """
    lo, hi = max(result.t[0], ref.t[0]), min(result.t[-1], ref.t[-1])
    if t_range is not None:
        lo, hi = max(lo, t_range[0]), min(hi, t_range[1])
    k = (result.t >= lo) & (result.t <= hi)
    if k.sum() < 2:
        raise InputError(f"compare: the solution and {ref.name!r} do not overlap in time")
    t = result.t[k]
    d = ned_difference(result.lat[k], result.lon[k], result.alt[k], ref, t)
    hz = np.hypot(d[:, 0], d[:, 1])
    vt = np.abs(d[:, 2])
    vel_rms = vel_p95 = None
    if ref.vel is not None:
        rv = np.column_stack([np.interp(t, ref.t, ref.vel[:, i]) for i in range(3)])
        dv = np.linalg.norm(result.vel[k] - rv, axis=1)
        vel_rms, vel_p95 = _rms(dv), float(np.percentile(dv, 95))
    roll = pitch = rp = yaw = rp95 = yaw95 = None
    if ref.euler_deg is not None:
        # Interpolate angles through their unit vectors (yaw wraps).
        ang = np.radians(ref.euler_deg)
        re_ = np.column_stack(
            [
                np.degrees(
                    np.arctan2(np.interp(t, ref.t, np.sin(ang[:, i])), np.interp(t, ref.t, np.cos(ang[:, i])))
                )
                for i in range(3)
            ]
        )
        de = (result.euler_deg[k] - re_ + 180.0) % 360.0 - 180.0
        roll, pitch = _rms(de[:, 0]), _rms(de[:, 1])
        rp = _rms(de[:, :2])
        yaw = _rms(de[:, 2])
        rp95 = float(np.percentile(np.abs(de[:, :2]), 95))
        yaw95 = float(np.percentile(np.abs(de[:, 2]), 95))
    return Comparison(
        horizontal_rms_m=_rms(hz),
        horizontal_p95_m=float(np.percentile(hz, 95)),
        vertical_rms_m=_rms(vt),
        vertical_p95_m=float(np.percentile(vt, 95)),
        vertical_bias_m=float(np.mean(d[:, 2])),
        velocity_rms_m_s=vel_rms,
        velocity_p95_m_s=vel_p95,
        roll_rms_deg=roll,
        pitch_rms_deg=pitch,
        roll_pitch_rms_deg=rp,
        yaw_rms_deg=yaw,
        n=int(k.sum()),
        reference=ref.name,
        t_span=(float(lo), float(hi)),
        roll_pitch_p95_deg=rp95,
        yaw_p95_deg=yaw95,
        datum=str(ref.alt_datum),
    )


def attitude_error(result: InsResult, truth: Trajectory) -> FloatArray:
    """(n, 3) attitude error ψ (rad, NED) with ``Ĉ = (I + [ψ×])·C`` at the result's rows;
    ``truth.extra["quat"]`` (scalar first) is required."""
    from scipy.spatial.transform import Rotation

    q = truth.extra.get("quat")
    if q is None:
        raise InputError(f"attitude_error: {truth.name!r} has no extra['quat']")
    idx = np.clip(np.searchsorted(truth.t, result.t), 0, truth.t.size - 1)
    qt = q[idx]
    est = Rotation.from_quat(np.column_stack([result.quat[:, 1:], result.quat[:, :1]]))
    tru = Rotation.from_quat(np.column_stack([qt[:, 1:], qt[:, :1]]))
    # Ĉ·Cᵀ = exp([ψ×]): the rotation vector of est·tru⁻¹ (NED side).
    return (est * tru.inv()).as_rotvec()


def nees(result: InsResult, truth: Trajectory) -> dict[str, FloatArray]:
    """Per-row normalised estimation error squared of position, velocity and attitude (each χ²
    with 3 degrees of freedom for a consistent filter), with the diagonal covariance the filter
    reports (its cross terms are not stored; per-axis NEES sums are compared with χ²₃)."""
    d = ned_difference(result.lat, result.lon, result.alt, truth, result.t)
    out = {"position": np.sum((d / result.std[:, 0:3]) ** 2, axis=1)}
    if truth.vel is not None:
        rv = np.column_stack([np.interp(result.t, truth.t, truth.vel[:, i]) for i in range(3)])
        out["velocity"] = np.sum(((result.vel - rv) / result.std[:, 3:6]) ** 2, axis=1)
    if "quat" in truth.extra:
        out["attitude"] = np.sum((attitude_error(result, truth) / result.std[:, 6:9]) ** 2, axis=1)
    return out


def chi2_bounds(dof: int, runs: int, confidence: float = 0.95) -> tuple[float, float]:
    """Two-sided bounds of the mean NEES over ``runs`` independent runs (Bar-Shalom §5.4):
    ``χ²_{dof·runs}`` quantiles divided by ``runs``."""
    a = (1.0 - confidence) / 2.0
    n = dof * runs
    return float(stats.chi2.ppf(a, n) / runs), float(stats.chi2.ppf(1.0 - a, n) / runs)


@dataclass(frozen=True)
class Outage:
    """One GNSS outage: ``start`` (s), ``duration`` (s), the horizontal/vertical error at its end
    against the unmasked GNSS fix (or truth), the filter's horizontal 1σ and 3σ there."""

    start: float
    duration: float
    horizontal_error_m: float
    vertical_error_m: float
    horizontal_std_m: float
    hpl_m: float
    against: str
    imu: str = ""

    @property
    def inside_3sigma(self) -> bool:
        """Horizontal error inside 3σ of the major horizontal axis (√(σ_N² + σ_E²) bound)."""
        return self.horizontal_error_m <= 3.0 * self.horizontal_std_m


@dataclass
class OutageTable:
    """Outages of one experiment, with summary statistics per duration."""

    outages: list[Outage] = field(default_factory=list)

    def by_duration(self) -> dict[float, list[Outage]]:
        """Outages grouped by duration."""
        out: dict[float, list[Outage]] = {}
        for o in self.outages:
            out.setdefault(o.duration, []).append(o)
        return out

    def summary(self) -> dict[str, dict[str, float]]:
        """Per duration: count, median/p95/max horizontal error (m), median vertical error, and
        the fraction inside 3σ."""
        s: dict[str, dict[str, float]] = {}
        for d, items in sorted(self.by_duration().items()):
            h = np.array([o.horizontal_error_m for o in items])
            v = np.array([o.vertical_error_m for o in items])
            s[f"{d:g}"] = {
                "count": len(items),
                "median_horizontal_m": float(np.median(h)),
                "p95_horizontal_m": float(np.percentile(h, 95)),
                "max_horizontal_m": float(h.max()),
                "median_vertical_m": float(np.median(v)),
                "fraction_inside_3sigma": float(np.mean([o.inside_3sigma for o in items])),
            }
        return s


def outage_end_error(
    result: InsResult, flight: Flight, start: float, duration: float, *, against: str = "gnss", imu: str = ""
) -> Outage:
    """The error at the end of an outage ``[start, start + duration)`` in ``result`` against the
    first unmasked GNSS fix at or after its end (``against="gnss"``) or the truth."""
    t_end = start + duration
    i = int(np.searchsorted(result.t, t_end))
    i = min(i, result.t.size - 1)
    # The last row inside the outage: the solution before the first fix is used.
    i = max(0, i - 1)
    if against == "truth":
        if flight.truth is None:
            raise InputError("outage_end_error: the flight has no truth")
        d = ned_difference(
            result.lat[i : i + 1],
            result.lon[i : i + 1],
            result.alt[i : i + 1],
            flight.truth,
            result.t[i : i + 1],
        )[0]
    else:
        g = flight.gnss
        j = int(np.searchsorted(g.t, t_end - 1e-9))
        if j >= g.n:
            raise InputError(f"outage at {start:g}+{duration:g} s: no GNSS fix after it")
        ref = Trajectory(
            np.array([g.t[j] - 1.0, g.t[j] + 1.0]),
            np.repeat(g.lat[j], 2),
            np.repeat(g.lon[j], 2),
            np.repeat(g.alt[j], 2),
            name="GNSS",
        )
        # Move the solution to the fix time with its own velocity.
        dtf = g.t[j] - result.t[i]
        lat, lon, alt = result.lat[i : i + 1], result.lon[i : i + 1], result.alt[i : i + 1]
        d = ned_difference(lat, lon, alt, ref, np.array([g.t[j]]))[0]
        d = d + result.vel[i] * dtf
    return Outage(
        start=float(start),
        duration=float(duration),
        horizontal_error_m=float(math.hypot(d[0], d[1])),
        vertical_error_m=float(abs(d[2])),
        horizontal_std_m=float(math.hypot(result.std[i, 0], result.std[i, 1])),
        hpl_m=float(result.hpl[i]),
        against=against,
        imu=imu,
    )


def outage_starts(
    interval: tuple[float, float], duration: float, count: int, lead_s: float = 30.0
) -> list[float]:
    """``count`` start times spread evenly over ``interval`` so that each outage ends inside it
    and the filter has ``lead_s`` of GNSS before the first."""
    lo, hi = interval[0] + lead_s, interval[1] - duration - 1.0
    if hi <= lo:
        return []
    return [float(x) for x in np.linspace(lo, hi, count)]


#: Elementary operations of one filter step (15-state error-state predict and update).
OPS_PER_FILTER_STEP = 1e4


def outage_experiment(
    flight: Flight,
    durations: Sequence[float] = (10.0, 30.0, 60.0),
    *,
    config: InsConfig | None = None,
    per_duration: int = 5,
    interval: tuple[float, float] | None = None,
    against: str = "gnss",
    imu_name: str = "",
    progress: Callable[[int, int], None] | None = None,
) -> OutageTable:
    """Mask GNSS for each duration at ``per_duration`` start times spread over ``interval``
    (default the airborne part) — one filter run per outage — and tabulate the end errors."""
    cfg = config or InsConfig()
    span = interval or flight.airborne or (float(flight.gnss.t[0]), float(flight.gnss.t[-1]))
    table = OutageTable()
    # estimate first: one whole filter run per outage (≈ 10⁴ operations per IMU sample)
    n_durations = len(durations)
    check_work(
        float(n_durations) * per_duration * len(flight.imu.t) * OPS_PER_FILTER_STEP,
        f"outage sweep of {n_durations} duration(s) × {per_duration} start(s), one filter run each",
        option="the number of outage durations (--outage-sweep)",
    )
    jobs = [(d, s) for d in durations for s in outage_starts(span, d, per_duration)]
    for k, (d, s) in enumerate(jobs):
        res = run(flight, cfg.replace(gnss_outages=((s, d),)))
        table.outages.append(outage_end_error(res, flight, s, d, against=against, imu=imu_name))
        if progress is not None:
            progress(k + 1, len(jobs))
    return table
