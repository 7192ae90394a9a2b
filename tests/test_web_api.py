"""The web application's API and pages through the framework's test client: status
codes, JSON bodies, validation errors naming the field, hostile uploads, Host/Origin guards,
generic 500s. The same application runs under ``uasnav serve`` (tests/test_web_serve.py,
tests/test_web_browser.py)."""

from __future__ import annotations

import csv
import html
import io
import json
import logging
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from markupsafe import escape as jinja_escape

from uasnav.cli import main
from uasnav.cli.select import command as select_command
from uasnav.io.plans import read_plan, write_plan
from uasnav.mission.request import SELECT_OPTIONS
from uasnav.trajectory.features import wind_vector
from uasnav.trajectory.simulator import phantom4_plans
from uasnav.web import create_app, forms
from uasnav.web.default_model import default_model

with warnings.catch_warnings():
    warnings.simplefilter("ignore")  # starlette's notice about httpx vs httpx2
    from fastapi.testclient import TestClient

BASE = "http://127.0.0.1:8000"
#: The thesis' precision-agriculture case (Table 22/23, §5.2.3.6) as the form/API takes it.
THESIS = {
    "mission": "precision-agriculture",
    "range": 1500,
    "resolution": 0.05,
    "image_size": "70x70",
    "altitude": 50,
    "imagery": "multispectral",
    "wind": 5,
    "order_by": "cost",
}


@pytest.fixture(scope="module")
def app():  # type: ignore[no-untyped-def]
    return create_app()


@pytest.fixture(scope="module")
def client(app):  # type: ignore[no-untyped-def]
    return TestClient(app, base_url=BASE, raise_server_exceptions=False)


def cli_json(values: dict) -> dict:
    """``uasnav select --json`` with ``values`` spelled as options (a true flag bare)."""
    argv = ["select", "--json"]
    for k, v in values.items():
        flag = "--" + k.replace("_", "-")
        argv += [flag] if v is True else [] if v is False else [flag, str(v)]
    r = CliRunner().invoke(main, argv)
    assert r.exit_code == 0, r.output
    return json.loads(r.output)


# -- the contract of POST /api/select -----------------------------------------------------------


@pytest.mark.parametrize(
    "values",
    [
        THESIS,
        {},
        {**THESIS, "order_by": "weight", "top": 3, "rain": True},
        {"range": 300, "jurisdiction": "faa"},
    ],
)
def test_api_select_is_what_the_cli_prints(client, values) -> None:
    r = client.post("/api/select", json=values)
    assert r.status_code == 200, r.text
    assert r.json() == cli_json(values)


def test_form_fields_are_the_cli_options() -> None:
    """The form (and the API) take exactly the CLI's options, less the server-side sources."""
    cli = {p.name for p in select_command.params} - {"as_json"}
    sources = {o.name for o in SELECT_OPTIONS if not forms.is_field(o)}
    assert sources >= {"db", "regulations", "matrices"}
    assert forms.field_names() == cli - sources
    fields = {f.name for f in forms.form_fields({})}
    assert fields == cli - sources


def test_form_renders_every_field(client) -> None:
    html = client.get("/").text
    for name in forms.field_names():
        assert f'data-field="{name}"' in html, name
    for o in SELECT_OPTIONS:
        if o.unit and forms.is_field(o) and forms.widget(o) not in ("pairs", "checkbox"):
            assert re.search(rf'for="f-{o.name}">[^<]*<span class="unit">\({re.escape(o.unit)}\)', html), (
                o.name
            )
    assert 'name="db"' not in html and 'name="matrices"' not in html


@pytest.mark.parametrize(
    ("body", "field"),
    [
        ({"range": -1}, "range"),
        ({"range": "nan"}, "range"),
        ({"wind": "fast"}, "wind"),
        ({"image_size": "0x70"}, "image_size"),
        ({"weights": {"range": -1}}, "weights"),
        ({"targets": "cost=5:5"}, "targets"),
        ({"top": 0}, "top"),
        ({"order_by": "speed"}, "order_by"),
        ({"mission": "moon-landing"}, "mission"),
        ({"jurisdiction": "mars", "category": "open"}, "jurisdiction"),
        ({"colour": "red"}, "colour"),
        ({"db": "/etc/passwd"}, "db"),
        ({"regulations": "http://example.com/regs.xml"}, "regulations"),
    ],
)
def test_api_select_refusals_name_the_field(client, body, field) -> None:
    r = client.post("/api/select", json=body)
    assert r.status_code == 422, r.text
    assert r.json()["field"] == field
    assert field in r.json()["error"]


def test_api_select_hostile_bodies(client) -> None:
    def post(content: bytes, ctype: str = "application/json"):  # type: ignore[no-untyped-def]
        return client.post("/api/select", content=content, headers={"content-type": ctype})

    assert post(b'{"range": 300}', "text/plain").status_code == 415
    assert post(b"range=300", "application/x-www-form-urlencoded").json()["field"] == "content-type"
    r = post(b'{"range": ')
    assert r.status_code == 400 and r.json()["field"] == "body"
    assert post(b"[1, 2]").status_code == 422
    assert post(b"\xff\xfe").status_code == 400
    assert post(b"[" * 100_000 + b"]" * 100_000).status_code in (400, 413)
    assert post(b'{"range": NaN}').json()["field"] == "range"
    assert post(b'{"a": "' + b"x" * (300 * 1024) + b'"}').status_code == 413
    big = client.post(
        "/api/select", content=b"x" * (17 * 2**20), headers={"content-type": "application/json"}
    )
    assert big.status_code == 413


