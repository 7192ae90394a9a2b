"""The uasnav report: every capability reproduces its thesis experiments in one HTML file.

Sections are discovered: each module in :mod:`uasnav.report.sections` that defines a
module-level ``SECTION`` (a :class:`Section`) is included, ordered by ``Section.order``. A
section's ``build(w)`` gets a :class:`SectionWriter` and adds paragraphs, tables (ours beside
the thesis') and figures, and records its headline numbers in ``w.data`` (written to
``report.json``). Sections must be deterministic from ``w.seed`` and must not read
``../shared`` (the report runs on embedded/simulated data only).

The output is one self-contained ``report.html`` (figures embedded as PNG data URIs), plus
``report.json`` and the figures as separate PNG files, all written atomically.
"""

from __future__ import annotations

import base64
import html
import importlib
import io
import json
import pkgutil
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from uasnav._extras import MissingExtraError
from uasnav.atomicfile import output_set
from uasnav.errors import InputError
from uasnav.jsonable import to_jsonable

if TYPE_CHECKING:
    from matplotlib.figure import Figure


@dataclass
class SectionWriter:
    """Collects one section's content. Methods return ``self`` for chaining."""

    key: str
    seed: int
    quick: bool
    out_dir: Path
    progress: Callable[[str], None]
    blocks: list[str] = field(default_factory=list)
    data: dict[str, Any] = field(default_factory=dict)
    figures: list[tuple[str, bytes]] = field(default_factory=list)

    def heading(self, text: str) -> SectionWriter:
        """A sub-heading."""
        self.blocks.append(f"<h3>{html.escape(text)}</h3>")
        return self

    def p(self, text: str) -> SectionWriter:
        """A paragraph (plain text; escaped)."""
        self.blocks.append(f"<p>{html.escape(text)}</p>")
        return self

    def table(
        self,
        headers: Sequence[str],
        rows: Sequence[Sequence[Any]],
        caption: str = "",
        fmt: str = "{:.4g}",
    ) -> SectionWriter:
        """A table; floats are formatted with ``fmt``, None shows as an em dash."""

        def cell(v: Any) -> str:
            if v is None:
                return "—"
            if isinstance(v, float):
                return html.escape(fmt.format(v))
            return html.escape(str(v))

        head = "".join(f"<th>{html.escape(h)}</th>" for h in headers)
        body = "".join("<tr>" + "".join(f"<td>{cell(v)}</td>" for v in r) + "</tr>" for r in rows)
        cap = f"<caption>{html.escape(caption)}</caption>" if caption else ""
        self.blocks.append(f"<table>{cap}<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>")
        return self

    def verdict(self, name: str, v: Any) -> str:
        """Record a :class:`~uasnav.experiments.verdicts.Verdict` under ``data["verdicts"][name]``
        (its outcome, rule and inputs, for report.json) and return its sentence, so the text a
        section prints around a verdict comes from the same numbers as the verdict."""
        self.data.setdefault("verdicts", {})[name] = v.to_dict()
        return str(v.sentence)

    def figure(self, fig: Figure, name: str, caption: str = "") -> SectionWriter:
        """Embed a matplotlib figure (also saved as ``figures/<key>-<name>.png``)."""
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=100)
        png = buf.getvalue()
        self.figures.append((f"{self.key}-{name}.png", png))
        b64 = base64.b64encode(png).decode("ascii")
        cap = f"<figcaption>{html.escape(caption)}</figcaption>" if caption else ""
        self.blocks.append(
            f'<figure><img alt="{html.escape(name)}" src="data:image/png;base64,{b64}"/>{cap}</figure>'
        )
        return self


@dataclass(frozen=True)
class Section:
    """A report section: ``build`` fills a :class:`SectionWriter`."""

    key: str
    title: str
    order: int
    build: Callable[[SectionWriter], None]


def discover_sections() -> list[Section]:
    """All sections in :mod:`uasnav.report.sections`, in order."""
    from uasnav.report import sections as pkg

    found = []
    for info in pkgutil.iter_modules(pkg.__path__):
        if info.name.startswith("_"):
            continue
        mod = importlib.import_module(f"{pkg.__name__}.{info.name}")
        sec = getattr(mod, "SECTION", None)
        if isinstance(sec, Section):
            found.append(sec)
    return sorted(found, key=lambda s: (s.order, s.key))


