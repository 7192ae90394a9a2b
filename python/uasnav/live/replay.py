"""Send a recorded flight as a live MAVLink stream over UDP or TCP (``uasnav replay``).

Messages leave in the log's timing divided by ``speed`` (a monotonic schedule, so a slow send
does not accumulate delay); the vehicle's own clocks inside the messages (``time_boot_ms``,
``time_usec``, ``SYSTEM_TIME``) are sent as recorded, so a receiver that judges on vehicle time
sees the same flight at any speed.

Test aids, all applied to the stream as sent: ``offset`` shifts every reported position
(``GLOBAL_POSITION_INT``, ``GPS_RAW_INT``, ``GPS2_RAW``) by metres north/east from a log time
on (a deviation from the intent); ``drop``/``duplicate`` lose or repeat a random fraction of
packets (seeded); ``start_s`` skips the beginning, ``stop_after_s`` cuts the stream (telemetry
loss).
"""

from __future__ import annotations

import math
import os
import random
import select
import socket
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import Any

from uasnav.errors import InputError, UasnavError
from uasnav.live.source import Packet, mavlink_dialect
from uasnav.live.stream import connect_tcp, listen_tcp

#: Messages whose ``lat``/``lon`` (1e-7 deg) an offset shifts.
POSITION_MESSAGES = ("GLOBAL_POSITION_INT", "GPS_RAW_INT", "GPS2_RAW")


@dataclass(frozen=True)
class Offset:
    """Shift reported positions by ``north_m``, ``east_m`` (m) from ``after_s`` seconds after the
    first message on (until ``until_s``, when given)."""

    after_s: float
    north_m: float
    east_m: float
    until_s: float = math.inf


def parse_offset(text: str, until_s: float | None = None) -> Offset:
    """``T:NORTH,EAST`` (s, m, m) → :class:`Offset` (shifting until ``until_s``, s, if given).

    >>> parse_offset("30:100,0")
    Offset(after_s=30.0, north_m=100.0, east_m=0.0, until_s=inf)
    """
    try:
        t, ne = text.split(":")
        n, e = ne.split(",")
        off = Offset(float(t), float(n), float(e), math.inf if until_s is None else float(until_s))
    except ValueError:
        raise InputError(f"--offset-after: expected T:NORTH,EAST (s:m,m), got {text!r}") from None
    if not all(math.isfinite(x) for x in (off.after_s, off.north_m, off.east_m)) or off.after_s < 0:
        raise InputError(f"--offset-after: expected finite values and T ≥ 0, got {text!r}")
    if off.until_s <= off.after_s:
        raise InputError(f"--offset-until: must be after the --offset-after time {off.after_s:g} s")
    return off


#: Forms of ``--to``: ``udp``/``udpout`` send datagrams to HOST:PORT; ``tcp`` connects to a
#: listening receiver; ``tcpin`` listens and sends to the first receiver that connects (as a
#: vehicle or simulator serving ``tcp:5760``); ``serial`` writes to ``/dev/ttyX,BAUD`` (a
#: telemetry radio's port, or a pseudo-terminal).
TARGET_SCHEMES = ("udp", "udpout", "tcp", "tcpin", "serial")


@dataclass(frozen=True)
class Target:
    """Where a replay sends: ``scheme`` (one of :data:`TARGET_SCHEMES`), ``host`` and ``port``
    (for ``serial``: the device and its baud rate)."""

    scheme: str
    host: str
    port: int

    def __str__(self) -> str:
        if self.scheme == "serial":
            return f"{self.host},{self.port}"
        return f"{self.scheme}:{self.host}:{self.port}"


