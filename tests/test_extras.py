"""The optional parts: one message naming the `pip install` line, and a report that runs the
sections it can."""

from __future__ import annotations

import json

import pytest

from uasnav import _extras
from uasnav import report as report_mod
from uasnav._extras import MissingExtraError, extra_of, require
from uasnav.errors import UasnavError


def test_require_names_the_extra_and_the_install_line(monkeypatch: pytest.MonkeyPatch) -> None:
    require("web", "uasnav serve")  # installed in the test environment: no error
    monkeypatch.setitem(_extras.EXTRAS, "web", ("fastapi", "no_such_module_for_uasnav"))
    with pytest.raises(MissingExtraError) as e:
        require("web", "uasnav serve")
    assert isinstance(e.value, UasnavError) and isinstance(e.value, ImportError)
    assert str(e.value) == (
        "uasnav serve needs the 'web' extra (no_such_module_for_uasnav is not installed): "
        "pip install 'uasnav[web]'"
    )
    with pytest.raises(KeyError):
        require("nope", "x")


def test_extra_of_maps_a_missing_module() -> None:
    assert extra_of(ModuleNotFoundError("x", name="distributed.client")) == "fleet"
    assert extra_of(ModuleNotFoundError("x", name="uas_standards")) == "utm"
    assert extra_of(ModuleNotFoundError("x", name="numpy")) is None


def test_report_runs_the_sections_it_can(tmp_path, monkeypatch: pytest.MonkeyPatch) -> None:
    def ok(w: report_mod.SectionWriter) -> None:
        w.p("fine")
        w.data["x"] = 1

    def needs_fleet(w: report_mod.SectionWriter) -> None:
        w.p("half")
        raise MissingExtraError("fleet", "fleet processing on a Dask cluster", "dask")

    sections = [report_mod.Section("a", "A", 1, ok), report_mod.Section("b", "B", 2, needs_fleet)]
    monkeypatch.setattr(report_mod, "discover_sections", lambda: sections)
    res = report_mod.build_report(tmp_path)
    data = json.loads(res.json_path.read_text())["sections"]
    assert data["a"] == {"x": 1}
    assert data["b"]["extra"] == "fleet" and "pip install 'uasnav[fleet]'" in data["b"]["skipped"]
    html = res.html_path.read_text()
    assert "Not run: fleet processing" in html and "half" not in html
    # asked for by name, the missing extra is the answer
    with pytest.raises(MissingExtraError):
        report_mod.build_report(tmp_path / "only", only=["b"])
