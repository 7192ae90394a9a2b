"""The web application's built-in trajectory model: trained on simulated flights only.

Shipped defaults never embed the unlicensed flight logs of ``../shared``: this model is trained,
deterministically (fixed seeds), on the thesis' two Phantom-4 test trajectories (Figure 57
analogue) flown by :func:`uasnav.trajectory.simulator.simulate_flight` in several winds, so
that the wind classes an operator is likely to enter are populated. It is built on first use
and kept for the life of the process.
"""

from __future__ import annotations

import functools
import threading
import warnings

from uasnav.trajectory.models import DEFAULT_METHOD, Predictor, make_predictor
from uasnav.trajectory.samples import ElementSamples, measure_elements
from uasnav.trajectory.simulator import WindModel, phantom4_plans, simulate_flight

#: Mean winds flown (speed m/s, from-direction deg): calm, the thesis' 2.78 m/s from NNE, and
#: stronger winds from other quarters, so that most of the 4 wind classes hold data.
TRAINING_WINDS: tuple[tuple[float, float], ...] = ((0.0, 0.0), (2.78, 22.5), (5.0, 200.0), (8.0, 290.0))
#: Simulated flights per trajectory and wind.
FLIGHTS_PER_WIND = 3
#: Seed of the simulation and of the network.
SEED = 0


_LOCK = threading.Lock()


def default_model() -> Predictor:
    """The built-in model (trained once per process, then cached).

    Returns
    -------
    KinematicPredictor or TrajectoryPredictor (the default method)
        Fitted on ``len(TRAINING_WINDS) × 2 × FLIGHTS_PER_WIND`` simulated flights; the same
        every time (fixed seeds).
    """
    # one training even when the first requests arrive together (server threads)
    with _LOCK:
        return _train()


def clear_cache() -> None:
    """Forget the trained model (the next :func:`default_model` trains again)."""
    with _LOCK:
        _train.cache_clear()


@functools.lru_cache(maxsize=1)
def _train() -> Predictor:
    parts = []
    index = 0
    for w, (speed, from_deg) in enumerate(TRAINING_WINDS):
        wind = WindModel(speed_ms=speed, from_deg=from_deg)
        for j, plan in enumerate(phantom4_plans().values()):
            for i in range(FLIGHTS_PER_WIND):
                tel = simulate_flight(plan, wind=wind, seed=SEED * 1000 + 100 * w + 10 * j + i)
                _, s = measure_elements(
                    tel.plan_ne, tel.t, tel.pos_ne, tel.vel_ne, tel.wind_ne, tel.cruise_ms, flight=index
                )
                parts.append(s)
                index += 1
    with warnings.catch_warnings():
        # few elements per cell is expected of a small simulated set; say nothing per request
        warnings.filterwarnings("ignore", category=UserWarning)
        # the default method (uasnav.trajectory.models.DEFAULT_METHOD), as `trajectory train`
        return make_predictor(DEFAULT_METHOD).fit(ElementSamples.concat(parts))


__all__ = ["FLIGHTS_PER_WIND", "SEED", "TRAINING_WINDS", "clear_cache", "default_model"]
