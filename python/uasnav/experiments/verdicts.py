"""Stated rules for every verdict the report prints, computed from the numbers.

A verdict is one of :data:`CONFIRMED`, :data:`PARTLY`, :data:`NOT_CONFIRMED` (or, for a change
between two numbers, a word such as ``"grows"``) together with the rule that produced it and the
inputs it was computed from. The report's sentence around a verdict is generated from the same
:class:`Verdict` (:attr:`Verdict.sentence`), and ``report.json`` records ``verdict``, ``rule``
and ``inputs`` under each section's ``"verdicts"`` key, so a reader can recompute it.

Rules (all on our own simulated numbers; none compares against "the thesis' number is beaten"):

* :func:`tczupt_claim` — the thesis' claim "TCZUPT converges faster and is not worse in RMS":
  per axis, it *holds* when TCZUPT reached 1e-5 rad/s first from the exact start **and** its
  whole-run RMS error is not above ZUPT's beyond the Monte-Carlo spread (mean of the per-run
  differences ≤ 2 standard errors). Confirmed on all three axes, partly on one or two, not
  confirmed on none.
* :func:`within_spread` — a quoted value (e.g. the thesis' Table-15 Δt%) against our Monte-Carlo
  distribution of the same quantity: consistent where it lies within the 5th–95th percentile.
  Confirmed at every point, partly at some, not confirmed at none.
* :func:`change` — "grows"/"shrinks" only when the relative change exceeds a tolerance (5 %, the
  same "no significant improvement" tolerance as the Sr structure selection), else "is unchanged".
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

CONFIRMED = "confirmed"
PARTLY = "partly"
NOT_CONFIRMED = "not confirmed"

#: Standard errors of the Monte-Carlo mean a difference must exceed to count (≈ 95 %, two-sided).
MC_SIGMAS = 2.0
#: Percentiles of a Monte-Carlo distribution taken as its spread.
SPREAD_PERCENTILES = (5.0, 95.0)
#: Relative change below which two numbers are called unchanged (as in thermal ``choose``).
CHANGE_REL_TOL = 0.05


@dataclass(frozen=True)
class Verdict:
    """A verdict, the rule that produced it, its inputs and the sentence stating it.

    Attributes
    ----------
    verdict : str
        The outcome (e.g. ``"confirmed"``, ``"partly"``, ``"not confirmed"``, ``"grows"``).
    rule : str
        The rule in words, with its thresholds.
    inputs : dict
        The numbers the rule was applied to (JSON-able).
    sentence : str
        The report's sentence, generated from ``verdict`` and ``inputs``.
    """

    verdict: str
    rule: str
    inputs: dict[str, Any] = field(default_factory=dict)
    sentence: str = ""

    def to_dict(self) -> dict[str, Any]:
        """``{"verdict", "rule", "inputs"}`` as recorded in report.json."""
        return {"verdict": self.verdict, "rule": self.rule, "inputs": self.inputs}


def _count_verdict(n_hold: int, n_total: int) -> str:
    if n_total > 0 and n_hold == n_total:
        return CONFIRMED
    return PARTLY if n_hold > 0 else NOT_CONFIRMED


def not_worse_beyond_spread(diff_runs: np.ndarray, sigmas: float = MC_SIGMAS) -> np.ndarray:
    """Per column: is the mean of ``diff_runs`` (runs × axes, candidate − reference) at most
    ``sigmas`` standard errors above zero? (True = not worse beyond the Monte-Carlo spread.)"""
    d = np.atleast_2d(np.asarray(diff_runs, dtype=float))
    n = d.shape[0]
    se = d.std(axis=0, ddof=1) / np.sqrt(n) if n > 1 else np.zeros(d.shape[1])
    return np.asarray(d.mean(axis=0) <= sigmas * se)


def tczupt_claim(faster: Sequence[bool], rms_tczupt: np.ndarray, rms_zupt: np.ndarray) -> Verdict:
    """The thesis' claim "TCZUPT converges faster in the 15 deg/h scenario and is not worse in
    RMS over the whole run", per axis.

    Parameters
    ----------
    faster : sequence of bool, length 3
        Per axis, whether TCZUPT reached 1e-5 rad/s before ZUPT (exact start + 15 deg/h).
    rms_tczupt, rms_zupt : ndarray, shape (n_runs, 3)
        Per Monte-Carlo run and axis, the whole-run RMS error against truth (rad/s).
    """
    faster_a = np.asarray(faster, dtype=bool)
    a, b = np.asarray(rms_tczupt, dtype=float), np.asarray(rms_zupt, dtype=float)
    d = a - b
    not_worse = not_worse_beyond_spread(d)
    holds = faster_a & not_worse
    v = _count_verdict(int(holds.sum()), holds.size)
    n = d.shape[0]
    se = d.std(axis=0, ddof=1) / np.sqrt(n) if n > 1 else np.zeros(d.shape[1])
    rule = (
        "per axis the claim holds if TCZUPT reached 1e-5 rad/s before ZUPT (exact start + 15 deg/h) "
        f"and the Monte-Carlo mean of its whole-run RMS error minus ZUPT's is at most {MC_SIGMAS:g} "
        "standard errors above 0 (not worse beyond the spread); confirmed if it holds on every axis, "
        "partly on some, not confirmed on none"
    )
    inputs = {
        "faster": faster_a.tolist(),
        "rms_diff_mean_rad_s": d.mean(axis=0).tolist(),
        "rms_diff_standard_error_rad_s": se.tolist(),
        "n_runs": n,
        "not_worse": not_worse.tolist(),
        "holds": holds.tolist(),
    }
    axes = "xyz"

    def on(mask: np.ndarray) -> str:
        return "axes " + ", ".join(axes[i] for i in np.flatnonzero(mask))

    held = f" ({on(holds)[5:]})" if holds.any() else ""  # without the word "axes"
    slower = (
        f"TCZUPT was not first to converge on {on(~faster_a)}"
        if (~faster_a).any()
        else ("TCZUPT converged first on every axis")
    )
    worse = (
        f"is worse in RMS beyond the Monte-Carlo spread on {on(~not_worse)}"
        if (~not_worse).any()
        else "is not worse in RMS beyond the Monte-Carlo spread on any axis"
    )
    sentence = (
        f"{v.upper()}: the claim holds on {int(holds.sum())}/{holds.size} axes{held}; {slower}, and it "
        f"{worse} ({n} runs, {MC_SIGMAS:g} standard errors)"
    )
    return Verdict(v, rule, inputs, sentence)


def within_spread(
    quoted: Sequence[float | None],
    samples: Sequence[Sequence[float]],
    labels: Sequence[str],
    what: str,
) -> Verdict:
    """Is each quoted value within the Monte-Carlo spread of the same quantity?

    Parameters
    ----------
    quoted : sequence of float or None
        The values to check (e.g. the thesis' Δt%), one per point; None = no value (skipped).
    samples : sequence of sequence of float
        Our Monte-Carlo values at each point (empty = not reached; the point is skipped).
    labels : sequence of str
        A name for each point (e.g. the threshold).
    what : str
        What is compared, for the sentence.
    """
    lo_p, hi_p = SPREAD_PERCENTILES
    pts = []
    for q, s, lab in zip(quoted, samples, labels, strict=True):
        s = np.asarray(s, dtype=float)
        if q is None or s.size == 0:
            continue
        lo, hi = (float(x) for x in np.percentile(s, [lo_p, hi_p]))
        pts.append(
            {
                "point": lab,
                "quoted": float(q),
                "lo": lo,
                "hi": hi,
                "n": int(s.size),
                "inside": bool(lo <= q <= hi),
            }
        )
    n_in = sum(p["inside"] for p in pts)
    v = _count_verdict(n_in, len(pts))
    rule = (
        f"a quoted value is consistent where it lies within the {lo_p:g}th–{hi_p:g}th percentile of "
        "our Monte-Carlo values at the same point; confirmed if at every point, partly at some, "
        "not confirmed at none (points without a value or never reached are skipped)"
    )
    detail = "; ".join(
        f"{p['point']}: {p['quoted']:.3g} {'inside' if p['inside'] else 'outside'} "
        f"[{p['lo']:.3g}, {p['hi']:.3g}]"
        for p in pts
    )
    sentence = (
        f"{what} within our Monte-Carlo spread ({lo_p:g}th–{hi_p:g}th percentile) at {n_in} of "
        f"{len(pts)} points — {v}" + (f" ({detail})" if detail else "")
    )
    return Verdict(v, rule, {"points": pts}, sentence)


def ratios_near_one(ratios: dict[str, float], rel_tol: float = 0.10) -> Verdict:
    """Do ablation ratios (e.g. "ZUPT given σ'_GBI over TCZUPT") all lie within ``1 ± rel_tol``?

    Used for "the difference comes from the process noise, not from eq. (31)": swapping only the
    process noise between the filters must make them score alike. Confirmed if every ratio is
    within the band, partly if some, not confirmed if none.
    """
    inside = {k: bool(abs(float(v) - 1.0) <= rel_tol) for k, v in ratios.items()}
    v = _count_verdict(sum(inside.values()), len(inside))
    rule = f"each ratio within 1 ± {rel_tol:g}; confirmed if all are, partly if some, not confirmed if none"
    detail = ", ".join(f"{k} {float(x):.2f}" for k, x in ratios.items())
    return Verdict(
        v,
        rule,
        {"ratios": {k: float(x) for k, x in ratios.items()}, "inside": inside},
        f"{v} ({detail}; band 1 ± {rel_tol:g})",
    )


def majority(n_part: int, n_total: int) -> Verdict:
    """ "most" if ``n_part`` is more than half of ``n_total``, "some" if > 0, else "none"
    (e.g. how many of Table 20's disagreements fall into the kinds a sentence explains)."""
    word = "most" if 2 * n_part > n_total else ("some" if n_part > 0 else "none")
    rule = "most if more than half, some if at least one, none otherwise"
    return Verdict(
        word,
        rule,
        {"n_part": int(n_part), "n_total": int(n_total)},
        f"{word} ({n_part} of {n_total})",
    )


def nees_consistency(mean: float, lo: float, hi: float, n_runs: int) -> Verdict:
    """ "consistent" if the time mean of the run-averaged NEES lies within its 99 % χ² bounds,
    "over-confident" above them, "under-confident" below."""
    if mean > hi:
        word = "over-confident"
    elif mean < lo:
        word = "under-confident"
    else:
        word = "consistent"
    rule = (
        "consistent if the time mean of the NEES averaged over the Monte-Carlo runs lies within the "
        "99 % χ² bounds for that number of runs; above: over-confident, below: under-confident"
    )
    inputs = {"mean": float(mean), "lo": float(lo), "hi": float(hi), "n_runs": int(n_runs)}
    return Verdict(word, rule, inputs, f"{word} (mean {mean:.2g}, bounds {lo:.2g}–{hi:.2g})")


def change(before: float, after: float, rel_tol: float = CHANGE_REL_TOL) -> Verdict:
    """ "grows" / "shrinks" / "is unchanged" from ``before`` to ``after`` (relative tolerance)."""
    b, a = float(before), float(after)
    rel = (a - b) / abs(b) if b != 0 else (np.inf if a != b else 0.0)
    if rel > rel_tol:
        word = "grows"
    elif rel < -rel_tol:
        word = "shrinks"
    else:
        word = "is unchanged"
    rule = (
        f"grows/shrinks if the relative change exceeds {rel_tol:.0%}, otherwise unchanged (the "
        "tolerance of the Sr structure selection's 'no significant improvement')"
    )
    if word == "is unchanged":
        sentence = f"is unchanged within {rel_tol:.0%} ({b:.3g} → {a:.3g}, {rel:+.1%})"
    else:
        sentence = f"{word} from {b:.3g} to {a:.3g} ({rel:+.1%})"
    return Verdict(word, rule, {"before": b, "after": a, "relative_change": float(rel)}, sentence)


__all__ = [
    "CHANGE_REL_TOL",
    "CONFIRMED",
    "MC_SIGMAS",
    "NOT_CONFIRMED",
    "PARTLY",
    "SPREAD_PERCENTILES",
    "Verdict",
    "change",
    "majority",
    "nees_consistency",
    "not_worse_beyond_spread",
    "ratios_near_one",
    "tczupt_claim",
    "within_spread",
]
