"""Each verdict rule of uasnav.experiments.verdicts on constructed inputs: confirmed, partly and
not confirmed, with the sentence generated from the same numbers (issue 14, honest verdicts)."""

from __future__ import annotations

import numpy as np
import pytest

from uasnav.experiments import verdicts as V
from uasnav.report import SectionWriter


def _runs(diff: list[float], spread: float, n: int = 6, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(tczupt, zupt) per-run RMS with per-axis mean difference ``diff`` and noise ``spread``."""
    rng = np.random.default_rng(seed)
    zupt = 1e-4 + rng.uniform(0, 1e-5, (n, 3))
    noise = rng.normal(0, 1, (n, 3))
    noise = (noise - noise.mean(axis=0)) / noise.std(axis=0, ddof=1) * spread  # exact mean/std
    return zupt + np.array(diff) + noise, zupt


def test_tczupt_claim_confirmed_partly_not() -> None:
    # Faster on every axis and not worse: confirmed.
    a, b = _runs([0.0, -1e-6, 1e-7], spread=1e-6)
    v = V.tczupt_claim([True, True, True], a, b)
    assert v.verdict == V.CONFIRMED and v.inputs["holds"] == [True, True, True]
    assert v.sentence.startswith("CONFIRMED: the claim holds on 3/3 axes")
    # Worse on z by 10 standard errors: holds on x, y only → partly, and the sentence names z.
    se = 1e-6 / np.sqrt(6)
    a, b = _runs([0.0, 0.0, 10 * se], spread=1e-6)
    v = V.tczupt_claim([True, True, True], a, b)
    assert v.verdict == V.PARTLY and v.inputs["not_worse"] == [True, True, False]
    assert "worse in RMS beyond the Monte-Carlo spread on axes z" in v.sentence
    # A difference within the spread (1 standard error) is not "worse".
    a, b = _runs([se, se, se], spread=1e-6)
    assert V.tczupt_claim([True, True, True], a, b).verdict == V.CONFIRMED
    # Never faster: not confirmed, whatever the RMS.
    v = V.tczupt_claim([False, False, False], a, b)
    assert v.verdict == V.NOT_CONFIRMED and "not first to converge on axes x, y, z" in v.sentence
    # Faster only on y: partly.
    assert V.tczupt_claim([False, True, False], a, b).verdict == V.PARTLY
    assert "rule" in v.to_dict() and v.to_dict()["inputs"]["n_runs"] == 6


def test_not_worse_beyond_spread_boundary() -> None:
    d = np.array([[1.0], [3.0]])  # mean 2, std √2, se 1
    assert V.not_worse_beyond_spread(d, sigmas=2.0).tolist() == [True]
    assert V.not_worse_beyond_spread(d, sigmas=1.9).tolist() == [False]


def test_within_spread_rule() -> None:
    samples = [np.linspace(0, 100, 101)] * 3  # 5th–95th percentile: [5, 95]
    labels = ["a", "b", "c"]
    v = V.within_spread([10.0, 50.0, 94.0], samples, labels, "q")
    assert v.verdict == V.CONFIRMED and all(p["inside"] for p in v.inputs["points"])
    v = V.within_spread([10.0, 99.0, 1.0], samples, labels, "q")
    assert v.verdict == V.PARTLY and "at 1 of 3 points" in v.sentence and "99 outside [5, 95]" in v.sentence
    assert V.within_spread([200.0, -5.0, 96.0], samples, labels, "q").verdict == V.NOT_CONFIRMED
    # Points without a quoted value or never reached are skipped, not counted as failures.
    v = V.within_spread([None, 50.0, 50.0], [samples[0], [], samples[0]], labels, "q")
    assert v.verdict == V.CONFIRMED and [p["point"] for p in v.inputs["points"]] == ["c"]


def test_change_rule_never_says_grows_for_a_smaller_number() -> None:
    # The report once said Sr "grows from 0.000564 to 0.000563".
    v = V.change(0.000564, 0.000563)
    assert v.verdict == "is unchanged" and "grows" not in v.sentence
    assert V.change(1.0, 1.2).verdict == "grows" and V.change(1.0, 0.8).verdict == "shrinks"
    assert V.change(1.0, 1.04).verdict == "is unchanged" and V.change(1.0, 1.06).verdict == "grows"
    v = V.change(2.0, 3.0)
    assert v.sentence == "grows from 2 to 3 (+50.0%)" and v.inputs["relative_change"] == pytest.approx(0.5)


def test_ratios_and_nees_rules() -> None:
    assert V.ratios_near_one({"a": 0.95, "b": 1.09}).verdict == V.CONFIRMED
    assert V.ratios_near_one({"a": 0.95, "b": 1.3}).verdict == V.PARTLY
    assert V.ratios_near_one({"a": 0.5, "b": 1.3}).verdict == V.NOT_CONFIRMED
    assert V.nees_consistency(3.0, 2.0, 4.0, 6).verdict == "consistent"
    assert V.nees_consistency(5.0, 2.0, 4.0, 6).verdict == "over-confident"
    assert V.nees_consistency(1.0, 2.0, 4.0, 6).verdict == "under-confident"


def test_section_writer_records_rule_and_returns_the_sentence(tmp_path) -> None:
    w = SectionWriter(key="k", seed=0, quick=True, out_dir=tmp_path, progress=lambda _m: None)
    v = V.change(1.0, 2.0)
    assert w.verdict("x", v) == v.sentence
    assert w.data["verdicts"]["x"] == {"verdict": "grows", "rule": v.rule, "inputs": v.inputs}


def test_majority_rule() -> None:
    assert V.majority(70, 133).verdict == "most" and V.majority(70, 133).sentence == "most (70 of 133)"
    assert V.majority(66, 132).verdict == "some"  # exactly half is not "most"
    assert V.majority(0, 10).verdict == "none"
