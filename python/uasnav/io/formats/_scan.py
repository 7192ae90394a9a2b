"""One decoding pass per log file, shared by every reader of that file.

A :class:`~uasnav.io.logfile.LogFile` decodes its file once, for the union of the message types
its views need (:class:`MavlinkScan`: one pymavlink pass with a ``type`` filter;
:class:`ULogScan`: one pyulog parse with ``message_name_filter_list``), and builds the views
while the scan is *active* (:func:`active`). Inside that block the format readers' low-level
access (:func:`uasnav.io._mavlink.reading`, :func:`uasnav.io.px4._open`) replays the scan
instead of opening the file again. A reader that asks for a type the scan does not hold
falls back to a real decoding pass (the parse-count test catches that as a defect).

The corruption notes of the decoding pass (what pymavlink / pyulog said) travel with the scan,
so the readers' salvage and :class:`~uasnav.errors.CorruptDataWarning` work as on a fresh read.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any

from uasnav.io._active import active, lookup
from uasnav.io._mavlink import scan_file
from uasnav.io._quiet import LibraryOutput
from uasnav.io.px4 import parse_ulog


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


class ULogScan:
    """A PX4 ULog parsed once by pyulog for the topics ``types`` only."""

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


__all__ = ["ReplayConnection", "ULogScan", "active", "decoder_of", "lookup"]
