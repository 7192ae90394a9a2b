"""Type stubs of the compiled extension ``uasnav._core`` (checked by ``mypy.stubtest``).

Private API: import :mod:`uasnav.allan`, :mod:`uasnav.attitude`, … instead. Units: SI;
quaternions scalar first, body → NED.

Errors: bad input raises :class:`uasnav.errors.InputError` naming the argument — wrong shapes,
zero-width or mismatched arrays, non-contiguous arrays, NaN/inf, NaN tolerances, and integers
out of range (negative or too large: ``InputError``, not ``OverflowError``); a non-integer where
an integer is expected stays a ``TypeError``. No call lets a Rust panic cross into Python.
"""

from collections.abc import Sequence
from typing import Any, final

import numpy as np
from numpy.typing import NDArray

from uasnav.ins.core import FilterConfig

__version__: str
__all__ = [
    "InsStream",
    "__version__",
    "allan_cluster_size_for_tau",
    "allan_cluster_sizes",
    "allan_oavar",
    "attitude_dcm_to_quat",
    "attitude_drift_angles",
    "attitude_euler_to_quat",
    "attitude_first_crossing_times",
    "attitude_propagate",
    "attitude_quat_to_dcm",
    "attitude_quat_to_euler",
    "attitude_rotation_angle",
    "earth_normal_gravity",
    "earth_radii",
    "earth_rate_ned",
    "ins_run",
    "mlp_evaluate_model",
    "noise_fit_ieee952",
    "noise_read_points",
    "redundancy_chi2_threshold",
    "redundancy_face_config",
    "redundancy_face_normals",
    "redundancy_fuse",
    "redundancy_kalman",
    "redundancy_kr",
    "redundancy_level",
    "redundancy_ls_covariance",
    "redundancy_mountings_config",
    "redundancy_parity_residuals",
    "redundancy_relative_rotation",
    "redundancy_wahba",
    "zupt_detect_static",
    "zupt_run",
]

# --- allan / noise -------------------------------------------------------------------------
def allan_cluster_sizes(n: int, spacing_name: str) -> list[int]:
    """Cluster sizes m of a spacing ('octave', 'decade', 'all') for n samples."""

def allan_cluster_size_for_tau(tau_s: float, tau0_s: float) -> int:
    """Cluster size for a cluster time (s) at sample period tau0_s (s)."""

def allan_oavar(
    data: NDArray[np.float64], tau0_s: float, ms: list[int]
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.uint64], NDArray[np.float64]]:
    """Overlapping Allan variance of each column of data (n, k): (taus, avar (len(ms), k),
    n_terms, rel_error)."""

def noise_fit_ieee952(
    taus: NDArray[np.float64], avar: NDArray[np.float64], rel_error: NDArray[np.float64]
) -> tuple[list[float], list[bool], float]:
    """Five-term IEEE 952 fit: ([Q, N, B, K, R] SI, active flags, weighted rms rel. residual)."""

def noise_read_points(
    taus: NDArray[np.float64], avar: NDArray[np.float64], rel_error: NDArray[np.float64]
) -> list[tuple[float, int, float] | None]:
    """Slope-line readings for Q, N, B, K, R: (value, segment index, slope) or None."""

# --- attitude ------------------------------------------------------------------------------
def attitude_propagate(
    q0: list[float], rates: NDArray[np.float64], dt_s: float, coning: bool = False
) -> NDArray[np.float64]:
    """Quaternions (n, 4) after each body-rate sample (n, 3) rad/s held for dt_s."""

def attitude_drift_angles(
    rates: NDArray[np.float64], dt_s: float, coning: bool = False
) -> NDArray[np.float64]:
    """Rotation angle θ (rad) after each step of integrating rates (n, 3) from identity."""

def attitude_first_crossing_times(
    theta: NDArray[np.float64], dt_s: float, thresholds: list[float]
) -> list[float | None]:
    """First time (s) θ reaches each threshold (rad), None if never."""

def attitude_rotation_angle(q: NDArray[np.float64]) -> NDArray[np.float64]:
    """θ = 2·acos(|q_s|) (rad) of quaternions (n, 4)."""

def attitude_euler_to_quat(euler: NDArray[np.float64]) -> NDArray[np.float64]:
    """Quaternions (n, 4) from 3-2-1 Euler angles (n, 3) [roll, pitch, yaw] rad."""

