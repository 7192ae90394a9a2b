"""Request guards of ``uasnav serve``: Host and Origin checks, body size limit.

A server on loopback is still reachable from any web page the operator opens: a hostile page
can make the browser post forms to ``http://127.0.0.1:8000`` (cross-site request forgery) or
resolve its own domain name to 127.0.0.1 and read the answers (DNS rebinding). Two checks close
both: the ``Host`` header must name this server (a rebound name does not), and a state-changing
request (POST, PUT, PATCH, DELETE) carrying a foreign ``Origin`` — or a ``Sec-Fetch-Site`` of
``cross-site`` — is refused. Tools that send neither header (curl, scripts) are not browsers
and pass.
"""

from __future__ import annotations

import json
from collections.abc import Awaitable, Callable, Iterable, Mapping, MutableMapping
from typing import Any

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[Message]]
Send = Callable[[Message], Awaitable[None]]
ASGIApp = Callable[[Scope, Receive, Send], Awaitable[None]]

#: Host names always accepted: the loopback names.
LOOPBACK_HOSTS = ("127.0.0.1", "localhost", "::1")
_UNSAFE_METHODS = {"POST", "PUT", "PATCH", "DELETE"}


def split_host(value: str) -> str:
    """``"[::1]:8000"`` → ``"::1"``, ``"localhost:80"`` → ``"localhost"`` (lower case)."""
    v = value.strip().lower()
    if v.startswith("["):
        return v[1 : v.find("]")] if "]" in v else v
    return v.rsplit(":", 1)[0] if v.count(":") == 1 else v


async def _refuse(send: Send, status: int, message: str, field: str) -> None:
    body = json.dumps({"error": message, "field": field}).encode()
    await send(
        {
            "type": "http.response.start",
            "status": status,
            "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())],
        }
    )
    await send({"type": "http.response.body", "body": body})


class GuardMiddleware:
    """Refuses foreign ``Host`` headers (400), cross-site state-changing requests (403) and
    bodies larger than ``max_body_bytes`` (413), before any route runs.

    Parameters
    ----------
    app : ASGI application
    allowed_hosts : iterable of str
        Host names (no port) this server answers to, besides :data:`LOOPBACK_HOSTS`.
    max_body_bytes : int
        Largest request body, bytes (declared by ``Content-Length`` or streamed).
    headers : mapping of str to str, optional
        Headers added to every response that does not set them (Content-Security-Policy …).
        Done here, in plain ASGI, rather than in a Starlette ``BaseHTTPMiddleware``, which
        costs a task and a stream per request.
    """

    def __init__(
        self,
        app: ASGIApp,
        allowed_hosts: Iterable[str],
        max_body_bytes: int,
        headers: Mapping[str, str] | None = None,
    ) -> None:
        self.app = app
        self.allowed = {h.lower() for h in (*LOOPBACK_HOSTS, *allowed_hosts)}
        self.max_body_bytes = max_body_bytes
        self.headers = [
            (k.lower().encode("latin-1"), v.encode("latin-1")) for k, v in (headers or {}).items()
        ]

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        headers = {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope["headers"]}
        host = headers.get("host", "")
        if split_host(host) not in self.allowed:
            await _refuse(send, 400, f"Host {host!r} is not this server (DNS rebinding guard)", "host")
            return
        if scope["method"] in _UNSAFE_METHODS:
            origin = headers.get("origin")
            if origin is not None:
                o = origin.strip().lower()
                scheme = scope.get("scheme", "http")
                if o != f"{scheme}://{host.strip().lower()}":
                    await _refuse(send, 403, f"cross-site request from Origin {origin!r} refused", "origin")
                    return
            elif headers.get("sec-fetch-site", "").lower() == "cross-site":
                await _refuse(send, 403, "cross-site request refused", "origin")
                return
            declared = headers.get("content-length")
            if declared is not None:
                try:
                    too_big = int(declared) > self.max_body_bytes
                except ValueError:
                    await _refuse(send, 400, "malformed Content-Length", "content-length")
                    return
                if too_big:
                    await _refuse(send, 413, f"request body over {self.max_body_bytes} bytes", "body")
                    return
            receive = self._limited(receive)
        await self.app(scope, receive, self._with_headers(send))

    def _with_headers(self, send: Send) -> Send:
        extra = self.headers
        if not extra:
            return send

        async def inner(message: Message) -> None:
            if message["type"] == "http.response.start":
                have = {k.lower() for k, _ in message.get("headers", [])}
                message["headers"] = [
                    *message.get("headers", []),
                    *((k, v) for k, v in extra if k not in have),
                ]
            await send(message)

        return inner

    def _limited(self, receive: Receive) -> Receive:
        """``receive`` that stops a streamed (chunked) body past the limit."""
        seen = 0
        limit = self.max_body_bytes

        async def inner() -> Message:
            nonlocal seen
            message = await receive()
            if message["type"] == "http.request":
                seen += len(message.get("body", b""))
                if seen > limit:
                    raise BodyTooLarge(limit)
            return message

        return inner


class BodyTooLarge(Exception):
    """A streamed request body passed the server's limit (answered 413)."""

    def __init__(self, limit: int) -> None:
        super().__init__(f"request body over {limit} bytes")
        self.limit = limit


__all__ = ["LOOPBACK_HOSTS", "BodyTooLarge", "GuardMiddleware", "split_host"]
