"""Receiving a live MAVLink stream: pymavlink connections and the receive loop.

``CONNECTION`` takes pymavlink's forms: ``udpin:HOST:PORT`` (listen), ``udpout:HOST:PORT``,
``tcp:HOST:PORT`` (connect), ``tcpin:HOST:PORT`` (listen for one sender), ``/dev/ttyX,BAUD`` (a
serial port and its baud rate). Messages are decoded
with the ``ardupilotmega`` dialect; packets that fail their checksum are dropped by pymavlink.

UDP is pymavlink's connection. TCP (:class:`TcpStream`) and serial ports
(:class:`SerialStream`) are byte streams owned here: pymavlink's TCP connections print to
standard output (which carries ``monitor --json-lines``) and reconnect, or poll a closed
socket, after the sender closes, and its serial connection needs pyserial. A TCP stream ends
when its sender closes it, and :func:`receive` returns then; a serial line has no end.
"""

from __future__ import annotations

import errno
import os
import select
import signal
import socket
import time
from abc import ABC, abstractmethod
from collections import deque
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

from uasnav.errors import InputError

#: How long one wait for a message lasts (s): the granularity of ticks (telemetry loss).
POLL_S = 0.02


#: How long ``tcp:`` keeps trying to connect to a sender that is not listening yet (s).
CONNECT_WAIT_S = 10.0


def connect_tcp(info: Any, wait_s: float, where: str) -> socket.socket:
    """A TCP socket connected to ``info`` (a ``getaddrinfo`` row), trying again while the peer
    refuses (it is not listening yet) for up to ``wait_s``; an :class:`InputError` that starts
    with ``where`` otherwise."""
    family, kind, proto, _, addr = info
    deadline = time.monotonic() + wait_s
    while True:
        sock = socket.socket(family, kind, proto)
        try:
            sock.connect(addr)
            return sock
        except OSError as e:
            sock.close()
            if not isinstance(e, ConnectionRefusedError) or time.monotonic() >= deadline:
                raise InputError(
                    f"{where}: cannot connect ({e.strerror or e}; waited {wait_s:g} s)"
                ) from None
            time.sleep(0.1)


def listen_tcp(info: Any, where: str) -> socket.socket:
    """A TCP socket listening for one peer at ``info``; an :class:`InputError` that starts
    with ``where`` when the address cannot be bound."""
    family, kind, proto, _, addr = info
    server = socket.socket(family, kind, proto)
    server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        server.bind(addr)
    except OSError as e:
        server.close()
        raise InputError(f"{where}: cannot listen ({e.strerror or e})") from None
    server.listen(1)
    return server


class ByteStream(ABC):
    """A MAVLink byte stream decoded here (pymavlink's parser, the ``ardupilotmega`` dialect).

    It offers what :func:`receive` and the commands use of a pymavlink connection:
    :meth:`recv_match`, :meth:`close` and ``port``. A subclass supplies :meth:`_source` (what
    to wait on, ``None`` while there is nothing yet), :meth:`_read` (bytes; ``b""`` when the
    peer closed) and may override :meth:`_idle` (called while :meth:`_source` is ``None``).
    """

    def __init__(self) -> None:
        from uasnav.live.source import mavlink_dialect

        self.closed = False
        self.end: str | None = None
        self._pending: deque[Any] = deque()
        self._mav = mavlink_dialect().MAVLink(None)
        self._mav.robust_parsing = True

    @abstractmethod
    def _source(self) -> Any:
        """What to wait on (a file descriptor or socket), ``None`` while there is nothing yet."""

    @abstractmethod
    def _read(self) -> bytes:
        """The bytes that arrived; ``b""`` when the peer closed."""

    def _idle(self, timeout_s: float) -> None:
        time.sleep(timeout_s)

    def recv_match(self, blocking: bool = True, timeout: float | None = None) -> Any:
        """The next message, or ``None`` when none came within ``timeout`` (s) or the stream
        is over."""
        wait = (timeout if timeout is not None else 1e9) if blocking else 0.0
        deadline = time.monotonic() + wait
        while not self._pending and not self.closed:
            left = max(deadline - time.monotonic(), 0.0)
            src = self._source()
            if src is None:
                self._idle(left)
                if self._source() is None and time.monotonic() >= deadline:
                    return None
                continue
            ready, _, _ = select.select([src], [], [], left)
            if not ready:
                return None
            try:
                data = self._read()
            except BlockingIOError:  # nothing after all (or a line without its other side yet)
                if time.monotonic() >= deadline:
                    return None
                continue
            except OSError as e:
                self._over(f"the connection failed ({e.strerror or e})")
                break
            if not data:
                self._over("the sender closed the connection")
                break
            self._pending.extend(m for m in self._mav.parse_buffer(data) or [] if m.get_type() != "BAD_DATA")
        return self._pending.popleft() if self._pending else None

    def _over(self, why: str) -> None:
        self.closed, self.end = True, why

    def close(self) -> None:
        if not self.closed:
            self._over("closed by this receiver")