# -- guards ----------------------------------------------------------------------------------------


def test_foreign_host_is_refused(client) -> None:
    """DNS rebinding: a name resolving to 127.0.0.1 still says its own Host."""
    r = client.get("/", headers={"host": "evil.example:8000"})
    assert r.status_code == 400 and r.json()["field"] == "host"
    assert client.get("/", headers={"host": "localhost:8000"}).status_code == 200
    assert client.get("/", headers={"host": "[::1]:8000"}).status_code == 200


def test_cross_site_posts_are_refused(client) -> None:
    r = client.post("/api/select", json={}, headers={"origin": "http://evil.example"})
    assert r.status_code == 403 and r.json()["field"] == "origin"
    assert client.post("/select", data={}, headers={"origin": "null"}).status_code == 403
    r = client.post("/select", data={}, headers={"sec-fetch-site": "cross-site"})
    assert r.status_code == 403
    assert client.post("/api/select", json={}, headers={"origin": BASE}).status_code == 200
    # a page (GET) may be opened from anywhere
    assert client.get("/", headers={"origin": "http://evil.example"}).status_code == 200


def test_security_headers_and_no_cdn(client) -> None:
    r = client.get("/")
    assert "default-src 'self'" in r.headers["content-security-policy"]
    assert r.headers["x-content-type-options"] == "nosniff"
    assert client.get("/docs").status_code == 404 and client.get("/redoc").status_code == 404
    spec = client.get("/openapi.json").json()
    assert {"/api/select", "/api/trajectory/predict", "/api/db/{name}"} <= set(spec["paths"])
    props = spec["paths"]["/api/select"]["post"]["requestBody"]["content"]["application/json"]["schema"]
    assert set(props["properties"]) == forms.field_names()
    for page in ["/", "/trajectory", "/db/uas", "/api"]:
        html = client.get(page).text
        # every src/href is the app's own (a path) or a data: download
        for url in re.findall(r'(?:src|href)="([^"]*)"', html):
            assert url.startswith(("/", "#", "data:")), (page, url)


def test_unexpected_error_is_a_generic_500(client, app, monkeypatch, caplog) -> None:
    import uasnav.web.app as web_app

    def boom(*a, **k):  # type: ignore[no-untyped-def]
        raise RuntimeError("secret detail /etc/shadow")

    monkeypatch.setattr(web_app, "run_select", boom)
    with caplog.at_level(logging.ERROR, logger="uasnav.web"):
        r = client.post("/api/select", json={})
        page = client.post("/select", data={"range": "300"})
    assert r.status_code == 500 and r.json() == {"error": web_app.GENERIC_500, "field": None}
    assert page.status_code == 500 and "secret" not in page.text and "Traceback" not in page.text
    assert "secret detail" in caplog.text  # the details are in the server log


# -- pages without JavaScript ------------------------------------------------------------------------


def test_form_post_shows_results_matching_the_api(client) -> None:
    form = {k: str(v) for k, v in THESIS.items()}
    r = client.post("/select", data=form)
    assert r.status_code == 200
    api = client.post("/api/select", json=THESIS).json()
    rows = re.findall(r"<tr>\s*<td class=\"num\">(\d+)</td><td>([^<]+)</td><td>([^<]+)</td>", r.text)
    assert [(u, c) for _, u, c in rows] == [(x["uas"], x["camera"]) for x in api["ranking"]]
    for name in api["feasible_uas"] + api["feasible_cameras"]:
        assert f"<li>{name}</li>" in r.text
    for e in api["equipment"]:
        assert e["name"] in r.text


def test_bad_values_are_shown_beside_their_fields(client) -> None:
    r = client.post("/select", data={"range": "-5", "wind": "fast", "weights.cost": "-1", "altitude": "50"})
    assert r.status_code == 422
    for field in ("range", "wind", "weights"):
        m = re.search(
            rf'data-field="{field}".*?<span class="msg" id="e-{field}" role="alert">([^<]*)<', r.text, re.S
        )
        assert m and m.group(1).startswith(field + ":"), field
    assert 'id="e-altitude" role="alert"></span>' in r.text
    assert 'value="-5"' in r.text  # what the operator typed is kept
    assert 'id="results"' not in r.text


def test_checkbox_and_pairs_fields(client) -> None:
    form = {"rain": ["false", "true"], "weights.range": "2", "weights.cost": "1", "top": "4"}
    r = client.post("/select", data=form)
    assert r.status_code == 200
    api = client.post("/api/select", json={"rain": True, "weights": "range=2,cost=1", "top": 4}).json()
    assert api["requirements"]["rain"] is True and len(api["ranking"]) <= 4
    for x in api["ranking"]:
        assert f"<b>{x['score']:,.3f}</b>" in r.text


