"""Element samples of real flight logs, and the leave-one-run-out evaluation on them.

The pipeline behind ``uasnav trajectory train`` and ``uasnav trajectory evaluate FLIGHT…``:
:func:`flight_samples` reads every log, cuts it into mission runs (or measures it against a
given plan when the log has no mission) and numbers the runs across files;
:func:`leave_one_run_out` predicts each run with every method trained on the other runs.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from uasnav.errors import InputError
from uasnav.io import read_flight
from uasnav.io.autopilot_limits import DEFAULT_LIMITS
from uasnav.io.flight import FlightLog
from uasnav.io.logfile import LogFile, open_log
from uasnav.io.plans import read_plan_route
from uasnav.trajectory.baselines import evaluate_methods, kinematic_times
from uasnav.trajectory.geometry import DEFAULT_SEGMENT_M, discretise, geodetic_to_local
from uasnav.trajectory.runs import FlownRun, run_samples
from uasnav.trajectory.samples import ElementSamples, measure_elements


@dataclass(frozen=True)
class FlightSamples:
    """Measured elements of every mission run of some flight logs.

    Attributes
    ----------
    runs : tuple of (str, FlownRun or None)
        Per run, the log it comes from and the run (None for a log measured against a plan).
    samples : tuple of ElementSamples
        Per run, its elements; ``flight`` holds the run's index in ``samples``.
    logs : dict of str → LogFile
        The binary logs as opened (their ``limits`` view comes from the same decoding pass).
    """

    runs: tuple[tuple[str, FlownRun | None], ...]
    samples: tuple[ElementSamples, ...]
    logs: dict[str, LogFile] = field(default_factory=dict, compare=False, repr=False)

    def __len__(self) -> int:
        return len(self.samples)

    @property
    def n_elements(self) -> int:
        """Number of elements over all runs."""
        return int(sum(len(s) for s in self.samples))

    def concat(self) -> ElementSamples:
        """All runs' elements as one sample set."""
        return ElementSamples.concat(list(self.samples))


def flight_samples(
    paths: Sequence[str | Path | LogFile],
    plan: str | Path | None = None,
    cruise_ms: float | None = None,
    wind_ne: NDArray[np.float64] | None = None,
    segment_m: float = DEFAULT_SEGMENT_M,
    max_gap_s: float = 5.0,
) -> FlightSamples:
    """Element samples of every mission run of every flight log (run index across files).

    Parameters
    ----------
    paths : sequence of path or LogFile
        Flight logs (.tlog, .bin, .ulg, .csv), by path or as opened (:func:`uasnav.io.open_log`).
    plan : path, optional
        Geodetic plan CSV (lat,lon,alt) for logs without mission waypoints.
    cruise_ms : float, optional
        Commanded speed (m/s); default the log's (needed when the log has none).
    wind_ne : ndarray, shape (2,), optional
        Wind velocity north/east (m/s, toward); default the log's estimate, else calm.
    segment_m : float
        Segment length L (m).
    max_gap_s : float
        Largest telemetry gap inside a measured element (s).

    Raises
    ------
    InputError
        A log without a mission and no (geodetic) plan, or without a speed and no ``cruise_ms``.
        The messages name the ``uasnav trajectory`` options (``--plan``, ``--speed``).
    """
    runs_all: list[tuple[str, FlownRun | None]] = []
    samples_all: list[ElementSamples] = []
    opened: dict[str, LogFile] = {}
    for item in paths:
        log, lf = _read(item)
        path = lf.path if isinstance(item, LogFile) and lf is not None else item
        if lf is not None:
            opened[str(path)] = lf
        runs: list[FlownRun] | list[None]
        v_log = cruise_ms
        if v_log is None and log.cruise_ms is None and lf is not None and lf.carries("limits"):
            # the waypoint speed parameter (WPNAV_SPEED, MPC_XY_CRUISE) when the telemetry
            # itself names no speed (DataFlash logs keep it in PARM)
            v_log = lf.limits.cruise_ms
        if log.waypoints:
            runs, samples = run_samples(log, segment_m, v_log, wind_ne, max_gap_s=max_gap_s)
        else:
            if plan is None:
                raise InputError(f"{path}: no mission waypoints in the log; give --plan")
            plan_ne, origin = read_plan_route(plan, other_as_csv=True)
            if origin is None:
                raise InputError("--plan for telemetry must be geodetic (lat,lon,alt)")
            if v_log is None:
                raise InputError(f"{path}: no waypoint speed in the log; give --speed")
            pos = geodetic_to_local(log.lat, log.lon, log.alt, origin=origin)[:, :2]
            w = wind_ne if wind_ne is not None else (log.wind_ne if log.wind_ne is not None else np.zeros(2))
            _, s = measure_elements(
                plan_ne, log.t, pos, log.vel_ned[:, :2], w, v_log, segment_m, max_gap_s=max_gap_s
            )
            runs, samples = [None], [s]
        for r, s in zip(runs, samples, strict=True):
            k = len(samples_all)
            s.flight[:] = k
            runs_all.append((str(path), r))
            samples_all.append(s)
    return FlightSamples(tuple(runs_all), tuple(samples_all), opened)


