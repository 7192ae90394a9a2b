"""The authorisation summary: one page an operator can file (HTML with a print stylesheet) and
the same content as JSON for machines, written atomically.

Content: the operation and how each fact was derived, the category and its legal basis, the
SORA result (edition, GRC, ARC, TMPR, SAIL, OSOs) or the open subcategory, the standard
scenarios / PDRAs or FAA waivers, the geographical zones entered and what they require, the
necessary equipment against what the chosen UAS carries, and the chosen configuration with its
score.
"""

from __future__ import annotations

import html
import json
import os
from typing import Any

from uasnav.atomicfile import atomic_write_text
from uasnav.errors import InputError
from uasnav.jsonable import to_jsonable
from uasnav.mission.selection import Selection

SUMMARY_VERSION = "2"  # 2: authorisation verdict, flight window, withheld configurations


def summary_dict(sel: Selection) -> dict[str, Any]:
    """The summary's content as plain JSON-able data."""
    op = sel.operation
    chosen = sel.chosen
    d: dict[str, Any] = {
        "summary_version": SUMMARY_VERSION,
        "mission": {"id": sel.requirements.mission, "name": sel.mission_name},
        "operation": op.to_dict() if op else None,
        "category": {
            "jurisdiction": sel.requirements.jurisdiction,
            "category": op.category if op else sel.requirements.category,
            "legal_basis": op.legal_basis if op else None,
            "open_subcategory": chosen.open_subcategory if chosen and op and op.category == "open" else None,
        },
        "sora": sel.sora.to_dict() if sel.sora else None,
        "scenarios": [x.__dict__ | {"reasons": list(x.reasons)} for x in sel.scenarios],
        "zones": sel.zones.to_dict() if sel.zones else None,
        "equipment": {
            "necessary": [
                {"id": e.id, "name": e.name, "reason": e.reason} for e in sel.equipment if e.necessary
            ],
            "optional": [e.name for e in sel.equipment if not e.necessary],
            "on_chosen_uas": sel.equipment_on(chosen.uas_id) if chosen else [],
        },
        "authorisation": sel.authorisation,
        "flight_window": sel.flight_window,
        "withheld": [c.__dict__ for c in sel.withheld],
        "chosen": chosen.__dict__ if chosen else None,
        "alternatives": [c.__dict__ for c in sel.ranking[1:5]],
        "notes": list(sel.notes),
    }
    return to_jsonable(d)


_CSS = """
body{font:10.5pt/1.35 system-ui,sans-serif;margin:1.5em auto;max-width:60em;color:#111}
h1{font-size:15pt;margin:0 0 .2em}h2{font-size:11.5pt;margin:1em 0 .3em;border-bottom:1px solid #999}
table{border-collapse:collapse;width:100%;margin:.2em 0}td,th{border:1px solid #bbb;padding:.15em .4em;
vertical-align:top;text-align:left}th{background:#eee}.muted{color:#555;font-size:9pt}
.warn{color:#a00;font-weight:600}.ok{color:#060}
@media print{@page{size:A4;margin:12mm}body{margin:0;max-width:none;font-size:8.5pt}
h2{break-after:avoid}table{break-inside:avoid}a{color:inherit;text-decoration:none}}
"""


def _table(head: list[str], rows: list[list[Any]]) -> str:
    e = html.escape
    out = ["<table><tr>" + "".join(f"<th>{e(h)}</th>" for h in head) + "</tr>"]
    for r in rows:
        out.append("<tr>" + "".join(f"<td>{e('' if c is None else str(c))}</td>" for c in r) + "</tr>")
    return "".join(out) + "</table>"


