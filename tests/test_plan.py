"""``uasnav plan``: a field to a filed authorisation — the operation, the survey's coverage
from the plan's own trigger points, flights within endurance that resume, zones, conflicts
with other intents, the predicted time against the simulator, and the files written."""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from click.testing import CliRunner
from shapely import geometry as sg
from shapely.ops import unary_union

import uasnav
from uasnav.cli import main
from uasnav.geo import frames
from uasnav.io.plans import read_plan
from uasnav.mission.survey import MAV_CMD_DO_SET_CAM_TRIGG_DIST

LAT0, LON0 = 45.0, 9.0
START = "2026-05-01T10:00:00Z"


def rect(east_m: float, north_m: float, width_m: float, height_m: float, lat0=LAT0, lon0=LON0) -> dict:
    """A GeoJSON rectangle whose south-west corner is east_m/north_m from (lat0, lon0)."""
    e = np.array([east_m, east_m + width_m, east_m + width_m, east_m, east_m])
    n = np.array([north_m, north_m, north_m + height_m, north_m + height_m, north_m])
    la, lo, _ = frames.enu_to_geodetic(e, n, 0.0, lat0, lon0, 0.0)
    return {"type": "Polygon", "coordinates": [[[float(x), float(y)] for x, y in zip(lo, la, strict=True)]]}


def _local(lat, lon):
    e, n, _ = frames.geodetic_to_enu(np.asarray(lat), np.asarray(lon), 0.0, LAT0, LON0, 0.0)
    return np.column_stack([e, n])


@pytest.fixture(scope="module")
def large(tmp_path_factory):
    """A 400 m × 300 m field at 0.02 m/px, RGB camera, written to a directory."""
    out = tmp_path_factory.mktemp("large")
    area = out / "field.geojson"
    area.write_text(json.dumps(rect(20, 20, 400, 300)))
    res = uasnav.plan(
        area=str(area),
        takeoff=f"{LAT0},{LON0}",
        resolution=0.02,
        imagery="rgb",
        wind="3@270",
        start=START,
        ground_elevation=200.0,
    )
    from uasnav.mission.planner import write_outputs

    write_outputs(res, out / "out")
    return res, out / "out"


def test_small_field_beside_takeoff_is_vlos_open() -> None:
    res = uasnav.plan(area=rect(10, 10, 70, 70), takeoff=f"{LAT0},{LON0}", resolution=0.05, start=START)
    assert res["operation"]["visibility"] == "VLOS"
    assert res["operation"]["category"] == "open"
    assert res["authorisation"]["authorisable"]
    d = res["distances"]
    assert d["area_pilot_distance_m"] < 150
    # the run-outs carry the UA past the field: the operation's distance is the route's
    assert d["pilot_distance_m"] == d["route_pilot_distance_m"] > d["area_pilot_distance_m"]
    assert d["pilot_distance_m"] == pytest.approx(res["operation"]["max_distance_m"])
    s = res["survey"]
    assert s["gsd_m"] <= 0.05 and s["photos"] >= 1 and s["flights"] == 1
    assert set(res.keys()) >= {
        "configuration",
        "operation",
        "survey",
        "eta_s",
        "zones",
        "conflicts",
        "authorisation",
    }
    assert {"altitude_m", "gsd_m", "photos", "lines", "length_m", "flights", "height_reason"} <= set(s)