def test_exports(client) -> None:
    q = "range=1500&order_by=cost&image_size=70x70"
    j = client.get(f"/select/export.json?{q}")
    assert j.status_code == 200 and "attachment" in j.headers["content-disposition"]
    assert j.json() == client.post("/api/select", json={"range": 1500, "order_by": "cost"}).json()
    c = client.get(f"/select/export.csv?{q}")
    rows = list(csv.DictReader(io.StringIO(c.text)))
    assert [r["uas"] for r in rows] == [x["uas"] for x in j.json()["ranking"]]
    assert float(rows[0]["score"]) == pytest.approx(j.json()["ranking"][0]["score"])
    rej = list(csv.DictReader(io.StringIO(client.get(f"/select/export.csv?{q}&table=rejections").text)))
    assert len(rej) == len(j.json()["rejections"])
    for got, x in zip(rej, j.json()["rejections"], strict=True):
        if x["limit"] is None or x["value"] is None:
            assert got["margin"] == ""  # no finite limit (e.g. airspeed below the wind): no margin
        else:
            assert float(got["margin"]) == pytest.approx(abs(x["value"] - x["limit"]))
    assert client.get(f"/select/export.csv?{q}&range=-1").json()["field"] == "range"
    assert client.get("/select/export.xml").status_code == 404


def test_database_tables(client, app) -> None:
    from uasnav.mission import load_database

    db = load_database()
    r = client.get("/api/db/uas").json()
    assert len(r["rows"]) == len(db.uas) and "source" in r["columns"]
    assert all(row["source"] for row in r["rows"])
    cams = client.get("/api/db/cameras?sort=cost_usd").json()["rows"]
    costs = [x["cost_usd"] for x in cams if x["cost_usd"] is not None]
    assert costs == sorted(costs) and len(cams) == len(db.cameras)
    dji = client.get("/api/db/uas?q=dji").json()["rows"]
    assert dji and all("dji" in json.dumps(x).lower() for x in dji) and len(dji) < len(db.uas)
    page = client.get("/db/uas?q=dji&sort=cost_usd&desc=true").text
    assert page.count("<tr>") == len(dji) + 1
    assert client.get("/api/db/passwords").status_code == 404
    for t in ("regulations", "missions", "equipment"):
        assert client.get(f"/api/db/{t}").json()["rows"], t
        assert client.get(f"/db/{t}").status_code == 200


# -- trajectory -------------------------------------------------------------------------------------


def _plan_csv(tmp_path: Path, name: str = "plan.csv") -> Path:
    """Trajectory A of the simulated experiment, as lat/lon near Zurich."""
    import pymap3d

    ne = phantom4_plans()["A"]
    lat, lon, _ = pymap3d.ned2geodetic(ne[:, 0], ne[:, 1], 0.0, 47.3977, 8.5456, 50.0)
    p = tmp_path / name
    p.write_text("lat,lon,alt\n" + "".join(f"{a:.9f},{b:.9f},50\n" for a, b in zip(lat, lon, strict=True)))
    return p


def test_predict_api_matches_the_predictor(client, tmp_path) -> None:
    p = _plan_csv(tmp_path)
    form = {"wind_speed": "2.78", "wind_from": "22.5", "speed": "3.33"}
    r = client.post("/api/trajectory/predict", files={"plan": ("a.csv", p.read_bytes())}, data=form)
    assert r.status_code == 200, r.text
    out = r.json()
    route = read_plan(p)
    from uasnav.io.plans import plan_route

    ne, _ = plan_route(route)
    ref = default_model().predict(ne, wind_vector(2.78, 22.5), 3.33)
    assert out["eta_s"] == pytest.approx(ref.eta_s)
    assert out["waypoint_times_s"] == pytest.approx(list(ref.waypoint_times_s))
    assert out["waypoint_times_s"][-1] == pytest.approx(out["eta_s"])
    assert out["low_confidence_elements"] == [i for i, f in enumerate(ref.flags) if f]
    # the same plan as a QGroundControl .plan gives the same times
    qgc = tmp_path / "a.plan"
    write_plan(route, qgc)
    r2 = client.post("/api/trajectory/predict", files={"plan": ("a.plan", qgc.read_bytes())}, data=form)
    assert r2.json()["waypoint_times_s"] == pytest.approx(out["waypoint_times_s"], abs=1e-6)
    gj = client.post(
        "/api/trajectory/predict",
        files={"plan": ("a.csv", p.read_bytes())},
        data={**form, "format": "geojson"},
    ).json()
    assert gj["type"] == "FeatureCollection"
    assert [f["properties"]["time_s"] for f in gj["features"][:-1]] == pytest.approx(out["waypoint_times_s"])
    first = gj["features"][0]["geometry"]["coordinates"]
    assert first == pytest.approx([8.5456, 47.3977], abs=1e-7)
    c = client.post(
        "/api/trajectory/predict", files={"plan": ("a.csv", p.read_bytes())}, data={**form, "format": "csv"}
    )
    rows = list(csv.DictReader(io.StringIO(c.text)))
    assert [float(x["time_s"]) for x in rows] == pytest.approx(out["waypoint_times_s"], abs=1e-3)


def cli_mission(plan: Path, *options: str) -> dict:
    """``uasnav trajectory mission PLAN --json`` (the figure the page must give)."""
    r = CliRunner().invoke(main, ["trajectory", "mission", str(plan), *options, "--json"])
    assert r.exit_code == 0, r.output
    return json.loads(r.output)


def page_eta(text: str, ident: str = "eta") -> float:
    m = re.search(rf'id="{ident}" data-eta="([^"]+)"', text)
    assert m, text[-3000:]
    return float(m.group(1))


