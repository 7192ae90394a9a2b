"""A plan given as ``--area`` flies at its own altitudes (issue 18): they are compared with
``--altitude`` in their frames (AMSL needs ``--ground-elevation``), the higher is used for the
height checks and the output says so; frames that cannot be compared are refused."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.errors import InputError
from uasnav.mission import Requirements, select
from uasnav.mission.zones import parse_area_document, plan_height

THESIS = (
    "select --mission precision-agriculture --resolution 0.05 --image-size 70x70 --imagery multispectral "
    "--wind 5 --order-by cost --range 1500 --json"
).split()


def _wpl(*items: tuple[int, float]) -> str:
    """A QGC WPL plan: home at 47°N 8°E (450 m AMSL), then one waypoint per (frame, altitude)."""
    rows = ["QGC WPL 110", "0\t1\t0\t16\t0\t0\t0\t0\t47.0\t8.0\t450\t1"]
    for k, (frame, alt) in enumerate(items, 1):
        rows.append(f"{k}\t0\t{frame}\t16\t0\t0\t0\t0\t{47.0 + k * 1e-3}\t8.001\t{alt}\t1")
    return "\n".join(rows) + "\n"


def _area(text: str):
    return parse_area_document(text, "plan.waypoints", buffer_m=50.0)


def test_plan_height_in_each_frame() -> None:
    # MAV_FRAME 3 relative to take-off, 10 above terrain, 0 AMSL
    assert plan_height(_area(_wpl((3, 40.0), (3, 60.0))), ground_elevation_m=None)[0] == 60.0
    h, how = plan_height(_area(_wpl((3, 40.0), (10, 70.0))), ground_elevation_m=None)
    assert h == 70.0 and "item 2" in how and "terrain" in how
    assert plan_height(_area(_wpl((0, 600.0), (0, 560.0))), ground_elevation_m=450.0)[0] == 150.0
    with pytest.raises(InputError, match="--ground-elevation"):
        plan_height(_area(_wpl((3, 40.0), (0, 600.0))), ground_elevation_m=None)


def test_higher_plan_is_used_for_the_height_checks_and_said() -> None:
    area = _area(_wpl((3, 30.0), (3, 130.0)))  # 130 m: above the 120 m of the open category
    sel = select(Requirements(range_m=300.0, altitude_m=50.0), area=area)
    assert sel.requirements.altitude_m == 130.0
    assert sel.operation is not None and sel.operation.height_m == 130.0
    assert sel.operation.category == "specific"  # above 120 m: Art. 5
    height = next(f for f in sel.operation.derivation if f.name == "height")
    assert "plan" in height.requirement and "item 2" in height.requirement
    assert any("the height checks use 130 m" in n for n in sel.notes)
    # a plan within --altitude changes nothing but is reported
    low = select(Requirements(range_m=300.0, altitude_m=50.0), area=_area(_wpl((3, 30.0), (3, 45.0))))
    assert low.requirements.altitude_m == 50.0 and low.operation.category == "open"
    assert any("within --altitude 50 m" in n for n in low.notes)
    ref = select(Requirements(range_m=300.0, altitude_m=50.0))
    assert [r.__dict__ for r in low.ranking] == [r.__dict__ for r in ref.ranking]


def test_amsl_plan_needs_ground_elevation_on_the_cli(tmp_path) -> None:
    plan = tmp_path / "survey.waypoints"
    plan.write_text(_wpl((3, 30.0), (0, 640.0)))
    res = CliRunner().invoke(main, [*THESIS, "--altitude", "50", "--area", str(plan)])
    assert res.exit_code == 1 and "--ground-elevation" in res.output and res.output.startswith("error:")
    res = CliRunner().invoke(
        main, [*THESIS, "--altitude", "50", "--area", str(plan), "--ground-elevation", "450"]
    )
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    assert out["requirements"]["altitude_m"] == 190.0  # 640 m AMSL - 450 m ground
    assert (
        any("regulation-height" == r["test"] for r in out["rejections"])
        or out["operation"]["category"] == "specific"
    )
    assert any("640 m AMSL" in n for n in out["notes"])
