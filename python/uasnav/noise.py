"""IMU noise identification from Allan curves, and the noise a Kalman filter needs.

:func:`identify` turns an :class:`~uasnav.allan.AllanResult` into a :class:`NoiseReport`:
the five IEEE Std 952 terms per axis from a weighted non-negative fit of the whole curve
(the primary result), plus the classic single-point readings as a cross-check.

Units are explicit everywhere. Coefficients are stored in SI units of the data's rate unit
``u`` (rad/s for gyros, m/s² for accelerometers):

=================== ================= ==================== ===================
term                symbol / slope    SI unit (gyro)       SI unit (accel)
=================== ================= ==================== ===================
quantization        Q, −1             rad                  m/s
random walk         N, −½ (ARW/VRW)   rad/√s (=rad/s/√Hz)  m/s/√s (=m/s²/√Hz)
bias instability    B, 0              rad/s                m/s²
rate random walk    K, +½             rad/s/√s             m/s²/√s
rate ramp           R, +1             rad/s²               m/s³
=================== ================= ==================== ===================

:meth:`NoiseTerms.to` converts to any field unit with a dimension check
(``terms.to("random_walk", "deg/√h")``), so a bias instability can never be read as an ARW.

From the curve to a filter (:class:`FilterNoise`): white rate noise has the continuous PSD
``N²`` and a per-sample standard deviation ``N/√Δt``; a bias driven by rate random walk grows
by ``K²·Δt`` in variance per step. The thesis' ZUPT filter (eqs. 22–25) uses σ_VRW, σ_ARW,
σ_ABI and σ_GBI directly as the diagonal of Q; :class:`FilterNoise` carries exactly those four
numbers in SI with their units in the field names.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav import _core
from uasnav.errors import InputError, UnitError
from uasnav.units import convert, dimension, parse_quantity

if TYPE_CHECKING:
    # noise.identify reads an AllanResult's fields; allan imports noise for
    # AllanResult.identify, so the type is needed for annotations only.
    from uasnav.allan import AllanResult

TERMS = ("quantization", "random_walk", "bias_instability", "rate_random_walk", "rate_ramp")

# SI unit of each term for gyros (data in rad/s) and accelerometers (data in m/s²).
SI_UNITS = {
    "gyro": {
        "quantization": "rad",
        "random_walk": "rad/√s",
        "bias_instability": "rad/s",
        "rate_random_walk": "rad/s/√s",
        "rate_ramp": "rad/s^2",
    },
    "accel": {
        "quantization": "m/s",
        "random_walk": "m/s/√s",
        "bias_instability": "m/s^2",
        "rate_random_walk": "m/s^2/√s",
        "rate_ramp": "m/s^3",
    },
}

# The units the field quotes (datasheets, the thesis' Tables 3–6).
FIELD_UNITS = {
    "gyro": {
        "quantization": "deg",
        "random_walk": "deg/√h",
        "bias_instability": "deg/h",
        "rate_random_walk": "deg/h/√h",
        "rate_ramp": "deg/h^2",
    },
    "accel": {
        "quantization": "m/s",
        "random_walk": "m/s/√h",
        "bias_instability": "m/s/h",
        "rate_random_walk": "m/s/h/√h",
        "rate_ramp": "m/s/h^2",
    },
}

_KIND_OF_UNIT = {"rad/s": "gyro", "m/s^2": "accel"}


def _kind_from_unit(unit: str) -> Literal["gyro", "accel"]:
    try:
        dim = dimension(unit) if unit else ""
    except UnitError:
        dim = ""
    kind = _KIND_OF_UNIT.get(dim)
    if kind is not None and convert(1.0, unit, dim) != 1.0:
        kind = None  # e.g. deg/s: right dimension, but the coefficients would not be SI
    if kind is None:
        raise InputError(
            f"cannot tell gyro from accelerometer data: unit {unit!r}; pass kind='gyro' or "
            "kind='accel', with the curve computed on rad/s or m/s^2 data"
        )
    return kind  # type: ignore[return-value]


@dataclass(frozen=True)
class NoiseTerms:
    """The five IEEE 952 coefficients per axis, in SI (see the module table).

    Each term is an array of shape (c,), one value per axis; 0 means the term is not
    supported by the data (fit) and NaN is never used: point readings that cannot be made
    are listed in ``missing``.
    """

    kind: Literal["gyro", "accel"]
    method: str
    quantization: NDArray[np.float64]
    random_walk: NDArray[np.float64]
    bias_instability: NDArray[np.float64]
    rate_random_walk: NDArray[np.float64]
    rate_ramp: NDArray[np.float64]
    missing: tuple[tuple[int, str], ...] = ()

    def si_unit(self, term: str) -> str:
        """SI unit of ``term``."""
        return SI_UNITS[self.kind][self._check(term)]

    def to(self, term: str, unit: str) -> NDArray[np.float64]:
        """Values of ``term`` in ``unit`` (dimension-checked; raises UnitError otherwise)."""
        return np.asarray(convert(getattr(self, self._check(term)), self.si_unit(term), unit))

    def field(self, term: str) -> tuple[NDArray[np.float64], str]:
        """``(values, unit)`` of ``term`` in the field's customary unit (deg/√h, deg/h …)."""
        unit = FIELD_UNITS[self.kind][self._check(term)]
        return self.to(term, unit), unit

    @staticmethod
    def _check(term: str) -> str:
        if term not in TERMS:
            raise InputError(f"unknown noise term {term!r}; expected one of {', '.join(TERMS)}")
        return term


