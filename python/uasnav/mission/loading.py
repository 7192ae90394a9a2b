"""Safe loading of the mission selector's XML documents from a path or an http(s) URL.

The thesis keeps its database "stored on a different server and updated online" (§5.2.2.1);
a document fetched from the network is untrusted input, so parsing is hardened:

* no DTD at all: a ``<!DOCTYPE`` is rejected before libxml2 sees the document, so neither
  entity expansion (billion laughs) nor external entities (XXE) can happen, and the parser is
  also configured with ``resolve_entities=False``, ``load_dtd=False``, ``no_network=True``;
* bounded size (``max_bytes``, checked before parsing and while downloading) and bounded
  element depth (``max_depth``, checked after parsing; libxml2's own limit without
  ``huge_tree`` stops pathological depths during parsing);
* every document is validated against the XSD shipped in the package for its root element,
  and schema errors name the line and the broken rule.

URL fetches have a total deadline (connect + headers + body), follow redirects to http(s)
only, read at most ``max_bytes + 1`` bytes (local files and devices too), and keep an on-disk
cache revalidated with HTTP conditional requests (``ETag`` / ``Last-Modified``); only
documents that passed validation are cached (an unwritable cache only warns), and a cached
body is checked against its recorded SHA-256 before use.
"""

from __future__ import annotations

import hashlib
import http.client
import json
import math
import os
import urllib.error
import urllib.parse
import urllib.request
import warnings
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from lxml import etree

from uasnav.atomicfile import atomic_write_bytes, atomic_write_text
from uasnav.errors import DataFormatError, InputError, ResourceLimitError
from uasnav.httpfetch import Deadline as _Deadline
from uasnav.httpfetch import new_request
from uasnav.httpfetch import one_line as _one_line
from uasnav.httpfetch import opener as _opener
from uasnav.limits import read_file_limited, read_limited

#: Largest document accepted (bytes).
MAX_BYTES = 8 * 1024 * 1024
#: Deepest element nesting accepted (our schemas need 5).
MAX_DEPTH = 32
#: Default network timeout (s).
TIMEOUT_S = 10.0

#: Root element → schema file shipped in ``uasnav/mission/data``.
SCHEMAS = {"database": "database.xsd", "regulations": "regulations.xsd", "matrices": "matrices.xsd"}

_SCHEMA_CACHE: dict[str, etree.XMLSchema] = {}


def _parser() -> etree.XMLParser:
    return etree.XMLParser(
        resolve_entities=False,
        load_dtd=False,
        dtd_validation=False,
        no_network=True,
        huge_tree=False,
        remove_pis=True,
        collect_ids=False,
    )


def data_file(name: str) -> bytes:
    """Bytes of a file shipped in ``uasnav/mission/data`` (via importlib.resources)."""
    return resources.files("uasnav.mission").joinpath("data").joinpath(name).read_bytes()


def parse_bytes(data: bytes, where: str, *, max_bytes: int = MAX_BYTES, max_depth: int = MAX_DEPTH):
    """Parse ``data`` with the hardened parser.

    Parameters
    ----------
    data : bytes
        The document.
    where : str
        Path or URL used in error messages.
    max_bytes, max_depth : int
        Size (bytes) and element-depth limits.

    Returns
    -------
    lxml.etree._ElementTree

    Raises
    ------
    DataFormatError
        Oversize, DTD present, malformed XML (with its line), entity references, or too deep.
    """
    if len(data) > max_bytes:
        raise DataFormatError(f"document is {len(data)} bytes, limit is {max_bytes}", path=where)
    # XML requires the keyword in upper case; a UTF-16/32 document hides it from this scan,
    # the docinfo check after parsing catches that case.
    pos = data.find(b"<!DOCTYPE")
    if pos >= 0:
        line = data.count(b"\n", 0, pos) + 1
        raise DataFormatError(
            "DTD (<!DOCTYPE …>) is not allowed (entity expansion / XXE guard)", path=where, line=line
        )
    try:
        tree = etree.ElementTree(etree.fromstring(data, _parser()))
    except etree.XMLSyntaxError as exc:
        raise DataFormatError(f"malformed XML: {exc.msg}", path=where, line=exc.lineno) from None
    if tree.docinfo.internalDTD is not None or tree.docinfo.doctype:
        raise DataFormatError("DTD (<!DOCTYPE …>) is not allowed (entity expansion / XXE guard)", path=where)
    root = tree.getroot()
    stack = [(root, 1)]
    while stack:
        el, depth = stack.pop()
        if isinstance(el, etree._Entity):
            raise DataFormatError(
                f"entity reference {el.text!r} is not allowed", path=where, line=el.sourceline
            )
        if depth > max_depth:
            raise DataFormatError(f"element nesting deeper than {max_depth}", path=where, line=el.sourceline)
        stack.extend((child, depth + 1) for child in el)
    return tree


