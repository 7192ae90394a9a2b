"""Fail when the built site would fetch anything from the network.

Two checks over the built site:

1. HTML and CSS: no script, stylesheet, font, image or iframe with an absolute http(s) URL, no
   CSS ``@import`` / ``url()`` of one. Links (``<a href>``) to other sites are fine: they are
   followed only when clicked.
2. JavaScript: every absolute URL outside a comment is accounted for in :data:`DORMANT`, which
   says why the script never requests it on this site and how that is checked here: the guard
   in the code right before the URL, and what the pages lack that the request needs. An
   unknown URL fails, so a theme upgrade that adds a request is caught.
"""

from __future__ import annotations

import bisect
import re
import sys
from dataclasses import dataclass
from pathlib import Path

LOADS = re.compile(
    r"<(?:script|img|iframe|source|audio|video)\b[^>]*\bsrc=[\"']?(?:https?:)?//"
    r"|<link\b(?=[^>]*\brel=[\"']?(?:stylesheet|preload|preconnect|icon|dns-prefetch))[^>]*\bhref=[\"']?(?:https?:)?//"
    r"|@import\s+(?:url\()?[\"']?(?:https?:)?//"
    r"|url\([\"']?(?:https?:)?//",
    re.IGNORECASE,
)
JS_URL = re.compile(r"https?://[^\s\"'`)<>]*")
# words after which `/` starts a regular expression, not a division
KEYWORDS = {"return", "typeof", "case", "in", "of", "do", "else", "void", "delete", "throw", "yield", "await"}


@dataclass(frozen=True)
class Dormant:
    """A URL in a script that this site never requests."""

    url: str  # the URL as written in the script (a prefix for template literals)
    guard: str  # regex the code right before the URL must match (the request's condition)
    why: str  # the reason, printed by the check
    page_mark: str | None = None  # regex no HTML page may match (what the request needs)


DORMANT = (
    Dormant(
        "https://unpkg.com/resize-observer-polyfill",
        r'typeof ResizeObserver=="undefined"\?\w+\("$',
        "Material's polyfill, requested only by a browser without ResizeObserver (every "
        "browser has it since 2020: Chrome 64, Firefox 69, Safari 13.1)",
    ),
    Dormant(
        "https://unpkg.com/mermaid@11/dist/mermaid.min.js",
        r'typeof mermaid=="undefined"\|\|mermaid instanceof Element\?\w+\("$',
        "Mermaid, requested only to draw a diagram block; no page has one",
        r"class=\"[^\"]*\bmermaid\b",
    ),
    Dormant(
        "https://api.github.com/",
        r"let \w+=`$",
        "the repository's stars and forks, fetched only for a header source link "
        "(repo_url); the site has none",
        r"data-md-component=\"source\"",
    ),
    Dormant(
        "https://${e}/api/v4/projects/",
        r"let \w+=`$",
        "the same for GitLab, fetched only for a header source link; the site has none",
        r"data-md-component=\"source\"",
    ),
    Dormant(
        "https://bit.ly/2s3ChXG",
        r"console\.warn\(`Invalid query: \$\{\w+\} \\u2013 see $",
        "text of the search worker's console warning, never requested",
    ),
    Dormant(
        "https://github.com/isaacs/node-glob/issues/167",
        r"'See: $",
        "text of an error message in the Thai word splitter, never requested",
    ),
)


def _comments(text: str) -> list[tuple[int, int]]:
    """(start, end) of every comment of a script, found by scanning it as a lexer does: string,
    template and regular-expression literals are skipped, so a ``/*`` or ``//`` inside one
    (``"**/*.js"``, ``/https?:\\/\\//``) opens nothing."""
    spans = []
    i, n = 0, len(text)
    # the last significant character (and word) of code: they decide whether `/` starts a regex
    last, word = "", ""
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            end = text.find("\n", i)
            end = n if end == -1 else end
            spans.append((i, end))
            i = end
        elif text.startswith("/*", i):
            end = text.find("*/", i + 2)
            end = n if end == -1 else end + 2
            spans.append((i, end))
            i = end
        elif c in "'\"`" or (c == "/" and (not last or last in "(,=:[!&|?{};+-*%<>~^" or word in KEYWORDS)):
            close, in_class, i = c, False, i + 1
            while i < n and (text[i] != close or in_class) and not (close != "`" and text[i] == "\n"):
                if text[i] == "\\":
                    i += 1
                elif close == "/" and text[i] in "[]":
                    in_class = text[i] == "["
                i += 1
            i += 1
            last, word = "a", ""
        else:
            if c.isalnum() or c in "_$":
                word = word + c if last.isalnum() or last in "_$" else c
            if not c.isspace():
                last = c
            i += 1
    return spans


def script_urls(text: str) -> list[tuple[int, str]]:
    """(position, URL) of every absolute URL of a script outside its comments."""
    spans = _comments(text)
    starts = [s for s, _ in spans]
    found = []
    for m in JS_URL.finditer(text):
        k = bisect.bisect_right(starts, m.start()) - 1
        if k < 0 or m.start() >= spans[k][1]:
            found.append((m.start(), m.group(0)))
    return found


def main(site: str) -> int:
    root = Path(site)
    pages = [p for p in root.rglob("*") if p.suffix in {".html", ".css", ".js"}]
    html = {p: p.read_text(errors="replace") for p in pages if p.suffix == ".html"}
    if not html:
        print(f"error: no HTML pages in {root}", file=sys.stderr)
        return 1
    bad = []
    dormant: dict[str, list[str]] = {}
    for p in pages:
        text = html.get(p) or p.read_text(errors="replace")
        where = p.relative_to(root)
        bad += [f"{where}: {m.group(0)[:120]}" for m in LOADS.finditer(text)]
        if p.suffix != ".js":
            continue
        for pos, url in script_urls(text):
            known = next((d for d in DORMANT if url.startswith(d.url)), None)
            if known is None:
                bad.append(f"{where}: script requests {url}")
            elif not re.search(known.guard, text[max(0, pos - 200) : pos]):
                bad.append(f"{where}: {url} is no longer behind its guard /{known.guard}/")
            else:
                dormant.setdefault(known.url, []).append(str(where))
    for d in DORMANT:
        if d.url in dormant and d.page_mark:
            for page, text in html.items():
                if re.search(d.page_mark, text):
                    bad.append(f"{page.relative_to(root)}: has /{d.page_mark}/, so {d.url} is requested")
    if bad:
        print("error: the site loads from the network:\n" + "\n".join(bad), file=sys.stderr)
        return 1
    print(f"{len(pages)} files of {root}: nothing loaded from the network")
    for d in DORMANT:
        if d.url in dormant:
            print(f"  {d.url} in {', '.join(sorted(set(dormant[d.url])))}: {d.why}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "build/site"))
