"""Resource limits: refuse, up front, inputs that would need unbounded memory, work or bytes.

A few characters of input (a plan leg of 10⁹ m, ``--segment 1e-6``, ``--duration 1e12``,
``--db /dev/zero``) can ask for terabytes. Every place whose cost grows with a number the user
controls estimates that cost *before* allocating and calls :func:`check_memory` or
:func:`check_work`, which raise :class:`~uasnav.errors.ResourceLimitError` naming the limit
and how to raise it. Reads of untrusted files go through :func:`read_limited`, which reads at
most ``limit + 1`` bytes whatever size the file claims (``/dev/zero``, FIFOs, growing files).

Limits (environment variables, read at each check so a test or a shell can change them):

``UASNAV_MAX_MEMORY``
    Bytes one operation may allocate, with an optional suffix ``K``, ``M``, ``G``, ``T``
    (powers of 1024; ``KB``/``KiB`` … are accepted too), e.g. ``UASNAV_MAX_MEMORY=16G``.
    Default: 4 GiB, or half the physical memory if that is less. A set value must be a positive
    byte count: ``abc``, ``-1``, ``0``, ``nan``, ``inf`` or an empty value are refused.
``UASNAV_MAX_WORK``
    Elementary operations one computation may take (about 10⁹ per second on one core), e.g.
    ``UASNAV_MAX_WORK=1e13``. Default 2·10¹¹ (minutes, not days). A set value must be a
    positive finite number.

>>> parse_size("2G"), parse_size("512 MiB"), parse_size("1e6")
(2147483648, 536870912, 1000000)
>>> format_size(3 * 1024**3)
'3.0 GiB'
"""

from __future__ import annotations

import math
import os
import re
from typing import BinaryIO

from uasnav.errors import InputError, ResourceLimitError

#: Environment variable holding the memory limit (bytes, suffixes K/M/G/T allowed).
ENV_MEMORY = "UASNAV_MAX_MEMORY"
#: Environment variable holding the work limit (elementary operations).
ENV_WORK = "UASNAV_MAX_WORK"
#: Upper bound of the default memory limit (bytes): 4 GiB.
DEFAULT_MAX_MEMORY = 4 * 1024**3
#: Default work limit (elementary operations, ≈ 10⁹ per second).
DEFAULT_MAX_WORK = 2e11

#: Cost of predicting one plan point (element) with a trajectory model, in elementary
#: operations: about 0.15 ms of CPU per point, reading and output included (a 10⁵-point plan,
#: kinematic model, ``uasnav trajectory predict --json``: 16 s of CPU on a loaded 2-core
#: machine), so a plan's work is estimated before it is predicted.
PREDICTION_OPS_PER_POINT = 1.5e5

_SUFFIX = {"": 1, "k": 1024, "m": 1024**2, "g": 1024**3, "t": 1024**4}
_SIZE_RE = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:e[+-]?[0-9]+)?)\s*([kmgt]?)(?:i?b)?\s*$", re.IGNORECASE)


def parse_size(text: str | int | float, what: str = "size") -> int:
    """Parse a byte count: ``"4096"``, ``"512M"``, ``"2G"``, ``"1.5 GiB"``, ``"1e9"``.

    Suffixes are powers of 1024. Raises :class:`InputError` naming ``what`` for anything else
    (negative, NaN, empty, unknown suffix).
    """
    if isinstance(text, bool):
        raise InputError(f"{what}: expected a byte count such as 2G, got {text!r}")
    if isinstance(text, int | float):
        value = float(text)
        mult = 1
    else:
        m = _SIZE_RE.match(str(text))
        if m is None:
            raise InputError(f"{what}: expected a byte count such as 4096, 512M or 2G, got {text!r}")
        value, mult = float(m.group(1)), _SUFFIX[m.group(2).lower()]
    if not (math.isfinite(value) and value >= 0):
        raise InputError(f"{what}: expected a non-negative byte count, got {text!r}")
    return int(value * mult)


def format_size(nbytes: float) -> str:
    """Human-readable byte count (binary units)."""
    n = float(nbytes)
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if abs(n) < 1024:
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n:.1f} PiB" if abs(n) < 1e4 else f"{n:.2g} PiB"


def _physical_memory() -> int | None:
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        return None


