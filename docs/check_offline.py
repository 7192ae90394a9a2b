"""Fail when the built site would fetch anything from the network: a script, stylesheet,
font, image or iframe with an absolute http(s) URL, or a CSS @import / url() of one.
Links (<a href>) to other sites are fine: they are followed only when clicked."""

from __future__ import annotations

import re
import sys
from pathlib import Path

LOADS = re.compile(
    r"<(?:script|img|iframe|source|audio|video)\b[^>]*\bsrc=[\"']?(?:https?:)?//"
    r"|<link\b(?=[^>]*\brel=[\"']?(?:stylesheet|preload|preconnect|icon|dns-prefetch))[^>]*\bhref=[\"']?(?:https?:)?//"
    r"|@import\s+(?:url\()?[\"']?(?:https?:)?//"
    r"|url\([\"']?(?:https?:)?//",
    re.IGNORECASE,
)


def main(site: str) -> int:
    root = Path(site)
    pages = [p for p in root.rglob("*") if p.suffix in {".html", ".css", ".js"}]
    if not any(p.suffix == ".html" for p in pages):
        print(f"error: no HTML pages in {root}", file=sys.stderr)
        return 1
    bad = []
    for p in pages:
        for m in LOADS.finditer(p.read_text(errors="replace")):
            bad.append(f"{p.relative_to(root)}: {m.group(0)[:120]}")
    if bad:
        print("error: the site loads from the network:\n" + "\n".join(bad), file=sys.stderr)
        return 1
    print(f"{len(pages)} files of {root}: nothing loaded from the network")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "build/site"))
