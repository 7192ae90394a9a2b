"""The in-memory IMU recording: :class:`ImuLog`.

One type for every source (CSV v1, simulator, PX4, ArduPilot …). Arrays are float64 in SI
units, body frame (x forward, y right, z down):

========  ============  =====================================
field     shape         unit
========  ============  =====================================
t         (n,)          s, strictly increasing
gyro      (n, 3)        rad/s
accel     (n, 3)        m/s² (specific force)
temp      (n,) or None  °C (die temperature of the sensor)
mag       (n, 3)|None   µT
truth     dict          ground-truth channels of simulated logs
========  ============  =====================================

``truth`` keys used across uasnav: ``gyro_bias`` (n, 3) rad/s, ``accel_bias`` (n, 3) m/s²,
``attitude`` (n, 4) quaternion body → NED, scalar first; the simulator (:mod:`uasnav.sim`)
adds ``rate_true`` (n, 3) rad/s, ``specific_force_true`` (n, 3) m/s², ``gyro_bias_thermal``
(n, 3) rad/s, ``temp_die`` and ``temp_chamber`` (n,) °C.

``meta`` holds sensor metadata (``preset``/``source``, ``format``, ``rate_hz``, ``frame``,
``mounting`` …). Helpers: :meth:`ImuLog.slice`, :meth:`ImuLog.between`,
:meth:`ImuLog.segments` (e.g. the static intervals of :func:`uasnav.stationary.detect_static`)
and :meth:`ImuLog.resample`.

Files are read and written by :mod:`uasnav.io` (one module per format), which also holds the
flight telemetry type beside this one, :class:`uasnav.io.flight.Flight`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uasnav.errors import InputError
from uasnav.limits import check_count

FloatArray = NDArray[np.float64]


def _to_float(name: str, value: Any) -> FloatArray:
    """``value`` as a float64 array; :class:`InputError` naming ``name`` if it is not numeric."""
    if isinstance(value, str | bytes) or value is None:
        raise InputError(f"{name}: expected an array of numbers, got {type(value).__name__}")
    try:
        return np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as e:
        # ragged lists, strings, complex numbers, objects: say which field, not numpy's words only
        raise InputError(f"{name}: expected an array of real numbers ({e})") from None


def _as_float_array(name: str, value: Any, shape_tail: tuple[int, ...], n: int | None) -> FloatArray:
    arr = _to_float(name, value)
    if arr.ndim != 1 + len(shape_tail) or arr.shape[1:] != shape_tail:
        want = "(n" + "".join(f", {d}" for d in shape_tail) + ")"
        raise InputError(f"{name}: expected shape {want}, got {arr.shape}")
    if n is not None and arr.shape[0] != n:
        raise InputError(f"{name}: expected {n} rows (one per time stamp), got {arr.shape[0]}")
    bad = ~np.isfinite(arr)
    if bad.any():
        idx = np.argwhere(bad)[0]
        where = f"row {idx[0]}" + (f", column {idx[1]}" if arr.ndim > 1 else "")
        raise InputError(f"{name}: non-finite value (NaN or inf) at {where}")
    return arr


def _number(name: str, value: Any) -> float:
    """``value`` as a float; :class:`InputError` naming ``name`` if it is not a real number."""
    if isinstance(value, bool | str | bytes) or value is None:
        raise InputError(f"{name}: expected a number, got {value!r}")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a number, got {type(value).__name__}") from None


def require_log(obj: Any, name: str = "log") -> ImuLog:
    """``obj`` if it is an :class:`ImuLog`, else :class:`InputError` naming ``name`` and what was
    given (instead of an ``AttributeError`` deep inside a computation).

    Examples
    --------
    >>> require_log("flight.csv")
    Traceback (most recent call last):
    ...
    uasnav.errors.InputError: log: expected an ImuLog (read a file with uasnav.io.read_log), got str
    """
    if isinstance(obj, ImuLog):
        return obj
    raise InputError(
        f"{name}: expected an ImuLog (read a file with uasnav.io.read_log), got {type(obj).__name__}"
    )


def check_time(t: FloatArray, name: str = "t") -> None:
    """Raise :class:`InputError` unless ``t`` is strictly increasing (names the first bad row)."""
    if t.size >= 2:
        d = np.diff(t)
        bad = np.flatnonzero(d <= 0)
        if bad.size:
            i = int(bad[0]) + 1
            kind = "duplicated" if d[bad[0]] == 0 else "decreasing"
            raise InputError(
                f"{name}: {kind} time stamp at row {i} ({float(t[i - 1])!r} then {float(t[i])!r})"
            )


#: Absolute zero (°C): no die temperature is below it.
ABSOLUTE_ZERO_C = -273.15
#: Highest die temperature taken as data (°C): MEMS dies are specified to 85–125 °C and solder
#: melts near 220 °C; 1000 °C is a unit error, not a temperature.
MAX_DIE_TEMP_C = 1000.0


@dataclass(frozen=True)
class ImuLog:
    """An IMU recording in SI units (see the module docs for shapes and units).

    The constructor validates shapes, finiteness and strictly increasing time, so an
    ``ImuLog`` that exists is usable.
    """

    t: FloatArray
    gyro: FloatArray
    accel: FloatArray
    temp: FloatArray | None = None
    mag: FloatArray | None = None
    truth: dict[str, FloatArray] = field(default_factory=dict)
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not isinstance(self.truth, Mapping):
            raise InputError(f"truth: expected a mapping of name → array, got {type(self.truth).__name__}")
        if not isinstance(self.meta, Mapping):
            raise InputError(f"meta: expected a mapping of name → value, got {type(self.meta).__name__}")
        for k in self.truth:
            if not isinstance(k, str) or not k:
                raise InputError(f"truth: channel names must be non-empty strings, got {k!r}")
        t = _as_float_array("t", self.t, (), None)
        if t.size < 2:
            raise InputError(f"t: need at least 2 samples, got {t.size}")
        check_time(t)
        n = t.size
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "gyro", _as_float_array("gyro", self.gyro, (3,), n))
        object.__setattr__(self, "accel", _as_float_array("accel", self.accel, (3,), n))
        if self.temp is not None:
            temp = _as_float_array("temp", self.temp, (), n)
            bad = np.flatnonzero((temp < ABSOLUTE_ZERO_C) | (temp > MAX_DIE_TEMP_C))
            if bad.size:  # a corrupt or mis-scaled column (K, m°C), not a temperature in °C
                i = int(bad[0])
                raise InputError(
                    f"temp: {temp[i]:g} °C at row {i} is outside "
                    f"{ABSOLUTE_ZERO_C:g}…{MAX_DIE_TEMP_C:g} °C "
                    "(absolute zero to beyond any working sensor die)"
                )
            object.__setattr__(self, "temp", temp)
        if self.mag is not None:
            object.__setattr__(self, "mag", _as_float_array("mag", self.mag, (3,), n))
        truth = {}
        for k, v in self.truth.items():
            arr = _to_float(f"truth[{k!r}]", v)
            truth[k] = _as_float_array(f"truth[{k!r}]", arr, arr.shape[1:], n)
        object.__setattr__(self, "truth", truth)

    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.t.size)

    @property
    def duration(self) -> float:
        """Time span ``t[-1] - t[0]`` (s)."""
        return float(self.t[-1] - self.t[0])

    @property
    def sample_rate(self) -> float:
        """Sample rate (Hz) from the median time step."""
        return float(1.0 / np.median(np.diff(self.t)))

    def uniform_rate(self, rtol: float = 0.01) -> float:
        """Sample rate (Hz) if every step is within ``rtol`` of the median, else InputError."""
        d = np.diff(self.t)
        med = float(np.median(d))
        worst = int(np.argmax(np.abs(d - med)))
        if abs(d[worst] - med) > rtol * med:
            raise InputError(
                f"t: sampling is not uniform (step {d[worst]:.6g} s at row {worst + 1} vs median "
                f"{med:.6g} s); resample first or pass the rate explicitly"
            )
        return 1.0 / med

    def slice(self, start: int, stop: int) -> ImuLog:
        """Samples ``start:stop`` as a new log (truth channels sliced alike)."""

        def cut(a: FloatArray | None) -> FloatArray | None:
            return None if a is None else a[start:stop]

        return ImuLog(
            t=self.t[start:stop],
            gyro=self.gyro[start:stop],
            accel=self.accel[start:stop],
            temp=cut(self.temp),
            mag=cut(self.mag),
            truth={k: v[start:stop] for k, v in self.truth.items()},
            meta=dict(self.meta),
        )

    def between(self, t_start: float, t_end: float) -> ImuLog:
        """Samples with ``t_start <= t <= t_end`` (s) as a new log (at least 2 samples)."""
        t_start, t_end = _number("t_start", t_start), _number("t_end", t_end)
        i0 = int(np.searchsorted(self.t, t_start, side="left"))
        i1 = int(np.searchsorted(self.t, t_end, side="right"))
        if i1 - i0 < 2:
            raise InputError(
                f"between({t_start!r}, {t_end!r}): fewer than 2 samples in the interval "
                f"(log spans {float(self.t[0])!r} … {float(self.t[-1])!r} s)"
            )
        return self.slice(i0, i1)

    def segments(self, intervals: list[tuple[float, float]], min_samples: int = 2) -> list[ImuLog]:
        """One log per ``(t_start, t_end)`` interval (e.g. static intervals); intervals with
        fewer than ``min_samples`` samples are skipped."""
        out = []
        for a, b in intervals:
            i0 = int(np.searchsorted(self.t, a, side="left"))
            i1 = int(np.searchsorted(self.t, b, side="right"))
            if i1 - i0 >= max(2, min_samples):
                out.append(self.slice(i0, i1))
        return out

    def resample(self, rate: float, t_start: float | None = None) -> ImuLog:
        """Linear interpolation of every channel (truth included) onto a uniform grid.

        Parameters
        ----------
        rate : float
            New sample rate (Hz).
        t_start : float, optional
            First time stamp (default the log's first).

        Notes
        -----
        No anti-alias filter is applied: when down-sampling noisy data, low-pass first.
        Quaternion truth channels (4 columns named ``attitude``) are re-normalised.
        """
        rate = _number("rate", rate)
        if not (np.isfinite(rate) and rate > 0):
            raise InputError(f"rate: must be a positive number of Hz, got {rate!r}")
        t0 = float(self.t[0]) if t_start is None else _number("t_start", t_start)
        if not np.isfinite(t0):
            raise InputError(f"t_start: must be a finite time in s, got {t0!r}")
        # bytes per output sample: time, gyro, accel, temp, mag and every truth channel
        per_sample = 8 * (11 + sum(v[0].size for v in self.truth.values()))
        check_count(float((self.t[-1] - t0) * rate), per_sample, f"resample at {rate:g} Hz", option="rate")
        n = int(np.floor((self.t[-1] - t0) * rate + 1e-9)) + 1
        if n < 2 or t0 < self.t[0]:
            raise InputError(f"resample: no room for 2 samples at {rate} Hz from t = {t0}")
        t = t0 + np.arange(n) / rate

        def interp(a: FloatArray | None) -> FloatArray | None:
            if a is None:
                return None
            if a.ndim == 1:
                return np.interp(t, self.t, a)
            flat = a.reshape(a.shape[0], -1)
            out = np.column_stack([np.interp(t, self.t, flat[:, j]) for j in range(flat.shape[1])])
            return out.reshape((n, *a.shape[1:]))

        truth = {k: interp(v) for k, v in self.truth.items()}
        if "attitude" in truth and truth["attitude"] is not None and truth["attitude"].shape[1:] == (4,):
            q = truth["attitude"]
            truth["attitude"] = q / np.linalg.norm(q, axis=1, keepdims=True)
        meta = dict(self.meta)
        meta["rate_hz"] = float(rate)
        gyro, accel = interp(self.gyro), interp(self.accel)
        assert gyro is not None and accel is not None
        return ImuLog(
            t=t,
            gyro=gyro,
            accel=accel,
            temp=interp(self.temp),
            mag=interp(self.mag),
            truth={k: v for k, v in truth.items() if v is not None},
            meta=meta,
        )


__all__ = ["ImuLog", "check_time", "require_log"]
