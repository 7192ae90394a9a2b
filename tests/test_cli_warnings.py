"""A command that fails prints its one ``error: …`` line and nothing else, even when the work
before the failure raised warnings (``cli._common.warnings_after_success``); a command that
succeeds shows them, one ``warning: …`` line each."""

from __future__ import annotations

import warnings

from click.testing import CliRunner

import uasnav.trajectory.element_table as element_table
from uasnav.cli import main
from uasnav.errors import InputError


def _train(tmp_path, monkeypatch, fail: bool):
    def samples(*args, **kwargs):
        warnings.warn("flight 0: element(s) [0] not measured (telemetry gap)", UserWarning, stacklevel=1)
        raise InputError("training element 0: ΔV 2225.39 m/s is outside [-150, 150] m/s")

    if fail:
        monkeypatch.setattr(element_table, "training_samples", samples)
    flight = tmp_path / "f.csv"
    flight.write_text("t,lat,lon\n0,0,0\n")
    return CliRunner().invoke(main, ["trajectory", "train", str(flight), "--out", str(tmp_path / "m.json")])


def test_failed_train_prints_one_error_line_only(tmp_path, monkeypatch) -> None:
    r = _train(tmp_path, monkeypatch, fail=True)
    assert r.exit_code == 1
    lines = r.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: training element 0"), r.stderr


def test_warnings_after_success_shows_them_once_the_block_succeeded(capsys) -> None:
    from uasnav.cli._common import warnings_after_success

    shown = []
    old = warnings.showwarning
    warnings.showwarning = lambda message, *a, **k: shown.append(str(message))
    try:
        with warnings_after_success():
            warnings.warn("held", UserWarning, stacklevel=1)
            assert shown == []
        assert shown == ["held"]
        shown.clear()
        try:
            with warnings_after_success():
                warnings.warn("dropped", UserWarning, stacklevel=1)
                raise InputError("boom")
        except InputError:
            pass
        assert shown == []
    finally:
        warnings.showwarning = old


def test_folded_warnings_name_each_file_once() -> None:
    """A warning about the file the error already names drops its prefix; others keep theirs."""
    from uasnav.cli import _with_warnings

    line = _with_warnings(
        "log.bin, column 'GPS.Status': fewer than 2 fixes",
        ["log.bin: corrupt data skipped: 1 record dropped", "other.csv: 3 rows skipped"],
    )
    assert line.count("log.bin") == 1
    assert line.endswith("(warnings: corrupt data skipped: 1 record dropped; other.csv: 3 rows skipped)")
