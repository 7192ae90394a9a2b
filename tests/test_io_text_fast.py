"""The vectorised CSV path of ``uasnav.io._text.numeric_rows`` returns exactly what the
row-by-row reader returns (values bit for bit, file line of every row), and hands every row it
cannot judge to the row-by-row reader, whose error names the cell."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from uasnav.errors import DataFormatError
from uasnav.io import _text
from uasnav.io._text import numeric_rows, split_lines


def _both(text: str, columns: list[str], exact: bool = True):
    lines = split_lines(text)
    header = [h.strip() for h in lines[0].split(",")]
    fast = _text._numeric_rows_fast(lines, 1, len(header), [header.index(c) for c in columns], exact)
    slow_pass = pytest.MonkeyPatch()
    slow_pass.setattr(_text, "_numeric_rows_fast", lambda *a, **k: None)
    try:
        slow = numeric_rows(lines, 1, "x.csv", header, columns, exact_width=exact)
    finally:
        slow_pass.undo()
    return fast, slow


cells = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
    st.integers(-(10**6), 10**6).map(str),
    st.sampled_from([" 1.5", "2 ", "+.5", "1_0", "1e-300", "-0.0"]),
)


@given(st.lists(st.lists(cells, min_size=3, max_size=3), min_size=2, max_size=30), st.booleans())
def test_fast_equals_row_by_row(rows, blanks) -> None:
    body = []
    for r in rows:
        body.append(",".join(r))
        if blanks:
            body.append("   ")
    text = "a,b,c\n" + "\n".join(body) + "\n"
    fast, slow = _both(text, ["c", "a"])
    # the parser refuses "1_0", which float() accepts: then the row-by-row reader decides alone
    assert fast is not None or any("_" in c for r in rows for c in r)
    if fast is None:
        return
    assert np.array_equal(fast[0], slow[0]) and fast[0].dtype == np.float64
    assert fast[1] == slow[1]


@pytest.mark.parametrize(
    ("row", "message", "column"),
    [
        ("1,nan,3", "non-finite", "b"),
        ("1,x,3", "not a number", "b"),
        ('1,"2",3', None, None),
        ("1,2", "expected 3 cells", None),
        ("1,2,3,4", "expected 3 cells", None),
        (",,", None, None),
    ],
)
def test_rows_it_cannot_judge_go_row_by_row(row, message, column) -> None:
    text = f"a,b,c\n1,2,3\n{row}\n4,5,6\n"
    lines = split_lines(text)
    assert _text._numeric_rows_fast(lines, 1, 3, [0, 1, 2], True) is None
    if message is None:
        data, where = numeric_rows(lines, 1, "x.csv", ["a", "b", "c"], ["a", "b", "c"], exact_width=True)
        assert len(data) in (3, 2) and where[0] == 2
        return
    with pytest.raises(DataFormatError, match=message) as e:
        numeric_rows(lines, 1, "x.csv", ["a", "b", "c"], ["a", "b", "c"], exact_width=True)
    assert e.value.line == 3
    if column:
        assert e.value.column == column
