"""Hardened XML loading: hostile documents, schema errors with line and rule, URL fetching
against a local server (timeout, size limit, cache with revalidation), packaged data."""

from __future__ import annotations

import hashlib
import http.server
import threading
import time
from importlib import resources
from pathlib import Path
from typing import ClassVar

import pytest

from uasnav.errors import DataFormatError, InputError
from uasnav.mission import load_database, load_matrices, load_regulations
from uasnav.mission.loading import data_file, fetch, load_document, parse_bytes

XXE = b"""<?xml version="1.0"?>
<!DOCTYPE database [<!ENTITY xxe SYSTEM "file:///etc/passwd">]>
<database version="1">&xxe;</database>"""

LAUGHS = b"""<?xml version="1.0"?>
<!DOCTYPE lolz [
 <!ENTITY lol "lol">
 <!ENTITY lol1 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
 <!ENTITY lol2 "&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;">
 <!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">
 <!ENTITY lol9 "&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;">
]>
<database version="1">&lol9;</database>"""


def test_packaged_data_found_via_importlib_resources() -> None:
    base = resources.files("uasnav.mission").joinpath("data")
    names = {p.name for p in base.iterdir()}
    assert {
        "database.xml",
        "database.xsd",
        "matrices.xml",
        "matrices.xsd",
        "regulations.xml",
        "regulations.xsd",
    } <= names
    db = load_database()
    assert len(db.uas) >= 30 and len(db.cameras) >= 20
    assert all(s and len(s) > 20 for s in db.uas.sources + db.cameras.sources)


@pytest.mark.parametrize("doc", [XXE, LAUGHS], ids=["xxe", "billion-laughs"])
def test_dtd_rejected_before_parsing(doc: bytes) -> None:
    with pytest.raises(DataFormatError, match=r"line 2.*DTD"):
        parse_bytes(doc, "evil.xml")


def test_utf16_doctype_rejected_after_parsing() -> None:
    # The byte scan cannot see an UTF-16 DOCTYPE; the parsed docinfo must still refuse it.
    doc = LAUGHS.decode().replace('<?xml version="1.0"?>', '<?xml version="1.0" encoding="UTF-16"?>')
    with pytest.raises(DataFormatError, match="DTD"):
        parse_bytes(doc.encode("utf-16"), "evil16.xml")


def test_deep_nesting_and_oversize_rejected() -> None:
    deep = b"<database>" + b"<a>" * 40 + b"</a>" * 40 + b"</database>"
    with pytest.raises(DataFormatError, match="deeper than 32"):
        parse_bytes(deep, "deep.xml")
    very_deep = b"<a>" * 5000 + b"</a>" * 5000  # beyond libxml2's own limit: a syntax error
    with pytest.raises(DataFormatError, match="malformed XML"):
        parse_bytes(very_deep, "deeper.xml")
    with pytest.raises(DataFormatError, match="limit is 100"):
        parse_bytes(b"<database>" + b" " * 200 + b"</database>", "big.xml", max_bytes=100)


def test_malformed_xml_reports_line() -> None:
    with pytest.raises(DataFormatError, match=r"bad\.xml, line 3: malformed XML"):
        parse_bytes(b"<database>\n<uas-list>\n</oops>\n</database>", "bad.xml")


def test_schema_error_reports_line_and_rule(tmp_path: Path) -> None:
    text = data_file("database.xml").decode()
    lines = text.splitlines()
    k = next(i for i, line in enumerate(lines) if "<mass_g>" in line)
    lines[k] = "      <mass_g>-5</mass_g>"
    bad = tmp_path / "db.xml"
    bad.write_text("\n".join(lines))
    with pytest.raises(DataFormatError) as exc:
        load_database(bad)
    assert exc.value.line == k + 1
    assert "SCHEMAV_CVC_MINEXCLUSIVE_VALID" in str(exc.value)
    assert f"line {k + 1}" in str(exc.value)
    # A missing source note is a schema error too (every entry must cite its source).
    lines = text.splitlines()
    k = next(i for i, line in enumerate(lines) if line.strip().startswith("<source>"))
    del lines[k]
    bad.write_text("\n".join(lines))
    with pytest.raises(DataFormatError, match="SCHEMAV_ELEMENT_CONTENT"):
        load_database(bad)


def test_duplicate_id_and_wrong_kind(tmp_path: Path) -> None:
    text = data_file("database.xml").decode().replace('id="dji-phantom-3-standard"', 'id="dji-phantom-2"')
    p = tmp_path / "dup.xml"
    p.write_text(text)
    with pytest.raises(DataFormatError, match="unique-uas-id"):
        load_database(p)
    q = tmp_path / "regs.xml"
    q.write_bytes(data_file("regulations.xml"))
    with pytest.raises(DataFormatError, match="expected a <database> document"):
        load_database(q)
    with pytest.raises(InputError, match="cannot read"):
        load_database(tmp_path / "missing.xml")


