"""Issue 18, part two follow-up: zone schedules over the whole flight window, a PROHIBITED zone
makes the operation not authorisable, REQ_AUTHORISATION/CONDITIONAL zones are requirements, the
area may be a mission plan (its route buffered), the residual-ARC claim, and the PDRA scopes."""

from __future__ import annotations

import copy
import datetime as dt
import itertools
import json

import pytest
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.io.ed269 import Applicability, DailyPeriod, zones_from_json
from uasnav.io.plans import read_plan, write_plan
from uasnav.mission import Requirements
from uasnav.mission.operation import PDRA_SOURCES, derive_operation, eu_scenarios
from uasnav.mission.request import SELECT_OPTIONS, OptionError, parse_select_options, run_select
from uasnav.mission.zones import check_zones, is_plan_document, parse_area, parse_area_document

UTC = dt.UTC
# A field inside the InterUSS sample zone (Geneva) — as in test_mission_zones.
INSIDE = {
    "type": "Polygon",
    "coordinates": [
        [[6.1680, 46.2160], [6.1689, 46.2160], [6.1689, 46.2165], [6.1680, 46.2165], [6.1680, 46.2160]]
    ],
}


@pytest.fixture
def doc(shared_data):
    return json.loads((shared_data / "utm" / "interuss_ed269_geozone_sample.json").read_text())


def _variant(doc, **zone) -> dict:
    d = copy.deepcopy(doc)
    d["UASZoneList"][0].update(zone)
    return d


def _wpl(points, alt=50.0) -> str:
    """A Mission Planner QGC WPL 110 file: home then one waypoint per (lat, lon)."""
    rows = ["QGC WPL 110"]
    for i, (lat, lon) in enumerate([points[0], *points]):
        rows.append(f"{i}\t{int(i == 0)}\t{0 if i == 0 else 3}\t16\t0\t0\t0\t0\t{lat}\t{lon}\t{alt}\t1")
    return "\n".join(rows) + "\n"


# --- schedules over the flight window -------------------------------------------------------


def _brute(a: Applicability, t0: dt.datetime, t1: dt.datetime) -> bool:
    t = t0
    while t <= t1:
        if a.active(t):
            return True
        t += dt.timedelta(seconds=1)
    return a.active(t1)


SCHEDULES = [
    Applicability(False, None, None, (DailyPeriod(("MON",), dt.time(10, 0), dt.time(10, 20)),)),
    Applicability(False, None, None, (DailyPeriod(("ANY",), dt.time(23, 50), dt.time(0, 10)),)),
    Applicability(
        False,
        dt.datetime(2026, 5, 4, 9, 55, tzinfo=UTC),
        dt.datetime(2026, 5, 4, 10, 5, tzinfo=UTC),
        (),
    ),
    Applicability(False, None, None, (DailyPeriod(("TUE",), None, dt.time(0, 5)),)),
]
WINDOWS = [
    (dt.datetime(2026, 5, 4, 9, 30, tzinfo=UTC), 1799),  # Monday, ends just before 10:00
    (dt.datetime(2026, 5, 4, 9, 30, tzinfo=UTC), 1800),  # ... on 10:00
    (dt.datetime(2026, 5, 4, 10, 20, 1, tzinfo=UTC), 3600),  # after Monday's window
    (dt.datetime(2026, 5, 4, 23, 0, tzinfo=UTC), 2999),  # to 23:49:59
    (dt.datetime(2026, 5, 4, 23, 58, tzinfo=UTC), 600),  # over midnight into Tuesday
    (dt.datetime(2026, 5, 5, 0, 5, 1, tzinfo=UTC), 1200),
    (dt.datetime(2026, 5, 3, 23, 0, tzinfo=UTC), 7200),  # Sunday into Monday
]


@pytest.mark.parametrize(("k", "w"), list(itertools.product(range(len(SCHEDULES)), range(len(WINDOWS)))))
def test_active_during_is_exact(k, w) -> None:
    """The interval test against a second-by-second scan of the window (every bound in the
    schedules is on a whole second, so the scan is exact)."""
    a = SCHEDULES[k]
    t0, secs = WINDOWS[w]
    t1 = t0 + dt.timedelta(seconds=secs)
    assert a.active_during(t0, t1) == _brute(a, t0, t1)


