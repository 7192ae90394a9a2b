"""Compare two ``report.json`` files value by value.

Used to check that a restructuring leaves the main job's numbers unchanged::

    python scripts/compare_reports.py BEFORE/report.json AFTER/report.json [--rtol 0] [--ignore seconds]

Prints every differing path (missing key, extra key, different value) and exits 1 if any; floats
compare equal when ``|a − b| ≤ rtol·max(|a|, |b|)`` (default 0: bit-identical). The ``seconds``
block (wall-clock timings) is ignored by default.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any


def diff(a: Any, b: Any, path: str, rtol: float, out: list[str]) -> None:
    """Append a line to ``out`` for every place where ``a`` and ``b`` differ."""
    if isinstance(a, dict) and isinstance(b, dict):
        for k in a.keys() - b.keys():
            out.append(f"{path}/{k}: only in the first")
        for k in b.keys() - a.keys():
            out.append(f"{path}/{k}: only in the second")
        for k in a.keys() & b.keys():
            diff(a[k], b[k], f"{path}/{k}", rtol, out)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            out.append(f"{path}: length {len(a)} vs {len(b)}")
        for i, (x, y) in enumerate(zip(a, b, strict=False)):
            diff(x, y, f"{path}[{i}]", rtol, out)
    elif isinstance(a, float | int) and isinstance(b, float | int) and not isinstance(a, bool):
        if a != b and not math.isclose(a, b, rel_tol=rtol, abs_tol=0.0):
            out.append(f"{path}: {a!r} vs {b!r}")
    elif a != b:
        out.append(f"{path}: {a!r} vs {b!r}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("before")
    ap.add_argument("after")
    ap.add_argument("--rtol", type=float, default=0.0, help="relative tolerance for numbers (default 0)")
    ap.add_argument("--ignore", action="append", default=["seconds"], help="top-level keys to skip")
    ap.add_argument("--only", help="compare only this section key")
    args = ap.parse_args(argv)
    with open(args.before, encoding="utf-8") as f:
        a = json.load(f)
    with open(args.after, encoding="utf-8") as f:
        b = json.load(f)
    for k in args.ignore:
        a.pop(k, None)
        b.pop(k, None)
    if args.only:
        a = a.get("sections", {}).get(args.only)
        b = b.get("sections", {}).get(args.only)
    out: list[str] = []
    diff(a, b, "", args.rtol, out)
    for line in sorted(out):
        print(line)
    print(f"{len(out)} difference(s)")
    return 1 if out else 0


if __name__ == "__main__":
    sys.exit(main())
