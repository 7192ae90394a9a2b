"""ED-269 geographical zones: the InterUSS sample hit and missed, schedules, altitude
references, hostile files; and the authorisation summary (HTML and JSON) from the CLI."""

from __future__ import annotations

import copy
import datetime as dt
import json

import pytest
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.errors import DataFormatError, InputError
from uasnav.io.ed269 import parse_zones, read_zones, zones_from_json
from uasnav.mission.zones import check_zones, load_zones, parse_area

UTC = dt.timezone.utc
# A 70 m x 55 m field inside the sample polygon (Geneva) and one 3 km north-east of it.
INSIDE = {
    "type": "Polygon",
    "coordinates": [
        [[6.1680, 46.2160], [6.1689, 46.2160], [6.1689, 46.2165], [6.1680, 46.2165], [6.1680, 46.2160]]
    ],
}
OUTSIDE = {"type": "Feature", "geometry": {"type": "Point", "coordinates": [6.20, 46.235]}}


@pytest.fixture
def sample(shared_data):
    return shared_data / "utm" / "interuss_ed269_geozone_sample.json"


@pytest.fixture
def doc(sample):
    return json.loads(sample.read_text())


def test_sample_zone_hit_inside_missed_outside(sample) -> None:
    zones, where = load_zones(sample)
    assert [z.identifier for z in zones] == ["LSXX"]
    hit = check_zones(zones, parse_area(INSIDE), height_m=50.0, source=where)
    assert [h.identifier for h in hit.hits] == ["LSXX"]
    h = hit.hits[0]
    assert h.restriction == "REQ_AUTHORISATION" and h.message == "MSG01" and h.certain
    assert "authorisation" in h.requires
    miss = check_zones(zones, parse_area(OUTSIDE, buffer_m=300.0), height_m=50.0)
    assert miss.hits == () and miss.n_zones == 1
    # a buffer that reaches the zone (about 2.3 km away) makes it a hit
    assert check_zones(zones, parse_area(OUTSIDE, buffer_m=3000.0), height_m=50.0).hits


def test_scheduled_copy_is_hit_only_inside_its_schedule(doc) -> None:
    d = copy.deepcopy(doc)
    d["UASZoneList"][0]["applicability"] = [
        {
            "permanent": "NO",
            "startDateTime": "2026-05-01T00:00:00Z",
            "endDateTime": "2026-05-31T23:59:59Z",
            "dailyPeriod": [{"day": ["MON", "TUE"], "startTime": "08:00:00Z", "endTime": "12:00:00Z"}],
        }
    ]
    zones = zones_from_json(d)
    area = parse_area(INSIDE)

    def hit(t):
        return bool(check_zones(zones, area, height_m=50.0, when=t).hits)

    assert hit(dt.datetime(2026, 5, 4, 10, 0, tzinfo=UTC))  # Monday 10:00
    assert hit(dt.datetime(2026, 5, 5, 8, 0, tzinfo=UTC))  # Tuesday, on the start time
    assert not hit(dt.datetime(2026, 5, 4, 12, 0, 1, tzinfo=UTC))  # Monday just after the end
    assert not hit(dt.datetime(2026, 5, 6, 10, 0, tzinfo=UTC))  # Wednesday
    assert not hit(dt.datetime(2026, 6, 1, 10, 0, tzinfo=UTC))  # Monday after endDateTime
    assert hit(dt.datetime(2026, 5, 4, 12, 30, tzinfo=dt.timezone(dt.timedelta(hours=2))))  # 10:30 UTC
    # no flight time: a scheduled zone counts as hit, and says why
    (h,) = check_zones(zones, area, height_m=50.0).hits
    assert not h.certain and any("schedule" in w for w in h.why)


def test_altitude_limits_and_references(doc) -> None:
    area = parse_area(INSIDE)

    def with_limits(lo, lo_ref, hi, hi_ref, unit="M"):
        d = copy.deepcopy(doc)
        g = d["UASZoneList"][0]["geometry"][0]
        g.update(
            lowerLimit=lo,
            lowerVerticalReference=lo_ref,
            upperLimit=hi,
            upperVerticalReference=hi_ref,
            uomDimensions=unit,
        )
        return zones_from_json(d)

    above = with_limits(120, "AGL", 300, "AGL")
    assert not check_zones(above, area, height_m=120.0).hits  # touching the floor is not entering
    assert check_zones(above, area, height_m=120.5).hits
    assert check_zones(with_limits(300, "AGL", 1000, "AGL", "FT"), area, height_m=100.0).hits  # 91.4 m
    assert not check_zones(with_limits(400, "AGL", 1000, "AGL", "FT"), area, height_m=100.0).hits
    amsl = with_limits(600, "AMSL", 2000, "AMSL")
    (h,) = check_zones(amsl, area, height_m=50.0).hits  # no ground elevation: counted, with reason
    assert not h.certain and any("ground-elevation" in w for w in h.why)
    assert not check_zones(amsl, area, height_m=50.0, ground_elevation_m=400.0).hits  # 400-450 m AMSL
    assert check_zones(amsl, area, height_m=50.0, ground_elevation_m=560.0).hits[0].certain