def summary_html(sel: Selection) -> str:
    """The summary as one self-contained HTML page (print stylesheet included)."""
    d = summary_dict(sel)
    e = html.escape
    op, cat, sora, chosen = d["operation"], d["category"], d["sora"], d["chosen"]
    parts = [
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
        f"<title>Authorisation summary — {e(d['mission']['name'])}</title><style>{_CSS}</style></head><body>",
        f"<h1>Authorisation summary — {e(d['mission']['name'])}</h1>",
        "<p class='muted'>Produced by uasnav select; a decision aid, not an authorisation.</p>",
    ]
    auth = d["authorisation"]
    parts.append(f"<p class='{'ok' if auth['authorisable'] else 'warn'}'>Verdict: {e(auth['verdict'])}</p>")
    if auth["requirements"]:
        parts.append(
            "<h2>What the operation requires</h2><ul>"
            + "".join(f"<li>{e(n)}</li>" for n in auth["requirements"])
            + "</ul>"
        )
    parts.append("<h2>Operation and category</h2>")
    if op:
        parts.append(
            f"<p><b>{e(op['visibility'])}</b>, {op['max_distance_m']:g} m from the pilot, "
            f"{op['height_m']:g} m AGL, {e(op['environment'])} ({e(op['population'])}), "
            f"over people: {e(op['over_people'])}, {'night' if op['night'] else 'day'}, "
            f"airspace {e(op['airspace'])}.</p>"
        )
    parts.append(
        f"<p>Category: <b>{e(str(cat['jurisdiction']))} / {e(str(cat['category']))}</b> — "
        f"{e(str(cat['legal_basis']))}"
        + (f"; open subcategory <b>{e(cat['open_subcategory'])}</b>" if cat["open_subcategory"] else "")
        + "</p>"
    )
    if op:
        parts.append(
            _table(
                ["fact", "value", "from", "rule"],
                [[f["name"], f["value"], f["requirement"], f["rule"]] for f in op["derivation"]],
            )
        )
    if sora:
        parts.append(f"<h2>SORA {e(sora['edition'])}</h2>")
        parts.append(
            _table(
                ["iGRC", "final GRC", "initial ARC", "residual ARC", "TMPR", "SAIL"],
                [
                    [
                        sora["igrc"],
                        sora["final_grc"],
                        sora["initial_arc"],
                        sora["residual_arc"],
                        sora["tmpr"],
                        sora["sail"] or "certified category",
                    ]
                ],
            )
        )
        parts.append("<p class='muted'>" + e("; ".join(sora["steps"])) + "</p>")
        if sora["osos"]:
            parts.append(
                "<p class='muted'>OSOs: "
                + e(
                    ", ".join(
                        f"{o['id']} {o['robustness']}" for o in sora["osos"] if o["robustness"] != "optional"
                    )
                )
                + "</p>"
            )
    if d["scenarios"]:
        parts.append("<h2>Standard scenarios, PDRAs, waivers</h2>")
        parts.append(
            _table(
                ["", "applies / needed", "conditions", "source"],
                [
                    [s["id"], "yes" if s["applies"] else "no", "; ".join(s["reasons"]), s["source"]]
                    for s in d["scenarios"]
                ],
            )
        )
    parts.append("<h2>Geographical zones</h2>")
    z = d["zones"]
    fw = d["flight_window"]
    if fw is not None:
        parts.append(
            f"<p class='muted'>Schedules checked over the flight window {e(fw['start'])} – {e(fw['end'])} "
            f"({fw['duration_s']:.0f} s: {e(fw['from'])}).</p>"
        )
    if z is None:
        parts.append("<p class='warn'>No zone file or no area given: zones not checked.</p>")
    elif not z["hits"]:
        parts.append(f"<p class='ok'>No zone entered ({z['n_zones']} zones read from {e(z['source'])}).</p>")
    else:
        parts.append(
            _table(
                ["zone", "restriction", "requires", "message", "why"],
                [
                    [
                        f"{h['identifier']} {h['name']}",
                        h["restriction"],
                        h["requires"],
                        h["message"],
                        "; ".join(h["why"]),
                    ]
                    for h in z["hits"]
                ],
            )
        )
    parts.append("<h2>Equipment</h2>")
    on = {x["id"]: x["state"] for x in d["equipment"]["on_chosen_uas"]}
    parts.append(
        _table(
            ["necessary item", "on the chosen UAS", "why necessary"],
            [[x["name"], on.get(x["id"], "-"), x["reason"]] for x in d["equipment"]["necessary"]],
        )
    )
    parts.append("<p class='muted'>Optional: " + e(", ".join(d["equipment"]["optional"])) + "</p>")
    parts.append("<h2>Chosen configuration</h2>")
    if chosen:
        parts.append(
            _table(
                ["UAS", "camera", "score (eq. 61, lower is better)", "mass g", "cost $", "SAIL"],
                [
                    [
                        chosen["uas"],
                        chosen["camera"],
                        f"{chosen['score']:.3f}",
                        f"{chosen['mass_g']:.0f}",
                        f"{chosen['cost_usd']:.0f}",
                        chosen["sail"],
                    ]
                ],
            )
        )
    elif d["withheld"]:
        w0 = d["withheld"][0]
        parts.append(
            "<p class='warn'>None: the area enters a PROHIBITED zone. Would rank first only with an "
            f"exemption from the zone authority: {e(w0['uas'])} + {e(w0['camera'])}.</p>"
        )
    else:
        parts.append("<p class='warn'>No feasible configuration.</p>")
    if d["notes"]:
        parts.append("<h2>Notes</h2><ul>" + "".join(f"<li>{e(n)}</li>" for n in d["notes"]) + "</ul>")
    parts.append("</body></html>")
    return "\n".join(parts)


def write_summary(sel: Selection, path: str | os.PathLike[str]) -> str:
    """Write the summary to ``path`` atomically: ``.html``/``.htm`` → the page, ``.json`` → the
    data. Returns the format written."""
    p = os.fspath(path)
    ext = os.path.splitext(p)[1].lower()
    if ext in (".html", ".htm"):
        atomic_write_text(p, summary_html(sel))
        return "html"
    if ext == ".json":
        atomic_write_text(p, json.dumps(summary_dict(sel), indent=2, allow_nan=False) + "\n")
        return "json"
    raise InputError(f"{p}: summary must end in .html or .json")
