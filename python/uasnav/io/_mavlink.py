"""pymavlink access shared by the DataFlash (``.bin``) and MAVLink telemetry (``.tlog``) readers.

One error handling for both formats: a missing file, a file pymavlink cannot open and a
message it cannot decode are each a :class:`~uasnav.errors.DataFormatError` naming the file.
What pymavlink prints about a corrupt log (one line per bad byte of a DataFlash log) is
silenced (:mod:`uasnav.io._quiet`); the readers report its statistics in one line.

The work of a decoding pass is bounded by the file size. pymavlink resynchronises a corrupt
``.tlog`` by reading one byte at a time until an 8-byte timestamp looks plausible, and its
indexed reader seeks back to every indexed message: a file of flipped bits can make it re-scan
the rest of the file once per damaged message (quadratic; ten minutes for 1 MB). The
connection's file is wrapped in a :class:`_BoundedFile` that stops the pass once the bytes read
exceed a small multiple of the file size or the reads exceed what the file's messages could
need; the timestamp resync itself searches whole blocks at once (:func:`_block_scan_timestamp`).
A pass stopped that way ends like a truncated log: what was decoded is kept and the corruption
note says where decoding stopped.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from uasnav.errors import DataFormatError
from uasnav.io._active import lookup
from uasnav.io._quiet import LibraryOutput, library_output_captured

#: Bytes one decoding pass may read: this many times the file size (plus :data:`SCAN_SLACK`).
SCAN_BYTES_PER_FILE_BYTE = 2
#: Read calls one pass may make per byte of file: a MAVLink message takes three reads
#: (timestamp, header, payload) and at least 16 bytes; one read per byte is a byte-wise resync.
SCAN_READS_PER_FILE_BYTE = 0.5
#: Fixed allowance of the scan budget (bytes, and read calls) for tiny files.
SCAN_SLACK = 1 << 20
#: A plausible tlog timestamp is within this of the previous one (s), as pymavlink decides.
_TIMESTAMP_JUMP_S = 3 * 24 * 60 * 60
_SCAN_BLOCK = 1 << 16


class ScanBudgetExceeded(Exception):
    """Raised inside pymavlink when a decoding pass reads more than its file could need."""


class _BoundedFile:
    """A file object that counts what pymavlink reads and stops it beyond a budget."""

    def __init__(self, f: Any, size: int) -> None:
        self._f = f
        self.size = size
        self.bytes_read = 0
        self.reads = 0
        self.max_bytes = SCAN_BYTES_PER_FILE_BYTE * size + SCAN_SLACK
        self.max_reads = int(SCAN_READS_PER_FILE_BYTE * size) + SCAN_SLACK
        self.stopped = ""

    def read(self, n: int = -1) -> bytes:
        data = self._f.read(n)
        self.bytes_read += len(data)
        self.reads += 1
        if self.bytes_read > self.max_bytes or self.reads > self.max_reads:
            self.stopped = self.summary()
            raise ScanBudgetExceeded(self.stopped)
        return data

    def summary(self) -> str:
        where = self.size
        with contextlib.suppress(Exception):  # position for the message only
            where = self._f.tell()
        return (
            f"decoding stopped at byte {where} of {self.size} after reading {self.bytes_read} bytes "
            f"in {self.reads} reads (too corrupt to resynchronise)"
        )

    def __getattr__(self, name: str) -> Any:
        return getattr(self._f, name)


def _block_scan_timestamp(conn: Any) -> Any:
    """pymavlink's ``scan_timestamp`` (find the next 8-byte big-endian µs timestamp within three
    days of the last good one), searching 64 KiB blocks at once instead of one byte per read."""
    weights = np.array([8 * (7 - k) for k in range(8)], dtype=np.uint64)

    def scan(tbuf: bytes) -> float:
        last = conn._last_timestamp
        f = conn.f
        buf = bytes(tbuf)
        t = int.from_bytes(buf[-8:], "big") * 1.0e-6
        while True:
            if len(buf) >= 8:
                win = np.lib.stride_tricks.sliding_window_view(np.frombuffer(buf, dtype=np.uint8), 8)
                ts = (win.astype(np.uint64) << weights).sum(axis=1, dtype=np.uint64) * 1.0e-6
                hit = np.flatnonzero(np.abs(ts - last) <= _TIMESTAMP_JUMP_S)
                if hit.size:
                    i = int(hit[0])
                    f.seek(f.tell() - len(buf) + i + 8)
                    return float(ts[i])
                t = float(ts[-1])
            block = f.read(_SCAN_BLOCK)
            if not block:
                return t  # end of file: pymavlink keeps the last candidate
            buf = buf[-7:] + block

    return scan


def _bound(conn: Any, p: Path) -> Any:
    """Wrap ``conn``'s file in a :class:`_BoundedFile`; give a tlog reader the block resync."""
    f = getattr(conn, "f", None)
    if f is not None and hasattr(f, "read") and not isinstance(f, _BoundedFile):
        with contextlib.suppress(OSError):
            conn.f = _BoundedFile(f, p.stat().st_size)
            if callable(getattr(conn, "scan_timestamp", None)):
                conn.scan_timestamp = _block_scan_timestamp(conn)
    return conn


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
        return _bound(mavutil.mavlink_connection(str(p), **kw), p)
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
    f = getattr(conn, "f", None)
    if isinstance(f, _BoundedFile) and f.stopped:
        out.note(f.stopped)
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
        except ScanBudgetExceeded:
            # like a truncated log: keep what was decoded; _note_corruption says where it stopped
            return
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