def test_large_field_photos_cover_it_with_the_overlaps_at_the_resolution(large) -> None:
    res, out = large
    s = res["survey"]
    assert s["lines"] >= 3 and s["gsd_m"] <= 0.02 + 1e-12
    assert s["height_reason"].startswith(("resolution", "legal"))
    cam = res.selection.database.cameras
    j = cam.ids.index(res["configuration"]["camera_id"])
    hfov, wpx, hpx = float(cam.hfov_deg[j]), float(cam.resolution_w_px[j]), float(cam.resolution_h_px[j])
    photos, footprints = [], []
    for k in range(1, s["flights"] + 1):
        plan = read_plan(out / f"flight-{k:02d}.plan")
        items = plan.items
        on = None
        last_wp = None
        for it in items:
            if it.command == 16:
                if on is not None:
                    a, b = _local(on[0][0], on[0][1])[0], _local(it.lat_deg, it.lon_deg)[0]
                    n = math.floor(np.linalg.norm(b - a) / on[1] + 1e-6) + 1
                    u = (b - a) / np.linalg.norm(b - a)
                    for q in range(n):
                        photos.append((a + q * on[1] * u, u, it.alt_m))
                last_wp = (it.lat_deg, it.lon_deg)
            elif it.command == MAV_CMD_DO_SET_CAM_TRIGG_DIST:
                on = (last_wp, it.params[0]) if it.params[0] > 0 else None
    assert len(photos) == s["photos"]
    h = photos[0][2]
    gsd = 2 * h * math.tan(math.radians(hfov) / 2) / wpx
    assert gsd <= 0.02 + 1e-9
    w = 2 * h * math.tan(math.radians(hfov) / 2)
    length = w * hpx / wpx
    for p, u, _ in photos:
        v = np.array([-u[1], u[0]])
        c = [p + sa * u * length / 2 + sb * v * w / 2 for sa, sb in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        footprints.append(sg.Polygon(c))
    field = sg.Polygon(_local(*np.array(rect(20, 20, 400, 300)["coordinates"][0])[:, ::-1].T))
    assert field.difference(unary_union(footprints)).area < 1e-3 * field.area
    # along a line: consecutive photos overlap by the front overlap; lines by the side overlap
    trig = s["trigger_distance_m"]
    assert 1 - trig / length >= 0.75 - 1e-6
    assert 1 - s["line_spacing_m"] / w >= 0.65 - 1e-6


def test_plans_read_back_and_files_are_all_written(large) -> None:
    res, out = large
    names = sorted(p.name for p in out.iterdir())
    assert set(res["files"]) == set(names)
    for k in range(1, res["survey"]["flights"] + 1):
        plan = read_plan(out / f"flight-{k:02d}.plan")
        wpl = read_plan(out / f"flight-{k:02d}.waypoints")
        assert [i.command for i in plan.items] == [i.command for i in wpl.items]
        doc = json.loads((out / f"flight-{k:02d}.plan").read_text())
        assert doc["fileType"] == "Plan" and doc["mission"]["items"]
        assert json.loads((out / f"flight-{k:02d}.intent.json").read_text())["volumes"]
    assert json.loads((out / "result.json").read_text()) == json.loads(json.dumps(res.result))
    assert "Survey" in (out / "summary.html").read_text()


def test_flights_split_within_endurance_and_resume_where_stopped() -> None:
    from uasnav.mission.survey import Camera, plan_survey

    field = sg.box(0, 0, 600, 400)
    cam = Camera("test", 60.0, 4000, 3000)
    one = plan_survey(field, cam, resolution_m=0.02, origin=(LAT0, LON0), cruise_ms=8.0)
    split = plan_survey(field, cam, resolution_m=0.02, origin=(LAT0, LON0), cruise_ms=8.0, endurance_s=400.0)
    assert len(one.flights) == 1 and len(split.flights) > 2
    assert all(t <= 400.0 for t in split.estimated_time_s)
    assert split.photos == one.photos
    a = one.photo_positions()
    b = np.vstack([split.photo_positions(k) for k in range(len(split.flights))])
    assert a.shape == b.shape and np.allclose(a, b, atol=1e-6)


def test_same_field_far_from_pilot_is_bvlos_with_an_authorisation_whose_conditions_hold() -> None:
    res = uasnav.plan(
        area=rect(1500, 0, 70, 70),
        takeoff=f"{LAT0},{LON0}",
        pilot=f"{LAT0},{LON0}",
        resolution=0.05,
        start=START,
    )
    assert res["distances"]["pilot_distance_m"] > 1500
    assert res["operation"]["visibility"] == "BVLOS"
    assert res["operation"]["category"] == "specific"
    auth = res["authorisation"]
    assert auth["authorisable"]
    sts = [x for x in res["scenarios"] if x["applies"]]
    assert res["sora"] is not None or sts
    for x in sts:  # an offered scenario's own conditions hold
        assert all("not" not in r.lower().split()[:1] for r in x["reasons"])
    assert res["configuration"] is not None
    assert all(r["open_subcategory"] is None for r in res.selection.to_dict()["ranking"])


def test_field_inside_a_zone_is_reported(shared_data) -> None:
    inside = {
        "type": "Polygon",
        "coordinates": [
            [[6.1680, 46.2160], [6.1689, 46.2160], [6.1689, 46.2165], [6.1680, 46.2165], [6.1680, 46.2160]]
        ],
    }
    res = uasnav.plan(
        area=inside,
        resolution=0.05,
        zones=str(shared_data / "utm" / "interuss_ed269_geozone_sample.json"),
        start=START,
    )
    assert [h["identifier"] for h in res["zones"]["hits"]] == ["LSXX"]
    assert any("LSXX" in r for r in res["authorisation"]["requirements"])
    # the zones were checked over the predicted flight time, not a default range estimate
    window = res["flight_window"]
    assert window["duration_s"] == pytest.approx(res["eta_s"]["window"]["duration_s"])


def test_overlapping_intent_is_a_conflict_with_a_delay(large, tmp_path) -> None:
    _res, out = large
    other = tmp_path / "neighbour.json"
    other.write_text((out / "flight-01.intent.json").read_text())
    again = uasnav.plan(
        area=rect(20, 20, 400, 300),
        takeoff=f"{LAT0},{LON0}",
        resolution=0.02,
        imagery="rgb",
        wind="3@270",
        start=START,
        ground_elevation=200.0,
        intents=[str(other)],
    )
    (c, *_) = [c for c in again["conflicts"] if c["flight"] == "flight-01"]
    assert c["intent"] == "neighbour"
    assert c["delay_s"] is not None and c["delay_s"] > 0
    assert any("neighbour" in r for r in again["authorisation"]["requirements"])


def test_predicted_time_flown_by_the_simulator_lies_within_its_bounds(large) -> None:
    from uasnav.trajectory.route3d import Route3D
    from uasnav.trajectory.route_sim import simulate_route
    from uasnav.trajectory.simulator import MultirotorParams

    res, _ = large
    speed = res["survey"]["speed_ms"]
    for f in res.flights:
        b = f.intent
        n = len(b.route_en)
        route = Route3D(b.route_en[:, ::-1], b.route_alt_w84, np.zeros(n), np.full(n, speed))
        truth = simulate_route(route, params=MultirotorParams(cruise_ms=speed), seed=f.number)
        t_end = float(truth.t[-1])
        lo, hi = b.eta_bounds_s
        assert lo <= t_end <= hi, (t_end, lo, hi)


def test_cli_plan_writes_outputs_and_prints_result_json(tmp_path) -> None:
    area = tmp_path / "f.geojson"
    area.write_text(json.dumps(rect(10, 10, 70, 70)))
    out = tmp_path / "out"
    r = CliRunner().invoke(
        main,
        ["plan", "--area", str(area), "--resolution", "0.05", "--wind", "4@180", "--start", START,
         "--out", str(out), "--json"],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert d == json.loads((out / "result.json").read_text())
    assert (out / "flight-01.plan").exists() and (out / "summary.html").exists()
    bad = CliRunner().invoke(
        main, ["plan", "--area", str(area), "--wind", "5@x", "--out", str(tmp_path / "o")]
    )
    assert bad.exit_code == 2 and "wind" in bad.output
    assert not (tmp_path / "o").exists()


def test_a_resolution_no_camera_reaches_is_said_as_such() -> None:
    res = uasnav.plan(area=rect(10, 10, 70, 70), resolution=0.0005, start=START)
    assert res["survey"] is None and not res["authorisation"]["authorisable"]
    verdict = res["authorisation"]["verdict"]
    assert verdict.startswith("no camera in the database meets resolution")
    # what was asked, in the option's own unit, then where the finest camera falls short
    assert "--resolution 0.0005 m/px (0.5 mm per pixel) asked" in verdict, verdict
    assert "asked at" not in verdict
    finest = re.search(r"the finest, ([^,]+), gives ([\d.]+) m/px \(([\d.]+) mm per pixel\) at 10 m, "
                       r"the lowest height a survey flies", verdict)  # fmt: skip
    assert finest, verdict
    assert float(finest.group(2)) * 1000 == pytest.approx(float(finest.group(3)), rel=0.05)
    assert set(res.files) == {"result.json"}


def _prohibited_sample(shared_data, tmp_path):
    """The ED-269 sample with its zone made PROHIBITED, and a field inside the zone."""
    doc = json.loads((shared_data / "utm" / "interuss_ed269_geozone_sample.json").read_text())
    doc["UASZoneList"][0]["restriction"] = "PROHIBITED"
    zones = tmp_path / "prohibited.json"
    zones.write_text(json.dumps(doc))
    inside = {
        "type": "Polygon",
        "coordinates": [
            [[6.1680, 46.2160], [6.1689, 46.2160], [6.1689, 46.2165], [6.1680, 46.2165], [6.1680, 46.2160]]
        ],
    }
    area = tmp_path / "inside.geojson"
    area.write_text(json.dumps(inside))
    return area, zones


def test_a_prohibited_zone_leaves_no_plan(shared_data, tmp_path) -> None:
    area, zones = _prohibited_sample(shared_data, tmp_path)
    res = uasnav.plan(area=str(area), resolution=0.05, zones=str(zones), start=START)
    # no configuration, no flight, no flight file: the verdict names the zone
    assert res["configuration"] is None and res["survey"] is None and res["flights"] == []
    assert not res["authorisation"]["authorisable"]
    assert "PROHIBITED zone LSXX" in res["authorisation"]["verdict"]
    assert [h["identifier"] for h in res["zones"]["hits"]] == ["LSXX"]
    assert res.selection.to_dict()["withheld_ranking"]
    assert set(res.files) == {"result.json"}


@pytest.mark.parametrize("case", ["prohibited", "resolution"])
def test_cli_without_a_plan_is_one_error_line_and_writes_nothing(shared_data, tmp_path, case) -> None:
    area, zones = _prohibited_sample(shared_data, tmp_path)
    if case == "prohibited":
        args = ["--area", str(area), "--resolution", "0.05", "--zones", str(zones)]
        why = "PROHIBITED zone LSXX"
    else:
        args = ["--area", str(area), "--resolution", "0.0005"]
        why = "no camera in the database meets resolution"
    fresh, kept = tmp_path / "fresh", tmp_path / "kept"
    kept.mkdir()
    (kept / "result.json").write_text("earlier plan\n")
    for out in (fresh, kept):
        r = CliRunner().invoke(main, ["plan", *args, "--start", START, "--out", str(out), "--json"])
        assert r.exit_code == 1, r.output
        assert r.stdout == ""
        lines = r.stderr.splitlines()
        assert len(lines) == 1 and lines[0].startswith(f"error: no survey plan for {area}: ")
        assert why in lines[0]
    assert not fresh.exists()
    assert [p.name for p in kept.iterdir()] == ["result.json"]
    assert (kept / "result.json").read_text() == "earlier plan\n"


def _volumes(intent_path) -> list[dict]:
    return [v["volume"] for v in json.loads(intent_path.read_text())["volumes"]]


def test_intent_heights_stand_on_the_stated_ground_and_geoid(large) -> None:
    """h_W84 = H_AMSL(ground) + height + N: the take-off volume starts at the ground's ellipsoidal
    height less the vertical buffer, and the survey's top is the survey height above it."""
    from uasnav.geo.geoid import geoid_height
    from uasnav.utm.intent import DEFAULT_VERTICAL_BUFFER_M as BUF

    res, out = large
    g = res["ground"]
    n = float(geoid_height(LAT0, LON0))
    assert 40.0 < n < 50.0  # EGM96 in northern Italy: a geoid height no plan may ignore
    assert g["elevation_m"] == 200.0 and g["datum"] == "AMSL" and not g["assumed"]
    assert "--ground-elevation" in g["source"]
    assert g["at"] == [LAT0, LON0]
    assert g["geoid_height_m"] == pytest.approx(n, abs=1e-9)
    assert g["ellipsoidal_height_m"] == pytest.approx(200.0 + n, abs=1e-9)
    vols = [v for f in res["flights"] for v in _volumes(out / f"{f['name']}.intent.json")]
    assert {v[k]["reference"] for v in vols for k in ("altitude_lower", "altitude_upper")} == {"W84"}
    # the take-off volume begins on the ground; N varies by centimetres over the field
    assert vols[0]["altitude_lower"]["value"] == pytest.approx(200.0 + n - BUF, abs=0.05)
    top = max(v["altitude_upper"]["value"] for v in vols)
    assert top == pytest.approx(200.0 + res["survey"]["altitude_m"] + n + BUF, abs=0.1)
    # the same datum in the summary written beside the intents
    assert json.loads((out / "summary.json").read_text())["plan"]["ground"] == g
    assert "Ground at take-off" in (out / "summary.html").read_text()


def test_ground_elevation_shifts_every_intent_altitude_by_itself() -> None:
    a = uasnav.plan(area=rect(10, 10, 70, 70), takeoff=f"{LAT0},{LON0}", resolution=0.05, start=START)
    b = uasnav.plan(
        area=rect(10, 10, 70, 70),
        takeoff=f"{LAT0},{LON0}",
        resolution=0.05,
        start=START,
        ground_elevation=812.5,
    )
    assert a["ground"]["assumed"] and a["ground"]["elevation_m"] == 0.0
    assert "assumed" in a["ground"]["source"]
    assert any("give --ground-elevation" in x for x in a["survey"]["assumptions"])
    assert not any("ground elevation not known" in x for x in b["survey"]["assumptions"])
    za = [(v["altitude_lower"]["value"], v["altitude_upper"]["value"]) for v in _intent_volumes(a)]
    zb = [(v["altitude_lower"]["value"], v["altitude_upper"]["value"]) for v in _intent_volumes(b)]
    assert len(za) == len(zb) > 0
    assert np.allclose(np.array(zb) - np.array(za), 812.5, atol=1e-6)


def _intent_volumes(res) -> list[dict]:
    return [
        v["volume"]
        for f in res["flights"]
        for v in json.loads(res.files[f"{f['name']}.intent.json"])["volumes"]
    ]


def test_a_plan_as_area_gives_the_ground_from_its_home(large, tmp_path) -> None:
    _res, out = large
    again = uasnav.plan(area=str(out / "flight-01.plan"), resolution=0.05, start=START)
    g = again["ground"]
    assert g["elevation_m"] == pytest.approx(200.0) and not g["assumed"]
    assert "home position of the plan" in g["source"]


def test_cli_warns_when_the_ground_is_assumed(tmp_path) -> None:
    area = tmp_path / "field.geojson"
    area.write_text(json.dumps(rect(10, 10, 70, 70)))
    args = [
        "plan",
        "--area",
        str(area),
        "--takeoff",
        f"{LAT0},{LON0}",
        "--resolution",
        "0.05",
        "--start",
        START,
    ]
    r = CliRunner().invoke(main, [*args, "--out", str(tmp_path / "a")])
    j = CliRunner().invoke(main, [*args, "--json", "--out", str(tmp_path / "j")])
    assert j.exit_code == 0 and json.loads(j.stdout)["ground"]["assumed"]
    assert j.stderr.startswith("warning: ") and "--ground-elevation" in j.stderr
    assert r.exit_code == 0, r.output
    assert "Ground at take-off: 0.0 m AMSL (assumed" in r.stdout
    assert next(x for x in r.stderr.splitlines() if "--ground-elevation" in x).startswith("warning: ")
    r = CliRunner().invoke(main, [*args, "--ground-elevation", "250", "--out", str(tmp_path / "b")])
    assert r.exit_code == 0, r.output
    assert "Ground at take-off: 250.0 m AMSL (the operator" in r.stdout and "warning" not in r.stderr


def test_camera_timing_comes_from_the_database_where_it_is_known(tmp_path) -> None:
    from importlib import resources

    from uasnav.mission.database import load_database
    from uasnav.mission.survey import DEFAULT_EXPOSURE_S, DEFAULT_TIMING, DEFAULT_TRIGGER_INTERVAL_S, Camera

    shipped = load_database()
    cams = shipped.cameras
    mx = Camera.from_table(cams, cams.ids.index("micasense-rededge-mx"))
    assert mx.trigger_interval_s == 1.0 and "capture interval 1 s from the database" in mx.timing_source
    assert "support.micasense.com" in cams.sources[cams.ids.index("micasense-rededge-mx")]
    assert mx.exposure_s == DEFAULT_EXPOSURE_S and "stated default" in mx.timing_source
    other = Camera.from_table(cams, cams.ids.index("sony-a6000-20-mm"))
    assert (other.trigger_interval_s, other.exposure_s) == (DEFAULT_TRIGGER_INTERVAL_S, DEFAULT_EXPOSURE_S)
    assert other.timing_source == DEFAULT_TIMING

    # a database giving both: the survey's speed obeys them (closed forms of the module doc)
    xml = resources.files("uasnav.mission").joinpath("data", "database.xml").read_text()
    entry = '<camera id="sony-a6000-20-mm"'
    at = xml.index("<source>", xml.index(entry))
    xml = xml[:at] + "<capture_interval_s>2.5</capture_interval_s><exposure_s>0.004</exposure_s>" + xml[at:]
    db_path = tmp_path / "database.xml"
    db_path.write_text(xml)
    db = load_database(str(db_path))
    cam = Camera.from_table(db.cameras, db.cameras.ids.index("sony-a6000-20-mm"))
    assert (cam.trigger_interval_s, cam.exposure_s) == (2.5, 0.004)
    assert "capture interval 2.5 s from the database; exposure 0.004 s from the database" in cam.timing_source
    from uasnav.mission.survey import DEFAULT_BLUR_PX, plan_survey

    sp = plan_survey(
        sg.box(0, 0, 200, 150),
        cam,
        resolution_m=0.02,
        origin=(LAT0, LON0),
        cruise_ms=30.0,
        overlap=(0.8, 0.7),
    )
    expected = min(sp.trigger_m / 2.5, DEFAULT_BLUR_PX * sp.gsd_m / 0.004, 30.0)
    assert sp.speed_ms == pytest.approx(expected, rel=1e-9)
    assert any(cam.timing_source in a for a in sp.assumptions)


def test_pilot_distance_reads_in_whole_metres_in_the_cli_and_the_summary(tmp_path) -> None:
    """The CLI summary, summary.html and summary.json give the pilot distance in whole metres,
    the same number everywhere; result.json keeps the measured value."""
    area = tmp_path / "f.geojson"
    area.write_text(json.dumps(rect(10, 10, 70, 70)))
    out = tmp_path / "out"
    r = CliRunner().invoke(
        main, ["plan", "--area", str(area), "--takeoff", f"{LAT0},{LON0}", "--resolution", "0.05",
               "--start", START, "--out", str(out)],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    d = json.loads((out / "result.json").read_text())["distances"]
    assert d["area_pilot_distance_m"] == pytest.approx(80 * math.sqrt(2), rel=1e-3)
    exact = d["pilot_distance_m"]
    assert exact != round(exact)
    texts = [r.stdout, (out / "summary.html").read_text(), (out / "summary.json").read_text()]
    for text in texts:
        shown = re.findall(r"(\d[\d.]*) m from the (?:pilot|farthest point)", text)
        assert shown and set(shown) == {f"{exact:.0f}"}, shown
    for text in texts[:2]:  # the JSON's numbers keep their precision, its sentences do not
        assert f"{exact:.1f}" not in text
    assert f"{exact:.1f}" not in "".join(json.loads(texts[2])["notes"])


@pytest.mark.parametrize(
    ("home_alt", "said"), [(0.0, "altitude 0 m"), (None, "no altitude")], ids=["zero", "null"]
)
def test_a_plan_home_at_0_m_or_without_altitude_is_no_ground(large, tmp_path, home_alt, said) -> None:
    """QGroundControl writes 0 m (or null) for a planned home it could not place on terrain:
    the ground is then assumed, said so in the ground block, the survey and the CLI warning."""
    _res, out = large
    doc = json.loads((out / "flight-01.plan").read_text())
    doc["mission"]["plannedHomePosition"][2] = home_alt
    area = tmp_path / "home.plan"
    area.write_text(json.dumps(doc))
    res = uasnav.plan(area=str(area), resolution=0.05, start=START)
    g = res["ground"]
    assert g["assumed"] and g["elevation_m"] == 0.0
    assert said in g["source"] and "QGroundControl" in g["source"]
    assert any(said in a and "give --ground-elevation" in a for a in res["survey"]["assumptions"])
    r = CliRunner().invoke(
        main,
        ["plan", "--area", str(area), "--resolution", "0.05", "--start", START, "--out", str(tmp_path / "o")],
    )
    assert r.exit_code == 0, r.output
    warning = [x for x in r.stderr.splitlines() if x.startswith("warning: ")]
    assert len(warning) == 1 and said in warning[0], r.stderr
    # a real home altitude is the ground, as before
    doc["mission"]["plannedHomePosition"][2] = 488.9
    area.write_text(json.dumps(doc))
    g = uasnav.plan(area=str(area), resolution=0.05, start=START)["ground"]
    assert g["elevation_m"] == 488.9 and not g["assumed"]


def _with_heights(geom: dict, h) -> dict:
    """``geom`` with a third coordinate on every position: ``h(lon, lat)`` m."""
    ring = [[lon, lat, float(h(lon, lat))] for lon, lat in geom["coordinates"][0]]
    return {"type": "Polygon", "coordinates": [ring]}


def test_geojson_heights_are_ellipsoidal_and_give_the_ground_in_amsl() -> None:
    """RFC 7946 heights are above the WGS-84 ellipsoid: the ground is each height less the EGM96
    geoid height there, and the intents stand on it (h_W84 = H + height + N)."""
    from uasnav.geo.geoid import geoid_height

    field = rect(10, 10, 70, 70)
    amsl = 450.0
    res = uasnav.plan(
        area=_with_heights(field, lambda lon, lat: amsl + geoid_height(lat, lon)),
        takeoff=f"{LAT0},{LON0}",
        resolution=0.05,
        start=START,
    )
    g = res["ground"]
    assert not g["assumed"] and g["elevation_m"] == pytest.approx(amsl, abs=1e-6)
    assert "RFC 7946" in g["source"] and "geoid" in g["source"]
    assert g["spread_m"] == pytest.approx(0.0, abs=1e-6)
    given = uasnav.plan(
        area=field, takeoff=f"{LAT0},{LON0}", resolution=0.05, start=START, ground_elevation=amsl
    )
    za = [(v["altitude_lower"]["value"], v["altitude_upper"]["value"]) for v in _intent_volumes(res)]
    zb = [(v["altitude_lower"]["value"], v["altitude_upper"]["value"]) for v in _intent_volumes(given)]
    assert np.allclose(za, zb, atol=1e-6)
    # the operator's elevation wins over the file's
    assert (
        uasnav.plan(
            area=_with_heights(field, lambda lon, lat: 999.0), takeoff=f"{LAT0},{LON0}", resolution=0.05,
            start=START, ground_elevation=amsl,
        )["ground"]["elevation_m"]
        == amsl
    )  # fmt: skip


def test_geojson_heights_that_cannot_be_the_ground_are_said_why() -> None:
    field = rect(10, 10, 70, 70)
    zeros = uasnav.plan(area=_with_heights(field, lambda lon, lat: 0.0), resolution=0.05, start=START)
    assert zeros["ground"]["assumed"] and "all 0" in zeros["ground"]["source"]
    far = uasnav.plan(
        area=_with_heights(rect(1500, 0, 70, 70), lambda lon, lat: 300.0),
        takeoff=f"{LAT0},{LON0}",
        resolution=0.05,
        start=START,
    )
    assert far["ground"]["assumed"] and "from area" in far["ground"]["source"]
    # a sloping field: its mean is taken, and the flat-field assumption is flagged with the span
    slope = uasnav.plan(
        area=_with_heights(field, lambda lon, lat: 300.0 + (lat - LAT0) * 111e3 * 0.5),
        takeoff=f"{LAT0},{LON0}",
        resolution=0.05,
        start=START,
    )
    assert slope["ground"]["spread_m"] == pytest.approx(35.0, abs=0.5)
    assert any("span 35 m" in a for a in slope["survey"]["assumptions"])


def test_the_large_field_is_flown_by_a_rotorcraft_and_the_fixed_wings_are_said_why(large) -> None:
    """The survey's lines are a rotorcraft pattern (stop and turn one swath away): a fixed wing,
    which turns on a circle of 2·v²/(g·tan 30°) at its cruise speed, is not ranked for it, and
    the answer says which ones and why."""
    from uasnav.mission.feasibility import HOVERING_TYPES

    res, _out = large
    db = res.selection.database.uas
    chosen = db.ids.index(res["configuration"]["uas_id"])
    assert db.types[chosen] in HOVERING_TYPES
    spacing = res["survey"]["line_spacing_m"]
    disco = next(
        r for r in res.selection.rejections if r.item == "parrot-disco" and r.test == "survey-pattern"
    )
    v = 0.7 * 22.0  # the cruise fraction of the Disco's 22 m/s
    assert disco.value == pytest.approx(2 * v**2 / (9.80665 * math.tan(math.radians(30.0))), rel=1e-9)
    assert disco.value > spacing  # 84 m across: wider than the lines are apart
    assert "cannot hover" in disco.message and f"{disco.value:.0f} m across" in disco.message
    note = next(n for n in res["notes"] if n.startswith("survey: "))
    assert "Parrot Disco" in note and "cannot hover" in note
    # rotorcraft are never held back by the pattern
    assert not any(
        r.test == "survey-pattern" and db.types[db.ids.index(r.item)] in HOVERING_TYPES
        for r in res.selection.rejections
        if r.kind == "uas"
    )


def test_the_pilot_distance_covers_the_route_the_plans_fly(large) -> None:
    """The operation's pilot distance is the farthest point the written flights reach (run-ins
    and run-outs past the field included), measured on the .plan files themselves."""
    res, out = large
    farthest = 0.0
    for f in res["flights"]:
        plan = read_plan(out / f"{f['name']}.plan")
        pos = [(it.lat_deg, it.lon_deg) for it in plan.items if it.has_position]
        farthest = max(farthest, float(np.hypot(*_local(*zip(*pos, strict=True)).T).max()))
    d, op = res["distances"], res["operation"]
    assert d["pilot_distance_on"].startswith("the planned route")
    assert d["pilot_distance_m"] == pytest.approx(farthest, abs=0.5)
    assert d["pilot_distance_m"] > d["area_pilot_distance_m"] == pytest.approx(math.hypot(420, 320), abs=1)
    assert op["max_distance_m"] == pytest.approx(d["pilot_distance_m"])
    assert (op["visibility"] == "VLOS") == (op["max_distance_m"] <= op["vlos_distance_m"])
    # the derivation names where the distance was measured, not an option nobody typed
    seen = next(f for f in res.selection.operation.derivation if f.name == "visibility")
    assert seen.requirement.startswith("the planned route's farthest point from the pilot position = ")
    assert "--max-distance" not in seen.requirement
