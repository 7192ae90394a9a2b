"""Finding the logs of a fleet: directories, glob patterns and list files.

A SOURCE of ``uasnav fleet …`` is

- a directory: every file under it (recursively, hidden ones left out) whose extension is a log
  format of :mod:`uasnav.io` (``.ulg``, ``.bin``, ``.tlog``, ``.csv``, ``.txt``, ``.npz``);
- a glob pattern (``logs/2026-*/**/*.ulg``; ``**`` crosses directories);
- a list file ending in ``.list`` or ``.urls``: one path, ``file://`` URL or ``http(s)://`` URL
  per line (``#`` comments and blank lines skipped; relative paths are relative to the list file);
- an ``http://`` or ``https://`` URL of one log;
- a file: taken as it is, whatever its extension (an unknown format becomes an error row).

Local paths are read by the workers from a file system they share with the client (a network
file system on a real cluster). An http(s) URL is kept as it is: the worker that processes it
downloads the log itself (:func:`uasnav.fleet.runner.process_log`), never the client. Other
schemes (``s3://``, ``ftp://`` …) are refused with a clear error.
"""

from __future__ import annotations

import glob
import os
import warnings
from collections.abc import Sequence
from pathlib import Path
from urllib.parse import unquote, urlparse

from uasnav.errors import InputError
from uasnav.httpfetch import is_url
from uasnav.limits import check_input_file

#: Extensions picked up when a directory is scanned.
LOG_EXTENSIONS = (".ulg", ".bin", ".tlog", ".csv", ".txt", ".npz")
LIST_EXTENSIONS = (".list", ".urls")
_GLOB_CHARS = set("*?[")


def _from_url(text: str, base: Path) -> str:
    if is_url(text):
        return text
    u = urlparse(text)
    if u.scheme == "file":
        return unquote(u.path)
    if u.scheme and len(u.scheme) > 1:  # not a Windows drive letter
        raise InputError(
            f"{text}: {u.scheme}:// URLs are not supported (only paths, file:// and http(s):// URLs)"
        )
    p = Path(text).expanduser()
    return str(p if p.is_absolute() else base / p)


def _walk(d: Path) -> list[str]:
    out = []
    for root, dirs, files in os.walk(d):
        dirs[:] = sorted(x for x in dirs if not x.startswith((".", "_")))
        out += [
            os.path.join(root, f)
            for f in files
            if not f.startswith(".") and os.path.splitext(f)[1].lower() in LOG_EXTENSIONS
        ]
    return [f for f in out if _readable(f)]


def _readable(path: str) -> bool:
    """False, with a warning, for a FIFO or socket found among the logs: opening it would
    block the run (:func:`uasnav.limits.check_input_file`)."""
    try:
        check_input_file(path)
    except InputError as e:
        warnings.warn(f"skipped {e}", stacklevel=3)
        return False
    return True


def discover(sources: Sequence[str | os.PathLike[str]]) -> list[str]:
    """The logs named by ``sources`` (see the module docs): absolute paths and http(s) URLs,
    sorted, each once.

    Raises
    ------
    InputError
        A source that does not exist, a glob or directory that holds no log, a URL of another
        scheme than file or http(s), or no source at all.
    """
    if not sources:
        raise InputError("no SOURCE given (directories, glob patterns, list files or log files)")
    found: list[str] = []
    for src in sources:
        s = os.fspath(src)
        p = Path(s)
        if any(c in s for c in _GLOB_CHARS) and not p.exists():
            hits = [h for h in glob.glob(s, recursive=True) if os.path.isfile(h)]
            if not hits:
                raise InputError(f"{s}: no file matches this pattern")
            found += hits
        elif p.is_dir():
            hits = _walk(p)
            if not hits:
                raise InputError(f"{s}: no log file ({', '.join(LOG_EXTENSIONS)}) in this directory")
            found += hits
        elif p.is_file() and p.suffix.lower() in LIST_EXTENSIONS:
            with open(p, encoding="utf-8") as fh:
                for line in fh:
                    line = line.strip()
                    if line and not line.startswith("#"):
                        found.append(_from_url(line, p.parent))
        elif is_url(s):
            found.append(s)
        elif p.exists():
            if not p.is_file():
                raise InputError(f"{s}: not a regular file or directory")
            found.append(s)
        else:
            _from_url(s, Path.cwd())  # a remote URL gets its own message
            raise InputError(f"{s}: no such file or directory")
    from uasnav.fleet.logs import is_gnss_companion

    # a GNSS CSV beside its IMU log is part of that log (the GNSS/INS flight format), not a log
    return sorted(
        {f if is_url(f) else os.path.abspath(f) for f in found if is_url(f) or not is_gnss_companion(f)}
    )


__all__ = ["LIST_EXTENSIONS", "LOG_EXTENSIONS", "discover"]
