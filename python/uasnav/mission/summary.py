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
from uasnav.mission.readable import metres
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


#: The summary's stylesheet, scoped to ``.auth-summary`` so the web application links the same
#: file into its results page (whose print view is this summary) without restyling the page.
SUMMARY_CSS = """
.auth-summary{font:10.5pt/1.35 system-ui,sans-serif;color:#111}
.auth-summary h2{font-size:15pt;margin:0 0 .2em;border:0}
.auth-summary h3{font-size:11.5pt;margin:1em 0 .3em;border-bottom:1px solid #999}
.auth-summary table{border-collapse:collapse;width:100%;margin:.2em 0}
.auth-summary td,.auth-summary th{border:1px solid #bbb;padding:.15em .4em;vertical-align:top;text-align:left}
.auth-summary th{background:#eee;font-weight:600}
.auth-summary td.num,.auth-summary th.num{text-align:right;font-variant-numeric:tabular-nums;
white-space:nowrap}
.auth-summary .muted{color:#555;font-size:9pt}
.auth-summary .warn{color:#a00;font-weight:600}.auth-summary .ok{color:#060}
.auth-summary .verdict{font-size:12pt;font-weight:700;padding:.35em .6em;margin:.4em 0;border:2px solid;
border-radius:4px}
.auth-summary .verdict.warn{background:#fdecec;border-color:#a00}
.auth-summary .verdict.ok{background:#e8f3ec;border-color:#060}
.auth-summary ul.osos{display:flex;flex-wrap:wrap;gap:.15em .6em;list-style:none;padding:0;margin:.2em 0;
font-size:9pt}
.auth-summary ul.osos b{font-variant-numeric:tabular-nums}
@media print{@page{size:A4;margin:10mm}
.auth-summary{font-size:6.4pt;line-height:1.22;columns:2;column-gap:5mm}
.auth-summary h2{font-size:11pt;column-span:all}.auth-summary h2+.muted{column-span:all;margin:0}
.auth-summary .verdict{font-size:8.5pt;column-span:all;padding:.2em .5em}
.auth-summary h3{font-size:7.5pt;margin:.5em 0 .15em;break-after:avoid}
.auth-summary p,.auth-summary ul{margin:.15em 0}.auth-summary ul{padding-left:1.2em}
.auth-summary .muted,.auth-summary ul.osos{font-size:6pt}
.auth-summary td,.auth-summary th{padding:0 .25em}
.auth-summary .chosen{column-span:all}

.auth-summary tr{break-inside:avoid}.auth-summary a{color:inherit;text-decoration:none}
.auth-summary *{-webkit-print-color-adjust:exact;print-color-adjust:exact}}
"""
#: The stand-alone document's page layout (the web page has its own).
_PAGE_CSS = "body{margin:1.5em auto;max-width:60em}@media print{body{margin:0;max-width:none}}"


def _table(head: list[str], rows: list[list[Any]], num: tuple[int, ...] = ()) -> str:
    """A table; the columns ``num`` are numbers (right-aligned, tabular figures)."""
    e = html.escape

    def cls(i: int) -> str:
        return " class='num'" if i in num else ""

    out = ["<table><tr>" + "".join(f"<th{cls(i)}>{e(h)}</th>" for i, h in enumerate(head)) + "</tr>"]
    for r in rows:
        out.append(
            "<tr>"
            + "".join(
                f"<td{cls(i)} data-label='{e(head[i])}'>{e('' if c is None else str(c))}</td>"
                for i, c in enumerate(r)
            )
            + "</tr>"
        )
    return "".join(out) + "</table>"