class _Handler(http.server.BaseHTTPRequestHandler):
    routes: ClassVar[dict[str, bytes]] = {}
    hits: ClassVar[list[tuple[str, str | None]]] = []

    def log_message(self, *args) -> None:  # keep pytest output clean
        pass

    def do_GET(self) -> None:
        body = self.routes.get(self.path)
        etag = None if body is None else '"' + hashlib.sha256(body).hexdigest()[:16] + '"'
        self.hits.append((self.path, self.headers.get("If-None-Match")))
        if self.path == "/slow":
            time.sleep(1.0)
            return
        if body is None:
            self.send_response(404)
            self.end_headers()
            return
        if self.headers.get("If-None-Match") == etag:
            self.send_response(304)
            self.end_headers()
            return
        self.send_response(200)
        self.send_header("Content-Type", "application/xml")
        self.send_header("Content-Length", str(len(body)))
        self.send_header("ETag", etag)
        self.end_headers()
        try:
            self.wfile.write(body)
        except (BrokenPipeError, ConnectionResetError):  # the client gave up (timeout/size tests)
            pass


@pytest.fixture(scope="module")
def server():
    srv = http.server.ThreadingHTTPServer(("127.0.0.1", 0), _Handler)
    th = threading.Thread(target=srv.serve_forever, daemon=True)
    th.start()
    yield f"http://127.0.0.1:{srv.server_address[1]}"
    srv.shutdown()
    srv.server_close()


def test_url_loading_with_cache_revalidation(server: str, tmp_path: Path) -> None:
    _Handler.routes["/db.xml"] = data_file("database.xml")
    _Handler.hits.clear()
    url = server + "/db.xml"
    first = fetch(url, cache_dir=tmp_path)
    assert first.origin == "network" and first.data == data_file("database.xml")
    second = fetch(url, cache_dir=tmp_path)
    assert second.origin == "revalidated" and second.data == first.data
    assert _Handler.hits[1][1] is not None  # sent If-None-Match
    db = load_database(url, cache_dir=tmp_path)
    assert len(db.uas) >= 30
    # Server goes away: the validated cached copy is used, with a warning.
    del _Handler.routes["/db.xml"]
    _Handler.routes.pop("/x", None)
    with pytest.raises(InputError, match="HTTP 404"):
        fetch(url, cache_dir=tmp_path)
    # A corrupted cache is not trusted: it is refetched (and here the server has nothing).
    body = next(tmp_path.glob("*.xml"))
    body.write_bytes(b"<database/>")
    with pytest.raises(InputError, match="HTTP 404"):
        fetch(url, cache_dir=tmp_path)


def test_offline_fallback_uses_validated_cache(tmp_path: Path) -> None:
    # Bind a port, serve once, then close it so that the next request is refused.
    srv = http.server.ThreadingHTTPServer(("127.0.0.1", 0), _Handler)
    th = threading.Thread(target=srv.serve_forever, daemon=True)
    th.start()
    url = f"http://127.0.0.1:{srv.server_address[1]}/regs.xml"
    _Handler.routes["/regs.xml"] = data_file("regulations.xml")
    assert fetch(url, cache_dir=tmp_path).origin == "network"
    srv.shutdown()
    srv.server_close()
    with pytest.warns(UserWarning, match="using the cached copy"):
        got = fetch(url, cache_dir=tmp_path)
    assert got.origin == "cache-offline" and got.data == data_file("regulations.xml")
    with pytest.raises(InputError, match="cannot fetch"):
        fetch(url, cache_dir=tmp_path, offline_fallback=False)


def test_url_timeout_size_limit_and_invalid_body(server: str, tmp_path: Path) -> None:
    _Handler.routes["/slow"] = data_file("regulations.xml")
    t0 = time.perf_counter()
    with pytest.raises(InputError, match="cannot fetch"):
        fetch(server + "/slow", cache_dir=tmp_path, timeout_s=0.2)
    assert time.perf_counter() - t0 < 0.9
    _Handler.routes["/big.xml"] = data_file("database.xml")
    with pytest.raises(DataFormatError, match=r"Content-Length .* exceeds the limit of 1000 bytes"):
        fetch(server + "/big.xml", cache_dir=tmp_path, max_bytes=1000)
    _Handler.routes["/evil.xml"] = LAUGHS
    with pytest.raises(DataFormatError, match="DTD"):
        fetch(server + "/evil.xml", cache_dir=tmp_path)
    assert not list(tmp_path.glob("*.xml"))  # nothing invalid was cached
    with pytest.raises(InputError, match="only http"):
        fetch("file:///etc/passwd", cache_dir=tmp_path)


def test_other_documents_load() -> None:
    assert len(load_matrices().missions) == 10
    assert set(load_regulations().jurisdictions) == {"easa", "faa"}
    tree, where = load_document(None, default="matrices.xml")
    assert where.endswith("matrices.xml") and tree.getroot().tag == "matrices"


def test_cli_db_validate_url_and_schema_error(server: str, tmp_path: Path, monkeypatch) -> None:
    from click.testing import CliRunner

    from uasnav.cli import main

    monkeypatch.setenv("UASNAV_CACHE_DIR", str(tmp_path))
    _Handler.routes["/m.xml"] = data_file("matrices.xml")
    res = CliRunner().invoke(main, ["db", "validate", server + "/m.xml"])
    assert res.exit_code == 0 and "valid <matrices>" in res.output
    _Handler.routes["/bad.xml"] = data_file("regulations.xml").replace(
        b'op="lt" value="250"', b'op="lte" value="250"'
    )
    res = CliRunner().invoke(main, ["db", "validate", server + "/bad.xml"])
    assert res.exit_code == 1
    assert "line 18" in res.output and "SCHEMAV_CVC_ENUMERATION_VALID" in res.output
