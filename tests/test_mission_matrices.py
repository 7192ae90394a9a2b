"""Compliance matrices: Table 18 as encoded, Table 19 reconstruction rules, and the derived
missions × equipment matrix against the printed Table 20 (disagreements are counted and
listed in the report; here their number is pinned as a change detector on the database files,
so that any change to them is deliberate — see test_against_table20)."""

from __future__ import annotations

from collections import Counter

import pytest

from uasnav.errors import InputError
from uasnav.mission import load_matrices
from uasnav.mission.matrices import INCOMPATIBLE, NECESSARY, OPTIONAL

MX = load_matrices()


def test_table18_rows() -> None:
    assert list(MX.missions) == [
        "packet-delivery",
        "precision-agriculture",
        "mapping",
        "surveillance",
        "law-enforcement",
        "traffic-monitoring",
        "infrastructure-inspection",
        "aerial-photo",
        "communication-relay",
        "search-and-rescue",
    ]
    pa = MX.mission("precision-agriculture").features
    assert pa["operations"] == ("vlos", "bvlos") and pa["range"] == ("lt1km", "1to5km", "gt5km")
    assert pa["risk"] == ("low",) and pa["realtime-payload"] == ("no",)
    # Table 18 "Real-time payload data" row: No, No, No, Yes, Yes, Yes, No, Yes, Yes, Yes.
    rtpd = [m.features["realtime-payload"] == ("yes",) for m in MX.missions.values()]
    assert rtpd == [False, False, False, True, True, True, False, True, True, True]
    # BLOS row: Yes for packet delivery, law enforcement, traffic, relay, search and rescue.
    blos = [mid for mid, m in MX.missions.items() if "blos" in m.features["operations"]]
    assert blos == [
        "packet-delivery",
        "law-enforcement",
        "traffic-monitoring",
        "communication-relay",
        "search-and-rescue",
    ]


def test_every_equipment_item_documents_its_judgement() -> None:
    for e in MX.equipment.values():
        assert len(e.note) > 10, e.id


def test_derivation_rule() -> None:
    # Necessary if any level needs it: packet delivery (>5 km, BLOS, high risk) needs the
    # airspeed sensor (rule A) and the BLOS C2 link (rule B).
    assert MX.equipment_status("packet-delivery", "airspeed-sensor") == NECESSARY
    assert MX.equipment_status("packet-delivery", "blos-c2") == NECESSARY
    # Incompatible only if every level of a feature is: manual control beyond 5 km only.
    assert MX.equipment_status("packet-delivery", "manual-control") == INCOMPATIBLE
    assert MX.equipment_status("traffic-monitoring", "manual-control") == INCOMPATIBLE
    # Precision agriculture spans <1 km … >5 km: manual control stays possible.
    assert MX.equipment_status("precision-agriculture", "manual-control") == OPTIONAL
    # Payload data link follows real-time payload data only (rule B item 3).
    for mid, m in MX.missions.items():
        expect = NECESSARY if m.features["realtime-payload"] == ("yes",) else OPTIONAL
        assert MX.equipment_status(mid, "payload-link") == expect
    with pytest.raises(InputError, match="unknown mission 'pizza'"):
        MX.derive("pizza")


def test_against_table20() -> None:
    rows = {r.equipment: r for r in MX.table20 if r.equipment}
    # Rows where the derivation reproduces Table 20 exactly.
    for eid in ("standard-gnss", "barometric-altimeter", "c2-link"):
        assert {mid: MX.equipment_status(mid, eid) for mid in MX.missions} == rows[eid].status
    # Necessary cells of the payload link and manual control agree everywhere.
    for eid in ("payload-link", "manual-control"):
        for mid in MX.missions:
            assert (MX.equipment_status(mid, eid) == NECESSARY) == (rows[eid].status[mid] == NECESSARY)
    diffs = MX.compare_table20()
    n_cells = sum(len(r.status) for r in rows.values())
    # Shape of the transcription: 30 equipment rows × 10 missions of the printed Table 20
    # (catches a lost row or mission column in the database file).
    assert len(rows) == 30 and all(len(r.status) == len(MX.missions) == 10 for r in rows.values())
    assert n_cells == 300
    # compare_table20 lists exactly the cells where derivation and print differ (recounted
    # independently here, so the report's "agrees in N/300 cells" is a count, not an estimate).
    recount = sum(
        MX.equipment_status(mid, eid) != printed
        for eid, r in rows.items()
        for mid, printed in r.status.items()
    )
    assert len(diffs) == recount
    assert all(d["derived"] != d["table20"] for d in diffs)
    # Change detector, on purpose: 167/300 cells agree exactly, 213/300 on necessary vs not. These
    # describe today's database (the Table 19 rules as encoded and the Table 20 transcription),
    # not a property of the method: they protect the report's agreement figures from moving
    # silently when either data file changes. Update them together with the report's
    # discussion of the disagreements.
    assert n_cells - len(diffs) == 167
    nec_disagree = [d for d in diffs if (d["derived"] == NECESSARY) != (d["table20"] == NECESSARY)]
    assert n_cells - len(nec_disagree) == 213
    kinds = Counter((d["derived"], d["table20"]) for d in diffs)
    # The largest class: Table 20 leaves blank (≈ "not relevant") what Table 19 allows.
    assert kinds.most_common(1)[0][0] == (OPTIONAL, INCOMPATIBLE)
