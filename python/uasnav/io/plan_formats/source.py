"""Reading a plan file's text, bounded and with clear errors, for every plan format."""

from __future__ import annotations

import os
from pathlib import Path

from uasnav.errors import DataFormatError, InputError
from uasnav.limits import read_file_limited

#: Largest plan file read (bytes): a plan of 100 000 waypoints is about 4 MB as CSV; read
#: bounded, whatever size the file reports (``/dev/zero``, a FIFO).
MAX_PLAN_BYTES = 16 * 2**20


def read_plan_text(path: str | os.PathLike[str]) -> str:
    """The UTF-8 text of plan file ``path`` (a leading byte-order mark removed).

    Raises
    ------
    InputError
        No such file, a directory, unreadable.
    ResourceLimitError
        More than :data:`MAX_PLAN_BYTES` bytes.
    DataFormatError
        Not UTF-8 (names the line).
    """
    p = Path(path)
    if not p.exists():
        raise InputError(f"no such plan file: {p}")
    if p.is_dir():
        raise InputError(f"{p}: is a directory, not a plan file")
    raw = read_file_limited(p, MAX_PLAN_BYTES)
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        raise DataFormatError("not UTF-8 text", path=str(p), line=line) from None


__all__ = ["MAX_PLAN_BYTES", "read_plan_text"]