class TcpStream(ByteStream):
    """A MAVLink stream over TCP: ``tcp`` connects to a sender, ``tcpin`` listens and takes the
    first sender that connects. The stream is over (:attr:`closed`, :attr:`end`) when the sender
    closes it; nothing is printed, nothing reconnects. ``port`` is the connected socket,
    ``None`` before a ``tcpin`` sender connects.
    """

    def __init__(self, scheme: str, host: str, port: int, *, wait_s: float | None = None) -> None:
        super().__init__()
        where = f"{scheme}:{host}:{port}"
        self.port: socket.socket | None = None
        self._server: socket.socket | None = None
        try:
            info = socket.getaddrinfo(
                host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE if scheme == "tcpin" else 0
            )[0]
        except (OSError, UnicodeError) as e:
            raise InputError(f"connection {where!r}: cannot resolve {host} ({e})") from None
        if scheme == "tcpin":
            self._server = listen_tcp(info, f"connection {where!r}")
            return
        sock = connect_tcp(info, CONNECT_WAIT_S if wait_s is None else wait_s, f"connection {where!r}")
        self._connected(sock)

    def _connected(self, sock: socket.socket) -> None:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        sock.setblocking(False)
        self.port = sock

    def _source(self) -> Any:
        return self.port

    def _idle(self, timeout_s: float) -> None:
        """tcpin: wait up to ``timeout_s`` for the sender to connect."""
        assert self._server is not None
        ready, _, _ = select.select([self._server], [], [], timeout_s)
        if ready:
            sock, _ = self._server.accept()
            self._server.close()
            self._server = None
            self._connected(sock)

    def _read(self) -> bytes:
        assert self.port is not None
        return self.port.recv(65536)

    def close(self) -> None:
        for sock in (self.port, self._server):
            if sock is not None:
                sock.close()
        self._server = None
        super().close()


