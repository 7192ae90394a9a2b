"""The 15-state ZUPT filter and the thermally compensated TCZUPT filter (thesis §4.2.2.2,
§4.2.3.2; evaluation §4.2.6.2).

:func:`run` hands a whole :class:`~uasnav.imu.ImuLog` to the Rust filter in one call and
returns a :class:`ZuptResult` with the decimated histories of the gyro and accelerometer
bias estimates, the attitude and the covariance diagonal, plus metrics and plotting helpers.

Modes
-----
``"classic"`` (also spelled ``"zupt"``)
    The thesis' standard ZUPT (Figure 24): the gyro data must be thermally calibrated. With ``model``
    the model's bias ``model.predict(temp)`` is subtracted first; without it the gyro data is
    taken as already calibrated. The estimated bias is the *residual* bias after calibration.
``"tczupt"``
    TCZUPT (Figure 26, eqs. 29–31): raw gyro data; the bias estimate is propagated with
    ``(∂b/∂T)·(dT/dt)·Ts``, ``∂b/∂T = model.derivative(temp)`` and ``dT/dt`` the sliding-window
    least-squares slope of ``log.temp``. The estimated bias is the *total* bias.

``"classic"`` is the name the whole package uses for the first mode (the GNSS/INS filter's
:class:`uasnav.ins.InsConfig` too): what sets it apart is its bias model, not the zero-velocity
updates, which TCZUPT applies as well. ``"zupt"`` is accepted everywhere as the thesis' name.

Both estimate the bias relative to the true body rate, Earth rate included: the filter's
mechanisation compensates the Earth rate itself, so for a static unit the estimate converges
to ``mean(gyro) − C_nᵇ·ω_ie``.

Evaluation helpers reproduce the thesis' §4.2.6.2: the 30 s moving-average reference
(:func:`moving_average_reference`, Table 9), per-axis RMS error (Table 10), convergence time
to 1e-5 rad/s (Table 11) and the statistics over five consecutive 5-minute segments
(Tables 12–13).
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav import _core
from uasnav.earth import OMEGA_IE
from uasnav.errors import InputError
from uasnav.imu import ImuLog, require_log
from uasnav.noise import FilterNoise
from uasnav.stationary import MAX_WINDOW_SAMPLES, StaticIntervals, detect_static
from uasnav.units import STANDARD_GRAVITY

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from uasnav.thermal.base import BiasModel

FloatArray = NDArray[np.float64]
Mode = Literal["classic", "zupt", "tczupt"]
#: The figure labels of the modes (the thesis' names of the filters).
MODE_LABELS = {"classic": "ZUPT", "zupt": "ZUPT", "tczupt": "TCZUPT"}

#: Convergence threshold of the thesis' Table 11 (rad/s).
CONVERGENCE_THRESHOLD = 1e-5
#: Moving-average window of the thesis' reference (s), Table 9.
REFERENCE_WINDOW_S = 30.0
#: 15 deg/h (the Earth rate) in rad/s: the thesis' residual initial bias scenario.
RESIDUAL_BIAS_15DEG_H = 15.0 * np.pi / 180.0 / 3600.0

#: Standard-ZUPT noise of the thesis, Tables 3–4 (CRS05-02 gyros, MS8010 accelerometers).
THESIS_ZUPT_NOISE = FilterNoise.from_datasheet(
    arw="3.18 deg/√h", gbi="1.5e-4 deg/s", vrw="0.05 m/s/√h", abi="2 m/s/h"
)
#: TCZUPT noise of the thesis, Tables 5–6 (σ'_GBI for raw gyro data).
THESIS_TCZUPT_NOISE = FilterNoise.from_datasheet(
    arw="3.18 deg/√h", gbi="5e-4 deg/s", vrw="0.05 m/s/√h", abi="2 m/s/h"
)

#: Columns of :meth:`ZuptResult.to_csv` (the CLI's EST.csv; the first seven are a contract).
CSV_COLUMNS = (
    "t", "bgx", "bgy", "bgz", "bax", "bay", "baz", "q0", "q1", "q2", "q3",
    "sbgx", "sbgy", "sbgz", "sbax", "sbay", "sbaz",
)  # fmt: skip
STATE_NAMES = (
    "rN", "rE", "rD", "vN", "vE", "vD", "psiN", "psiE", "psiD",
    "bax", "bay", "baz", "bgx", "bgy", "bgz",
)  # fmt: skip


@dataclass(frozen=True)
class ZuptConfig:
    """Filter configuration; every field names its unit.

    Attributes
    ----------
    noise : FilterNoise or None
        Q of eqs. (22)–(25). ``None``: the thesis' Tables 3–4 for ZUPT, Tables 5–6 (σ'_GBI =
        5e-4 deg/s) for TCZUPT. Note the thesis uses σ_GBI (rad/s) directly as the PSD of the
        bias random walk; so do we.
    meas_std_position_m, meas_std_velocity_m_s, meas_std_attitude_rad : float
        R of the frozen-position, zero-velocity and frozen-attitude measurements.
    update_interval_s : float
        ZUPT cadence (s); the thesis applies one update per second.
    init_std_* : float
        Initial σ of each state group (m, m/s, rad, m/s², rad/s).
    latitude_deg, height_m : float
        Frozen position (WGS-84 geodetic latitude, ellipsoidal height).
    levelling_s : float
        Initial zeroing window for coarse levelling (thesis: 60 s).
    zeroing : bool
        Start the gyro-bias estimate from the mean gyro output over the zeroing window minus
        the Earth rate in the levelled body frame (the thesis' "initial zeroing procedure").
        The default ``init_std_gyro_bias_rad_s`` (2e-4 rad/s) assumes it; without zeroing
        set it to the turn-on bias spread.
    heading_rad : float or None
        Initial true heading. ``None`` with ``declination_rad`` set: magnetic heading (eq. 3)
        from ``log.mag``; both ``None``: heading 0 (it does not affect the bias estimates).
    declination_rad : float or None
        Magnetic declination (east positive) for the magnetic heading.
    gyro_bias0_rad_s, accel_bias0_m_s2 : tuple of 3 floats
        Initial bias estimates (body axes).
    residual_gyro_bias_rad_s : float
        Added to every axis of the initial gyro-bias estimate: the thesis' "residual bias
        after rough initial alignment" scenario uses 15 deg/h (:data:`RESIDUAL_BIAS_15DEG_H`).
    discretisation : {"first_order", "second_order"}
        Φ = I + F·Ts (eq. 16) or with the (F·Ts)²/2 term.
    temp_slope_window_s : float
        Window of the least-squares dT/dt slope (TCZUPT).
    derivative : {"analytic", "network"}
        Where TCZUPT takes ∂b/∂T from: ``model.derivative(temp)`` (the analytic derivative of
        the bias model), or ``model.derivative(temp, method="network")`` (a network trained on
        the derivative of the calibration data, thesis eq. 37; needs a
        :class:`~uasnav.thermal.NeuralBiasModel` fitted with ``derivative_network=True``).
    decimation : int
        Keep one history row every ``decimation`` samples.
    """

    noise: FilterNoise | None = None
    meas_std_position_m: float = 1e-3
    meas_std_velocity_m_s: float = 1e-3
    meas_std_attitude_rad: float = 1e-4
    update_interval_s: float = 1.0
    init_std_position_m: float = 1e-3
    init_std_velocity_m_s: float = 1e-3
    init_std_attitude_rad: float = 1e-4
    init_std_accel_bias_m_s2: float = 0.05
    init_std_gyro_bias_rad_s: float = 2e-4
    latitude_deg: float = 45.0
    height_m: float = 0.0
    levelling_s: float = 60.0
    zeroing: bool = True
    heading_rad: float | None = None
    declination_rad: float | None = None
    gyro_bias0_rad_s: tuple[float, float, float] = (0.0, 0.0, 0.0)
    accel_bias0_m_s2: tuple[float, float, float] = (0.0, 0.0, 0.0)
    residual_gyro_bias_rad_s: float = 0.0
    discretisation: Literal["first_order", "second_order"] = "first_order"
    temp_slope_window_s: float = 30.0
    derivative: Literal["analytic", "network"] = "analytic"
    decimation: int = 1

    def replace(self, **changes: Any) -> ZuptConfig:
        """A copy with some fields changed."""
        return dataclasses.replace(self, **changes)

    def filter_config(self, mode: Mode) -> FilterConfig:
        """The configuration of the Rust filter for ``mode`` (the thesis' noise of that mode
        unless :attr:`noise` is set)."""
        noise = self.noise or (THESIS_TCZUPT_NOISE if mode == "tczupt" else THESIS_ZUPT_NOISE)
        return FilterConfig(
            mode=mode,
            discretisation=self.discretisation,
            sigma_vrw_m_s_sqrt_s=noise.sigma_vrw_m_s_sqrt_s,
            sigma_arw_rad_sqrt_s=noise.sigma_arw_rad_sqrt_s,
            sigma_abi_m_s2=noise.sigma_abi_m_s2,
            sigma_gbi_rad_s=noise.sigma_gbi_rad_s,
            meas_std_position_m=self.meas_std_position_m,
            meas_std_velocity_m_s=self.meas_std_velocity_m_s,
            meas_std_attitude_rad=self.meas_std_attitude_rad,
            update_interval_s=self.update_interval_s,
            init_std_position_m=self.init_std_position_m,
            init_std_velocity_m_s=self.init_std_velocity_m_s,
            init_std_attitude_rad=self.init_std_attitude_rad,
            init_std_accel_bias_m_s2=self.init_std_accel_bias_m_s2,
            init_std_gyro_bias_rad_s=self.init_std_gyro_bias_rad_s,
            latitude_rad=float(np.deg2rad(self.latitude_deg)),
            height_m=self.height_m,
            temp_slope_window_s=self.temp_slope_window_s,
        )


@dataclass(frozen=True)
class FilterConfig:
    """The configuration of the Rust ZUPT filter (``nav_core::zupt::ZuptConfig``) as it crosses
    into Rust: one typed object, each field named and in the units of its nav-core namesake (SI,
    units in the names). ``None`` keeps nav-core's default. :meth:`ZuptConfig.filter_config`
    builds it.

    Attributes
    ----------
    mode : {"classic", "zupt", "tczupt"}
        The filter (``"zupt"`` is another name of ``"classic"``).
    discretisation : {"first_order", "second_order"}
        Transition-matrix discretisation.
    sigma_vrw_m_s_sqrt_s, sigma_arw_rad_sqrt_s, sigma_abi_m_s2, sigma_gbi_rad_s : float or None
        Process noise: velocity and angle random walk, accelerometer and gyro bias instability.
    meas_std_position_m, meas_std_velocity_m_s, meas_std_attitude_rad : float or None
        R of the frozen-position, zero-velocity and frozen-attitude measurements.
    update_interval_s : float or None
        ZUPT cadence, s.
    init_std_position_m, …, init_std_gyro_bias_rad_s : float or None
        Initial σ of each state group (m, m/s, rad, m/s², rad/s).
    latitude_rad, height_m : float or None
        Frozen position: geodetic latitude (rad), ellipsoidal height (m).
    temp_slope_window_s : float or None
        Window of the least-squares dT/dt slope (TCZUPT), s.
    """

    mode: str = "classic"
    discretisation: str = "first_order"
    sigma_vrw_m_s_sqrt_s: float | None = None
    sigma_arw_rad_sqrt_s: float | None = None
    sigma_abi_m_s2: float | None = None
    sigma_gbi_rad_s: float | None = None
    meas_std_position_m: float | None = None
    meas_std_velocity_m_s: float | None = None
    meas_std_attitude_rad: float | None = None
    update_interval_s: float | None = None
    init_std_position_m: float | None = None
    init_std_velocity_m_s: float | None = None
    init_std_attitude_rad: float | None = None
    init_std_accel_bias_m_s2: float | None = None
    init_std_gyro_bias_rad_s: float | None = None
    latitude_rad: float | None = None
    height_m: float | None = None
    temp_slope_window_s: float | None = None


@dataclass(frozen=True)
class ZuptResult:
    """Histories of one filter run (row ``j`` = state after sample ``j·decimation``).

    Attributes
    ----------
    t : ndarray, shape (m,)
        Time (s) of each row.
    gyro_bias : ndarray, shape (m, 3)
        Gyro bias estimate (rad/s, body): residual after calibration (ZUPT) or total (TCZUPT).
    accel_bias : ndarray, shape (m, 3)
        Accelerometer bias estimate (m/s², body).
    attitude : ndarray, shape (m, 4)
        Attitude estimate, quaternion body → NED, scalar first.
    cov_diag : ndarray, shape (m, 15)
        Diagonal of P (order :data:`STATE_NAMES`, SI units).
    temp_rate : ndarray, shape (m,)
        dT/dt (°C/s) used by TCZUPT (zeros for ZUPT).
    mode : {"classic", "tczupt"}
        The filter that ran (``"zupt"`` given is reported as ``"classic"``).
    config : ZuptConfig
    initial_attitude : ndarray, shape (4,)
        Coarse-levelled attitude (the frozen reference).
    updates : int
        Number of ZUPT updates applied.
    mean_nis : float
        Mean normalised innovation squared (≈ 9 for a consistent filter, χ²₉).
    """

    t: FloatArray
    gyro_bias: FloatArray
    accel_bias: FloatArray
    attitude: FloatArray
    cov_diag: FloatArray
    temp_rate: FloatArray
    mode: str
    config: ZuptConfig
    initial_attitude: FloatArray
    updates: int
    mean_nis: float
    meta: dict[str, Any] = field(default_factory=dict)

    @property
    def gyro_bias_std(self) -> FloatArray:
        """1σ of the gyro-bias estimate (m, 3) rad/s, from P."""
        return np.sqrt(self.cov_diag[:, 12:15])

    @property
    def accel_bias_std(self) -> FloatArray:
        """1σ of the accelerometer-bias estimate (m, 3) m/s², from P."""
        return np.sqrt(self.cov_diag[:, 9:12])

    def metrics(self, reference: ArrayLike, *, threshold: float = CONVERGENCE_THRESHOLD) -> dict[str, Any]:
        """RMS error and convergence time per axis against ``reference`` (m, 3) rad/s."""
        ref = _match_rows("reference", reference, self.t.size)
        return {
            "rms_rad_s": rms_error(self.gyro_bias, ref).tolist(),
            "convergence_time_s": convergence_time(self.t, self.gyro_bias, ref, threshold),
            "final_bias_rad_s": self.gyro_bias[-1].tolist(),
            "final_bias_std_rad_s": self.gyro_bias_std[-1].tolist(),
            "updates": self.updates,
            "mean_nis": self.mean_nis,
        }

    def nees(self, true_gyro_bias: ArrayLike) -> FloatArray:
        """NEES of the gyro-bias states (m,) against a true bias (m, 3): χ²₃ if consistent
        (uses the diagonal of P: the cross-axis bias covariances are negligible here)."""
        ref = _match_rows("true_gyro_bias", true_gyro_bias, self.t.size)
        e = self.gyro_bias - ref
        return np.asarray(np.sum(e * e / self.cov_diag[:, 12:15], axis=1), dtype=np.float64)

    def plot_bias(
        self,
        axis: int,
        *,
        reference: ArrayLike | None = None,
        reference_label: str = "reference",
        label: str | None = None,
        sigma: bool = True,
        ax: Axes | None = None,
    ) -> Axes:
        """Gyro bias estimate of one axis (0, 1, 2) with ±1σ band and an optional reference."""
        from uasnav.plotting import new_figure

        if axis not in (0, 1, 2):
            raise InputError(f"axis: expected 0, 1 or 2, got {axis!r}")
        if ax is None:
            _, ax = new_figure()
        (line,) = ax.plot(self.t, self.gyro_bias[:, axis], lw=1, label=label or MODE_LABELS[self.mode])
        if sigma:
            s = self.gyro_bias_std[:, axis]
            b = self.gyro_bias[:, axis]
            ax.fill_between(self.t, b - s, b + s, color=line.get_color(), alpha=0.15, lw=0)
        if reference is not None:
            ref = _match_rows("reference", reference, self.t.size)
            ax.plot(self.t, ref[:, axis], "k--", lw=1, label=reference_label)
        ax.set_xlabel("time (s)")
        ax.set_ylabel(f"gyro bias {'xyz'[axis]} (rad/s)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        return ax

    def to_csv(self, path: str | os.PathLike[str]) -> None:
        """Write the CLI's EST.csv atomically (:func:`uasnav.io.write_csv_table`, columns
        :data:`CSV_COLUMNS`): ``t,bgx,bgy,bgz,bax,bay,baz`` (s, rad/s, m/s²), then the attitude
        ``q0..q3`` and the 1σ of the gyro and accelerometer biases."""
        from uasnav.io import write_csv_table

        cols = np.column_stack(
            [self.t, self.gyro_bias, self.accel_bias, self.attitude, self.gyro_bias_std, self.accel_bias_std]
        )
        write_csv_table(path, dict(zip(CSV_COLUMNS, cols.T, strict=True)))


def _match_rows(name: str, a: ArrayLike, m: int) -> FloatArray:
    arr = np.asarray(a, dtype=np.float64)
    if arr.shape != (m, 3):
        raise InputError(f"{name}: expected shape ({m}, 3), got {arr.shape}")
    return arr


def run(
    log: ImuLog,
    mode: Mode = "classic",
    model: BiasModel | None = None,
    config: ZuptConfig | None = None,
    *,
    stationary: ArrayLike | Literal["auto"] | None = None,
) -> ZuptResult:
    """Run the ZUPT or TCZUPT filter over a whole log (one call into Rust, GIL released).

    Parameters
    ----------
    log : ImuLog
        Uniformly sampled log; ``temp`` (°C) is required for TCZUPT and for ZUPT with a model.
    mode : {"classic", "zupt", "tczupt"}
        See the module docs (``"zupt"`` is another name of ``"classic"``).
    model : uasnav.thermal.base.BiasModel, optional
        Thermal bias model; only its ``predict(temp)`` (rad/s) and ``derivative(temp)``
        (rad/s/°C) are used. ZUPT: subtracted before filtering (None → data already calibrated).
        TCZUPT: required; its derivative drives eq. (31).
    config : ZuptConfig, optional
    stationary : array_like of bool, shape (n,), or "auto", optional
        Per-sample stationarity; ZUPT updates are applied only where true. ``"auto"`` runs
        :func:`detect_stationary` with its default thresholds. Default: stationary
        throughout.

    Returns
    -------
    ZuptResult

    Raises
    ------
    InputError
        Bad mode, missing temperature or model, non-uniform sampling, non-finite data.
    NumericalError
        The covariance stopped being positive definite.
    """
    if not isinstance(log, ImuLog):  # else an AttributeError deep inside, not a clear message
        raise InputError(f"log: expected an ImuLog, got {type(log).__name__}")
    cfg = config or ZuptConfig()
    if mode not in MODE_LABELS:
        raise InputError(f"mode: expected 'classic' (or 'zupt') or 'tczupt', got {mode!r}")
    if mode == "zupt":
        mode = "classic"
    if not isinstance(cfg.decimation, int) or cfg.decimation < 1:
        raise InputError(f"config.decimation: expected an int >= 1, got {cfg.decimation!r}")
    if cfg.derivative not in ("analytic", "network"):
        raise InputError(f"config.derivative: expected 'analytic' or 'network', got {cfg.derivative!r}")
    for name in ("levelling_s", "update_interval_s", "temp_slope_window_s"):
        v = getattr(cfg, name)
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise InputError(f"config.{name}: expected a finite number of seconds > 0, got {v}")
    if not (math.isfinite(cfg.latitude_deg) and abs(cfg.latitude_deg) <= 90.0):
        raise InputError(f"config.latitude_deg: expected a latitude in [-90, 90] deg, got {cfg.latitude_deg}")
    rate = log.uniform_rate()
    dt = 1.0 / rate
    gyro = log.gyro
    dbdt = None
    if mode == "tczupt":
        if model is None:
            raise InputError("model: TCZUPT needs a thermal model (its derivative ∂b/∂T)")
        if log.temp is None:
            raise InputError("log.temp: TCZUPT needs the die temperature")
        dbdt = _model_derivative(model, log.temp, cfg.derivative, log.n)
    elif model is not None:
        if log.temp is None:
            raise InputError("log.temp: calibrating with a model needs the die temperature")
        gyro = gyro - _model_rows("model.predict(temp)", model.predict(log.temp), log.n)
    mask = None
    if isinstance(stationary, str):
        if stationary != "auto":
            raise InputError(f"stationary: expected a bool array or 'auto', got {stationary!r}")
        mask = detect_stationary(log).mask
    elif stationary is not None:
        mask = np.ascontiguousarray(np.asarray(stationary, dtype=bool))
        if mask.shape != (log.n,):
            raise InputError(f"stationary: expected shape ({log.n},), got {mask.shape}")
    heading, declination = cfg.heading_rad, cfg.declination_rad
    mag = None
    if heading is None and declination is not None:
        if log.mag is None:
            raise InputError("config.declination_rad: magnetic heading needs log.mag")
        mag = np.ascontiguousarray(log.mag)
    gb0 = np.asarray(cfg.gyro_bias0_rad_s, dtype=np.float64) + cfg.residual_gyro_bias_rad_s
    out = _core.zupt_run(
        np.ascontiguousarray(gyro),
        np.ascontiguousarray(log.accel),
        dt,
        config=cfg.filter_config(mode),
        temp=None if log.temp is None else np.ascontiguousarray(log.temp),
        dbias_dtemp=dbdt,
        mag=mag,
        stationary=mask,
        levelling_samples=max(1, round(min(cfg.levelling_s * rate, log.n))),  # a longer window: the whole log
        heading_rad=heading,
        declination_rad=declination if heading is None else None,
        accel_bias0=[float(v) for v in cfg.accel_bias0_m_s2],
        gyro_bias0=[float(v) for v in gb0],
        zero_gyro_bias=cfg.zeroing,
        decimation=cfg.decimation,
    )
    return ZuptResult(
        t=log.t[:: cfg.decimation].copy(),
        gyro_bias=out["gyro_bias"],
        accel_bias=out["accel_bias"],
        attitude=out["attitude"],
        cov_diag=out["cov_diag"],
        temp_rate=out["temp_rate"],
        mode=mode,
        config=cfg,
        initial_attitude=np.asarray(out["initial_attitude"], dtype=np.float64),
        updates=int(out["updates"]),
        mean_nis=float(out["mean_nis"]),
        meta={"rate_hz": rate, "n": log.n},
    )


#: The result type of :func:`detect_stationary` (the one static-detection result type).
StationarityResult = StaticIntervals


def detect_stationary(
    log: ImuLog,
    *,
    window_s: float = 0.25,
    sigma_accel_m_s2: float = 0.05,
    sigma_gyro_rad_s: float = 0.01,
    threshold: float = 10.0,
    gravity_m_s2: float = STANDARD_GRAVITY,
) -> StaticIntervals:
    """Per-sample stationarity by the generalised likelihood ratio test ("SHOE", Skog et al.
    2010) computed in Rust (``nav_core::zupt::StationarityDetector``, the same test the
    filter can run per sample on a microcontroller).

    ``T = (1/W)·Σ [‖a − g·ā/‖ā‖‖²/σ_a² + ‖ω‖²/σ_ω²]`` over a centred window of ``window_s``;
    stationary where ``T < threshold``. The defaults (σ_a = 0.05 m/s², σ_ω = 0.01 rad/s,
    0.25 s, γ = 10) give T ≈ 2–3 for a consumer MEMS IMU at rest and 10²–10⁴ in motion; raise
    the σ for noisier sensors.

    This is :func:`uasnav.stationary.detect_static` with these fixed thresholds, no gyro bias
    removed, and the window rounded to 1–256 samples (clamped, as the filter's detector is)
    at the median sample rate.
    """
    if not isinstance(log, ImuLog):
        raise InputError(f"log: expected an ImuLog, got {type(log).__name__}")
    w = max(1, min(MAX_WINDOW_SAMPLES, round(window_s * log.sample_rate), log.n))
    return detect_static(
        log,
        window_samples=w,
        sigma_a=sigma_accel_m_s2,
        sigma_g=sigma_gyro_rad_s,
        threshold=threshold,
        gravity=gravity_m_s2,
        gyro_bias=np.zeros(3),
    )


def _model_derivative(model: BiasModel, temp: FloatArray, method: str, n: int) -> FloatArray:
    if method == "analytic":
        return _model_rows("model.derivative(temp)", model.derivative(temp), n)
    try:
        d = model.derivative(temp, method="network")  # type: ignore[call-arg]
    except TypeError:
        raise InputError(
            f"config.derivative='network': {type(model).__name__} has no derivative network "
            "(use a NeuralBiasModel fitted with derivative_network=True)"
        ) from None
    return _model_rows('model.derivative(temp, method="network")', d, n)


def _model_rows(name: str, a: ArrayLike, n: int) -> FloatArray:
    arr = np.ascontiguousarray(np.asarray(a, dtype=np.float64))
    if arr.shape != (n, 3):
        raise InputError(f"{name}: expected shape ({n}, 3), got {arr.shape}")
    if not np.isfinite(arr).all():
        raise InputError(f"{name}: non-finite value at row {int(np.argwhere(~np.isfinite(arr))[0, 0])}")
    return arr


# ---------------------------------------------------------------------------------------------
# Evaluation (thesis §4.2.6.2)


def moving_average(x: ArrayLike, rate_hz: float, window_s: float = REFERENCE_WINDOW_S) -> FloatArray:
    """Centred moving average (n, k) over ``window_s`` seconds (shrinking at the ends)."""
    for name, v in (("rate_hz", rate_hz), ("window_s", window_s)):
        if not (math.isfinite(v) and v > 0):
            raise InputError(f"{name}: must be finite and > 0, got {v!r}")
    a = np.asarray(x, dtype=np.float64)
    a2 = a[:, None] if a.ndim == 1 else a
    w = max(1, round(window_s * rate_hz))
    c = np.vstack([np.zeros((1, a2.shape[1])), np.cumsum(a2, axis=0)])
    n = a2.shape[0]
    i = np.arange(n)
    lo = np.clip(i - w // 2, 0, n)
    hi = np.clip(i - w // 2 + w, 0, n)
    out = (c[hi] - c[lo]) / (hi - lo)[:, None]
    return out if a.ndim > 1 else out[:, 0]


def moving_average_reference(
    log: ImuLog,
    initial_attitude: ArrayLike,
    *,
    latitude_deg: float = 45.0,
    model: BiasModel | None = None,
    window_s: float = REFERENCE_WINDOW_S,
) -> FloatArray:
    """The thesis' benchmark (Table 9): 30 s moving average of the (calibrated when ``model``
    is given) gyro output, minus the Earth rate resolved in the body frame at the given
    attitude, so that it is comparable with the filters' bias estimates. Shape (n, 3), rad/s."""
    log = require_log(log)
    gyro = log.gyro if model is None or log.temp is None else log.gyro - model.predict(log.temp)
    w_b = _earth_rate_body(initial_attitude, latitude_deg)
    return moving_average(gyro, log.sample_rate, window_s) - w_b[None, :]


