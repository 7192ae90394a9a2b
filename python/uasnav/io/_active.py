"""Which decoded log scans are active (see :mod:`uasnav.io.formats._scan`).

Kept apart, importing nothing of uasnav, so that the low-level readers can consult it without
an import circle.
"""

from __future__ import annotations

import contextlib
import contextvars
from collections.abc import Iterator
from pathlib import Path
from typing import Any

_ACTIVE: contextvars.ContextVar[dict[Path, Any] | None] = contextvars.ContextVar("uasnav_scans", default=None)


def _key(p: str | Path) -> Path:
    return Path(p).absolute()


@contextlib.contextmanager
def active(*scans: Any) -> Iterator[None]:
    """Make each of ``scans`` what the readers see for its ``path`` during the block."""
    current = dict(_ACTIVE.get() or {})
    for scan in scans:
        current[_key(scan.path)] = scan
    token = _ACTIVE.set(current)
    try:
        yield
    finally:
        _ACTIVE.reset(token)


def lookup(p: str | Path) -> Any | None:
    """The active scan of ``p``, or None."""
    scans = _ACTIVE.get()
    return None if not scans else scans.get(_key(p))


__all__ = ["active", "lookup"]