CIRCLE = {"type": "Circle", "center": [0, 0], "radius": 5}


def _zone(hp=None, geometry=None, **zone) -> str:
    """One-zone ED-269 text with the given overrides (a valid circle zone by default)."""
    g = {"horizontalProjection": hp or CIRCLE, **(geometry or {})}
    z = {"identifier": "A", "restriction": "PROHIBITED", "geometry": [g], **zone}
    return json.dumps({"UASZoneList": [z]})


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("[]", "expected an object"),
        ('{"UASZoneList": {}}', "expected an array"),
        (_zone(restriction="MAYBE"), "restriction"),
        (
            _zone({"type": "Polygon", "coordinates": [[[0, 0], [1, 0], [1, 1], [0, 1]]]}),
            "last equal to the first",
        ),
        (_zone({"type": "Polygon", "coordinates": [[[0, 0], [1, 0], [1, 100], [0, 0]]]}), "WGS84"),
        (_zone(geometry={"lowerLimit": "NaN"}), "finite"),
        (_zone(geometry={"uomDimensions": "FURLONG"}), "uomDimensions"),
        (_zone(applicability=[{"permanent": "NO"}]), "no schedule"),
        (_zone(applicability=[{"permanent": "NO", "startDateTime": "2026-01-01T00:00:00"}]), "time zone"),
        (_zone(applicability=[{"permanent": "NO", "dailyPeriod": [{"day": ["FUNDAY"]}]}]), "day"),
        (_zone({"type": "Circle", "center": [0, 0], "radius": -5}), "radius"),
        (_zone({"type": "Polygon", "coordinates": [[[0, 0], [1, 0], [1, 1]]]}), "at least 4"),
        ("[" * 100000 + "]" * 100000, "nested"),
        ('{"UASZoneList": [1e999]}', "finite|expected an object"),
        ("\ufeff{not json", "not valid JSON"),
    ],
)
def test_hostile_zone_files_are_refused(tmp_path, text, match) -> None:
    p = tmp_path / "zones.json"
    p.write_text(text)
    with pytest.raises(DataFormatError, match=match) as e:
        read_zones(p)
    assert e.value.path == str(p)


def test_zone_file_size_and_binary_are_refused(tmp_path) -> None:
    with pytest.raises(DataFormatError, match="UTF-8"):
        parse_zones(b"\xff\xfe\x00garbage", "bin")
    with pytest.raises(DataFormatError, match="larger"):
        parse_zones(b" " * 101, "big", max_bytes=100)
    with pytest.raises(InputError, match="directory"):
        load_zones(tmp_path)


def test_self_intersecting_zone_polygon_is_refused(doc) -> None:
    d = copy.deepcopy(doc)
    ring = [[6.166, 46.212], [6.171, 46.218], [6.171, 46.212], [6.166, 46.218], [6.166, 46.212]]
    d["UASZoneList"][0]["geometry"][0]["horizontalProjection"]["coordinates"] = [ring]
    with pytest.raises(DataFormatError, match="not valid"):
        check_zones(zones_from_json(d), parse_area(INSIDE), height_m=50.0)


def test_summary_from_the_cli(tmp_path, sample) -> None:
    area = tmp_path / "field.geojson"
    area.write_text(json.dumps(INSIDE))
    base = [
        "select",
        "--range",
        "1500",
        "--max-distance",
        "1500",
        "--area",
        str(area),
        "--zones",
        str(sample),
        "--population-density",
        "40",
    ]
    html_out, json_out = tmp_path / "s.html", tmp_path / "s.json"
    res = CliRunner().invoke(main, [*base, "--summary", str(html_out)])
    assert res.exit_code == 0, res.output
    page = html_out.read_text()
    assert "@media print" in page and "SORA 2.5" in page and "LSXX" in page and "REQ_AUTHORISATION" in page
    assert "BLOS C2 data link" in page and "Art. 5" in page
    res = CliRunner().invoke(main, [*base, "--summary", str(json_out)])
    assert res.exit_code == 0, res.output
    s = json.loads(json_out.read_text())
    assert s["category"]["category"] == "specific" and s["sora"]["edition"] == "2.5"
    assert [h["identifier"] for h in s["zones"]["hits"]] == ["LSXX"]
    assert s["chosen"]["uas"] and any(x["state"] == "present" for x in s["equipment"]["on_chosen_uas"])
    # the zone file is an input: the summary may not overwrite it
    res = CliRunner().invoke(main, [*base, "--summary", str(sample)])
    assert res.exit_code != 0 and sample.read_text().startswith("{")
    # a hostile zone file is a usage error naming the option, and nothing is written
    bad = tmp_path / "bad.json"
    bad.write_text('{"UASZoneList": [{"identifier": "A", "restriction": "NOPE", "geometry": []}]}')
    out = tmp_path / "never.html"
    res = CliRunner().invoke(main, [*base[:-4], "--zones", str(bad), "--summary", str(out)])
    assert res.exit_code == 2 and "--zones" in res.stderr and not out.exists()


