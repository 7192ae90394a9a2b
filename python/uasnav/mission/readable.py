"""Lengths as an operator reads them, in every text the selection and the plan print.

The numbers in ``result.json`` keep their full precision; the sentences built from them
(notes, regulation lines, derivations, the CLI summary, the web page and its print view)
round a distance or a height to what matters on the field: whole metres from 10 m, one
decimal below. A value compared with a limit that would round to the limit keeps the
decimals that tell them apart, so "1000.4 m exceeds 1000 m" never reads "1000 m exceeds 1000 m".

Examples
--------
>>> metres(44.4733)
'44 m'
>>> metres(2.83)
'2.8 m'
>>> metres(120.0)
'120 m'
>>> metres(500.3, against=500.0)
'500.3 m'
"""

from __future__ import annotations

import math


def _number(x: float, decimals: int) -> str:
    text = f"{x:.{decimals}f}"
    return text.rstrip("0").rstrip(".") if "." in text else text


def metres(x: float, *, against: float | None = None) -> str:
    """``x`` metres as text with its unit: whole metres from 10 m, one decimal below.

    Parameters
    ----------
    x : float
        A length, m.
    against : float, optional
        A limit ``x`` is compared with, m: decimals are added (up to three) until ``x`` and
        the limit no longer read the same.
    """
    if not math.isfinite(x):
        return f"{x} m"
    decimals = 0 if abs(x) >= 9.95 else 1
    if against is not None and math.isfinite(against) and x != against:
        while decimals < 3 and _number(x, decimals) == _number(against, decimals):
            decimals += 1
    return f"{_number(x, decimals)} m"
