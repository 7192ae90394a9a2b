"""Oversize uploads on a page answered by the page, not by raw JSON.

The request guard refuses a body over its limit before the application reads it, with the
API's JSON error. A browser posting a form would show that JSON in place of the page; this
wrapper (outside the guard, so the guard's checks still come first) turns the guard's 413 on a
page's form post into that page, the message beside its upload fields. The body was never read,
so the fields show their defaults; the page's script refuses such a file before it is sent, with
the form kept.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable

from starlette.requests import Request
from starlette.responses import Response
from starlette.types import ASGIApp, Message, Receive, Scope, Send

#: A page's answer to an oversize post: (request, message) → the page.
PageRenderer = Callable[[Request, str], Awaitable[Response] | Response]


class OversizePages:
    """ASGI wrapper: a 413 on ``POST`` to one of ``pages`` becomes that page (status 413)."""

    def __init__(self, app: ASGIApp, pages: dict[str, PageRenderer], max_body_bytes: int) -> None:
        self.app, self.pages, self.max_body_bytes = app, pages, max_body_bytes

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        render = self.pages.get(scope.get("path", "")) if scope["type"] == "http" else None
        if render is None or scope.get("method") != "POST":
            await self.app(scope, receive, send)
            return
        swallowed = False

        async def inner(message: Message) -> None:
            nonlocal swallowed
            if message["type"] == "http.response.start" and message["status"] == 413:
                swallowed = True
                return
            if swallowed:
                if message["type"] == "http.response.body" and not message.get("more_body", False):
                    mb = self.max_body_bytes // 2**20
                    text = f"the files sent together are over {mb} MB: choose a smaller file"
                    resp = render(Request(scope), text)
                    if not isinstance(resp, Response):
                        resp = await resp
                    await resp(scope, receive, send)
                return
            await send(message)

        await self.app(scope, receive, inner)


__all__ = ["OversizePages", "PageRenderer"]
