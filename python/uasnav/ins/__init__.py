"""In-flight navigation: the loosely coupled GNSS/INS error-state filter (thesis §4.1.4).

``run(flight, config) -> InsResult`` hands a whole :class:`Flight` (IMU, GNSS, baro,
magnetometer) to the Rust filter in one call; :mod:`uasnav.ins.evaluate` compares the result
with the autopilot's estimate or a simulation's truth, runs GNSS-outage experiments and checks
consistency (NEES). Readers for real logs live in :mod:`uasnav.io.flight`; simulated flights
with truth in :mod:`uasnav.sim.flight`.

Examples
--------
>>> from uasnav.sim.flight import simulate_flight
>>> from uasnav import ins
>>> flight = simulate_flight(duration_s=60.0, seed=1)
>>> result = ins.run(flight, ins.InsConfig(decimation=10))
>>> err = ins.evaluate.compare(result, flight.truth)
>>> bool(err.horizontal_rms_m < 3.0)
True
"""

from uasnav.ins import evaluate, magnetic
from uasnav.ins.core import FIX_STATUS, InsConfig, InsResult, integrity_thresholds, run
from uasnav.io.flight import BaroData, Flight, GnssData, MagData, Trajectory
from uasnav.io.track import TRACK_COLUMNS

__all__ = [
    "FIX_STATUS",
    "TRACK_COLUMNS",
    "BaroData",
    "Flight",
    "GnssData",
    "InsConfig",
    "InsResult",
    "MagData",
    "Trajectory",
    "evaluate",
    "integrity_thresholds",
    "magnetic",
    "run",
]
