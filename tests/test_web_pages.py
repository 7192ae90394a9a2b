"""The selection and trajectory pages through the framework's test client: the short form,
required fields and oversize uploads answered beside the field, the offline area map, help in
the operator's words, and the routers the application is built from."""

from __future__ import annotations

import json
import re
import warnings
from pathlib import Path

import pytest

from uasnav.web import create_app, forms
from uasnav.web.context import MAX_BODY_BYTES

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from fastapi.testclient import TestClient

BASE = "http://127.0.0.1:8000"
#: A 70 × 55 m field (lon, lat) beside Geneva.
RING = [[6.1680, 46.2160], [6.1689, 46.2160], [6.1689, 46.2165], [6.1680, 46.2165], [6.1680, 46.2160]]
AREA = json.dumps({"type": "Polygon", "coordinates": [RING]}).encode()


@pytest.fixture(scope="module")
def client():  # type: ignore[no-untyped-def]
    return TestClient(create_app(), base_url=BASE, raise_server_exceptions=False)


def field_value(html: str, name: str) -> str:
    m = re.search(rf'id="f-{name}" name="{name}"[^>]*value="([^"]*)"', html, re.S)
    assert m, name
    return m.group(1)


def test_short_form_then_advanced(client) -> None:
    html = client.get("/").text
    core_part, _, advanced = html.partition('<details class="advanced"')
    for name in forms.CORE_FIELDS:
        assert f'id="f-{name}"' in core_part, name
    assert advanced and 'id="f-top"' in advanced and 'id="f-top"' not in core_part
    # the run button comes before any advanced field is open: nothing but the core to Tab past
    n_core = len(re.findall(r'<(?:input|select)(?![^>]*type="hidden")', core_part))
    assert n_core <= 12
    assert 'class="actions sticky"' in html


def test_help_is_in_the_operators_words(client) -> None:
    html = client.get("/").text
    helps = re.findall(r'<small class="help"[^>]*>(.*?)</small>', html, re.S)
    assert len(helps) == len(forms.form_fields({})) or len(helps) > 20
    for h in helps:
        assert not re.search(r"--[a-z]", h), h  # no command-line option names
        assert "http(s) URL" not in h and "path or" not in h, h


def test_api_help_is_in_the_operators_words(client) -> None:
    """``/api/options`` and the OpenAPI description give the form's help, not the CLI's."""
    options = client.get("/api/options").json()
    schema = client.get("/openapi.json").json()["paths"]["/api/select"]["post"]["requestBody"]
    props = schema["content"]["application/json"]["schema"]["properties"]
    assert {o["name"] for o in options} == set(props) == forms.field_names()
    for o in options:
        for text in (o["help"], props[o["name"]]["description"]):
            assert not re.search(r"--[a-z]", text), (o["name"], text)
            assert "http(s) URL" not in text and "path or" not in text, (o["name"], text)
            assert "Table 2" not in text and "eq. " not in text, (o["name"], text)  # no thesis references
    assert {o["name"]: o["help"] for o in options}["camera_height"] == forms.OPERATOR_HELP["camera_height"]


def test_summary_from_column_names_fields_and_the_area(client) -> None:
    """The authorisation summary's "from" column in the form's words; a pilot distance measured
    on the uploaded area says so (it was not typed)."""
    r = client.post("/select", data={"range": "", "altitude": "50"}, files={"area": ("field.geojson", AREA)})
    assert r.status_code == 200
    froms = from_column(r.text)
    assert froms["visibility"].startswith("the area&#x27;s farthest point from the pilot position = ")
    assert all(not re.search(r"--[a-z]", src) for src in froms.values()), froms
    assert froms["height"] == "“Altitude” = 50 m"
    typed = client.post(
        "/select",
        data={"range": "", "altitude": "50", "max_distance": "300"},
        files={"area": ("f.geojson", AREA)},
    )
    assert from_column(typed.text)["visibility"].startswith("“Max pilot distance” = 300 m")


def from_column(html: str) -> dict[str, str]:
    """The authorisation summary's derivation table: fact → its "from" cell."""
    cells = r"<td data-label='{}'>([^<]*)</td>"
    rows = re.findall(cells.format("fact") + cells.format("value") + cells.format("from"), html)
    assert rows
    return {name: src for name, _, src in rows}


def marker_latlon(html: str, which: str) -> tuple[float, float]:
    """A map point's position from the drawing and the georeference on the svg."""
    svg = re.search(r"<svg class=\"map\"[^>]*>", html).group(0)
    lat0, lon0 = map(float, re.search(r'data-origin="([^"]+)"', svg).group(1).split(","))
    m_lat, m_lon = map(float, re.search(r'data-m-per-deg="([^"]+)"', svg).group(1).split(","))
    ox, oy, k, x0, y1 = map(float, re.search(r'data-view="([^"]+)"', svg).group(1).split(","))
    dot = re.search(rf'<g class="pt {which}"><circle cx="([\d.]+)" cy="([\d.]+)"', html)
    cx, cy = map(float, dot.groups())
    east, north = x0 + (cx - ox) / k, y1 - (cy - oy) / k
    return lat0 + north / m_lat, lon0 + east / m_lon


