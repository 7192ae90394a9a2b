"""Log format v1 (CSV): round trips and errors that name the line and column."""

from __future__ import annotations

import numpy as np
import pytest

from uasnav.errors import DataFormatError
from uasnav.imu import ImuLog
from uasnav.io import read_log, write_csv_v1
from uasnav.io.formats.csv_v1 import parse_csv_v1


def _log(n=50, temp=True, truth=True):
    rng = np.random.default_rng(0)
    t = np.arange(n) * 0.01 + 1.0 / 3.0
    return ImuLog(
        t=t,
        gyro=rng.normal(size=(n, 3)) * 1e-3,
        accel=rng.normal(size=(n, 3)) + [0, 0, -9.81],
        temp=20.0 + rng.random(n) if temp else None,
        truth={"gyro_bias": rng.normal(size=(n, 3)) * 1e-4} if truth else {},
        meta={"sensor": "test"},
    )


def test_round_trip_bit_for_bit(tmp_path):
    log = _log()
    p = tmp_path / "a.csv"
    write_csv_v1(log, p)
    back = read_log(p)
    for name in ("t", "gyro", "accel", "temp"):
        np.testing.assert_array_equal(getattr(back, name), getattr(log, name))
    np.testing.assert_array_equal(back.truth["gyro_bias"], log.truth["gyro_bias"])
    assert back.meta["sensor"] == "test"
    assert not [f for f in tmp_path.iterdir() if f.name.startswith(".")]


GOOD_HEADER = "t,gx,gy,gz,ax,ay,az\n"


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("t,gx,gy,gz,ax,ay\n0,0,0,0,0,0\n", "missing required column.*az"),
        (GOOD_HEADER + "0,0,0,0,0,0,0\n0.01,0,x,0,0,0,0\n", r"line 3, column 'gy': not a number"),
        (GOOD_HEADER + "0,0,0,0,0,0,0\n0.01,0,0,nan,0,0,0\n", r"line 3, column 'gz': non-finite"),
        (GOOD_HEADER + "0,0,0,0,0,0,0\n0,0,0,0,0,0,0\n", r"line 3, column 't': duplicated"),
        (GOOD_HEADER + "0.02,0,0,0,0,0,0\n0.01,0,0,0,0,0,0\n", r"line 3, column 't': decreasing"),
        (GOOD_HEADER + "0,0,0,0,0,0,0\n", "at least 2 data rows"),
        (GOOD_HEADER + "0,0,0,0,0,0,0\n0.01,0,0,0\n", "line 3: expected 7 cells"),
        ("", "empty file"),
    ],
)
def test_errors_name_line_and_column(text, match):
    with pytest.raises(DataFormatError, match=match):
        parse_csv_v1(text, source="x.csv")


def test_optional_columns_and_comments():
    text = (
        "# sensor: demo\n# rate: 100\n" + "t,gx,gy,gz,ax,ay,az,extra\n0,1,2,3,4,5,6,7\n0.01,1,2,3,4,5,6,7\n"
    )
    log = parse_csv_v1(text)
    assert log.temp is None and log.meta["sensor"] == "demo"
    np.testing.assert_array_equal(log.gyro[0], [1, 2, 3])


def test_missing_file_and_unknown_format(tmp_path):
    with pytest.raises(DataFormatError, match="no such file"):
        read_log(tmp_path / "nope.csv")
    with pytest.raises(ValueError, match="unknown log format"):
        read_log(tmp_path / "x.weird")


def test_failed_write_leaves_no_file(tmp_path):
    log = _log()
    p = tmp_path / "out.csv"
    p.write_text("previous")

    class Boom(ImuLog):
        @property
        def extra(self):  # pragma: no cover
            return None

    bad = _log()
    object.__setattr__(bad, "accel", np.zeros((3, 3)))  # wrong length: column_stack fails
    with pytest.raises(ValueError):
        write_csv_v1(bad, p)
    assert p.read_text() == "previous"
    assert [f.name for f in tmp_path.iterdir()] == ["out.csv"]
    write_csv_v1(log, p)
    assert read_log(p).n == log.n


# --- generic numeric tables (write_csv_table) -------------------------------------------------


def test_csv_table_round_trip_is_exact(tmp_path):
    from uasnav.io import read_csv_table, write_csv_table

    rng = np.random.default_rng(3)
    cols = {
        "t": np.arange(40) * 0.01 + 1.0 / 3.0,
        "bgx": rng.normal(size=40) * 1e-5,
        "flag": np.arange(40) % 3,  # integers are written as numbers
        "sigma": np.where(np.arange(40) == 7, np.nan, rng.random(40)),  # NaN: a missing value
    }
    p = tmp_path / "sub" / "est.csv"
    write_csv_table(p, cols, comments={"mode": "tczupt", "unit.bgx": "rad/s"})
    text = p.read_text()
    assert text.startswith("# mode: tczupt\n# unit.bgx: rad/s\nt,bgx,flag,sigma\n")
    back, notes = read_csv_table(p)
    assert list(back) == list(cols) and notes == {"mode": "tczupt", "unit.bgx": "rad/s"}
    for k, v in cols.items():
        assert back[k].tobytes() == np.asarray(v, dtype=np.float64).tobytes(), k
    assert not [f for f in p.parent.iterdir() if f.name != "est.csv"]  # no temporary file left
    # the comments are CSV v1-style metadata lines: the CSV v1 comment parser reads them too
    write_csv_table(p, {"t": [0.0, 0.01], **{c: [0.0, 0.0] for c in ("gx", "gy", "gz", "ax", "ay", "az")}})
    assert read_log(p).n == 2


