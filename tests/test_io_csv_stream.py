"""The CSV engine (``uasnav.io._csvstream``): log format v1 and every other numeric CSV read in
chunks through the extension's parser give the same values bit for bit and the same errors (message,
line, column) as the whole-text row-by-row reader, whatever the chunk size; memory is refused
early and realistically; the calibration's block means computed while reading equal the
in-memory ones; every base-install reader works with pyarrow unimportable."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from uasnav.cli import main
from uasnav.errors import DataFormatError, InputError, ResourceLimitError
from uasnav.imu import ImuLog
from uasnav.io import _csvstream, _text, read_log
from uasnav.io._text import read_text
from uasnav.io.formats.csv_v1 import open_csv_v1, parse_csv_v1, read_csv_v1, write_csv_v1
from uasnav.thermal import load_training_data
from uasnav.thermal._common import check_training_temp
from uasnav.thermal.binning import TimeBlockMeans, bin_by_time

HEAD = "t,gx,gy,gz,ax,ay,az,temp,extra,truth_gyro_bias_x,truth_gyro_bias_y,truth_gyro_bias_z"


def _same(path: Path) -> None:
    """read_csv_v1(path) (chunks) and the whole-text reader, row by row (csv and float), agree
    exactly."""
    try:
        with pytest.MonkeyPatch.context() as slow:
            slow.setattr(_text, "_numeric_rows_fast", lambda *a: None)
            want = parse_csv_v1(read_text(path), source=str(path))
    except DataFormatError as e:
        with pytest.raises(DataFormatError) as got:
            read_csv_v1(path)
        assert str(got.value) == str(e)
        assert (got.value.line, got.value.column) == (e.line, e.column)
        return
    got = read_csv_v1(path)
    for name in ("t", "gyro", "accel", "temp"):
        assert getattr(got, name).tobytes() == getattr(want, name).tobytes(), name
    assert got.truth.keys() == want.truth.keys()
    assert all(got.truth[k].tobytes() == want.truth[k].tobytes() for k in want.truth)
    assert got.meta == want.meta


cells = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False, width=64).map(repr),
    st.integers(-(10**6), 10**6).map(str),
    st.sampled_from([" 1.5", "2 ", "+.5", "1_0", "1e-300", "-0.0", "1e400", "x", "", "nan", "٣"]),
    # the extension's parser: plain syntax it reads, and everything it hands over
    st.sampled_from(["5.", ".5", "+1", "1E+05", "\t2.5\t", "4.9406564584124654e-324", "2.2250738585e-308"]),
    st.sampled_from(["-nan", "NaN", "inf", "-Infinity", "0x10", "1d5", "e5", ".", "1.5.2", "\x0c1", "1\x7f"]),
    st.from_regex(r"\A[ \t]?[+-]?[0-9]{0,25}\.?[0-9]{0,25}([eE][+-]?[0-9]{1,4})?[ \t]?\Z", fullmatch=True),
)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.lists(cells, min_size=10, max_size=10), min_size=0, max_size=40),
    st.sampled_from(["\n", "\r\n", "\r"]),
    st.integers(60, 400),
    st.booleans(),
    st.sampled_from(["", "quote", "nul", "latin1", "short", "long", "blank", "decrease"]),
)
def test_chunks_equal_the_whole_text_reader(tmp_path_factory, rows, nl, chunk, increasing, hostile) -> None:
    lines = ["# sensor: x", "", HEAD]
    for k, r in enumerate(rows):
        t = repr(0.01 * k) if increasing else r[0]
        extra = "note é" if k % 7 == 3 else "1"
        lines.append(",".join([t, *r[1:8], extra, *r[7:10]]))
    if rows:
        at = 3 + len(rows) // 2
        if hostile == "quote":
            lines[at] = lines[at].replace(",", ',"', 1)
        elif hostile == "nul":
            lines[at] += "\x00"
        elif hostile == "short":
            lines[at] = lines[at].rsplit(",", 1)[0]
        elif hostile == "long":
            lines[at] += ",1"
        elif hostile == "blank":
            lines.insert(at, "   ")
        elif hostile == "decrease":
            lines[at] = "-1" + lines[at][lines[at].index(",") :]
    text = nl.join(lines) + nl
    raw = text.encode("utf-8")
    if hostile == "latin1" and rows:
        raw = raw.replace("é".encode(), b"\xe9", 1)
    path = tmp_path_factory.mktemp("s") / "log.csv"
    path.write_bytes(raw)
    mp = pytest.MonkeyPatch()
    mp.setattr(_csvstream, "chunk_bytes", lambda: chunk)
    try:
        _same(path)
    finally:
        mp.undo()


def _sim_log(n: int = 3000, seed: int = 0) -> ImuLog:
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 0.01 + 1.0 / 3.0
    temp = np.linspace(-10.0, 40.0, n) + rng.normal(0, 0.01, n)
    return ImuLog(
        t=t,
        gyro=rng.normal(size=(n, 3)) * 1e-3 + 1e-4 * temp[:, None],
        accel=rng.normal(size=(n, 3)) + [0, 0, -9.81],
        temp=temp,
        truth={"gyro_bias": rng.normal(size=(n, 3)) * 1e-4, "temp_die": temp},
        meta={"rate_hz": "100"},
    )


@pytest.fixture
def small_chunks(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(_csvstream, "chunk_bytes", lambda: 16 * 1024)


def test_clean_log_never_goes_row_by_row(tmp_path: Path, small_chunks: None, monkeypatch) -> None:
    log = _sim_log()
    p = tmp_path / "a.csv"
    write_csv_v1(log, p)

    def refuse(*a, **k):
        raise AssertionError("row-by-row reader used on a clean chunk")

    monkeypatch.setattr(_csvstream.NumericCsv, "_row_by_row", refuse)
    back = read_csv_v1(p)
    assert back.t.tobytes() == log.t.tobytes() and back.gyro.tobytes() == log.gyro.tobytes()
    with open_csv_v1(p) as s:
        assert sum(1 for _ in s.blocks()) > 5  # many chunks


def test_errors_far_apart_are_reported_in_the_whole_text_order(tmp_path: Path, small_chunks: None) -> None:
    log = _sim_log()
    p = tmp_path / "a.csv"
    write_csv_v1(log, p)
    lines = p.read_text().splitlines()
    base = list(lines)
    # a decreasing time stamp early, a bad cell late: the bad cell wins (cells are parsed first)
    lines[30] = "0" + lines[30][lines[30].index(",") :]
    lines[-5] = lines[-5].replace(",", ",x", 1)
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataFormatError, match=rf"line {len(lines) - 4}, column 'gx': not a number"):
        read_csv_v1(p)
    # ... and a NUL byte later still wins over both (the whole text is decoded first)
    p.write_bytes(("\n".join(lines) + "\n").encode() + b"1\x00\n")
    with pytest.raises(DataFormatError, match=rf"line {len(lines) + 1}.*NUL byte"):
        read_csv_v1(p)
    # the time error alone, many chunks after the first
    base[-40] = "0" + base[-40][base[-40].index(",") :]
    p.write_text("\n".join(base) + "\n")
    with pytest.raises(DataFormatError, match=rf"line {len(base) - 39}, column 't': decreasing"):
        read_csv_v1(p)


def test_memory_is_checked_on_the_projected_log(tmp_path: Path, monkeypatch) -> None:
    p = tmp_path / "a.csv"
    write_csv_v1(_sim_log(20_000), p)  # ≈ 5 MB of text, 20 000 × 12 numbers
    monkeypatch.setenv("UASNAV_MAX_MEMORY", "4M")
    with pytest.raises(
        ResourceLimitError, match=r"a\.csv: a CSV v1 log of about 1\.9\de\+04 rows × 12 columns needs about"
    ):
        read_csv_v1(p)
    # the log's own size decides, not the text's: 6 MB of numbers pass a 16 MB limit
    monkeypatch.setenv("UASNAV_MAX_MEMORY", "16M")
    assert read_csv_v1(p).n == 20_000


def test_block_means_while_reading_equal_the_in_memory_ones(tmp_path: Path, small_chunks: None) -> None:
    log = _sim_log(6000)
    p = tmp_path / "a.csv"
    write_csv_v1(log, p)
    for seconds in (1.0, 0.37, 2.0):
        temp, bias = load_training_data(p, seconds)
        ref_t, ref_b = bin_by_time(log.t, log.temp, log.gyro, seconds)
        assert temp.shape == ref_t.shape and bias.shape == ref_b.shape
        np.testing.assert_allclose(temp, ref_t, rtol=1e-14, atol=0)
        np.testing.assert_allclose(bias, ref_b, rtol=1e-12, atol=1e-20)
    # the accumulator alone, fed in uneven pieces
    acc = TimeBlockMeans(0.5)
    for a, b in ((0, 1), (1, 700), (700, 701), (701, 6000)):
        acc.add(log.t[a:b], log.temp[a:b], log.gyro[a:b])
    tm, vm = acc.result()
    ref_t, ref_b = bin_by_time(log.t, log.temp, log.gyro, 0.5)
    np.testing.assert_allclose(tm, ref_t, rtol=1e-14)
    np.testing.assert_allclose(vm, ref_b, rtol=1e-12, atol=1e-20)


def test_streamed_calibration_errors_match_the_in_memory_path(tmp_path: Path, small_chunks: None) -> None:
    log = _sim_log(4000)
    temp = log.temp.copy()
    temp[[1500, 2500, 3900]] = [250.0, -150.0, 300.0]
    bad = ImuLog(t=log.t, gyro=log.gyro, accel=log.accel, temp=temp)
    p = tmp_path / "hot.csv"
    write_csv_v1(bad, p)
    with pytest.raises(InputError) as want:
        check_training_temp(read_log(p).temp, f"{p}: temp")
    with pytest.raises(InputError) as got:
        load_training_data(p)
    assert (
        str(got.value) == str(want.value) and "row 1500" in str(got.value) and "3 such rows" in str(got.value)
    )
    ok = tmp_path / "ok.csv"
    write_csv_v1(log, ok)
    with pytest.raises(InputError, match=r"too short for a log of 39\.99 s"):
        load_training_data(ok, 1e-300)
    nt = tmp_path / "notemp.csv"
    write_csv_v1(ImuLog(t=log.t, gyro=log.gyro, accel=log.accel), nt)
    with pytest.raises(InputError, match="no temp column"):
        load_training_data(nt)


def test_calibrate_a_log_larger_than_the_memory_limit_allows_reading(tmp_path: Path, monkeypatch) -> None:
    """The soak log case in small: the whole log does not fit the limit, its block means do."""
    p = tmp_path / "soak.csv"
    write_csv_v1(_sim_log(40_000), p)
    monkeypatch.setenv("UASNAV_MAX_MEMORY", "8M")
    with pytest.raises(ResourceLimitError):
        read_log(p)
    out = tmp_path / "m.json"
    r = CliRunner().invoke(main, ["calibrate", str(p), "--method", "poly", "--out", str(out), "--json"])
    assert r.exit_code == 0, r.output
    assert out.is_file() and '"n_samples": 400' in r.output


def _select_all(header: list[str], header_line: int) -> list[str]:
    return header


def _select_two(header: list[str], header_line: int) -> list[str]:
    if "b" not in header:
        raise DataFormatError("no column b", path="x", line=header_line)
    return ["c", "a"] if "c" in header else ["a"]


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.lists(cells, min_size=3, max_size=3), min_size=0, max_size=40),
    st.sampled_from(["\n", "\r\n", "\r"]),
    st.integers(40, 300),
    st.booleans(),
    st.booleans(),
    st.sampled_from(["", "quote", "nul", "latin1", "short", "long", "blank", "inf", "nan"]),
)
def test_any_table_in_chunks_equals_the_whole_text_reader(
    tmp_path_factory, rows, nl, chunk, exact, nan_ok, hostile
) -> None:
    """read_table (the numeric tables, GNSS, x-io and flight CSVs) against the row-by-row
    reader of the whole text (csv and float, no numpy), for every option of the engine."""
    lines = ["# unit: m", "a,b,c"]
    lines += [",".join(r) for r in rows]
    if rows:
        at = 2 + len(rows) // 2
        lines[at] = {
            "quote": lines[at].replace(",", ',"', 1),
            "nul": lines[at] + "\x00",
            "short": lines[at].rsplit(",", 1)[0],
            "long": lines[at] + ",1",
            "blank": "  ",
            "inf": "inf" + lines[at][lines[at].index(",") :],
            "nan": "nan" + lines[at][lines[at].index(",") :],
            "latin1": lines[at] + "é",
        }.get(hostile, lines[at])
    raw = (nl.join(lines) + nl).encode("utf-8")
    if hostile == "latin1":
        raw = raw.replace("é".encode(), b"\xe9", 1)
    path = tmp_path_factory.mktemp("t") / "t.csv"
    path.write_bytes(raw)
    for select in (_select_all, _select_two):
        kw = {"what": "table", "exact_width": exact, "nan_ok": nan_ok, "min_rows": 2 if exact else 0}
        try:
            with pytest.MonkeyPatch.context() as slow:  # the reference: every row by csv and float
                slow.setattr(_text, "_numeric_rows_fast", lambda *a: None)
                want = _csvstream._read_whole(str(path), select, "empty", exact, nan_ok, kw["min_rows"])
        except DataFormatError as e:
            mp = pytest.MonkeyPatch()
            mp.setattr(_csvstream, "chunk_bytes", lambda: chunk)
            try:
                with pytest.raises(DataFormatError) as got:
                    _csvstream.read_table(path, select, **kw)
            finally:
                mp.undo()
            assert (str(got.value), got.value.line, got.value.column) == (str(e), e.line, e.column)
            continue
        mp = pytest.MonkeyPatch()
        mp.setattr(_csvstream, "chunk_bytes", lambda: chunk)
        try:
            got = _csvstream.read_table(path, select, **kw)
        finally:
            mp.undo()
        assert got.columns.keys() == want.columns.keys()
        assert all(got.columns[c].tobytes() == want.columns[c].tobytes() for c in want.columns)
        assert (got.header, got.header_line, got.comments) == (want.header, want.header_line, want.comments)
        for r in range(got.rows):
            assert got.row_line(r) == want.row_line(r)


def test_clean_tables_never_go_row_by_row(tmp_path: Path, small_chunks: None, monkeypatch) -> None:
    """The GNSS, x-io, flight and numeric-table readers parse clean files in the extension's
    parser alone, NaN of a numeric table included."""
    from uasnav.io import read_csv_table, write_csv_table
    from uasnav.io.formats.flight_csv import read_flight_csv
    from uasnav.io.formats.gnss_csv import read_gnss_csv, write_gnss_csv
    from uasnav.io.formats.xio import read_xio_csv
    from uasnav.sim.flight import simulate_flight

    def refuse(*a, **k):
        raise AssertionError("row-by-row reader used on a clean chunk")

    n = 2000
    x = np.linspace(0.0, 1.0, n)
    x[5] = np.nan
    write_csv_table(tmp_path / "t.csv", {"t": np.arange(n) * 0.1, "x": x}, comments={"unit": "m"})
    f = simulate_flight(duration_s=60.0, seed=1)
    write_gnss_csv(tmp_path / "g.csv", f.gnss)
    head = "Time (s),Gyroscope X (deg/s),Gyroscope Y (deg/s),Gyroscope Z (deg/s),"
    head += "Accelerometer X (g),Accelerometer Y (g),Accelerometer Z (g)"
    rows = "\n".join(f"{0.01 * k!r},0.1,0.2,0.3,0,0,1" for k in range(n))
    (tmp_path / "x.csv").write_text(head + "\n" + rows + "\n")
    track = "\n".join(f"{k},{45 + k * 1e-6!r},7.5,100,1,0,0" for k in range(n))
    (tmp_path / "f.csv").write_text("t,lat,lon,alt,v_N,v_E,v_D\n" + track + "\n")
    monkeypatch.setattr(_csvstream.NumericCsv, "_row_by_row", refuse)
    cols, notes = read_csv_table(tmp_path / "t.csv")
    assert np.isnan(cols["x"][5]) and cols["x"][6] == x[6] and notes == {"unit": "m"}
    assert read_gnss_csv(tmp_path / "g.csv").t.tobytes() == f.gnss.t.tobytes()
    assert read_xio_csv(tmp_path / "x.csv").n == n
    assert read_flight_csv(tmp_path / "f.csv").t.size == n


def test_table_errors_name_the_row_of_a_chunked_file(tmp_path: Path, small_chunks: None) -> None:
    """A value error found after reading (time, range) names the file line of its row, found
    again in the chunk that holds it."""
    from uasnav.io.formats.flight_csv import read_flight_csv
    from uasnav.io.formats.xio import read_xio_csv

    n = 3000
    track = [f"{k},{45 + k * 1e-6!r},7.5,100,1,0,0" for k in range(n)]
    track[2500] = "2500,95.5,7.5,100,1,0,0"
    (tmp_path / "f.csv").write_text("# flight\nt,lat,lon,alt,v_N,v_E,v_D\n" + "\n".join(track) + "\n")
    with pytest.raises(DataFormatError) as e:
        read_flight_csv(tmp_path / "f.csv")
    assert (e.value.line, e.value.column) == (2503, "lat") and "95.5 is outside [-90, 90]" in str(e.value)
    head = "Time (s),Gyroscope X (deg/s),Gyroscope Y (deg/s),Gyroscope Z (deg/s),"
    head += "Accelerometer X (g),Accelerometer Y (g),Accelerometer Z (g)"
    rows = [f"{0.01 * k!r},0.1,0.2,0.3,0,0,1" for k in range(n)]
    rows[2000] = "0.5,0.1,0.2,0.3,0,0,1"
    (tmp_path / "x.csv").write_text(head + "\n" + "\n".join(rows) + "\n")
    with pytest.raises(DataFormatError) as e:
        read_xio_csv(tmp_path / "x.csv")
    assert (e.value.line, e.value.column) == (2002, "Time (s)")


def test_every_base_reader_works_without_pyarrow(tmp_path: Path) -> None:
    """pyarrow unimportable (as in a base install): CSV v1 (whole, streamed, calibration block
    means), numeric tables, GNSS, x-io and flight CSVs and npz read, with their own errors, and
    nothing imports pyarrow on the way."""
    script = textwrap.dedent(
        f"""
        import sys
        sys.modules["pyarrow"] = None  # any import of pyarrow now fails
        from pathlib import Path
        import numpy as np
        from uasnav import sim
        from uasnav.errors import DataFormatError
        from uasnav.io import (open_log, read_csv_table, read_flight, read_log, read_nav,
            write_csv_table, write_log)
        from uasnav.io.formats.gnss_csv import read_gnss_csv, write_gnss_csv
        from uasnav.sim.flight import simulate_flight
        from uasnav.thermal import load_training_data
        d = Path({str(tmp_path)!r})
        log = sim.simulate("ax1", profile="ramp", duration=120.0, rate=50.0, seed=1)
        write_log(log, d / "imu.csv"); write_log(log, d / "imu.npz")
        assert read_log(d / "imu.csv").gyro.tobytes() == log.gyro.tobytes()
        assert read_log(d / "imu.npz").gyro.tobytes() == log.gyro.tobytes()
        with open_log(d / "imu.csv").format.stream() as s:
            assert sum(b.shape[0] for b in s.blocks()) == log.n
        assert load_training_data(d / "imu.csv", 1.0) is not None
        write_csv_table(d / "t.csv", {{"t": [0.0, 1.0], "x": [1.5, float("nan")]}})
        cols, _ = read_csv_table(d / "t.csv")
        assert np.isnan(cols["x"][1])
        f = simulate_flight(duration_s=30.0, seed=2)
        write_gnss_csv(d / "g.csv", f.gnss)
        assert read_gnss_csv(d / "g.csv").n == f.gnss.n
        assert read_nav(d / "imu.csv", gnss_csv=d / "g.csv").gnss.n == f.gnss.n
        (d / "x.csv").write_text("Time (s),Gyroscope X (deg/s),Gyroscope Y (deg/s),"
            "Gyroscope Z (deg/s),Accelerometer X (g),Accelerometer Y (g),Accelerometer Z (g)\\n"
            "0,1,2,3,0,0,1\\n0.01,1,2,3,0,0,1\\n")
        assert read_log(d / "x.csv").n == 2
        (d / "f.csv").write_text("t,lat,lon,alt,v_N,v_E,v_D\\n0,45,7,100,1,0,0\\n1,45.00001,7,100,1,0,0\\n")
        assert read_flight(d / "f.csv").t.size == 2
        (d / "bad.csv").write_text("t,gx,gy,gz,ax,ay,az\\n0,1,2,3,4,5,6\\n1,1,x,3,4,5,6\\n")
        try:
            read_log(d / "bad.csv")
        except DataFormatError as e:
            assert (e.line, e.column) == (3, "gy"), (e.line, e.column)
        else:
            raise AssertionError("no error")
        assert sys.modules["pyarrow"] is None
        assert not [m for m in sys.modules if m.startswith("pyarrow.")]
        print("ok")
        """
    )
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr[-3000:]
