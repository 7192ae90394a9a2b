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
import math
import os
import zipfile
import zlib
from pathlib import Path
from typing import IO, Any, ClassVar

import numpy as np
from numpy.lib import format as npformat

from uasnav.atomicfile import atomic_write_bytes
from uasnav.errors import DataFormatError, InputError
from uasnav.imu import ImuLog, require_log
from uasnav.io.formats.base import ImuFileFormat
from uasnav.limits import check_memory
from uasnav.units import convert

FORMAT = "uasnav-npz/1"
#: Most members an archive may have (a uasnav log has a few plus its truth channels).
MAX_MEMBERS = 1000


def write_npz(log: ImuLog, path: str | os.PathLike[str]) -> None:
    """Write ``log`` to ``path`` (uasnav npz layout) atomically."""
    require_log(log)
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
    """Every ``.npy`` member of the archive ``p``, read with checks before any allocation.

    np.load would trust the archive: a member's declared size is checked here against the
    memory limit (a zip bomb is refused before it is inflated), object arrays are refused (they
    need pickle, which would run code from the file), and a member whose array header does not
    match its size is corrupt.
    """
    src = str(p)
    if not p.exists():
        raise DataFormatError("no such file", path=src)
    if not p.is_file():
        raise DataFormatError("not a regular file", path=src)  # a device or FIFO
    try:
        with zipfile.ZipFile(p) as zf:
            infos = zf.infolist()
            if len(infos) > MAX_MEMBERS:
                raise DataFormatError(f"{len(infos)} members, more than {MAX_MEMBERS}", path=src)
            check_memory(float(sum(i.file_size for i in infos)), f"{src}: the arrays (uncompressed sizes)")
            out = {}
            for info in infos:
                if info.filename.endswith(".npy"):
                    key = info.filename[: -len(".npy")]
                    with zf.open(info) as fh:
                        out[key] = _read_member(fh, info, key, src)
            return out
    # zipfile raises NotImplementedError for a compression method it does not support (a hostile
    # or exotic archive): a bad file, reported as such.
    except (zipfile.BadZipFile, zipfile.LargeZipFile, zlib.error, EOFError, NotImplementedError) as e:
        raise DataFormatError(f"not a readable .npz archive ({e})", path=src) from None
    except RuntimeError as e:  # an encrypted member
        raise DataFormatError(f"not a readable .npz archive ({e})", path=src) from None
    except OSError as e:
        raise DataFormatError(f"not a readable .npz archive ({e.strerror or e})", path=src) from None


def _read_member(fh: IO[bytes], info: zipfile.ZipInfo, key: str, src: str) -> np.ndarray:
    """The array of one ``.npy`` member (see :func:`_load`)."""
    try:
        version = npformat.read_magic(fh)
        header = {(1, 0): npformat.read_array_header_1_0, (2, 0): npformat.read_array_header_2_0}.get(version)
        if header is None:
            raise ValueError(f"unsupported .npy version {version}")
        shape, fortran, dtype = header(fh)
    except (ValueError, SyntaxError, TypeError) as e:
        raise DataFormatError(f"array {key!r}: not a .npy array ({e})", path=src, column=key) from None
    if dtype.hasobject:
        raise DataFormatError(
            f"array {key!r} holds Python objects ({dtype}); uasnav reads numeric arrays only "
            "(object arrays would need pickle, which can run code from the file)",
            path=src,
            column=key,
        )
    count = math.prod(shape)
    nbytes = count * dtype.itemsize
    check_memory(float(nbytes), f"{src}: array {key!r} of shape {shape}")
    start = fh.tell()
    if start + nbytes != info.file_size:
        raise DataFormatError(
            f"array {key!r}: corrupt member (shape {shape} of {dtype} needs {nbytes} bytes, "
            f"the member holds {info.file_size - start})",
            path=src,
            column=key,
        )
    buf = bytearray(nbytes)  # writable, like np.load's arrays
    got = 0
    while got < nbytes:
        chunk = fh.read(min(1 << 20, nbytes - got))
        if not chunk:
            raise DataFormatError(f"array {key!r}: truncated member", path=src, column=key)
        buf[got : got + len(chunk)] = chunk
        got += len(chunk)
    arr = np.frombuffer(buf, dtype=dtype, count=count) if count else np.empty(0, dtype=dtype)
    return arr.reshape(shape, order="F" if fortran else "C")


