"""Quick-mode report section of the mission selector."""

from __future__ import annotations

import json

from click.testing import CliRunner

from uasnav.cli import main


def test_report_mission_quick(tmp_path) -> None:
    r = CliRunner().invoke(main, ["report", "--out", str(tmp_path), "--quick", "--only", "mission"])
    assert r.exit_code == 0, r.output
    data = json.loads((tmp_path / "report.json").read_text())["sections"]["mission"]
    assert data["table20"] == {"cells": 300, "agree": 167, "agree_necessary": 213}
    pairs = {(u, c): s for u, c, s in data["table24"]["ours_thesis_pairs"]}
    assert abs(pairs[("Phantom 4", "Micro ADC")] - 1.426) < 1e-3
    assert pairs[("Phantom 4", "Snap ADC")] is None  # fails eq. 60 with our Snap values
    html = (tmp_path / "report.html").read_text()
    for table in ("Table 18", "Table 19", "Table 20", "Table 21", "Table 24"):
        assert table in html
