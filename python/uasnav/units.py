"""Named unit conversions for inertial sensors — one table, checked dimensions.

Datasheets and Allan plots mix units (deg/√h, deg/h, mg, µg/√Hz, m/s/√h …); filters need SI.
Every conversion in uasnav goes through :func:`convert`, which refuses to convert between
different dimensions, so "deg/h" can never silently be used as an angle random walk.

Examples
--------
>>> round(convert(3.18, "deg/√h", "rad/√s"), 6)   # CRS05-02 ARW (thesis Table 3)
0.000925
>>> convert(1.0, "g", "m/s^2")
9.80665
>>> parse_quantity("15deg/h", "rad/s") == convert(15.0, "deg/h", "rad/s")  # command-line text
True
"""

from __future__ import annotations

import math
import re

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav.errors import InputError, UnitError

#: Standard gravity (m/s²), the conventional value used for "g" and "mg" units.
STANDARD_GRAVITY = 9.80665
_DEG = math.pi / 180.0
_H = 3600.0

# unit name → (factor to SI, dimension). Dimensions are written in SI base form.
_UNITS: dict[str, tuple[float, str]] = {
    # angle
    "rad": (1.0, "rad"),
    "deg": (_DEG, "rad"),
    "mrad": (1e-3, "rad"),
    # angular rate
    "rad/s": (1.0, "rad/s"),
    "deg/s": (_DEG, "rad/s"),
    "dps": (_DEG, "rad/s"),
    "mdps": (1e-3 * _DEG, "rad/s"),
    "deg/h": (_DEG / _H, "rad/s"),
    "rad/h": (1.0 / _H, "rad/s"),
    # angle random walk (rate noise density)
    "rad/√s": (1.0, "rad/√s"),
    "rad/s/√Hz": (1.0, "rad/√s"),
    "deg/√h": (_DEG / math.sqrt(_H), "rad/√s"),
    "deg/√s": (_DEG, "rad/√s"),
    "deg/s/√Hz": (_DEG, "rad/√s"),
    "deg/h/√Hz": (_DEG / _H, "rad/√s"),
    "mdps/√Hz": (1e-3 * _DEG, "rad/√s"),
    # rate random walk
    "rad/s/√s": (1.0, "rad/s/√s"),
    "deg/s/√s": (_DEG, "rad/s/√s"),
    "deg/h/√h": (_DEG / _H / math.sqrt(_H), "rad/s/√s"),
    "deg/s/√h": (_DEG / math.sqrt(_H), "rad/s/√s"),
    # angular acceleration (rate ramp)
    "rad/s^2": (1.0, "rad/s^2"),
    "deg/s^2": (_DEG, "rad/s^2"),
    "deg/h^2": (_DEG / _H**2, "rad/s^2"),
    "deg/h/h": (_DEG / _H**2, "rad/s^2"),
    # acceleration
    "m/s^2": (1.0, "m/s^2"),
    "g": (STANDARD_GRAVITY, "m/s^2"),
    "mg": (1e-3 * STANDARD_GRAVITY, "m/s^2"),
    "ug": (1e-6 * STANDARD_GRAVITY, "m/s^2"),
    "µg": (1e-6 * STANDARD_GRAVITY, "m/s^2"),
    "m/s/h": (1.0 / _H, "m/s^2"),
    # velocity random walk (acceleration noise density)
    "m/s/√s": (1.0, "m/s/√s"),
    "m/s^2/√Hz": (1.0, "m/s/√s"),
    "m/s/√h": (1.0 / math.sqrt(_H), "m/s/√s"),
    "g/√Hz": (STANDARD_GRAVITY, "m/s/√s"),
    "mg/√Hz": (1e-3 * STANDARD_GRAVITY, "m/s/√s"),
    "ug/√Hz": (1e-6 * STANDARD_GRAVITY, "m/s/√s"),
    "µg/√Hz": (1e-6 * STANDARD_GRAVITY, "m/s/√s"),
    # acceleration random walk
    "m/s^2/√s": (1.0, "m/s^2/√s"),
    "m/s/h/√h": (1.0 / _H / math.sqrt(_H), "m/s^2/√s"),
    "mg/√h": (1e-3 * STANDARD_GRAVITY / math.sqrt(_H), "m/s^2/√s"),
    # jerk (acceleration ramp)
    "m/s^3": (1.0, "m/s^3"),
    "m/s/h^2": (1.0 / _H**2, "m/s^3"),
    # temperature (differences and rates; absolute °C ↔ K is an offset, not handled here)
    "degC": (1.0, "K"),
    "K": (1.0, "K"),
    "degC/s": (1.0, "K/s"),
    "degC/min": (1.0 / 60.0, "K/s"),
    # time, length, speed
    "s": (1.0, "s"),
    "min": (60.0, "s"),
    "h": (_H, "s"),
    "m": (1.0, "m"),
    "ft": (0.3048, "m"),
    "km": (1e3, "m"),
    "m/s": (1.0, "m/s"),
    "km/h": (1.0 / 3.6, "m/s"),
    "kn": (1852.0 / _H, "m/s"),
    "Hz": (1.0, "1/s"),
    # dimensionless ratios (scale factors, misalignment as small angles use "mrad")
    "1": (1.0, "1"),
    "ppm": (1e-6, "1"),
    "%": (1e-2, "1"),
    # temperature coefficients (per kelvin = per °C difference)
    "1/K": (1.0, "1/K"),
    "1/degC": (1.0, "1/K"),
    "ppm/degC": (1e-6, "1/K"),
    "%/degC": (1e-2, "1/K"),
    "rad/s/K": (1.0, "rad/s/K"),
    "deg/s/degC": (_DEG, "rad/s/K"),
    "mdps/degC": (1e-3 * _DEG, "rad/s/K"),
    "deg/h/degC": (_DEG / _H, "rad/s/K"),
    "m/s^2/K": (1.0, "m/s^2/K"),
    "mg/degC": (1e-3 * STANDARD_GRAVITY, "m/s^2/K"),
    "ug/degC": (1e-6 * STANDARD_GRAVITY, "m/s^2/K"),
    # g-sensitivity of gyros (rate error per specific force)
    "rad/s/(m/s^2)": (1.0, "rad·s/m"),
    "deg/s/g": (_DEG / STANDARD_GRAVITY, "rad·s/m"),
    "deg/h/g": (_DEG / _H / STANDARD_GRAVITY, "rad·s/m"),
    # magnetic flux density
    "T": (1.0, "T"),
    "uT": (1e-6, "T"),
    "µT": (1e-6, "T"),
    "G": (1e-4, "T"),
    "gauss": (1e-4, "T"),
    "mG": (1e-7, "T"),
    "mgauss": (1e-7, "T"),
}

