"""Trajectory prediction with LVQ networks (thesis §5.1): the Phantom-4 experiment, simulated.

The thesis' Phantom-4 flights are not public, so the experiment of §5.1.4 is reproduced with the
simulated multirotor of :mod:`uasnav.trajectory.simulator`: two waypoint trajectories flown
``n_flights`` times each in 2.78 m/s wind from NNE, the first ``n_train`` flights of each train
the LVQ predictor, the rest test it (Table 17), against the baselines of
:mod:`uasnav.trajectory.baselines`, and across trajectories (train on one, test on the other).

:func:`run_phantom4` is the experiment itself (also behind ``uasnav trajectory evaluate
--simulated``); :func:`run` adds what chapter 5.1 shows of it: the four training elements of
§5.1.4.2, Table 17 with e%, the per-element method summary and the cross-trajectory test.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from uasnav.experiments.thesis import SEC5142_TRAINING_ELEMENTS
from uasnav.trajectory.baselines import MethodResult, evaluate_methods, kinematic_times, percent_error
from uasnav.trajectory.features import wind_vector
from uasnav.trajectory.geometry import DEFAULT_SEGMENT_M, discretise
from uasnav.trajectory.predictor import TrajectoryPredictor
from uasnav.trajectory.samples import ElementSamples, measure_elements
from uasnav.trajectory.simulator import Telemetry, phantom4_experiment

#: The two cross-trajectory directions: train on the first trajectory, test on the second.
CROSS_DIRECTIONS = ("A→B", "B→A")


@dataclass(frozen=True)
class Table17Piece:
    """One Table-17 test piece of a trajectory: predicted and real times of the test flights.

    Attributes
    ----------
    piece : str
        ``"trajectory A"`` or ``"trajectory B"``.
    t_nn_s : float
        Predicted time of the piece (s): sum of the predicted element times, mean wind.
    t_real_s : tuple of float
        Flown time of the piece in each test flight (s).
    error_pct : tuple of float
        e% of ``t_nn_s`` against each ``t_real_s`` (%, eq. 59).
    """

    piece: str
    t_nn_s: float
    t_real_s: tuple[float, ...]
    error_pct: tuple[float, ...]


@dataclass(frozen=True)
class Phantom4Result:
    """Train/test split, the fitted predictor, every method's e% and the Table-17 pieces.

    Attributes
    ----------
    flights : mapping str → list of Telemetry
        The simulated flights of trajectories ``"A"`` and ``"B"`` (training flights first).
    train, test : ElementSamples
        Measured elements of the training and test flights; flight index 0… for A, 100… for B.
    test_plan : ndarray, shape (k, 2)
        Waypoints of trajectory A, north/east (m).
    predictor : TrajectoryPredictor
        The LVQ predictor fitted on ``train``.
    methods : tuple of MethodResult
        Every method's element times and e% on ``test`` (LVQ first).
    table17 : tuple of Table17Piece
        One piece per trajectory.
    """

    flights: Mapping[str, list[Telemetry]]
    train: ElementSamples
    test: ElementSamples
    test_plan: NDArray[np.float64]
    predictor: TrajectoryPredictor
    methods: tuple[MethodResult, ...]
    table17: tuple[Table17Piece, ...]


@dataclass(frozen=True)
class CornerView:
    """The flown tracks around one training corner, in local metres from the box's minimum corner.

    Attributes
    ----------
    trajectory : str
        ``"A"`` or ``"B"``.
    corner_ne : ndarray, shape (3, 2)
        Start, middle and end point of the corner element, north/east (m), local.
    tracks_ne : tuple of ndarray, shape (n_i, 2)
        Each training flight's positions inside the box (3 m around the element), local.
    """

    trajectory: str
    corner_ne: NDArray[np.float64]
    tracks_ne: tuple[NDArray[np.float64], ...]


@dataclass(frozen=True)
class TrainingElement:
    """One training element of §5.1.4.2: the thesis' ΔV and ours (means over the training flights).

    Attributes
    ----------
    theta_deg, theta_w_deg : float
        Turn angle θ and relative wind direction θ_w (deg).
    dv_thesis_ms : float
        The thesis' ΔV (m/s), relative to the element's initial speed.
    dv_vs_cruise_ms : float
        Our mean ΔV relative to the commanded speed (m/s), what the predictor trains on.
    v_init_ms : float
        Our mean initial speed of the element (m/s).
    dv_vs_v_init_ms : float
        Our mean ΔV relative to the initial speed (m/s), the thesis' definition.
    n : int
        Number of training samples of the element.
    views : tuple of CornerView
        The corners of the plans with this turn angle, for Figures 59–62.
    """

    theta_deg: float
    theta_w_deg: float
    dv_thesis_ms: float
    dv_vs_cruise_ms: float
    v_init_ms: float
    dv_vs_v_init_ms: float
    n: int
    views: tuple[CornerView, ...]


@dataclass(frozen=True)
class MethodSummary:
    """e% per test element of one method (%, eq. 59): mean, median and maximum.

    ``reason`` is None for a fitted method; otherwise why the method is not applicable to the
    training data (the three e% are then NaN and must not be shown as numbers).
    """

    name: str
    mean_pct: float
    median_pct: float
    max_pct: float
    reason: str | None = None

    @classmethod
    def of(cls, m: MethodResult) -> MethodSummary:
        """Summary of one :class:`MethodResult` (NaN e% and its reason if not applicable)."""
        if not m.applicable:
            return cls(m.name, float("nan"), float("nan"), float("nan"), m.reason)
        e = m.error_pct
        return cls(m.name, float(e.mean()), float(np.median(e)), float(e.max()))


@dataclass(frozen=True)
class CrossTrajectory:
    """Generalisation to a trajectory never flown in training.

    Attributes
    ----------
    results : mapping str → list of MethodResult
        Per direction of :data:`CROSS_DIRECTIONS`, every method's result.
    mean_pct : mapping str → tuple of float
        Per method, its mean e% (%) in each direction, in the order of ``results``.
    """

    results: Mapping[str, list[MethodResult]]
    mean_pct: Mapping[str, tuple[float, ...]]


@dataclass(frozen=True)
class TrajectoryResult:
    """Everything chapter 5.1's experiment shows (see :func:`run`).

    Attributes
    ----------
    n_flights, n_train : int
        Flights per trajectory, and how many of them train.
    phantom4 : Phantom4Result
        The experiment.
    piece_mid_ne : mapping str → ndarray, shape (k, 2)
        Per trajectory, the midpoints of the Table-17 piece's elements, north/east (m).
    training_elements : tuple of TrainingElement
        The four training elements of §5.1.4.2, in the thesis' order.
    methods : tuple of MethodSummary
        Per-element e% of every method on the test flights.
    cross : CrossTrajectory
        The cross-trajectory test.
    """

    n_flights: int
    n_train: int
    phantom4: Phantom4Result
    piece_mid_ne: Mapping[str, NDArray[np.float64]]
    training_elements: tuple[TrainingElement, ...]
    methods: tuple[MethodSummary, ...]
    cross: CrossTrajectory


def samples_of(
    flights: list[Telemetry], first_index: int = 0, segment_m: float = DEFAULT_SEGMENT_M
) -> list[ElementSamples]:
    """Measured elements of each simulated flight (flight index ``first_index + i``)."""
    out = []
    for i, tel in enumerate(flights):
        _, s = measure_elements(
            tel.plan_ne,
            tel.t,
            tel.pos_ne,
            tel.vel_ne,
            tel.wind_ne,
            tel.cruise_ms,
            segment_m,
            flight=first_index + i,
        )
        out.append(s)
    return out


def table17_piece(plan_ne: NDArray[np.float64], segment_m: float = DEFAULT_SEGMENT_M) -> NDArray[np.intp]:
    """Element indices of the Table-17 test piece of a plan.

    From the corner element at waypoint 1 up to (not including) the corner element at waypoint
    3 — about 90 m, the length implied by the thesis' 25–28 s at 3.33 m/s.

    >>> from uasnav.trajectory.simulator import phantom4_plans
    >>> table17_piece(phantom4_plans()["A"]).tolist()
    [2, 3, 4, 5]
    """
    el = discretise(plan_ne, segment_m)
    p = np.asarray(plan_ne)
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))])
    lo = cum[1] - segment_m - 1e-6
    hi = cum[min(3, p.shape[0] - 1)] - segment_m + 1e-6
    return np.flatnonzero((el.s_start_m >= lo) & (el.s_end_m <= hi))


def run_phantom4(
    n_flights: int = 10, n_train: int = 7, seed: int = 0, **predictor_kw: object
) -> Phantom4Result:
    """Both trajectories flown ``n_flights`` times; the first ``n_train`` train, the rest test.

    Parameters
    ----------
    n_flights, n_train : int
        Flights per trajectory and how many of them train (thesis: 10 and 7).
    seed : int
        Seed of the simulation and of the predictors.
    **predictor_kw
        Further :class:`TrajectoryPredictor` arguments.
    """
    flights = phantom4_experiment(n_flights, seed=seed)
    train_parts, test_parts, kin = [], [], []
    pieces = []
    for j, fl in enumerate(flights.values()):
        parts = samples_of(fl, first_index=100 * j)
        train_parts += parts[:n_train]
        test_parts += parts[n_train:]
        plan = fl[0].plan_ne
        el = discretise(plan)
        for s in parts[n_train:]:
            kin.append(
                kinematic_times(
                    plan, el.s_start_m[s.element], el.s_start_m[s.element] + s.length_m, fl[0].cruise_ms
                )
            )
    train = ElementSamples.concat(train_parts)
    test = ElementSamples.concat(test_parts)
    kw = {"random_state": seed, **predictor_kw}
    pred = TrajectoryPredictor(**kw).fit(train)  # type: ignore[arg-type]
    methods = evaluate_methods(
        train,
        test,
        lvq_factory=lambda: TrajectoryPredictor(**kw),  # type: ignore[arg-type]
        kinematic_s=np.concatenate(kin),
        random_state=seed,
    )
    for j, (name, fl) in enumerate(flights.items()):
        plan = fl[0].plan_ne
        piece = table17_piece(plan)
        p = pred.predict(plan, _mean_wind(fl), fl[0].cruise_ms)
        t_nn = float(p.time_s[piece].sum())
        reals = []
        for s in samples_of(fl[n_train:], first_index=100 * j):
            m = np.isin(s.element, piece)
            reals.append(float(s.t_real_s[m].sum()))
        e = percent_error(np.full(len(reals), t_nn), np.array(reals))
        pieces.append(Table17Piece(f"trajectory {name}", t_nn, tuple(reals), tuple(float(x) for x in e)))
    return Phantom4Result(flights, train, test, flights["A"][0].plan_ne, pred, tuple(methods), tuple(pieces))


def cross_trajectory(r: Phantom4Result, seed: int = 0) -> dict[str, list[MethodResult]]:
    """Generalisation to a trajectory never flown in training.

    Train on the training flights of one trajectory, test on the test flights of the other (A→B
    and B→A). Here cells are missing from training, and the network's nearest-prototype
    fallback is what separates it from the per-cell table.
    """
    out = {}
    for name, tr_mask, te_mask in (
        (CROSS_DIRECTIONS[0], r.train.flight < 100, r.test.flight >= 100),
        (CROSS_DIRECTIONS[1], r.train.flight >= 100, r.test.flight < 100),
    ):
        out[name] = evaluate_methods(r.train.subset(tr_mask), r.test.subset(te_mask), random_state=seed)
    return out


def training_elements(r: Phantom4Result, n_train: int) -> tuple[TrainingElement, ...]:
    """The four training elements of §5.1.4.2: our ΔV beside the thesis', and their corners.

    Elements are matched on the folded features within 1° (corner elements only); the corners
    drawn are those of either plan whose turn angle is within 1° of θ.
    """
    out = []
    train = r.train
    f = train.features
    for th, tw, dv_thesis in SEC5142_TRAINING_ELEMENTS:
        m = (np.abs(f.theta_deg - th) < 1.0) & (np.abs(f.theta_w_deg - tw) < 1.0) & (f.kind == 0)
        views = []
        for name, fl in r.flights.items():
            el = discretise(fl[0].plan_ne)
            for i in np.flatnonzero(el.kind == "corner"):
                if abs(abs(el.turn_deg[i]) - th) < 1.0:
                    pts = np.array([el.start_ne[i], el.mid_ne[i], el.end_ne[i]])
                    lo = pts.min(axis=0) - 3
                    hi = pts.max(axis=0) + 3
                    tracks = []
                    for tel in fl[:n_train]:
                        sel = np.all((tel.pos_ne >= lo) & (tel.pos_ne <= hi), axis=1)
                        tracks.append(tel.pos_ne[sel] - lo)
                    views.append(CornerView(name, pts - lo, tuple(tracks)))
        out.append(
            TrainingElement(
                th,
                tw,
                dv_thesis,
                float(np.mean(train.dv_ms[m])),
                float(np.mean(train.v_init_ms[m])),
                float(np.mean(train.length_m[m] / train.t_real_s[m] - train.v_init_ms[m])),
                int(m.sum()),
                tuple(views),
            )
        )
    return tuple(out)


def run(
    *, seed: int = 2024, quick: bool = False, progress: Callable[[str], None] | None = None
) -> TrajectoryResult:
    """The Phantom-4 experiment with everything chapter 5.1 shows of it.

    Parameters
    ----------
    seed : int
        Seed of the simulation and of every predictor.
    quick : bool
        5 flights per trajectory (3 train) instead of the thesis' 10 (7 train).
    progress : callable, optional
        Receives one-line progress messages.
    """
    say = progress or (lambda _msg: None)
    n_flights, n_train = (5, 3) if quick else (10, 7)
    say("simulating the Phantom-4 experiment")
    r = run_phantom4(n_flights=n_flights, n_train=n_train, seed=seed)
    piece_mid = {
        name: discretise(fl[0].plan_ne).mid_ne[table17_piece(fl[0].plan_ne)] for name, fl in r.flights.items()
    }
    elements = training_elements(r, n_train)
    methods = tuple(MethodSummary.of(m) for m in r.methods)
    cross = cross_trajectory(r, seed=seed)
    names = [m.name for m in next(iter(cross.values()))]
    # NaN where a method is not applicable in that direction (its MethodResult says why).
    means = {
        n: tuple(
            float(m.error_pct.mean()) if m.applicable else float("nan")
            for m in (next(m for m in res if m.name == n) for res in cross.values())
        )
        for n in names
    }
    return TrajectoryResult(
        n_flights, n_train, r, piece_mid, elements, methods, CrossTrajectory(cross, means)
    )


def _mean_wind(fl: list[Telemetry]) -> NDArray[np.float64]:
    # The forecast a planner would use: the experiment's mean wind, not each flight's draw.
    m = fl[0].meta
    return wind_vector(2.78, m.get("wind_from_deg", 22.5))


__all__ = [
    "CROSS_DIRECTIONS",
    "CornerView",
    "CrossTrajectory",
    "MethodSummary",
    "Phantom4Result",
    "Table17Piece",
    "TrainingElement",
    "TrajectoryResult",
    "cross_trajectory",
    "run",
    "run_phantom4",
    "samples_of",
    "table17_piece",
    "training_elements",
]
