"""The mission plan of a PX4 ULog (``navigator_mission_item``, ``home_position``, ``mission``).

Neither shared ULog carries mission items (px4_sample_log_small.ulg has an empty ``mission``
topic, count 0; px4_sample.ulg no mission topic at all), so the logs with a mission are written
here by a minimal ULog writer following the format specification
(https://docs.px4.io/main/en/dev_log/ulog_file_format.html: file header, ``F`` formats,
``A`` subscriptions, ``D`` data), and read back through pyulog by the reader under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from pyulog import ULog

from uasnav.errors import DataFormatError
from uasnav.io.mission_plan import AltitudeFrame, ItemKind, route_points
from uasnav.io.plans import read_plan
from ulog_writer import write_ulog

NAV_ITEM = (
    ("uint64_t", "timestamp"), ("uint32_t", "instance_count"), ("uint16_t", "sequence_current"),
    ("uint16_t", "nav_cmd"), ("float", "latitude"), ("float", "longitude"), ("float", "time_inside"),
    ("float", "acceptance_radius"), ("float", "loiter_radius"), ("float", "yaw"), ("float", "altitude"),
    ("uint8_t", "frame"), ("uint8_t", "origin"), ("bool", "loiter_exit_xtrack"), ("bool", "force_heading"),
    ("bool", "altitude_is_relative"), ("bool", "autocontinue"), ("bool", "vtol_back_transition"),
)  # fmt: skip
HOME = (("uint64_t", "timestamp"), ("double", "lat"), ("double", "lon"), ("float", "alt"))
MISSION = (
    ("uint64_t", "timestamp"),
    ("int32_t", "current_seq"),
    ("uint16_t", "count"),
    ("uint8_t", "dataman_id"),
)


def _item(
    t: int, seq: int, cmd: int, lat: float, lon: float, alt: float, hold: float = 0.0, rel: bool = True
) -> dict:
    return {
        "timestamp": t, "instance_count": 1, "sequence_current": seq, "nav_cmd": cmd, "latitude": lat,
        "longitude": lon, "time_inside": hold, "acceptance_radius": 2.0, "loiter_radius": 0.0,
        "yaw": math.radians(90.0), "altitude": alt, "frame": 3 if rel else 0, "origin": 0,
        "loiter_exit_xtrack": False, "force_heading": False, "altitude_is_relative": rel,
        "autocontinue": True, "vtol_back_transition": False,
    }  # fmt: skip


ITEMS = [
    _item(1_000_000, 0, 22, 47.3977, 8.5456, 30.0),
    _item(2_000_000, 1, 16, 47.3987, 8.5456, 30.0, hold=5.0),
    _item(3_000_000, 2, 16, 47.3987, 8.5476, 50.0),
    _item(3_500_000, 2, 16, 47.3987, 8.5476, 60.0),  # re-sent: the last record wins
    _item(4_000_000, 3, 178, 0.0, 0.0, 0.0),  # DO_CHANGE_SPEED: no position
    _item(5_000_000, 4, 21, 47.3977, 8.5476, 0.0),
]


def test_ulog_mission_items_home_and_frames(tmp_path):
    path = tmp_path / "mission.ulg"
    home = {"timestamp": 500_000, "lat": 47.3977, "lon": 8.5456, "alt": 488.0}
    write_ulog(path, {"navigator_mission_item": (NAV_ITEM, ITEMS), "home_position": (HOME, [home])})
    # the writer's file is a ULog pyulog reads with the values written
    u = ULog(str(path))
    nav = next(d for d in u.data_list if d.name == "navigator_mission_item")
    np.testing.assert_array_equal(nav.data["sequence_current"], [0, 1, 2, 2, 3, 4])
    plan = read_plan(path)
    assert [it.command for it in plan.items] == [22, 16, 16, 178, 21]
    assert [it.jump_id for it in plan.items] == [0, 1, 2, 3, 4]
    wp = plan.items[1]
    assert wp.altitude_frame == AltitudeFrame.RELATIVE and wp.params[0] == 5.0 and wp.params[1] == 2.0
    assert wp.params[3] == pytest.approx(90.0)  # yaw rad → deg (MAVLink param 4)
    assert wp.lat_deg == pytest.approx(47.3987, abs=1e-5)  # float32 in the log
    assert plan.items[2].alt_m == 60.0  # the last record of sequence 2
    assert plan.items[3].kind != ItemKind.WAYPOINT and math.isnan(plan.items[3].lat_deg)
    assert plan.home is not None and plan.home.alt_amsl_m == 488.0
    # the 3D route: take-off climb at home, the hold, the climb to 60 m, the landing
    pts = route_points(plan)
    assert [p.hold_s for p in pts].count(5.0) == 1
    assert max(p.alt_m for p in pts) == 60.0 and pts[-1].alt_m == 0.0


def test_ulog_amsl_items(tmp_path):
    path = tmp_path / "amsl.ulg"
    items = [_item(1, 0, 16, 47.0, 8.0, 520.0, rel=False), _item(2, 1, 16, 47.001, 8.0, 530.0, rel=False)]
    write_ulog(path, {"navigator_mission_item": (NAV_ITEM, items)})
    plan = read_plan(path)
    assert all(it.altitude_frame == AltitudeFrame.AMSL for it in plan.items) and plan.home is None


def test_ulog_without_mission_items_says_what_it_holds(tmp_path, shared_data):
    with pytest.raises(DataFormatError, match=r"empty mission \(mission.count = 0\)"):
        read_plan(shared_data / "logs" / "px4_sample_log_small.ulg")
    with pytest.raises(DataFormatError, match="no mission topic"):
        read_plan(shared_data / "logs" / "px4_sample.ulg")
    path = tmp_path / "count.ulg"
    write_ulog(
        path, {"mission": (MISSION, [{"timestamp": 1, "current_seq": 0, "count": 7, "dataman_id": 0}])}
    )
    with pytest.raises(DataFormatError, match=r"a mission of 7 items .* but not the items"):
        read_plan(path)
    bad = tmp_path / "bad.ulg"
    write_ulog(bad, {"navigator_mission_item": (NAV_ITEM, [_item(1, 0, 16, 95.0, 8.0, 30.0)])})
    with pytest.raises(DataFormatError, match=r"navigator_mission_item 0: latitude .* outside ±90°"):
        read_plan(bad)
    junk = tmp_path / "junk.ulg"
    junk.write_bytes(b"not a ulog at all")
    with pytest.raises(DataFormatError, match="not a readable ULog"):
        read_plan(junk)


def test_ulog_altitude_frame_from_the_frame_field_else_refused(tmp_path):
    # a log whose topic has no altitude_is_relative: the MAV_FRAME field says the frame
    no_rel = tuple(f for f in NAV_ITEM if f[1] != "altitude_is_relative")
    items = [_item(1, 0, 16, 47.0, 8.0, 520.0, rel=False), _item(2, 1, 16, 47.001, 8.0, 30.0, rel=True)]
    path = tmp_path / "frame.ulg"
    write_ulog(path, {"navigator_mission_item": (no_rel, items)})
    plan = read_plan(path)
    assert [it.altitude_frame for it in plan.items] == [AltitudeFrame.AMSL, AltitudeFrame.RELATIVE]
    assert [it.frame for it in plan.items] == [0, 3]
    # a frame that is no global altitude frame (1 = MAV_FRAME_LOCAL_NED) is refused, named
    local = tmp_path / "local.ulg"
    write_ulog(local, {"navigator_mission_item": (no_rel, [{**items[0], "frame": 1}])})
    with pytest.raises(DataFormatError, match=r"navigator_mission_item 0: frame 1 is not a global altitude"):
        read_plan(local)
    # neither field: refused, never assumed relative to home
    neither = tuple(f for f in no_rel if f[1] != "frame")
    bare = tmp_path / "bare.ulg"
    write_ulog(bare, {"navigator_mission_item": (neither, items)})
    with pytest.raises(DataFormatError, match="lacks both altitude_is_relative and frame"):
        read_plan(bare)
    # a DO_* item (no position) needs no frame
    do = tmp_path / "do.ulg"
    write_ulog(do, {"navigator_mission_item": (neither, [_item(1, 0, 178, 0.0, 0.0, 0.0)])})
    assert read_plan(do).items[0].altitude_frame == AltitudeFrame.NONE


def test_corrupt_ulog_plan_prints_nothing(tmp_path, capfd):
    """pyulog prints its corruption notices to stdout: the plan reader keeps them off it (a
    command's --json output must stay clean) and still reads what the file holds."""
    path = tmp_path / "cut.ulg"
    write_ulog(path, {"navigator_mission_item": (NAV_ITEM, ITEMS)})
    data = bytearray(path.read_bytes())
    data[7] = 9  # a file version pyulog does not know: it warns on stdout and reads on
    path.write_bytes(bytes(data[:-7]) + b"\xff" * 40)  # last record cut, then garbage
    capfd.readouterr()
    try:
        plan = read_plan(path)
    except DataFormatError:
        plan = None
    out = capfd.readouterr()
    assert out.out == "", out.out
    assert plan is None or [it.command for it in plan.items][:3] == [22, 16, 16]