@pytest.mark.parametrize(
    ("name", "autopilot"),
    [
        ("ardupilot_autotest_dalby_obc2016.waypoints", ""),  # the real QuadPlane plan
        ("mavsdk_qgroundcontrol_sample.plan", ""),  # a QGroundControl multirotor plan
        ("mavsdk_qgroundcontrol_sample.plan", "px4-mc"),  # the stack chosen on the form
    ],
)
def test_mission_file_gets_the_cli_mission_time(client, shared_data, name, autopilot) -> None:
    """An autopilot mission file on the page and the API gives exactly the figure of
    ``uasnav trajectory mission`` (same model, same autopilot default), not the element
    model at a guessed speed; the element model is shown beside it."""
    plan = shared_data / "missions" / name
    ref = cli_mission(plan, *(["--autopilot", autopilot] if autopilot else []))
    form = {"autopilot": autopilot} if autopilot else {}
    page = client.post("/trajectory", files={"plan": (name, plan.read_bytes())}, data=form)
    assert page.status_code == 200, page.text[-2000:]
    assert page_eta(page.text) == ref["eta_s"]
    assert page_eta(page.text, "qgc-eta") == ref["qgc_estimate_s"]
    element_eta = page_eta(page.text, "element-eta")
    assert element_eta != ref["eta_s"]  # shown apart, not in place of the autopilot's
    assert 'id="mission-items"' in page.text and page.text.count("data-arrive=") == len(ref["items"])
    chosen = "autopilot chosen" if autopilot else "autopilot from the plan"
    assert chosen in page.text and forms_label(ref["autopilot"]) in page.text
    api = client.post("/api/trajectory/predict", files={"plan": (name, plan.read_bytes())}, data=form).json()
    flown = api["autopilot"]
    assert flown.pop("chosen_by") == ("form" if autopilot else "plan")
    assert flown == ref  # every key of `trajectory mission --json`, equal
    assert api["eta_s"] == pytest.approx(element_eta)


def forms_label(family: str) -> str:
    from uasnav.web.prediction import AUTOPILOT_LABELS

    return str(jinja_escape(AUTOPILOT_LABELS[family]))


def test_dalby_page_is_the_autopilot_figure_not_the_slow_multirotor_one(client, shared_data) -> None:
    """The QuadPlane plan gives no speed before its first waypoints: the page flies it at the
    plane's cruise airspeed (about an hour, as QGroundControl says), never at a multirotor's
    default speed (over four hours)."""
    plan = shared_data / "missions" / "ardupilot_autotest_dalby_obc2016.waypoints"
    text = client.post("/trajectory", files={"plan": (plan.name, plan.read_bytes())}).text
    eta, qgc = page_eta(text), page_eta(text, "qgc-eta")
    assert abs(eta - qgc) / qgc < 0.05 and eta < 3600.0
    assert "AIRSPEED_CRUISE" in text and "ArduPlane" in text


def test_csv_route_has_no_autopilot_model_and_a_bad_autopilot_is_named(client, tmp_path) -> None:
    p = _plan_csv(tmp_path)
    out = client.post("/api/trajectory/predict", files={"plan": ("a.csv", p.read_bytes())}).json()
    assert out["autopilot"] is None and out["eta_s"] > 0
    text = client.post("/trajectory", files={"plan": ("a.csv", p.read_bytes())}).text
    assert 'id="mission-items"' not in text and 'id="element-eta"' not in text
    assert page_eta(text) == pytest.approx(out["eta_s"])
    r = client.post(
        "/trajectory",
        files={"plan": ("a.csv", p.read_bytes())},
        data={"autopilot": "betaflight", "wind_speed": "4"},
    )
    assert r.status_code == 422
    msg = re.search(r'id="te-autopilot" role="alert">([^<]*)<', r.text)
    assert msg and html.unescape(msg.group(1)).startswith("autopilot: 'betaflight' is not one of")
    assert 'value="4"' in r.text  # the other fields stay as typed
    a = client.post(
        "/api/trajectory/predict", files={"plan": ("a.csv", p.read_bytes())}, data={"autopilot": "x"}
    )
    assert a.status_code == 422 and "autopilot" in a.text


def test_predict_page_without_javascript(client, tmp_path) -> None:
    p = _plan_csv(tmp_path)
    r = client.post(
        "/trajectory", files={"plan": ("a.csv", p.read_bytes())}, data={"wind_speed": "3", "wind_from": "90"}
    )
    assert r.status_code == 200 and 'id="prediction"' in r.text
    assert "data:text/csv;base64," in r.text and "data:application/geo+json;base64," in r.text
    assert r.text.count('<circle class="wp"') >= 4


