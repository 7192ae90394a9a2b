"""Log format v1 (CSV): round trips and errors that name the line and column."""

from __future__ import annotations

import numpy as np
import pytest

from uasnav.errors import DataFormatError
from uasnav.imu import ImuLog
from uasnav.io import read_log, write_csv_v1
from uasnav.io.csv_v1 import parse_csv_v1


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