def parse_target(text: str) -> Target:
    """``udp:HOST:PORT``, ``udpout:HOST:PORT``, ``tcp:HOST:PORT``, ``tcpin:HOST:PORT`` or
    ``/dev/ttyX,BAUD`` → :class:`Target` (pymavlink's connection strings, seen from the sender).

    >>> parse_target("tcpin:127.0.0.1:5760")
    Target(scheme='tcpin', host='127.0.0.1', port=5760)
    >>> parse_target("/dev/ttyUSB0,57600")
    Target(scheme='serial', host='/dev/ttyUSB0', port=57600)
    """
    from uasnav.live.stream import parse_serial

    if text.startswith("/dev/"):
        dev, baud = parse_serial(text, "--to")
        return Target("serial", dev, baud)
    scheme, _, rest = text.partition(":")
    host, _, port = rest.rpartition(":")
    if scheme not in TARGET_SCHEMES[:4] or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise InputError(
            "--to: expected udp:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT, tcpin:HOST:PORT or "
            f"/dev/ttyX,BAUD, got {text!r}"
        )
    return Target(scheme, host.strip("[]"), int(port))


def shift_position(msg: Any, north_m: float, east_m: float) -> None:
    """Move a position message's ``lat``/``lon`` by metres north/east (in place; WGS-84 via
    :func:`uasnav.geo.ned_to_geodetic`)."""
    from uasnav.geo import ned_to_geodetic

    lat, lon = msg.lat * 1e-7, msg.lon * 1e-7
    if lat == 0.0 and lon == 0.0:
        return  # no fix yet: nothing to shift
    la, lo, _ = ned_to_geodetic(north_m, east_m, 0.0, lat, lon, 0.0)
    msg.lat, msg.lon = round(float(la) * 1e7), round(float(lo) * 1e7)


def _encoded(pk: Packet, offset: Offset | None, t0: float, mav: Any) -> bytes:
    msg = pk.msg
    if (
        offset is not None
        and offset.after_s <= pk.t_s - t0 < offset.until_s
        and msg.get_type() in POSITION_MESSAGES
    ):
        shift_position(msg, offset.north_m, offset.east_m)
        mav.srcSystem, mav.srcComponent = msg.get_srcSystem(), msg.get_srcComponent()
        mav.seq = msg.get_seq()
        return bytes(msg.pack(mav))
    buf = msg.get_msgbuf()
    if not buf:  # a converted message: encode it as vehicle 1, autopilot component
        mav.srcSystem, mav.srcComponent = 1, 1
        return bytes(msg.pack(mav))
    return bytes(buf)


@dataclass
class ReplayStats:
    """What a replay sent: packets, bytes, log seconds, and how late the sender ran at worst (s)."""

    packets: int = 0
    dropped: int = 0
    duplicated: int = 0
    bytes: int = 0
    log_s: float = 0.0
    max_late_s: float = 0.0


def replay(
    packets: Callable[[], Iterable[Packet]],
    send: Callable[[bytes], Any],
    *,
    speed: float = 1.0,
    loop: bool = False,
    offset: Offset | None = None,
    drop: float = 0.0,
    duplicate: float = 0.0,
    start_s: float = 0.0,
    stop_after_s: float | None = None,
    seed: int = 0,
    clock: Callable[[], float] = time.monotonic,
    sleep: Callable[[float], Any] = time.sleep,
) -> ReplayStats:
    """Send ``packets()`` through ``send`` in recorded timing / ``speed`` (module doc).

    ``packets`` is called once per pass (``loop`` repeats until interrupted). Times ``start_s``
    and ``stop_after_s`` (s after the first message) bound the part sent.
    """
    if not (math.isfinite(speed) and speed > 0):
        raise InputError(f"--speed: expected a finite value > 0, got {speed!r}")
    for name, p in (("--drop", drop), ("--duplicate", duplicate)):
        if not 0.0 <= p < 1.0:
            raise InputError(f"{name}: expected a fraction in [0, 1), got {p!r}")
    rng = random.Random(seed)
    mav = mavlink_dialect().MAVLink(None, srcSystem=1, srcComponent=1)
    stats = ReplayStats()
    while True:
        it: Iterator[Packet] = iter(packets())
        t0: float | None = None
        start: float | None = None
        for pk in it:
            if t0 is None:
                t0 = pk.t_s
            rel = pk.t_s - t0
            if rel < start_s:
                continue
            if stop_after_s is not None and rel > stop_after_s:
                break
            if start is None:
                start = clock()
            due = start + (rel - start_s) / speed
            wait = due - clock()
            if wait > 0:
                sleep(wait)
            else:
                stats.max_late_s = max(stats.max_late_s, -wait)
            data = _encoded(pk, offset, t0, mav)
            stats.log_s = rel
            if drop and rng.random() < drop:
                stats.dropped += 1
                continue
            copies = 2 if duplicate and rng.random() < duplicate else 1
            stats.duplicated += copies - 1
            for _ in range(copies):
                send(data)
                stats.packets += 1
                stats.bytes += len(data)
        if not loop or t0 is None:
            return stats