@dataclass(frozen=True)
class NoiseReport:
    """Noise identification of one sensor (gyro or accelerometer triad).

    Attributes
    ----------
    fit : NoiseTerms
        Five-term weighted non-negative fit of σ²(τ) (the primary result).
    points : NoiseTerms
        Single-point readings on slope lines (N at 1 s, K at 3 s, B = σ_min/0.664 …).
    fit_rms_rel_residual : ndarray, shape (c,)
        RMS relative residual of the fit in σ², per axis.
    curve : AllanResult
        The curve the terms were read from.
    fit_min_tau_s : ndarray, shape (c,)
        Shortest cluster time (s) used per axis (longer than the curve's first when points
        flattened by an anti-alias filter were left out; see :func:`identify`).
    """

    fit: NoiseTerms
    points: NoiseTerms
    fit_rms_rel_residual: NDArray[np.float64]
    curve: AllanResult = field(repr=False)
    fit_min_tau_s: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))

    @property
    def kind(self) -> Literal["gyro", "accel"]:
        """``"gyro"`` or ``"accel"``."""
        return self.fit.kind

    def model_adev(self, taus: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
        """σ(τ) of the fitted model at ``taus`` (default: the curve's), shape (k, c)."""
        t = self.curve.taus if taus is None else np.asarray(taus, dtype=np.float64)
        f = self.fit
        c = np.stack([getattr(f, name) ** 2 for name in TERMS])  # (5, c)
        basis = np.stack(
            [3.0 / t**2, 1.0 / t, np.full_like(t, 2.0 * np.log(2.0) / np.pi), t / 3.0, t**2 / 2.0]
        )  # (5, k)
        return np.sqrt(basis.T @ c)

    def table(self) -> list[dict[str, object]]:
        """Rows (axis × term) with the fit and the point reading in SI and field units."""
        rows: list[dict[str, object]] = []
        for ax in range(self.fit.random_walk.size):
            for term in TERMS:
                fv, fu = self.fit.field(term)
                pv, _ = self.points.field(term)
                missing = (ax, term) in self.points.missing
                rows.append(
                    {
                        "axis": ax,
                        "term": term,
                        "fit_si": float(getattr(self.fit, term)[ax]),
                        "si_unit": self.fit.si_unit(term),
                        "fit_field": float(fv[ax]),
                        "field_unit": fu,
                        "point_field": None if missing else float(pv[ax]),
                    }
                )
        return rows


def band_limited_points(
    taus: ArrayLike, adev: ArrayLike, rel_error: ArrayLike, slope_tol: float = 0.03
) -> int:
    """Number of leading τ whose σ(τ) is flattened by an anti-alias low-pass filter.

    No IEEE 952 term is shallower than the white noise's τ^(−1/2) at the short-τ end
    (quantisation falls as τ⁻¹; the flat and rising terms dominate only at long τ), so a
    leading run of points whose slope to the next point is shallower than −1/2 by more than
    ``slope_tol`` plus 3σ of the slope's statistical error is the signature of a band-limited
    output (e.g. a 30 Hz filter at 100 Hz: σ(10 ms) is ~45 % low). Those points would pull the
    fit's white-noise coefficient low, so :func:`identify` leaves them out. The run is only
    cut when a white-noise slope follows within the first third of the curve (otherwise the
    curve is not white-noise dominated at short τ and nothing is cut).
    """
    t = np.asarray(taus, dtype=np.float64)
    a = np.asarray(adev, dtype=np.float64)
    e = np.asarray(rel_error, dtype=np.float64)
    for k in range(max(0, t.size // 3)):
        dlog = np.log(t[k + 1] / t[k])
        if not (a[k] > 0 and a[k + 1] > 0 and dlog > 0):
            return 0
        slope = np.log(a[k + 1] / a[k]) / dlog
        margin = slope_tol + 3.0 * np.hypot(e[k], e[k + 1]) / dlog
        if slope <= -0.5 + margin:
            return k
    return 0


def identify(
    curve: AllanResult,
    kind: Literal["gyro", "accel"] | None = None,
    *,
    min_tau: float | Literal["auto"] | None = "auto",
) -> NoiseReport:
    """Identify IEEE 952 noise terms from an Allan curve.

    Parameters
    ----------
    curve : AllanResult
        Computed on gyro data in rad/s or accelerometer data in m/s² (the unit recorded in the
        curve decides the kind unless ``kind`` is given; other units are refused, so
        deg/s data cannot silently produce rad-based coefficients).
    kind : {"gyro", "accel"}, optional
    min_tau : float, "auto" or None
        Shortest cluster time (s) used. ``"auto"`` (default) leaves out, per axis, the
        leading points flattened by an anti-alias filter (:func:`band_limited_points`);
        ``None`` uses every point. The report records what was used (``fit_min_tau_s``).

    Returns
    -------
    NoiseReport
    """
    if kind is None:
        kind = _kind_from_unit(curve.unit)
    elif curve.unit:
        expected = "rad/s" if kind == "gyro" else "m/s^2"
        if dimension(curve.unit) != expected or convert(1.0, curve.unit, expected) != 1.0:
            raise UnitError(
                f"{kind} noise terms need the curve in {expected}, got {curve.unit!r}: "
                "convert the data with uasnav.units first"
            )
    avar = curve.avar if curve.avar.ndim == 2 else curve.avar[:, None]
    ncol = avar.shape[1]
    fit_vals = np.zeros((5, ncol))
    pt_vals = np.zeros((5, ncol))
    rms = np.zeros(ncol)
    missing: list[tuple[int, str]] = []
    used = np.zeros(ncol)
    for j in range(ncol):
        if min_tau == "auto":
            k = band_limited_points(curve.taus, np.sqrt(avar[:, j]), curve.rel_error)
        elif min_tau is None:
            k = 0
        else:
            if not (isinstance(min_tau, (int, float)) and np.isfinite(min_tau) and min_tau >= 0):
                raise InputError(
                    f"min_tau: expected a non-negative number of seconds, 'auto' or None, got {min_tau!r}"
                )
            k = int(np.searchsorted(curve.taus, float(min_tau) * (1 - 1e-12)))
            if curve.taus.size - k < 5:
                raise InputError(
                    f"min_tau={min_tau}: leaves {curve.taus.size - k} cluster times; the fit needs 5"
                )
        taus, rel = curve.taus[k:], curve.rel_error[k:]
        used[j] = taus[0]
        col = np.ascontiguousarray(avar[k:, j])
        coeffs, _active, r = _core.noise_fit_ieee952(taus, col, rel)
        fit_vals[:, j] = coeffs
        rms[j] = r
        readings = _core.noise_read_points(taus, col, rel)
        for i, (name, rd) in enumerate(zip(TERMS, readings, strict=True)):
            if rd is None:
                missing.append((j, name))
            else:
                pt_vals[i, j] = rd[0]
    fit = NoiseTerms(kind, "ieee952-fit", *fit_vals)
    points = NoiseTerms(kind, "slope-points", *pt_vals, missing=tuple(missing))
    return NoiseReport(fit=fit, points=points, fit_rms_rel_residual=rms, curve=curve, fit_min_tau_s=used)


@dataclass(frozen=True)
class FilterNoise:
    """The four noise parameters of the thesis' ZUPT filter Q (eqs. 22–25), in SI.

    Attributes
    ----------
    sigma_vrw_m_s_sqrt_s : float
        Velocity random walk σ_VRW (m/s/√s = m/s²/√Hz): accelerometer white noise.
    sigma_arw_rad_sqrt_s : float
        Angle random walk σ_ARW (rad/√s = rad/s/√Hz): gyro white noise.
    sigma_abi_m_s2 : float
        Accelerometer bias instability σ_ABI (m/s²).
    sigma_gbi_rad_s : float
        Gyro bias instability σ_GBI (rad/s).
    sigma_arrw_m_s2_sqrt_s, sigma_grrw_rad_s_sqrt_s : float
        Rate random walks (m/s²/√s, rad/s/√s), for filters that model the bias as a random
        walk with PSD K².
    """

    sigma_vrw_m_s_sqrt_s: float
    sigma_arw_rad_sqrt_s: float
    sigma_abi_m_s2: float
    sigma_gbi_rad_s: float
    sigma_arrw_m_s2_sqrt_s: float = 0.0
    sigma_grrw_rad_s_sqrt_s: float = 0.0

    def __post_init__(self) -> None:
        for name, v in self.__dict__.items():
            if not (np.isfinite(v) and v >= 0):
                raise InputError(f"{name}: must be finite and >= 0, got {v!r}")

    @classmethod
    def from_reports(cls, gyro: NoiseReport, accel: NoiseReport, axis_reduce: str = "max") -> FilterNoise:
        """From gyro and accelerometer noise reports (fit results; worst axis by default)."""
        if gyro.kind != "gyro" or accel.kind != "accel":
            raise InputError("from_reports: expected (gyro report, accel report)")
        red = {"max": np.max, "mean": np.mean}.get(axis_reduce)
        if red is None:
            raise InputError(f"axis_reduce: expected 'max' or 'mean', got {axis_reduce!r}")
        return cls(
            sigma_vrw_m_s_sqrt_s=float(red(accel.fit.random_walk)),
            sigma_arw_rad_sqrt_s=float(red(gyro.fit.random_walk)),
            sigma_abi_m_s2=float(red(accel.fit.bias_instability)),
            sigma_gbi_rad_s=float(red(gyro.fit.bias_instability)),
            sigma_arrw_m_s2_sqrt_s=float(red(accel.fit.rate_random_walk)),
            sigma_grrw_rad_s_sqrt_s=float(red(gyro.fit.rate_random_walk)),
        )

    @classmethod
    def from_datasheet(cls, *, arw: str, gbi: str, vrw: str, abi: str) -> FilterNoise:
        """From datasheet strings with units, e.g. ``arw="3.18 deg/√h"``, ``gbi="1.5e-4 deg/s"``,
        ``vrw="0.05 m/s/√h"``, ``abi="2 m/s/h"`` (the thesis' Tables 3–4)."""

        return cls(
            sigma_vrw_m_s_sqrt_s=parse_quantity(vrw, "m/s/√s", what="vrw"),
            sigma_arw_rad_sqrt_s=parse_quantity(arw, "rad/√s", what="arw"),
            sigma_abi_m_s2=parse_quantity(abi, "m/s^2", what="abi"),
            sigma_gbi_rad_s=parse_quantity(gbi, "rad/s", what="gbi"),
        )

    def white_sample_std(self, dt_s: float) -> tuple[float, float]:
        """Per-sample standard deviations (gyro rad/s, accel m/s²) of white noise at ``dt_s``:
        ``σ_ARW/√Δt`` and ``σ_VRW/√Δt``."""
        if not dt_s > 0:
            raise InputError(f"dt_s: must be > 0, got {dt_s!r}")
        return self.sigma_arw_rad_sqrt_s / np.sqrt(dt_s), self.sigma_vrw_m_s_sqrt_s / np.sqrt(dt_s)


__all__ = [
    "FIELD_UNITS",
    "SI_UNITS",
    "TERMS",
    "FilterNoise",
    "NoiseReport",
    "NoiseTerms",
    "band_limited_points",
    "identify",
]