def schema(kind: str) -> etree.XMLSchema:
    """The XSD shipped for documents whose root element is ``kind``."""
    if kind not in SCHEMAS:
        raise InputError(f"unknown document kind {kind!r}; expected one of {sorted(SCHEMAS)}")
    if kind not in _SCHEMA_CACHE:
        xsd = parse_bytes(data_file(SCHEMAS[kind]), SCHEMAS[kind])
        _SCHEMA_CACHE[kind] = etree.XMLSchema(xsd)
    return _SCHEMA_CACHE[kind]


def validate(tree, where: str, kind: str | None = None) -> str:
    """Validate ``tree`` against the schema of its root element; return the kind.

    Raises
    ------
    DataFormatError
        Root element unknown or not ``kind``, or a schema rule broken: the message gives the
        line, the libxml2 rule identifier (e.g. ``SCHEMAV_CVC_MININCLUSIVE_VALID``) and text,
        and ``errors`` lists every violation as ``(line, rule, message)``.
    """
    root_tag = etree.QName(tree.getroot()).localname
    if root_tag not in SCHEMAS:
        raise DataFormatError(
            f"root element <{root_tag}> is not one of {sorted(SCHEMAS)}",
            path=where,
            line=tree.getroot().sourceline,
        )
    if kind is not None and root_tag != kind:
        raise DataFormatError(f"expected a <{kind}> document, got <{root_tag}>", path=where)
    xsd = schema(root_tag)
    if not xsd.validate(tree):
        errors = [(e.line, e.type_name, e.message) for e in xsd.error_log]
        line, rule, msg = errors[0]
        more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
        err = DataFormatError(f"schema rule {rule}: {msg}{more}", path=where, line=line)
        err.errors = errors  # type: ignore[attr-defined]
        raise err
    return root_tag


def is_url(source: str | os.PathLike) -> bool:
    """True for ``http://`` and ``https://`` sources."""
    return isinstance(source, str) and source.lower().startswith(("http://", "https://"))


def default_cache_dir() -> Path:
    """``$UASNAV_CACHE_DIR`` or ``~/.cache/uasnav``, subfolder ``mission``."""
    base = os.environ.get("UASNAV_CACHE_DIR") or os.path.join(os.path.expanduser("~"), ".cache", "uasnav")
    return Path(base) / "mission"


@dataclass(frozen=True)
class Fetched:
    """Outcome of :func:`fetch`: the body and where it came from."""

    data: bytes
    #: "network" (200), "revalidated" (304, cache used), "cache-offline" (network failed).
    origin: str


def check_timeout(timeout_s: float) -> float:
    """``timeout_s`` as a float if it is a finite number of seconds > 0, else :class:`InputError`."""
    try:
        t = float(timeout_s)
    except (TypeError, ValueError):
        raise InputError(f"timeout: expected a number of seconds, got {timeout_s!r}") from None
    if not (math.isfinite(t) and t > 0):
        raise InputError(f"timeout: expected a finite number of seconds > 0, got {timeout_s!r}")
    return t


def _download(req: urllib.request.Request, url: str, deadline: _Deadline, max_bytes: int):
    """GET ``req`` within ``deadline``; returns (body, ETag, Last-Modified)."""
    with _opener(deadline).open(req, timeout=deadline.remaining()) as resp:
        length = resp.headers.get("Content-Length")
        if length is not None and length.strip().isdigit() and int(length) > max_bytes:
            raise DataFormatError(f"Content-Length {length} exceeds the limit of {max_bytes} bytes", path=url)
        try:
            data = read_limited(resp, max_bytes, url)
        except ResourceLimitError:
            raise DataFormatError(f"document exceeds the limit of {max_bytes} bytes", path=url) from None
        return data, resp.headers.get("ETag"), resp.headers.get("Last-Modified")


