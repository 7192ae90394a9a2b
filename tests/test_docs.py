"""The documentation's code runs: every ``bash`` and ``python`` block of each tutorial, in page
order, in an empty folder with this environment's ``uasnav`` on PATH. The site builds offline
(`make docs`); here the offline check itself is checked on pages that do load from the network."""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
TUTORIALS = sorted(p for p in (DOCS / "tutorials").glob("*.md") if p.name != "index.md")

sys.path.insert(0, str(DOCS))
from check_offline import main as check_offline  # noqa: E402

sys.path.remove(str(DOCS))

BLOCK = re.compile(r"```(bash|python)\n(.*?)```", re.S)
PIP = re.compile(r"^pip install '?uasnav\[(\w+)\]'?$", re.M)


def blocks(page: Path) -> list[tuple[str, str]]:
    return BLOCK.findall(page.read_text())


def test_every_tutorial_has_code_and_the_three_jobs_are_covered() -> None:
    names = {p.stem for p in TUTORIALS}
    assert {"replay-and-outage", "imu-noise-and-calibration", "plan-to-authorisation"} <= names
    for page in TUTORIALS:
        assert blocks(page), page.name


@pytest.mark.slow
@pytest.mark.parametrize("page", TUTORIALS, ids=lambda p: p.stem)
def test_tutorial_code_runs(page: Path, tmp_path: Path) -> None:
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}:{env['PATH']}"
    for kind, code in blocks(page):
        if kind == "bash":
            # this environment has every extra: the page's own `pip install` is checked, not run
            for extra in PIP.findall(code):
                assert extra in ("web", "utm", "fleet", "all")
                if extra != "all":
                    assert importlib.util.find_spec(
                        {"web": "fastapi", "utm": "uas_standards", "fleet": "distributed"}[extra]
                    )
            code = PIP.sub("true", code)
            cmd = ["bash", "-euo", "pipefail", "-c", code]
        else:
            cmd = [sys.executable, "-c", code]
        p = subprocess.run(
            cmd, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600, check=False
        )
        assert p.returncode == 0, f"{page.name}: {code}\n{p.stdout[-2000:]}\n{p.stderr[-3000:]}"
        assert "error:" not in p.stderr, p.stderr


def test_offline_check_finds_network_loads(tmp_path: Path) -> None:
    (tmp_path / "index.html").write_text(
        "<html><body><p>ok</p><a href='https://example.org'>x</a></body></html>"
    )
    assert check_offline(str(tmp_path)) == 0
    for bad in (
        "<script src='https://cdn.example.org/x.js'></script>",
        '<link rel="stylesheet" href="https://fonts.googleapis.com/css?family=Roboto">',
        "<style>@import url(https://fonts.googleapis.com/css)</style>",
        "<img src=//example.org/a.png>",
    ):
        (tmp_path / "index.html").write_text(f"<html><head>{bad}</head></html>")
        assert check_offline(str(tmp_path)) == 1, bad


def test_offline_check_accounts_for_every_url_of_a_script(tmp_path: Path) -> None:
    page = "<html><body><p>ok</p></body></html>"
    (tmp_path / "index.html").write_text(page)
    js = tmp_path / "bundle.js"
    guarded = 'var a=typeof ResizeObserver=="undefined"?_t("https://unpkg.com/resize-observer-polyfill"):0;'
    comments = '/*! lib v1 * https://example.org/licence */ var g="**/*.js"; // see http://example.org\n'
    js.write_text(comments + guarded)
    assert check_offline(str(tmp_path)) == 0
    # a URL the table does not know, one that lost its guard, one after a `/*` inside a string
    for bad in (
        'fetch("https://cdn.example.org/x.json")',
        '_t("https://unpkg.com/resize-observer-polyfill")',
        'var g="**/*.js";fetch("https://cdn.example.org/x.json");',
        "var r=/\\/*/;fetch('https://cdn.example.org/x.json');",
    ):
        js.write_text(comments + bad)
        assert check_offline(str(tmp_path)) == 1, bad
    # a dormant request becomes live when a page has what triggers it
    js.write_text(
        'function as(){return typeof mermaid=="undefined"||mermaid instanceof Element?'
        '_t("https://unpkg.com/mermaid@11/dist/mermaid.min.js"):0}'
        "function Ci(e,t){let r=`https://api.github.com/repos/${e}/${t}`;}"
    )
    assert check_offline(str(tmp_path)) == 0
    for trigger in ('<pre class="mermaid">graph</pre>', '<a href="x" data-md-component="source">'):
        (tmp_path / "index.html").write_text(f"<html><body>{trigger}</body></html>")
        assert check_offline(str(tmp_path)) == 1, trigger