def test_kept_area_reruns_with_the_points_placed(client) -> None:
    """The page keeps the uploaded area for the next run (a file field cannot be re-filled), so a
    take-off and pilot point placed on the map (or typed) plan from the same area; the map's
    georeference puts them where they are."""
    first = client.post(
        "/select", data={"range": "", "altitude": "50"}, files={"area": ("field.geojson", AREA)}
    )
    assert first.status_code == 200 and "Using <b>field.geojson</b> from the last run" in first.text
    # an emptied field stays empty for the next run (not re-filled with its default)
    assert field_value(first.text, "range") == "" and field_value(first.text, "altitude") == "50"
    assert field_value(client.get("/").text, "range") == "1500"
    kept = re.search(r'name="kept-data.area" value="([^"]*)"', first.text).group(1)
    again = client.post(
        "/select",
        data={
            "range": "",
            "altitude": "50",
            "kept-name.area": "field.geojson",
            "kept-data.area": kept,
            "takeoff": "46.2161,6.1681",
            "pilot": "46.21655,6.16895",
        },
    )
    assert again.status_code == 200 and 'id="plan"' in again.text
    for which, (lat, lon) in (("takeoff", (46.2161, 6.1681)), ("pilot", (46.21655, 6.16895))):
        got = marker_latlon(again.text, which)
        # within 0.3 m: the drawing's coordinates are written to 0.1 unit (~0.02 m here)
        assert abs(got[0] - lat) * 111e3 < 0.3 and abs(got[1] - lon) * 77e3 < 0.3, (which, got)
    bad = client.post("/select", data={"range": "", "altitude": "50", "kept-data.area": "@@@"})
    assert bad.status_code == 422
    assert "kept file is damaged" in re.search(r'id="e-area"[^>]*>([^<]*)<', bad.text).group(1)


def test_empty_required_field_is_answered_beside_it(client) -> None:
    r = client.post("/select", data={"range": "", "resolution": "0.02", "wind": "7"})
    assert r.status_code == 422
    assert 'id="e-range" role="alert">range: enter the range (m), or upload an area</span>' in r.text
    # the form keeps what was typed
    assert field_value(r.text, "resolution") == "0.02" and field_value(r.text, "wind") == "7"
    assert 'id="results"' not in r.text
    # with an area uploaded, no range is needed: distances come from the area
    r = client.post("/select", data={"range": ""}, files={"area": ("field.geojson", AREA)})
    assert r.status_code == 200, re.findall(r'class="msg"[^>]*>([^<]+)<', r.text)


def test_oversize_upload_is_answered_on_the_page(client) -> None:
    big = b" " * (MAX_BODY_BYTES + 1)
    r = client.post("/select", files={"area": ("big.geojson", big)}, data={"range": "800"})
    assert r.status_code == 413 and r.headers["content-type"].startswith("text/html")
    assert re.search(r'id="e-area" role="alert">area: the files sent together are over 16 MB', r.text)
    assert '<form method="post" action="/select#results"' in r.text
    r = client.post("/trajectory", files={"plan": ("big.plan", big)})
    assert r.status_code == 413 and 'id="te-plan" role="alert">plan: the files sent together' in r.text
    # the API keeps its JSON answer
    r = client.post("/api/trajectory/predict", files={"plan": ("big.plan", big)})
    assert r.status_code == 413 and r.json()["field"] == "body"
    # a file under the body limit but over the per-file limit: beside the field, form kept
    r = client.post(
        "/select",
        files={"area": ("a.geojson", b" " * (forms.MAX_OPTION_FILE_BYTES + 1))},
        data={"range": "800", "wind": "6"},
    )
    assert r.status_code == 422 and 'id="e-area" role="alert">area: file over' in r.text
    assert field_value(r.text, "range") == "800" and field_value(r.text, "wind") == "6"


def test_area_upload_draws_the_offline_map(client, shared_data: Path) -> None:
    doc = json.loads((shared_data / "utm" / "interuss_ed269_geozone_sample.json").read_text())
    doc["UASZoneList"][0].update(restriction="REQ_AUTHORISATION")
    r = client.post(
        "/select",
        data={"range": "800"},
        files={"area": ("field.geojson", AREA), "zones": ("zones.json", json.dumps(doc).encode())},
    )
    assert r.status_code == 200
    svg = re.search(r'<svg class="map".*?</svg>', r.text, re.S)
    assert svg, "no map"
    s = svg.group(0)
    assert 'class="area"' in s and 'class="pt takeoff"' in s and 'class="north"' in s
    assert re.search(r'<g class="scale">.*?<text[^>]*>\d+(\.\d+)? k?m</text>', s, re.S)
    assert 'class="zone z-auth"' in s  # the zone the field is in, coloured by its restriction
    # nothing in the map is fetched: no URL but the SVG namespace
    assert re.findall(r"https?://[^\"' ]+", s) == ["http://www.w3.org/2000/svg"]
    # the area's polygon is drawn with north up: its northern edge above its southern edge
    d = re.search(r'class="area" d="M([^"]+)"', s).group(1)
    ys = [float(p.split(",")[1]) for p in re.findall(r"[\d.]+,[\d.]+", d)]
    assert max(ys) - min(ys) > 10