@pytest.mark.parametrize(
    ("name", "data", "form", "field"),
    [
        ("a.exe", b"lat,lon\n1,2\n", {}, "plan"),
        ("a.csv", b"", {}, "plan"),
        ("a.csv", b"\x00\x01binary", {}, "plan"),
        ("a.csv", b"lat,lon\n1,nan\n2,3\n", {}, "plan"),
        ("a.plan", b'{"fileType": "Plan", "mission": {"items": [' * 50, {}, "plan"),
        ("a.plan", b"[" * 50_000, {}, "plan"),
        ("a.waypoints", b"QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\t999\t8\t10\t1\n", {}, "plan"),
        ("a.csv", b"lat,lon\n47,8\n47.001,8\n", {"wind_speed": "-1"}, "wind_speed"),
        ("a.csv", b"lat,lon\n47,8\n47.001,8\n", {"wind_speed": "inf"}, "wind_speed"),
        ("a.csv", b"lat,lon\n47,8\n47.001,8\n", {"speed": "0"}, "speed"),
        ("a.csv", b"lat,lon\n47,8\n47.001,8\n", {"format": "xml"}, "format"),
    ],
)
def test_predict_refusals_name_the_field(client, name, data, form, field) -> None:
    r = client.post("/api/trajectory/predict", files={"plan": (name, data)}, data=form)
    assert 400 <= r.status_code < 500, r.text
    assert r.json()["field"] == field, r.json()
    assert "/tmp" not in r.json()["error"] and "uasnav-plan-" not in r.json()["error"]


def test_hostile_model_uploads(client, tmp_path) -> None:
    p = _plan_csv(tmp_path).read_bytes()
    for model in [b"{", b'{"format": "nope"}', b"[" * 10_000, b'{"a": NaN}', b"\xff"]:
        r = client.post("/api/trajectory/predict", files={"plan": ("a.csv", p), "model": ("m.json", model)})
        assert r.status_code == 422 and r.json()["field"] == "model", (model[:20], r.text)


def test_uploaded_model_is_used(client, tmp_path) -> None:
    m = default_model()
    path = tmp_path / "m.json"
    m.save(path)
    p = _plan_csv(tmp_path).read_bytes()
    a = client.post(
        "/api/trajectory/predict", files={"plan": ("a.csv", p), "model": ("m.json", path.read_bytes())}
    )
    b = client.post("/api/trajectory/predict", files={"plan": ("a.csv", p)})
    assert a.json()["model"] == "uploaded model"
    # the method is named as `trajectory predict --json` names it: the built-in model is the default
    from uasnav.trajectory.models import DEFAULT_METHOD, method_of

    assert a.json()["method"] == b.json()["method"] == method_of(m) == DEFAULT_METHOD
    from uasnav.trajectory.models import make_predictor
    from uasnav.trajectory.samples import ElementSamples, measure_elements
    from uasnav.trajectory.simulator import WindModel, simulate_flight

    parts = []
    for j, plan in enumerate(phantom4_plans().values()):
        tel = simulate_flight(plan, wind=WindModel(speed_ms=3.0, from_deg=0.0), seed=j)
        parts.append(
            measure_elements(
                tel.plan_ne, tel.t, tel.pos_ne, tel.vel_ne, tel.wind_ne, tel.cruise_ms, flight=j
            )[1]
        )
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=UserWarning)  # few samples per class, expected
        make_predictor("lvq", random_state=0).fit(ElementSamples.concat(parts)).save(path)
    c = client.post(
        "/api/trajectory/predict", files={"plan": ("a.csv", p), "model": ("m.json", path.read_bytes())}
    )
    assert c.status_code == 200 and c.json()["method"] == "lvq"
    assert a.json()["waypoint_times_s"] == pytest.approx(b.json()["waypoint_times_s"])


def test_upload_names_never_reach_the_file_system(client, tmp_path, monkeypatch) -> None:
    """A hostile file name is only used for its suffix: nothing is written where it points."""
    target = tmp_path / "pwned.csv"
    name = str(target.parent / ".." / target.parent.name / "pwned.csv")
    monkeypatch.chdir(tmp_path)
    body = _plan_csv(tmp_path, "src.csv").read_bytes()
    r = client.post("/api/trajectory/predict", files={"plan": (name, body)})
    assert r.status_code == 200
    assert not target.exists() and sorted(x.name for x in tmp_path.iterdir()) == ["src.csv"]


def test_oversized_upload_is_413(client) -> None:
    big = b"lat,lon\n" + b"47.0,8.0\n" * (2 * 2**20)
    r = client.post("/api/trajectory/predict", files={"plan": ("a.csv", big)})
    assert r.status_code == 413 and r.json()["field"] == "body"
    r = client.post("/api/trajectory/predict", content=b"x", headers={"content-type": "text/plain"})
    assert r.status_code == 415


def test_default_model_is_deterministic_and_simulated_only() -> None:
    from uasnav.web import default_model as dm

    a = dm.default_model()
    assert dm.default_model() is a  # cached
    dm.clear_cache()
    b = dm.default_model()
    assert json.dumps(a.to_dict(), sort_keys=True) == json.dumps(b.to_dict(), sort_keys=True)
    # trained on every wind of the simulated set: calm to 8 m/s
    lo, hi = b.wind_range_ms_
    assert lo < 1.0 and hi > 7.0
    assert np.isfinite(b.cruise_ms_)


