"""Temperature profiles of the thermal tests (thesis §4.2.4) and user profiles.

A :class:`TemperatureProfile` gives the *chamber* temperature as a piecewise-linear function
of time. The die temperature follows it through the sensor's first-order thermal lag plus its
self-heating (:class:`~uasnav.sim.model.TemperatureSensorModel`). The named profiles are
defined by the *die* temperatures of the thesis (what the AHRS temperature sensor reported),
so their chamber set points are the die targets minus the sensor's self-heating:

========  ====================================================================================
soak      die −20.53 → 37.30 °C in 5 °C steps, each reached with a 1 °C/min chamber ramp and
          held 20 min (stabilised), thesis Figure 29
ramp      die 27.28 → 34.08 °C at 2 °C/min, held 10 min, back down at 2 °C/min, held 10 min
          (heating then cooling branch: hysteresis), thesis Figure 30
cycles    die 27.28 ↔ 34.08 °C at 2 °C/min with 5-min dwells at both ends, repeated, after 60 s at
          27.28 °C (the thesis' zeroing window): the ramp test as a long ZUPT/TCZUPT input with
          several heating and cooling branches (§4.2.6.2; a 90 s die lag ends each dwell within
          0.1 °C of the target); natural length 1 h
warmup    constant chamber (ambient); the die warms by the self-heating with time constant
          ``warmup_tau_s`` after power-on (natural length 5 time constants)
static    constant temperature, die at the ambient temperature (chamber = ambient − self-heating,
          so the preset's 25 °C specification applies); natural length 1 h
========  ====================================================================================
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav.errors import InputError
from uasnav.imu import check_time

FloatArray = NDArray[np.float64]
PROFILE_NAMES = ("static", "soak", "ramp", "cycles", "warmup")

#: Die temperatures of the thesis' soak test (°C): −20.53 °C in steps of 5 °C up to 37.30 °C.
SOAK_DIE_C = (*tuple(round(-20.53 + 5.0 * k, 2) for k in range(12)), 37.30)
#: Die temperature range of the thesis' ramp test (°C) and its ramp rate (°C/s).
RAMP_DIE_C = (27.28, 34.08)
RAMP_RATE_C_PER_S = 2.0 / 60.0


@dataclass(frozen=True)
class TemperatureProfile:
    """Chamber temperature vs time, piecewise linear between breakpoints.

    Parameters
    ----------
    t : array (k,)
        Breakpoint times (s), strictly increasing, starting at 0.
    chamber_c : array (k,)
        Chamber temperature (°C) at the breakpoints; held constant after the last one.
    name : str
        Label stored in ``log.meta["profile"]``.
    warmup : bool
        If true the die self-heating starts from zero at t = 0 (power-on), otherwise the
        unit is already in thermal equilibrium with its self-heating.
    """

    t: FloatArray
    chamber_c: FloatArray
    name: str = "user"
    warmup: bool = False

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=np.float64).ravel()
        c = np.asarray(self.chamber_c, dtype=np.float64).ravel()
        if t.size < 1 or t.size != c.size:
            raise InputError(
                f"profile: t and chamber_c need the same non-zero length, got {t.size}, {c.size}"
            )
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(c))):
            raise InputError("profile: non-finite breakpoint")
        check_time(t, "profile t")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "chamber_c", c)

    @property
    def duration(self) -> float:
        """Natural length (s): the last breakpoint (at least 1 s)."""
        return max(float(self.t[-1]), 1.0)

    def chamber(self, t: ArrayLike) -> FloatArray:
        """Chamber temperature (°C) at times ``t`` (s)."""
        return np.interp(np.asarray(t, dtype=np.float64), self.t, self.chamber_c)

    @classmethod
    def from_arrays(cls, t: ArrayLike, chamber_c: ArrayLike, name: str = "user") -> TemperatureProfile:
        """A user profile from arrays (see the class parameters)."""
        return cls(np.asarray(t, dtype=np.float64), np.asarray(chamber_c, dtype=np.float64), name=name)


def _ramp_hold(points: list[tuple[float, float]], target: float, rate: float, hold: float) -> None:
    t, c = points[-1]
    t_new = t + abs(target - c) / rate
    points.append((t_new, target))
    points.append((t_new + hold, target))


def named_profile(
    name: str, *, self_heating_c: float, ambient_c: float, warmup_tau_s: float
) -> TemperatureProfile:
    """One of :data:`PROFILE_NAMES` for a sensor with the given thermal constants."""
    if name == "static":
        # die at the ambient (= reference) temperature: chamber below it by the self-heating
        return TemperatureProfile(
            np.array([0.0, 3600.0]), np.full(2, ambient_c - self_heating_c), name="static"
        )
    if name == "warmup":
        return TemperatureProfile(
            np.array([0.0, 5.0 * warmup_tau_s]), np.full(2, ambient_c), name="warmup", warmup=True
        )
    if name == "soak":
        die = np.array(SOAK_DIE_C)
        pts = [(0.0, die[0] - self_heating_c), (1800.0, die[0] - self_heating_c)]
        for target in die[1:]:
            _ramp_hold(pts, float(target) - self_heating_c, 1.0 / 60.0, 1200.0)
        t, c = zip(*pts, strict=True)
        return TemperatureProfile(np.array(t), np.array(c), name="soak")
    if name == "ramp":
        lo, hi = RAMP_DIE_C
        pts = [(0.0, lo - self_heating_c), (600.0, lo - self_heating_c)]
        _ramp_hold(pts, hi - self_heating_c, RAMP_RATE_C_PER_S, 600.0)
        _ramp_hold(pts, lo - self_heating_c, RAMP_RATE_C_PER_S, 600.0)
        t, c = zip(*pts, strict=True)
        return TemperatureProfile(np.array(t), np.array(c), name="ramp")
    if name == "cycles":
        lo, hi = RAMP_DIE_C
        pts = [(0.0, lo - self_heating_c), (60.0, lo - self_heating_c)]
        while pts[-1][0] < 3600.0:
            _ramp_hold(pts, hi - self_heating_c, RAMP_RATE_C_PER_S, 300.0)
            _ramp_hold(pts, lo - self_heating_c, RAMP_RATE_C_PER_S, 300.0)
        t, c = zip(*pts, strict=True)
        return TemperatureProfile(np.array(t), np.array(c), name="cycles")
    raise InputError(
        f"unknown profile {name!r}; expected one of {', '.join(PROFILE_NAMES)} or a TemperatureProfile"
    )


__all__ = ["PROFILE_NAMES", "RAMP_DIE_C", "SOAK_DIE_C", "TemperatureProfile", "named_profile"]