def reference_residual(
    log: ImuLog,
    reference: ArrayLike,
    initial_attitude: ArrayLike,
    *,
    latitude_deg: float = 45.0,
    model: BiasModel | None = None,
) -> FloatArray:
    """Table 9: absolute mean (3,) rad/s of the residuals ``gyro − C_nᵇ·ω_ie − reference`` of
    the moving-average reference (calibrated gyro when ``model`` is given)."""
    log = require_log(log)
    gyro = log.gyro if model is None or log.temp is None else log.gyro - model.predict(log.temp)
    r = gyro - _earth_rate_body(initial_attitude, latitude_deg)[None, :] - np.asarray(reference)
    return np.asarray(np.abs(np.mean(r, axis=0)), dtype=np.float64)


def _earth_rate_body(q: ArrayLike, latitude_deg: float) -> FloatArray:
    """Earth rate (3,) rad/s resolved in the body frame of attitude ``q`` (body → NED)."""
    lat = np.deg2rad(latitude_deg)
    w_n = OMEGA_IE * np.array([np.cos(lat), 0.0, -np.sin(lat)])
    c_bn = _core.attitude_quat_to_dcm(np.asarray(q, dtype=np.float64).reshape(1, 4))[0]
    return np.asarray(c_bn.T @ w_n, dtype=np.float64)