def test_page_downloads_are_what_is_shown(client) -> None:
    import base64

    r = client.post("/select", data={k: str(v) for k, v in THESIS.items()})
    found = re.findall(r'href="data:([^;]+);charset=utf-8;base64,([^"]+)" download="([^"]+)"', r.text)
    uris = {name: base64.b64decode(data).decode() for _, data, name in found}
    assert set(uris) == {
        "selection.json",
        "ranking.csv",
        "rejections.csv",
        "authorisation-summary.html",
        "authorisation-summary.json",
    }
    api = client.post("/api/select", json=THESIS).json()
    assert json.loads(uris["selection.json"]) == api
    assert [row["uas"] for row in csv.DictReader(io.StringIO(uris["ranking.csv"]))] == [
        x["uas"] for x in api["ranking"]
    ]
    # each configuration with the operation it implies (the operation follows the UA)
    assert [
        (row["visibility"], row["category"]) for row in csv.DictReader(io.StringIO(uris["ranking.csv"]))
    ] == [(x["visibility"], x["category"]) for x in api["ranking"]]


def test_page_shows_the_operation_of_each_configuration_and_every_operation(client) -> None:
    """At 300 m the best UA flies VLOS in the open category while the small UAS that cannot be
    kept in sight there imply a BVLOS/specific operation: the page lists both operations with
    their best configuration, and each ranked row its own operation."""
    form = {**{k: str(v) for k, v in THESIS.items()}, "range": "300"}
    api = client.post("/api/select", json={**THESIS, "range": 300}).json()
    assert {o["visibility"] for o in api["operations"]} >= {"VLOS", "BVLOS"}
    page = client.post("/select", data=form).text
    table = page[page.index('id="operations"') : page.index("</table>", page.index('id="operations"'))]
    for o in api["operations"]:
        assert f"<td>{o['visibility']}</td><td>{o['category']}</td>" in table
        if o["best"]:
            assert f"{o['best']['uas']} + {o['best']['camera']}" in table
    ops = re.findall(r'<td class="operation">([^<]+)</td>', page)
    assert ops == [f"{x['visibility']}, {x['category']}" for x in api["ranking"]]


def test_new_option_kinds_are_handled_generically(client, monkeypatch) -> None:
    """An option added to the table later (an area file, an output summary) appears
    in the form and the API without editing the web app; a file option's value is the document
    (bytes or parsed JSON), never a path the server opens; an output path is never a request
    option."""
    import uasnav.mission.request as request_mod
    import uasnav.web.app as web_app
    from uasnav.mission.request import SelectOption

    extra = (
        SelectOption("fake_area", "file", None, "An operation area (GeoJSON).", label="Area"),
        SelectOption("fake_summary", "output", None, "Write a summary here."),
    )
    monkeypatch.setattr(request_mod, "SELECT_OPTIONS", request_mod.SELECT_OPTIONS + extra)
    seen: list[object] = []
    real = web_app.run_select

    real_parse = web_app.parse_select_options
    fake = ("fake_area", "fake_summary")

    def spy(values, **kw):  # type: ignore[no-untyped-def]
        seen.append(values.get("fake_area"))
        return real({k: v for k, v in values.items() if k not in fake}, **kw)

    monkeypatch.setattr(web_app, "run_select", spy)
    monkeypatch.setattr(
        web_app, "parse_select_options", lambda v: real_parse({k: x for k, x in v.items() if k not in fake})
    )
    html = client.get("/").text
    assert 'type="file" id="f-fake_area" name="fake_area"' in html and 'name="fake_summary"' not in html
    r = client.post("/api/select", json={"fake_area": "/etc/passwd"})
    assert r.status_code == 200, r.text
    area = seen[-1]
    assert getattr(area, "data", area) == b"/etc/passwd"  # the text itself, as bytes: not a path
    client.post("/api/select", json={"fake_area": {"type": "FeatureCollection", "features": []}})
    assert seen[-1] == {"type": "FeatureCollection", "features": []}
    assert client.post("/api/select", json={"fake_area": 5}).json()["field"] == "fake_area"
    r = client.post("/api/select", json={"fake_summary": "/tmp/summary.html"})
    assert r.status_code == 422 and r.json()["field"] == "fake_summary"
    assert client.get("/select/export.json?fake_area=/etc/passwd").json()["field"] == "fake_area"
    page = client.post(
        "/select", files={"fake_area": ("../../zone.geojson", b'{"type": "Polygon"}')}, data={"range": "300"}
    )
    assert page.status_code == 200
    assert getattr(seen[-1], "data", seen[-1]) == b'{"type": "Polygon"}'
    big = client.post("/select", files={"fake_area": ("a.geojson", b" " * (forms.MAX_OPTION_FILE_BYTES + 1))})
    assert big.status_code == 422 and "fake_area: file over" in big.text


def test_authorisation_summary_is_the_compliance_document(client, tmp_path) -> None:
    """The results page embeds the authorisation summary rendered by ``uasnav.mission.summary``
    (its print view, linked to the same stylesheet), and its downloads are that document: the
    same bytes as ``uasnav select --summary`` writes, in the form's words (the "from" column
    names the form's fields where the command line names its options). One renderer, one
    document."""
    import base64

    from uasnav.mission.request import run_select
    from uasnav.mission.summary import SUMMARY_CSS, summary_dict, summary_fragment
    from uasnav.web.context import in_operator_words, plain

    r = client.post("/select", data={"range": "300", "top": "4"})
    sel = run_select({"range": 300.0, "top": 4})
    fragment = plain(summary_fragment(sel))
    assert fragment != summary_fragment(sel) and not re.search(r"--[a-z]", fragment)
    assert fragment in r.text  # rendered once, by the summary module
    assert r.text.count("class='auth-summary'") == 1
    assert '<link rel="stylesheet" href="/summary.css">' in r.text
    css = client.get("/summary.css")
    assert (
        css.status_code == 200
        and css.text == SUMMARY_CSS
        and css.headers["content-type"].startswith("text/css")
    )
    found = dict(
        (name, base64.b64decode(data).decode())
        for data, name in re.findall(
            r'href="data:[^;]+;charset=utf-8;base64,([^"]+)" download="(authorisation-summary\.[a-z]+)"',
            r.text,
        )
    )
    out = tmp_path / "s.html"
    res = CliRunner().invoke(main, ["select", "--range", "300", "--top", "4", "--summary", str(out)])
    assert res.exit_code == 0, res.output
    assert found["authorisation-summary.html"] == plain(out.read_text())
    assert fragment in plain(out.read_text())
    assert json.loads(found["authorisation-summary.json"]) == summary_dict(in_operator_words(sel, {}))


