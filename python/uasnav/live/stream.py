"""Receiving a live MAVLink stream: pymavlink connections and the receive loop.

``CONNECTION`` takes pymavlink's forms: ``udpin:HOST:PORT`` (listen), ``udpout:HOST:PORT``,
``tcp:HOST:PORT``, ``/dev/ttyX,BAUD`` (a serial port and its baud rate). Messages are decoded
with the ``ardupilotmega`` dialect; packets that fail their checksum are dropped by pymavlink.
"""

from __future__ import annotations

import signal
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

from uasnav.errors import InputError

#: How long one wait for a message lasts (s): the granularity of ticks (telemetry loss).
POLL_S = 0.02


def open_connection(text: str) -> Any:
    """A pymavlink connection for ``text`` (module doc); a bad string is an InputError."""
    from pymavlink import mavutil

    head = text.split(":", 1)[0]
    if head not in ("udpin", "udpout", "udp", "tcp", "tcpin") and not text.startswith("/dev/"):
        raise InputError(
            f"connection {text!r}: expected udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT "
            "or /dev/ttyX,BAUD"
        )
    kw: dict[str, Any] = {"dialect": "ardupilotmega", "autoreconnect": True}
    if text.startswith("/dev/"):
        dev, _, baud = text.partition(",")
        if baud and not baud.isdigit():
            raise InputError(f"connection {text!r}: the baud rate must be a number")
        text, kw["baud"] = dev, int(baud or 57600)
    try:
        return mavutil.mavlink_connection(text, **kw)
    except OSError as e:
        raise InputError(f"connection {text!r}: {e.strerror or e}") from None
    except Exception as e:  # pymavlink raises assorted types on a malformed address
        raise InputError(f"connection {text!r}: {type(e).__name__}: {e}") from None


@contextmanager
def stop_on_signals() -> Iterator[list[bool]]:
    """A flag set by SIGTERM/SIGINT, so the loop ends cleanly (files closed, summary printed)."""
    stop = [False]

    def handler(signum: int, frame: Any) -> None:
        stop[0] = True

    old = {s: signal.signal(s, handler) for s in (signal.SIGTERM, signal.SIGINT)}
    try:
        yield stop
    finally:
        for s, h in old.items():
            signal.signal(s, h)


#: Messages held between the reading thread and the processing (bounded memory); beyond, the
#: oldest are dropped and counted.
QUEUE_MESSAGES = 100_000
#: Receive buffer asked of the kernel for a UDP socket (bytes): bursts of a fast replay.
UDP_RCVBUF = 8 * 1024 * 1024


def _enlarge_buffer(conn: Any) -> None:
    import contextlib
    import socket

    sock = getattr(conn, "port", None)
    if isinstance(sock, socket.socket) and sock.type == socket.SOCK_DGRAM:
        with contextlib.suppress(OSError):
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, UDP_RCVBUF)


def receive(
    conn: Any,
    on_message: Callable[[Any, float], Any],
    on_tick: Callable[[float], Any],
    *,
    stop: list[bool],
    idle_timeout_s: float | None = None,
    done: Callable[[], bool] = lambda: False,
) -> int:
    """Call ``on_message(msg, wall_s)`` for every message and ``on_tick(wall_s)`` at least every
    :data:`POLL_S`, until ``stop[0]``, ``done()``, or ``idle_timeout_s`` of wall time without a
    message (after the first). Returns the messages dropped from a full queue.

    A thread only reads and decodes (``wall_s`` is its receive time), so the processing never
    keeps the socket waiting: a slow step (the filter releases the GIL) does not lose packets.
    """
    import queue
    import threading

    _enlarge_buffer(conn)
    q: queue.Queue[tuple[Any, float]] = queue.Queue(maxsize=QUEUE_MESSAGES)
    dropped = [0]
    halt = threading.Event()
    polled = [time.monotonic()]  # when the reader last finished a wait on the socket

    def reader() -> None:
        while not halt.is_set():
            polled[0] = time.monotonic()
            try:
                msg = conn.recv_match(blocking=True, timeout=POLL_S)
            except (OSError, ConnectionError):
                msg = None
            if msg is None or msg.get_type() == "BAD_DATA":
                continue
            try:
                q.put_nowait((msg, time.monotonic()))
            except queue.Full:
                dropped[0] += 1

    th = threading.Thread(target=reader, name="uasnav-mavlink-reader", daemon=True)
    th.start()
    last_msg: float | None = None
    try:
        while not stop[0] and not done():
            try:
                msg, wall = q.get(timeout=POLL_S)
            except queue.Empty:
                msg = None
            now = time.monotonic()
            if msg is not None:
                last_msg = now
                on_message(msg, wall)
            # silence is judged only when nothing waits: no backlog in the queue, and the reader
            # has had the processor recently (after a stall of the whole process, packets may
            # still sit in the socket)
            if q.empty() and now - polled[0] <= 3 * POLL_S:
                on_tick(now)
            if idle_timeout_s is not None and last_msg is not None and now - last_msg > idle_timeout_s:
                break
    finally:
        halt.set()
        th.join(timeout=1.0)
    return dropped[0]