class LinkClosed(UasnavError):
    """The receiver of a TCP replay closed the connection."""


#: How long ``tcp`` keeps trying to connect to a receiver that is not listening yet (s), and
#: how long ``tcpin`` waits for a receiver to connect (s).
CONNECT_WAIT_S = 30.0


def open_sender(
    target: Target, *, wait_s: float | None = None, on_wait: Callable[[str], Any] = lambda _: None
) -> tuple[Callable[[bytes], Any], Any]:
    """A sender of encoded packets to ``target`` and its socket or port (close it when done).

    UDP is fire and forget (nobody listening is not an error). TCP is a byte stream: the
    packets are written whole, in order; a receiver that closes the connection ends the
    replay with :class:`LinkClosed`. ``on_wait`` is told once what a ``tcpin`` replay waits for;
    ``wait_s`` defaults to :data:`CONNECT_WAIT_S`.
    """
    wait_s = CONNECT_WAIT_S if wait_s is None else wait_s
    if target.scheme == "serial":
        return _serial_sender(target)
    try:
        infos = socket.getaddrinfo(
            target.host,
            target.port,
            type=socket.SOCK_DGRAM if target.scheme.startswith("udp") else socket.SOCK_STREAM,
            flags=socket.AI_PASSIVE if target.scheme == "tcpin" else 0,
        )
    except (OSError, UnicodeError) as e:
        raise InputError(f"--to {target}: cannot resolve {target.host} ({e})") from None
    family, kind, proto, _, addr = infos[0]
    if target.scheme in ("udp", "udpout"):
        sock = socket.socket(family, kind, proto)

        def send_datagram(data: bytes) -> None:
            try:
                sock.sendto(data, addr)
            except ConnectionRefusedError:
                pass  # nobody listening yet (ICMP port unreachable): UDP telemetry is fire and forget

        return send_datagram, sock
    if target.scheme == "tcp":
        sock = connect_tcp(infos[0], wait_s, f"--to {target}")
    else:
        sock = _tcp_accept(target, infos[0], wait_s, on_wait)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def send_stream(data: bytes) -> None:
        try:
            sock.sendall(data)
        except (BrokenPipeError, ConnectionResetError, ConnectionAbortedError):
            raise LinkClosed(f"--to {target}: the receiver closed the connection") from None

    return send_stream, sock


class _SerialPort:
    """The replay's serial port: a file descriptor with ``close`` (as the sockets have)."""

    def __init__(self, fd: int) -> None:
        self.fd = fd

    def close(self) -> None:
        if self.fd >= 0:
            os.close(self.fd)
            self.fd = -1


def _serial_sender(target: Target) -> tuple[Callable[[bytes], Any], Any]:
    """Write whole packets to a serial port: a full output buffer (the line's baud rate, or a
    reader that is behind) waits until it drains; the line holds back, it does not drop."""
    from uasnav.live.stream import open_serial

    port = _SerialPort(open_serial(target.host, target.port, f"--to {target}"))

    def send_serial(data: bytes) -> None:
        view = memoryview(data)
        while view:
            try:
                view = view[os.write(port.fd, view) :]
            except BlockingIOError:
                select.select([], [port.fd], [], 1.0)

    return send_serial, port


def _tcp_accept(target: Target, info: Any, wait_s: float, on_wait: Callable[[str], Any]) -> socket.socket:
    with listen_tcp(info, f"--to {target}") as server:
        server.settimeout(wait_s)
        on_wait(f"waiting up to {wait_s:g} s for a receiver to connect to {target.host}:{target.port}")
        try:
            sock, _ = server.accept()
        except TimeoutError:
            raise InputError(f"--to {target}: no receiver connected within {wait_s:g} s") from None
    sock.settimeout(None)
    return sock
