"""Hostile files for every log reader (issue #20, classes 5 and 7).

Each bad input must give one :class:`DataFormatError` (or another :class:`InputError`) naming the
file and, for text, the line and column; nothing may reach a user as a traceback. Corrupt binary
logs are read as far as they are valid, with the decoders' own output silenced (checked at the
file-descriptor level with ``capfd``) and one :class:`CorruptDataWarning` giving the counts.
"""

from __future__ import annotations

import io
import json
import os
import pickle
import re
import struct
import subprocess
import sys
import tracemalloc
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.errors import CorruptDataWarning, DataFormatError, InputError, ResourceLimitError
from uasnav.imu import ImuLog, require_log
from uasnav.io import (
    read_csv_table,
    read_dataflash,
    read_dataflash_messages,
    read_flight,
    read_flight_csv,
    read_log,
    read_npz,
    read_tlog,
    read_ulog,
    write_csv_table,
    write_log,
)
from uasnav.io._common import longest_nondecreasing
from uasnav.io._quiet import library_output_captured
from uasnav.io.flight import Flight
from uasnav.io.formats.csv_v1 import parse_csv_v1
from uasnav.io.formats.xio import read_xio_csv

V1_HEAD = "t,gx,gy,gz,ax,ay,az"
XIO_HEAD = (
    "Time (s),Gyroscope X (deg/s),Gyroscope Y (deg/s),Gyroscope Z (deg/s),"
    "Accelerometer X (g),Accelerometer Y (g),Accelerometer Z (g)"
)
FLIGHT_HEAD = "t,lat,lon,alt,v_N,v_E,v_D"
TABLE_HEAD = "a,b,c,d,e,f,g"


def _rows(n: int = 4) -> list[str]:
    return [f"{0.01 * k:.2f},0.1,0.2,0.3,0.4,0.5,0.6" for k in range(n)]


# (reader, header, name of the second column) for every CSV reader
CSV_READERS: dict[str, tuple[Callable[[Path], Any], str, str]] = {
    "csv_v1": (read_log, V1_HEAD, "gx"),
    "xio": (read_xio_csv, XIO_HEAD, "Gyroscope X (deg/s)"),
    "flight": (read_flight_csv, FLIGHT_HEAD, "lat"),
    "table": (read_csv_table, TABLE_HEAD, "b"),
}


def _write(path: Path, text: str | bytes) -> Path:
    path.write_bytes(text if isinstance(text, bytes) else text.encode("utf-8"))
    return path


@pytest.fixture(params=sorted(CSV_READERS))
def csv_reader(request: pytest.FixtureRequest) -> tuple[Callable[[Path], Any], str, str]:
    return CSV_READERS[request.param]


# --- CSV: one DataFormatError naming file, line and column ---------------------------------


def test_stray_quote_names_line_and_column(tmp_path: Path, csv_reader: Any) -> None:
    reader, head, col = csv_reader
    rows = _rows(5)
    rows[2] = rows[2].replace(",0.1,", ',"0.1,', 1)  # opens a quoted cell that never closes
    p = _write(tmp_path / "q.csv", "\n".join([head, *rows]) + "\n")
    with pytest.raises(
        DataFormatError, match=rf"q\.csv, line 4, column '{re.escape(col)}'.*unbalanced '\"'"
    ) as e:
        reader(p)
    assert (e.value.line, e.value.column) == (4, col)


def test_cell_beyond_the_csv_field_limit(tmp_path: Path, csv_reader: Any) -> None:
    # 128 KiB is csv.field_size_limit(): before, this was a bare _csv.Error (a traceback)
    reader, head, col = csv_reader
    rows = _rows(4)
    rows[1] = rows[1].replace(",0.1,", "," + "1" * (128 * 1024 + 10) + ",", 1)
    p = _write(tmp_path / "big.csv", "\n".join([head, *rows]) + "\n")
    with pytest.raises(
        DataFormatError, match=rf"line 3, column '{re.escape(col)}': a cell of more than 131072"
    ) as e:
        reader(p)
    assert len(str(e.value)) < 300  # the cell itself is not echoed


