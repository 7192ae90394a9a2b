"""Optional parts of uasnav and the one ``pip install`` line that adds each.

``pip install uasnav`` gives the navigation core, the log formats, the command line and the
report's navigation sections. The rest is opt-in:

========  =====================================================  ==================================
extra     adds                                                   needs
========  =====================================================  ==================================
web       ``uasnav serve`` (the local web application)           fastapi, uvicorn, jinja2,
                                                                 python-multipart
utm       operational intents (ASTM F3548), ``uasnav utm``,      uas-standards, pyyaml
          ``plan``, ``monitor``, ``trajectory intent``
fleet     ``uasnav fleet`` on a local Dask cluster, Parquet      dask[distributed], pyarrow
          datasets (also read by ``trajectory train``)
all       everything above
========  =====================================================  ==================================

A command that needs a missing extra stops with one line naming it and the install line
(:class:`MissingExtraError`); :func:`require` is called where the optional library is imported,
so the rest of the package never imports it.
"""

from __future__ import annotations

import importlib.util

from uasnav.errors import UasnavError

#: Import names each extra provides (the first missing one is named in the message).
EXTRAS: dict[str, tuple[str, ...]] = {
    "web": ("fastapi", "uvicorn", "jinja2", "multipart"),
    "utm": ("uas_standards", "yaml"),
    "fleet": ("dask", "distributed", "pyarrow"),
}


class MissingExtraError(UasnavError, ImportError):
    """A command needs an optional part of uasnav that is not installed."""

    def __init__(self, extra: str, what: str, module: str) -> None:
        self.extra = extra
        self.module = module
        super().__init__(
            f"{what} needs the '{extra}' extra ({module} is not installed): pip install 'uasnav[{extra}]'"
        )


def missing(extra: str) -> str | None:
    """The first import name of ``extra`` that is not installed, or None."""
    for module in EXTRAS[extra]:
        try:
            if importlib.util.find_spec(module) is None:
                return module
        except (ImportError, ValueError):
            return module
    return None


def require(extra: str, what: str) -> None:
    """Raise :class:`MissingExtraError` when ``extra`` is not installed; ``what`` names the
    command or function that needs it (``"uasnav serve"``)."""
    if extra not in EXTRAS:
        raise KeyError(f"unknown extra {extra!r}")
    module = missing(extra)
    if module is not None:
        raise MissingExtraError(extra, what, module)


def extra_of(error: ModuleNotFoundError) -> str | None:
    """The extra that provides the module ``error`` could not import, or None."""
    top = (error.name or "").split(".")[0]
    return next((extra for extra, mods in EXTRAS.items() if top in mods), None)


__all__ = ["EXTRAS", "MissingExtraError", "extra_of", "missing", "require"]
