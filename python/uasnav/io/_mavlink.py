"""pymavlink access shared by the DataFlash (``.bin``) and MAVLink telemetry (``.tlog``) readers.

One error handling for both formats: a missing file, a file pymavlink cannot open and a
message it cannot decode are each a :class:`~uasnav.errors.DataFormatError` naming the file.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from uasnav.errors import DataFormatError


def connect(p: Path, **kw: Any) -> Any:
    """A pymavlink connection reading the log ``p`` (keyword arguments go to pymavlink).

    Raises
    ------
    DataFormatError
        If ``p`` is not a file or pymavlink cannot open it.
    """
    from pymavlink import mavutil

    if not p.is_file():
        raise DataFormatError("no such file", path=str(p))
    try:
        return mavutil.mavlink_connection(str(p), **kw)
    except Exception as e:  # pymavlink raises many exception types on bad input
        raise DataFormatError(f"not readable by pymavlink ({type(e).__name__}: {e})", path=str(p)) from None


def messages(conn: Any, types: Sequence[str], p: Path, what: str) -> Iterator[Any]:
    """Every message of the given ``types``, in log order.

    ``what`` names the format in the error (``"DataFlash"``, ``"MAVLink"``).

    Raises
    ------
    DataFormatError
        If pymavlink fails to decode a message.
    """
    wanted = list(types)
    while True:
        try:
            msg = conn.recv_match(type=wanted)
        except Exception as e:  # struct.error, IndexError, … on a truncated or corrupt log
            raise DataFormatError(f"corrupt {what} message ({type(e).__name__}: {e})", path=str(p)) from None
        if msg is None:
            return
        yield msg


__all__ = ["connect", "messages"]