def max_memory() -> int:
    """The memory limit in bytes: ``$UASNAV_MAX_MEMORY`` or the default (4 GiB, at most half the RAM)."""
    env = os.environ.get(ENV_MEMORY)
    if env is not None:
        value = parse_size(env, ENV_MEMORY) if env.strip() else 0
        if value <= 0:
            raise InputError(f"{ENV_MEMORY}: expected a positive byte count such as 16G, got {env!r}")
        return value
    ram = _physical_memory()
    return min(DEFAULT_MAX_MEMORY, ram // 2) if ram else DEFAULT_MAX_MEMORY


def env_positive(name: str, default: float, what: str) -> float:
    """The positive finite number in the environment variable ``name``, or ``default`` if it
    is unset; a set but invalid value (``abc``, ``-1``, ``0``, ``nan``, ``inf``, empty) is an
    :class:`InputError` naming the variable, ``what`` it expects and the value."""
    env = os.environ.get(name)
    if env is None:
        return default
    try:
        value = float(env)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise InputError(f"{name}: expected a positive number of {what}, got {env!r}")
    return value


def max_work() -> float:
    """The work limit (elementary operations): ``$UASNAV_MAX_WORK`` or 2·10¹¹."""
    return env_positive(ENV_WORK, DEFAULT_MAX_WORK, "operations such as 1e12")


def check_environment() -> None:
    """Refuse, up front, a set but invalid ``UASNAV_MAX_MEMORY`` / ``UASNAV_MAX_WORK`` (``abc``,
    ``-1``, ``0``, ``nan``, ``inf``, empty): a limit that is silently ignored is no limit.

    Raises
    ------
    InputError
        Naming the variable and its value.
    """
    max_memory()
    max_work()


def _hint(option: str | None) -> str:
    return f"reduce {option}, or " if option else ""


def check_memory(nbytes: float, what: str, *, option: str | None = None) -> None:
    """Refuse an allocation of about ``nbytes`` bytes if it exceeds :func:`max_memory`.

    Parameters
    ----------
    nbytes : float
        Estimated peak memory (bytes); may be inf or NaN (both refused).
    what : str
        What needs it, e.g. ``"simulate: 10¹⁴ samples"``.
    option : str, optional
        The option or parameter that drives the size (named in the message).

    Raises
    ------
    ResourceLimitError
        With the estimate, the limit and how to raise it.
    """
    limit = max_memory()
    if not (nbytes <= limit):  # also catches NaN
        need = format_size(nbytes) if math.isfinite(nbytes) else "unbounded memory"
        raise ResourceLimitError(
            f"{what} needs about {need}, more than the memory limit of {format_size(limit)}: "
            f"{_hint(option)}raise the limit with {ENV_MEMORY} (e.g. {ENV_MEMORY}=16G)"
        )


def check_work(ops: float, what: str, *, option: str | None = None) -> None:
    """Refuse a computation of about ``ops`` elementary operations beyond :func:`max_work`.

    Raises
    ------
    ResourceLimitError
        With the estimate, the limit and how to raise it.
    """
    limit = max_work()
    if not (ops <= limit):
        need = f"{ops:.2g}" if math.isfinite(ops) else "unbounded"
        raise ResourceLimitError(
            f"{what} needs about {need} operations, more than the work limit of {limit:.2g} "
            f"(≈ {limit / 1e9:.0f} s): {_hint(option)}raise the limit with {ENV_WORK} (e.g. {ENV_WORK}=1e13)"
        )


def check_count(n: float, bytes_each: float, what: str, *, option: str | None = None) -> int:
    """Check ``n`` items of ``bytes_each`` bytes against the memory limit; return ``int(n)``.

    ``n`` may be a float from a user's arithmetic (``duration × rate``): inf/NaN are refused
    before any ``int()`` conversion can raise ``OverflowError``.
    """
    if not math.isfinite(n):
        check_memory(math.inf, what, option=option)
    check_memory(float(n) * float(bytes_each), what, option=option)
    return int(n)


def read_limited(
    fh: BinaryIO, limit: int, where: str, *, option: str | None = None, chunk: int = 1 << 20
) -> bytes:
    """Read a binary stream, at most ``limit + 1`` bytes; refuse a longer stream.

    Works whatever the stream reports about its size (``/dev/zero``, pipes, sockets, files that
    grow while read). Raises :class:`ResourceLimitError` naming ``where``, the limit and
    ``option`` (the option that raises it, e.g. ``"--max-bytes"``).
    """
    parts: list[bytes] = []
    got = 0
    while got <= limit:
        block = fh.read(min(chunk, limit + 1 - got))
        if not block:
            break
        parts.append(block)
        got += len(block)
    if got > limit:
        how = f" (raise it with {option})" if option else ""
        raise ResourceLimitError(f"{where}: larger than the size limit of {limit} bytes{how}")
    return b"".join(parts)


def check_input_file(path: str | os.PathLike, what: str | None = None) -> None:
    """Refuse, before opening it, an input that would block a reader: a FIFO or a socket.

    ``open()`` of a FIFO waits for a writer, forever if none comes; a socket cannot be opened.
    Regular files, directories and character devices (``/dev/zero``: reads are bounded by
    :func:`read_limited`) pass; a missing path is left to the reader's own message.

    Raises
    ------
    InputError
        Naming ``what`` (default: the path) and the kind of file.
    """
    import stat

    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return
    kind = "a FIFO (named pipe)" if stat.S_ISFIFO(mode) else "a socket" if stat.S_ISSOCK(mode) else None
    if kind is not None:
        name = what if what is not None else os.fspath(path)
        raise InputError(
            f"{name}: {kind}, not a file; refusing to read it (a reader would wait for a writer)"
        )


def read_file_limited(
    path: str | os.PathLike, limit: int, where: str | None = None, *, option: str | None = None
) -> bytes:
    """Read a file (or device) with :func:`read_limited`; OSError → :class:`InputError`.

    A FIFO or socket is refused before opening (:func:`check_input_file`)."""
    name = where if where is not None else str(path)
    check_input_file(path, name)
    try:
        with open(path, "rb") as fh:
            return read_limited(fh, limit, name, option=option)
    except OSError as exc:
        raise InputError(f"{name}: cannot read ({exc.strerror or exc})") from None


__all__ = [
    "DEFAULT_MAX_MEMORY",
    "DEFAULT_MAX_WORK",
    "ENV_MEMORY",
    "ENV_WORK",
    "PREDICTION_OPS_PER_POINT",
    "check_count",
    "check_environment",
    "check_input_file",
    "check_memory",
    "check_work",
    "env_positive",
    "format_size",
    "max_memory",
    "max_work",
    "parse_size",
    "read_file_limited",
    "read_limited",
]
