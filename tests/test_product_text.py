"""Product text describes the product: no issue numbers, work sessions, follow-ups or "before
it was …" in the README, the docs, the package (code comments, CLI help, report, web pages,
stubs), the crates (sources, READMEs, examples, manifests), the Makefile and pyproject.toml.
History belongs in CHANGELOG.md."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

PRODUCT = [
    "README.md",
    "Makefile",
    "pyproject.toml",
    "Cargo.toml",
    "docs/**/*.md",
    "docs/**/*.py",
    "docs/**/*.yml",
    "mkdocs.yml",
    "python/uasnav/**/*.py",
    "python/uasnav/**/*.pyi",
    "python/uasnav/**/*.html",
    "python/uasnav/**/*.j2",
    "python/uasnav/**/*.js",
    "python/uasnav/**/*.css",
    "crates/*/src/**/*.rs",
    "crates/*/examples/**/*.rs",
    "crates/*/tests/**/*.rs",
    "crates/*/README.md",
    "crates/*/Cargo.toml",
    "crates/*/*.py",
    "crates/*/include/*.h",
]

# "Issue 1, Amendment 3" is the edition of an EASA document, not ours.
HISTORY = re.compile(
    r"\bissues? ?#? ?\d+(?!,? Amendment)"
    r"|\bfollow-?up \d"
    r"|\bsessions? \d+"
    r"|\bs2\d-\d+\b"
    r"|does not exist yet"
    r"|\bbefore it was\b"
    r"|\bused to be\b",
    re.IGNORECASE,
)


def product_files() -> list[Path]:
    files: set[Path] = set()
    for pattern in PRODUCT:
        files.update(p for p in ROOT.glob(pattern) if p.is_file() and "target" not in p.parts)
    return sorted(files)


def test_pattern_finds_history_and_spares_editions() -> None:
    assert HISTORY.search("the report title (issue 19)")
    assert HISTORY.search("// No unchecked indexing (issue #20)")
    assert HISTORY.search("Follow-up 3 (session 24)")
    assert HISTORY.search("the format does not exist yet")
    assert not HISTORY.search("(EU) 2019/947 Issue 1, Amendment 3")
    assert not HISTORY.search("Regulation (EU) 2019/947 Issue 1 Amendment 3")


def test_product_text_has_no_history() -> None:
    files = product_files()
    assert len(files) > 100  # the globs match the tree
    found = []
    for path in files:
        for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            m = HISTORY.search(line)
            if m:
                found.append(f"{path.relative_to(ROOT)}:{n}: {m.group(0)!r} in {line.strip()[:120]}")
    assert not found, "history in product text (move it to CHANGELOG.md):\n" + "\n".join(found)