def _read(path: str | Path | LogFile) -> tuple[FlightLog, LogFile | None]:
    """The telemetry of ``path`` and, for a binary log, the opened log (one decoding pass for
    the telemetry and the autopilot limits; an already opened log is used as it is)."""
    if isinstance(path, LogFile):
        return path.flight, path
    p = Path(path)
    if p.suffix.lower() in (".tlog", ".bin", ".ulg") and p.is_file():
        lf = open_log(p, need=("flight", "limits"))
        return lf.flight, lf
    return read_flight(p), None


@dataclass(frozen=True)
class RunErrors:
    """e% (eq. 59) of one method over the leave-one-run-out folds.

    Attributes
    ----------
    name : str
        Method name (see :func:`~uasnav.trajectory.baselines.evaluate_methods`).
    element_pct : ndarray, shape (m,)
        e% of every element of every run (%), runs in order.
    run_pct : tuple of float
        e% of each run's total time (%).
    reason : str or None
        None if the method was fitted in every fold; otherwise why it is not applicable (the
        first fold whose training runs cannot support it) and ``element_pct``/``run_pct`` are NaN.
    """

    name: str
    element_pct: NDArray[np.float64]
    run_pct: tuple[float, ...]
    reason: str | None = None

    @property
    def applicable(self) -> bool:
        """True if the method was fitted in every fold."""
        return self.reason is None


def leave_one_run_out(
    flights: FlightSamples,
    segment_m: float = DEFAULT_SEGMENT_M,
    random_state: int = 0,
    accel_ms2: float = DEFAULT_LIMITS.accel_ms2 or 1.0,
) -> list[RunErrors]:
    """Predict each run with every method trained on the other runs.

    The kinematic point mass (acceleration limit ``accel_ms2``, m/s²: the vehicle's
    ``WPNAV_ACCEL``/``MPC_ACC_HOR`` when its log carries it, see
    :func:`uasnav.io.autopilot_limits.read_autopilot_limits`) is included when every run is cut
    from a mission (it needs the plan), and with it the kinematic model plus a residual learned
    on the other runs.

    Returns
    -------
    list of RunErrors
        One per method, in the order :func:`evaluate_methods` first returns them.

    Raises
    ------
    InputError
        Fewer than two runs.
    """
    samples = flights.samples
    if len(samples) < 2:
        raise InputError("leave-one-run-out needs at least two mission runs")
    if not (np.isfinite(accel_ms2) and accel_ms2 > 0):
        raise InputError(f"acceleration limit must be finite and > 0 m/s², got {accel_ms2}")
    per: dict[str, tuple[list[float], list[float]]] = {}
    reasons: dict[str, str] = {}
    kins: list[np.ndarray | None] = []
    for (_, run), s in zip(flights.runs, samples, strict=True):
        if run is None:
            kins.append(None)
            continue
        el = discretise(run.plan_ne, segment_m)
        kins.append(
            kinematic_times(
                run.plan_ne,
                el.s_start_m[s.element],
                el.s_start_m[s.element] + s.length_m,
                s.v_ref_ms[0],
                accel_ms2=accel_ms2,
            )
        )
    for k, test in enumerate(samples):
        train = ElementSamples.concat([s for i, s in enumerate(samples) if i != k])
        kin = kins[k]
        others = [x for i, x in enumerate(kins) if i != k]
        kin_train: np.ndarray | None = None
        if kin is not None and all(x is not None for x in others):
            kin_train = np.concatenate([x for x in others if x is not None])
        for m in evaluate_methods(
            train, test, kinematic_s=kin, random_state=random_state, kinematic_train_s=kin_train
        ):
            element, whole = per.setdefault(m.name, ([], []))
            if not m.applicable:
                # One fold the method cannot be fitted in makes the whole comparison unfair
                # (its mean would cover other runs than the other methods'): not applicable.
                reasons.setdefault(m.name, f"leaving out run {k + 1}: {m.reason}")
            element += m.error_pct.tolist()
            whole.append(float(abs(m.time_s.sum() - test.t_real_s.sum()) / test.t_real_s.sum() * 100))
    out = []
    for n, (e, r) in per.items():
        if n in reasons:
            out.append(RunErrors(n, np.full(len(e), np.nan), (float("nan"),) * len(r), reasons[n]))
        else:
            out.append(RunErrors(n, np.array(e, dtype=float), tuple(r)))
    return out


__all__ = ["FlightSamples", "RunErrors", "flight_samples", "leave_one_run_out"]
