"""pymavlink access shared by the DataFlash (``.bin``) and MAVLink telemetry (``.tlog``) readers.

One error handling for both formats: a missing file, a file pymavlink cannot open and a
message it cannot decode are each a :class:`~uasnav.errors.DataFormatError` naming the file.
What pymavlink prints about a corrupt log (one line per bad byte of a DataFlash log) is
silenced (:mod:`uasnav.io._quiet`); the readers report its statistics in one line.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from uasnav.errors import DataFormatError
from uasnav.io._active import lookup
from uasnav.io._quiet import LibraryOutput, library_output_captured


def connect(p: Path, **kw: Any) -> Any:
    """A pymavlink connection reading the log ``p`` (keyword arguments go to pymavlink).

    Raises
    ------
    DataFormatError
        If ``p`` is not a regular file or pymavlink cannot open it.
    """
    from pymavlink import mavutil

    if not p.exists():
        raise DataFormatError("no such file", path=str(p))
    if not p.is_file():
        # a device or FIFO: pymavlink would map or block on it
        raise DataFormatError("not a regular file", path=str(p))
    try:
        return mavutil.mavlink_connection(str(p), **kw)
    except Exception as e:  # pymavlink raises many exception types on bad input
        raise DataFormatError(f"not readable by pymavlink ({type(e).__name__}: {e})", path=str(p)) from None


@contextlib.contextmanager
def reading(p: Path, **kw: Any) -> Iterator[tuple[Any, LibraryOutput]]:
    """``(connection, decoder output)`` for reading ``p``, with pymavlink's printing captured.

    The :class:`LibraryOutput` is complete only after the block: report it (and issue any
    warning) *after* leaving the block, since output inside it is swallowed. The connection
    is closed on exit; pymavlink's statistics of a corrupt log are noted (:func:`_note_corruption`).

    While a decoded scan of ``p`` is active (:mod:`uasnav.io.formats._scan`), the connection
    replays it and the decoder output is the scan's: the file is not opened again.
    """
    scan = None if kw.pop("fresh", False) else lookup(p)
    if scan is not None and hasattr(scan, "replay"):
        yield scan.replay(), scan.decoder
        return
    conn = None
    with library_output_captured() as out:
        try:
            conn = connect(p, **kw)
            yield conn, out
        finally:
            if conn is not None:
                _note_corruption(conn, out)
                with contextlib.suppress(Exception):  # closing a half-read log cannot fail usefully
                    conn.close()


def _note_corruption(conn: Any, out: LibraryOutput) -> None:
    """Add pymavlink's own statistics of a corrupt log to ``out``: checksum failures of a
    ``.tlog``; for a DataFlash log, the bytes its index did not cover (bad bytes, and all bytes
    after a record of unknown type, where pymavlink stops indexing)."""
    mav = getattr(conn, "mav", None)
    errors = int(getattr(mav, "total_receive_errors", 0) or 0)
    if errors:
        out.note(f"{errors} MAVLink message(s) failed their checksum")
    counts, formats = getattr(conn, "counts", None), getattr(conn, "formats", None)
    size = getattr(conn, "data_len", None)
    if counts is not None and formats is not None and size:
        with contextlib.suppress(Exception):  # statistics only: never fail a read over them
            decoded = sum(c * formats[t].len for t, c in enumerate(counts) if c and t in formats)
            bad = int(size) - int(decoded)
            if bad > 0:
                out.note(f"{bad} of {size} bytes could not be decoded ({100.0 * bad / size:.1f} %)")


def messages(conn: Any, types: Sequence[str], p: Path, what: str) -> Iterator[Any]:
    """Every message of the given ``types``, in log order.

    ``what`` names the format in the error (``"DataFlash"``, ``"MAVLink"``).

    Raises
    ------
    DataFormatError
        If pymavlink fails to decode a message.
    """
    wanted = list(types)
    covers = getattr(conn, "covers", None)
    if covers is not None and not covers(wanted):
        # a replayed scan without these types: read them from the file (one more pass)
        with reading(p, **conn.kw, fresh=True) as (fresh, _):
            yield from messages(fresh, wanted, p, what)
        return
    while True:
        try:
            msg = conn.recv_match(type=wanted)
        except Exception as e:  # struct.error, IndexError, … on a truncated or corrupt log
            raise DataFormatError(f"corrupt {what} message ({type(e).__name__}: {e})", path=str(p)) from None
        if msg is None:
            return
        yield msg


def scan_file(p: Path, types: Sequence[str], **kw: Any) -> tuple[list[Any], LibraryOutput]:
    """Every message of ``types`` in the log ``p`` (one pass, in log order) and what the decoder
    reported (complete: the file is closed).

    Raises
    ------
    DataFormatError
        As :func:`connect` and :func:`messages`.
    """
    with reading(p, fresh=True, **kw) as (conn, decoder):
        msgs = list(messages(conn, types, p, "MAVLink" if p.suffix.lower() == ".tlog" else "DataFlash"))
    return msgs, decoder


__all__ = ["connect", "messages", "reading", "scan_file"]