def open_serial(device: str, baud: int, where: str) -> int:
    """A file descriptor of the serial device (or pseudo-terminal) ``device`` opened for
    reading and writing in raw mode at ``baud`` (POSIX termios: 8 data bits, no parity, no
    flow control); an :class:`InputError` that starts with ``where`` otherwise."""
    import termios
    import tty

    speed = getattr(termios, f"B{baud}", None)
    if speed is None:
        raise InputError(f"{where}: baud rate {baud} is not one this system's serial ports support")
    try:
        fd = os.open(device, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
    except OSError as e:
        raise InputError(f"{where}: cannot open {device} ({e.strerror or e})") from None
    try:
        tty.setraw(fd, termios.TCSANOW)  # keep what the line already holds
        attrs = termios.tcgetattr(fd)
        attrs[4] = attrs[5] = speed
        attrs[2] &= ~termios.CRTSCTS
        termios.tcsetattr(fd, termios.TCSANOW, attrs)
    except (OSError, termios.error) as e:
        os.close(fd)
        raise InputError(f"{where}: {device} is not a serial port ({e})") from None
    return fd


def parse_serial(text: str, where: str) -> tuple[str, int]:
    """``/dev/ttyX,BAUD`` (``BAUD`` default 57600) → (device, baud)."""
    dev, _, baud = text.partition(",")
    if not dev.startswith("/dev/") or (baud and not baud.isdigit()):
        raise InputError(f"{where}: expected /dev/ttyX,BAUD (the baud rate a number), got {text!r}")
    return dev, int(baud or 57600)


class SerialStream(ByteStream):
    """A MAVLink stream from a serial port or pseudo-terminal (``/dev/ttyX,BAUD``), read with the
    standard library (no pyserial). A serial line has no end: the stream lasts until closed."""

    def __init__(self, text: str) -> None:
        super().__init__()
        dev, baud = parse_serial(text, f"connection {text!r}")
        self.fd = open_serial(dev, baud, f"connection {text!r}")
        self.port = None  # no socket (kernel_drops: unknown)

    def _source(self) -> Any:
        return self.fd

    def _read(self) -> bytes:
        try:
            return os.read(self.fd, 65536)
        except OSError as e:  # a pseudo-terminal whose other side is not open reads as EIO
            if e.errno == errno.EIO:
                time.sleep(POLL_S)
                raise BlockingIOError from None
            raise

    def close(self) -> None:
        if self.fd >= 0:
            os.close(self.fd)
            self.fd = -1
        super().close()


def open_connection(text: str) -> Any:
    """A pymavlink connection for ``text`` (module doc); a bad string is an InputError."""
    from pymavlink import mavutil

    head = text.split(":", 1)[0]
    if head not in ("udpin", "udpout", "udp", "tcp", "tcpin") and not text.startswith("/dev/"):
        raise InputError(
            f"connection {text!r}: expected udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT, "
            "tcpin:HOST:PORT or /dev/ttyX,BAUD"
        )
    if head in ("tcp", "tcpin"):
        host, _, port = text.split(":", 1)[1].rpartition(":")
        if not host or not port.isdigit() or not 0 < int(port) < 65536:
            raise InputError(f"connection {text!r}: expected {head}:HOST:PORT")
        return TcpStream(head, host, int(port))
    if text.startswith("/dev/"):
        return SerialStream(text)
    kw: dict[str, Any] = {"dialect": "ardupilotmega", "autoreconnect": True}
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

    sock = getattr(conn, "port", None)
    if isinstance(sock, socket.socket) and sock.type == socket.SOCK_DGRAM:
        with contextlib.suppress(OSError):
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, UDP_RCVBUF)


def kernel_drops(conn: Any) -> int | None:
    """Datagrams the kernel dropped for the connection's UDP socket because its receive buffer
    was full (Linux: the ``drops`` column of ``/proc/net/udp{,6}`` for the socket's inode);
    None when unknown (not UDP, not Linux, or the socket is closed)."""
    import os

    sock = getattr(conn, "port", None)
    if not isinstance(sock, socket.socket) or sock.type != socket.SOCK_DGRAM or sock.fileno() < 0:
        return None
    try:
        inode = str(os.fstat(sock.fileno()).st_ino)
        for table in ("/proc/net/udp", "/proc/net/udp6"):
            with open(table, encoding="ascii") as fh:
                next(fh)  # header
                for line in fh:
                    cols = line.split()
                    if len(cols) >= 13 and cols[9] == inode:
                        return int(cols[-1])
    except (OSError, ValueError, StopIteration):
        return None
    return None


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
    :data:`POLL_S`, until ``stop[0]``, ``done()``, ``idle_timeout_s`` of wall time without a
    message (after the first), or the end of a stream that can end (a :class:`TcpStream`
    closed by its sender, every message processed). Returns the messages dropped from a full
    queue.

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
        while not halt.is_set() and not getattr(conn, "closed", False):
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
            if not th.is_alive() and q.empty():  # the stream is over and fully processed
                break
    finally:
        halt.set()
        th.join(timeout=1.0)
    return dropped[0]