def test_api_takes_uploaded_documents(sample) -> None:
    from uasnav.mission.request import Upload, run_select

    sel = run_select(
        {"range": 300, "area": json.dumps(INSIDE).encode(), "zones": Upload("z.json", sample.read_bytes())}
    )
    assert sel.operation.category == "open" and [h.identifier for h in sel.zones.hits] == ["LSXX"]
    assert sel.to_dict()["zones"]["source"] == "z.json"


def test_zones_by_url_are_checked_before_caching(sample, tmp_path) -> None:
    import http.server
    import threading

    bodies = {"/good.json": sample.read_bytes(), "/bad.json": _zone(restriction="MAYBE").encode()}

    class Handler(http.server.BaseHTTPRequestHandler):
        def log_message(self, *args) -> None:
            pass

        def do_GET(self) -> None:
            body = bodies.get(self.path)
            self.send_response(200 if body else 404)
            self.send_header("Content-Length", str(len(body or b"")))
            self.end_headers()
            self.wfile.write(body or b"")

    srv = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    threading.Thread(target=srv.serve_forever, daemon=True).start()
    try:
        base = f"http://127.0.0.1:{srv.server_address[1]}"
        zones, where = load_zones(base + "/good.json", cache_dir=tmp_path, timeout_s=5.0)
        assert [z.identifier for z in zones] == ["LSXX"] and where.endswith("good.json")
        cached = set(tmp_path.iterdir())
        with pytest.raises(DataFormatError, match="restriction"):
            load_zones(base + "/bad.json", cache_dir=tmp_path, timeout_s=5.0)
        assert set(tmp_path.iterdir()) == cached  # a refused document is never cached
    finally:
        srv.shutdown()
        srv.server_close()


@pytest.mark.parametrize("reader", ["geojson", "kml", "plan"])
def test_area_bytes_are_bounded_utf8_text_for_every_reader(reader) -> None:
    """GeoJSON, KML and plan areas read their bytes the same way: UTF-8 (a BOM dropped), at
    most the reader's size, else one error naming the file."""
    from uasnav.io.ed269 import MAX_BYTES
    from uasnav.io.plan_formats.source import MAX_PLAN_BYTES
    from uasnav.mission.zones import kml_area_geojson, parse_area_document

    where, limit, read = {
        "geojson": ("a.geojson", MAX_BYTES, lambda d, w: parse_area(d, w)),
        "kml": ("a.kml", MAX_BYTES, kml_area_geojson),
        "plan": ("a.plan", MAX_PLAN_BYTES, lambda d, w: parse_area_document(d, w, buffer_m=10.0)),
    }[reader]
    with pytest.raises(DataFormatError, match=rf"^{where}: not a UTF-8 text file"):
        read(b"\xff\xfe{", where)
    with pytest.raises(DataFormatError, match=rf"^{where}: .* larger than {limit} bytes"):
        read(b" " * (limit + 1), where)
    good = {
        "geojson": json.dumps(INSIDE),
        "kml": "<kml xmlns='http://www.opengis.net/kml/2.2'><Placemark><Polygon><outerBoundaryIs>"
        "<LinearRing><coordinates>6.168,46.216 6.1689,46.216 6.1689,46.2165 6.168,46.216</coordinates>"
        "</LinearRing></outerBoundaryIs></Polygon></Placemark></kml>",
        "plan": json.dumps(_qgc_plan([46.216, 6.168, 400], [(46.2162, 6.1685), (46.2162, 6.1688)])),
    }[reader]  # fmt: skip
    assert read("\ufeff".encode() + good.encode(), where)  # a BOM is dropped


def _qgc_plan(home: list, points: list[tuple[float, float]], alt_m: float = 30.0) -> dict:
    """A QGroundControl plan: ``home`` [lat, lon, alt AMSL], waypoints at ``alt_m`` above home."""
    items = [
        {"type": "SimpleItem", "command": 16, "frame": 3, "autoContinue": True, "doJumpId": k + 1,
         "params": [0, 0, 0, None, lat, lon, alt_m]}
        for k, (lat, lon) in enumerate(points)
    ]  # fmt: skip
    mission = {"version": 2, "firmwareType": 12, "vehicleType": 2, "cruiseSpeed": 15, "hoverSpeed": 5}
    return {
        "fileType": "Plan",
        "version": 1,
        "groundStation": "QGroundControl",
        "geoFence": {"circles": [], "polygons": [], "version": 2},
        "rallyPoints": {"points": [], "version": 2},
        "mission": {**mission, "plannedHomePosition": home, "items": items},
    }
