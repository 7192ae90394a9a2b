"""The navigation data of any log in one call: :func:`read_nav` (``open_log(path).nav``)."""

from __future__ import annotations

from typing import Any

from uasnav.io.flight import Flight
from uasnav.io.logfile import open_log


def read_nav(path: str | Any, *, gnss_csv: str | None = None) -> Flight:
    """The navigation data of a log (:func:`uasnav.io.logfile.open_log` ``(path).nav``):
    ``.bin``, ``.ulg``, ``.tlog``, ``.csv`` (CSV v1, with ``gnss_csv`` required) or an ALFA
    ROS-topic CSV folder. ``gnss_csv`` replaces the log's own GNSS when given.

    Raises
    ------
    InputError
        Unknown extension, or a CSV log without ``gnss_csv``.
    DataFormatError
        The format reader's errors.
    """
    return open_log(path, need=("nav",), gnss=gnss_csv).nav  # type: ignore[no-any-return]


__all__ = ["read_nav"]
