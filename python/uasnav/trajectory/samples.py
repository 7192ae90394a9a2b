"""Flown elements measured from telemetry: entry speed, real time, mean speed change ΔV.

For a flight along a plan, each telemetry position is projected onto the plan (arc length s,
made non-decreasing); the times at which s passes an element's start and end give the real
time t_Real of the element (eq. 59). The speed change of eq. (47) is then

    ΔV = L / t_Real − V_ref,

with V_ref the commanded cruise speed (so that a prediction for a new plan, where only the
commanded speed is known, uses the same reference). The measured entry speed |V_init| is kept
too (``v_init_ms``).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from uasnav.errors import InputError
from uasnav.trajectory.features import Features, cell_index, features
from uasnav.trajectory.geometry import DEFAULT_SEGMENT_M, Elements, arc_length_along, discretise


class TelemetryGapWarning(UserWarning):
    """Elements were left out of the measured samples because telemetry had a gap inside them."""


@dataclass
class ElementSamples:
    """Measured elements of one or more flights (arrays of length m).

    Attributes
    ----------
    features : Features
    length_m, t_real_s, v_init_ms, v_ref_ms, dv_ms : ndarray, shape (m,)
        Element length (m), real time (s), measured entry speed, reference (cruise) speed and
        ΔV = L/t − V_ref (m/s).
    flight : ndarray of int, shape (m,)
        Flight index.
    element : ndarray of int, shape (m,)
        Element index within its plan.
    climb_rate_ms : ndarray, shape (m,), or None
        Measured climb rate over the element, Δaltitude / t_real (m/s, up; NaN where the
        flight had no altitude); None if no flight had one.
    """

    features: Features
    length_m: np.ndarray
    t_real_s: np.ndarray
    v_init_ms: np.ndarray
    v_ref_ms: np.ndarray
    dv_ms: np.ndarray
    flight: np.ndarray
    element: np.ndarray
    climb_rate_ms: np.ndarray | None = None

    def __len__(self) -> int:
        return int(self.length_m.size)

    @property
    def cell(self) -> np.ndarray:
        """Class cell of each element (see :func:`cell_index`)."""
        return cell_index(self.features)

    def subset(self, mask: np.ndarray) -> ElementSamples:
        """The samples where ``mask`` is true."""
        f = self.features
        return ElementSamples(
            features=Features(
                f.theta_deg[mask], f.theta_w_deg[mask], f.wind_ms[mask], f.kind[mask], f.mirrored[mask]
            ),
            length_m=self.length_m[mask],
            t_real_s=self.t_real_s[mask],
            v_init_ms=self.v_init_ms[mask],
            v_ref_ms=self.v_ref_ms[mask],
            dv_ms=self.dv_ms[mask],
            flight=self.flight[mask],
            element=self.element[mask],
            climb_rate_ms=None if self.climb_rate_ms is None else self.climb_rate_ms[mask],
        )

    @staticmethod
    def concat(parts: list[ElementSamples]) -> ElementSamples:
        """Join samples of several flights."""
        if not parts:
            raise InputError("no element samples to join")

        def cat(get):  # type: ignore[no-untyped-def]
            return np.concatenate([get(p) for p in parts])

        return ElementSamples(
            features=Features(
                cat(lambda p: p.features.theta_deg),
                cat(lambda p: p.features.theta_w_deg),
                cat(lambda p: p.features.wind_ms),
                cat(lambda p: p.features.kind),
                cat(lambda p: p.features.mirrored),
            ),
            length_m=cat(lambda p: p.length_m),
            t_real_s=cat(lambda p: p.t_real_s),
            v_init_ms=cat(lambda p: p.v_init_ms),
            v_ref_ms=cat(lambda p: p.v_ref_ms),
            dv_ms=cat(lambda p: p.dv_ms),
            flight=cat(lambda p: p.flight),
            element=cat(lambda p: p.element),
            climb_rate_ms=None
            if all(p.climb_rate_ms is None for p in parts)
            else cat(lambda p: np.full(len(p), np.nan) if p.climb_rate_ms is None else p.climb_rate_ms),
        )


def crossing_times(t: np.ndarray, s: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """First time the non-decreasing arc length ``s(t)`` reaches each target (linear
    interpolation between samples); NaN where it never does."""
    i = np.searchsorted(s, targets, side="left")
    out = np.full(targets.shape, np.nan)
    ok = i < s.size
    first = ok & (i == 0)
    out[first] = t[0]
    mid = ok & (i > 0)
    j = i[mid]
    ds = s[j] - s[j - 1]
    frac = np.where(ds > 0, (targets[mid] - s[j - 1]) / np.where(ds > 0, ds, 1.0), 1.0)
    out[mid] = t[j - 1] + frac * (t[j] - t[j - 1])
    return out


def measure_elements(
    plan_ne: np.ndarray,
    t: np.ndarray,
    pos_ne: np.ndarray,
    vel_ne: np.ndarray,
    wind_ne: np.ndarray,
    cruise_ms: float,
    segment_m: float = DEFAULT_SEGMENT_M,
    flight: int = 0,
    end_tolerance_m: float = 1.0,
    max_gap_s: float = 5.0,
    alt_m: np.ndarray | None = None,
) -> tuple[Elements, ElementSamples]:
    """Cut one flight along ``plan_ne`` into elements and measure each (module notes).

    Parameters
    ----------
    plan_ne : ndarray, shape (n, 2)
        The waypoints flown (north/east m).
    t : ndarray, shape (k,)
        Telemetry time, s, increasing.
    pos_ne, vel_ne : ndarray, shape (k, 2)
        Position (m) and ground velocity (m/s), north/east.
    wind_ne : ndarray, shape (2,)
        Wind velocity during the flight (m/s, toward); zeros if unknown.
    cruise_ms : float
        Commanded speed, m/s.
    end_tolerance_m : float
        The last element ends this far before the final waypoint (autopilots accept a waypoint
        within a radius and the vehicle settles slowly).
    max_gap_s : float
        Telemetry gaps longer than this inside an element make it unmeasurable: such elements
        are dropped (and counted in the raised error if none is left).
    alt_m : ndarray, shape (k,), optional
        Altitude (m, up, any fixed reference): each element's climb rate is measured too.

    Raises
    ------
    InputError
        Bad shapes, NaN, non-increasing time, a flight that never reaches the plan's end, or
        no measurable element.
    """
    t = np.asarray(t, dtype=float)
    pos = np.asarray(pos_ne, dtype=float)[:, :2]
    vel = np.asarray(vel_ne, dtype=float)[:, :2]
    if t.ndim != 1 or pos.shape != (t.size, 2) or vel.shape != (t.size, 2) or t.size < 2:
        raise InputError(f"telemetry shapes differ: t {t.shape}, pos {pos.shape}, vel {vel.shape}")
    if not (np.isfinite(t).all() and np.isfinite(pos).all() and np.isfinite(vel).all()):
        raise InputError("telemetry contains NaN/inf")
    if np.any(np.diff(t) <= 0):
        raise InputError(f"telemetry time is not increasing at sample {int(np.argmin(np.diff(t))) + 1}")
    if not (np.isfinite(cruise_ms) and cruise_ms > 0):
        raise InputError(f"cruise speed must be > 0 m/s, got {cruise_ms}")
    el = discretise(plan_ne, segment_m)
    s = arc_length_along(plan_ne, pos)
    s_end = el.s_end_m.copy()
    s_end[-1] -= end_tolerance_m
    if s[-1] < s_end[-1]:
        raise InputError(
            f"flight {flight} reaches only {s[-1]:.1f} m of the {el.s_end_m[-1]:.1f} m plan "
            "(incomplete flight or wrong plan)"
        )
    t0 = crossing_times(t, s, el.s_start_m)
    t1 = crossing_times(t, s, s_end)
    dt = t1 - t0
    # Largest telemetry gap over the samples bracketing each element (an element inside a hole
    # has interpolated, not measured, times).
    gap = np.full(dt.shape, np.inf)
    for k, (a, b) in enumerate(zip(t0, t1, strict=True)):
        if np.isfinite(a) and np.isfinite(b) and b > a:
            i0 = max(int(np.searchsorted(t, a, side="right")) - 1, 0)
            i1 = min(int(np.searchsorted(t, b, side="left")), t.size - 1)
            gap[k] = np.diff(t[i0 : i1 + 1]).max() if i1 > i0 else 0.0
    ok = np.isfinite(dt) & (dt > 0) & (gap <= max_gap_s)
    if not ok.any():
        raise InputError(f"flight {flight}: no element measurable (telemetry gaps > {max_gap_s} s?)")
    if not ok.all():
        bad = np.flatnonzero(~ok)
        warnings.warn(
            f"flight {flight}: element(s) {bad.tolist()} not measured (telemetry gap > {max_gap_s} s "
            "inside the element)",
            TelemetryGapWarning,
            stacklevel=2,
        )
    length = s_end - el.s_start_m
    speed = np.hypot(vel[:, 0], vel[:, 1])
    v_init = np.interp(t0, t, speed)
    f = features(el.heading1_deg, el.turn_deg, el.kind, np.asarray(wind_ne, dtype=float))
    climb = None
    if alt_m is not None:
        z = np.asarray(alt_m, dtype=float)
        if z.shape != t.shape:
            raise InputError(f"altitude shape {z.shape} differs from the time's {t.shape}")
        with np.errstate(invalid="ignore", divide="ignore"):
            climb = np.where(ok, (np.interp(t1, t, z) - np.interp(t0, t, z)) / np.where(ok, dt, 1.0), np.nan)
    idx = np.flatnonzero(ok)
    samples = ElementSamples(
        features=f,
        length_m=length,
        t_real_s=dt,
        v_init_ms=v_init,
        v_ref_ms=np.full(length.size, float(cruise_ms)),
        dv_ms=np.where(ok, length / np.where(ok, dt, 1.0) - cruise_ms, np.nan),
        flight=np.full(length.size, flight, dtype=int),
        element=np.arange(length.size),
        climb_rate_ms=climb,
    ).subset(idx)
    return el, samples


__all__ = ["ElementSamples", "TelemetryGapWarning", "crossing_times", "measure_elements"]