def summary_fragment(sel: Selection) -> str:
    """The summary's content as one ``<article class="auth-summary">`` element: the one
    renderer of the summary, used by :func:`summary_html` (``uasnav select --summary``) and by
    the web application's results page, whose print view is this element."""
    d = summary_dict(sel)
    e = html.escape
    op, cat, sora, chosen = d["operation"], d["category"], d["sora"], d["chosen"]
    parts = [
        "<article class='auth-summary' id='auth-summary' aria-labelledby='auth-summary-h'>",
        f"<h2 id='auth-summary-h'>Authorisation summary — {e(d['mission']['name'])}</h2>",
        "<p class='muted'>Produced by uasnav select; a decision aid, not an authorisation.</p>",
    ]
    auth = d["authorisation"]
    parts.append(
        f"<p class='verdict {'ok' if auth['authorisable'] else 'warn'}' role='status'>"
        f"Verdict: {e(auth['verdict'])}</p>"
    )
    if auth["requirements"]:
        parts.append(
            "<h3>What the operation requires</h3><ul>"
            + "".join(f"<li>{e(n)}</li>" for n in auth["requirements"])
            + "</ul>"
        )
    parts.append("<h3>Operation and category</h3>")
    if op:
        parts.append(
            f"<p><b>{e(op['visibility'])}</b>, {metres(op['max_distance_m'])} from the pilot, "
            f"{metres(op['height_m'])} AGL, {e(op['environment'])} ({e(op['population'])}), "
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
        parts.append(f"<h3>SORA {e(sora['edition'])}</h3>")
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
                num=(0, 1),
            )
        )
        parts.append("<p class='muted'>" + e("; ".join(sora["steps"])) + "</p>")
        required = [o for o in sora["osos"] if o["robustness"] != "optional"]
        if required:
            parts.append(
                "<p class='muted'>OSOs and their robustness (optional ones left out):</p><ul class='osos'>"
                + "".join(
                    f"<li title='{e(o.get('title', ''))}'>{e(o['id'])} <b>{e(o['robustness'])}</b></li>"
                    for o in required
                )
                + "</ul>"
            )
    if d["scenarios"]:
        parts.append("<h3>Standard scenarios, PDRAs, waivers</h3>")
        parts.append(
            _table(
                ["", "applies / needed", "conditions", "source"],
                [
                    [s["id"], "yes" if s["applies"] else "no", "; ".join(s["reasons"]), s["source"]]
                    for s in d["scenarios"]
                ],
            )
        )
    parts.append("<h3>Geographical zones</h3>")
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
    parts.append("<h3>Equipment</h3>")
    on = {x["id"]: x["state"] for x in d["equipment"]["on_chosen_uas"]}
    parts.append(
        _table(
            ["necessary item", "on the chosen UAS", "why necessary"],
            [[x["name"], on.get(x["id"], "-"), x["reason"]] for x in d["equipment"]["necessary"]],
        )
    )
    parts.append("<p class='muted'>Optional: " + e(", ".join(d["equipment"]["optional"])) + "</p>")
    parts.append("<section class='chosen'><h3>Chosen configuration</h3>")
    if chosen:
        parts.append(
            _table(
                ["UAS", "camera", "score (eq. 61, lower better)", "mass (g)", "cost (USD)", "SAIL"],
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
                num=(2, 3, 4),
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
    parts.append("</section>")
    if d["notes"]:
        parts.append("<h3>Notes</h3><ul>" + "".join(f"<li>{e(n)}</li>" for n in d["notes"]) + "</ul>")
    parts.append("</article>")
    return "\n".join(parts)


def _ground_rows(g: dict[str, Any] | None) -> list[list[str]]:
    """The take-off ground's elevation, its datum and source, and the geoid height that turns
    it into the intents' WGS-84 altitudes."""
    if not g:
        return []
    src = f"{g['source']}" + (" — check before filing" if g.get("assumed") else "")
    return [
        ["Ground at take-off", f"{g['elevation_m']:.1f} m {g['datum']} ({src})"],
        [
            "Geoid height (intents are WGS-84)",
            f"{g['geoid_height_m']:.2f} m, {g['geoid']}: ground {g['ellipsoidal_height_m']:.1f} m "
            "above the ellipsoid",
        ],
        *(
            [
                [
                    "Ground heights over the area",
                    f"span {g['spread_m']:.1f} m (heights above the take-off point)",
                ]
            ]
            if "spread_m" in g
            else []
        ),
    ]


def plan_fragment(result: dict[str, Any]) -> str:
    """The survey part of a ``uasnav plan`` result (``result.json``) as one
    ``<section class="auth-plan">``: the survey, each flight with its predicted time and
    bounds, the zones' window and the strategic conflicts."""
    e = html.escape
    s = result.get("survey")
    if not s:
        return ""
    parts = ["<section class='auth-plan'><h3>Survey</h3>"]
    parts.append(
        _table(
            ["Quantity", "Value"],
            [
                ["Height", f"{s['altitude_m']:.1f} m {s['altitude_datum']}"],
                ["Why this height", s["height_reason"]],
                *_ground_rows(result.get("ground")),
                ["Ground resolution", f"{s['gsd_m'] * 100:.2f} cm/px"],
                ["Overlap front / side", f"{s['overlap']['front']:.0%} / {s['overlap']['side']:.0%}"],
                [
                    "Line spacing / trigger distance",
                    f"{s['line_spacing_m']:.1f} m / {s['trigger_distance_m']:.1f} m",
                ],
                ["Speed", f"{s['speed_ms']:.1f} m/s ({s['speed_reason']})"],
                ["Lines / photos / flights", f"{s['lines']} / {s['photos']} / {s['flights']}"],
                ["Photographed length", f"{s['length_m']:.0f} m"],
            ],
        )
    )
    rows = [
        [
            f["name"],
            f["start"],
            f"{f['eta_s']:.0f}",
            f"{f['eta_bounds_s'][0]:.0f}–{f['eta_bounds_s'][1]:.0f}",
            f["photos"],
            f["volumes"],
        ]
        for f in result.get("flights", [])
    ]
    parts.append("<h3>Flights</h3>")
    parts.append(
        _table(["Flight", "Take-off", "Time s", "Bounds s", "Photos", "Volumes"], rows, (2, 3, 4, 5))
    )
    conflicts = result.get("conflicts") or []
    parts.append("<h3>Strategic deconfliction</h3>")
    if conflicts:
        parts.append(
            _table(
                ["Flight", "Intent", "Overlap", "Resolution"],
                [
                    [c["flight"], c["intent"], f"{c['overlap_start']} – {c['overlap_end']}", c["resolution"]]
                    for c in conflicts
                ],
            )
        )
    else:
        parts.append("<p>No conflict with the intents given.</p>")
    if s.get("assumptions"):
        parts.append(
            "<h3>Assumptions</h3><ul>" + "".join(f"<li>{e(a)}</li>" for a in s["assumptions"]) + "</ul>"
        )
    parts.append("</section>")
    return "\n".join(parts)


def summary_html(sel: Selection, plan: dict[str, Any] | None = None) -> str:
    """The summary as one self-contained HTML page: :func:`summary_fragment` with its
    stylesheet (print included) inline; with ``plan`` (a ``uasnav plan`` result) its survey,
    flights and conflicts (:func:`plan_fragment`) follow."""
    title = html.escape(f"Authorisation summary — {sel.mission_name}")
    return (
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
        f"<title>{title}</title><style>{SUMMARY_CSS}{_PAGE_CSS}</style></head><body>\n"
        + summary_fragment(sel)
        + (plan_fragment(plan) if plan else "")
        + "\n</body></html>"
    )


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
