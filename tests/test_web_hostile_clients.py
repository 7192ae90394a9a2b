"""``uasnav serve`` under hostile clients: the real command on a loopback port, raw sockets.

The deadlines are shortened through the environment so that each probe takes about a second;
the queue and 503 of heavy requests are pinned on the middleware with a slow stand-in app.
"""

from __future__ import annotations

import asyncio
import http.client
import socket
import time

import pytest
from click.testing import CliRunner

from uasnav.cli import main
from uasnav.web.process import running_server
from uasnav.web.server_limits import ServerLimitsMiddleware


def _raw(port: int, data: bytes, wait_s: float = 10.0) -> tuple[bytes, float]:
    """Send ``data``, then read until the server closes (or ``wait_s``): (answer, seconds)."""
    t0 = time.monotonic()
    with socket.create_connection(("127.0.0.1", port), timeout=wait_s) as s:
        s.sendall(data)
        got = b""
        try:
            while chunk := s.recv(65536):
                got += chunk
        except TimeoutError:
            pytest.fail(f"the server held the connection past {wait_s} s: {got[:200]!r}")
        except ConnectionResetError:
            pass
    return got, time.monotonic() - t0


@pytest.fixture(scope="module")
def server():  # type: ignore[no-untyped-def]
    mp = pytest.MonkeyPatch()
    mp.setenv("UASNAV_SERVE_HEAD_TIMEOUT_S", "1")
    mp.setenv("UASNAV_SERVE_BODY_TIMEOUT_S", "1")
    try:
        with running_server() as s:
            yield s
    finally:
        mp.undo()


def test_a_dribbled_request_head_is_cut(server) -> None:  # type: ignore[no-untyped-def]
    got, took = _raw(server.port, b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: a")
    assert got == b"" and took < 10


def test_a_lying_content_length_is_answered_408(server) -> None:  # type: ignore[no-untyped-def]
    head = b"POST /api/select HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
    got, took = _raw(server.port, head + b'Content-Length: 5000\r\n\r\n{"mission"')
    assert got.startswith(b"HTTP/1.1 408"), got[:200]
    assert took < 10


def test_non_http_bytes_are_answered_and_closed(server) -> None:  # type: ignore[no-untyped-def]
    got, _ = _raw(server.port, b"\x16\x03\x01\x02\x00\x01\x00\x01\xfc\x03\x03garbage\r\n\r\n")
    assert got.startswith(b"HTTP/1.1 400"), got[:200]
    got, took = _raw(server.port, b"\x00" * 100)  # no line end at all: closed at the head deadline
    assert took < 10


def test_a_client_that_leaves_mid_body_is_not_an_error(server) -> None:  # type: ignore[no-untyped-def]
    head = b"POST /api/select HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
    with socket.create_connection(("127.0.0.1", server.port)) as s:
        s.sendall(head + b"Content-Length: 100\r\n\r\n{")
    time.sleep(1.5)
    c = http.client.HTTPConnection("127.0.0.1", server.port, timeout=10)
    c.request("GET", "/api/options")
    assert c.getresponse().status == 200
    log = server.log()
    assert "Traceback" not in log and "Exception in ASGI application" not in log


def test_serve_refuses_an_impossible_host_in_one_line() -> None:
    res = CliRunner().invoke(main, ["serve", "--host", "256.256.256.256"])
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert res.exit_code == 1 and len(lines) == 1 and lines[0].startswith("error: --host 256.256.256.256")
    res = CliRunner(env={"UASNAV_SERVE_BODY_TIMEOUT_S": "nan"}).invoke(main, ["serve"])
    assert res.exit_code == 1 and "UASNAV_SERVE_BODY_TIMEOUT_S" in res.stderr


def test_heavy_requests_queue_then_get_503_while_pages_answer() -> None:
    async def slow_app(scope, receive, send):  # type: ignore[no-untyped-def]
        if scope["method"] == "POST":
            await asyncio.sleep(0.3)
        await send({"type": "http.response.start", "status": 200, "headers": []})
        await send({"type": "http.response.body", "body": b"ok"})

    mw = ServerLimitsMiddleware(
        slow_app, body_timeout_s=5, heavy_concurrency=2, heavy_queue=2, heavy_wait_s=5
    )

    async def call(method: str) -> tuple[int, dict[bytes, bytes], float]:
        out: dict[str, object] = {}

        async def receive():  # type: ignore[no-untyped-def]
            return {"type": "http.request", "body": b"", "more_body": False}

        async def send(message):  # type: ignore[no-untyped-def]
            if message["type"] == "http.response.start":
                out["status"], out["headers"] = message["status"], dict(message["headers"])

        t0 = time.monotonic()
        scope = {"type": "http", "method": method, "path": "/api/trajectory/predict", "headers": []}
        await mw(scope, receive, send)
        return out["status"], out["headers"], time.monotonic() - t0  # type: ignore[return-value]

    async def scenario():  # type: ignore[no-untyped-def]
        posts = [asyncio.create_task(call("POST")) for _ in range(6)]
        await asyncio.sleep(0.05)
        page = await call("GET")
        return page, await asyncio.gather(*posts)

    page, posts = asyncio.run(scenario())
    assert page[0] == 200 and page[2] < 0.2  # a page does not wait behind the computations
    codes = sorted(p[0] for p in posts)
    assert codes == [200, 200, 200, 200, 503, 503]  # 2 running + 2 queued; the rest refused
    assert all(p[1].get(b"retry-after") == b"5" for p in posts if p[0] == 503)