def _need(z: dict[str, np.ndarray], key: str, p: Path, shape_tail: tuple[int, ...]) -> np.ndarray:
    if key not in z:
        raise DataFormatError(f"missing array {key!r} (has: {', '.join(sorted(z))})", path=str(p), column=key)
    a = z[key]
    if not (np.issubdtype(a.dtype, np.integer) or np.issubdtype(a.dtype, np.floating)):
        kind = "complex, not real" if np.issubdtype(a.dtype, np.complexfloating) else "not numeric"
        raise DataFormatError(f"array {key!r} is {kind} ({a.dtype})", path=str(p), column=key)
    if a.ndim != 1 + len(shape_tail) or a.shape[1:] != shape_tail:
        want = "(n" + "".join(f", {d}" for d in shape_tail) + ")"
        raise DataFormatError(f"array {key!r} has shape {a.shape}, expected {want}", path=str(p), column=key)
    bad = ~np.isfinite(a)
    if bad.any():
        row = int(np.argwhere(bad)[0][0])
        raise DataFormatError(f"non-finite value in {key!r} at row {row}", path=str(p), line=row, column=key)
    return a.astype(np.float64, copy=False)


def _scalar(z: dict[str, np.ndarray], key: str, p: Path) -> np.ndarray:
    a = z[key]
    if a.size != 1:
        raise DataFormatError(f"{key!r} must hold one value, has shape {a.shape}", path=str(p), column=key)
    return a.reshape(())


def read_npz(path: str | os.PathLike[str]) -> ImuLog:
    """Read an ``.npz`` log (uasnav layout, or the ADIS reference layout).

    Raises
    ------
    DataFormatError
        Missing, ill-shaped, non-real or non-finite arrays (named), object arrays (never
        unpickled), an unreadable or corrupt archive, ``meta_json`` that is not a JSON object.
    ResourceLimitError
        If an array would need more memory than the limit (checked from the sizes the archive
        declares, before inflating; ``UASNAV_MAX_MEMORY``).
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
            if not k[7:]:
                raise DataFormatError("truth array without a name ('truth__')", path=str(p), column=k)
            truth[k[7:]] = _need(z, k, p, z[k].shape[1:])
    meta: dict[str, Any] = {}
    if "meta_json" in z:
        raw = _scalar(z, "meta_json", p)
        if raw.dtype.kind not in "US":
            raise DataFormatError(f"meta_json is not a string ({raw.dtype})", path=str(p), column="meta_json")
        try:
            meta = json.loads(str(raw))
        except json.JSONDecodeError as e:
            raise DataFormatError(f"meta_json is not JSON ({e})", path=str(p), column="meta_json") from None
        except (RecursionError, ValueError) as e:
            raise DataFormatError(
                f"meta_json is not usable JSON ({e})", path=str(p), column="meta_json"
            ) from None
        if not isinstance(meta, dict):
            raise DataFormatError(
                f"meta_json must be a JSON object, got {type(meta).__name__}", path=str(p), column="meta_json"
            )
    try:
        return ImuLog(t=t, gyro=gyro, accel=accel, temp=temp, mag=mag, truth=truth, meta=meta)
    except InputError as e:
        raise DataFormatError(str(e), path=str(p)) from None


def _read_adis(z: dict[str, np.ndarray], p: Path) -> ImuLog:
    g = _need(z, "gyro_dps", p, (3,))
    a = _need(z, "accel_g", p, (3,))
    if g.shape[0] != a.shape[0]:
        raise DataFormatError(f"gyro_dps has {g.shape[0]} rows, accel_g {a.shape[0]}", path=str(p))
    rate = 100.0
    if "rate_hz" in z:
        r = _scalar(z, "rate_hz", p)
        if not (np.issubdtype(r.dtype, np.integer) or np.issubdtype(r.dtype, np.floating)):
            raise DataFormatError(f"rate_hz is not a real number ({r.dtype})", path=str(p), column="rate_hz")
        rate = float(r)
    if not (np.isfinite(rate) and rate > 0):
        raise DataFormatError(
            f"rate_hz must be a finite number > 0, got {rate}", path=str(p), column="rate_hz"
        )
    t = np.arange(g.shape[0], dtype=np.float64) / rate
    return ImuLog(
        t=t,
        gyro=np.asarray(convert(g, "deg/s", "rad/s")),
        accel=np.asarray(convert(a, "g", "m/s^2")),
        meta={"source": str(p), "format": "adis-npz", "rate_hz": rate},
    )


class NpzFormat(ImuFileFormat):
    """uasnav / ADIS ``.npz`` IMU arrays (:func:`read_npz`)."""

    name = "npz"
    SOURCES: ClassVar[dict[str, tuple[str, ...]]] = {"imus": (), "imu": (), "identity": ()}

    def read_imu(self) -> ImuLog:
        return read_npz(self.path)


__all__ = ["FORMAT", "NpzFormat", "read_npz", "write_npz"]