def test_nul_byte_names_line_and_column(tmp_path: Path, csv_reader: Any) -> None:
    reader, head, col = csv_reader
    rows = _rows(4)
    rows[2] = rows[2].replace(",0.1,", ",0.\x001,", 1)
    p = _write(tmp_path / "nul.csv", "\n".join([head, *rows]) + "\n")
    with pytest.raises(DataFormatError, match=rf"nul\.csv, line 4, column '{re.escape(col)}': NUL byte"):
        reader(p)


@pytest.mark.parametrize(
    ("encoding", "pattern"),
    [
        ("latin-1", r"line 3, column '{col}': not UTF-8 text: byte 0xe9"),
        ("utf-16", r"line 1: a UTF-16 text file; save it as UTF-8"),
        ("utf-32", r"line 1: a UTF-32 text file"),
    ],
)
def test_wrong_encodings(tmp_path: Path, csv_reader: Any, encoding: str, pattern: str) -> None:
    reader, head, col = csv_reader
    rows = _rows(4)
    rows[1] = rows[1].replace(",0.1,", ",0.1é,", 1)
    p = _write(tmp_path / "enc.csv", "\n".join([head, *rows]).encode(encoding))
    with pytest.raises(DataFormatError, match=pattern.format(col=re.escape(col))):
        reader(p)


def test_utf8_bom_in_the_header_is_accepted(tmp_path: Path, csv_reader: Any) -> None:
    # before: "missing column t" while the header shows t
    reader, head, _ = csv_reader
    p = _write(tmp_path / "bom.csv", b"\xef\xbb\xbf" + ("\n".join([head, *_rows(4)]) + "\n").encode())
    out = reader(p)
    t = out[0]["a"] if isinstance(out, tuple) else out.t
    assert t.size == 4 and t[0] == 0.0


def test_bom_before_comment_lines_of_csv_v1(tmp_path: Path) -> None:
    text = "# rate_hz: 100\n" + "\n".join([V1_HEAD, *_rows(4)]) + "\n"
    log = read_log(_write(tmp_path / "bomc.csv", b"\xef\xbb\xbf" + text.encode()))
    assert log.meta["rate_hz"] == "100" and log.n == 4


def test_line_numbers_survive_crlf_blank_lines_and_form_feeds(tmp_path: Path) -> None:
    # str.splitlines() would also split at \x0c and shift every later line number
    rows = _rows(5)
    rows[1] = rows[1] + ",\x0c"  # an extra cell: a ragged row
    text = "\r\n".join(["# c", V1_HEAD, rows[0], "", rows[1], *rows[2:]]) + "\r\n"
    with pytest.raises(DataFormatError, match=r"line 5: expected 7 cells, got 8"):
        read_log(_write(tmp_path / "crlf.csv", text))
    rows = _rows(5)
    rows[3] = rows[3].replace("0.3", "x")
    text = "\r\n".join(["# c", V1_HEAD, rows[0], "", *rows[1:]]) + "\r\n"
    with pytest.raises(DataFormatError, match=r"line 7, column 'gz': not a number: 'x'"):
        read_log(_write(tmp_path / "crlf.csv", text))


def test_time_errors_show_numbers_as_typed(tmp_path: Path) -> None:
    rows = _rows(4)
    rows[2] = rows[1]
    with pytest.raises(
        DataFormatError, match=r"line 4, column 't': duplicated time stamp \(0.01 then 0.01\)"
    ):
        read_log(_write(tmp_path / "dup.csv", "\n".join([V1_HEAD, *rows]) + "\n"))


