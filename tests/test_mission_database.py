"""The shipped database against the public specification data in ../shared/data
(opendronelist, MIT; MissionPlanner camerasBuiltin, GPL-3.0 — read here, never copied)."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from lxml import etree

from uasnav.mission import load_database
from uasnav.mission.loading import parse_bytes

DB = load_database()

# Our camera id → MissionPlanner camerasBuiltin name.
MP_NAMES = {
    "canon-powershot-s110": "Canon S110-S120",
    "canon-powershot-sx260-hs": "Canon SX260-SX280",
    "canon-elph-520-hs": "Canon ELPH 520HS",
    "sony-nex-5-16-mm": "Nex5 16mm",
    "sony-nex-7-16-mm": "Nex7 16mm",
    "sony-a6000-20-mm": "Sony A6000",
    "sony-a7r-28-mm": "Sony A7R",
    "sony-wx500": "WX 500",
    "samsung-nx1000-20-mm": "NX1000",
    "micasense-rededge": "RedEdge",
    "parrot-sequoia": "Parrot Sequoia Monochrome",
    "flir-vue-pro-336-9-mm": "FLIR Vue 336 9mm",
    "flir-vue-pro-r-640-13-mm": "FLIR Vue 640 13mm",
}


def test_size_and_sources() -> None:
    assert len(DB.uas) >= 30 and len(DB.cameras) >= 20
    assert {"multirotor", "fixed-wing", "vtol"} <= set(DB.uas.types)
    assert sum(t == "multispectral" for t in DB.cameras.types) >= 8
    for name in ("Phantom 3 Professional", "Phantom 4"):
        assert name in DB.uas.names
    assert {"ADC Micro", "ADC Snap"} <= set(DB.cameras.names)
    assert np.all(DB.uas.payload_g >= 0) and np.all(DB.cameras.hfov_deg > 0)


def test_uas_against_opendronelist(shared_data: Path) -> None:
    with open(shared_data / "specs" / "opendronelist.csv", newline="") as fh:
        rows = {(r["manufacturer"].lower(), r["name"].lower()): r for r in csv.DictReader(fh)}
    u = DB.uas
    checked = 0
    for i in range(len(u)):
        r = rows.get((u.producers[i].lower(), u.names[i].lower()))
        if r is None:
            continue
        checked += 1
        # The list sometimes gives MTOM as "weight" (e.g. Matrice 350 RTK): accept either match.
        mass_ok = r["weight"] and abs(u.mass_g[i] - float(r["weight"])) <= 0.1 * float(r["weight"])
        mtom_ok = abs(u.max_takeoff_g[i] - float(r["max_takeoff"])) <= 0.1 * float(r["max_takeoff"])
        assert mass_ok or mtom_ok, u.label(i)
        assert abs(u.endurance_min[i] - float(r["endurance"])) <= 0.25 * float(r["endurance"]), u.label(i)
    assert checked >= 20


def test_cameras_against_missionplanner(shared_data: Path) -> None:
    data = (shared_data / "specs" / "missionplanner_camerasBuiltin.xml").read_bytes()
    root = parse_bytes(data, "camerasBuiltin.xml").getroot()
    mp = {c.findtext("name"): c for c in root.iterfind("Camera")}
    c = DB.cameras
    for cid, name in MP_NAMES.items():
        j = c.ids.index(cid)
        ref = mp[name]
        assert c.focal_mm[j] == pytest.approx(float(ref.findtext("flen")), rel=1e-9), cid
        assert c.resolution_w_px[j] == float(ref.findtext("imgw")), cid
        assert c.sensor_w_mm[j] == pytest.approx(float(ref.findtext("senw")), abs=0.06), cid
    assert isinstance(root, etree._Element)
