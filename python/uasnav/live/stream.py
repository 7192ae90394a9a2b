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


def receive(
    conn: Any,
    on_message: Callable[[Any, float], Any],
    on_tick: Callable[[float], Any],
    *,
    stop: list[bool],
    idle_timeout_s: float | None = None,
    done: Callable[[], bool] = lambda: False,
) -> None:
    """Call ``on_message(msg, wall_s)`` for every message and ``on_tick(wall_s)`` at least every
    :data:`POLL_S`, until ``stop[0]``, ``done()``, or ``idle_timeout_s`` of wall time without a
    message (after the first)."""
    last_msg: float | None = None
    while not stop[0] and not done():
        try:
            msg = conn.recv_match(blocking=True, timeout=POLL_S)
        except (OSError, ConnectionError):
            msg = None
        now = time.monotonic()
        if msg is not None and msg.get_type() != "BAD_DATA":
            last_msg = now
            on_message(msg, now)
        on_tick(now)
        if idle_timeout_s is not None and last_msg is not None and now - last_msg > idle_timeout_s:
            return
