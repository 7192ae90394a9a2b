"""Helpers shared by the binary-log readers: building an :class:`ImuLog` from decoded arrays,
salvaging the valid records of a corrupt log, and the one-line corruption summary.

DataFlash and ULog records carry no checksum: a flipped bit in a record shows up as a time stamp
out of order, a non-finite value or a physically impossible one (a flipped exponent bit
multiplies a float by up to 2¹²⁸). :func:`salvage` keeps the records that are none of these,
:func:`report_corruption` says once, as a :class:`~uasnav.errors.CorruptDataWarning`, how much
was dropped, and :func:`build_log` refuses a stream with nothing valid left. Corruption that
leaves plausible values (a flipped low mantissa bit) cannot be detected without a checksum.
"""

from __future__ import annotations

import warnings
from bisect import bisect_right
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from uasnav.errors import CorruptDataWarning, DataFormatError
from uasnav.imu import ImuLog
from uasnav.io._quiet import LibraryOutput

#: |angular rate| above which a record is corrupt, rad/s: no MEMS gyro measures beyond
#: ±4000 °/s ≈ 70 rad/s.
MAX_RATE_RAD_S = 100.0
#: |specific force| above which a record is corrupt, m/s² (≈ 400 g, the largest MEMS
#: accelerometer range, e.g. H3LIS331).
MAX_SPECIFIC_FORCE_M_S2 = 4000.0
#: Plausible sensor temperatures, °C (outside: a corrupt record).
TEMP_RANGE_C = (-100.0, 200.0)


def longest_nondecreasing(t: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Mask of a longest non-decreasing subsequence of ``t`` (the records whose time stamps are
    in order; the others are corrupt). O(n log n); ``t`` already in order costs one pass.

    Examples
    --------
    >>> longest_nondecreasing(np.array([1.0, 2.0, 9e9, 3.0, 0.5, 4.0])).tolist()
    [True, True, False, True, False, True]
    """
    t = np.asarray(t, dtype=np.float64)
    n = t.size
    if n < 2 or not np.any(np.diff(t) < 0):
        return np.ones(n, dtype=bool)
    tails: list[float] = []  # smallest last value of a run of each length
    tail_idx: list[int] = []
    prev = [-1] * n
    for i, x in enumerate(t.tolist()):
        k = bisect_right(tails, x)
        if k:
            prev[i] = tail_idx[k - 1]
        if k == len(tails):
            tails.append(x)
            tail_idx.append(i)
        else:
            tails[k] = x
            tail_idx[k] = i
    keep = np.zeros(n, dtype=bool)
    i = tail_idx[-1]
    while i >= 0:
        keep[i] = True
        i = prev[i]
    return keep


def salvage(
    t: NDArray[np.float64],
    values: Mapping[str, NDArray[np.float64]],
    limits: Mapping[str, tuple[float, float]] | None = None,
) -> NDArray[np.bool_]:
    """Mask of the valid records of a stream without checksums.

    A record is valid if its time and every value in ``values`` (name → (n,) or (n, k)) are
    finite, every value named in ``limits`` lies within its (low, high) bounds, and its time
    stamp belongs to the longest run of records in time order (:func:`longest_nondecreasing`).
    """
    t = np.asarray(t, dtype=np.float64)
    ok = np.isfinite(t)
    for name, arr in values.items():
        a = np.asarray(arr, dtype=np.float64).reshape(t.size, -1)
        with np.errstate(invalid="ignore"):
            good = np.all(np.isfinite(a), axis=1)
            if limits and name in limits:
                lo, hi = limits[name]
                good &= np.all((a >= lo) & (a <= hi), axis=1)
        ok &= good
    keep = np.zeros(t.size, dtype=bool)
    idx = np.flatnonzero(ok)
    keep[idx[longest_nondecreasing(t[idx])]] = True
    return keep


def imu_limits(has_temp: bool) -> dict[str, tuple[float, float]]:
    """Bounds of :func:`salvage` for IMU records (gyro rad/s, accel m/s², temp °C)."""
    out = {
        "gyro": (-MAX_RATE_RAD_S, MAX_RATE_RAD_S),
        "accel": (-MAX_SPECIFIC_FORCE_M_S2, MAX_SPECIFIC_FORCE_M_S2),
    }
    if has_temp:
        out["temp"] = TEMP_RANGE_C
    return out


def report_corruption(
    path: str,
    decoder: LibraryOutput | None,
    dropped: int,
    total: int,
    what: str,
) -> None:
    """Warn once (:class:`~uasnav.errors.CorruptDataWarning`, one line) if the decoder found
    corruption or records were dropped; silent for a clean log."""
    parts = []
    if decoder is not None and decoder.problems:
        parts.append(decoder.summary())
    if dropped:
        parts.append(
            f"{dropped} of {total} {what} records dropped (time out of order, non-finite or "
            "implausible values)"
        )
    if parts:
        warnings.warn(f"{path}: corrupt data skipped: {'; '.join(parts)}", CorruptDataWarning, stacklevel=3)


def corruption_meta(decoder: LibraryOutput | None, dropped: int) -> dict[str, Any]:
    """The ``meta`` entries of a salvaged log (only when there was corruption):
    ``corrupt_records_dropped`` (int) and ``corruption`` (what the decoder found, one line)."""
    found = decoder.summary() if decoder is not None else ""
    if not found and not dropped:
        return {}
    return {"corrupt_records_dropped": int(dropped), "corruption": found or "invalid records"}


def because(decoder: LibraryOutput | None) -> str:
    """``" (what the decoder found)"`` for an error message, or ``""`` for a clean file."""
    return f" ({decoder.summary()})" if decoder is not None and decoder.problems else ""


def nothing_valid(path: str, what: str, total: int, decoder: LibraryOutput | None) -> DataFormatError:
    """The error for a corrupt stream of ``what`` records with fewer than 2 valid ones left."""
    extra = f"; {decoder.summary()}" if decoder is not None and decoder.problems else ""
    return DataFormatError(
        f"fewer than 2 valid {what} records among {total} (the others have time out of order, "
        f"non-finite or implausible values{extra}): the log is corrupt",
        path=path,
    )


def drop_sparse_streams(counts: Mapping[str, int], fraction: float = 0.01) -> Sequence[str]:
    """Keys of instance streams far smaller than the largest (fewer than ``fraction`` of its
    records, or fewer than 2): the product of a corrupt instance number, not a sensor."""
    if not counts:
        return []
    biggest = max(counts.values())
    return [k for k, c in counts.items() if c < max(2, fraction * biggest)]


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
            f"{what}: time stamp goes backwards at message #{i} ({float(t[i - 1])!r} → {float(t[i])!r} s)",
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
