"""Flown mission runs of flight telemetry (:class:`uasnav.io.flight.Flight`, read with
:func:`uasnav.io.open_log`), and the elements measured on them.

:func:`flown_runs` cuts a log into mission runs (consecutive reached events of increasing
sequence number) and :func:`run_samples` measures their elements.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from uasnav.errors import InputError
from uasnav.io.flight import Flight
from uasnav.trajectory.geometry import DEFAULT_SEGMENT_M, arc_length_along, geodetic_to_local, plan_length
from uasnav.trajectory.samples import ElementSamples, measure_elements

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class FlownRun:
    """One run of the mission: the waypoint sequence reached, their times and the telemetry.

    Attributes
    ----------
    seqs : list of int
        Sequence numbers of the navigation waypoints reached, in order (m of them).
    reached_t : ndarray, shape (m,)
        Times the waypoints were reached (s).
    plan_ne : ndarray, shape (m, 2)
        The waypoints in local north, east (m).
    t : ndarray, shape (k,)
        Telemetry time over the run (s).
    pos_ne, vel_ne : ndarray, shape (k, 2)
        Local position (m) and ground velocity (m/s), north and east.
    alt_m : ndarray, shape (k,), or None
        Altitude of the telemetry (m, the log's reference).
    """

    seqs: list[int]
    reached_t: FloatArray
    plan_ne: FloatArray
    t: FloatArray
    pos_ne: FloatArray
    vel_ne: FloatArray
    alt_m: FloatArray | None = None


def flown_runs(log: Flight, origin: tuple[float, float, float] | None = None) -> list[FlownRun]:
    """Cut a log into mission runs between reached navigation waypoints (local NED plan).

    Raises :class:`InputError` if the log has no mission waypoints or no run reaching two of
    them.
    """
    if not log.waypoints:
        raise InputError(f"{log.source}: telemetry has no mission waypoints (give the plan separately)")
    if not log.reached:
        raise InputError(f"{log.source}: telemetry has no waypoint-reached events")
    seqs = sorted(log.waypoints)
    o = origin or log.waypoints[seqs[0]]
    runs: list[list[tuple[float, int]]] = [[]]
    for ev in log.reached:
        if runs[-1] and ev[1] <= runs[-1][-1][1]:
            runs.append([])
        runs[-1].append(ev)
    out = []
    for run in runs:
        nav = [(t, s) for t, s in run if s in log.waypoints]
        if len(nav) < 2:
            continue
        wp = np.array([log.waypoints[s] for _, s in nav])
        plan = geodetic_to_local(wp[:, 0], wp[:, 1], wp[:, 2], origin=o)[:, :2]
        t0, t1 = nav[0][0], nav[-1][0]
        sel = (log.t >= t0) & (log.t <= t1 + 5.0)
        if sel.sum() < 2:
            continue
        pos = geodetic_to_local(log.lat[sel], log.lon[sel], log.alt[sel], origin=o)[:, :2]
        out.append(
            FlownRun(
                seqs=[s for _, s in nav],
                reached_t=np.array([t for t, _ in nav]),
                plan_ne=plan,
                t=log.t[sel],
                pos_ne=pos,
                vel_ne=log.vel_ned[sel, :2],
                alt_m=np.asarray(log.alt[sel], dtype=float),
            )
        )
    if not out:
        raise InputError(f"{log.source}: no mission run reaches two navigation waypoints")
    return out


def run_samples(
    log: Flight,
    segment_m: float = DEFAULT_SEGMENT_M,
    cruise_ms: float | None = None,
    wind_ne: np.ndarray | None = None,
    max_gap_s: float = 5.0,
) -> tuple[list[FlownRun], list[ElementSamples]]:
    """Measure the elements of every run of a log (flight index = run index).

    ``cruise_ms`` and ``wind_ne`` override the log's values; without wind in the log and no
    override the wind is taken as calm (zero), and the caller should say so.
    """
    v = cruise_ms if cruise_ms is not None else log.cruise_ms
    if v is None:
        raise InputError(f"{log.source}: no waypoint speed in the log; give the cruise speed")
    w = wind_ne if wind_ne is not None else (log.wind_ne if log.wind_ne is not None else np.zeros(2))
    runs = flown_runs(log)
    samples = []
    for i, r in enumerate(runs):
        # Autopilots accept the last waypoint within a radius and then start the next command
        # (ArduCopter lands where it is, ~7 m short here): the flown plan ends where the vehicle
        # was when the reached event came.
        s_run = arc_length_along(r.plan_ne, r.pos_ne)
        s_reached = float(np.interp(r.reached_t[-1], r.t, s_run))
        tol = max(1.0, plan_length(r.plan_ne) - s_reached)
        _, s = measure_elements(
            r.plan_ne,
            r.t,
            r.pos_ne,
            r.vel_ne,
            w,
            v,
            segment_m=segment_m,
            flight=i,
            end_tolerance_m=tol,
            max_gap_s=max_gap_s,
            alt_m=r.alt_m,
        )
        samples.append(s)
    return runs, samples


__all__ = ["FlownRun", "flown_runs", "run_samples"]
