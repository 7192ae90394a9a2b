"""The numeric chunk parser of the extension (``_core.csv_parse_chunk``, the csv-chunk crate),
the fast path of every CSV reader: each cell it reads has the value Python's ``float`` gives it,
bit for bit; it reads every plain decimal cell and hands everything else over; the parts parsed
on several threads join into the one-thread result; the GIL is released while it parses."""

from __future__ import annotations

import math
import re
import sys
import threading
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uasnav import _core
from uasnav.errors import InputError
from uasnav.io import _text
from uasnav.io._text import numeric_rows, split_lines

#: Plain decimal syntax (spaces and tabs around it): the cells the parser must read itself.
PLAIN = re.compile(r"[ \t]*[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?[ \t]*")

cell_text = st.one_of(
    st.from_regex(r"\A[ \t]{0,2}[+-]?[0-9]{0,30}\.?[0-9]{0,30}([eE][+-]?[0-9]{1,5})?[ \t]{0,2}\Z"),
    st.floats(width=64).map(repr),
    st.floats(width=64).map(lambda x: f"{x:.17e}"),
    st.floats(min_value=0.0, max_value=3e-308).map(repr),  # subnormals and the smallest normals
    st.text(alphabet="0123456789+-.eE_ naifINFxX\t", max_size=12),
    st.sampled_from(["nan", "-nan", "+NaN", "inf", "-Infinity", "1_0", "٣", "1e400", "-1e-400"]),
)


def _bits(x: float) -> int:
    return int(np.array(x, dtype=np.float64).view(np.uint64))


@settings(max_examples=400, deadline=None)
@given(cell_text, st.booleans())
def test_a_cell_is_read_as_float_reads_it_or_handed_over(cell, nan_ok) -> None:
    got = _core.csv_parse_chunk(f"{cell}\n".encode(), 1, [0], True, nan_ok)
    if not cell:  # an empty line: skipped
        assert got is not None and got.shape == (0, 1)
        return
    try:
        want: float | None = float(cell.strip())
    except ValueError:
        want = None
    plain = PLAIN.fullmatch(cell) is not None
    if got is None:
        # handed over: blank, not plain syntax, or a value the reader refuses (±inf, NaN)
        assert want is None or not plain or math.isinf(want) or (math.isnan(want) and not nan_ok), cell
        return
    assert want is not None and got.shape == (1, 1), cell
    assert _bits(float(got[0, 0])) == _bits(want), (cell, got[0, 0], want)
    assert plain or (nan_ok and math.isnan(want)), cell


@pytest.mark.parametrize(
    ("cell", "value"),
    [
        ("+1", 1.0),
        (".5", 0.5),
        ("5.", 5.0),
        ("-0", -0.0),
        ("\t 2.5 ", 2.5),
        ("1E+05", 1e5),
        ("4.9406564584124654e-324", 5e-324),
        ("2.2250738585072009e-308", 2.2250738585072009e-308),
        ("0.30000000000000004", 0.30000000000000004),
        ("9007199254740993", 9007199254740992.0),
        ("1" + "0" * 400 + "e-400", 1.0),
        ("1e-400", 0.0),
    ],
)
def test_numbers_bit_for_bit(cell, value) -> None:
    got = _core.csv_parse_chunk(f"{cell},0\n".encode(), 2, [0], True)
    assert got is not None and _bits(float(got[0, 0])) == _bits(value) == _bits(float(cell))


def test_nan_keeps_its_sign_as_float_does() -> None:
    got = _core.csv_parse_chunk(b"nan,-nan,NaN\n", 3, [0, 1, 2], True, True)
    assert got is not None
    assert [_bits(float(v)) for v in got[0]] == [_bits(float(c)) for c in ("nan", "-nan", "NaN")]
    assert _core.csv_parse_chunk(b"nan,-nan,NaN\n", 3, [0, 1, 2], True, False) is None


@pytest.mark.parametrize(
    "text",
    [
        b'1,2\n"3",4\n',
        b"1,2\n3,4\x00\n",
        b"1,2\n3,4\x0c\n",
        "1,2\n3,é\n".encode(),
        b"1,2\n3,\xe9\n",
        b"1,2\n  \n3,4\n",
        b"1,2\n,\n",
        b"1,2\n3\n",
        b"1,2\n3,4,5\n",
        b"1,2\n3,\n",
        b"1,2\n1_0,4\n",
        b"1,2\n3,inf\n",
        b"1,2," + b"3" * (64 * 1024) + b"\n",
    ],
)
def test_chunks_it_hands_over(text) -> None:
    assert _core.csv_parse_chunk(text, 2, [0, 1], True) is None


