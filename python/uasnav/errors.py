"""The uasnav exception hierarchy.

Every error uasnav raises on purpose derives from :class:`UasnavError`. Errors caused by bad
input (wrong shapes, NaN, malformed files, unknown units) also derive from :class:`ValueError`
so that ``except ValueError`` keeps working for users who do not know our types. The Rust core
raises the same classes (see ``crates/py-uasnav/src/errors.rs``).
"""

from __future__ import annotations


class UasnavError(Exception):
    """Base class of every uasnav error."""


class InputError(UasnavError, ValueError):
    """Input data or parameters are invalid (shape, NaN/inf, range, too short …)."""


class DataFormatError(InputError):
    """A file's contents are malformed. The message names the file, line and column."""

    def __init__(
        self,
        message: str,
        *,
        path: str | None = None,
        line: int | None = None,
        column: str | None = None,
    ) -> None:
        where = []
        if path is not None:
            where.append(str(path))
        if line is not None:
            where.append(f"line {line}")
        if column is not None:
            where.append(f"column {column!r}")
        super().__init__(f"{', '.join(where)}: {message}" if where else message)
        self.path = path
        self.line = line
        self.column = column


class UnitError(InputError):
    """A unit is unknown, or two units are not of the same dimension."""


class NumericalError(UasnavError, ArithmeticError):
    """A computation became numerically invalid (e.g. a covariance lost positive definiteness)."""


class ResourceLimitError(InputError):
    """The input asks for more memory, work or bytes than a resource limit allows.

    Raised up front (before allocating) by :mod:`uasnav.limits`; the message names the limit
    and how to raise it (``UASNAV_MAX_MEMORY``, ``UASNAV_MAX_WORK`` or an option).
    """


class CorruptDataWarning(UserWarning):
    """Part of a file was corrupt and was skipped; the data read are the valid rest.

    Issued once per file read, as one line naming the file and how much was dropped (e.g. a
    DataFlash log with flipped bits). Readers raise :class:`DataFormatError` instead when
    nothing valid is left.
    """


__all__ = [
    "CorruptDataWarning",
    "DataFormatError",
    "InputError",
    "NumericalError",
    "ResourceLimitError",
    "UasnavError",
    "UnitError",
]
