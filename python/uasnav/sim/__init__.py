"""MEMS IMU simulator with thermal effects (thesis §4.2.4 soak/ramp tests, §4.3 consumer IMUs).

>>> from uasnav.sim import simulate
>>> log = simulate("ax1", profile="static", duration=10.0, seed=1)
>>> log.gyro.shape, sorted(log.truth)[:3]
((1000, 3), ['accel_bias', 'attitude', 'gyro_bias'])

Every output is a deterministic function of the arguments (seed included) and carries its
ground truth (``log.truth``). Presets are data files in ``uasnav/sim/presets`` (one per
sensor, with their sources); see :mod:`uasnav.sim.model` for the error terms,
:mod:`uasnav.sim.profiles` for the temperature profiles and :mod:`uasnav.sim.core` for the
signal chain.
"""

from uasnav.sim.core import (
    ARRAY_SHAPES,
    array_mountings,
    die_temperature,
    gauss_markov_sum,
    random_walk,
    simulate,
    simulate_array,
    thermal_bias,
    thermal_bias_derivative,
    thermal_model,
)
from uasnav.sim.faults import FAULT_KINDS, inject_fault
from uasnav.sim.model import (
    PRESET_NAMES,
    SensorModel,
    TemperatureSensorModel,
    ThermalErrorTruth,
    TriadModel,
    load_preset,
)
from uasnav.sim.profiles import PROFILE_NAMES, TemperatureProfile, named_profile

__all__ = [
    "ARRAY_SHAPES",
    "FAULT_KINDS",
    "PRESET_NAMES",
    "PROFILE_NAMES",
    "SensorModel",
    "TemperatureProfile",
    "TemperatureSensorModel",
    "ThermalErrorTruth",
    "TriadModel",
    "array_mountings",
    "die_temperature",
    "gauss_markov_sum",
    "inject_fault",
    "load_preset",
    "named_profile",
    "random_walk",
    "simulate",
    "simulate_array",
    "thermal_bias",
    "thermal_bias_derivative",
    "thermal_model",
]