def fetch(
    url: str,
    *,
    timeout_s: float = TIMEOUT_S,
    max_bytes: int = MAX_BYTES,
    cache_dir: str | os.PathLike | None = None,
    kind: str | None = None,
    offline_fallback: bool = True,
    check=None,
    accept: str = "application/xml",
) -> Fetched:
    """Download ``url`` with a total deadline, a size limit and a revalidated cache.

    ``timeout_s`` bounds the whole exchange (connect, status line, headers, redirects and body),
    not each socket read. Redirects are followed to http(s) URLs only. The body is read up to
    ``max_bytes + 1`` bytes, then parsed and schema-validated before it is cached. With
    ``offline_fallback`` a network failure falls back to a previously validated cached copy
    (with a warning). A cache directory that cannot be written only warns: the document was
    fetched and validated, so the load succeeds.

    ``check`` (a callable taking the body and the URL, raising on a bad document) replaces the
    XML parse-and-validate step for documents that are not XML (e.g. ED-269 zone files, JSON);
    ``accept`` is the ``Accept`` header sent.
    """
    if not is_url(url):
        raise InputError(f"{url!r}: only http:// and https:// URLs are fetched")
    timeout_s = check_timeout(timeout_s)
    cdir = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    key = hashlib.sha256(url.encode()).hexdigest()[:32]
    body_path, meta_path = cdir / f"{key}.xml", cdir / f"{key}.json"
    cached: bytes | None = None
    meta: dict = {}
    try:
        if body_path.is_file() and meta_path.is_file():
            meta = json.loads(read_file_limited(meta_path, 1 << 16))
            blob = read_file_limited(body_path, max_bytes)
            if meta.get("url") == url and hashlib.sha256(blob).hexdigest() == meta.get("sha256"):
                cached = blob
    except (OSError, ValueError, AttributeError):  # unreadable, oversize or not a JSON object
        cached, meta = None, {}
    req = new_request(url, {"User-Agent": "uasnav-mission", "Accept": accept})
    if cached is not None:
        if meta.get("etag"):
            req.add_header("If-None-Match", meta["etag"])
        if meta.get("last_modified"):
            req.add_header("If-Modified-Since", meta["last_modified"])
    deadline = _Deadline(timeout_s)
    failure: str | None = None
    try:
        data, etag, modified = _download(req, url, deadline, max_bytes)
    except urllib.error.HTTPError as exc:
        exc.close()
        if exc.code == 304 and cached is not None:
            return Fetched(cached, "revalidated")
        if not deadline.expired:
            raise InputError(f"{url}: HTTP {exc.code} {_one_line(exc.reason)}") from None
        failure = f"no complete answer within the timeout of {timeout_s:g} s"
    except (urllib.error.URLError, http.client.HTTPException, OSError) as exc:
        if deadline.expired:
            failure = f"no complete answer within the timeout of {timeout_s:g} s"
        elif isinstance(exc, http.client.HTTPException) and not isinstance(exc, ConnectionError):
            failure = f"malformed HTTP response ({type(exc).__name__}: {_one_line(exc)})"
        else:
            failure = _one_line(getattr(exc, "reason", None) or exc)
    finally:
        deadline.cancel()
    if failure is None and deadline.expired:
        # The deadline fired between two reads: what was read may be a truncated body.
        failure = f"no complete answer within the timeout of {timeout_s:g} s"
    if failure is not None:
        if offline_fallback and cached is not None:
            warnings.warn(f"{url}: {failure}; using the cached copy", stacklevel=2)
            return Fetched(cached, "cache-offline")
        raise InputError(f"{url}: cannot fetch ({failure})")
    if check is not None:
        check(data, url)
    else:
        validate(parse_bytes(data, url, max_bytes=max_bytes), url, kind)
    try:
        cdir.mkdir(parents=True, exist_ok=True)
        atomic_write_bytes(body_path, data)
        atomic_write_text(
            meta_path,
            json.dumps(
                {
                    "url": url,
                    "etag": etag,
                    "last_modified": modified,
                    "sha256": hashlib.sha256(data).hexdigest(),
                }
            ),
        )
    except OSError as exc:
        # The document is valid and in hand: a cache that cannot be written costs a refetch
        # next time, not this load.
        warnings.warn(f"{url}: not cached in {cdir} ({exc.strerror or exc})", stacklevel=2)
    return Fetched(data, "network")


def load_document(
    source: str | os.PathLike | None,
    kind: str | None = None,
    *,
    default: str | None = None,
    **fetch_kw,
):
    """Parse and validate a document from a path, an http(s) URL, or the shipped ``default``.

    Returns
    -------
    tree : lxml.etree._ElementTree
    where : str
        The path/URL used in messages.
    """
    if source is None:
        if default is None:
            raise InputError("no document given")
        where, data = f"<package>/{default}", data_file(default)
    elif is_url(source):
        where, data = str(source), fetch(str(source), kind=kind, **fetch_kw).data
    else:
        where = str(source)
        if os.path.isdir(source):
            raise InputError(f"{where}: is a directory, not a document")
        # The limit is enforced on the bytes read, not on the size the file reports: a device
        # (/dev/zero), a FIFO or a growing file reports 0 or less than it delivers.
        data = read_file_limited(source, fetch_kw.get("max_bytes", MAX_BYTES), where)
    tree = parse_bytes(data, where, max_bytes=fetch_kw.get("max_bytes", MAX_BYTES))
    validate(tree, where, kind)
    return tree, where
