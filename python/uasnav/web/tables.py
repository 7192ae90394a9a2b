"""The loaded documents as tables for the database pages and ``/api/db/…``.

Each table is (columns, rows) with units in the column names and every entry's source. The
pages filter (``q``) and sort (``sort``, ``desc``) on the server, so they work without
JavaScript; the small script only makes the same thing instant.
"""

from __future__ import annotations

import math
from typing import Any

from uasnav.mission.database import Database
from uasnav.mission.matrices import Matrices
from uasnav.mission.regulations import Regulations

Table = tuple[list[str], list[dict[str, Any]]]

#: Tables served, by URL name: title shown on the page.
TABLES = {
    "uas": "UAS",
    "cameras": "Cameras",
    "regulations": "Regulations",
    "missions": "Missions",
    "equipment": "Equipment",
}


def _num(x: Any) -> float | None:
    v = float(x)
    return v if math.isfinite(v) else None


def uas_table(db: Database) -> Table:
    u = db.uas
    cols = [
        "id",
        "producer",
        "name",
        "type",
        "cost_usd",
        "mass_g",
        "max_takeoff_g",
        "payload_g",
        "endurance_min",
        "max_speed_ms",
        "max_altitude_m",
        "max_range_m",
        "span_m",
        "eu_class",
        "rain",
        "estimated",
        "source",
    ]
    rows = [
        {
            "id": u.ids[i],
            "producer": u.producers[i],
            "name": u.names[i],
            "type": u.types[i],
            "cost_usd": _num(u.cost_usd[i]),
            "mass_g": _num(u.mass_g[i]),
            "max_takeoff_g": _num(u.max_takeoff_g[i]),
            "payload_g": _num(u.payload_g[i]),
            "endurance_min": _num(u.endurance_min[i]),
            "max_speed_ms": _num(u.max_speed_ms[i]),
            "max_altitude_m": _num(u.max_altitude_m[i]),
            "max_range_m": _num(u.max_range_m[i]),
            "span_m": _num(u.span_m[i]),
            "eu_class": u.eu_class[i],
            "rain": bool(u.rain[i]),
            "estimated": " ".join(sorted(u.estimated[i])),
            "source": u.sources[i],
        }
        for i in range(len(u))
    ]
    return cols, rows


def camera_table(db: Database) -> Table:
    c = db.cameras
    cols = [
        "id",
        "producer",
        "name",
        "type",
        "cost_usd",
        "mass_g",
        "hfov_deg",
        "resolution_w_px",
        "resolution_h_px",
        "ifov_deg_px",
        "bands",
        "estimated",
        "source",
    ]
    ifov = c.ifov_deg
    rows = [
        {
            "id": c.ids[i],
            "producer": c.producers[i],
            "name": c.names[i],
            "type": c.types[i],
            "cost_usd": _num(c.cost_usd[i]),
            "mass_g": _num(c.mass_g[i]),
            "hfov_deg": _num(c.hfov_deg[i]),
            "resolution_w_px": _num(c.resolution_w_px[i]),
            "resolution_h_px": _num(c.resolution_h_px[i]),
            "ifov_deg_px": _num(ifov[i]),
            "bands": c.bands[i],
            "estimated": " ".join(sorted(c.estimated[i])),
            "source": c.sources[i],
        }
        for i in range(len(c))
    ]
    return cols, rows


def regulations_table(regs: Regulations) -> Table:
    cols = ["jurisdiction", "scope", "id", "quantity", "limit", "unit", "vlos_required", "source"]
    rows: list[dict[str, Any]] = []
    for jid, j in regs.jurisdictions.items():
        for cid, cat in j.categories.items():
            for lim in cat.limits:
                rows.append(
                    {
                        "jurisdiction": jid,
                        "scope": "category",
                        "id": cid,
                        "quantity": lim.quantity,
                        "limit": f"{'<' if lim.op == 'lt' else '≤'} {lim.value:g}",
                        "unit": lim.unit,
                        "vlos_required": cat.vlos_required,
                        "source": lim.source or cat.source,
                    }
                )
        for kid, limits in j.classes.items():
            for lim in limits:
                rows.append(
                    {
                        "jurisdiction": jid,
                        "scope": "class",
                        "id": kid,
                        "quantity": lim.quantity,
                        "limit": f"{'<' if lim.op == 'lt' else '≤'} {lim.value:g}",
                        "unit": lim.unit,
                        "vlos_required": None,
                        "source": lim.source,
                    }
                )
    return cols, rows


def mission_table(m: Matrices) -> Table:
    feats = list(m.features)
    cols = ["id", "name", *[m.feature_names.get(f, f) for f in feats], "source"]
    rows = [
        {
            "id": mid,
            "name": mis.name,
            **{m.feature_names.get(f, f): ", ".join(mis.features.get(f, ())) for f in feats},
            "source": m.source,
        }
        for mid, mis in m.missions.items()
    ]
    return cols, rows


def equipment_table(m: Matrices) -> Table:
    cols = ["id", "name", "group", "always_necessary", "note", "source"]
    rows = [
        {
            "id": e.id,
            "name": e.name,
            "group": e.group,
            "always_necessary": e.always_necessary,
            "note": e.note,
            "source": m.source,
        }
        for e in m.equipment.values()
    ]
    return cols, rows


def filter_sort(table: Table, q: str | None, sort: str | None, desc: bool) -> Table:
    """Rows containing every word of ``q`` (case-insensitive, any column), sorted by ``sort``
    (numbers numerically, missing values last)."""
    cols, rows = table
    if q:
        words = q.lower().split()
        rows = [r for r in rows if all(any(w in str(v).lower() for v in r.values()) for w in words)]
    if sort in cols:

        def key(r: dict[str, Any]) -> tuple[int, Any]:
            v = r.get(sort)
            if v is None:
                return (1, 0)
            if isinstance(v, bool | int | float):
                return (0, (0, float(v), ""))
            return (0, (1, 0.0, str(v).lower()))

        present = [r for r in rows if r.get(sort) is not None]
        missing = [r for r in rows if r.get(sort) is None]
        rows = sorted(present, key=key, reverse=desc) + missing
    return cols, rows


__all__ = [
    "TABLES",
    "camera_table",
    "equipment_table",
    "filter_sort",
    "mission_table",
    "regulations_table",
    "uas_table",
]
