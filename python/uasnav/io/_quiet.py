"""Silence what third-party log decoders print; keep what matters for one summary line.

pymavlink prints one line per bad byte of a corrupt DataFlash log (``bad header 0x… at …``,
hundreds of thousands of lines, from C with ``fprintf(stderr)``) and pyulog prints its
corruption notices to *stdout*, where they would corrupt a command's ``--json`` output. The
readers run the decoder inside :func:`library_output_captured`:

- output through Python's ``sys.stdout``/``sys.stderr`` is counted (the first line kept as an
  example), not shown;
- output written to file descriptors 1 and 2 directly (C code) goes to ``os.devnull``: it cannot
  be counted without storing it (a garbage file can make the decoder print gigabytes), so the
  readers compute their own statistics (undecodable bytes, checksum failures) and add them
  with :meth:`LibraryOutput.note`.

The file-descriptor redirection is process-wide: output of *other threads* during the read is
discarded too. uasnav's readers are called from one thread (the CLI); a multi-threaded caller
that needs its output should read logs outside its printing threads.
"""

from __future__ import annotations

import contextlib
import ctypes
import io
import os
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field

_LONG_LINE = 1 << 16


@dataclass
class LibraryOutput:
    """What a decoder reported while :func:`library_output_captured` was active.

    Attributes
    ----------
    lines : int
        Non-blank lines it printed through Python's ``sys.stdout``/``sys.stderr``.
    example : str
        The first of them (stripped, at most 200 characters), or ``""``.
    notes : list of str
        Statistics added by the reader (:meth:`note`), e.g. "2359034 of 2981888 bytes could
        not be decoded"; they describe the corruption better than the printed lines do.
    """

    lines: int = 0
    example: str = ""
    notes: list[str] = field(default_factory=list)

    def add_text(self, text: str) -> None:
        """Count the non-blank lines of ``text``; keep the first as the example."""
        for line in text.splitlines():
            line = line.strip()
            if line:
                self.lines += 1
                if not self.example:
                    self.example = line[:200]

    def note(self, text: str) -> None:
        """Add a statistic of the corruption (one phrase)."""
        self.notes.append(text)

    @property
    def problems(self) -> bool:
        """True if the decoder printed anything or a statistic was noted."""
        return bool(self.lines or self.notes)

    def summary(self) -> str:
        """One phrase: the notes if any, else the count of printed lines with the first one."""
        if self.notes:
            return "; ".join(self.notes)
        if self.lines:
            return f"the decoder reported {self.lines} problem(s) (first: {self.example})"
        return ""


class _CountingStream(io.TextIOBase):
    """A text stream that counts lines instead of storing them (memory stays bounded)."""

    def __init__(self, out: LibraryOutput) -> None:
        self._out = out
        self._partial = ""

    def writable(self) -> bool:
        return True

    def write(self, s: str) -> int:
        head, sep, tail = (self._partial + s).rpartition("\n")
        if sep:
            self._out.add_text(head)
        self._partial = tail
        if len(self._partial) > _LONG_LINE:  # a line without end: count what we have
            self._out.add_text(self._partial)
            self._partial = ""
        return len(s)

    def close_out(self) -> None:
        if self._partial:
            self._out.add_text(self._partial)
            self._partial = ""


def _flush_c_stdio() -> None:
    """Flush the C library's stdio buffers (output of C code still sitting in them)."""
    with contextlib.suppress(Exception):  # no libc (exotic platform): nothing we can flush
        ctypes.CDLL(None).fflush(None)


def _flush_python() -> None:
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):  # a closed or missing stream has nothing buffered
            if stream is not None:
                stream.flush()


@contextlib.contextmanager
def library_output_captured() -> Iterator[LibraryOutput]:
    """Capture (count, do not show) what is printed inside the block (see the module docs).

    Yields a :class:`LibraryOutput` that is complete when the block has exited.
    """
    out = LibraryOutput()
    stream = _CountingStream(out)
    _flush_python()
    _flush_c_stdio()
    saved: list[tuple[int, int]] = []
    sink = os.open(os.devnull, os.O_WRONLY)
    try:
        for fd in (1, 2):
            try:
                saved.append((fd, os.dup(fd)))
            except OSError:  # descriptor closed (e.g. a daemon): nothing to protect
                continue
            os.dup2(sink, fd)
        with contextlib.redirect_stdout(stream), contextlib.redirect_stderr(stream):
            yield out
    finally:
        _flush_c_stdio()
        for fd, copy in saved:
            os.dup2(copy, fd)
            os.close(copy)
        os.close(sink)
        stream.close_out()


__all__ = ["LibraryOutput", "library_output_captured"]
