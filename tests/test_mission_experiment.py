"""The mission-selector experiment of chapter 5.2 (what the report's mission section shows)."""

from __future__ import annotations

import pytest

from uasnav.experiments import mission


@pytest.fixture(scope="module")
def result() -> mission.MissionResult:
    return mission.run(quick=True)


def test_table20_agreement(result: mission.MissionResult) -> None:
    t20 = result.table20
    assert (t20.cells, t20.agree, t20.agree_necessary) == (300, 167, 213)
    assert sum(n for _, _, n in t20.kinds) == t20.cells - t20.agree


def test_table24_thesis_pairs(result: mission.MissionResult) -> None:
    pairs = {(r.uas, r.camera): r.score for r in result.table24}
    assert abs(pairs[("Phantom 4", "Micro ADC")] - 1.426) < 1e-3
    assert pairs[("Phantom 4", "Snap ADC")] is None  # fails eq. 60 with our Snap values
    snap = next(r for r in result.table24 if r.camera == "Snap ADC")
    assert snap.reason


def test_every_table_has_its_data(result: mission.MissionResult) -> None:
    # Tables 18–21 and 24 of the report are rendered from these.
    assert result.missions and result.matrices.features  # Table 18
    assert result.matrices.equipment  # Table 19
    assert len(result.table20.rows) == len(result.matrices.table20)  # Table 20
    assert len(result.database.uas) and len(result.database.cameras)  # Table 21
    assert len(result.table24) == 5 and len(result.top5) == 5  # Table 24
