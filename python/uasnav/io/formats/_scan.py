"""One decoding pass per log file, shared by every reader of that file.

A :class:`~uasnav.io.logfile.LogFile` decodes its file once, for the union of the message types
its views need (:class:`MavlinkScan`: one pymavlink pass with a ``type`` filter;
:class:`ULogScan`: one pyulog parse with
``message_name_filter_list``), and builds the views while the scan is *active*
(:func:`active`). Inside that block the format readers' low-level access
(:func:`uasnav.io._mavlink.reading`, :func:`_open`) replays the scan
instead of opening the file again. A reader that asks for a type the scan does not hold
falls back to a real decoding pass (the parse-count test catches that as a defect).

The corruption notes of the decoding pass (what pymavlink / pyulog said) travel with the scan,
so the readers' salvage and :class:`~uasnav.errors.CorruptDataWarning` work as on a fresh read.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any

from uasnav.errors import DataFormatError
from uasnav.io._active import active, lookup
from uasnav.io._mavlink import scan_file
from uasnav.io._quiet import LibraryOutput, library_output_captured


class MavlinkScan:
    """Every message of ``types`` in a DataFlash / MAVLink log, decoded in one pymavlink pass."""

    def __init__(self, path: Path, types: Iterable[str], **kw: Any) -> None:
        self.path = Path(path)
        self.types = frozenset(types)
        self.kw = kw
        self.messages, self.decoder = scan_file(self.path, sorted(self.types), **kw)

    def covers(self, types: Iterable[str]) -> bool:
        return set(types) <= self.types

    def replay(self) -> ReplayConnection:
        return ReplayConnection(self)


class ReplayConnection:
    """A stand-in for a pymavlink connection: ``recv_match(type=…)`` over a scan's messages."""

    def __init__(self, scan: MavlinkScan) -> None:
        self._msgs = scan.messages
        self._i = 0
        self.kw = scan.kw
        self.covers = scan.covers

    def recv_match(self, type: Iterable[str] | str | None = None) -> Any | None:
        want = {type} if isinstance(type, str) else (None if type is None else set(type))
        while self._i < len(self._msgs):
            m = self._msgs[self._i]
            self._i += 1
            if want is None or m.get_type() in want:
                return m
        return None

    def close(self) -> None:
        """Nothing to close: the file was closed after the decoding pass."""


def parse_ulog(p: Path, topics: list[str] | None = None) -> tuple[Any, LibraryOutput]:
    """The ULog ``p`` parsed by pyulog (only ``topics`` when given: its
    ``message_name_filter_list``) and what pyulog printed meanwhile (its corruption notices go
    to stdout, which must stay clean for ``--json``).

    Raises
    ------
    DataFormatError
        Missing file, not a regular file (a device or FIFO), or not a ULog pyulog can parse.
    """
    from pyulog import ULog

    if not p.exists():
        raise DataFormatError("no such file", path=str(p))
    if not p.is_file():
        raise DataFormatError("not a regular file", path=str(p))  # a device or FIFO
    ulog = None
    failure: Exception | None = None
    with library_output_captured() as decoder:
        try:
            ulog = ULog(str(p), message_name_filter_list=topics)
        except Exception as e:  # pyulog raises bare exceptions on corrupt headers
            failure = e
    if ulog is None:
        raise DataFormatError(
            f"not a readable ULog ({type(failure).__name__}: {failure})", path=str(p)
        ) from None
    if getattr(ulog, "file_corruption", False) and not decoder.lines:
        decoder.note("pyulog detected file corruption")
    return ulog, decoder


def _open(p: Path, topics: list[str] | None = None) -> tuple[Any, LibraryOutput]:
    """The parsed ULog ``p``: the active scan's (the :class:`ULogScan`) when there is
    one, else a fresh parse of ``topics`` (None: every topic)."""
    scan = lookup(p)
    if scan is not None and hasattr(scan, "ulog"):
        return scan.ulog, scan.decoder
    return parse_ulog(p, topics)


class ULogScan:
    """A PX4 ULog parsed once by pyulog for the topics ``types`` only (the decoding pass of a
    :class:`~uasnav.io.logfile.LogFile`; :func:`_open` replays it while it is active)."""

    def __init__(self, path: Path, types: Iterable[str]) -> None:
        self.path = Path(path)
        self.types = frozenset(types)
        self.ulog, self.decoder = parse_ulog(self.path, sorted(self.types))

    def covers(self, types: Iterable[str]) -> bool:
        return set(types) <= self.types


def decoder_of(scan: Any) -> LibraryOutput:
    """The decoder output of a scan (a fresh, empty one for a scan without notes)."""
    out = getattr(scan, "decoder", None)
    return out if isinstance(out, LibraryOutput) else LibraryOutput()


__all__ = ["MavlinkScan", "ReplayConnection", "ULogScan", "active", "decoder_of", "lookup", "parse_ulog"]