def test_every_router_answers(client) -> None:
    """Each page and the API is served by its router at its URL."""
    for url in ("/", "/trajectory", "/db/uas", "/api", "/api/options", "/api/db/cameras", "/summary.css"):
        assert client.get(url).status_code == 200, url
    assert client.get("/db", follow_redirects=False).status_code == 303
    spec = client.get("/openapi.json").json()["paths"]
    assert set(spec) == {"/api/select", "/api/options", "/api/db/{name}", "/api/trajectory/predict"}


def test_area_upload_runs_the_plan(client) -> None:
    """With an area, the page shows the survey plan ``uasnav.plan`` makes for the same values,
    draws its lines on the map and offers every file the plan writes."""
    import base64

    import uasnav
    from uasnav.mission.request import Upload

    r = client.post(
        "/select", data={"range": "", "overlap": "70,60"}, files={"area": ("field.geojson", AREA)}
    )
    assert r.status_code == 200
    links = dict(
        re.findall(
            r'<a class="button" href="data:[^;]+;charset=utf-8;base64,([^"]+)" download="([^"]+)"', r.text
        )
    )
    got = {name: base64.b64decode(b64) for b64, name in links.items()}
    want = uasnav.plan(area=Upload("field.geojson", AREA), overlap="70,60")
    assert set(want.files) <= set(got)
    assert {"flight-01.plan", "flight-01.waypoints", "flight-01.intent.json", "result.json"} <= set(got)
    page_result = json.loads(got["result.json"])
    assert page_result["survey"] == json.loads(json.dumps(want.result["survey"]))
    assert page_result["configuration"] == want.result["configuration"]
    n_lines = want.result["survey"]["lines"]
    assert r.text.count('<polyline class="survey"') == n_lines
    assert f'<b class="n">{want.result["survey"]["photos"]}</b> photos' in r.text


def test_answers_name_fields_not_command_line_options(client) -> None:
    r = client.post("/select", data={"range": "", "altitude": "50"}, files={"area": ("field.geojson", AREA)})
    assert r.status_code == 200 and 'id="plan"' in r.text
    plan = re.search(r'<section class="plan".*?</section>', r.text, re.S).group(0)
    plan = re.sub(r'href="data:[^"]*"', "", plan)
    notes = " ".join(re.findall(r'<p class="note">(.*?)</p>', r.text, re.S))
    assert "“Altitude”" in plan and not re.search(r"--[a-z]", plan + notes)


def _pilot_distances(text: str) -> list[str]:
    """Every "<n> m from the pilot" of a text, and the derivation's "… = <n> m" distances."""
    return re.findall(r"(\d[\d.,]*) m from the pilot", text) + re.findall(
        r"pilot position = (\d[\d.,]*) m", text
    )


def test_pilot_distance_reads_in_whole_metres_on_the_page_and_its_print_view(client) -> None:
    """The page, its print view (the summary download) and the summary JSON round the pilot
    distance measured on the area the same way (whole metres), the JSON keeps its precision."""
    import base64

    r = client.post("/select", data={"range": "", "altitude": "50"}, files={"area": ("field.geojson", AREA)})
    assert r.status_code == 200
    links = re.findall(r'href="data:[^;]+;charset=utf-8;base64,([^"]+)"\s+download="([^"]+)"', r.text)
    views = {name: base64.b64decode(b).decode() for b, name in links}
    page = r.text
    shown = _pilot_distances(page) + _pilot_distances(views["authorisation-summary.html"])
    shown += _pilot_distances(views["authorisation-summary.json"])
    assert len(shown) >= 4, shown
    exact = json.loads(views["selection.json"])["operation"]["max_distance_m"]
    assert exact != round(exact)  # the case shows the rounding
    assert set(shown) == {f"{exact:.0f}"}, shown
    assert f"{exact:.4g}" not in page.replace(f"{exact:.0f} m", "")


def test_unreachable_resolution_is_said_in_the_forms_words(client) -> None:
    """A resolution no camera reaches: the page names the field and the value as typed, in its
    unit, and where the finest camera falls short (no option names, no height never asked)."""
    r = client.post("/select", data={"resolution": "0.0005", "altitude": "50"})
    assert r.status_code == 200
    box = re.search(r'<div class="verdict-box" role="alert" id="not-authorisable">(.*?)</div>', r.text, re.S)
    assert box, r.text[:2000]
    text = box.group(1)
    assert "“Resolution” 0.0005 m/px (0.5 mm per pixel) asked" in text, text
    assert "at 50 m, the planned height (“Altitude”)" in text, text
    assert not re.search(r"--[a-z]", text), text
