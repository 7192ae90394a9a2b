"""NumPy ``.npz`` logs (uasnav layout) and the ADIS16405 reference recording layout.

uasnav layout (written by :func:`write_npz`, uncompressed, no pickles):

============== =========== =====================================================
array          shape       content
============== =========== =====================================================
t              (n,)        s
gyro           (n, 3)      rad/s
accel          (n, 3)      m/s²
temp           (n,)        °C (optional)
mag            (n, 3)      µT (optional)
truth__<key>   (n, …)      ``ImuLog.truth[key]`` (optional)
meta_json      ()          ``ImuLog.meta`` as a JSON string
format         ()          ``"uasnav-npz/1"``
============== =========== =====================================================

Arrays are stored as float64 exactly, so write → read round-trips bit for bit.

ADIS layout (``imu/adis16405_static_imu1.npz`` of the reference data): ``gyro_dps`` (n, 3)
deg/s, ``accel_g`` (n, 3) g, ``rate_hz``; read with unit conversion and ``t = k / rate``.
"""

from __future__ import annotations

import io
import json
import os
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from uasnav.atomicfile import atomic_write_bytes
from uasnav.errors import DataFormatError, InputError
from uasnav.imu import ImuLog
from uasnav.units import convert

FORMAT = "uasnav-npz/1"


def write_npz(log: ImuLog, path: str | os.PathLike[str]) -> None:
    """Write ``log`` to ``path`` (uasnav npz layout) atomically."""
    arrays: dict[str, Any] = {"t": log.t, "gyro": log.gyro, "accel": log.accel}
    if log.temp is not None:
        arrays["temp"] = log.temp
    if log.mag is not None:
        arrays["mag"] = log.mag
    for k, v in log.truth.items():
        arrays[f"truth__{k}"] = np.ascontiguousarray(v)
    try:
        meta = json.dumps(log.meta, allow_nan=False)
    except (TypeError, ValueError) as e:
        raise InputError(f"meta: not JSON-serialisable ({e})") from None
    arrays["meta_json"] = np.array(meta)
    arrays["format"] = np.array(FORMAT)
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    atomic_write_bytes(path, buf.getvalue())


def _load(p: Path) -> dict[str, np.ndarray]:
    try:
        with np.load(p, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    except FileNotFoundError:
        raise DataFormatError("no such file", path=str(p)) from None
    except (zipfile.BadZipFile, OSError, ValueError, EOFError) as e:
        raise DataFormatError(f"not a readable .npz archive ({e})", path=str(p)) from None


def _need(z: dict[str, np.ndarray], key: str, p: Path, shape_tail: tuple[int, ...]) -> np.ndarray:
    if key not in z:
        raise DataFormatError(f"missing array {key!r} (has: {', '.join(sorted(z))})", path=str(p), column=key)
    a = z[key]
    if a.ndim != 1 + len(shape_tail) or a.shape[1:] != shape_tail:
        raise DataFormatError(f"array {key!r} has shape {a.shape}", path=str(p), column=key)
    if not np.issubdtype(a.dtype, np.number):
        raise DataFormatError(f"array {key!r} is not numeric ({a.dtype})", path=str(p), column=key)
    bad = ~np.isfinite(a)
    if bad.any():
        row = int(np.argwhere(bad)[0][0])
        raise DataFormatError(f"non-finite value in {key!r} at row {row}", path=str(p), line=row, column=key)
    return a.astype(np.float64, copy=False)


def read_npz(path: str | os.PathLike[str]) -> ImuLog:
    """Read an ``.npz`` log (uasnav layout, or the ADIS reference layout).

    Raises
    ------
    DataFormatError
        Missing/ill-shaped/non-finite arrays (named), unreadable archive.
    """
    p = Path(path)
    z = _load(p)
    if "gyro_dps" in z and "accel_g" in z:
        return _read_adis(z, p)
    gyro = _need(z, "gyro", p, (3,))
    accel = _need(z, "accel", p, (3,))
    t = _need(z, "t", p, ())
    temp = _need(z, "temp", p, ()) if "temp" in z else None
    mag = _need(z, "mag", p, (3,)) if "mag" in z else None
    truth = {}
    for k in z:
        if k.startswith("truth__"):
            a = z[k]
            truth[k[7:]] = _need(z, k, p, a.shape[1:])
    meta: dict[str, Any] = {}
    if "meta_json" in z:
        try:
            meta = json.loads(str(z["meta_json"]))
        except json.JSONDecodeError as e:
            raise DataFormatError(f"meta_json is not JSON ({e})", path=str(p), column="meta_json") from None
    try:
        return ImuLog(t=t, gyro=gyro, accel=accel, temp=temp, mag=mag, truth=truth, meta=meta)
    except InputError as e:
        raise DataFormatError(str(e), path=str(p)) from None


def _read_adis(z: dict[str, np.ndarray], p: Path) -> ImuLog:
    g = _need(z, "gyro_dps", p, (3,))
    a = _need(z, "accel_g", p, (3,))
    if g.shape[0] != a.shape[0]:
        raise DataFormatError(f"gyro_dps has {g.shape[0]} rows, accel_g {a.shape[0]}", path=str(p))
    rate = float(z["rate_hz"]) if "rate_hz" in z else 100.0
    if not rate > 0:
        raise DataFormatError(f"rate_hz must be > 0, got {rate}", path=str(p), column="rate_hz")
    t = np.arange(g.shape[0], dtype=np.float64) / rate
    return ImuLog(
        t=t,
        gyro=np.asarray(convert(g, "deg/s", "rad/s")),
        accel=np.asarray(convert(a, "g", "m/s^2")),
        meta={"source": str(p), "format": "adis-npz", "rate_hz": rate},
    )


__all__ = ["FORMAT", "read_npz", "write_npz"]
