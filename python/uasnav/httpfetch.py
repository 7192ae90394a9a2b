"""The project's hardened HTTP transport: a total deadline, redirects to http(s) only, bounded size.

Shared by the mission selector's document fetch (:func:`uasnav.mission.loading.fetch`, which adds
a validated cache) and the fleet runner's log download (:func:`download`, which streams a log to
a file on the worker). One client, one set of guarantees:

* ``timeout_s`` bounds the whole exchange (connect, TLS, status line, headers, redirects and
  body), not each socket read: a timer shuts every socket of the fetch down at the deadline, so
  a server dripping one byte per second is cut too;
* redirects are followed (at most 5) to ``http://`` and ``https://`` only; ``file://``,
  ``ftp://`` … targets are refused with the target named;
* at most ``max_bytes`` bytes are accepted: a larger ``Content-Length`` is refused before the
  body is read, and the body is counted while it is read whatever the server claims.
"""

from __future__ import annotations

import http.client
import socket
import threading
import time
import urllib.error
import urllib.parse
import urllib.request
from typing import BinaryIO

from uasnav.errors import InputError

#: Bytes read at a time while streaming a body to a file.
CHUNK = 1 << 20


def is_url(source: object) -> bool:
    """True for ``http://`` and ``https://`` sources."""
    return isinstance(source, str) and source.lower().startswith(("http://", "https://"))


class FetchError(InputError):
    """A URL that could not be fetched; the message names the URL and the reason on one line."""


def new_request(url: str, headers: dict[str, str]) -> urllib.request.Request:
    """``urllib.request.Request(url, headers=…)``; a malformed URL (``http://[::1``) is a
    :class:`FetchError` naming it instead of urllib's bare ``ValueError``."""
    try:
        return urllib.request.Request(url, headers=headers)
    except ValueError as e:
        raise FetchError(f"{url}: not a valid URL ({e})") from None


class Deadline:
    """A total deadline for one fetch: at expiry every connection it watches is shut down.

    ``socket`` timeouts apply to each read, so a server sending one byte per second never trips
    them; shutting the socket down from a timer thread wakes any blocked read (connect, status
    line, headers, body) at the deadline, whatever the server does.
    """

    def __init__(self, seconds: float) -> None:
        self.end = time.monotonic() + seconds
        self.expired = False
        self._lock = threading.Lock()
        self._socks: list[socket.socket] = []
        self._timer = threading.Timer(seconds, self._expire)
        self._timer.daemon = True
        self._timer.start()

    def remaining(self) -> float:
        return max(self.end - time.monotonic(), 1e-3)

    def watch(self, sock: socket.socket | None) -> None:
        if sock is None:
            return
        with self._lock:
            self._socks.append(sock)
            if self.expired:
                self._shut(sock)

    @staticmethod
    def _shut(sock: socket.socket) -> None:
        try:
            sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass  # already closed

    def _expire(self) -> None:
        with self._lock:
            self.expired = True
            for sock in self._socks:
                self._shut(sock)

    def cancel(self) -> None:
        self._timer.cancel()


