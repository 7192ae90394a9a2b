"""The uasnav command line: help, version, allan, report; errors and exit codes."""

from __future__ import annotations

import json

import numpy as np
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.imu import ImuLog
from uasnav.io import write_csv_v1


def _write_log(path, n=20_000, rate=100.0):
    rng = np.random.default_rng(1)
    t = np.arange(n) / rate
    log = ImuLog(t=t, gyro=rng.normal(0, 1e-3, (n, 3)), accel=rng.normal(0, 1e-2, (n, 3)) + [0, 0, -9.8])
    write_csv_v1(log, path)


def test_version_and_help():
    r = CliRunner().invoke(main, ["--version"])
    assert r.exit_code == 0 and "uasnav" in r.output
    for args in (["--help"], ["allan", "--help"], ["report", "--help"]):
        r = CliRunner().invoke(main, args)
        assert r.exit_code == 0, r.output
        assert "Usage" in r.output


def test_allan_json_and_plot(tmp_path):
    log = tmp_path / "log.csv"
    _write_log(log)
    png = tmp_path / "adev.png"
    r = CliRunner().invoke(main, ["allan", str(log), "--json", "--plot", str(png)])
    assert r.exit_code == 0, r.output
    out = json.loads(r.output)
    assert abs(out["rate_hz"] - 100.0) < 1e-9
    rw = [row for row in out["gyro"]["noise"] if row["term"] == "random_walk"]
    expect = 1e-3 * np.sqrt(0.01) * 180 / np.pi * 60  # deg/√h
    for row in rw:
        assert abs(row["fit_field"] / expect - 1) < 0.1
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_allan_table_and_explicit_taus(tmp_path):
    log = tmp_path / "log.csv"
    _write_log(log)
    r = CliRunner().invoke(main, ["allan", str(log), "--taus", "0.01,0.1,1,10,20,40"])
    assert r.exit_code == 0, r.output
    assert "random_walk" in r.output and "deg/√h" in r.output


def test_errors_are_one_line_with_nonzero_exit(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("t,gx,gy,gz,ax,ay,az\n0,0,0,0,0,0,0\n0.01,0,zz,0,0,0,0\n")
    r = CliRunner().invoke(main, ["allan", str(bad)])
    assert r.exit_code == 1
    assert r.output.strip().count("\n") == 0
    assert "line 3" in r.output and "'gy'" in r.output
    r = CliRunner().invoke(main, ["allan", str(tmp_path / "missing.csv")])
    assert r.exit_code == 1 and "no such file" in r.output
    r = CliRunner().invoke(main, ["allan"])
    assert r.exit_code == 2
    good = tmp_path / "good.csv"
    _write_log(good, n=100)
    r = CliRunner().invoke(main, ["allan", str(good), "--taus", "a,b"])
    assert r.exit_code == 2 and "--taus" in r.output


def test_report_quick(tmp_path):
    r = CliRunner().invoke(main, ["report", "--out", str(tmp_path), "--quick", "--only", "allan,attitude"])
    assert r.exit_code == 0, r.output
    html = (tmp_path / "report.html").read_text()
    assert "data:image/png;base64," in html and "NIST SP 1065" in html
    data = json.loads((tmp_path / "report.json").read_text())
    assert data["sections"]["allan"]["nist_max_rel_diff"] < 1e-5
    r = CliRunner().invoke(main, ["report", "--out", str(tmp_path), "--only", "nope"])
    assert r.exit_code == 1 and "unknown report section" in r.output


def test_report_fleet_section_through_the_cli(tmp_path):
    # The fleet experiment writes a simulated fleet to a scratch folder and reads it back in the
    # same run: the command's own output staging must not hide those files from it.
    r = CliRunner().invoke(main, ["report", "--out", str(tmp_path), "--quick", "--only", "fleet"])
    assert r.exit_code == 0, r.output
    data = json.loads((tmp_path / "report.json").read_text())
    assert "fleet" in data["sections"]
