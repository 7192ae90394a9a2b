"""The UTM experiment of the report (quick) and the real-flight coverage check."""

from __future__ import annotations

import pytest

from uasnav.experiments import utm
from uasnav.trajectory.timebounds import clopper_pearson


@pytest.fixture(scope="module")
def model():
    from uasnav.experiments.trajectory import run_phantom4

    return run_phantom4(n_flights=5, n_train=3).predictor


def test_quick_experiment(model):
    r = utm.run(model, quick=True)
    c = r.coverage
    assert c.n == 10 and 0 <= c.k <= c.n and c.ci == clopper_pearson(c.k, c.n)
    assert r.contained  # the simulated survey stays inside its live volumes
    assert r.conflict is not None and r.conflict.later == "crossing"
    assert r.conflict.delay_s is not None and r.conflict.delay_s > 0
    assert r.conflicts_after_delay == 0
    # volumes in W84: home 450 m AMSL + N 47.3 m, ground ± 10 m buffer … 60 m + 10 m
    assert r.intent.volume_alt_w84.min() == pytest.approx(450 + 47.3 - 10)
    assert r.intent.volume_alt_w84.max() == pytest.approx(450 + 47.3 + 60 + 10)


def test_real_coverage_on_the_arducopter_runs(model, shared_data):
    k, n, ci = utm.real_coverage(
        model, str(shared_data / "flights" / "phoenix_mission1_arducopter.tlog"), n_cal=25
    )
    assert n == 5 and 0 <= k <= n
    assert ci == clopper_pearson(k, n) and ci[0] <= k / n <= ci[1]