_CSS = """
body{font-family:system-ui,sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;margin:1em 0;font-size:0.9em}
th,td{border:1px solid #bbb;padding:3px 8px;text-align:right}th{background:#eee}
caption{caption-side:top;text-align:left;font-weight:600;padding:4px 0}
figure{margin:1em 0}img{max-width:100%}figcaption{font-size:0.85em;color:#555}
h2{border-bottom:2px solid #345;padding-bottom:4px;margin-top:2em}
.meta{color:#666;font-size:0.85em}
"""


@dataclass(frozen=True)
class ReportResult:
    """Paths written and the numbers of every section."""

    html_path: Path
    json_path: Path
    data: dict[str, Any]
    seconds: dict[str, float]


def build_report(
    out_dir: str | Path,
    *,
    seed: int = 2024,
    quick: bool = False,
    only: Sequence[str] | None = None,
    progress: Callable[[str], None] | None = None,
) -> ReportResult:
    """Run every section's experiments and write ``report.html`` / ``report.json``.

    Parameters
    ----------
    out_dir : path
        Output folder (created).
    seed : int
        Seed of every simulation (the report is deterministic for a given seed).
    quick : bool
        Smaller experiments (for tests); the numbers are then less precise.
    only : sequence of str, optional
        Section keys to run (default: all).
    progress : callable, optional
        Receives one-line progress messages.
    """
    from uasnav import __version__

    say = progress or (lambda _msg: None)
    out = Path(out_dir)
    sections = discover_sections()
    if only:
        keys = {s.key for s in sections}
        unknown = sorted(set(only) - keys)
        if unknown:
            raise InputError(
                f"unknown report section(s) {', '.join(unknown)}; known: {', '.join(sorted(keys))}"
            )
        sections = [s for s in sections if s.key in set(only)]
    parts, data, seconds = [], {}, {}
    figures: list[tuple[str, bytes]] = []  # written with the html and json, all or nothing
    for i, sec in enumerate(sections, 1):
        say(f"[{i}/{len(sections)}] {sec.title} …")
        w = SectionWriter(key=sec.key, seed=seed, quick=quick, out_dir=out, progress=say)
        t0 = time.perf_counter()
        try:
            sec.build(w)
        except MissingExtraError as e:
            if only:  # asked for by name: the missing extra is the answer
                raise
            # a base install reports what it can; the section says how to add the rest
            w = SectionWriter(key=sec.key, seed=seed, quick=quick, out_dir=out, progress=say)
            w.p(f"Not run: {e}")
            w.data = {"skipped": str(e), "extra": e.extra}
        seconds[sec.key] = time.perf_counter() - t0
        state = "skipped" if "skipped" in w.data else "done"
        say(f"[{i}/{len(sections)}] {sec.title}: {state} in {seconds[sec.key]:.1f} s")
        data[sec.key] = w.data
        figures.extend(w.figures)
        parts.append(
            f'<section id="{sec.key}"><h2>{html.escape(sec.title)}</h2>{"".join(w.blocks)}</section>'
        )
    toc = "".join(f'<li><a href="#{s.key}">{html.escape(s.title)}</a></li>' for s in sections)
    doc = (
        "<!DOCTYPE html><html><head><meta charset='utf-8'><title>uasnav report</title>"
        f"<style>{_CSS}</style></head><body><h1>uasnav — thesis experiments reproduced</h1>"
        f"<p class='meta'>uasnav {html.escape(__version__)}, seed {seed}{', quick mode' if quick else ''}. "
        "Every number is computed by this run; thesis values are quoted beside ours.</p>"
        f"<ul>{toc}</ul>{''.join(parts)}</body></html>"
    )
    html_path, json_path = out / "report.html", out / "report.json"
    report_json = json.dumps(
        to_jsonable({"seed": seed, "quick": quick, "sections": data, "seconds": seconds}), indent=2
    )
    with output_set() as files:
        for name, png in figures:
            files.write_bytes(out / "figures" / name, png)
        files.write_text(html_path, doc)
        files.write_text(json_path, report_json)
    return ReportResult(html_path=html_path, json_path=json_path, data=data, seconds=seconds)


__all__ = ["ReportResult", "Section", "SectionWriter", "build_report", "discover_sections"]
