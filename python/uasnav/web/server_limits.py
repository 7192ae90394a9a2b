"""Connection deadlines and bounded concurrency of ``uasnav serve`` under hostile clients.

The application's routes trust the server to bound what a client can hold:

- **Request head deadline** (:data:`HEAD_TIMEOUT_S`): a connection that has not sent a complete
  request head within it (slowloris, non-HTTP bytes without a line end) is closed. Bytes that
  are not HTTP at all are answered 400 by the parser and closed.
- **Body deadline** (:data:`BODY_TIMEOUT_S`): a body must arrive whole within it from the first
  read; a ``Content-Length`` larger than what is sent, or a body dribbled a byte at a time, is
  answered 408 and the connection closed.
- **Heavy requests** (``POST`` of a trajectory prediction, :data:`HEAVY_PATHS`: seconds of
  CPU for a long uploaded plan) run at most :data:`HEAVY_CONCURRENCY` at once; up to :data:`HEAVY_QUEUE` more
  wait, each at most :data:`HEAVY_WAIT_S`; beyond that the answer is ``503`` with
  ``Retry-After``. Pages and the selection (milliseconds each) never wait behind them, so
  ``/api/options`` and the forms stay responsive while predictions run.
- **Client disconnects** during a request end it quietly (no traceback in the server log).
- uvicorn's own limits: keep-alive :data:`KEEP_ALIVE_S`, at most :data:`MAX_CONNECTIONS`
  connections (more are answered 503), request heads of at most :data:`MAX_HEAD_BYTES`.

:func:`harden` wraps the ASGI application; :func:`uvicorn_settings` gives the keyword
arguments of ``uvicorn.run`` (including the protocol class with the head deadline). The two
deadlines can be set with ``UASNAV_SERVE_HEAD_TIMEOUT_S`` and ``UASNAV_SERVE_BODY_TIMEOUT_S``
(seconds, > 0), read when the server starts.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
from collections.abc import Awaitable, Callable
from typing import Any

from uasnav.web.security import ASGIApp, Message, Receive, Scope, Send

#: Seconds a connection may take to send a complete request head.
HEAD_TIMEOUT_S = 10.0
#: Seconds a request body may take to arrive whole.
BODY_TIMEOUT_S = 20.0
#: Path prefixes whose ``POST`` is a heavy request (trajectory prediction of an uploaded plan).
HEAVY_PATHS = ("/trajectory", "/api/trajectory")
#: Heavy requests computed at once (default: one per core, at least 2).
HEAVY_CONCURRENCY = max(2, os.cpu_count() or 1)
#: Heavy requests that may wait for a slot; more are answered 503 at once.
HEAVY_QUEUE = 8
#: Seconds a queued heavy request waits for a slot before it is answered 503.
HEAVY_WAIT_S = 30.0
#: ``Retry-After`` of a 503 (s).
RETRY_AFTER_S = 5
#: Seconds an idle keep-alive connection is kept.
KEEP_ALIVE_S = 5
#: Open connections served at once; more are answered 503 by uvicorn.
MAX_CONNECTIONS = 256
#: Largest request head (request line + headers), bytes.
MAX_HEAD_BYTES = 16 * 1024


def _seconds(env: str, default: float) -> float:
    from uasnav.limits import env_positive

    return env_positive(env, default, "seconds")


#: Work one plan prediction may cost on the server (elementary operations, ≈ 10⁹ per second):
#: a plan within the upload limit can hold 10⁵ points (15 s of CPU); beyond 3 s of CPU (20 000
#: points) it is refused up front with its estimate. ``UASNAV_WEB_MAX_PLAN_WORK`` overrides it.
MAX_PLAN_WORK = 3e9


def check_plan_work(n_points: int) -> None:
    """Refuse, before predicting, a plan of ``n_points`` whose estimated work exceeds the server's
    limit (:data:`MAX_PLAN_WORK`), naming the estimate (an :class:`~uasnav.errors.InputError`)."""
    from uasnav.errors import InputError
    from uasnav.limits import PREDICTION_OPS_PER_POINT, env_positive

    limit = env_positive("UASNAV_WEB_MAX_PLAN_WORK", MAX_PLAN_WORK, "operations such as 3e9")
    ops = n_points * PREDICTION_OPS_PER_POINT
    if ops > limit:
        raise InputError(
            f"{n_points} plan points need about {ops:.2g} operations (≈ {ops / 1e9:.0f} s of CPU), more than "
            f"this server's limit of {limit:.2g} per prediction; split the plan, or run "
            "`uasnav trajectory predict` on your own machine"
        )


async def _answer(
    send: Send, status: int, message: str, headers: list[tuple[bytes, bytes]] | None = None
) -> None:
    body = json.dumps({"error": message}).encode()
    await send(
        {
            "type": "http.response.start",
            "status": status,
            "headers": [
                (b"content-type", b"application/json"),
                (b"content-length", str(len(body)).encode()),
                (b"connection", b"close"),
                *(headers or []),
            ],
        }
    )
    await send({"type": "http.response.body", "body": body})


class ServerLimitsMiddleware:
    """ASGI middleware: body deadline, bounded heavy requests, quiet client disconnects (module
    docs). One instance per application: the slots are shared by its requests."""

    def __init__(
        self,
        app: ASGIApp,
        *,
        body_timeout_s: float | None = None,
        heavy_concurrency: int = HEAVY_CONCURRENCY,
        heavy_queue: int = HEAVY_QUEUE,
        heavy_wait_s: float = HEAVY_WAIT_S,
    ) -> None:
        self.app = app
        if body_timeout_s is None:
            body_timeout_s = _seconds("UASNAV_SERVE_BODY_TIMEOUT_S", BODY_TIMEOUT_S)
        self.body_timeout_s = body_timeout_s
        self.heavy_concurrency = heavy_concurrency
        self.heavy_queue = heavy_queue
        self.heavy_wait_s = heavy_wait_s
        self._slots: asyncio.Semaphore | None = None
        self._waiting = 0

    def _heavy(self, scope: Scope) -> bool:
        path = str(scope.get("path", ""))
        return scope.get("method") == "POST" and any(path.startswith(p) for p in HEAVY_PATHS)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        state = {"started": False, "answered": False}

        async def tracked(message: Message) -> None:
            if state["answered"]:
                return  # the request was answered here (408): what the app sends after is dropped
            if message["type"] == "http.response.start":
                state["started"] = True
            await send(message)

        async def on_timeout() -> None:
            # answered here rather than raised: the application's error handler would turn an
            # exception into a 500
            if not state["started"] and not state["answered"]:
                state["answered"] = True
                await _answer(send, 408, f"request body not received within {self.body_timeout_s:g} s")

        app_receive = self._deadlined(receive, on_timeout)
        try:
            if self._heavy(scope):
                await self._heavy_call(scope, app_receive, tracked)
            else:
                await self.app(scope, app_receive, tracked)
        except Exception as e:
            if state["answered"] or _is_disconnect(e):
                return  # the client went away or was answered 408: nothing to log
            raise

    async def _heavy_call(self, scope: Scope, receive: Receive, send: Send) -> None:
        if self._slots is None:
            self._slots = asyncio.Semaphore(self.heavy_concurrency)
        retry = [(b"retry-after", str(RETRY_AFTER_S).encode())]
        if not self._slots.locked():
            await self._slots.acquire()  # a free slot: taken at once
        elif self._waiting >= self.heavy_queue:
            await _answer(send, 503, "server busy: too many computations queued, retry later", retry)
            return
        else:
            self._waiting += 1
            try:
                await asyncio.wait_for(self._slots.acquire(), timeout=self.heavy_wait_s)
            except asyncio.TimeoutError:
                await _answer(send, 503, "server busy: no computation slot free in time, retry later", retry)
                return
            finally:
                self._waiting -= 1
        try:
            await self.app(scope, receive, send)
        finally:
            self._slots.release()

    def _deadlined(self, receive: Receive, on_timeout: Callable[[], Awaitable[None]]) -> Receive:
        """``receive`` with the body deadline: past it, ``on_timeout`` answers the client and the
        application sees a disconnect."""
        deadline: list[float] = []
        timeout = self.body_timeout_s

        async def inner() -> Message:
            loop = asyncio.get_running_loop()
            if not deadline:
                deadline.append(loop.time() + timeout)
            if deadline[0] == float("inf"):
                return await receive()
            left = deadline[0] - loop.time()
            try:
                if left <= 0:
                    raise asyncio.TimeoutError
                message = await _within(receive(), left)
            except asyncio.TimeoutError:
                await on_timeout()
                return {"type": "http.disconnect"}
            if message["type"] == "http.request" and not message.get("more_body", False):
                deadline[0] = float("inf")  # body complete: later receives wait for a disconnect
            return message

        return inner


async def _within(awaitable: Awaitable[Message], seconds: float) -> Message:
    """``await awaitable`` with a deadline; ``asyncio.timeout`` (3.11+) costs no extra task."""
    timeout = getattr(asyncio, "timeout", None)
    if timeout is None:  # Python 3.10
        return await asyncio.wait_for(awaitable, timeout=seconds)
    async with timeout(seconds):
        return await awaitable


def _is_disconnect(e: BaseException) -> bool:
    """Whether ``e`` means the client closed the connection during the request."""
    with contextlib.suppress(ImportError):
        from starlette.requests import ClientDisconnect

        if isinstance(e, ClientDisconnect):
            return True
    if isinstance(e, ConnectionError):
        return True
    return type(e).__name__ in ("ClientDisconnected", "ClientDisconnect")


def harden(app: ASGIApp) -> ASGIApp:
    """``app`` behind :class:`ServerLimitsMiddleware` (module docs).

    A Starlette application inside ``app`` (found through the ``.app`` of its middlewares) also
    gets a handler for client disconnects, which would otherwise reach its catch-all error
    handler and be logged as an unexpected error with a traceback."""
    inner: Any = app
    for _ in range(8):
        if hasattr(inner, "add_exception_handler"):
            from starlette.requests import ClientDisconnect

            inner.add_exception_handler(ClientDisconnect, _client_left)
            break
        inner = getattr(inner, "app", None)
        if inner is None:
            break
    return ServerLimitsMiddleware(app)


async def _client_left(request: Any, exc: Exception) -> Any:
    """The client closed the connection during the request: nobody reads an answer."""
    from starlette.responses import Response

    return Response(status_code=499)


def _head_deadline_protocol(head_timeout_s: float) -> type:
    """uvicorn's h11 protocol with a deadline on each request head (:data:`HEAD_TIMEOUT_S`)."""
    from uvicorn.protocols.http.h11_impl import H11Protocol

    class HeadDeadlineProtocol(H11Protocol):  # type: ignore[misc]
        _head_timer: asyncio.TimerHandle | None = None
        _awaiting: Any = None

        def connection_made(self, transport: Any) -> None:
            super().connection_made(transport)
            self._arm()

        def _arm(self) -> None:
            self._awaiting = self.cycle
            self._head_timer = self.loop.call_later(head_timeout_s, self._head_expired)

        def _disarm(self) -> None:
            if self._head_timer is not None:
                self._head_timer.cancel()
                self._head_timer = None

        def _head_expired(self) -> None:
            self._head_timer = None
            if self.cycle is self._awaiting and not self.transport.is_closing():
                self.transport.close()  # no complete request head in time

        def data_received(self, data: bytes) -> None:
            if self._head_timer is None and (self.cycle is None or self.cycle.response_complete):
                self._arm()
            super().data_received(data)
            if self.cycle is not self._awaiting:
                self._disarm()

        def connection_lost(self, exc: Exception | None) -> None:
            self._disarm()
            super().connection_lost(exc)

    return HeadDeadlineProtocol


def uvicorn_settings() -> dict[str, Any]:
    """Keyword arguments of ``uvicorn.run`` for the limits of the module docs."""
    return {
        "http": _head_deadline_protocol(_seconds("UASNAV_SERVE_HEAD_TIMEOUT_S", HEAD_TIMEOUT_S)),
        "timeout_keep_alive": KEEP_ALIVE_S,
        "limit_concurrency": MAX_CONNECTIONS,
        "h11_max_incomplete_event_size": MAX_HEAD_BYTES,
        "timeout_graceful_shutdown": 5,
    }


__all__ = [
    "BODY_TIMEOUT_S",
    "HEAD_TIMEOUT_S",
    "HEAVY_CONCURRENCY",
    "HEAVY_QUEUE",
    "ServerLimitsMiddleware",
    "harden",
    "uvicorn_settings",
]
