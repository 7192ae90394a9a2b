"""Run the GNSS/INS filter over a :class:`~uasnav.io.flight.Flight` (one FFI call, GIL released).

The filter (``nav_core::ins``) is a loosely coupled 15-state error-state Kalman filter on the
same strapdown mechanisation and error-state kernel as the ZUPT filter: WGS-84 latitude,
longitude, height (f64), NED velocity, Earth rate and transport rate; GNSS position and
velocity updates with their reported accuracies and the lever arm, barometric height, ZUPT/ZARU
when static (on the ground), magnetometer or GNSS-course heading at start-up; χ² fault
detection and exclusion of whole GNSS fixes (a loosely coupled filter cannot exclude single
satellites), protection levels and HAL/VAL alerts (thesis §4.1.4).

Integrity parameters are probabilities here and turned into the filter's thresholds with
scipy: the per-fix and window tests use ``gate = χ²₆⁻¹(1 − p_fa)``; the non-centrality ``λ``
solves ``F_ncχ²₆(gate; λ) = p_md`` (the largest fault missed with probability ``p_md``); the
fault-free multipliers are ``k_H = √(−2 ln p_ir)`` (Rayleigh tail on the major-axis σ, exact
for a circular error, conservative otherwise) and ``k_V = Φ⁻¹(1 − p_ir/2)``.
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import TYPE_CHECKING, Any, ClassVar, Literal

import numpy as np
from numpy.typing import NDArray

from uasnav import _core
from uasnav.attitude import quat_to_euler
from uasnav.errors import InputError
from uasnav.imu import ImuLog
from uasnav.ins.magnetic import resolve_declination
from uasnav.io import track
from uasnav.io.flight import Flight
from uasnav.stationary import MAX_WINDOW_SAMPLES, detect_static
from uasnav.zupt import MODE_LABELS, Mode

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from uasnav.thermal.base import BiasModel

FloatArray = NDArray[np.float64]

#: Below this IMU rate (Hz) strapdown integration is refused: a turn of 30 °/s would rotate
#: the body by more than 6° between samples.
MIN_IMU_RATE_HZ = 5.0
#: Fix status codes of the Rust filter.
FIX_STATUS = {
    0: "used",
    1: "excluded",
    2: "excluded_window",
    3: "masked",
    4: "unused",
    5: "reset",
    6: "separation_alert",
}


@lru_cache(maxsize=32)
def integrity_thresholds(p_fa: float, p_md: float, p_ir: float) -> dict[str, float]:
    """χ² gate, non-centrality λ and fault-free multipliers (see the module docs).

    Examples
    --------
    >>> th = integrity_thresholds(1e-5, 1e-3, 1e-7)
    >>> round(th["gate_chi2"], 2), round(th["k_vertical"], 2)
    (33.11, 5.33)
    """
    from scipy import optimize, stats

    for name, p in (("p_fa", p_fa), ("p_md", p_md), ("p_ir", p_ir)):
        if not (0.0 < p < 0.5):
            raise InputError(f"{name}: expected a probability in (0, 0.5), got {p!r}")
    gate = float(stats.chi2.isf(p_fa, 6))
    lam = float(optimize.brentq(lambda lam: stats.ncx2.cdf(gate, 6, lam) - p_md, 1e-6, 1e4, xtol=1e-10))
    return {
        "gate_chi2": gate,
        "lambda_undetected": lam,
        "k_horizontal": math.sqrt(-2.0 * math.log(p_ir)),
        "k_vertical": float(stats.norm.isf(p_ir / 2.0)),
        # Solution separation (slow ramps): χ²₂ on the normalised N/E separation, Gaussian on D.
        "separation_k_h": math.sqrt(-2.0 * math.log(p_fa)),
        "separation_k_v": float(stats.norm.isf(p_fa / 2.0)),
    }


#: Process noise for logged IMU streams: a 50 Hz DataFlash ``IMU`` record (or a 10 Hz ROS
#: ``imu/data_raw``) is a snapshot of the filtered rate, not an integrated increment, so
#: integrating it leaves errors far above the sensor's noise (log171: gyro-only integration
#: drifts 5–15° in 15 s of flight against the autopilot's EKF). The filter is told so: σ_VRW
#: 0.5 m/s/√s, σ_ARW 0.02 rad/√s, bias random walks 1e-3 m/s²/√s and 1e-4 rad/s/√s, and an
#: initial accelerometer-bias σ of 0.5 m/s² (the logs' static |f| is 9.1–9.6 m/s²).
LOGGED_IMU_NOISE: dict[str, Any] = {
    "sigma_vrw_m_s_sqrt_s": 0.5,
    "sigma_arw_rad_sqrt_s": 0.02,
    "sigma_abi_m_s2": 1e-3,
    "sigma_gbi_rad_s": 1e-4,
    "extra": {"init_std_accel_bias_m_s2": 0.5},
}


#: σ (rad/s/√°C) of the classic filter's gyro-bias wander with die temperature, a random walk
#: *in temperature* (variance σ²·|ΔT|): an uncalibrated consumer MEMS gyro's bias moves
#: ≈ 1–3·10⁻⁴ rad/s per °C (0.006–0.017 °/s/°C; the ``lsm6dsm`` preset ≈ 2·10⁻⁴), so over the
#: 5–10 °C a die warms in flight the wander σ·√ΔT must reach k·ΔT: σ = 2·10⁻⁴·√10 ≈ 6·10⁻⁴.
#: Without it the classic filter's heading grew 9° beyond its 0.8° σ on simulated flights and
#: sound GNSS fixes were excluded at the corners (41 of 7 208 on 8 lap circuits).
GYRO_BIAS_THERMAL_WANDER = 6e-4


@dataclass(frozen=True)
class InsConfig:
    """Settings of :func:`run` (SI units in every name; keyword arguments stored unchanged).

    Attributes
    ----------
    mode : {"classic", "tczupt"}
        ``"classic"`` (also spelled ``"zupt"``): the gyro is calibrated with ``model`` (if
        given) and its bias is a random walk; ``"tczupt"``: raw gyro, the bias follows
        ``model``'s ∂b/∂T·dT/dt (eqs. 29–31).
    model : BiasModel or None
        Thermal gyro-bias model (a ``uasnav calibrate`` file); required for ``"tczupt"``.
    sigma_vrw_m_s_sqrt_s, sigma_arw_rad_sqrt_s, sigma_abi_m_s2, sigma_gbi_rad_s : float
        IMU process noise (velocity/angle random walk, bias instabilities as random-walk PSD).
        Defaults: a consumer MEMS IMU in flight, rotor vibration included (0.012 m/s/√s,
        2.5e-4 rad/√s ≈ 0.86 deg/√h; bias random walks 1e-4 m/s²/√s, 1e-5 rad/s/√s), which is
        what :func:`uasnav.sim.flight.simulate_flight` simulates.
    sigma_gbt_rad_s_sqrt_c : float
        Classic filter without a thermal model: gyro-bias random walk in die temperature
        (rad/s/√°C; :data:`GYRO_BIAS_THERMAL_WANDER`), used when the IMU log has a temperature;
        0 turns it off. Ignored with a model (the model compensates the thermal bias).
    lever_arm_m : tuple of 3 floats
        GNSS antenna relative to the IMU, body frame (m).
    gnss_outages : tuple of (start_s, duration_s)
        GNSS masked in these intervals (log time, s): the filter dead-reckons.
    p_fa, p_md, p_ir : float
        False-alarm and missed-detection probabilities of the χ² tests, and the fault-free
        integrity risk of the protection levels.
    hal_m, val_m : float or None
        Horizontal/vertical alert limits (m): an alert when a protection level exceeds them.
    window_fixes : int
        Fixes in the averaged-innovation test (1–32).
    reset_after_exclusions : int
        Consecutive excluded fixes after which the filter re-initialises on GNSS (0: never).
    static_updates : bool
        ZUPT/ZARU when the static detector fires and GNSS speed is below ``static_max_speed_m_s``
        (on the ground: hovering is not static, and the GLRT rejects its vibration).
    declination_deg : float or None
        Magnetic declination (degrees, east positive): the magnetometer heading aiding uses
        true heading = magnetic heading + declination. ``None`` (default): the log's own
        (ArduPilot ``COMPASS_DEC`` when auto-declination is off, PX4 ``EKF2_MAG_DECL``), else
        the World Magnetic Model at the first fix on the log's GPS date, else 0 — see
        :func:`uasnav.ins.magnetic.resolve_declination`; ``InsResult.summary`` reports the value
        and its source.
    decimation : int
        Keep one output row every ``decimation`` IMU samples.
    extra : dict
        Further nav-core fields by name (e.g. ``{"baro_std_m": 2.0}``).
    """

    mode: Mode = "classic"
    model: BiasModel | None = None
    sigma_vrw_m_s_sqrt_s: float = 0.012
    sigma_arw_rad_sqrt_s: float = 2.5e-4
    sigma_abi_m_s2: float = 1e-4
    sigma_gbi_rad_s: float = 1e-5
    sigma_gbt_rad_s_sqrt_c: float = GYRO_BIAS_THERMAL_WANDER
    lever_arm_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    gnss_outages: tuple[tuple[float, float], ...] = ()
    p_fa: float = 1e-5
    p_md: float = 1e-3
    p_ir: float = 1e-7
    hal_m: float | None = None
    val_m: float | None = None
    window_fixes: int = 10
    reset_after_exclusions: int = 50
    static_updates: bool = True
    static_max_speed_m_s: float = 0.3
    use_baro: bool = True
    use_mag: bool = True
    declination_deg: float | None = None
    decimation: int = 1
    discretisation: Literal["first_order", "second_order"] = "first_order"
    extra: dict[str, float] = field(default_factory=dict)

    def replace(self, **changes: Any) -> InsConfig:
        """A copy with some fields changed."""
        return replace(self, **changes)

    @classmethod
    def for_logged_imu(cls, **changes: Any) -> InsConfig:
        """The configuration for real logs whose IMU stream is a low-rate snapshot
        (:data:`LOGGED_IMU_NOISE`), with ``changes`` on top (``extra`` entries merged)."""
        base = dict(LOGGED_IMU_NOISE)
        extra = dict(base.pop("extra"))
        extra.update(changes.pop("extra", {}) or {})
        base.update(changes)
        return cls(**base, extra=extra)

    def filter_config(self, declination_rad: float) -> FilterConfig:
        """The Rust filter's configuration: noise, the integrity thresholds of ``p_fa``,
        ``p_md``, ``p_ir``, the lever arm and window, ``extra`` on top, and the magnetic
        declination (rad, east positive) resolved for the flight."""
        fields: dict[str, Any] = {
            "sigma_vrw_m_s_sqrt_s": self.sigma_vrw_m_s_sqrt_s,
            "sigma_arw_rad_sqrt_s": self.sigma_arw_rad_sqrt_s,
            "sigma_abi_m_s2": self.sigma_abi_m_s2,
            "sigma_gbi_rad_s": self.sigma_gbi_rad_s,
            # a thermal model compensates the bias: no thermal wander on top of it
            "sigma_gbt_rad_s_sqrt_c": 0.0 if self.model is not None else self.sigma_gbt_rad_s_sqrt_c,
        }
        fields.update(integrity_thresholds(self.p_fa, self.p_md, self.p_ir))
        for key, value in self.extra.items():
            if key not in FilterConfig.FLOAT_FIELDS:
                raise InputError(f"config: unknown key {key!r} (expected one of FilterConfig.FLOAT_FIELDS)")
            try:
                fields[key] = float(value)
            except (TypeError, ValueError):
                raise InputError(f"extra[{key!r}]: expected a float, got {value!r}") from None
        fields["declination_rad"] = declination_rad
        return FilterConfig(
            mode=self.mode,
            discretisation=self.discretisation,
            lever_arm_m=self.lever_arm_m,
            window_fixes=self.window_fixes,
            reset_after_exclusions=self.reset_after_exclusions,
            **fields,
        )


@dataclass(frozen=True)
class FilterConfig:
    """The configuration of the Rust filter (``nav_core::ins::InsConfig``) as it crosses into
    Rust: one typed object, each field named and in the units of its nav-core namesake (SI,
    units in the names; see the Rust docs). ``None`` keeps nav-core's default, so defaults live
    in nav-core alone. :meth:`InsConfig.filter_config` builds it; ``InsConfig.extra`` sets any
    float field by name.

    Attributes
    ----------
    mode : {"classic", "tczupt"}
        Gyro-bias model (see :class:`InsConfig`).
    discretisation : {"first_order", "second_order"}
        Transition-matrix discretisation.
    lever_arm_m : tuple of 3 floats or None
        GNSS antenna relative to the IMU, body frame (m).
    window_fixes, reset_after_exclusions : int or None
        Fixes in the averaged-innovation test; consecutive exclusions before a GNSS reset.
    sigma_vrw_m_s_sqrt_s, …, temp_slope_window_s : float or None
        The float fields (:attr:`FLOAT_FIELDS`): process noise, initial σ, measurement σ and
        cadences, declination, integrity thresholds, thermal slope window.
    """

    mode: Mode = "classic"
    discretisation: Literal["first_order", "second_order"] = "first_order"
    lever_arm_m: tuple[float, float, float] | None = None
    window_fixes: int | None = None
    reset_after_exclusions: int | None = None
    sigma_vrw_m_s_sqrt_s: float | None = None
    sigma_arw_rad_sqrt_s: float | None = None
    sigma_abi_m_s2: float | None = None
    sigma_gbi_rad_s: float | None = None
    sigma_gbt_rad_s_sqrt_c: float | None = None
    init_std_tilt_rad: float | None = None
    init_std_heading_rad: float | None = None
    init_std_accel_bias_m_s2: float | None = None
    init_std_gyro_bias_rad_s: float | None = None
    gnss_min_std_position_m: float | None = None
    gnss_min_std_velocity_m_s: float | None = None
    baro_std_m: float | None = None
    baro_offset_time_constant_s: float | None = None
    zupt_std_velocity_m_s: float | None = None
    zaru_std_rad_s: float | None = None
    zupt_interval_s: float | None = None
    mag_heading_std_rad: float | None = None
    heading_aiding_s: float | None = None
    mag_interval_s: float | None = None
    declination_rad: float | None = None
    course_min_speed_m_s: float | None = None
    gate_chi2: float | None = None
    lambda_undetected: float | None = None
    k_horizontal: float | None = None
    k_vertical: float | None = None
    separation_k_h: float | None = None
    separation_k_v: float | None = None
    temp_slope_window_s: float | None = None

    #: Names of the float fields (those ``InsConfig.extra`` may set).
    FLOAT_FIELDS: ClassVar[frozenset[str]]


FilterConfig.FLOAT_FIELDS = frozenset(
    f.name for f in dataclasses.fields(FilterConfig) if f.type == "float | None"
)


@dataclass
class InsResult:
    """Per-sample output of :func:`run` (rows every ``decimation`` IMU samples).

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time, s.
    lat, lon, alt : ndarray, shape (n,)
        Degrees, degrees, ellipsoidal height m.
    vel : ndarray, shape (n, 3)
        NED velocity, m/s.
    quat : ndarray, shape (n, 4)
        Attitude body → NED, scalar first.
    euler_deg : ndarray, shape (n, 3)
        Roll, pitch, yaw (3-2-1), degrees.
    gyro_bias, accel_bias : ndarray, shape (n, 3)
        rad/s, m/s² (body).
    std : ndarray, shape (n, 15)
        1σ of the error states (δr m NED, δv m/s, ψ rad, δb_a, δb_g).
    hpl, vpl : ndarray, shape (n,)
        Protection levels, m.
    gnss_used : ndarray of bool, shape (n,)
        A GNSS fix was used since the previous row.
    fix_t, fix_status, fix_nis : ndarray, shape (m,)
        Per GNSS fix: time (s), status code (see :data:`FIX_STATUS`), NIS.
    summary : dict
        Counts of updates, exclusions, alerts; the thresholds used.
    """

    t: FloatArray
    lat: FloatArray
    lon: FloatArray
    alt: FloatArray
    vel: FloatArray
    quat: FloatArray
    euler_deg: FloatArray
    gyro_bias: FloatArray
    accel_bias: FloatArray
    std: FloatArray
    hpl: FloatArray
    vpl: FloatArray
    gnss_used: NDArray[np.bool_]
    fix_t: FloatArray
    fix_status: NDArray[np.uint8]
    fix_nis: FloatArray
    hal_m: float | None = None
    val_m: float | None = None
    summary: dict[str, Any] = field(default_factory=dict)

    @property
    def excluded_fixes(self) -> list[dict[str, Any]]:
        """Every excluded GNSS fix: time (s), test, NIS."""
        out = []
        for i in np.flatnonzero((self.fix_status == 1) | (self.fix_status == 2) | (self.fix_status == 5)):
            out.append(
                {
                    "t": float(self.fix_t[i]),
                    "test": FIX_STATUS[int(self.fix_status[i])],
                    "nis": float(self.fix_nis[i]),
                }
            )
        return out

    @property
    def separation_alert(self) -> NDArray[np.bool_]:
        """Per row: the latest GNSS fix tested at or before it raised a solution-separation
        alert (a GNSS position fault such as a slow ramp is detected)."""
        tested = self.fix_status <= 2  # used, excluded or separation alert, in time order
        tested |= (self.fix_status == 5) | (self.fix_status == 6)
        ft, fs = self.fix_t[tested], self.fix_status[tested]
        i = np.searchsorted(ft, self.t, side="right") - 1
        return (i >= 0) & (fs[np.maximum(i, 0)] == 6)

    @property
    def alert(self) -> NDArray[np.bool_]:
        """Per row: a protection level exceeds its alert limit (HAL/VAL), or the
        solution-separation monitor is raising an alert (see :attr:`separation_alert`)."""
        a = self.separation_alert.copy()
        if self.hal_m is not None:
            a |= self.hpl > self.hal_m
        if self.val_m is not None:
            a |= self.vpl > self.val_m
        return a

    @property
    def alerts(self) -> list[dict[str, Any]]:
        """Every alert interval: start and end time (s), which limits, the largest PLs."""
        out: list[dict[str, Any]] = []
        a = self.alert
        if not a.any():
            return out
        edges = np.flatnonzero(np.diff(np.r_[0, a.astype(np.int8), 0]))
        for i0, i1 in zip(edges[::2], edges[1::2], strict=True):
            h = float(self.hpl[i0:i1].max())
            v = float(self.vpl[i0:i1].max())
            kinds = []
            if self.separation_alert[i0:i1].any():
                kinds.append("separation")
            if self.hal_m is not None and h > self.hal_m:
                kinds.append("HAL")
            if self.val_m is not None and v > self.val_m:
                kinds.append("VAL")
            out.append(
                {
                    "t_start": float(self.t[i0]),
                    "t_end": float(self.t[i1 - 1]),
                    "limits": kinds,
                    "max_hpl": h,
                    "max_vpl": v,
                }
            )
        return out

    def track_table(self) -> FloatArray:
        """The TRACK.csv rows (:func:`uasnav.io.track.track_table`)."""
        return track.track_table(self)

    def to_csv(self, path: str | os.PathLike[str]) -> None:
        """Write TRACK.csv (:func:`uasnav.io.track.write_track_csv`)."""
        track.write_track_csv(self, path)

    def to_geojson(self, max_points: int = 5000) -> dict[str, Any]:
        """The track as GeoJSON (:func:`uasnav.io.track.track_geojson`)."""
        return track.track_geojson(self, max_points)

    def to_kml(self, path: str | os.PathLike[str], max_points: int = 5000) -> None:
        """Write the track as KML (:func:`uasnav.io.track.write_track_kml`)."""
        track.write_track_kml(self, path, max_points)

    def write_geojson(self, path: str | os.PathLike[str]) -> None:
        """Write :meth:`to_geojson` (:func:`uasnav.io.track.write_track_geojson`)."""
        track.write_track_geojson(self, path)

    def plot(self, ax: Axes | None = None, *, reference: Any = None) -> Axes:
        """Plot the horizontal track (:func:`uasnav.io.track.plot_track`)."""
        return track.plot_track(self, ax, reference=reference)


#: Period (samples) after which the Rust detector recomputes its running window sums from its
#: buffer (``nav_core::zupt::DETECT_CAPACITY``, = :data:`uasnav.stationary.MAX_WINDOW_SAMPLES`).
#: A detector run started at a multiple of it gives bit-identical statistics to a run over the
#: whole log from its first recomputation on (see :func:`_detect_on_spans`).
_DETECT_RESUM = MAX_WINDOW_SAMPLES
#: Slow spans closer than this (IMU samples) are run through the detector as one span.
_SPAN_MERGE_SAMPLES = 4096


def _slow_ranges(flight: Flight, cfg: InsConfig) -> list[tuple[int, int]]:
    """IMU index ranges ``[a, b)`` whose nearest earlier GNSS fix (the first fix for samples
    before it) is slow: speed below ``static_max_speed_m_s + 3·s_acc``."""
    g, t = flight.gnss, flight.imu.t
    speed = np.linalg.norm(g.vel, axis=1)
    ok = speed < cfg.static_max_speed_m_s + 3.0 * g.s_acc
    edges = np.diff(np.concatenate([[0], ok.astype(np.int8), [0]]))
    ja, jb = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)  # fix runs [ja, jb)
    # Sample i belongs to fix j(i) = clip(#{fixes at or before t_i} − 1, 0, m − 1):
    # j(i) ≥ ja ⟺ t_i ≥ t[ja] (or ja = 0); j(i) < jb ⟺ t_i < t[jb] (or jb = m).
    a = np.where(ja == 0, 0, np.searchsorted(t, g.t[np.minimum(ja, g.n - 1)], side="left"))
    b = np.where(jb == g.n, t.size, np.searchsorted(t, g.t[np.minimum(jb, g.n - 1)], side="left"))
    return [(int(x), int(y)) for x, y in zip(a, b, strict=True) if y > x]


def _detect_on_spans(
    imu: ImuLog, spans: list[tuple[int, int]], **params: Any
) -> tuple[NDArray[np.bool_], NDArray[np.float64]]:
    """The detector's mask and statistic over ``imu`` exactly as ``detect_static(imu, **params)``
    gives them, but computed only at the samples of ``spans`` (``[a, b)`` index ranges; False
    and NaN elsewhere).

    Each span runs the detector over a slice that starts ``lag = (W − 1)/2`` samples before it,
    pulled back to a multiple of :data:`_DETECT_RESUM` at least that period before: the Rust
    detector's running sums are recomputed from its window buffer every ``_DETECT_RESUM``
    pushes, after which its state depends only on the last W samples, so from there on the
    slice's statistics are bit-identical to the whole log's (tested). The slice ends ``lag``
    samples after the span (centred windows), or at the log's end, whose edge handling is then
    the same as the whole log's.
    """
    n = imu.n
    w = int(params["window_samples"])
    lag = (w - 1) // 2
    mask = np.zeros(n, dtype=bool)
    stat = np.full(n, np.nan)
    for a, b in spans:
        p0 = min(max(a + lag, w - 1), n - 1)  # the first push whose statistic is needed
        s = max(0, (p0 - (_DETECT_RESUM - 1)) // _DETECT_RESUM * _DETECT_RESUM)
        e = max(min(n, b + lag), p0 + 1)
        det = detect_static(imu.slice(s, e), **params)
        mask[a:b] = det.mask[a - s : b - s]
        stat[a:b] = det.statistic[a - s : b - s]
    return mask, stat


def _merge_spans(spans: list[tuple[int, int]], gap: int) -> list[tuple[int, int]]:
    merged: list[tuple[int, int]] = []
    for a, b in spans:
        if merged and a - merged[-1][1] < gap:
            merged[-1] = (merged[-1][0], max(merged[-1][1], b))
        else:
            merged.append((a, b))
    return merged


def _static_mask(flight: Flight, cfg: InsConfig, rate: float | None = None) -> NDArray[np.bool_] | None:
    if not cfg.static_updates:
        return None
    imu = flight.imu
    rate = imu.sample_rate if rate is None else rate
    # The GLRT with the noise, gyro bias and |g| of the first two seconds — the levelling
    # window, which the filter assumes static anyway — instead of a noise-estimation pass over
    # the whole log (0.13 s per 10⁵ samples).
    k = min(imu.n, max(10, round(2.0 * rate)))
    a0, g0 = imu.accel[:k], imu.gyro[:k]
    w = max(3, round(0.2 * rate))
    if w > imu.n or w > MAX_WINDOW_SAMPLES:
        return None  # the detector cannot run (it would refuse the whole log)
    params: dict[str, Any] = {
        "window_samples": w,
        "sigma_a": max(float(np.mean(np.std(a0, axis=0))), 1e-3),
        "sigma_g": max(float(np.mean(np.std(g0, axis=0))), 1e-5),
        "gyro_bias": g0.mean(axis=0),
        "gravity": float(np.linalg.norm(a0.mean(axis=0))),
    }
    # A static sample needs the nearest earlier GNSS fix to be slow too (a detector alone can
    # fire in smooth cruise), so the detector runs only over the slow spans — a few percent of
    # a flight (≈ 8 % of `ins.run`'s time on a 10⁶-sample flight when run over everything).
    slow = _slow_ranges(flight, cfg)
    gate = np.zeros(imu.n, dtype=bool)
    for a, b in slow:
        gate[a:b] = True
    try:
        det, _ = _detect_on_spans(imu, _merge_spans(slow, _SPAN_MERGE_SAMPLES), **params)
    except InputError:
        return None
    return np.ascontiguousarray(det & gate)


def run(flight: Flight, config: InsConfig | None = None) -> InsResult:
    """Run the GNSS/INS filter over a whole flight.

    The IMU is cut to start at the first GNSS fix (the filter initialises its position and
    velocity there); GNSS fixes inside ``config.gnss_outages`` are masked.

    Parameters
    ----------
    flight : Flight
        IMU (gyro rad/s, accel m/s², optional temp °C), GNSS, optional baro and magnetometer.
    config : InsConfig, optional
        Filter settings (defaults: classic filter, consumer MEMS noise).

    Returns
    -------
    InsResult

    Raises
    ------
    InputError
        Bad input (no GNSS fix inside the IMU span, TCZUPT without a model or a temperature,
        non-monotonic time …), naming what.
    NumericalError
        The covariance stopped being positive definite.
    """
    cfg = InsConfig() if config is None else config
    if not isinstance(flight, Flight):
        raise InputError(f"flight: expected a uasnav.ins.Flight, got {type(flight).__name__}")
    if flight.imu is None or flight.gnss is None:
        missing = " and ".join(k for k in ("imu", "gnss") if getattr(flight, k) is None)
        raise InputError(f"flight: no {missing} to integrate (read the log's nav view)")
    if cfg.mode not in MODE_LABELS:
        raise InputError(f"mode: expected 'classic' (or 'zupt') or 'tczupt', got {cfg.mode!r}")
    if cfg.mode == "zupt":
        cfg = cfg.replace(mode="classic")
    g = flight.gnss
    imu = flight.imu
    t_start = max(float(g.t[0]), float(imu.t[0]))
    if t_start > imu.t[-1]:
        raise InputError(
            f"gnss: the first fix ({g.t[0]:.3f} s) is after the IMU's last sample ({imu.t[-1]:.3f} s)"
        )
    use = np.ones(g.n, dtype=bool)
    for start, dur in cfg.gnss_outages:
        if not (math.isfinite(start) and math.isfinite(dur) and dur > 0):
            raise InputError(f"gnss_outages: expected (start_s, duration_s > 0), got ({start!r}, {dur!r})")
        use &= ~((g.t >= start) & (g.t < start + dur))
    # Start at the first usable fix.
    usable_t = g.t[use]
    if usable_t.size == 0:
        raise InputError("gnss: every fix is masked by the outages")
    t_start = max(t_start, float(usable_t[0]))
    if t_start > imu.t[0]:
        imu = imu.between(t_start, float(imu.t[-1]))
        flight = flight.with_imu(imu, flight.meta.get("imu"))
    rate = imu.sample_rate
    if rate < MIN_IMU_RATE_HZ:
        raise InputError(
            f"IMU rate {rate:.2f} Hz is too low for strapdown navigation (need >= {MIN_IMU_RATE_HZ:g} Hz; "
            "a telemetry log's IMU stream is often decimated: use the on-board log)"
        )
    temp = imu.temp
    gyro = imu.gyro
    dbias = None
    model = cfg.model
    if cfg.mode == "tczupt":
        if model is None:
            raise InputError("mode 'tczupt' needs a thermal model (model=…, a `uasnav calibrate` file)")
        if temp is None:
            raise InputError("mode 'tczupt' needs the IMU die temperature (the log has no temp)")
        dbias = np.ascontiguousarray(np.asarray(model.derivative(temp), dtype=np.float64))
        if dbias.shape != (imu.n, 3) or not np.isfinite(dbias).all():
            raise InputError(f"model.derivative(temp): expected finite shape ({imu.n}, 3), got {dbias.shape}")
        gyro0 = np.asarray(model.predict(temp[:1]), dtype=np.float64).reshape(3)
    elif model is not None:
        if temp is None:
            raise InputError("a thermal model needs the IMU die temperature (the log has no temp)")
        gyro = gyro - np.asarray(model.predict(temp), dtype=np.float64)
        gyro0 = np.zeros(3)
    else:
        gyro0 = np.zeros(3)
    stationary = _static_mask(flight, cfg, rate)
    filter_cfg = cfg.filter_config(declination_rad=0.0)  # checks `extra` before any look-up
    baro = flight.baro if cfg.use_baro else None
    mag = flight.mag if cfg.use_mag else None
    if "declination_rad" in cfg.extra:  # an explicit nav-core key wins
        declination_deg, declination_source = (
            math.degrees(float(cfg.extra["declination_rad"])),
            "extra['declination_rad']",
        )
    elif mag is None and cfg.declination_deg is None:
        # only the magnetometer's heading aiding uses it: nothing to look up (nor to fail on)
        declination_deg, declination_source = 0.0, "not used (no magnetometer aiding)"
    else:
        declination_deg, declination_source = resolve_declination(flight, cfg.declination_deg)
    filter_cfg = replace(filter_cfg, declination_rad=math.radians(declination_deg))
    llh = np.ascontiguousarray(np.column_stack([np.radians(g.lat), np.radians(g.lon), g.alt]))
    acc = np.ascontiguousarray(np.column_stack([g.h_acc, g.v_acc, g.s_acc]))
    c = np.ascontiguousarray
    out = _core.ins_run(
        c(imu.t),
        c(gyro),
        c(imu.accel),
        c(g.t),
        llh,
        c(g.vel),
        acc,
        gnss_use=use,
        baro_t=None if baro is None else c(baro.t),
        baro_h=None if baro is None else c(baro.alt),
        mag_t=None if mag is None else c(mag.t),
        mag=None if mag is None else c(mag.field),
        temp=c(temp)
        if temp is not None and (cfg.mode == "tczupt" or (filter_cfg.sigma_gbt_rad_s_sqrt_c or 0.0) > 0)
        else None,
        dbias_dtemp=dbias,
        stationary=stationary,
        levelling_samples=max(1, round(min(2.0, imu.duration / 4) * rate)),
        gyro_bias0=list(gyro0),
        config=filter_cfg,
        decimation=cfg.decimation,
    )
    t = imu.t[:: cfg.decimation]
    quat = out["attitude"]
    euler = np.degrees(quat_to_euler(quat))
    status = out["fix_status"]
    res = InsResult(
        t=t,
        lat=np.degrees(out["llh"][:, 0]),
        lon=np.degrees(out["llh"][:, 1]),
        alt=out["llh"][:, 2].copy(),
        vel=out["vel"],
        quat=quat,
        euler_deg=euler,
        gyro_bias=out["gyro_bias"],
        accel_bias=out["accel_bias"],
        std=np.sqrt(np.maximum(out["cov_diag"], 0.0)),
        hpl=out["protection"][:, 0].copy(),
        vpl=out["protection"][:, 1].copy(),
        gnss_used=out["gnss_used"],
        fix_t=g.t,
        fix_status=status,
        fix_nis=out["fix_nis"],
        hal_m=cfg.hal_m,
        val_m=cfg.val_m,
    )
    res.summary = {
        "mode": cfg.mode,
        "imu_rate_hz": rate,
        "fixes_used": int(out["fixes_used"]),
        "fixes_excluded": int(out["fixes_excluded"]),
        "fixes_masked": int((status == 3).sum()),
        "static_updates": int(out["static_updates"]),
        "baro_updates": int(out["baro_updates"]),
        "mag_updates": int(out["mag_updates"]),
        "declination_deg": declination_deg,
        "declination_source": declination_source,
        "course_reset": bool(out["course_reset"]),
        "imu_gaps": int(out["imu_gaps"]),
        "gnss_resets": int(out["gnss_resets"]),
        "separation_alerts": int(out["separation_alerts"]),
        "alerts": len(res.alerts),
        "thresholds": integrity_thresholds(cfg.p_fa, cfg.p_md, cfg.p_ir),
    }
    return res
