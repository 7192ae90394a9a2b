"""Answers an operator can trust: the camera tested at the planned height (the thesis' rule
on request), the category falling back instead of "not flyable", what no camera meets, the
pilot distance from the area, consistent rows, the C2 link by its range, STS/PDRA only when
their own conditions hold, and the scoring explained."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.geo import frames
from uasnav.mission import Requirements, select
from uasnav.mission.request import run_select

LAT0, LON0 = 45.0, 9.0


def rect(east_m: float, north_m: float, size_m: float) -> dict:
    e = np.array([east_m, east_m + size_m, east_m + size_m, east_m, east_m])
    n = np.array([north_m, north_m, north_m + size_m, north_m + size_m, north_m])
    la, lo, _ = frames.enu_to_geodetic(e, n, 0.0, LAT0, LON0, 0.0)
    return {"type": "Polygon", "coordinates": [[[float(x), float(y)] for x, y in zip(lo, la, strict=True)]]}


def test_camera_tested_at_the_planned_height_or_the_thesis_rule() -> None:
    planned = {h: select(Requirements(altitude_m=h)) for h in (20.0, 50.0, 100.0)}
    hfov = {h: s.required_hfov_deg for h, s in planned.items()}
    assert hfov[20.0] > hfov[50.0] > hfov[100.0]  # 2·atan(35/h)
    assert hfov[50.0] == pytest.approx(69.98, abs=0.01)
    for h, s in planned.items():
        d = s.to_dict()["camera_height"]
        assert d["rule"] == "planned" and d["height_m"] == h
    thesis = [select(Requirements(altitude_m=h, camera_height="regulatory-max")) for h in (20.0, 50.0, 100.0)]
    assert {round(s.required_hfov_deg, 1) for s in thesis} == {32.5}
    assert thesis[0].to_dict()["camera_height"] == {
        "rule": "regulatory-max",
        "height_m": 120.0,
        "explained": thesis[0].to_dict()["camera_height"]["explained"],
    }


def test_specific_category_is_a_fallback_not_unflyable() -> None:
    # 1500 m from the pilot: beyond sight, no open category — the specific category authorises it
    sel = select(Requirements(camera_height="regulatory-max"))
    auth = sel.authorisation
    assert auth["authorisable"] and sel.operation.category == "specific"
    assert auth["verdict"].startswith("authorisable") and "specific category" in auth["route"]


def test_no_camera_reaching_the_resolution_is_said_as_such() -> None:
    sel = select(Requirements(resolution_m=0.001, imagery=None))
    auth = sel.authorisation
    assert not auth["authorisable"] and not sel.ranking
    assert auth["verdict"].startswith("no camera in the database meets")
    assert "resolution" in auth["verdict"] and "0.001 m/px" in auth["verdict"]


def test_pilot_distance_comes_from_the_area_and_the_pilot() -> None:
    near = run_select({"area": rect(10, 10, 70)})  # the range option keeps its 1500 m default
    assert near.operation.visibility == "VLOS" and near.operation.category == "open"
    assert near.operation.max_distance_m < 100
    far = run_select({"area": rect(10, 10, 70), "pilot": f"{LAT0 - 0.0135},{LON0}"})  # 1.5 km south
    assert far.operation.visibility == "BVLOS"
    assert far.operation.max_distance_m == pytest.approx(1500 + 80, abs=15)


def test_bvlos_rows_have_no_open_subcategory_and_the_c2_link_fits_the_range() -> None:
    sel = select(Requirements(max_distance_m=1500.0))
    assert sel.ranking and all(r.visibility == "BVLOS" for r in sel.ranking)
    assert all(r.open_subcategory is None for r in sel.ranking)
    (c2,) = [e for e in sel.equipment if e.id == "blos-c2" and e.necessary]
    assert "1500 m" in c2.name and "direct radio" in c2.name and "SATCOM" not in c2.name
    far = select(Requirements(range_m=8000.0, max_distance_m=8000.0, imagery=None))
    (c2,) = [e for e in far.equipment if e.id == "blos-c2" and e.necessary]
    assert "SATCOM" in c2.name


def test_pdra_s01_and_sts_need_a_controlled_ground_area() -> None:
    sel = select(
        Requirements(
            range_m=300.0, max_distance_m=300.0, vlos_distance_m=500.0, over_people="uninvolved",
            population_density=5000.0, category="specific",
        )
    )  # fmt: skip
    by = {x.id: x for x in sel.scenarios}
    for sid in ("PDRA-S01", "STS-01"):
        assert not by[sid].applies
        assert any("controlled ground area" in r and "uninvolved" in r for r in by[sid].reasons)


def test_scoring_targets_are_explained_with_the_ranking() -> None:
    d = select(Requirements()).to_dict()
    lines = d["scoring"]["explained"]
    assert any(x.startswith("cost") and "4000 USD" in x and "ties" in x for x in lines)
    r = CliRunner().invoke(main, ["select"])
    assert r.exit_code == 0 and "ties on cost" in r.output


def test_select_wind_takes_a_direction_and_json_says_the_camera_height(tmp_path) -> None:
    r = CliRunner().invoke(main, ["select", "--wind", "6@270", "--camera-height", "regulatory-max", "--json"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert d["requirements"]["wind_ms"] == 6.0 and d["camera_height"]["rule"] == "regulatory-max"
    bad = CliRunner().invoke(main, ["select", "--wind", "6@north"])
    assert bad.exit_code == 2 and "wind" in bad.output


def test_select_window_is_the_survey_of_the_area_not_the_range(shared_data) -> None:
    # a 500 m × 500 m mapping field: the zones' window is the survey's time, minutes not seconds
    zones = (shared_data / "utm" / "interuss_ed269_geozone_sample.json").read_text()
    sel = run_select(
        {"area": rect(10, 10, 500), "zones": zones, "flight_time": "2027-05-03T10:00Z", "resolution": 0.03}
    )
    w = sel.flight_window
    assert w is not None and "survey of the area" in w["from"]
    assert w["duration_s"] > 600