def test_a_schedule_starting_after_take_off_is_hit(doc) -> None:
    d = _variant(
        doc,
        applicability=[
            {
                "permanent": "NO",
                "dailyPeriod": [{"day": ["MON"], "startTime": "10:00:00Z", "endTime": "12:00:00Z"}],
            }
        ],
    )
    zones, area = zones_from_json(d), parse_area(INSIDE)
    off = dt.datetime(2026, 5, 4, 9, 50, tzinfo=UTC)
    assert not check_zones(zones, area, height_m=50.0, when=off).hits  # at take-off: not yet
    assert not check_zones(zones, area, height_m=50.0, when=off, until=off + dt.timedelta(seconds=599)).hits
    (h,) = check_zones(zones, area, height_m=50.0, when=off, until=off + dt.timedelta(seconds=600)).hits
    assert any("flight window" in w for w in h.why)
    # through the selector: the default window is the chosen UAS's mission time estimate
    base = {
        "range": 1500,
        "max_distance": 1500,
        "area": INSIDE,
        "zones": d,
        "flight_time": "2026-05-04T09:50Z",
    }
    sel = run_select({**base, "flight_duration": 599})
    assert sel.zones is not None and not sel.zones.hits and sel.flight_window["from"] == "--flight-duration"
    # the default window: the survey of the area (about 150 s for this field), not the range's
    # out-and-back estimate
    sel = run_select({**base, "flight_time": "2026-05-04T09:58Z"})
    assert sel.flight_window is not None and "survey of the area" in sel.flight_window["from"]
    assert sel.flight_window["duration_s"] > 120 and [x.identifier for x in sel.zones.hits] == ["LSXX"]
    early = run_select({**base, "flight_time": "2026-05-04T09:56Z"})
    assert early.flight_window["duration_s"] < 240 and not early.zones.hits
    with pytest.raises(ValueError, match="before"):
        SCHEDULES[0].active_during(off, off - dt.timedelta(seconds=1))


# --- verdict: PROHIBITED, REQ_AUTHORISATION, CONDITIONAL -------------------------------------


