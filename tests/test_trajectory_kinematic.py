"""The default predictor (kinematic point mass with the autopilot's limits) and the model-file
reader of both methods: closed form, flags, round trip, hostile files."""

from __future__ import annotations

import json

import numpy as np
import pytest

from uasnav.errors import DataFormatError, InputError
from uasnav.trajectory.kinematic import KinematicPredictor
from uasnav.trajectory.models import DEFAULT_METHOD, METHODS, load_model, make_predictor, method_of


@pytest.fixture(scope="module")
def train():
    from uasnav.experiments.trajectory import run_phantom4

    return run_phantom4(n_flights=4, n_train=3).train


def test_default_is_the_kinematic_model_and_lvq_is_selectable(train):
    assert DEFAULT_METHOD == "kinematic" and set(METHODS) == {"kinematic", "lvq"}
    assert method_of(make_predictor()) == "kinematic"
    assert method_of(make_predictor("lvq", n_prototypes=8, max_iter=50).fit(train)) == "lvq"
    with pytest.raises(InputError, match="unknown trajectory method 'knn'"):
        make_predictor("knn")


def test_straight_leg_closed_form_and_flags(train):
    # one straight leg from rest to rest: t = L/V + V/a (accelerate, cruise, brake)
    for a in (0.5, 1.0, 3.0):
        m = KinematicPredictor(accel_ms2=a).fit(train)
        p = m.predict(np.array([[0.0, 0.0], [300.0, 0.0]]), np.zeros(2), 5.0)
        assert p.eta_s == pytest.approx(300 / 5 + 5 / a, rel=1e-4)
        assert p.waypoint_times_s[-1] == pytest.approx(p.eta_s)
    m = KinematicPredictor().fit(train)
    # the training flights flew 2.5–3.3 m/s winds: a 9 m/s wind is flagged on every element,
    # and the kinematic times do not depend on the wind
    calm = m.predict(np.array([[0.0, 0.0], [100.0, 0.0]]), np.zeros(2))
    windy = m.predict(np.array([[0.0, 0.0], [100.0, 0.0]]), np.array([9.0, 0.0]))
    np.testing.assert_array_equal(calm.time_s, windy.time_s)
    assert all(any("outside the trained range" in r for r in f) for f in windy.flags)
    with pytest.raises(InputError, match="not fitted"):
        KinematicPredictor().predict(np.zeros((2, 2)), np.zeros(2))
    with pytest.raises(InputError, match="accel_ms2"):
        KinematicPredictor(accel_ms2=-1.0).fit(train)


def test_model_file_round_trip_and_hostile_files(train, tmp_path):
    m = KinematicPredictor(accel_ms2=2.0, climb_ms=3.0, limits_source="test").fit(train)
    path = tmp_path / "k.json"
    m.save(path)
    back = load_model(path)
    assert isinstance(back, KinematicPredictor) and back.get_params() == m.get_params()
    plan = np.array([[0.0, 0.0], [80.0, 0.0], [80.0, 60.0]])
    np.testing.assert_array_equal(back.predict(plan, np.zeros(2)).time_s, m.predict(plan, np.zeros(2)).time_s)
    good = json.loads(path.read_text())

    def refused(change, pattern):
        d = json.loads(json.dumps(good))
        change(d)
        path.write_text(json.dumps(d))
        with pytest.raises(DataFormatError, match=pattern):
            load_model(path)

    refused(lambda d: d.update(format="uasnav-trajectory-x/9"), "not a trajectory model")
    refused(lambda d: d["params"].update(accel_ms2=0.0), r"params\.accel_ms2: expected a number > 0")
    refused(lambda d: d["params"].update(climb_ms=1e9), r"params\.climb_ms: .* above the accepted maximum")
    refused(lambda d: d["params"].update(colour="red"), "colour")
    refused(lambda d: d.update(extra=1), "extra")
    refused(lambda d: d.update(n_train=d["n_train"] + 1), "counts sum to")
    refused(lambda d: d.update(cruise_ms=-3), r"cruise_ms: expected a number > 0")
    refused(lambda d: d.update(wind_range_ms=[5, 1]), "exceeds maximum")
    path.write_text("{not json")
    with pytest.raises(DataFormatError, match="invalid JSON"):
        load_model(path)
