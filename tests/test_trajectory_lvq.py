"""LVQClassifier: scikit-learn contract, MATLAB lvqnet semantics, LVQ2.1 by neuron index."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.utils.estimator_checks import check_estimator

from uasnav.errors import InputError
from uasnav.trajectory.lvq import LVQClassifier, _train_lvq1, _train_lvq21, neurons_per_class


def test_sklearn_check_estimator():
    check_estimator(LVQClassifier(n_prototypes=6, max_iter=300, random_state=0))


def test_neurons_shared_by_class_frequency():
    # MATLAB lvqnet: neurons in proportion to class frequency; every class gets at least one.
    n = neurons_per_class(np.array([60, 30, 10]), 10)
    assert n.tolist() == [6, 3, 1]
    n = neurons_per_class(np.array([98, 1, 1]), 256)
    assert n.tolist() == [251, 3, 2]  # 250.88, 2.56, 2.56 by largest remainder
    assert neurons_per_class(np.array([1000, 1, 1]), 4).tolist() == [2, 1, 1]
    with pytest.raises(InputError, match="fewer than"):
        neurons_per_class(np.array([1, 1, 1]), 2)


def test_lvq1_single_update_by_hand():
    w = np.array([[0.0, 0.0], [1.0, 1.0]])
    lab = np.array([0, 1])
    # Sample near neuron 0, same class: w0 += 0.5 (x − w0)
    _train_lvq1(w, lab, np.array([[0.2, 0.0]]), np.array([0]), np.array([0.5]), 0.25)
    np.testing.assert_allclose(w[0], [0.1, 0.0])
    # Sample near neuron 0, other class: w0 −= 0.5 (x − w0)
    _train_lvq1(w, lab, np.array([[0.3, 0.0]]), np.array([1]), np.array([0.5]), 0.25)
    np.testing.assert_allclose(w[0], [0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(w[1], [1.0, 1.0])


def test_lvq21_runner_up_is_second_nearest_neuron_not_nearest_of_class():
    # Two neurons of class 0 at 0 and 0.9, one of class 1 at 1.3; sample of class 1 at 1.0.
    # Nearest neuron: #1 (class 0, d=0.1); second nearest: #2 (class 1, d=0.3): in the window
    # min(0.1/0.3, 3) = 0.33 ≤ (1−w)/(1+w) = 0.6 → no update with w = 0.25 ...
    w = np.array([[0.0], [0.9], [1.3]])
    lab = np.array([0, 0, 1])
    w0 = w.copy()
    _train_lvq21(w, lab, np.array([[1.0]]), np.array([1]), np.array([0.1]), 0.25)
    np.testing.assert_allclose(w, w0)
    # ... and with the sample at 1.08 (d = 0.18, 0.22; ratio 0.82 > 0.6) both move.
    _train_lvq21(w, lab, np.array([[1.08]]), np.array([1]), np.array([0.1]), 0.25)
    np.testing.assert_allclose(w[:, 0], [0.0, 0.9 - 0.1 * 0.18, 1.3 + 0.1 * (1.08 - 1.3)])
    # Neuron-index semantics: when the two nearest neurons are both of the wrong class, nothing
    # moves even though a correct prototype exists further away (a class-based runner-up
    # implementation would update it).
    w = np.array([[0.0], [1.0], [1.1], [3.0]])
    lab = np.array([1, 0, 0, 1])
    w0 = w.copy()
    _train_lvq21(w, lab, np.array([[1.05]]), np.array([1]), np.array([0.1]), 0.25)
    np.testing.assert_allclose(w, w0)


@pytest.mark.parametrize("algorithm", ["lvq1", "lvq2.1", "glvq"])
def test_learns_separable_blobs_more_prototypes_than_classes(algorithm):
    rng = np.random.default_rng(3)
    centres = np.array([[0, 0], [4, 0], [0, 4]])
    X = np.concatenate([c + rng.normal(0, 0.5, (100, 2)) for c in centres])
    y = np.repeat([0, 1, 2], 100)
    clf = LVQClassifier(n_prototypes=9, algorithm=algorithm, learning_rate=0.05, random_state=1).fit(X, y)
    assert clf.score(X, y) > 0.97
    assert clf.prototypes_.shape == (9, 2)
    np.testing.assert_array_equal(np.bincount(clf.prototype_labels_), [3, 3, 3])


def test_deterministic_with_seed_and_midpoint_init():
    rng = np.random.default_rng(0)
    X = rng.normal(size=(200, 3))
    y = (X[:, 0] > 0).astype(int)
    a = LVQClassifier(n_prototypes=4, random_state=7).fit(X, y).prototypes_
    b = LVQClassifier(n_prototypes=4, random_state=7).fit(X, y).prototypes_
    np.testing.assert_array_equal(a, b)
    m = LVQClassifier(n_prototypes=4, init="midpoint", max_iter=4000, learning_rate=0.05, random_state=0).fit(
        X, y
    )
    assert m.score(X, y) > 0.85


def test_predict_proba_and_distances_consistent():
    X = np.array([[0.0], [0.1], [1.0], [1.1]])
    y = np.array([0, 0, 1, 1])
    clf = LVQClassifier(n_prototypes=2, random_state=0).fit(X, y)
    p = clf.predict_proba(X)
    np.testing.assert_allclose(p.sum(axis=1), 1.0)
    np.testing.assert_array_equal(clf.classes_[p.argmax(axis=1)], clf.predict(X))
    assert clf.class_distances(X).shape == (4, 2)


@pytest.mark.parametrize(
    ("kw", "msg"),
    [
        ({"algorithm": "lvq3"}, "algorithm"),
        ({"window": 1.5}, "window"),
        ({"learning_rate": -1}, "learning_rate"),
    ],
)
def test_bad_params(kw, msg):
    with pytest.raises(InputError, match=msg):
        LVQClassifier(**kw).fit(np.zeros((4, 1)) + np.arange(4)[:, None], [0, 0, 1, 1])
