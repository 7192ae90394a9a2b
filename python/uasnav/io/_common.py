"""Helpers shared by the binary-log readers."""

from __future__ import annotations

from typing import Any

import numpy as np

from uasnav.errors import DataFormatError
from uasnav.imu import ImuLog


def build_log(
    path: str,
    what: str,
    t: np.ndarray,
    gyro: np.ndarray,
    accel: np.ndarray,
    temp: np.ndarray | None,
    meta: dict[str, Any],
    mag: np.ndarray | None = None,
) -> ImuLog:
    """Validate arrays decoded from message ``what`` and build an :class:`ImuLog`.

    Exact duplicate time stamps (repeated messages) are dropped and counted in
    ``meta["dropped_duplicates"]``; a time stamp going backwards, or a non-finite value, is a
    :class:`DataFormatError` naming the message, field and index.
    """
    t = np.asarray(t, dtype=np.float64)
    if t.size < 2:
        raise DataFormatError(f"{what}: {t.size} messages, need at least 2", path=path, column=what)
    fields = {"time": t[:, None], "gyro": gyro, "accel": accel}
    if temp is not None:
        fields["temperature"] = np.asarray(temp, dtype=np.float64)[:, None]
    if mag is not None:
        fields["mag"] = mag
    for name, arr in fields.items():
        bad = ~np.isfinite(arr)
        if bad.any():
            i = int(np.argwhere(bad)[0][0])
            raise DataFormatError(
                f"{what}: non-finite {name} in message #{i}", path=path, column=f"{what}.{name}"
            )
    d = np.diff(t)
    back = np.flatnonzero(d < 0)
    if back.size:
        i = int(back[0]) + 1
        raise DataFormatError(
            f"{what}: time stamp goes backwards at message #{i} ({t[i - 1]!r} → {t[i]!r} s)",
            path=path,
            column=f"{what}.time",
        )
    keep = np.concatenate([[True], d > 0])
    dropped = int((~keep).sum())
    meta = {**meta, "dropped_duplicates": dropped}
    return ImuLog(
        t=t[keep],
        gyro=np.asarray(gyro, dtype=np.float64)[keep],
        accel=np.asarray(accel, dtype=np.float64)[keep],
        temp=None if temp is None else np.asarray(temp, dtype=np.float64)[keep],
        mag=None if mag is None else np.asarray(mag, dtype=np.float64)[keep],
        meta=meta,
    )