# A field inside the InterUSS sample zone (Geneva), as in test_mission_authorisation.
INSIDE = {
    "type": "Polygon",
    "coordinates": [
        [[6.1680, 46.2160], [6.1689, 46.2160], [6.1689, 46.2165], [6.1680, 46.2165], [6.1680, 46.2160]]
    ],
}


def _prohibited(shared_data, tmp_path) -> tuple[Path, Path]:
    doc = json.loads((shared_data / "utm" / "interuss_ed269_geozone_sample.json").read_text())
    doc["UASZoneList"][0].update(restriction="PROHIBITED", message="military area")
    z, a = tmp_path / "prohibited.json", tmp_path / "field.geojson"
    z.write_text(json.dumps(doc))
    a.write_text(json.dumps(INSIDE))
    return z, a


def test_not_authorisable_is_shown_and_nothing_is_flyable(client, shared_data, tmp_path) -> None:
    """A PROHIBITED zone: the page leads with the verdict and lists the configurations as
    withheld (not as a ranking); the API with the same documents equals ``select --json``."""
    z, a = _prohibited(shared_data, tmp_path)
    cli = CliRunner().invoke(
        main, ["select", "--range", "1500", "--zones", str(z), "--area", str(a), "--json"]
    )
    want = json.loads(cli.output)
    assert want["authorisation"]["authorisable"] is False and want["withheld_ranking"]
    body = {"range": 1500, "zones": json.loads(z.read_text()), "area": json.loads(a.read_text())}
    got = client.post("/api/select", json=body).json()
    assert (
        got["authorisation"] == want["authorisation"] and got["withheld_ranking"] == want["withheld_ranking"]
    )
    assert got["ranking"] == [] and got["sora"] == want["sora"]
    page = client.post(
        "/select",
        data={"range": "1500"},
        files={"zones": ("prohibited.json", z.read_bytes()), "area": ("field.geojson", a.read_bytes())},
    ).text
    box = re.search(r'<div class="verdict-box" role="alert" id="not-authorisable">(.*?)</div>', page, re.S)
    assert box and "Not flyable as planned" in box.group(1)
    assert str(jinja_escape(want["authorisation"]["verdict"])) in box.group(1)
    assert 'id="ranking"' not in page
    table = re.search(r'<table class="data sortable withheld" id="withheld">(.*?)</table>', page, re.S)
    assert table
    rows = re.findall(r"<tr><td class=\"num\">\d+</td><td>([^<]*)</td><td>([^<]*)</td>", table.group(1))
    assert rows == [
        (str(jinja_escape(w["uas"])), str(jinja_escape(w["camera"]))) for w in want["withheld_ranking"]
    ]
    assert table.group(1).count("withheld</span>") == len(rows)


