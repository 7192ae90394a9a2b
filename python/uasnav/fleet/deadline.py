"""Run one log's analysis in a child process that is killed at the per-log deadline.

A deadline delivered inside the process (an asynchronous exception, a signal handler) lands
only at the next Python bytecode: a decoder stuck in C (pymavlink's resync, a long call into the
Rust core, a ``read`` on a slow device) holds it off for as long as the call lasts. A process
can always be stopped. So, when a run has a per-log deadline, each thread that processes logs
(the loop of ``--workers 0``, the task thread of each Dask worker) keeps one child process:

- the child is started once (``python -m uasnav.fleet.deadline``) with the parent's import
  path, and then analyses one log per request, so the interpreter start and the imports are
  paid once per worker, not per log;
- a request is ``(modules, function, argument)`` pickled (functions by reference, as Dask
  sends them); the child imports the modules and the function's own, says it has started, and
  the deadline counts from there (the child's start and the imports, seconds on a loaded
  machine, have a deadline of their own, :data:`STARTUP_S`); the answer is the function's value
  or its exception, pickled back;
- at the deadline the child's whole process group is killed (``SIGKILL``), the parent raises
  :class:`LogTimeout`, and the next log starts a fresh child.

Requests and answers travel over two pipes of their own, so whatever a decoder prints to its
standard output (pymavlink does) never mixes with them; the child's stdout and stderr are
discarded and its warnings ignored (the runner ignores them too). A child whose parent dies
reads the end of its request pipe and exits.
"""

from __future__ import annotations

import atexit
import contextlib
import importlib
import os
import pickle
import select
import signal
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from typing import Any

#: Deadline (s) for a child to start and load the analysis' function, apart from the per-log
#: deadline.
STARTUP_S = 120.0
#: Frame header: the length of the pickled payload that follows (unsigned 64-bit, big-endian).
_HEADER = struct.Struct(">Q")


class LogTimeout(Exception):
    """A log's analysis ran past the run's per-log deadline."""


class ChildDied(Exception):
    """The process analysing a log ended without answering (killed by the system, out of memory,
    a crash in native code)."""


def _read_exact(fd: int, n: int, deadline: float | None) -> bytes | None:
    """``n`` bytes from ``fd``, or None at the end of the stream; :class:`LogTimeout` once
    ``deadline`` (``time.monotonic()``) has passed."""
    parts: list[bytes] = []
    got = 0
    while got < n:
        if deadline is not None:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([fd], [], [], left)[0]:
                raise LogTimeout
        block = os.read(fd, min(n - got, 1 << 20))
        if not block:
            return None
        parts.append(block)
        got += len(block)
    return b"".join(parts)


def _write_frame(fd: int, payload: bytes) -> None:
    data = memoryview(_HEADER.pack(len(payload)) + payload)
    while data:
        data = data[os.write(fd, data) :]


class _Child:
    """One child process and its two pipes (parent side)."""

    def __init__(self) -> None:
        req_r, self.req_w = os.pipe()
        self.resp_r, resp_w = os.pipe()
        try:
            self.proc = subprocess.Popen(
                [sys.executable, "-m", "uasnav.fleet.deadline", str(req_r), str(resp_w)],
                pass_fds=(req_r, resp_w),
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
                start_new_session=True,  # its own process group: killed with whatever it started
                env={**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)},
            )
        finally:
            os.close(req_r)
            os.close(resp_w)

    def _receive(self, deadline: float | None) -> Any:
        head = _read_exact(self.resp_r, _HEADER.size, deadline)
        body = None if head is None else _read_exact(self.resp_r, _HEADER.unpack(head)[0], deadline)
        if body is None:
            code = self.proc.wait()
            how = f"signal {-code}" if code < 0 else f"exit status {code}"
            raise ChildDied(f"the process analysing the log ended without an answer ({how})")
        return pickle.loads(body)

    def call(
        self, fn: Callable[[Any], Any], arg: Any, seconds: float | None, imports: tuple[str, ...] = ()
    ) -> Any:
        _write_frame(self.req_w, pickle.dumps((imports, fn, arg), protocol=pickle.HIGHEST_PROTOCOL))
        # The deadline counts from the start of the analysis: the child's interpreter start and
        # the imports of the analysis' modules (seconds on a loaded machine) have their own.
        self._receive(time.monotonic() + max(STARTUP_S, seconds or 0.0))
        ok, value = self._receive(None if seconds is None else time.monotonic() + seconds)
        if ok:
            return value
        raise value

    def kill(self) -> None:
        with contextlib.suppress(OSError):
            os.killpg(self.proc.pid, signal.SIGKILL)
        with contextlib.suppress(OSError):
            self.proc.kill()
        self.proc.wait()
        for fd in (self.req_w, self.resp_r):
            with contextlib.suppress(OSError):
                os.close(fd)


_local = threading.local()
_children: list[_Child] = []
_children_lock = threading.Lock()


@atexit.register
def _kill_children() -> None:
    with _children_lock:
        for c in _children:
            c.kill()
        _children.clear()


def call_with_deadline(
    fn: Callable[[Any], Any], arg: Any, seconds: float | None, imports: tuple[str, ...] = ()
) -> Any:
    """``fn(arg)`` computed in this thread's child process, stopped after ``seconds``.

    ``imports`` names modules that ``fn`` imports when it runs (lazily): the child imports them
    before the deadline starts, so that the first log of a child is not charged for them.

    Raises
    ------
    LogTimeout
        The call ran past ``seconds``; the child was killed (the next call starts a new one).
    ChildDied
        The child ended without answering.
    Exception
        Whatever ``fn`` raised, re-raised here.
    """
    child: _Child | None = getattr(_local, "child", None)
    if child is None or child.proc.poll() is not None:
        child = _local.child = _Child()
        with _children_lock:
            _children.append(child)
    try:
        return child.call(fn, arg, seconds, imports)
    except (LogTimeout, ChildDied, OSError, EOFError, pickle.UnpicklingError):
        _local.child = None
        child.kill()
        with _children_lock, contextlib.suppress(ValueError):
            _children.remove(child)
        raise


def _answer(fn: Callable[[Any], Any], arg: Any) -> bytes:
    import warnings

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            value = fn(arg)
        return pickle.dumps((True, value), protocol=pickle.HIGHEST_PROTOCOL)
    except Exception as e:  # sent back and re-raised by the parent
        try:
            return pickle.dumps((False, e), protocol=pickle.HIGHEST_PROTOCOL)
        except Exception:  # an exception that does not pickle: keep its type name and text
            return pickle.dumps((False, RuntimeError(f"{type(e).__name__}: {e}")))


_STARTED = pickle.dumps("started")


def _serve(req_r: int, resp_w: int) -> None:
    """The child's loop: one request, one answer, until the parent closes the request pipe."""
    while (head := _read_exact(req_r, _HEADER.size, None)) is not None:
        body = _read_exact(req_r, _HEADER.unpack(head)[0], None)
        if body is None:
            return
        try:
            imports, fn, arg = pickle.loads(body)
            for name in imports:
                importlib.import_module(name)
        except Exception as e:  # a function or module this process cannot import
            _write_frame(resp_w, _STARTED)
            _write_frame(resp_w, pickle.dumps((False, RuntimeError(f"cannot load the analysis: {e}"))))
            continue
        _write_frame(resp_w, _STARTED)
        _write_frame(resp_w, _answer(fn, arg))


if __name__ == "__main__":
    _serve(int(sys.argv[1]), int(sys.argv[2]))