def rms_error(estimate: ArrayLike, reference: ArrayLike) -> FloatArray:
    """Per-axis RMS of ``estimate − reference`` (3,), same units."""
    e = np.asarray(estimate, dtype=np.float64) - np.asarray(reference, dtype=np.float64)
    return np.asarray(np.sqrt(np.mean(e * e, axis=0)), dtype=np.float64)


def convergence_time(
    t: ArrayLike, estimate: ArrayLike, reference: ArrayLike, threshold: float = CONVERGENCE_THRESHOLD
) -> list[float | None]:
    """First time (s from the start) the per-axis error falls below ``threshold`` (Table 11's
    definition: 1e-5 rad/s); ``None`` if it never does."""
    if not (math.isfinite(threshold) and threshold > 0):
        raise InputError(f"threshold: must be finite and > 0 (rad/s), got {threshold!r}")
    tt = np.asarray(t, dtype=np.float64)
    e = np.abs(np.asarray(estimate, dtype=np.float64) - np.asarray(reference, dtype=np.float64))
    out: list[float | None] = []
    for j in range(e.shape[1]):
        idx = np.flatnonzero(e[:, j] < threshold)
        out.append(float(tt[idx[0]] - tt[0]) if idx.size else None)
    return out


def segment_rms(
    log: ImuLog,
    mode: Mode,
    reference: ArrayLike,
    *,
    model: BiasModel | None = None,
    config: ZuptConfig | None = None,
    segments: int = 5,
    segment_s: float = 300.0,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Tables 12–13: run the filter separately on ``segments`` consecutive ``segment_s``
    pieces of the log; returns (rms (segments, 3), mean (3,), std (3,)) in rad/s."""
    log = require_log(log)
    rate = log.uniform_rate()
    per = round(segment_s * rate)
    if segments * per > log.n:
        raise InputError(
            f"log: {segments} × {segment_s} s segments need {segments * per} samples, got {log.n}"
        )
    ref = np.asarray(reference, dtype=np.float64)
    rms = np.empty((segments, 3))
    for s in range(segments):
        piece = log.slice(s * per, (s + 1) * per)
        res = run(piece, mode, model, config)
        rms[s] = rms_error(res.gyro_bias, ref[s * per : (s + 1) * per : res.config.decimation])
    return rms, rms.mean(axis=0), rms.std(axis=0, ddof=1)


__all__ = [
    "CONVERGENCE_THRESHOLD",
    "CSV_COLUMNS",
    "REFERENCE_WINDOW_S",
    "RESIDUAL_BIAS_15DEG_H",
    "STATE_NAMES",
    "THESIS_TCZUPT_NOISE",
    "THESIS_ZUPT_NOISE",
    "FilterConfig",
    "StationarityResult",
    "ZuptConfig",
    "ZuptResult",
    "convergence_time",
    "detect_stationary",
    "moving_average",
    "moving_average_reference",
    "reference_residual",
    "rms_error",
    "run",
    "segment_rms",
]