# ASCII spellings users type on a command line.
_ALIASES = {"sqrt(h)": "√h", "sqrt(s)": "√s", "sqrt(Hz)": "√Hz", "rtHz": "√Hz", "rt(h)": "√h"}


def _normalise(unit: str) -> str:
    u = unit.strip().replace(" ", "").replace("²", "^2").replace("**", "^")
    for a, b in _ALIASES.items():
        u = u.replace(a, b)
    u = u.replace("°", "deg").replace("deg C", "degC")
    return u


def lookup(unit: str) -> tuple[float, str]:
    """Return ``(factor_to_SI, dimension)`` of a unit name.

    Raises
    ------
    UnitError
        If the unit is unknown (the message lists the known units of similar spelling).
    """
    u = _normalise(unit)
    if u not in _UNITS:
        near = sorted(k for k in _UNITS if k.split("/")[0] == u.split("/")[0])
        hint = f"; known units starting alike: {', '.join(near)}" if near else ""
        raise UnitError(f"unknown unit {unit!r}{hint}")
    return _UNITS[u]


def dimension(unit: str) -> str:
    """SI dimension of ``unit`` (e.g. ``"rad/√s"`` for ``"deg/√h"``)."""
    return lookup(unit)[1]


def convert(value: ArrayLike, from_unit: str, to_unit: str) -> NDArray[np.float64] | float:
    """Convert ``value`` from ``from_unit`` to ``to_unit``.

    Raises
    ------
    UnitError
        If either unit is unknown or their dimensions differ.
    """
    f1, d1 = lookup(from_unit)
    f2, d2 = lookup(to_unit)
    if d1 != d2:
        raise UnitError(f"cannot convert {from_unit!r} ({d1}) to {to_unit!r} ({d2}): different dimensions")
    arr = np.asarray(value, dtype=np.float64)
    out = arr * (f1 / f2)
    return float(out) if out.ndim == 0 else out


def to_si(value: ArrayLike, unit: str) -> NDArray[np.float64] | float:
    """Convert ``value`` in ``unit`` to the SI unit of its dimension."""
    f, _ = lookup(unit)
    arr = np.asarray(value, dtype=np.float64) * f
    return float(arr) if arr.ndim == 0 else arr


# A decimal number (no inf/nan), then the unit; the space between them is optional.
_QUANTITY = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*")


def parse_quantity(text: str, to: str, *, what: str | None = None) -> float:
    """Parse ``"<number><unit>"`` text (``"15deg/h"``, ``"7e-5 rad/s"``, ``"3.18 deg/√h"``) into
    a float in unit ``to``, refusing a unit of another dimension.

    The one parser of quantities written as text (command-line options, datasheet strings):
    the unit is any name :func:`lookup` knows, with its ASCII spellings (``deg/sqrt(h)``).

    Parameters
    ----------
    text : str
        A decimal number followed by a unit; the space between them is optional.
    to : str
        Unit of the result; must have the dimension of the unit in ``text``.
    what : str, optional
        Name of the option or field, put in front of error messages (e.g. ``"--residual-bias"``).

    Returns
    -------
    float
        The value in ``to``.

    Raises
    ------
    InputError
        ``text`` is not a string holding a number followed by a unit, or its value in ``to``
        is not finite.
    UnitError
        The unit is unknown or of another dimension than ``to`` (an :class:`InputError`).

    Examples
    --------
    >>> parse_quantity("2 m/s/h", "m/s^2") == 2.0 / 3600.0
    True
    >>> parse_quantity("15 m/s", "rad/s", what="--residual-bias")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    uasnav.errors.UnitError: --residual-bias: '15 m/s': cannot convert 'm/s' ... different dimensions
    """
    where = f"{what}: " if what else ""
    m = _QUANTITY.fullmatch(text) if isinstance(text, str) else None
    if m is None or not m.group(2):
        raise InputError(f"{where}expected '<number><unit>', e.g. '15deg/h', got {text!r}")
    try:
        with np.errstate(over="ignore"):  # an overflow is refused just below, by value
            value = float(convert(float(m.group(1)), m.group(2), to))
    except UnitError as e:
        raise UnitError(f"{where}{text!r}: {e}") from None
    if not math.isfinite(value):  # "1e999 m", "1e308 km": beyond the float range
        raise InputError(f"{where}{text!r} is not a finite quantity (beyond the float range in {to})")
    return value


def known_units() -> list[str]:
    """All unit names :func:`convert` accepts."""
    return sorted(_UNITS)


__all__ = ["STANDARD_GRAVITY", "convert", "dimension", "known_units", "lookup", "parse_quantity", "to_si"]