def test_table_reader_refuses_inf_like_the_writer(tmp_path: Path) -> None:
    p = _write(tmp_path / "tab.csv", "a,b\n1,nan\n2,inf\n")
    with pytest.raises(DataFormatError, match=r"line 3, column 'b': infinite value 'inf'"):
        read_csv_table(p)
    write_csv_table(tmp_path / "ok.csv", {"a": [1.0, 2.0], "b": [np.nan, 3.0]})
    cols, _ = read_csv_table(tmp_path / "ok.csv")
    assert np.isnan(cols["b"][0]) and cols["b"][1] == 3.0


def test_flight_csv_refuses_positions_off_the_globe(tmp_path: Path) -> None:
    p = _write(tmp_path / "f.csv", f"{FLIGHT_HEAD}\n0,45,7,100,0,0,0\n1,95,7,100,0,0,0\n")
    with pytest.raises(DataFormatError, match=r"line 3, column 'lat': 95.0 is outside \[-90, 90\]"):
        read_flight(p)


def test_text_size_limit_is_on_bytes_read(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # /dev/zero reports size 0 and never ends: the limit must hold on the bytes read
    monkeypatch.setenv("UASNAV_MAX_MEMORY", "1M")  # → 128 KiB of text
    zero = tmp_path / "zero.csv"
    zero.symlink_to("/dev/zero")
    with pytest.raises(ResourceLimitError, match=r"zero\.csv: larger than 128.0 KiB.*UASNAV_MAX_MEMORY"):
        read_log(zero)
    big = _write(tmp_path / "big.csv", "\n".join([V1_HEAD, *_rows(10_000)]) + "\n")
    with pytest.raises(ResourceLimitError, match="UASNAV_MAX_MEMORY"):
        read_log(big)
    monkeypatch.setenv("UASNAV_MAX_MEMORY", "64M")
    assert read_log(big).n == 10_000


def test_directory_and_missing_files(tmp_path: Path, csv_reader: Any) -> None:
    reader, _, _ = csv_reader
    d = tmp_path / "dir.csv"
    d.mkdir()
    with pytest.raises(DataFormatError, match=r"dir\.csv: is a directory"):
        reader(d)
    with pytest.raises(InputError, match="no such"):
        reader(tmp_path / "missing.csv")


def test_flight_reader_names_non_regular_files(tmp_path: Path) -> None:
    d = tmp_path / "dir.tlog"
    d.mkdir()
    with pytest.raises(InputError, match=r"dir\.tlog: not a regular file"):
        read_flight(d)
    z = tmp_path / "zero.bin"
    z.symlink_to("/dev/zero")
    with pytest.raises(InputError, match=r"zero\.bin: not a regular file"):
        read_flight(z)
    with pytest.raises(DataFormatError, match=r"zero\.bin: not a regular file"):
        read_dataflash(z)
    with pytest.raises(InputError, match="expected the CSV text as str"):
        parse_csv_v1(b"t,gx")  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("name", "body", "expected"),
    [
        ("quote.csv", "\n".join([V1_HEAD, *_rows(2), '0.1,"0,0,0,0,0,0'] + _rows(3)[1:]), "unbalanced"),
        ("big.csv", "\n".join([V1_HEAD, *_rows(2), "0.1," + "1" * 140_000 + ",0,0,0,0,0"]), "131072"),
        ("nul.csv", "\n".join([V1_HEAD, *_rows(2), "0.1,0\x00,0,0,0,0,0"]), "NUL byte"),
        ("l1.csv", ("\n".join([V1_HEAD, *_rows(2), "0.1,é,0,0,0,0,0"])).encode("latin-1"), "not UTF-8"),
    ],
)
def test_cli_gives_one_error_line(tmp_path: Path, name: str, body: str | bytes, expected: str) -> None:
    p = _write(tmp_path / name, body)
    r = CliRunner().invoke(main, ["allan", str(p), "--json"])
    assert r.exit_code == 1, r.output
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and expected in lines[0], r.stderr
    assert "internal error" not in r.stderr and r.stdout == ""


