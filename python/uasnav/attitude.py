"""Quaternion attitude propagation, conversions and free-inertial drift analysis.

Convention (stated once, tested in ``tests/test_attitude.py``): Hamilton quaternions, scalar
first ``[q_s, q_x, q_y, q_z]``, rotating body → NED (``v_n = q ⊗ v_b ⊗ q*``, ``C_b^n = R(q)``).
Euler angles are the 3-2-1 (yaw, pitch, roll) sequence of the thesis' eqs. (41)–(43).

The drift tools reproduce the thesis' free-inertial study (§4.2.5.3 and §4.3.6): integrate a
residual rate profile (e.g. an uncompensated gyro bias), report the rotation angle
``θ = 2·acos(|q_s|)`` (eq. 35) of the accumulated attitude error, and the first time it
exceeds each accuracy threshold, with ``Δt% = (t_new − t_ref)/t_ref·100`` (eqs. 36, 46).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav import _core
from uasnav.errors import InputError
from uasnav.limits import check_count

if TYPE_CHECKING:
    from matplotlib.axes import Axes

#: The thesis' attitude accuracy thresholds (rad), Tables 7, 8 and 15.
DEFAULT_THRESHOLDS = (1.70e-3, 3.50e-3, 8.70e-3, 1.75e-2)


def _rows(name: str, a: ArrayLike, k: int) -> NDArray[np.float64]:
    arr = np.asarray(a, dtype=np.float64)
    if arr.ndim == 1 and arr.shape == (k,):
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != k:
        raise InputError(f"{name}: expected shape (n, {k}), got {arr.shape}")
    return np.ascontiguousarray(arr)


#: Largest |‖q‖ − 1| of a quaternion taken as a rotation (filter outputs are normalised each
#: step; a quaternion of norm 2 is not an attitude, and the conversions would silently use it).
UNIT_NORM_TOL = 1e-4


def _unit_quats(name: str, q: ArrayLike) -> NDArray[np.float64]:
    arr = _rows(name, q, 4)
    with np.errstate(over="ignore", invalid="ignore"):
        norm = np.linalg.norm(arr, axis=1)
    bad = np.flatnonzero(np.abs(norm - 1.0) > UNIT_NORM_TOL)  # NaN rows: the core names them
    if bad.size:
        i = int(bad[0])
        raise InputError(f"{name}[{i}]: a quaternion of norm {norm[i]:.6g}, not a rotation (norm 1)")
    return arr


def _dt(dt: float) -> float:
    if not (np.isfinite(dt) and dt > 0):
        raise InputError(f"dt: must be finite and > 0, got {dt!r}")
    return float(dt)


def propagate(q0: ArrayLike, rates: ArrayLike, dt: float, *, coning: bool = False) -> NDArray[np.float64]:
    """Propagate an attitude through body angular rates.

    Parameters
    ----------
    q0 : array_like, shape (4,)
        Initial attitude, scalar first, body → NED, of unit norm (within :data:`UNIT_NORM_TOL`;
        renormalised on input).
    rates : array_like, shape (n, 3)
        Body-frame angular rate (rad/s), each sample held for ``dt``.
    dt : float
        Sample period (s).
    coning : bool
        Apply Savage's two-sample coning correction.

    Returns
    -------
    ndarray, shape (n, 4)
        Attitude after each sample (exact rotation-vector exponential per step).
    """
    q = np.asarray(q0, dtype=np.float64)
    if q.shape != (4,):
        raise InputError(f"q0: expected shape (4,), got {q.shape}")
    if np.isfinite(q).all() and q.any():  # (zero and non-finite: the core's own messages)
        _unit_quats("q0", q)
    return _core.attitude_propagate([float(x) for x in q], _rows("rates", rates, 3), _dt(dt), coning)


def rotation_angle(q: ArrayLike) -> NDArray[np.float64]:
    """Rotation angle θ = 2·acos(|q_s|) (rad) of quaternions (n, 4) — eq. (35)."""
    return _core.attitude_rotation_angle(_unit_quats("q", q))


def euler_to_quat(euler: ArrayLike) -> NDArray[np.float64]:
    """Quaternions (n, 4) from 3-2-1 Euler angles (n, 3) ``[roll, pitch, yaw]`` (rad)."""
    return _core.attitude_euler_to_quat(_rows("euler", euler, 3))


def quat_to_euler(q: ArrayLike) -> NDArray[np.float64]:
    """3-2-1 Euler angles (n, 3) ``[roll, pitch, yaw]`` (rad) of quaternions (n, 4)."""
    return _core.attitude_quat_to_euler(_unit_quats("q", q))


def quat_to_dcm(q: ArrayLike) -> NDArray[np.float64]:
    """Direction cosine matrices C_b^n (n, 3, 3) of quaternions (n, 4)."""
    return _core.attitude_quat_to_dcm(_unit_quats("q", q))


def dcm_to_quat(dcm: ArrayLike, tol: float = 1e-6) -> NDArray[np.float64]:
    """Quaternions (n, 4) of DCMs C_b^n (n, 3, 3); each must be a rotation to within ``tol``."""
    arr = np.asarray(dcm, dtype=np.float64)
    if arr.shape == (3, 3):
        arr = arr[None]
    if arr.ndim != 3 or arr.shape[1:] != (3, 3):
        raise InputError(f"dcm: expected shape (n, 3, 3), got {arr.shape}")
    return _core.attitude_dcm_to_quat(np.ascontiguousarray(arr), float(tol))


@dataclass(frozen=True)
class DriftResult:
    """Free-inertial attitude drift of a residual rate profile.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time after each step (s).
    theta : ndarray, shape (n,)
        Rotation angle of the accumulated attitude error (rad).
    thresholds : tuple of float
        Thresholds (rad).
    crossing_times : tuple of (float or None)
        First time θ reaches each threshold (s), linearly interpolated; None if never.
    """

    t: NDArray[np.float64]
    theta: NDArray[np.float64]
    thresholds: tuple[float, ...]
    crossing_times: tuple[float | None, ...]

    def plot(self, ax: Axes | None = None, label: str | None = None) -> Axes:
        """Plot θ(t) with the thresholds; returns the axes."""
        return plot_drift([(label or "θ(t)", self)], ax=ax)


def plot_drift(series: Sequence[tuple[str, DriftResult]], ax: Axes | None = None) -> Axes:
    """θ(t) curves (rad) with the accuracy thresholds as horizontal lines."""
    if ax is None:
        from uasnav.plotting import new_figure

        _, ax = new_figure()
    for label, d in series:
        ax.plot(d.t, d.theta, label=label)
    if series:
        for th in series[0][1].thresholds:
            ax.axhline(th, color="grey", ls=":", lw=0.8)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("rotation angle θ (rad)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def drift(
    rates: ArrayLike,
    dt: float,
    duration: float | None = None,
    *,
    thresholds: Sequence[float] = DEFAULT_THRESHOLDS,
    coning: bool = False,
) -> DriftResult:
    """Attitude error θ(t) accumulated by integrating a residual rate.

    Parameters
    ----------
    rates : array_like, shape (n, 3) or (3,)
        Residual body rate (rad/s): a series, or one constant vector (then ``duration`` is
        required and the series is ``round(duration/dt)`` copies).
    dt : float
        Step (s).
    duration : float, optional
        Length of a constant profile (s).
    thresholds : sequence of float
        Attitude thresholds (rad); default: the thesis' four.
    coning : bool
        Apply the coning correction.
    """
    dt = _dt(dt)
    arr = np.asarray(rates, dtype=np.float64)
    if arr.shape == (3,):
        if duration is None or not (np.isfinite(duration) and duration > 0):
            raise InputError("duration: required (> 0) for a constant rate vector")
        # the constant vector becomes n rows, θ(t) and t: refused before any allocation
        # (the count is checked as a float first: 1e308 s / 1e-300 s is inf, which round() cannot take)
        what = f"attitude drift over {duration:g} s"
        check_count(duration / dt, 6 * 8, what, option="duration (or raise dt)")
        n = round(duration / dt)
        arr = np.broadcast_to(arr, (n, 3))
    r = _rows("rates", arr, 3)
    if r.shape[0] == 0:
        raise InputError("rates: empty")
    th = [float(x) for x in thresholds]
    if any(not (np.isfinite(x) and x > 0) for x in th):
        raise InputError(f"thresholds: must be finite and > 0, got {th}")
    theta = _core.attitude_drift_angles(r, dt, coning)
    times = _core.attitude_first_crossing_times(theta, dt, th)
    t = dt * np.arange(1, theta.size + 1)
    return DriftResult(t=t, theta=theta, thresholds=tuple(th), crossing_times=tuple(times))


def delta_t_percent(t_new: float | None, t_ref: float | None) -> float | None:
    """``Δt% = (t_new − t_ref)/t_ref · 100`` (eqs. 36, 46); None if either time is None."""
    if t_new is None or t_ref is None:
        return None
    return (t_new - t_ref) / t_ref * 100.0


def crossing_table(
    new: DriftResult, ref: DriftResult
) -> list[tuple[float, float | None, float | None, float | None]]:
    """Rows ``(threshold, t_new, t_ref, Δt%)`` in the layout of the thesis' Tables 7, 8, 15."""
    if new.thresholds != ref.thresholds:
        raise InputError("crossing_table: the two results use different thresholds")
    return [
        (th, a, b, delta_t_percent(a, b))
        for th, a, b in zip(new.thresholds, new.crossing_times, ref.crossing_times, strict=True)
    ]


__all__ = [
    "DEFAULT_THRESHOLDS",
    "DriftResult",
    "crossing_table",
    "dcm_to_quat",
    "delta_t_percent",
    "drift",
    "euler_to_quat",
    "plot_drift",
    "propagate",
    "quat_to_dcm",
    "quat_to_euler",
    "rotation_angle",
]