def test_layout_and_line_breaks() -> None:
    text = b"1,2,3,x\r\n\r\n4,5,6,y\r7,8,9,z\n\n"
    got = _core.csv_parse_chunk(text, 4, [2, 0], False)
    assert got is not None and got.flags.f_contiguous and got.dtype == np.float64
    assert got.tolist() == [[3.0, 1.0], [6.0, 4.0], [9.0, 7.0]]
    exact = _core.csv_parse_chunk(text, 4, [2, 0], True)  # the cells 'x' are not wanted …
    assert exact is not None and exact.tolist() == got.tolist()
    assert _core.csv_parse_chunk(text, 3, [2, 0], True) is None  # … but counted
    assert _core.csv_parse_chunk(b"1,2\n", 2, [], True).shape == (1, 0)
    assert _core.csv_parse_chunk(b"", 3, [0], True).shape == (0, 1)
    # a prefix of the bytes, read in place
    part = _core.csv_parse_chunk(b"1,2\n3,4\n5,x", 2, [0, 1], True, end=8)
    assert part is not None and part.tolist() == [[1.0, 2.0], [3.0, 4.0]]
    with pytest.raises(InputError, match="end: 12 is beyond the chunk's 11 bytes"):
        _core.csv_parse_chunk(b"1,2\n3,4\n5,x", 2, [0, 1], True, end=12)
    with pytest.raises(InputError, match="columns: 3 is not below width 3"):
        _core.csv_parse_chunk(b"1,2,3\n", 3, [3], True)
    with pytest.raises(InputError, match="columns"):
        _core.csv_parse_chunk(b"1,2,3\n", 3, [-1], True)


def _big_table(rows: int, seed: int) -> tuple[bytes, list[str]]:
    rng = np.random.default_rng(seed)
    x = rng.standard_normal((rows, 4)) * 10.0 ** rng.integers(-30, 30, (rows, 4))
    breaks = ["\n", "\r\n", "\r", "\n\n"]
    lines = [",".join(repr(float(v)) for v in r) for r in x]
    text = "".join(ln + breaks[k % 4] for k, ln in enumerate(lines))
    return text.encode(), lines


def test_parts_on_several_threads_join_into_the_row_by_row_result() -> None:
    raw, _ = _big_table(40_000, 3)  # ≈ 3 MB: parts of ≥ 256 KiB each
    header = ["a", "b", "c", "d"]
    with pytest.MonkeyPatch.context() as slow:
        slow.setattr(_text, "_numeric_rows_fast", lambda *a: None)
        want, _ = numeric_rows(split_lines(raw.decode()), 0, "x", header, ["d", "a", "c"], exact_width=True)
    for threads in (1, 2, 3, 8, 0):
        got = _core.csv_parse_chunk(raw, 4, [3, 0, 2], True, False, threads)
        assert got is not None and got.shape == want.shape
        assert got.tobytes("F") == np.asfortranarray(want).tobytes("F"), threads
    bad = raw + b"1,2,3,x\n"  # the last part refuses: the whole chunk is handed over
    assert _core.csv_parse_chunk(bad, 4, [3, 0, 2], True, False, 2) is None


def test_the_gil_is_released_while_parsing() -> None:
    """Another Python thread runs while a large chunk is parsed, and only then (no timing
    asserted): with a long switch interval the main thread gives the GIL away only when it
    blocks or the extension releases it, and the spinner hands it back at once."""
    raw, _ = _big_table(100_000, 4)
    count = 0
    stop = False

    def spin() -> None:
        nonlocal count
        while not stop:
            count += 1
            time.sleep(0)  # releases the GIL: the main thread takes it back when it wants it

    interval = sys.getswitchinterval()
    t = threading.Thread(target=spin)
    t.start()
    sys.setswitchinterval(30.0)
    try:
        progressed = []
        for _ in range(3):
            before = count
            _core.csv_parse_chunk(raw, 4, [0, 1, 2, 3], True, False, 1)
            progressed.append(count - before)
            before = count
            sum(range(200_000))  # pure Python, GIL held: the spinner cannot run
            progressed.append(-(count - before))
    finally:
        sys.setswitchinterval(interval)
        stop = True
        t.join()
    assert max(progressed[0::2]) > 0 and progressed[1::2] == [0, 0, 0], progressed


@given(st.text(alphabet="\r\n1,", max_size=40), st.integers(0, 40))
def test_line_breaks_are_counted_as_split_lines_counts_them(text, end) -> None:
    raw = text.encode()
    end = min(end, len(raw))
    assert _core.csv_line_breaks(raw) == len(re.findall(r"\r\n|\r|\n", text))
    assert _core.csv_line_breaks(raw, end) == len(re.findall(r"\r\n|\r|\n", text[:end]))
