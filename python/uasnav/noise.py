"""IMU noise identification from Allan curves, and the noise a Kalman filter needs.

:func:`identify` turns an :class:`~uasnav.allan.AllanResult` into a :class:`NoiseReport`:
the five IEEE Std 952 terms per axis from a non-negative maximum-likelihood fit of the whole
curve (the primary result) with a 95 % confidence interval per term, a verdict per term
(identifiable, or not and why), plus the classic single-point readings as a cross-check.

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
from typing import Literal, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import optimize

from uasnav import _core
from uasnav.errors import InputError, UnitError
from uasnav.units import convert, dimension, parse_quantity


class AllanCurve(Protocol):
    """What the noise fit reads from an Allan curve (:class:`uasnav.allan.AllanResult` is one).

    Stated here rather than imported: ``allan`` imports this module for ``AllanResult.identify``,
    so this module depends on the shape of a curve, not on the ``allan`` module.
    """

    @property
    def taus(self) -> NDArray[np.float64]:
        """Cluster times τ (k,) in s."""
        ...

    @property
    def avar(self) -> NDArray[np.float64]:
        """Allan variance (k,) or (k, c), in ``unit`` squared."""
        ...

    @property
    def rel_error(self) -> NDArray[np.float64]:
        """IEEE 952 relative error of σ(τ) per τ (k,)."""
        ...

    @property
    def m(self) -> NDArray[np.int64]:
        """Cluster sizes (samples) per τ (k,)."""
        ...

    @property
    def n_samples(self) -> int:
        """Samples in the series."""
        ...

    @property
    def unit(self) -> str:
        """Unit of the data ("rad/s", "m/s^2" …; "" if not given)."""
        ...


TERMS = ("quantization", "random_walk", "bias_instability", "rate_random_walk", "rate_ramp")

#: Least number of τ points the five-term fit is made on.
MIN_FIT_POINTS = 5

#: Relative model error of σ(τ) assumed at every point (real sensors deviate from the five ideal
#: slopes: anti-alias filters, flicker bending the floor). It caps the weight of the shortest τ,
#: averaged from millions of differences (σ² then has at most 200 degrees of freedom).
MODEL_ERROR_FLOOR = 0.05

#: Confidence level of the per-term intervals, and the χ²₁ quantile at that level (profile
#: likelihood: a deviance rise of 3.84 bounds a single parameter at 95 %).
CONFIDENCE = 0.95
_CHI2_1 = 3.841458820694124

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
    curve : AllanCurve
        The curve the terms were read from.
    fit_min_tau_s : ndarray, shape (c,)
        Shortest cluster time (s) used per axis (longer than the curve's first when points
        flattened by an anti-alias filter were left out; see :func:`identify`).
    ci_low, ci_high : NoiseTerms
        Profile-likelihood confidence interval (level ``confidence``) of each fitted term
        (see :func:`identify`); both 0 on axes whose fit was skipped.
    identifiable : ndarray of bool, shape (5, c)
        Per term (order of :data:`TERMS`) and axis: the data demand the term, i.e. its
        confidence interval excludes 0.
    reasons : tuple of (axis, term, reason)
        Why each term that is not identifiable is not (one entry per such axis × term).
    fit_skipped : tuple of str, length c
        Per axis: ``""`` if the five-term fit was made, else why not (fewer than 5 τ points,
        no noise above the resolution …); the Allan deviations themselves are still valid.
    confidence : float
        Confidence level of ``ci_low``/``ci_high`` (0.95).
    """

    fit: NoiseTerms
    points: NoiseTerms
    fit_rms_rel_residual: NDArray[np.float64]
    curve: AllanCurve = field(repr=False)
    fit_min_tau_s: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    ci_low: NoiseTerms | None = None
    ci_high: NoiseTerms | None = None
    identifiable: NDArray[np.bool_] = field(default_factory=lambda: np.zeros((5, 0), dtype=bool))
    reasons: tuple[tuple[int, str, str], ...] = ()
    fit_skipped: tuple[str, ...] = ()
    confidence: float = CONFIDENCE

    def reason(self, axis: int, term: str) -> str | None:
        """Why ``term`` is not identifiable on ``axis`` (None if it is)."""
        NoiseTerms._check(term)
        for ax, t, why in self.reasons:
            if ax == axis and t == term:
                return why
        return None

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
        """Rows (axis × term): the fit with its confidence interval (field units), whether the
        term is identifiable and why not, and the point reading, in SI and field units."""
        rows: list[dict[str, object]] = []
        for ax in range(self.fit.random_walk.size):
            for term in TERMS:
                fv, fu = self.fit.field(term)
                pv, _ = self.points.field(term)
                missing = (ax, term) in self.points.missing
                lo = None if self.ci_low is None else float(self.ci_low.field(term)[0][ax])
                hi = None if self.ci_high is None else float(self.ci_high.field(term)[0][ax])
                why = self.reason(ax, term)
                rows.append(
                    {
                        "axis": ax,
                        "term": term,
                        "fit_si": float(getattr(self.fit, term)[ax]),
                        "si_unit": self.fit.si_unit(term),
                        "fit_field": float(fv[ax]),
                        "field_unit": fu,
                        "ci_low_field": lo,
                        "ci_high_field": hi,
                        "identifiable": why is None,
                        "not_identifiable_reason": why,
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
    curve: AllanCurve,
    kind: Literal["gyro", "accel"] | None = None,
    *,
    min_tau: float | Literal["auto"] | None = "auto",
) -> NoiseReport:
    """Identify IEEE 952 noise terms from an Allan curve.

    Parameters
    ----------
    curve : AllanCurve
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

    Notes
    -----
    Each Allan point σ²ᵢ is taken as μᵢ·χ²_ν/ν (μ the five-term model, ν its equivalent degrees
    of freedom: NIST SP 1065 Table 5 for the term that dominates μᵢ, mixed by their shares,
    with a 5 % model error of σ added), and the squared coefficients c ≥ 0 maximise that
    likelihood (iteratively reweighted non-negative least squares). Quantisation and rate
    ramp are kept only where dropping them raises the deviance by χ²₁(95 %) = 3.84 or more,
    so that a few long-τ points cannot trade a rate random walk for a ramp. The interval of
    each term is its profile likelihood interval (deviance within 3.84 of the best, the other
    terms refitted); a term is identifiable when that interval excludes 0, and otherwise
    ``reasons`` says why (consistent with zero and where it could show; not required; fit
    skipped). The points are treated as independent, which octave-spaced overlapping
    estimates nearly are; on 2 h simulated logs the intervals contain the true ARW and RRW on
    about 90–100 % of axes.

    An axis whose σ(τ) is 0 everywhere (constant output), or that has fewer than 5 τ points
    with σ > 0, is not fitted: ``fit_skipped`` gives the reason and the curve stays valid.
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
    ntau = curve.taus.size
    fit_vals = np.zeros((5, ncol))
    lo_vals = np.zeros((5, ncol))
    hi_vals = np.zeros((5, ncol))
    ident = np.zeros((5, ncol), dtype=bool)
    pt_vals = np.zeros((5, ncol))
    rms = np.zeros(ncol)
    missing: list[tuple[int, str]] = []
    reasons: list[tuple[int, str, str]] = []
    skipped: list[str] = []
    used = np.zeros(ncol)
    for j in range(ncol):
        if min_tau == "auto":
            k = band_limited_points(curve.taus, np.sqrt(avar[:, j]), curve.rel_error)
            if ntau - k < MIN_FIT_POINTS:
                k = 0  # too few points left to cut any: fit them all
        elif min_tau is None:
            k = 0
        else:
            if not (isinstance(min_tau, (int, float)) and np.isfinite(min_tau) and min_tau >= 0):
                raise InputError(
                    f"min_tau: expected a non-negative number of seconds, 'auto' or None, got {min_tau!r}"
                )
            k = int(np.searchsorted(curve.taus, float(min_tau) * (1 - 1e-12)))
            if ntau - k < MIN_FIT_POINTS:
                raise InputError(
                    f"min_tau={min_tau}: leaves {ntau - k} τ points; the fit needs {MIN_FIT_POINTS}"
                )
        taus, rel, col, m = curve.taus[k:], curve.rel_error[k:], avar[k:, j], curve.m[k:]
        used[j] = taus[0]
        # σ² = 0 (a constant or quantisation-limited output) has no log-log slope: such points
        # are left out of both the point readings and the fit.
        pos = col > 0
        readings: tuple = (None,) * 5
        if np.count_nonzero(pos) >= 2:
            readings = _core.noise_read_points(
                np.ascontiguousarray(taus[pos]), np.ascontiguousarray(col[pos]), rel[pos]
            )
        for i, (name, rd) in enumerate(zip(TERMS, readings, strict=True)):
            if rd is None:
                missing.append((j, name))
            else:
                pt_vals[i, j] = rd[0]
        # The likelihood treats the points as independent: true of octave-spaced overlapping
        # estimates to a good approximation, far from it for denser spacings ("all": 10⁴
        # nearly identical points would give absurdly narrow intervals, and take minutes).
        sel = np.flatnonzero(pos)
        sel = sel[_octave_subset(m[sel])]
        why_skip = _skip_reason(avar[:, j], col, pos, sel.size)
        skipped.append(why_skip)
        if why_skip:
            reasons.extend((j, name, why_skip) for name in TERMS)
            continue
        ax = _fit_axis(taus[sel], col[sel], m[sel], curve.n_samples)
        fit_vals[:, j], lo_vals[:, j], hi_vals[:, j] = ax.coeffs, ax.lo, ax.hi
        ident[:, j] = ax.identifiable
        w = 1.0 / np.maximum(rel[sel], MODEL_ERROR_FLOOR) ** 2
        r = (_basis(taus[sel]) @ ax.coeffs**2) / col[sel] - 1.0
        rms[j] = float(np.sqrt(np.sum(w * r * r) / np.sum(w)))
        for i, name in enumerate(TERMS):
            if not ax.identifiable[i]:
                reasons.append((j, name, _why(kind, i, ax, taus[sel])))
    fit = NoiseTerms(kind, "ieee952-fit", *fit_vals)
    points = NoiseTerms(kind, "slope-points", *pt_vals, missing=tuple(missing))
    return NoiseReport(
        fit=fit,
        points=points,
        fit_rms_rel_residual=rms,
        curve=curve,
        fit_min_tau_s=used,
        ci_low=NoiseTerms(kind, "ieee952-fit-ci-low", *lo_vals),
        ci_high=NoiseTerms(kind, "ieee952-fit-ci-high", *hi_vals),
        identifiable=ident,
        reasons=tuple(reasons),
        fit_skipped=tuple(skipped),
        confidence=CONFIDENCE,
    )


# --------------------------------------------------------------------------------------------
# The five-term fit: maximum likelihood on the χ² distribution of the Allan points
# --------------------------------------------------------------------------------------------

_BI2 = 2.0 * np.log(2.0) / np.pi  # (0.664)²: flat-floor level of σ² for unit bias instability
_QUANT, _WHITE, _BIAS, _RRW, _RAMP = range(5)
# Terms the fit keeps only when the data demand them (a deviance rise ≥ χ²₁(95 %) without
# them): quantisation and rate ramp sit at the ends of the curve, where a few points with a
# handful of degrees of freedom would otherwise trade a rate random walk for a ramp (the
# simulated AX1 log: RRW 30 deg/h/√h read as 0 with a ramp on two axes).
_OPTIONAL = (_RAMP, _QUANT)


def _basis(t: NDArray[np.float64]) -> NDArray[np.float64]:
    """σ² basis of the five terms (coefficients squared multiply it), shape (k, 5)."""
    return np.stack([3.0 / t**2, 1.0 / t, np.full_like(t, _BI2), t / 3.0, t**2 / 2.0], axis=1)


def _edf_table(n_samples: int, m: NDArray[np.int64]) -> NDArray[np.float64]:
    """EDF of each point if the term of each column dominated, shape (k, 5).

    NIST SP 1065 Table 5 (the same approximations as :func:`uasnav.allan.oadev`'s ``edf``,
    repeated here because ``allan`` imports this module): white FM for Q and N, flicker FM
    for B, random-walk FM for K and R.
    """
    n = float(n_samples + 1)  # phase points
    mf = m.astype(np.float64)
    white = (3.0 * (n - 1.0) / (2.0 * mf) - 2.0 * (n - 2.0) / n) * (4.0 * mf**2 / (4.0 * mf**2 + 5.0))
    flicker = np.where(mf == 1, 2.0 * (n - 2.0) / (2.3 * n - 4.9), 5.0 * n**2 / (4.0 * mf * (n + 3.0 * mf)))
    rw = (n - 2.0) / (mf * (n - 3.0) ** 2) * ((n - 1.0) ** 2 - 3.0 * mf * (n - 1.0) + 4.0 * mf**2)
    return np.maximum(np.stack([white, white, flicker, rw, rw], axis=1), 1.0)


def _nu(edf: NDArray[np.float64], f: NDArray[np.float64], c: NDArray[np.float64]) -> NDArray[np.float64]:
    """Degrees of freedom of each σ² under model ``c``: the EDF of the terms mixed by their share
    of σ², then the model-error floor added in quadrature (relative variance of σ² is 2/ν)."""
    parts = f * c
    tot = parts.sum(axis=1)
    frac = parts / np.where(tot > 0, tot, 1.0)[:, None]
    inv = np.where(tot > 0, (frac / edf).sum(axis=1), 1.0 / edf[:, _WHITE])
    return 2.0 / (2.0 * inv + (2.0 * MODEL_ERROR_FLOOR) ** 2)


def _deviance(y: NDArray[np.float64], mu: NDArray[np.float64], nu: NDArray[np.float64]) -> float:
    """Deviance of σ² ~ μ·χ²_ν/ν (a Gamma law): ν·Σ(y/μ − 1 − ln(y/μ))."""
    r = y / mu
    return float(np.sum(nu * (r - 1.0 - np.log(r))))


def _ml_fit(
    f: NDArray[np.float64],
    y: NDArray[np.float64],
    edf: NDArray[np.float64],
    free: NDArray[np.bool_],
    fixed: tuple[int, float] | None = None,
    start: NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.float64], float]:
    """Squared coefficients c ≥ 0 maximising the χ² likelihood of the Allan points.

    Iteratively reweighted non-negative least squares (Fisher scoring of the Gamma law with
    identity link: weights ν/μ² from the previous model). Terms not ``free`` stay 0;
    ``fixed = (j, v)`` holds term j at v (for profile likelihood intervals).
    """
    free = free.copy()
    c = np.zeros(5) if start is None else start.copy()
    off = np.zeros_like(y)
    if fixed is not None:
        free[fixed[0]] = False
        c[fixed[0]] = fixed[1]
        off = f[:, fixed[0]] * fixed[1]
    c[~free & (np.arange(5) != (fixed[0] if fixed else -1))] = 0.0
    mu = y.copy() if start is None else np.maximum(f @ c, 1e-9 * y)
    nu = _nu(edf, f, c) if start is not None else 2.0 / (2.0 / edf[:, _WHITE] + (2 * MODEL_ERROR_FLOOR) ** 2)
    last = np.inf
    dev = np.inf
    for _ in range(50):
        w = np.sqrt(nu / 2.0) / mu
        a = f[:, free] * w[:, None]
        scale = np.linalg.norm(a, axis=0)
        scale[scale == 0] = 1.0
        x, _ = optimize.nnls(a / scale, (y - off) * w)
        c[free] = x / scale
        # floor far below the data: a zero model (all terms 0) must not give infinite weights
        mu = np.maximum(f @ c, 1e-9 * y)
        nu = _nu(edf, f, c)
        dev = _deviance(y, mu, nu)
        if abs(last - dev) <= 1e-7 * (1.0 + dev):
            break
        last = dev
    return c, dev


def _profile_bounds(
    f: NDArray[np.float64],
    y: NDArray[np.float64],
    edf: NDArray[np.float64],
    free: NDArray[np.bool_],
    c: NDArray[np.float64],
    dev0: float,
    i: int,
) -> tuple[float, float]:
    """Profile-likelihood interval of squared coefficient i: the values whose best fit of the
    other terms raises the deviance by less than χ²₁(95 %). ``inf`` if no upper bound is found."""

    def excess(v: float) -> float:
        return _ml_fit(f, y, edf, free, fixed=(i, v), start=c)[1] - dev0 - _CHI2_1

    lo = 0.0
    if c[i] > 0 and excess(0.0) > 0:
        a, b = 0.0, c[i]
        for _ in range(30):
            mid = 0.5 * (a + b)
            a, b = (mid, b) if excess(mid) > 0 else (a, mid)
        lo = b
    # upper bound: double until outside, then bisect geometrically
    a = c[i]
    b = 2.0 * c[i] if c[i] > 0 else 1e-3 * float(np.min(y / f[:, i]))
    for _ in range(80):
        if excess(b) > 0:
            break
        a, b = b, 2.0 * b
    else:
        return lo, np.inf
    for _ in range(16):
        mid = np.sqrt(a * b) if a > 0 else 0.5 * b
        a, b = (mid, b) if excess(mid) <= 0 else (a, mid)
    return lo, b


@dataclass(frozen=True)
class _AxisFit:
    coeffs: NDArray[np.float64]  # (5,) SI, square roots of the fitted c
    lo: NDArray[np.float64]
    hi: NDArray[np.float64]
    identifiable: NDArray[np.bool_]
    dropped: NDArray[np.bool_]  # optional terms the data did not demand
    drop_gain: NDArray[np.float64]  # deviance rise if a dropped term were required to be 0 …
    squared: NDArray[np.float64]  # fitted c (SI²)
    edf_last: float


def _fit_axis(taus: NDArray[np.float64], y: NDArray[np.float64], m: NDArray[np.int64], n: int) -> _AxisFit:
    """Maximum-likelihood five-term fit of one axis with 95 % profile intervals per term."""
    f = _basis(taus)
    edf = _edf_table(n, m)
    free = np.ones(5, dtype=bool)
    c, dev = _ml_fit(f, y, edf, free)
    gain = np.zeros(5)
    for i in _OPTIONAL:
        trial = free.copy()
        trial[i] = False
        c2, dev2 = _ml_fit(f, y, edf, trial)
        gain[i] = dev2 - dev
        if dev2 - dev < _CHI2_1:
            free, c, dev = trial, c2, dev2
    lo, hi = np.zeros(5), np.zeros(5)
    for i in range(5):
        if free[i]:
            lo[i], hi[i] = _profile_bounds(f, y, edf, free, c, dev, i)
        else:
            # bound of a dropped term: profile it with the term let back in
            allowed = free.copy()
            allowed[i] = True
            c_a, dev_a = _ml_fit(f, y, edf, allowed, start=c)
            hi[i] = _profile_bounds(f, y, edf, allowed, c_a, dev_a, i)[1]
    nu_last = float(_nu(edf, f, c)[-1])
    return _AxisFit(
        coeffs=np.sqrt(c),
        lo=np.sqrt(lo),
        hi=np.sqrt(hi),
        identifiable=free & (lo > 0),
        dropped=~free,
        drop_gain=gain,
        squared=c,
        edf_last=nu_last,
    )


def _octave_subset(m: NDArray[np.int64]) -> NDArray[np.int64]:
    """Indices of an increasing run of cluster sizes, each at least twice the previous one."""
    keep: list[int] = []
    for i, mi in enumerate(m):
        if not keep or mi >= 2 * m[keep[-1]]:
            keep.append(i)
    return np.asarray(keep, dtype=np.int64)


def _skip_reason(
    whole: NDArray[np.float64], used: NDArray[np.float64], pos: NDArray[np.bool_], n_octave: int
) -> str:
    """Why the five-term fit cannot be made on one axis ("" if it can)."""
    if not np.any(whole > 0):
        return "no noise above resolution: σ(τ) = 0 at every τ (constant or quantisation-limited output)"
    if used.size < MIN_FIT_POINTS:
        return f"only {used.size} τ points; the five-term fit needs at least {MIN_FIT_POINTS}"
    npos = int(np.count_nonzero(pos))
    if npos < MIN_FIT_POINTS:
        return (
            f"only {npos} of {used.size} τ points have σ(τ) > 0 (quantisation-limited output); "
            f"the five-term fit needs at least {MIN_FIT_POINTS}"
        )
    if n_octave < MIN_FIT_POINTS:
        return (
            f"only {n_octave} τ points at least an octave apart (closer ones are strongly "
            f"correlated); the five-term fit needs at least {MIN_FIT_POINTS}"
        )
    return ""


def _why(kind: str, i: int, ax: _AxisFit, taus: NDArray[np.float64]) -> str:
    """One sentence: why term i is not identifiable on this axis."""
    name = TERMS[i]
    unit = FIELD_UNITS[kind][name]
    hi = float(convert(ax.hi[i], SI_UNITS[kind][name], unit)) if np.isfinite(ax.hi[i]) else np.inf
    bound = f"95 % upper bound {hi:.3g} {unit}" if np.isfinite(hi) else "no upper bound"
    if ax.dropped[i]:
        return (
            f"not required by the data (the fit without it is worse by Δdeviance "
            f"{ax.drop_gain[i]:.2f} < {_CHI2_1:.2f}); {bound}"
        )
    # Where would the term, at its upper bound, stand above the other fitted terms?
    grid = np.geomspace(taus[0] / 1e4, taus[-1] * 1e4, 400)
    fg = _basis(grid)
    others = fg @ np.where(np.arange(5) == i, 0.0, ax.squared)
    term = fg[:, i] * (ax.hi[i] ** 2 if np.isfinite(ax.hi[i]) else 0.0)
    above = term > others
    inside = (grid >= taus[0]) & (grid <= taus[-1])
    head = f"consistent with 0 ({bound})"
    if not np.any(above & inside):
        if i in (_QUANT, _WHITE):
            tail = (
                f"below the other terms at every τ ≥ {taus[0]:.3g} s: shorter cluster times "
                "(a higher sample rate) would be needed"
            )
        else:
            later = grid[above & (grid > taus[-1])]
            tail = f"below the other terms at every τ ≤ {taus[-1]:.3g} s" + (
                f": a longer log is needed (it could show beyond τ ≈ {later[0]:.3g} s)"
                if later.size
                else ", and at longer τ the fitted rising terms would hide it too"
            )
        return f"{head}: {tail}"
    span = grid[above & inside]
    return (
        f"{head}: it could dominate only on τ ≈ {span[0]:.3g}–{span[-1]:.3g} s, where the Allan "
        f"points are too few and too uncertain (EDF ≈ {ax.edf_last:.1f} at the longest τ) to tell "
        "it from the neighbouring terms"
    )


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
        for rep in (gyro, accel):
            if rep.fit_skipped and all(rep.fit_skipped):
                # a filter tuned with zero noise would trust the sensor blindly: refuse
                raise InputError(f"from_reports: no {rep.kind} noise fit ({rep.fit_skipped[0]})")
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
    "AllanCurve",
    "FilterNoise",
    "NoiseReport",
    "NoiseTerms",
    "band_limited_points",
    "identify",
]