def test_prohibited_zone_makes_the_operation_not_authorisable(doc, tmp_path) -> None:
    zfile = tmp_path / "prohibited.json"
    zfile.write_text(json.dumps(_variant(doc, restriction="PROHIBITED", message="military area")))
    afile = tmp_path / "field.geojson"
    afile.write_text(json.dumps(INSIDE))
    base = ["select", "--range", "1500", "--area", str(afile), "--zones", str(zfile)]
    res = CliRunner().invoke(main, [*base, "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    assert out["ranking"] == [] and out["withheld_ranking"], "nothing flyable is presented"
    # no operation points at a rank of the (empty) ranking
    assert out["operations"] and all(o["rank"] is None for o in out["operations"])
    auth = out["authorisation"]
    assert auth["authorisable"] is False and auth["verdict"].startswith("not authorisable")
    assert "PROHIBITED zone LSXX" in auth["verdict"] and "military area" in auth["verdict"]
    assert any(r["test"] == "zone-prohibited" for r in out["rejections"])
    assert out["chosen_equipment"] == []
    text = CliRunner().invoke(main, base)
    assert "Verdict: not authorisable" in text.output and "Withheld" in text.output
    html = tmp_path / "s.html"
    assert CliRunner().invoke(main, [*base, "--summary", str(html)]).exit_code == 0
    page = html.read_text()
    assert "not authorisable" in page and "exemption from the zone authority" in page
    js = tmp_path / "s.json"
    assert CliRunner().invoke(main, [*base, "--summary", str(js)]).exit_code == 0
    s = json.loads(js.read_text())
    assert s["authorisation"]["authorisable"] is False and s["chosen"] is None and s["withheld"]


@pytest.mark.parametrize(
    ("restriction", "word"), [("REQ_AUTHORISATION", "authorisation"), ("CONDITIONAL", "conditions")]
)
def test_zone_requirements_are_listed(doc, restriction, word) -> None:
    # the pilot 1500 m away: BVLOS, the specific category
    sel = run_select(
        {"range": 1500, "max_distance": 1500, "area": INSIDE, "zones": _variant(doc, restriction=restriction)}
    )
    auth = sel.authorisation
    assert auth["authorisable"] and sel.ranking
    zone_needs = [n for n in auth["requirements"] if n.startswith("zone LSXX")]
    assert len(zone_needs) == 1 and restriction in zone_needs[0] and word in zone_needs[0]
    assert any("Art. 12" in n and "SAIL" in n for n in auth["requirements"])  # specific: SORA SAIL


def test_open_category_needs_no_authorisation() -> None:
    auth = run_select({"range": 300}).authorisation
    assert auth["authorisable"] and auth["verdict"] == "no authorisation needed (open category)"


# --- the area as a mission plan ---------------------------------------------------------------


def test_plan_file_footprint_is_its_route_buffered(doc, tmp_path) -> None:
    zfile = tmp_path / "z.json"
    zfile.write_text(json.dumps(doc))
    inside = tmp_path / "in.waypoints"
    inside.write_text(_wpl([(46.2160, 6.1680), (46.2165, 6.1689)]))
    far = tmp_path / "far.waypoints"
    far.write_text(_wpl([(46.235, 6.20), (46.236, 6.201)]))  # about 2.3 km from the zone

    def hits(*extra):
        res = CliRunner().invoke(main, ["select", "--range", "1500", "--zones", str(zfile), "--json", *extra])
        assert res.exit_code == 0, res.output
        return [h["identifier"] for h in json.loads(res.output)["zones"]["hits"]]

    assert hits("--area", str(inside)) == ["LSXX"]
    assert hits("--area", str(far)) == []  # default buffer: the 50 m flight height (1:1 rule)
    assert hits("--area", str(far), "--area-buffer", "3000") == ["LSXX"]
    # the buffer is the user's when given; by default the flight height (here the plan's 80 m,
    # above --altitude 50); a route has no footprint without one: an explicit 0 is refused, not
    # silently replaced
    high = _wpl([(46.2160, 6.1680), (46.2165, 6.1689)], alt=80.0)
    for given, want in ((None, 80.0), (25.0, 25.0)):
        got = parse_select_options({"range": 1500, "area": high, "area_buffer": given}).area
        assert got is not None and got.buffer_m == want, (given, got.buffer_m)
    with pytest.raises(OptionError, match=r"buffer 0\.0 m") as e:
        parse_select_options({"range": 1500, "area": high, "area_buffer": 0.0})
    assert e.value.option == "area"
    # the same route as a QGroundControl .plan, by extension and by content (an upload)
    qgc = tmp_path / "in.plan"
    write_plan(read_plan(inside), qgc)
    assert hits("--area", str(qgc)) == ["LSXX"]
    content = json.loads(qgc.read_text())
    assert is_plan_document("upload", content) and not is_plan_document("a.geojson", INSIDE)
    area = parse_area_document(content, "upload", buffer_m=10.0)
    assert area.buffer_m == 10.0 and area.parts[0][0] == "line"
    # a plan in local north/east cannot be placed on the map: a usage error naming --area
    ne = tmp_path / "local.csv"
    ne.write_text("north,east\n0,0\n100,0\n")
    res = CliRunner().invoke(main, ["select", "--zones", str(zfile), "--area", str(ne)])
    assert res.exit_code == 2 and "--area" in res.stderr and "geographic origin" in res.stderr


# --- strategic air-risk mitigation (residual ARC) --------------------------------------------


def test_residual_arc_option() -> None:
    names = {o.name for o in SELECT_OPTIONS}
    assert {"residual_arc", "flight_duration"} <= names
    base = {"range": 1500, "mitigations": "M1A=low"}
    plain = run_select(base).sora
    assert plain is not None and (plain.final_grc, plain.residual_arc, plain.sail) == (2, "b", "II")
    claimed = run_select({**base, "residual_arc": "a"}).sora
    assert claimed is not None and (claimed.residual_arc, claimed.sail) == ("a", "I")
    assert "Annex C" in claimed.residual_arc_rule  # BVLOS: a claim to substantiate
    assert parse_select_options({"residual_arc": "c"}).requirements.residual_arc == "c"
    res = CliRunner().invoke(main, ["select", "--range", "1500", "--residual-arc", "c"])
    assert res.exit_code == 1 and "only lower" in res.output + res.stderr
    res = CliRunner().invoke(main, ["select", "--residual-arc", "e"])
    assert res.exit_code == 2


# --- PDRA scopes --------------------------------------------------------------------------------


def _checks(req: Requirements, *, dim=0.9, mtom=6300.0, speed=23.0) -> dict:
    op = derive_operation(req)
    return {c.id: c for c in eu_scenarios(op, eu_class=None, mtom_g=mtom, dimension_m=dim, speed_ms=speed)}


def test_pdra_scopes() -> None:
    vlos = _checks(Requirements(range_m=300.0))
    assert vlos["PDRA-S01"].applies and not vlos["PDRA-S02"].applies and not vlos["PDRA-G02"].applies
    assert not _checks(Requirements(range_m=300.0), dim=3.5)["PDRA-S01"].applies
    assert not _checks(Requirements(range_m=300.0, airspace="airport-bcd"))["PDRA-S01"].applies
    sparse = Requirements(range_m=900.0, population_density=100.0)
    c = _checks(sparse)
    assert c["PDRA-S02"].applies and c["PDRA-G01"].applies and not c["PDRA-S01"].applies
    assert not c["PDRA-G02"].applies and any("ARC-a" in r for r in c["PDRA-G02"].reasons)
    assert not _checks(Requirements(range_m=1500.0, population_density=100.0))["PDRA-S02"].applies
    assert _checks(Requirements(range_m=1500.0, population_density=100.0, observers=2))["PDRA-S02"].applies
    assert not _checks(sparse, mtom=26000.0)["PDRA-S02"].applies
    assert not _checks(Requirements(range_m=900.0, population_density=600.0))["PDRA-S02"].applies
    g02 = _checks(Requirements(range_m=900.0, population_density=100.0, airspace="atypical"))["PDRA-G02"]
    assert g02.applies
    atyp = Requirements(range_m=900.0, population_density=100.0, airspace="atypical")
    heavy = _checks(atyp, mtom=26000.0, speed=60.0)["PDRA-G02"]  # 46.8 kJ > 34 kJ
    assert not heavy.applies and any("kJ" in r for r in heavy.reasons)
    g03 = _checks(Requirements(range_m=900.0, population_density=100.0, altitude_m=25.0))["PDRA-G03"]
    assert g03.applies and "NOT REACHED" in g03.source
    assert not _checks(sparse)["PDRA-G03"].applies  # 50 m is above its 30 m
    for k in ("PDRA-S01", "PDRA-S02", "PDRA-G02"):
        assert "Article 11" in PDRA_SOURCES[k] and "ED Decision" in PDRA_SOURCES[k]


# Every numeric scope limit of the STS/PDRA table at its boundary: (scenario, requirements,
# UA (dimension m, MTOM g, speed m/s)) just inside, then just outside the limit. A VLOS flight
# is one within --vlos-distance; BVLOS beyond it.
_BV = dict(vlos_distance_m=100.0, population_density=100.0)
_UA = (0.9, 6300.0, 23.0)
_KE_EDGE = (0.9, 2000.0, (2 * 34e3 / 2.0) ** 0.5)  # exactly 34 kJ
SCOPE_EDGES = [
    ("STS-02", dict(range_m=1000.0, **_BV), dict(range_m=1000.1, **_BV), "C6"),
    ("STS-02", dict(range_m=2000.0, observers=1, **_BV), dict(range_m=2000.1, observers=1, **_BV), "C6"),
    (
        "STS-02",
        dict(range_m=900.0, altitude_m=120.0, **_BV),
        dict(range_m=900.0, altitude_m=120.1, **_BV),
        "C6",
    ),
    ("STS-01", dict(range_m=50.0, altitude_m=120.0), dict(range_m=50.0, altitude_m=120.1), "C5"),
    ("PDRA-S02", dict(range_m=1000.0, **_BV), dict(range_m=1000.1, **_BV), None),
    (
        "PDRA-S02",
        dict(range_m=900.0, altitude_m=149.9, **_BV),
        dict(range_m=900.0, altitude_m=150.0, **_BV),
        None,
    ),
    ("PDRA-S01", dict(range_m=50.0, altitude_m=149.9), dict(range_m=50.0, altitude_m=150.0), None),
    (
        "PDRA-G01",
        dict(range_m=900.0, altitude_m=149.9, **_BV),
        dict(range_m=900.0, altitude_m=150.0, **_BV),
        None,
    ),
    (
        "PDRA-G03",
        dict(range_m=900.0, altitude_m=30.0, **_BV),
        dict(range_m=900.0, altitude_m=30.01, **_BV),
        None,
    ),
]


@pytest.mark.parametrize(("sid", "inside", "outside", "cls"), SCOPE_EDGES)
def test_scenario_scope_limits_at_their_boundary(sid, inside, outside, cls) -> None:
    def applies(req_kw: dict, ua=_UA) -> bool:
        op = derive_operation(Requirements(**req_kw))
        dim, m, v = ua
        return next(
            x for x in eu_scenarios(op, eu_class=cls, mtom_g=m, dimension_m=dim, speed_ms=v) if x.id == sid
        ).applies

    assert applies(inside) and not applies(outside)


@pytest.mark.parametrize("sid", ["PDRA-G01", "PDRA-G02", "PDRA-G03", "PDRA-S01", "PDRA-S02"])
def test_ua_limits_of_the_pdras_at_their_boundary(sid) -> None:
    kw = dict(range_m=900.0, altitude_m=25.0, **_BV)
    if sid == "PDRA-S01":
        kw = dict(range_m=50.0, altitude_m=25.0)
    if sid == "PDRA-G02":
        kw["airspace"] = "atypical"
    op = derive_operation(Requirements(**kw))

    def applies(dim: float, m: float, v: float) -> bool:
        return next(
            x for x in eu_scenarios(op, eu_class=None, mtom_g=m, dimension_m=dim, speed_ms=v) if x.id == sid
        ).applies

    assert applies(3.0, 2000.0, 10.0) and not applies(3.01, 2000.0, 10.0)  # 3 m dimension
    if sid in ("PDRA-G01", "PDRA-G02", "PDRA-G03"):  # 34 kJ typical kinetic energy
        dim, m, v = _KE_EDGE
        assert applies(dim, m, v) and not applies(dim, m, v * 1.0001)
    if sid == "PDRA-S02":  # 25 kg MTOM
        assert applies(1.0, 25e3, 5.0) and not applies(1.0, 25e3 + 1.0, 5.0)
