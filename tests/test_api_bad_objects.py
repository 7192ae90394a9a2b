"""Every public function that takes an ImuLog refuses anything else with an InputError naming
the argument (issue 20, class 8, Python side): never an AttributeError from deep inside."""

from __future__ import annotations

import numpy as np
import pytest

from uasnav import redundancy, stationary, thermal, zupt
from uasnav.errors import InputError
from uasnav.experiments import ardupilot
from uasnav.thermal import PolynomialBiasModel, workflow

_Q = np.array([1.0, 0.0, 0.0, 0.0])
_MODEL = PolynomialBiasModel(1).fit(np.linspace(20.0, 40.0, 11), np.zeros((11, 3)))

CALLS = {
    "stationary.detect_static": lambda bad: stationary.detect_static(bad),
    "zupt.run": lambda bad: zupt.run(bad),
    "zupt.detect_stationary": lambda bad: zupt.detect_stationary(bad),
    "zupt.moving_average_reference": lambda bad: zupt.moving_average_reference(bad, _Q),
    "zupt.reference_residual": lambda bad: zupt.reference_residual(bad, np.zeros((2, 3)), _Q),
    "zupt.segment_rms": lambda bad: zupt.segment_rms(bad, "zupt", np.zeros((2, 3))),
    "redundancy.fuse": lambda bad: redundancy.fuse([bad], redundancy.configuration("cube", 1)),
    "redundancy.stack_logs": lambda bad: redundancy.stack_logs([bad]),
    "redundancy.array_for_logs": lambda bad: redundancy.array_for_logs("meta", [bad]),
    "thermal.apply": lambda bad: thermal.apply(_MODEL, bad),
    "thermal.workflow.evaluate_model": lambda bad: workflow.evaluate_model(_MODEL, bad),
    "experiments.ardupilot.common_samples": lambda bad: ardupilot.common_samples([bad, bad]),
}


@pytest.mark.parametrize("name", sorted(CALLS))
@pytest.mark.parametrize("bad", ["flight.csv", None, np.zeros((10, 3))], ids=["str", "None", "array"])
def test_non_log_objects_are_input_errors(name: str, bad: object) -> None:
    with pytest.raises(InputError, match=r"log"):
        CALLS[name](bad)
