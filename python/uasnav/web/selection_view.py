"""What the selection page draws from a selection: CSV tables, Figure 74's transfer functions
with the ranked configurations on them, and each configuration's score breakdown (eq. 61).

All inputs are the plain dict of :meth:`uasnav.mission.Selection.to_dict` (the API's answer)
plus the request's targets, so the page shows exactly what the API returns.
"""

from __future__ import annotations

import csv
import io
from typing import Any

import numpy as np

from uasnav.mission.database import Database
from uasnav.mission.scoring import PARAMETERS, Targets, transfer

#: Per parameter: label, unit, and the Targets field holding (target, limit).
PARAMETER_INFO = {
    "range": ("Range", "m", "range_m"),
    "weight": ("Take-off mass", "g", "weight_g"),
    "cost": ("Cost", "USD", "cost_usd"),
    "resolution": ("Angular resolution", "deg/px", "resolution_deg"),
}
RANKING_COLUMNS = (
    "rank",
    "uas_id",
    "uas",
    "camera_id",
    "camera",
    "score",
    "score_range",
    "score_weight",
    "score_cost",
    "score_resolution",
    "mass_g",
    "cost_usd",
    "visibility",
    "category",
    "open_subcategory",
)
REJECTION_COLUMNS = ("kind", "item", "test", "value", "limit", "unit", "margin", "message")


def margin(rej: dict[str, Any]) -> float | None:
    """How far the rejected value is from its limit, in the test's unit (|value − limit|)."""
    v, lim = rej.get("value"), rej.get("limit")
    if v is None or lim is None:
        return None
    return abs(float(v) - float(lim))


def ranking_csv(sel: dict[str, Any]) -> str:
    """The ranked configurations as CSV (one row per configuration, rank first)."""
    out = io.StringIO()
    w = csv.DictWriter(out, RANKING_COLUMNS, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for i, row in enumerate(sel["ranking"], 1):
        w.writerow({**row, "rank": i})
    return out.getvalue()


def rejections_csv(sel: dict[str, Any]) -> str:
    """Every rejection with its failed test, value, limit and margin as CSV."""
    out = io.StringIO()
    w = csv.DictWriter(out, REJECTION_COLUMNS, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for row in sel["rejections"]:
        w.writerow({**row, "margin": margin(row)})
    return out.getvalue()


def _config_values(sel: dict[str, Any], db: Database) -> list[dict[str, float]]:
    """The four scored values of each ranked configuration (units of PARAMETER_INFO)."""
    u, c = db.uas, db.cameras
    ui = {k: i for i, k in enumerate(u.ids)}
    ci = {k: i for i, k in enumerate(c.ids)}
    ifov = c.ifov_deg
    out = []
    for row in sel["ranking"]:
        i, j = ui.get(row["uas_id"]), ci.get(row["camera_id"])
        out.append(
            {
                "range": float(u.max_range_m[i]) if i is not None else float("nan"),
                "weight": float(row["mass_g"]),
                "cost": float(row["cost_usd"]),
                "resolution": float(ifov[j]) if j is not None else float("nan"),
            }
        )
    return out


def transfer_plots(sel: dict[str, Any], targets: Targets, db: Database, top: int = 5) -> list[dict[str, Any]]:
    """Figure 74 per parameter: the transfer line in a 240×120 box and the best ``top``
    configurations as dots on it (x clipped to the plotted span)."""
    values = _config_values(sel, db)[:top]
    w, h, pad = 240.0, 120.0, 22.0
    plots = []
    for p in PARAMETERS:
        label, unit, attr = PARAMETER_INFO[p]
        target, limit = getattr(targets, attr)
        lo, hi = min(target, limit), max(target, limit)
        span = hi - lo
        x0, x1 = lo - 0.5 * span, hi + 0.5 * span

        def sx(x: float, x0: float = x0, x1: float = x1) -> float:
            return round(pad + (min(max(x, x0), x1) - x0) / (x1 - x0) * (w - 2 * pad), 2)

        def sy(s: float) -> float:
            return round(h - pad - s * (h - 2 * pad), 2)

        xs = np.array([x0, lo, hi, x1])
        line = " ".join(f"{sx(x)},{sy(float(transfer(x, target, limit)))}" for x in xs)
        dots = [
            {"rank": k + 1, "x": sx(v[p]), "y": sy(float(transfer(v[p], target, limit))), "value": v[p]}
            for k, v in enumerate(values)
            if np.isfinite(v[p])
        ]
        plots.append(
            {
                "parameter": p,
                "label": label,
                "unit": unit,
                "target": target,
                "limit": limit,
                "weight": sel["weights"][p],
                "line": line,
                "dots": dots,
                "x_target": sx(target),
                "x_limit": sx(limit),
                "width": w,
                "height": h,
                "pad": pad,
                "y0": sy(0.0),
                "y1": sy(1.0),
            }
        )
    return plots


def breakdown(sel: dict[str, Any]) -> dict[str, Any]:
    """Each ranked configuration's total as stacked weighted partial scores w·s (eq. 61)."""
    weights = sel["weights"]
    rows = []
    for i, r in enumerate(sel["ranking"], 1):
        parts = [(p, weights[p] * (r[f"score_{p}"] or 0.0)) for p in PARAMETERS]
        rows.append({"rank": i, "uas": r["uas"], "camera": r["camera"], "score": r["score"], "parts": parts})
    # the bar scale: the largest possible total (every partial at its limit) keeps bars comparable
    full = sum(weights[p] for p in PARAMETERS) or 1.0
    for row in rows:
        x = 0.0
        segs = []
        for p, v in row["parts"]:
            wpct = 100.0 * v / full
            segs.append({"parameter": p, "value": v, "x": round(x, 3), "w": round(wpct, 3)})
            x += wpct
        row["segments"] = segs
    return {"rows": rows, "full": full}


__all__ = [
    "PARAMETER_INFO",
    "RANKING_COLUMNS",
    "REJECTION_COLUMNS",
    "breakdown",
    "margin",
    "ranking_csv",
    "rejections_csv",
    "transfer_plots",
]
