"""Mission-plan readers and writers (uasnav.io.plans) on the real plans in ../shared/data/missions."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pymap3d
import pytest

from uasnav.errors import DataFormatError, InputError, ResourceLimitError
from uasnav.io.plans import (
    AltitudeFrame,
    ItemKind,
    MissionItem,
    MissionPlan,
    flight_sequence,
    plan_cruise_speed,
    plan_route,
    read_plan,
    read_plan_route,
    write_plan,
)

M = "missions"
READABLE = [
    "ardupilot_autotest_dalby_obc2016.waypoints",
    "mavsdk_mission_planner_sample.waypoints",
    "mavsdk_python_example_mission.plan",
    "mavsdk_qgroundcontrol_sample.plan",
    "mavsdk_qgroundcontrol_sample_with_survey.plan",
    "qgc_unittest_missionplanner.waypoints",
]


def _same(a: MissionPlan, b: MissionPlan) -> None:
    assert len(a.items) == len(b.items)
    for x, y in zip(a.items, b.items, strict=True):
        assert (x.command, x.frame, x.autocontinue) == (y.command, y.frame, y.autocontinue)
        np.testing.assert_array_equal(
            [*x.params, x.lat_deg, x.lon_deg, x.alt_m], [*y.params, y.lat_deg, y.lon_deg, y.alt_m]
        )
    assert a.home == b.home or (
        a.home is not None
        and b.home is not None
        and math.isnan(a.home.alt_amsl_m)
        and math.isnan(b.home.alt_amsl_m)
    )


def test_every_shared_plan_is_read_or_refused_clearly(shared_data):
    files = sorted(p.name for p in (shared_data / M).iterdir())
    assert set(READABLE) < set(files)
    for name in files:
        if name in READABLE:
            plan = read_plan(shared_data / M / name)
            route, origin = plan_route(plan)
            assert route.shape[1] == 2 and route.shape[0] >= 2 and origin is not None
        else:  # the structure scan holds no flight path: a clear refusal, naming the JSON path
            with pytest.raises(
                DataFormatError, match=r"structured_scan\.plan: mission\.items\[1\]: complex item"
            ):
                read_plan(shared_data / M / name)


def test_qgc_plan_fields(shared_data):
    plan = read_plan(shared_data / M / "mavsdk_qgroundcontrol_sample.plan")
    kinds = [it.kind for it in plan.items]
    assert kinds == [
        ItemKind.TAKEOFF,
        ItemKind.WAYPOINT,
        ItemKind.OTHER,
        ItemKind.WAYPOINT,
        ItemKind.WAYPOINT,
        ItemKind.RETURN,
    ]
    assert plan.items[0].altitude_frame is AltitudeFrame.RELATIVE and plan.items[0].alt_m == 50
    assert plan.items[2].altitude_frame is AltitudeFrame.NONE and not plan.items[2].has_position
    assert plan.home is not None and plan.home.alt_amsl_m == pytest.approx(488.931, abs=1e-3)
    assert (plan.cruise_speed_ms, plan.hover_speed_ms, plan.vehicle_type) == (15, 5, 2)
    assert plan_cruise_speed(plan) == 5  # a quadrotor flies the hover speed
    # null params are "not set" (NaN), not 0
    assert math.isnan(plan.items[1].params[3])
    route, origin = plan_route(plan)
    # take-off (at home) → 3 waypoints → RTL back to home: 5 points, first == last
    assert route.shape == (5, 2)
    np.testing.assert_allclose(route[0], route[-1], atol=1e-6)
    # independent check of one leg against pymap3d from the file's own numbers
    raw = json.loads((shared_data / M / "mavsdk_qgroundcontrol_sample.plan").read_text())["mission"]["items"]
    n, e, _ = pymap3d.geodetic2ned(raw[1]["params"][4], raw[1]["params"][5], 50, *origin)
    np.testing.assert_allclose(route[1], [n, e], atol=1e-6)


def test_survey_items_are_inlined(shared_data):
    plan = read_plan(shared_data / M / "mavsdk_qgroundcontrol_sample_with_survey.plan")
    raw = json.loads((shared_data / M / "mavsdk_qgroundcontrol_sample_with_survey.plan").read_text())
    n_sub = len(raw["mission"]["items"][1]["TransectStyleComplexItem"]["Items"])
    assert len(plan.items) == len(raw["mission"]["items"]) - 1 + n_sub


def test_wpl_home_and_frames(shared_data):
    plan = read_plan(shared_data / M / "qgc_unittest_missionplanner.waypoints")
    assert plan.home is not None and plan.home.alt_amsl_m == pytest.approx(5.21)
    assert len(plan.items) == 5 and all(it.altitude_frame is AltitudeFrame.RELATIVE for it in plan.items)
    px4 = read_plan(shared_data / M / "mavsdk_mission_planner_sample.waypoints")
    # line 0 is a take-off, not a home position
    assert px4.home is None and px4.items[0].kind is ItemKind.TAKEOFF
    assert px4.items[-1].kind is ItemKind.RETURN


def test_do_jump_is_expanded(shared_data):
    plan = read_plan(shared_data / M / "ardupilot_autotest_dalby_obc2016.waypoints")
    jump = next(i for i, it in enumerate(plan.items) if it.kind is ItemKind.JUMP)
    target, repeat = int(plan.items[jump].params[0]), int(plan.items[jump].params[1])
    seq = flight_sequence(plan)
    t = next(i for i, it in enumerate(plan.items) if it.jump_id == target)
    loop = list(range(t, jump))
    # the loop body is flown 1 + repeat times, then the mission goes on past the jump
    assert seq[:jump] == list(range(jump))
    assert seq[jump : jump + repeat * len(loop)] == loop * repeat
    assert seq[jump + repeat * len(loop)] == jump + 1
    speeds = [it.speed_ms for it in plan.items if it.kind is ItemKind.SPEED]
    assert speeds and all(s is not None and s > 0 for s in speeds)


@pytest.mark.parametrize("name", READABLE)
@pytest.mark.parametrize("ext", [".plan", ".waypoints"])
def test_round_trip(shared_data, tmp_path, name, ext):
    plan = read_plan(shared_data / M / name)
    out = tmp_path / f"copy{ext}"
    write_plan(plan, out)
    back = read_plan(out)
    if ext == Path(name).suffix:
        _same(plan, back)
    # across formats the flown route is the same
    np.testing.assert_allclose(plan_route(back)[0], plan_route(plan)[0], atol=1e-6)
    if ext == ".plan":  # .waypoints files carry no default speeds
        assert plan_cruise_speed(back) == plan_cruise_speed(plan)


def test_csv_plan_round_trip_and_options(tmp_path):
    src = tmp_path / "p.csv"
    src.write_text(
        "# a comment\nlat,lon,alt,frame,command,hold_s,speed_ms\n"
        "47.0,8.0,0,relative,takeoff,0,\n47.001,8.0,30,relative,waypoint,5,7.5\n"
        "47.001,8.002,30,amsl,loiter,20,\n47.0,8.002,0,,land,,\n"
    )
    plan = read_plan(src)
    kinds = [it.kind for it in plan.items]
    assert kinds == [ItemKind.TAKEOFF, ItemKind.SPEED, ItemKind.WAYPOINT, ItemKind.LOITER, ItemKind.LAND]
    assert plan.items[2].hold_s == 5 and plan.items[3].hold_s == 20 and plan.items[1].speed_ms == 7.5
    assert plan.items[3].altitude_frame is AltitudeFrame.AMSL
    assert plan.items[4].altitude_frame is AltitudeFrame.RELATIVE
    write_plan(plan, tmp_path / "q.csv")
    _same(plan, read_plan(tmp_path / "q.csv"))
    # the old CSV layouts and the old import still work
    import functools

    read_route = functools.partial(read_plan_route, other_as_csv=True)

    (tmp_path / "ne.csv").write_text("north,east\n0,0\n100,0\n100,50\n")
    ne, origin = read_route(tmp_path / "ne.csv")
    assert origin is None and ne.tolist() == [[0, 0], [100, 0], [100, 50]]
    write_plan(read_plan(tmp_path / "ne.csv"), tmp_path / "ne2.csv")
    assert read_plan_route(tmp_path / "ne2.csv")[0].tolist() == ne.tolist()
    with pytest.raises(InputError, match="no positions"):
        write_plan(read_plan(tmp_path / "ne.csv"), tmp_path / "x.plan")


def test_csv_writer_refuses_what_it_cannot_hold(shared_data, tmp_path):
    plan = read_plan(shared_data / M / "mavsdk_qgroundcontrol_sample.plan")
    with pytest.raises(InputError, match=r"item 2 .command 2000. cannot be written to a plan CSV"):
        write_plan(plan, tmp_path / "x.csv")
    assert not (tmp_path / "x.csv").exists()


def _qgc(items: object, **mission: object) -> str:
    return json.dumps({"fileType": "Plan", "mission": {"version": 2, "items": items, **mission}})


def _simple(**kw: object) -> dict:
    d = {"type": "SimpleItem", "command": 16, "frame": 3, "params": [0, 0, 0, None, 47.0, 8.0, 50]}
    d.update(kw)
    return d


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("{", "not a QGroundControl plan: not valid JSON"),
        (json.dumps({"fileType": "Mission"}), 'fileType: expected "Plan"'),
        (_qgc([]), "plan has no mission items"),
        (_qgc([_simple(frame=1)]), r"mission\.items\[0\]: unknown or unsupported MAV_FRAME 1"),
        (
            _qgc([_simple(params=[0, 0, 0, 0, 95.0, 8.0, 50])]),
            r"mission\.items\[0\]: latitude 95\.0° outside",
        ),
        (_qgc([_simple(params=[0, 0, 0, 0, 47.0, 8.0, 1e6])]), r"items\[0\]: impossible altitude"),
        (
            _qgc([_simple(params=[0, 0, 0, 0, "47", 8.0, 5])]),
            r"mission\.items\[0\]\.params\[4\]: expected a number",
        ),
        (_qgc([_simple(params=[0, 0])]), r"mission\.items\[0\]\.params: expected an array of 7"),
        (_qgc([_simple(type="Bogus")]), r"mission\.items\[0\]\.type"),
        (_qgc([_simple()], cruiseSpeed=-3), r"mission\.cruiseSpeed: expected a number > 0"),
        ("[" * 100 + "]" * 100, "nested deeper"),
    ],
)
def test_bad_qgc_plans(tmp_path, text, match):
    f = tmp_path / "bad.plan"
    f.write_text(text)
    with pytest.raises(DataFormatError, match=match) as ei:
        read_plan(f)
    assert "bad.plan" in str(ei.value)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("QGC WPL 100\n", r"line 1: not a QGC WPL 110 file"),
        ("QGC WPL 110\n0\t0\t3\t16\t0\t0\t0\t0\t47\t8\n", r"line 2: expected 12 fields"),
        ("QGC WPL 110\n1\t0\t3\t16\t0\t0\t0\t0\tx\t8\t5\t1\n", r"line 2, column 'lat': not a number"),
        (
            "QGC WPL 110\n1\t0\t77\t16\t0\t0\t0\t0\t47\t8\t5\t1\n",
            r"line 2: unknown or unsupported MAV_FRAME 77",
        ),
        (
            "QGC WPL 110\n1\t0\t3\t16\t0\t0\t0\t0\t47\t8\t5\t1\n1\t0\t3\t16\t0\t0\t0\t0\t47\t8\t5\t1\n",
            "line 3, column 'seq'",
        ),
        ("QGC WPL 110\n1\t0\t3\t16\t0\t0\t0\t0\t47\t8\tinf\t1\n", r"line 2, column 'alt': infinite"),
        ("QGC WPL 110\n", "plan has no mission items"),
    ],
)
def test_bad_waypoint_files(tmp_path, text, match):
    f = tmp_path / "bad.waypoints"
    f.write_text(text)
    with pytest.raises(DataFormatError, match=match):
        read_plan(f)


def test_unknown_extension_missing_file_and_size_limit(tmp_path):
    with pytest.raises(InputError, match=r"unknown plan format '\.kmz'"):
        read_plan(tmp_path / "x.kmz")
    with pytest.raises(InputError, match="no such plan file"):
        read_plan(tmp_path / "x.plan")
    import functools

    read_route = functools.partial(read_plan_route, other_as_csv=True)

    with pytest.raises(InputError, match="is a directory"):
        read_route(tmp_path)  # no extension: the old CSV path, same message
    with pytest.raises(InputError, match="unknown plan format"):
        read_plan_route(tmp_path)
    big = tmp_path / "big.plan"
    from uasnav.io.plans import MAX_PLAN_BYTES

    big.write_bytes(b" " * (MAX_PLAN_BYTES + 1))
    with pytest.raises(ResourceLimitError, match="size limit"):
        read_plan(big)


def test_endless_jump_and_model_checks():
    wp = MissionItem(command=16, frame=3, lat_deg=47.0, lon_deg=8.0, alt_m=10, jump_id=1)
    wp2 = MissionItem(command=16, frame=3, lat_deg=47.001, lon_deg=8.0, alt_m=10, jump_id=2)
    forever = MissionItem(command=177, frame=2, params=(1.0, -1.0, 0.0, 0.0), jump_id=3)
    with pytest.raises(InputError, match="repeats forever"):
        flight_sequence(MissionPlan(items=(wp, wp2, forever)))
    with pytest.raises(InputError, match="unknown item"):
        flight_sequence(
            MissionPlan(items=(wp, MissionItem(command=177, frame=2, params=(9.0, 1.0, 0.0, 0.0))))
        )
    with pytest.raises(InputError, match="at least two waypoints"):
        plan_route(MissionPlan(items=(wp,)))
    with pytest.raises(InputError, match="cruise_speed_ms must be a positive speed"):
        MissionPlan(items=(wp,), cruise_speed_ms=0.0)
    # 0°, 0° on a navigation item means "here": no position
    assert not MissionItem(command=22, frame=3, lat_deg=0.0, lon_deg=0.0, alt_m=10).has_position


def test_kml_and_geojson_plans(shared_data, tmp_path):
    import pymap3d

    kml = read_plan(shared_data / "utm" / "interuss_rid_zurich.kml")
    # the first LineString (the "Train" track), clampToGround: on the terrain
    assert len(kml) == 66 and {it.altitude_frame for it in kml.items} == {AltitudeFrame.TERRAIN}
    assert (kml.items[0].lon_deg, kml.items[0].lat_deg) == (8.5233997, 47.3714318)
    route, origin = plan_route(kml)
    n, e, _ = pymap3d.geodetic2ned(47.3716534, 8.5231624, 0.0, *origin)
    np.testing.assert_allclose(route[1], [n, e], atol=1e-6)
    from uasnav.io.plan_formats.kml import read_kml

    assert len(read_kml(shared_data / "utm" / "interuss_rid_zurich.kml", name="ETH")) > 2
    # round trips: an AMSL plan through KML and GeoJSON keeps positions, altitudes and frame
    amsl = MissionPlan(
        items=tuple(
            MissionItem(16, 0, lat_deg=47.0 + 1e-3 * k, lon_deg=8.0, alt_m=500.0 + k) for k in range(3)
        ),
        source="a",
    )
    for ext in (".kml", ".geojson"):
        write_plan(amsl, tmp_path / f"p{ext}")
        back = read_plan(tmp_path / f"p{ext}")
        assert [(it.lat_deg, it.lon_deg, it.alt_m, it.altitude_frame) for it in back.items] == [
            (it.lat_deg, it.lon_deg, it.alt_m, AltitudeFrame.AMSL) for it in amsl.items
        ]
    rel = read_plan(shared_data / M / "qgc_unittest_missionplanner.waypoints")
    with pytest.raises(InputError, match="KML holds one altitude frame"):
        write_plan(rel, tmp_path / "r.kml")
    write_plan(rel, tmp_path / "r.geojson")  # GeoJSON says "relative" explicitly
    assert read_plan(tmp_path / "r.geojson").items[0].altitude_frame is AltitudeFrame.RELATIVE


@pytest.mark.parametrize(
    ("name", "text", "match"),
    [
        ("x.kml", '<?xml version="1.0"?><!DOCTYPE kml [<!ENTITY a "b">]><kml/>', "DTD"),
        ("x.kml", "<kml><Placemark>", "malformed XML"),
        (
            "x.kml",
            "<kml><Placemark><LineString><coordinates>8,47,0 8,x</coordinates>"
            "</LineString></Placemark></kml>",
            "is not lon,lat",
        ),
        ("x.kml", "<kml/>", "no LineString or Point placemark"),
        (
            "x.geojson",
            '{"type": "LineString", "coordinates": [[8, 47, 10], [8.1, 47, 10]]}',
            "no .altitude_frame",
        ),
        ("x.geojson", '{"type": "LineString", "coordinates": [[8, 47], [8.1]]}', r"coordinates\[1\]"),
        ("x.geojson", '{"type": "Polygon"}', "expected a FeatureCollection"),
        (
            "x.geojson",
            '{"type": "LineString", "altitude_frame": "w84", "coordinates": [[8, 47, 1], [8, 48, 1]]}',
            "not one of",
        ),
    ],
)
def test_bad_kml_and_geojson(tmp_path, name, text, match):
    f = tmp_path / name
    f.write_text(text)
    with pytest.raises(DataFormatError, match=match) as ei:
        read_plan(f)
    assert name in str(ei.value)


def test_plans_embedded_in_logs(shared_data):
    plan = read_plan(shared_data / "flights" / "phoenix_mission1_arducopter.tlog")
    # the mission the README describes: take-off to 20 m → waypoint → waypoint → land
    assert [it.kind for it in plan.items] == [
        ItemKind.TAKEOFF,
        ItemKind.WAYPOINT,
        ItemKind.WAYPOINT,
        ItemKind.LAND,
    ]
    assert plan.items[0].alt_m == 20 and plan.home is not None
    route, _ = plan_route(plan)
    assert route.shape == (2, 2) and 95 < float(np.hypot(*route[1])) < 105  # the ~100 m leg
    # the same waypoints as the flight reader takes from the log
    from uasnav.io import read_flight

    log = read_flight(shared_data / "flights" / "phoenix_mission1_arducopter.tlog")
    wps = [log.waypoints[s] for s in sorted(log.waypoints)]
    np.testing.assert_allclose(
        [(it.lat_deg, it.lon_deg) for it in plan.items[1:3]], [w[:2] for w in wps], atol=1e-9
    )
    # log171 carries only ArduPilot's home item: no mission, said so
    with pytest.raises(DataFormatError, match="only a home position"):
        read_plan(shared_data / "logs" / "ardupilot_log171.bin")


def test_items_built_in_code_take_any_numbers_and_refuse_others(tmp_path):
    """A plan built through the API with integer (or numpy) numbers writes like a read one; a
    non-number is refused when the item is built, naming the item."""
    from uasnav.io.mission_plan import HomePosition, MissionItem, MissionPlan

    items = (
        MissionItem(22, 3, (0, 0, 0, 0), 47, 8, 30),
        MissionItem(16, 3, (5, 2, 0, np.float32(90.0)), 47.001, 8, np.int64(30)),
        MissionItem(21, 3, (0, 0, 0, 0), 47.001, 8.001, 0),
    )
    assert all(isinstance(x, float) for it in items for x in (*it.params, it.lat_deg, it.alt_m))
    plan = MissionPlan(items, HomePosition(47.0, 8.0, 480.0))
    for ext in (".plan", ".waypoints"):
        path = tmp_path / f"p{ext}"
        write_plan(plan, path)
        back = read_plan(path)
        assert [it.command for it in back.items] == [22, 16, 21]
        assert back.items[1].params[:2] == (5.0, 2.0) and back.items[1].alt_m == 30.0
    with pytest.raises(InputError, match="command 16"):
        MissionItem(16, 3, ("5", None, 0, 0))
    with pytest.raises(InputError, match="expected 4 params"):
        MissionItem(16, 3, (1.0, 2.0))
