"""Hostile HTTP servers and sources for the mission documents (issue #20, classes 2 and 3).

A raw-socket server on 127.0.0.1 (one thread per connection) plays the servers a careless or
hostile network offers: one byte per second, a garbage status line, redirects to file:// and
ftp://, an endless body. Every handler is bounded in bytes and time and stops when the client
goes away, and the server stops with the module, so nothing outlives the tests.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import socket
import threading
import time
import tracemalloc
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.errors import DataFormatError, InputError, ResourceLimitError
from uasnav.mission.loading import data_file, fetch, load_document

#: A small valid document (the shipped regulations).
GOOD = data_file("regulations.xml")
#: Longest any handler runs (s): the tests' deadlines are far shorter.
HANDLER_BUDGET_S = 8.0


def _head(status: str = "200 OK", length: int | None = None, extra: str = "") -> bytes:
    cl = f"Content-Length: {length}\r\n" if length is not None else ""
    return f"HTTP/1.1 {status}\r\n{cl}{extra}Connection: close\r\n\r\n".encode()


def _drip(conn: socket.socket, data: bytes, pause_s: float) -> None:
    stop = time.monotonic() + HANDLER_BUDGET_S
    for i in range(len(data)):
        if time.monotonic() > stop:
            return
        conn.sendall(data[i : i + 1])
        time.sleep(pause_s)


def _routes(port: int) -> dict[str, Callable[[socket.socket], None]]:
    base = f"http://127.0.0.1:{port}"

    def good(c: socket.socket) -> None:
        c.sendall(_head(length=len(GOOD)) + GOOD)

    def drip_headers(c: socket.socket) -> None:
        # Every read gets a byte within 0.2 s, so no per-read timeout ever fires.
        _drip(c, _head(length=len(GOOD), extra="X-Padding: " + "a" * 200 + "\r\n") + GOOD, 0.2)

    def drip_body(c: socket.socket) -> None:
        c.sendall(_head(length=len(GOOD)))
        _drip(c, GOOD, 0.2)

    def garbage_status(c: socket.socket) -> None:
        c.sendall(b"SPLAT \x00\x01 not http at all\r\nmore junk\r\n\r\n")

    def redirect_to(target: str) -> Callable[[socket.socket], None]:
        return lambda c: c.sendall(_head("302 Found", 0, f"Location: {target}\r\n"))

    def endless(c: socket.socket) -> None:
        c.sendall(_head())  # no Content-Length: the body ends when the server closes
        block = b"<a>" + b" " * 65533
        stop = time.monotonic() + HANDLER_BUDGET_S
        sent = 0
        while time.monotonic() < stop and sent < 1 << 30:  # bounded: 1 GiB or the budget
            c.sendall(block)
            sent += len(block)

    return {
        "/good.xml": good,
        "/drip-headers": drip_headers,
        "/drip-body": drip_body,
        "/garbage": garbage_status,
        "/to-file": redirect_to("file:///etc/passwd"),
        "/to-ftp": redirect_to("ftp://127.0.0.1/x.xml"),
        "/to-good": redirect_to(f"{base}/good.xml"),
        "/to-relative": redirect_to("/good.xml"),
        "/endless": endless,
    }


class _Server:
    """Accept loop in a daemon thread; each connection gets the handler of its request path."""

    def __init__(self) -> None:
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.sock.settimeout(0.2)
        self.port = self.sock.getsockname()[1]
        self.routes = _routes(self.port)
        self.stopping = threading.Event()
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        while not self.stopping.is_set():
            try:
                conn, _ = self.sock.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            threading.Thread(target=self._handle, args=(conn,), daemon=True).start()

    def _handle(self, conn: socket.socket) -> None:
        conn.settimeout(HANDLER_BUDGET_S)
        try:
            request = conn.recv(4096)
            if request[:1] == b"\x16":  # a TLS ClientHello: answer a record header, then drip
                _drip(conn, b"\x16\x03\x03\x40\x00" + b"\x02" * 1000, 0.2)
                return
            while b"\r\n\r\n" not in request and len(request) < 65536:
                block = conn.recv(4096)
                if not block:
                    return
                request += block
            path = request.split(b" ", 2)[1].decode("latin-1")
            handler = self.routes.get(path)
            if handler is None:
                conn.sendall(_head("404 Not Found", 0))
            else:
                handler(conn)
        except OSError:
            pass  # the client gave up: the point of most of these tests
        finally:
            conn.close()

    def close(self) -> None:
        self.stopping.set()
        self.thread.join(timeout=2.0)
        self.sock.close()


@pytest.fixture(scope="module")
def server() -> Iterator[str]:
    srv = _Server()
    yield f"http://127.0.0.1:{srv.port}"
    srv.close()


def _timed(fn: Callable[[], object]) -> tuple[BaseException | None, float]:
    t0 = time.monotonic()
    try:
        fn()
    except Exception as exc:  # returned to the test to assert on
        return exc, time.monotonic() - t0
    return None, time.monotonic() - t0


def test_good_document_and_redirects_to_http_are_followed(server: str, tmp_path: Path) -> None:
    assert fetch(server + "/good.xml", cache_dir=tmp_path / "a", kind="regulations").data == GOOD
    assert fetch(server + "/to-good", cache_dir=tmp_path / "b").data == GOOD
    assert fetch(server + "/to-relative", cache_dir=tmp_path / "c").data == GOOD


@pytest.mark.parametrize("path", ["/drip-headers", "/drip-body"])
def test_timeout_is_total_for_a_server_sending_a_byte_at_a_time(
    server: str, tmp_path: Path, path: str
) -> None:
    """Before: the timeout applied to each socket read, so the drip (a byte every 0.2 s, never
    idle for 0.5 s) was read to its end, ~20–900 s. Now the whole exchange stops at 0.5 s."""
    exc, took = _timed(lambda: fetch(server + path, cache_dir=tmp_path, timeout_s=0.5))
    assert isinstance(exc, InputError), exc
    assert "within the timeout of 0.5 s" in str(exc)
    assert took < 2.0


def test_timeout_is_total_for_a_dripping_tls_handshake(server: str, tmp_path: Path) -> None:
    url = server.replace("http://", "https://") + "/good.xml"
    exc, took = _timed(lambda: fetch(url, cache_dir=tmp_path, timeout_s=0.5))
    assert isinstance(exc, InputError) and "within the timeout of 0.5 s" in str(exc), exc
    assert took < 2.0


def test_timeout_falls_back_to_a_cached_copy(server: str, tmp_path: Path) -> None:
    # A validated copy of the slow URL in the cache, as an earlier successful fetch leaves it.
    url = server + "/drip-body"
    key = hashlib.sha256(url.encode()).hexdigest()[:32]
    (tmp_path / f"{key}.xml").write_bytes(GOOD)
    meta = {"url": url, "etag": None, "last_modified": None, "sha256": hashlib.sha256(GOOD).hexdigest()}
    (tmp_path / f"{key}.json").write_text(json.dumps(meta))
    with pytest.warns(UserWarning, match="timeout of 0.5 s; using the cached copy"):
        got = fetch(url, cache_dir=tmp_path, timeout_s=0.5)
    assert got.origin == "cache-offline" and got.data == GOOD


def test_garbage_status_line_is_one_clear_error(server: str, tmp_path: Path) -> None:
    with pytest.raises(InputError, match="malformed HTTP response") as exc:
        fetch(server + "/garbage", cache_dir=tmp_path)
    assert "\n" not in str(exc.value) and "\r" not in str(exc.value)


@pytest.mark.parametrize("path", ["/to-file", "/to-ftp"])
def test_redirect_to_another_scheme_is_refused(server: str, tmp_path: Path, path: str) -> None:
    with pytest.raises(InputError, match=r"redirect to '(file|ftp)://.*' refused \(only http"):
        fetch(server + path, cache_dir=tmp_path)


def test_endless_body_stops_at_the_size_limit_in_bounded_memory(server: str, tmp_path: Path) -> None:
    tracemalloc.start()
    try:
        exc, took = _timed(lambda: fetch(server + "/endless", cache_dir=tmp_path, max_bytes=1 << 20))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert isinstance(exc, DataFormatError) and "exceeds the limit of 1048576 bytes" in str(exc)
    assert peak < 16 << 20
    assert took < 5.0


def test_unwritable_cache_warns_and_the_load_succeeds(server: str, tmp_path: Path) -> None:
    blocker = tmp_path / "not-a-dir"
    blocker.write_text("x")  # a file where the cache directory should be: mkdir fails, even as root
    with pytest.warns(UserWarning, match="not cached in"):
        got = fetch(server + "/good.xml", cache_dir=blocker / "mission")
    assert got.origin == "network" and got.data == GOOD


@pytest.mark.parametrize("bad", [-1.0, 0.0, math.nan, math.inf, "soon"])
def test_bad_timeouts_are_refused(server: str, tmp_path: Path, bad: object) -> None:
    with pytest.raises(InputError, match="timeout: expected"):
        fetch(server + "/good.xml", cache_dir=tmp_path, timeout_s=bad)  # type: ignore[arg-type]


@pytest.mark.parametrize("bad", ["-1", "0", "nan", "inf"])
def test_cli_refuses_bad_timeouts(bad: str) -> None:
    res = CliRunner().invoke(main, ["db", "validate", "http://127.0.0.1:9/x.xml", "--timeout", bad])
    assert res.exit_code == 2, res.output


def _one_error_line(res) -> str:  # type: ignore[no-untyped-def]
    lines = res.stderr.strip().splitlines()
    assert res.exit_code == 1 and len(lines) == 1 and lines[0].startswith("error: "), res.stderr
    assert "Traceback" not in res.output
    return lines[0]


def test_cli_garbage_status_and_slow_server_are_one_line(server: str, tmp_path: Path) -> None:
    env = {"UASNAV_CACHE_DIR": str(tmp_path)}
    runner = CliRunner()
    line = _one_error_line(runner.invoke(main, ["db", "validate", server + "/garbage"], env=env))
    assert "malformed HTTP response" in line
    t0 = time.monotonic()
    res = runner.invoke(main, ["db", "validate", server + "/drip-headers", "--timeout", "0.5"], env=env)
    assert time.monotonic() - t0 < 2.0
    assert "timeout of 0.5 s" in _one_error_line(res)


def test_dev_zero_hits_the_size_limit_on_bytes_read() -> None:
    """Before: the size check used os.path.getsize (0 for a device), then read() forever."""
    exc, took = _timed(lambda: load_document("/dev/zero", max_bytes=1 << 20))
    assert isinstance(exc, ResourceLimitError) and "size limit of 1048576 bytes" in str(exc)
    assert took < 5.0
    res = CliRunner().invoke(main, ["db", "validate", "/dev/zero", "--max-bytes", "1000"])
    assert "/dev/zero: larger than the size limit of 1000 bytes" in _one_error_line(res)
    res = CliRunner().invoke(main, ["select", "--db", "/dev/zero"])
    assert "/dev/zero" in _one_error_line(res)


def test_a_fifo_is_refused_before_it_is_opened(tmp_path: Path) -> None:
    """A FIFO would block ``open()`` until a writer comes (forever if none does): it is refused
    by name before any read, whether or not a writer is waiting."""
    fifo = tmp_path / "pipe.xml"
    os.mkfifo(fifo)
    with pytest.raises(InputError, match=r"pipe\.xml: a FIFO \(named pipe\), not a file"):
        load_document(str(fifo), max_bytes=100_000)
    res = CliRunner().invoke(main, ["db", "validate", str(fifo)])
    assert "a FIFO" in _one_error_line(res)