def opener(deadline: Deadline) -> urllib.request.OpenerDirector:
    """A urllib opener (proxies from the environment as usual) whose connections obey
    ``deadline`` and whose redirects go to http(s) only."""

    def watched(base: type[http.client.HTTPConnection]) -> type[http.client.HTTPConnection]:
        class Conn(base):  # type: ignore[misc, valid-type]
            def __init__(self, *args: object, **kw: object) -> None:
                kw["timeout"] = deadline.remaining()  # per operation; the deadline is total
                super().__init__(*args, **kw)  # type: ignore[arg-type]
                # Watch the TCP socket as soon as it exists, so that a TLS handshake or a proxy
                # CONNECT that drips is cut at the deadline too.
                create = self._create_connection  # type: ignore[has-type]

                def create_watched(*a: object, **k: object) -> socket.socket:
                    sock = create(*a, **k)
                    deadline.watch(sock)
                    return sock

                self._create_connection = create_watched

        return Conn

    http_conn, https_conn = watched(http.client.HTTPConnection), watched(http.client.HTTPSConnection)

    class Http(urllib.request.HTTPHandler):
        def http_open(self, req):  # type: ignore[no-untyped-def]
            return self.do_open(http_conn, req)

    class Https(urllib.request.HTTPSHandler):
        def https_open(self, req):  # type: ignore[no-untyped-def]
            return self.do_open(https_conn, req, context=self._context)  # type: ignore[attr-defined]

    class Redirect(urllib.request.HTTPRedirectHandler):
        max_redirections = 5

        def http_error_302(self, req, fp, code, msg, headers):  # type: ignore[no-untyped-def]
            # urllib follows ftp:// redirects and reports file:// ones as an HTTP error; only
            # http(s) is promised, so anything else is refused here with its target named.
            target = headers.get("location") or headers.get("uri") or ""
            scheme = urllib.parse.urlsplit(urllib.parse.urljoin(req.full_url, target)).scheme.lower()
            if scheme not in ("http", "https"):
                fp.close()
                raise InputError(
                    f"{req.full_url}: redirect to {target!r} refused (only http:// and https:// are followed)"
                )
            return super().http_error_302(req, fp, code, msg, headers)

        http_error_301 = http_error_303 = http_error_307 = http_error_308 = http_error_302

    return urllib.request.build_opener(Http, Https, Redirect)


def one_line(exc: BaseException | str) -> str:
    """An exception's text on one line, at most 200 characters (servers send anything)."""
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) <= 200 else text[:197] + "..."


def download(
    url: str,
    sink: BinaryIO,
    *,
    timeout_s: float,
    max_bytes: int,
    accept: str = "*/*",
    user_agent: str = "uasnav",
) -> int:
    """Stream the body of ``url`` into ``sink`` (an open binary file); returns the bytes written.

    Within ``timeout_s`` seconds in total, following redirects to http(s) only, at most
    ``max_bytes`` bytes. Raises :class:`FetchError` (``"URL: HTTP 404 Not Found"``, ``"URL:
    cannot fetch (no complete answer within the timeout of 2 s)"``, ``"URL: larger than the
    size limit of N bytes"``, ``"URL: redirect to 'file:///…' refused …"``) for any failure;
    ``sink`` may then hold a partial body, which the caller discards.
    """
    if not is_url(url):
        raise FetchError(f"{url!r}: only http:// and https:// URLs are fetched")
    req = new_request(url, {"User-Agent": user_agent, "Accept": accept})
    deadline = Deadline(timeout_s)
    late = f"{url}: cannot fetch (no complete answer within the timeout of {timeout_s:g} s)"
    got = 0
    try:
        with opener(deadline).open(req, timeout=deadline.remaining()) as resp:
            length = resp.headers.get("Content-Length")
            if length is not None and length.strip().isdigit() and int(length) > max_bytes:
                raise FetchError(
                    f"{url}: Content-Length {length.strip()} exceeds the size limit of {max_bytes} bytes"
                )
            while True:
                block = resp.read(min(CHUNK, max_bytes + 1 - got))
                if not block:
                    break
                got += len(block)
                if got > max_bytes:
                    raise FetchError(f"{url}: larger than the size limit of {max_bytes} bytes")
                sink.write(block)
    except FetchError:
        raise
    except InputError as exc:  # a refused redirect (from the opener)
        raise FetchError(one_line(exc)) from None
    except urllib.error.HTTPError as exc:
        exc.close()
        if deadline.expired:
            raise FetchError(late) from None
        raise FetchError(f"{url}: HTTP {exc.code} {one_line(exc.reason)}") from None
    except (urllib.error.URLError, http.client.HTTPException, OSError) as exc:
        if deadline.expired:
            raise FetchError(late) from None
        if isinstance(exc, http.client.HTTPException) and not isinstance(exc, ConnectionError):
            raise FetchError(
                f"{url}: cannot fetch (malformed HTTP response ({type(exc).__name__}: {one_line(exc)}))"
            ) from None
        raise FetchError(f"{url}: cannot fetch ({one_line(getattr(exc, 'reason', None) or exc)})") from None
    finally:
        deadline.cancel()
    if deadline.expired:
        # the deadline fired between two reads: what was read may be a truncated body
        raise FetchError(late)
    return got


__all__ = ["CHUNK", "Deadline", "FetchError", "download", "is_url", "one_line", "opener"]