@pytest.mark.parametrize(
    ("columns", "comments", "match"),
    [
        ({}, None, "at least one column"),
        ({"t": [0.0, 1.0], "x": [1.0]}, None, "different lengths"),
        ({"t": [0.0, np.inf]}, None, r"column 't': infinite value at row 1"),
        ({"t": [[0.0, 1.0]]}, None, "1-D"),
        ({"t": ["a", "b"]}, None, "not numeric"),
        ({"a,b": [0.0]}, None, "column name"),
        ({"": [0.0]}, None, "column name"),
        ({"t": [0.0]}, {"two words": "x"}, "comment key"),
        ({"t": [0.0]}, {"k": "line\nbreak"}, "one line"),
    ],
)
def test_csv_table_bad_input_writes_nothing(tmp_path, columns, comments, match):
    from uasnav.errors import InputError
    from uasnav.io import write_csv_table

    p = tmp_path / "out.csv"
    p.write_text("previous")
    with pytest.raises(InputError, match=match):
        write_csv_table(p, columns, comments=comments)
    assert p.read_text() == "previous"
    assert [f.name for f in tmp_path.iterdir()] == ["out.csv"]


def test_csv_table_failure_while_writing_leaves_old_file(tmp_path, monkeypatch):
    import uasnav.io.table as table
    from uasnav.io import write_csv_table

    p = tmp_path / "out.csv"
    p.write_text("previous")

    def boom(fh, block):
        fh.write("partial")
        raise OSError("disk full")

    monkeypatch.setattr(table, "write_rows", boom)
    with pytest.raises(OSError, match="disk full"):
        write_csv_table(p, {"t": [0.0, 1.0]})
    assert p.read_text() == "previous"
    assert [f.name for f in tmp_path.iterdir()] == ["out.csv"]


def test_read_csv_table_errors_name_line_and_column(tmp_path):
    from uasnav.io import read_csv_table

    p = tmp_path / "x.csv"
    p.write_text("# a: 1\nt,x\n0,1\n0.1,oops\n")
    with pytest.raises(DataFormatError, match=r"line 4, column 'x': not a number"):
        read_csv_table(p)
    p.write_text("t,x\n0,1,2\n")
    with pytest.raises(DataFormatError, match="line 2: expected 2 cells"):
        read_csv_table(p)
    with pytest.raises(DataFormatError, match="no such file"):
        read_csv_table(tmp_path / "nope.csv")


# --- CSV v1 with extra columns and metadata (the fused output of `uasnav redundancy fuse`) ------


def test_csv_v1_extra_columns_and_metadata(tmp_path):
    log = _log(temp=False, truth=False)
    log = ImuLog(
        t=log.t,
        gyro=log.gyro,
        accel=log.accel,
        meta={"fused_from": "a.csv b.csv", "shape": "cube", "fdi": True, "dropped_samples": 3},
    )
    chi2 = np.linspace(0.0, 2.0, log.n)
    chi2[4] = np.nan
    health = (np.arange(log.n) % 2 * 8).astype(float)
    p = tmp_path / "fused.csv"
    write_csv_v1(log, p, extra_columns={"chi2_gyro": chi2, "health_0": health})
    lines = p.read_text().splitlines()
    assert lines[:6] == [
        "# uasnav log format v1 (SI units: s, rad/s, m/s^2, degC, uT)",
        "# fused_from: a.csv b.csv",
        "# shape: cube",
        "# fdi: True",
        "# dropped_samples: 3",
        "t,gx,gy,gz,ax,ay,az,chi2_gyro,health_0",
    ]
    assert lines[6 + 4].split(",")[7] == "nan" and lines[7].split(",")[8] == "8"
    back = read_log(p)  # the extra columns are ignored by the reader
    np.testing.assert_array_equal(back.gyro, log.gyro)
    assert back.meta["fdi"] == "True" and back.meta["dropped_samples"] == "3"
    from uasnav.io import read_csv_table

    cols, _ = read_csv_table(p)
    assert cols["chi2_gyro"].tobytes() == chi2.tobytes() and cols["health_0"].tobytes() == health.tobytes()


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        ({"chi2": np.zeros(3)}, "3 values for 50 samples"),
        ({"gx": np.zeros(50)}, "already a column"),
        ({"chi2": np.full(50, np.inf)}, "infinite"),
    ],
)
def test_csv_v1_bad_extra_columns(tmp_path, extra, match):
    p = tmp_path / "out.csv"
    with pytest.raises(ValueError, match=match):
        write_csv_v1(_log(), p, extra_columns=extra)
    assert not p.exists() and not list(tmp_path.iterdir())
