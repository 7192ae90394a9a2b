"""``uasnav serve`` as an operator starts it: the real command on a loopback port, over real HTTP."""

from __future__ import annotations

import http.client
import json
import subprocess
import time

from click.testing import CliRunner

from uasnav.cli import main
from uasnav.cli.serve import is_loopback
from uasnav.web.process import running_server, uasnav_command

THESIS = {
    "mission": "precision-agriculture",
    "range": 1500,
    "image_size": "70x70",
    "wind": 5,
    "order_by": "cost",
}


def _request(port: int, method: str, path: str, body: bytes | None = None, headers: dict | None = None):  # type: ignore[no-untyped-def]
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    c.request(method, path, body=body, headers=headers or {})
    r = c.getresponse()
    data = r.read()
    c.close()
    return r.status, data


def test_serve_answers_select_as_the_cli_does() -> None:
    argv = ["select", "--json"] + [a for k, v in THESIS.items() for a in ("--" + k.replace("_", "-"), str(v))]
    cli = subprocess.run([*uasnav_command(), *argv], capture_output=True, check=True, timeout=120)
    with running_server() as s:
        status, body = _request(
            s.port, "POST", "/api/select", json.dumps(THESIS).encode(), {"content-type": "application/json"}
        )
        assert status == 200
        assert json.loads(body) == json.loads(cli.stdout)
        # DNS rebinding: a foreign name in Host is refused even on loopback
        status, body = _request(s.port, "GET", "/", headers={"host": "attacker.example"})
        assert status == 400 and json.loads(body)["field"] == "host"
        # the stylesheet and script are served by the app itself
        assert _request(s.port, "GET", "/static/app.css")[0] == 200
        assert _request(s.port, "GET", "/static/app.js")[0] == 200
        assert "warning" not in s.log()
    assert s.process.returncode is not None  # stopped by the context manager


def test_serve_warns_when_bound_off_loopback() -> None:
    with running_server(host="0.0.0.0") as s:
        time.sleep(0.2)
        log = s.log()
        assert "warning: uasnav serve is bound to 0.0.0.0, not loopback" in log
        # still answers on loopback, with the loopback names
        assert _request(s.port, "GET", "/api/options")[0] == 200


def test_loopback_detection() -> None:
    assert (
        is_loopback("127.0.0.1") and is_loopback("localhost") and is_loopback("::1") and is_loopback("[::1]")
    )
    assert is_loopback("127.0.0.2")
    assert not is_loopback("0.0.0.0") and not is_loopback("192.168.1.10") and not is_loopback("example.com")


def test_serve_refuses_hostile_documents_before_starting(tmp_path) -> None:
    bomb = tmp_path / "db.xml"
    bomb.write_text(
        '<?xml version="1.0"?><!DOCTYPE d [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;">]>'
        "<database>&b;</database>"
    )
    r = CliRunner().invoke(main, ["serve", "--db", str(bomb), "--port", "1"])
    assert r.exit_code == 1
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "db.xml" in lines[0]
    r = CliRunner().invoke(main, ["serve", "--port", "0"])
    assert r.exit_code == 2 and "--port" in r.stderr
