"""Scoring: Figure 74 transfer function, eq. 61, vectorised matrix vs a plain loop, ranking."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from uasnav.errors import InputError
from uasnav.mission import Targets, Weights, rank, score_matrix, transfer


def test_transfer_function_figure_74() -> None:
    # Lower is better (weight: target 800 g, limit 1600 g).
    x = np.array([0.0, 800.0, 1000.0, 1200.0, 1600.0, 5000.0])
    assert transfer(x, 800.0, 1600.0).tolist() == [0.0, 0.0, 0.25, 0.5, 1.0, 1.0]
    # Higher is better (range: target 5000 m, minimum 1500 m).
    r = np.array([10000.0, 5000.0, 3250.0, 1500.0, 100.0])
    assert transfer(r, 5000.0, 1500.0).tolist() == [0.0, 0.0, 0.5, 1.0, 1.0]
    assert str(transfer(4999.9999, 5000.0, 1500.0)) != "-0.0"
    with pytest.raises(InputError):
        transfer(1.0, 2.0, 2.0)


@given(
    st.floats(-1e6, 1e6),
    st.floats(-1e3, 1e3),
    st.floats(1e-3, 1e3),
)
def test_transfer_is_monotone_and_bounded(x: float, target: float, width: float) -> None:
    up = transfer(x, target, target + width)
    down = transfer(-x, -target, -target - width)  # mirrored "higher is better"
    assert 0.0 <= float(up) <= 1.0
    assert float(up) == pytest.approx(float(down), abs=1e-12)


def test_eq61_by_hand() -> None:
    # One UAS (range 3250 m, 1000 g, $2500) with one camera (200 g, $2000, 0.035 deg/px):
    # range 0.5, weight (1200-800)/800 = 0.5, cost (4500-4000)/3000 = 1/6, resolution 0.5.
    s = score_matrix(
        np.array([3250.0]),
        np.array([1000.0]),
        np.array([2500.0]),
        np.array([200.0]),
        np.array([2000.0]),
        np.array([0.035]),
    )
    expected = 0.5 + 0.75 * 0.5 + 1.25 / 6 + 0.5
    assert s.total[0, 0] == pytest.approx(expected, rel=1e-12)
    assert Weights() == Weights.order_by("cost") == Weights(1.0, 0.75, 1.25, 1.0)
    assert Weights.order_by("weight") == Weights(1.0, 1.25, 1.0, 1.0)
    with pytest.raises(InputError):
        Weights(cost=-1.0)


def test_vectorised_matches_loop_and_rank() -> None:
    rng = np.random.default_rng(3)
    nu, nc = 40, 15
    ur, um, uc = rng.uniform(500, 8000, nu), rng.uniform(300, 3000, nu), rng.uniform(500, 9000, nu)
    cm, cc, ci = rng.uniform(40, 600, nc), rng.uniform(300, 9000, nc), rng.uniform(0.005, 0.08, nc)
    feas = rng.random((nu, nc)) > 0.3
    t, w = Targets(), Weights(0.9, 0.7, 1.3, 1.1)
    s = score_matrix(ur, um, uc, cm, cc, ci, t, w, feas)
    for i in range(nu):
        for j in range(nc):
            ref = (
                w.range * min(max((ur[i] - 5000) / (1500 - 5000), 0), 1)
                + w.weight * min(max((um[i] + cm[j] - 800) / 800, 0), 1)
                + w.cost * min(max((uc[i] + cc[j] - 4000) / 3000, 0), 1)
                + w.resolution * min(max((ci[j] - 0.01) / 0.05, 0), 1)
            )
            if feas[i, j]:
                assert s.total[i, j] == pytest.approx(ref, abs=1e-12)
            else:
                assert s.total[i, j] == np.inf
    top = rank(s.total, 7)
    flat = sorted((s.total[i, j], i * nc + j) for i in range(nu) for j in range(nc) if feas[i, j])
    assert [divmod(k, nc) for _, k in flat[:7]] == top
    assert rank(np.full((2, 2), np.inf), 3) == []