def attitude_quat_to_euler(q: NDArray[np.float64]) -> NDArray[np.float64]:
    """3-2-1 Euler angles (n, 3) of quaternions (n, 4)."""

def attitude_quat_to_dcm(q: NDArray[np.float64]) -> NDArray[np.float64]:
    """DCMs C_b^n (n, 3, 3) of quaternions (n, 4)."""

def attitude_dcm_to_quat(dcm: NDArray[np.float64], tol: float = 1e-6) -> NDArray[np.float64]:
    """Quaternions (n, 4) of DCMs C_b^n (n, 3, 3)."""

# --- mlp -----------------------------------------------------------------------------------
def mlp_evaluate_model(
    model_json: str,
    temp_c: NDArray[np.float64],
    clip: bool = True,
    derivative_networks: bool = False,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """Networks of a neural thermal-model file (JSON text) at temperatures (n,) degC:
    (value (n, k) rad/s, d/dT (n, k) rad/s/degC, clipped (n,))."""

def zupt_run(
    gyro: NDArray[np.float64],
    accel: NDArray[np.float64],
    dt_s: float,
    *,
    config: Any | None = None,
    temp: NDArray[np.float64] | None = None,
    dbias_dtemp: NDArray[np.float64] | None = None,
    mag: NDArray[np.float64] | None = None,
    stationary: NDArray[np.bool_] | None = None,
    levelling_samples: int = 6000,
    heading_rad: float | None = None,
    declination_rad: float | None = None,
    accel_bias0: Sequence[float] = ...,
    gyro_bias0: Sequence[float] = ...,
    zero_gyro_bias: bool = True,
    decimation: int = 1,
) -> dict[str, Any]:
    """Run the ZUPT filter, classic ('classic', also spelled 'zupt') or thermally compensated
    ('tczupt'), over a whole log (GIL released).

    gyro, accel (n, 3) rad/s and m/s² (body); dt_s sample period (s); config: one object with
    the attributes of uasnav.zupt.FilterConfig (mode, discretisation and the SI floats of
    nav_core::zupt::ZuptConfig by name, None keeps nav-core's default; None: the classic
    filter with nav-core's defaults); temp (n,) °C; dbias_dtemp (n, 3)
    rad/s/°C (TCZUPT); mag (n, 3) for a magnetic heading with declination_rad; stationary
    (n,) bool (updates only where true); zero_gyro_bias starts the bias from the mean
    gyro over the levelling window minus the Earth rate (plus gyro_bias0). Returns a dict:
    gyro_bias (m, 3), accel_bias (m, 3), attitude (m, 4), cov_diag (m, 15), temp_rate (m,),
    initial_attitude [4], updates, mean_nis; m = ceil(n / decimation).
    """

def zupt_detect_static(
    accel: NDArray[np.float64],
    gyro: NDArray[np.float64],
    *,
    sigma_accel_m_s2: float = 0.05,
    sigma_gyro_rad_s: float = 0.01,
    window_samples: int = 25,
    threshold: float = 10.0,
    gravity_m_s2: float = 9.80665,
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """GLRT (SHOE) stationarity statistic T (n,) and mask T < threshold (n,) of accel (n, 3)
    m/s² and gyro (n, 3) rad/s over a centred window of window_samples samples."""

# --- earth -----------------------------------------------------------------------------------
def earth_normal_gravity(latitude_rad: float, height_m: float) -> float:
    """WGS-84 normal gravity (m/s²) at geodetic latitude (rad) and ellipsoidal height (m)."""

def earth_rate_ned(latitude_rad: float) -> list[float]:
    """Earth rotation rate resolved in NED (rad/s) at geodetic latitude (rad)."""

def earth_radii(latitude_rad: float) -> tuple[float, float]:
    """Meridian and transverse radii of curvature (m) at geodetic latitude (rad)."""

# --- redundancy ----------------------------------------------------------------------------
def redundancy_face_config(
    shape: str, counts: list[int], triaxial: bool
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Axes (n, 3) and sensor index (n,) of counts[f] sensors on face f of a Platonic solid."""

def redundancy_mountings_config(
    mountings: NDArray[np.float64], tol: float = 1e-6
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Axes and sensor index of triaxial sensors with mountings (s, 3, 3) (IMU → sensor)."""

def redundancy_face_normals(shape: str) -> NDArray[np.float64]:
    """Face normals (F, 3) of a Platonic solid."""

def redundancy_kr(axes: NDArray[np.float64], sensor_of: list[int]) -> list[float]:
    """Improvement factor k_r per IMU axis (eq. 40) of a configuration."""

def redundancy_ls_covariance(
    axes: NDArray[np.float64], sensor_of: list[int], sigma: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Least-squares covariance (HᵀWH)⁻¹ (3, 3) for per-axis noise sigma (n,)."""

def redundancy_chi2_threshold(dof: int, p_fa: float) -> float:
    """Upper χ² quantile for dof and false-alarm probability p_fa."""

def redundancy_fuse(
    axes: NDArray[np.float64],
    sensor_of: list[int],
    z: NDArray[np.float64],
    sigma: NDArray[np.float64],
    bias: NDArray[np.float64],
    fdi: bool,
    p_fa: float = 1e-6,
    saturation: float = ...,
    stuck_samples: int = 0,
    max_isolations: int = 2,
) -> tuple[
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.bool_],
    NDArray[np.bool_],
    NDArray[np.uint8],
]:
    """Batch fusion of z (m, n): (fused (m, 3), variance (m, 3), chi2 (m,), valid (m,),
    alarm (m,), health (m, n_sensors))."""

def redundancy_parity_residuals(
    axes: NDArray[np.float64],
    sensor_of: list[int],
    z: NDArray[np.float64],
    sigma: NDArray[np.float64],
) -> NDArray[np.float64]:
    """LS residuals z − H·x̂ (m, n); NaN rows where a sample is non-finite."""

def redundancy_kalman(
    axes: NDArray[np.float64],
    sensor_of: list[int],
    z: NDArray[np.float64],
    sigma: NDArray[np.float64],
    dt_s: float,
    rate_psd: float,
    bias_psd: float,
    bias_sigma0: float,
    rate_sigma0: float,
    zero_rate: list[bool] | None = None,
    zero_rate_sigma: float = 1e-3,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Kalman fusion with per-axis bias states: (rate, rate σ, biases, bias σ)."""

def redundancy_level(f: NDArray[np.float64]) -> NDArray[np.float64]:
    """Roll and pitch (k, 2) rad from mean specific forces (k, 3) m/s²."""

def redundancy_relative_rotation(
    c_bi_n: NDArray[np.float64], c_br_n: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Eq. (45): C_br^bi = (C_bi^n)ᵀ · C_br^n."""

def redundancy_wahba(
    v_ref: NDArray[np.float64], v_sensor: NDArray[np.float64], weights: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Rotation C (3, 3), reference → sensor, with v_sensor ≈ C·v_ref."""

# --- utm: the utm-index crate -----------------------------------------------------------

def utm_encounters(
    intent: NDArray[np.uint32],
    alt: NDArray[np.float64],
    time: NDArray[np.float64],
    offsets: NDArray[np.uint64],
    vertices: NDArray[np.float64],
    circle: NDArray[np.float64],
    horizontal_m: float = 0.0,
    vertical_m: float = 0.0,
    threads: int = 1,
    brute: bool = False,
) -> tuple[NDArray[np.uint32], NDArray[np.float64], NDArray[np.float64]]:
    """Encounters of volumes of different intents: (pairs (k, 2) volume indices, overlap
    (k, 2) s, distances (k, 2) horizontal/vertical m). ``brute`` selects the O(n²) reference."""

def utm_earliest_delays(
    intent: NDArray[np.uint32],
    alt: NDArray[np.float64],
    time: NDArray[np.float64],
    offsets: NDArray[np.uint64],
    vertices: NDArray[np.float64],
    circle: NDArray[np.float64],
    which: NDArray[np.uint32],
    max_delay_s: float,
) -> NDArray[np.float64]:
    """Smallest departure delay (s) of each intent in ``which`` that leaves it free of conflict
    with every other intent, NaN where none within ``max_delay_s``."""

__all__ += ["utm_earliest_delays", "utm_encounters"]
# ---- GNSS/INS ---------------------------------------------------------------------------

# Times (k,) s and rows (k, 3) of the IMU and GNSS arrays both filter entry points take (units
# in ins_run's docstring).
_Times = NDArray[np.float64]
_Rows = NDArray[np.float64]

def ins_run(
    imu_t: _Times,
    gyro: _Rows,
    accel: _Rows,
    gnss_t: _Times,
    gnss_llh: _Rows,
    gnss_vel: _Rows,
    gnss_acc: _Rows,
    *,
    gnss_use: NDArray[np.bool_] | None = None,
    baro_t: NDArray[np.float64] | None = None,
    baro_h: NDArray[np.float64] | None = None,
    mag_t: NDArray[np.float64] | None = None,
    mag: NDArray[np.float64] | None = None,
    temp: NDArray[np.float64] | None = None,
    dbias_dtemp: NDArray[np.float64] | None = None,
    stationary: NDArray[np.bool_] | None = None,
    initial_attitude: Sequence[float] | None = None,
    levelling_samples: int = 100,
    gyro_bias0: Sequence[float] = ...,
    config: FilterConfig,
    decimation: int = 1,
) -> dict[str, Any]:
    """Run the GNSS/INS filter over a whole flight (one call, GIL released).

    IMU times (n,) s, gyro (n, 3) rad/s, accel (n, 3) m/s²; GNSS times (m,) s, llh (m, 3)
    rad/rad/m, NED velocity (m, 3) m/s, accuracies (m, 3) = horizontal m, vertical m, speed m/s;
    each array's rows match its times (checked). Returns decimated ``llh``, ``vel``,
    ``attitude``, ``gyro_bias``, ``accel_bias``, ``cov_diag``, ``protection`` (HPL, VPL m),
    ``gnss_used``; per fix ``fix_status`` (0 used, 1/2 excluded, 3 masked, 4 unused, 5 reset)
    and ``fix_nis``; and the update counts. ``config`` is one
    :class:`uasnav.ins.core.FilterConfig`, read by attribute (nav-core's field names; ``None``
    keeps nav-core's default); a missing attribute or a wrong type is an ``InputError`` naming
    the field.
    """

@final
class InsStream:
    """The GNSS/INS filter stepped one batch of received messages per call (nav-core's
    ``InsStream``: causal; levels on the first ``levelling_samples`` IMU samples, starts at the
    latest fix within 1 s, then applies each fix at the first IMU sample at or after its time).
    ``config`` as for :func:`ins_run`."""

    def __new__(cls, *, config: FilterConfig, levelling_samples: int = 100) -> InsStream: ...
    def step(
        self,
        imu_t: _Times,
        gyro: _Rows,
        accel: _Rows,
        gnss_t: _Times,
        gnss_llh: _Rows,
        gnss_vel: _Rows,
        gnss_acc: _Rows,
        gnss_before: NDArray[np.uint64],
    ) -> dict[str, NDArray[Any]]:
        """Process one batch in arrival order (GIL released): the IMU and GNSS arrays as for
        :func:`ins_run`, fix ``j`` having arrived after ``gnss_before[j]`` of the batch's IMU
        samples. Returns, per processed IMU sample, ``t``,
        ``llh``, ``vel``, ``attitude``, ``protection`` (HPL, VPL m), ``gyro_bias``,
        ``accel_bias``, ``fixes_used``, ``fixes_excluded``."""
    @property
    def running(self) -> bool:
        """Whether the filter runs (levelling done, initialised on a fix)."""
    def counts(self) -> dict[str, Any]:
        """Running counts: imu_samples, imu_refused, imu_gaps, fixes_used, fixes_excluded,
        fixes_dropped, gnss_resets, course_reset."""

# --- csv: the csv-chunk crate ----------------------------------------------------------------

def csv_parse_chunk(
    chunk: bytes,
    width: int,
    columns: Sequence[int],
    exact_width: bool,
    nan_ok: bool = False,
    threads: int = 0,
    end: int | None = None,
) -> NDArray[np.float64] | None:
    """The rows of ``chunk[:end]`` (bytes of whole CSV lines below a header row of ``width``
    cells, read in place) as an (m, len(columns)) Fortran-order float64 array of the cells at
    ``columns``, parsed on ``threads`` threads (0: one per core) with the GIL released; None
    when some line needs the row-by-row reader (quoting, a non-ASCII or control byte, a line
    over 64 KiB, a blank line, a row of the wrong width, a cell that is not a plain decimal
    number, ±inf, NaN unless ``nan_ok``)."""

def csv_line_breaks(chunk: bytes, end: int | None = None) -> int:
    """Line breaks (``\\n``, ``\\r\\n`` or ``\\r``) in ``chunk[:end]``, counted with the GIL
    released."""

__all__ += ["csv_line_breaks", "csv_parse_chunk"]