# --- npz -------------------------------------------------------------------------------------


def _npz(path: Path, **arrays: Any) -> Path:
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    path.write_bytes(buf.getvalue())
    return path


def _good(n: int = 10) -> dict[str, Any]:
    return {"t": np.arange(n) * 0.01, "gyro": np.zeros((n, 3)), "accel": np.zeros((n, 3))}


class _Boom:
    """Unpickling this would create a file: proof that the reader never unpickles."""

    marker: Path

    def __reduce__(self) -> tuple[Any, ...]:
        return (Path.touch, (self.marker,))


def test_npz_object_arrays_are_refused_without_unpickling(tmp_path: Path) -> None:
    boom = _Boom()
    boom.marker = tmp_path / "pwned"
    obj = np.empty(1, dtype=object)
    obj[0] = boom
    p = _npz(tmp_path / "obj.npz", **{**_good(), "gyro": obj})
    pickle.dumps(boom)  # the object is really picklable: the test could fail
    with pytest.raises(DataFormatError, match=r"obj\.npz, column 'gyro': array 'gyro' holds Python objects"):
        read_npz(p)
    assert not boom.marker.exists()


def test_npz_zip_bomb_is_refused_before_inflating(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("UASNAV_MAX_MEMORY", "16M")
    p = tmp_path / "bomb.npz"
    n = 4_000_000  # 4e6 × 3 float64 = 96 MB of zeros, about 100 kB compressed
    with zipfile.ZipFile(p, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for key, arr in _good(10).items():
            zf.writestr(f"{key}.npy", _npy_bytes(arr))
        with zf.open("mag.npy", "w", force_zip64=True) as fh:
            header = io.BytesIO()
            np.lib.format.write_array_header_1_0(
                header, {"descr": "<f8", "fortran_order": False, "shape": (n, 3)}
            )
            fh.write(header.getvalue())
            chunk = bytes(1 << 20)
            for _ in range(n * 24 // len(chunk)):
                fh.write(chunk)
    assert p.stat().st_size < 1_000_000
    tracemalloc.start()
    try:
        with pytest.raises(ResourceLimitError, match=r"bomb\.npz.*more than the memory limit of 16.0 MiB"):
            read_npz(p)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 4_000_000


def _npy_bytes(arr: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.save(buf, arr)
    return buf.getvalue()


def test_npz_header_claiming_a_huge_array(tmp_path: Path) -> None:
    # a 100-byte member whose header claims 10¹² rows: refused before any allocation
    p = tmp_path / "claim.npz"
    with zipfile.ZipFile(p, "w") as zf:
        for key, arr in _good().items():
            if key != "gyro":
                zf.writestr(f"{key}.npy", _npy_bytes(arr))
        header = io.BytesIO()
        np.lib.format.write_array_header_1_0(
            header, {"descr": "<f8", "fortran_order": False, "shape": (10**12, 3)}
        )
        zf.writestr("gyro.npy", header.getvalue() + bytes(100))
    with pytest.raises(ResourceLimitError, match=r"claim\.npz: array 'gyro' of shape \(1000000000000, 3\)"):
        read_npz(p)
    # a header that promises more than the member holds is corrupt, not a short read later
    with zipfile.ZipFile(p, "w") as zf:
        for key, arr in _good().items():
            data = _npy_bytes(arr)
            zf.writestr(f"{key}.npy", data[:-24] if key == "gyro" else data)
    with pytest.raises(DataFormatError, match=r"array 'gyro': corrupt member"):
        read_npz(p)


@pytest.mark.parametrize(
    ("change", "pattern"),
    [
        ({"gyro": np.zeros((10, 3), dtype=complex)}, r"'gyro' is complex, not real"),
        ({"t": np.array([str(k) for k in range(10)])}, r"'t' is not numeric \(<U1\)"),
        ({"accel": np.zeros((10, 4))}, r"'accel' has shape \(10, 4\), expected \(n, 3\)"),
        ({"accel": np.zeros((9, 3))}, r"accel: expected 10 rows"),
        ({"gyro": np.zeros((10, 3), dtype=bool)}, r"'gyro' is not numeric \(bool\)"),
        ({"meta_json": np.array("[1, 2]")}, r"meta_json must be a JSON object, got list"),
        ({"meta_json": np.array("[" * 100_000 + "]" * 100_000)}, r"meta_json is not usable JSON"),
        ({"meta_json": np.array(["{}", "{}"])}, r"'meta_json' must hold one value"),
        ({"meta_json": np.array(3.0)}, r"meta_json is not a string"),
        ({"truth__": np.zeros(10)}, r"truth array without a name"),
    ],
)
def test_npz_wrong_dtypes_and_shapes(tmp_path: Path, change: dict[str, Any], pattern: str) -> None:
    p = _npz(tmp_path / "bad.npz", **{**_good(), **change})
    with pytest.raises(DataFormatError, match=pattern):
        read_npz(p)


@pytest.mark.parametrize(
    ("rate", "pattern"),
    [
        (np.array([100.0, 200.0]), "must hold one value"),
        (np.array("fast"), "not a real number"),
        (np.nan, "finite"),
    ],
)
def test_npz_adis_rate(tmp_path: Path, rate: Any, pattern: str) -> None:
    p = _npz(tmp_path / "adis.npz", gyro_dps=np.zeros((10, 3)), accel_g=np.zeros((10, 3)), rate_hz=rate)
    with pytest.raises(DataFormatError, match=pattern):
        read_npz(p)


def test_npz_not_an_archive_and_devices(tmp_path: Path) -> None:
    with pytest.raises(DataFormatError, match=r"junk\.npz: not a readable \.npz archive"):
        read_npz(_write(tmp_path / "junk.npz", b"PK\x03\x04" + bytes(64)))
    z = tmp_path / "zero.npz"
    z.symlink_to("/dev/zero")
    with pytest.raises(DataFormatError, match=r"zero\.npz: not a regular file"):
        read_npz(z)


def test_npz_round_trip_still_bit_for_bit(tmp_path: Path) -> None:
    rng = np.random.default_rng(1)
    log = ImuLog(
        t=np.arange(50) * 0.01,
        gyro=rng.normal(size=(50, 3)),
        accel=rng.normal(size=(50, 3)),
        temp=rng.normal(size=50),
        truth={"gyro_bias": rng.normal(size=(50, 3))},
        meta={"a": 1},
    )
    write_log(log, tmp_path / "r.npz")
    back = read_npz(tmp_path / "r.npz")
    assert np.array_equal(back.gyro, log.gyro) and np.array_equal(
        back.truth["gyro_bias"], log.truth["gyro_bias"]
    )
    back.gyro[0, 0] = 1.0  # writable, as np.load's arrays were


# --- corrupt binary logs: silent, counted, one warning ---------------------------------------


def _fmt(type_id: int, length: int, name: str, fmt: str, cols: str) -> bytes:
    return b"\xa3\x95\x80" + struct.pack(
        "<BB4s16s64s", type_id, length, name.encode(), fmt.encode(), cols.encode()
    )


def _dataflash(t_us: np.ndarray, gyro: np.ndarray, accel: np.ndarray, garbage: int = 0) -> bytes:
    """A minimal ArduPilot DataFlash log: FMT, then one IMU record per row (TimeUS, GyrXYZ, AccXYZ)."""
    out = [
        _fmt(0x80, 89, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns"),
        _fmt(129, 35, "IMU", "Qffffff", "TimeUS,GyrX,GyrY,GyrZ,AccX,AccY,AccZ"),
    ]
    for k, (t, g, a) in enumerate(zip(t_us, gyro, accel, strict=True)):
        if garbage and k == len(t_us) // 2:
            out.append(
                bytes(7 + k % 150 for k in range(garbage))
            )  # bytes without a header: "bad header" lines
        out.append(b"\xa3\x95\x81" + struct.pack("<Q6f", int(t), *g, *a))
    return b"".join(out)


def _imu_rows(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.arange(n, dtype=np.int64) * 20_000 + 1_000_000
    return t, np.full((n, 3), 0.01), np.tile([0.0, 0.0, -9.81], (n, 1))


def test_dataflash_corrupt_records_are_dropped_counted_and_reported_once(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    t, g, a = _imu_rows(200)
    g[50, 1] = np.nan  # non-finite
    a[60, 2] = 1e30  # a flipped exponent bit
    t[70] -= 500_000  # time out of order
    t[80] += 2**40  # a flipped high time bit
    p = _write(tmp_path / "bad.bin", _dataflash(t, g, a, garbage=600))
    with pytest.warns(CorruptDataWarning) as rec:
        logs = read_dataflash(p)
    assert len(rec) == 1
    msg = str(rec[0].message)
    assert "bad.bin: corrupt data skipped" in msg and "4 of 200 IMU records dropped" in msg
    assert "600 of 7778 bytes could not be decoded" in msg  # the garbage bytes
    log = logs["IMU"]
    assert log.n == 196 and np.all(np.diff(log.t) > 0) and np.all(np.abs(log.accel) < 100)
    assert log.meta["corrupt_records_dropped"] == 4 and "bytes could not be decoded" in log.meta["corruption"]
    out, err = capfd.readouterr()
    assert out == "" and err == ""  # pymavlink's "bad header …" lines are silenced


def test_dataflash_clean_log_is_quiet(tmp_path: Path, recwarn: pytest.WarningsRecorder) -> None:
    p = _write(tmp_path / "ok.bin", _dataflash(*_imu_rows(50)))
    log = read_dataflash(p)["IMU"]
    assert log.n == 50 and "corrupt_records_dropped" not in log.meta
    assert not [w for w in recwarn if issubclass(w.category, CorruptDataWarning)]


def test_dataflash_with_nothing_valid_left_fails(tmp_path: Path) -> None:
    t, g, a = _imu_rows(20)
    g[:] = np.inf
    p = _write(tmp_path / "dead.bin", _dataflash(t, g, a))
    with pytest.raises(DataFormatError, match=r"dead\.bin: fewer than 2 valid IMU records among 20"):
        read_dataflash(p)


def test_dataflash_message_reader_drops_only_time_disorder(tmp_path: Path) -> None:
    t, g, a = _imu_rows(5)
    t[2] += 10**12  # a flipped high time bit
    g[3] = np.nan  # generic fields may legitimately be NaN: kept as logged
    with pytest.warns(CorruptDataWarning, match="1 of 5 message records dropped"):
        tables = read_dataflash_messages(_write(tmp_path / "m.bin", _dataflash(t, g, a)), ["IMU"])
    imu = tables["IMU"]
    assert imu["t"].size == 4 and np.all(np.diff(imu["t"]) > 0) and np.isnan(imu["GyrX"][2])


def _flip_bits(src: Path, dst: Path, count: int, start: float, seed: int) -> Path:
    """A copy of ``src`` with ``count`` random bits flipped after ``start`` (a byte offset, or a
    fraction of the file if < 1)."""
    data = bytearray(src.read_bytes())
    rng = np.random.default_rng(seed)
    first = int(len(data) * start) if start < 1 else int(start)
    for i in rng.integers(first, len(data), count):
        data[i] ^= 1 << int(rng.integers(0, 8))
    dst.write_bytes(bytes(data))
    return dst


@pytest.fixture(scope="module")
def flipped(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("flipped")
    return {
        "bin": _flip_bits(shared_data / "logs" / "ardupilot_log171.bin", d / "f.bin", 2000, 0.0, 1),
        "tlog": _flip_bits(
            shared_data / "flights" / "phoenix_mission1_arducopter.tlog", d / "f.tlog", 2000, 0.0, 1
        ),
        "ulg": _flip_bits(shared_data / "logs" / "px4_sample.ulg", d / "f.ulg", 300, 0.5, 3),
        "ulg_head": _flip_bits(shared_data / "logs" / "px4_sample_log_small.ulg", d / "h.ulg", 500, 5000, 2),
    }


def test_real_dataflash_with_flipped_bits(
    flipped: dict[str, Path], capfd: pytest.CaptureFixture[str]
) -> None:
    with pytest.warns(CorruptDataWarning) as rec:
        logs = read_dataflash(flipped["bin"])
    # pymavlink stops indexing at a record of unknown type: most of this log is lost, and says so
    assert len(rec) == 1 and re.search(r"\d+ of 2981888 bytes could not be decoded", str(rec[0].message))
    assert sorted(logs) == ["IMU", "IMU2", "IMU3"]
    for log in logs.values():
        assert 1000 < log.n < 11916 and np.all(np.diff(log.t) > 0)
        assert np.all(np.abs(log.gyro) <= 100) and np.all(np.abs(log.accel) <= 4000)
    with pytest.warns(CorruptDataWarning):
        flight = read_flight(flipped["bin"])
    assert flight.t.size > 10 and np.all(np.abs(flight.lat) <= 90)
    out, err = capfd.readouterr()
    assert out == "" and err == ""  # was ~1000 lines of "bad header …"


def test_real_tlog_with_flipped_bits(flipped: dict[str, Path], capfd: pytest.CaptureFixture[str]) -> None:
    with pytest.warns(CorruptDataWarning, match=r"f\.tlog: .*MAVLink message\(s\) failed their checksum"):
        logs = read_tlog(flipped["tlog"])
    assert "SCALED_IMU2" in logs
    with pytest.warns(CorruptDataWarning, match=r"position fix records dropped"):
        flight = read_flight(flipped["tlog"])
    assert np.all(np.diff(flight.t) > 0) and np.all(np.abs(flight.lat) <= 90)
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_real_ulog_with_flipped_bits(flipped: dict[str, Path], capfd: pytest.CaptureFixture[str]) -> None:
    with pytest.warns(CorruptDataWarning, match=r"f\.ulg: corrupt data skipped") as rec:
        log = read_ulog(flipped["ulg"])
    assert len(rec) == 1
    assert 10_000 < log.n < 17070 and log.meta["corrupt_records_dropped"] >= 0
    with pytest.raises(DataFormatError, match=r"h\.ulg: corrupt ULog: no topic could be read"):
        read_ulog(flipped["ulg_head"])
    out, err = capfd.readouterr()
    assert out == "" and err == ""  # pyulog prints its notices to stdout: --json must stay clean


def test_cli_on_a_corrupt_log_prints_no_decoder_output(tmp_path: Path) -> None:
    # a real process: the decoder's fd-level output and Python's warning display are both real
    t, g, a = _imu_rows(400)
    a[100, 0] = 1e30
    p = _write(tmp_path / "c.bin", _dataflash(t, g, a, garbage=2000))
    code = "import sys; from uasnav.cli import main; sys.argv[0] = 'uasnav'; main()"
    r = subprocess.run(
        [sys.executable, "-c", code, "allan", str(p), "--json", "--rate", "50"],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert r.returncode == 0, r.stderr
    json.loads(r.stdout)  # stdout is clean JSON
    assert "corrupt data skipped" in r.stderr and "1 of 400 IMU records dropped" in r.stderr
    assert len(r.stderr.splitlines()) <= 2, r.stderr  # was one line per bad byte


def test_library_output_captured_counts_python_and_fd_output(capfd: pytest.CaptureFixture[str]) -> None:
    with library_output_captured() as out:
        print("one")
        print("two", file=sys.stderr)
        os.write(1, b"three\nfour\n")
        os.write(2, b"five")
    assert out.lines == 2 and out.example == "one"  # fd-level output is discarded, not counted
    o, e = capfd.readouterr()
    assert o == "" and e == ""
    print("after")  # the streams are restored
    assert capfd.readouterr().out == "after\n"


def test_longest_nondecreasing_keeps_the_longest_run_in_order() -> None:
    t = np.array([1.0, 2.0, 3.0, 1e12, 4.0, 0.5, 5.0, 5.0, 6.0])
    assert longest_nondecreasing(t).tolist() == [True, True, True, False, True, False, True, True, True]
    assert longest_nondecreasing(np.arange(5.0)).all()


# --- ImuLog and Flight given something that is not data -----------------------------------


@pytest.mark.parametrize(
    ("kw", "pattern"),
    [
        ({"t": "abc"}, r"t: expected an array of numbers, got str"),
        ({"t": None}, r"t: expected an array of numbers, got NoneType"),
        ({"gyro": [[0, 0, 0], [1]]}, r"gyro: expected an array of real numbers"),
        ({"accel": [[1j, 0, 0], [0, 0, 0]]}, r"accel: expected an array of real numbers"),
        ({"t": [{}, {}]}, r"t: expected an array of real numbers"),
        ({"truth": [1, 2]}, r"truth: expected a mapping"),
        ({"truth": {"b": "xy"}}, r"truth\['b'\]: expected an array of numbers"),
        ({"truth": {3: [0, 0]}}, r"truth: channel names must be non-empty strings"),
        ({"meta": 3}, r"meta: expected a mapping"),
    ],
)
def test_imulog_refuses_non_data_with_input_error(kw: dict[str, Any], pattern: str) -> None:
    base: dict[str, Any] = {"t": [0.0, 0.1], "gyro": np.zeros((2, 3)), "accel": np.zeros((2, 3))}
    with pytest.raises(InputError, match=pattern):
        ImuLog(**{**base, **kw})


def test_non_logs_give_input_error(tmp_path: Path) -> None:
    with pytest.raises(InputError, match=r"log: expected an ImuLog .* got str"):
        require_log("flight.csv")
    with pytest.raises(InputError, match="expected an ImuLog"):
        write_log("not a log", tmp_path / "x.csv")  # type: ignore[arg-type]
    assert not (tmp_path / "x.csv").exists()
    log = ImuLog(t=np.arange(10) * 0.1, gyro=np.zeros((10, 3)), accel=np.zeros((10, 3)))
    assert require_log(log) is log
    with pytest.raises(InputError, match="rate: expected a number"):
        log.resample("fast")  # type: ignore[arg-type]
    with pytest.raises(ResourceLimitError, match="resample at 1e\\+12 Hz"):
        log.resample(1e12)
    with pytest.raises(InputError, match="t_start: expected a number"):
        log.between("a", 1.0)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kw", "pattern"),
    [
        ({"lat": [45.0, np.nan]}, r"non-finite lat at sample 1"),
        ({"vel_ned": np.zeros((2, 2))}, r"vel_ned has shape \(2, 2\)"),
        ({"alt": [1.0]}, r"alt has shape \(1,\)"),
        ({"lon": ["a", "b"]}, r"lon is not numeric"),
        ({"wind_ne": [np.inf, 0.0]}, r"wind_ne must be a finite"),
        ({"cruise_ms": float("nan")}, r"cruise speed"),
    ],
)
def test_flightlog_validates(kw: dict[str, Any], pattern: str) -> None:
    base: dict[str, Any] = {
        "t": [0.0, 1.0],
        "lat": [45.0, 45.1],
        "lon": [7.0, 7.1],
        "alt": [100.0, 101.0],
        "vel_ned": np.zeros((2, 3)),
        "source": "f.csv",
    }
    with pytest.raises(InputError, match=pattern):
        Flight.from_track(**{**base, **kw})