def test_operation_inputs_by_kind(client, tmp_path) -> None:
    """Density, mitigations, datetime as text; a choice whose default is None has an empty
    option (selected, so nothing is submitted); a flag defaulting on is sent as ``false`` when
    unchecked; an uploaded plan keeps its extension so the area reader picks its format."""
    html = client.get("/").text
    sel = re.search(r'<select id="f-residual_arc".*?</select>', html, re.S)
    assert sel and re.search(r'<option value="" selected>', sel.group(0))
    for name in ("population_density", "mitigations", "flight_time"):
        assert re.search(rf'<input id="f-{name}" name="{name}" ', html), name
    assert re.search(
        r'type="hidden" name="gnss_autopilot" value="false".*?id="f-gnss_autopilot"[^>]*checked', html, re.S
    )
    # an unchecked default-on flag: the hidden false is what the browser posts
    off = client.post("/select", data={"range": "300", "gnss_autopilot": "false"}).text
    api_off = client.post("/api/select", json={"range": 300, "gnss_autopilot": False}).json()
    api_on = client.post("/api/select", json={"range": 300}).json()
    n_off, n_on = len(api_off["rejections"]), len(api_on["rejections"])
    assert n_off != n_on and f"({n_off}: failed test and margin)" in off

    def ranked(page: str) -> list[tuple[str, str]]:
        table = re.search(r'id="ranking">(.*?)</table>', page, re.S)
        assert table
        return re.findall(r'<tr>\s*<td class="num">\d+</td><td>([^<]*)</td><td>([^<]*)</td>', table.group(1))

    assert ranked(off) == [
        (str(jinja_escape(x["uas"])), str(jinja_escape(x["camera"]))) for x in api_off["ranking"]
    ]
    # typed issue-18 values reach the selector as the API takes them
    typed = {
        "range": "1500",
        "population_density": "sparsely",
        "mitigations": "M1=low",
        "flight_time": "2026-06-01T10:00:00+02:00",
        "residual_arc": "",
        "sora_edition": "2.0",
    }
    page = client.post("/select", data=typed).text
    api = client.post("/api/select", json={k: v for k, v in typed.items() if v}).json()
    assert api["sora"]["edition"] == "2.0" and f"SORA {api['sora']['edition']}" in page
    # equipment: each item with its reason, necessary ones with their state on the chosen UAS
    for e in api["equipment"]:
        assert str(jinja_escape(e["reason"])) in page, e["id"]
    for x in api["chosen_equipment"]:
        assert re.search(
            rf'data-id="{x["id"]}">.*?<span class="state [^"]*">{re.escape(x["state"])}</span>', page, re.S
        ), x
    # a Mission Planner plan as the area, recognised by its uploaded file name's extension
    wpl = "QGC WPL 110\n" + "".join(
        f"{i}\t{int(i == 0)}\t{0 if i == 0 else 3}\t16\t0\t0\t0\t0\t{lat}\t{lon}\t{0 if i == 0 else 50}\t1\n"
        for i, (lat, lon) in enumerate([(46.2161, 6.1681), (46.2161, 6.1682), (46.2164, 6.1688)])
    )
    p = tmp_path / "route.waypoints"
    p.write_text(wpl)
    cli = CliRunner().invoke(main, ["select", "--range", "300", "--area", str(p), "--json"])
    up = client.post(
        "/select", data={"range": "300"}, files={"area": ("C:\\plans\\route.waypoints", wpl.encode())}
    )
    assert up.status_code == 200, up.text
    want = json.loads(cli.output)
    assert cli.exit_code == 0, cli.output
    api = client.post("/api/select", json={"range": 300, "area": wpl}).json()
    assert api["operation"] == want["operation"] and api["ranking"] == want["ranking"]
    assert ranked(up.text) == [
        (str(jinja_escape(x["uas"])), str(jinja_escape(x["camera"]))) for x in want["ranking"]
    ]


def test_4d_plan_check_is_the_predictors_rule(client, tmp_path) -> None:
    """Required waypoint times: each within the tolerance, as `trajectory predict --required`."""
    p = _plan_csv(tmp_path).read_bytes()
    base = client.post("/api/trajectory/predict", files={"plan": ("a.csv", p)}).json()
    times = base["waypoint_times_s"]
    late = [t + (30.0 if i == 2 else 1.0) for i, t in enumerate(times)]
    form = {"required": ",".join(f"{t:.3f}" for t in late), "tolerance": "5"}
    r = client.post("/api/trajectory/predict", files={"plan": ("a.csv", p)}, data=form).json()
    assert r["feasible"] is False
    assert r["waypoint_ok"] == [i != 2 for i in range(len(times))]
    ok = {"required": ",".join(f"{t:.3f}" for t in times)}
    assert client.post("/api/trajectory/predict", files={"plan": ("a.csv", p)}, data=ok).json()["feasible"]
    page = client.post("/trajectory", files={"plan": ("a.csv", p)}, data=form)
    assert "4D plan not feasible" in page.text and page.text.count("late/early") == 1
    for bad in ["1,2", "nan," * (len(times) - 1) + "1", "a,b"]:
        r = client.post("/api/trajectory/predict", files={"plan": ("a.csv", p)}, data={"required": bad})
        assert r.status_code == 422 and r.json()["field"] == "required", bad
    r = client.post("/api/trajectory/predict", files={"plan": ("a.csv", p)}, data={**ok, "tolerance": "-1"})
    assert r.json()["field"] == "tolerance"


def test_predict_api_is_what_the_cli_prints(client, tmp_path) -> None:
    """The same model file, plan, wind and 4D times through `uasnav trajectory predict --json`."""
    model = tmp_path / "m.json"
    default_model().save(model)
    plan = _plan_csv(tmp_path)
    required = "0,20,40,60,80"
    argv = ["trajectory", "predict", "--model", str(model), "--plan", str(plan), "--wind", "3@250"]
    cli = CliRunner().invoke(main, [*argv, "--required", required, "--tolerance", "4", "--json"])
    assert cli.exit_code == 0, cli.output
    ref = json.loads(cli.output)
    form = {"wind_speed": "3", "wind_from": "250", "required": required, "tolerance": "4"}
    files = {"plan": ("a.csv", plan.read_bytes()), "model": ("m.json", model.read_bytes())}
    api = client.post("/api/trajectory/predict", files=files, data=form).json()
    assert api["eta_s"] == pytest.approx(ref["eta_s"])
    assert api["waypoint_times_s"] == pytest.approx(ref["waypoint_times_s"])
    assert api["feasible"] == ref["feasible"] and api["waypoint_ok"] == ref["waypoint_ok"]
    keys = ("element", "kind", "class", "low_confidence", "flags")
    assert [{k: e[k] for k in keys} for e in api["elements"]] == [
        {k: e[k] for k in keys} for e in ref["elements"]
    ]
    assert [e["time_s"] for e in api["elements"]] == pytest.approx([e["time_s"] for e in ref["elements"]])
