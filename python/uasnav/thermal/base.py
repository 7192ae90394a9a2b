"""What every thermal bias model is, and the registry that rebuilds one from its file by ``kind``.

:class:`BiasModel` is the interface the polynomial, neural and PX4 models share (and what
:mod:`uasnav.zupt` and :func:`uasnav.thermal.apply` need of a model): bias against die
temperature, fitted to ``temp`` (n,) °C and ``bias`` (n, k) rad/s.

A concrete model class registers itself with :func:`register_model`; the model file reader
(:mod:`uasnav.thermal.modelfile`) finds the class by the file's ``"kind"`` with
:func:`model_class`. So the reader imports no concrete model and the models import only this
module and the reader: no import circle.

>>> from uasnav.thermal import PolynomialBiasModel
>>> model_class("polynomial") is PolynomialBiasModel
True
>>> registered_kinds()
('neural', 'polynomial', 'px4')
"""

from __future__ import annotations

import os
from typing import Any, Literal, Protocol, Self, TypeVar, overload, runtime_checkable

from numpy.typing import ArrayLike

from uasnav.errors import InputError
from uasnav.thermal._common import BoolArray, FloatArray

#: A model's file content: the JSON object of :mod:`uasnav.thermal.modelfile` (JSON values,
#: hence ``Any``).
ModelDict = dict[str, Any]


@runtime_checkable
class BiasModel(Protocol):
    """A thermal model of gyro bias against die temperature (scikit-learn-like API).

    Attributes
    ----------
    kind : str
        The model file's ``"kind"`` (``"polynomial"``, ``"neural"``, ``"px4"``).
    range_c_ : tuple of float
        Calibrated temperature range (°C), set by :meth:`fit` or on loading; inputs outside it
        are clipped to it and flagged (:class:`uasnav.thermal.TemperatureRangeWarning`).
    """

    kind: str
    range_c_: tuple[float, float]

    def fit(self, temp: ArrayLike, bias: ArrayLike) -> Self:
        """Fit to temperatures ``temp`` (n,) °C and biases ``bias`` (n, k) rad/s; returns self."""
        ...

    @overload
    def predict(self, temp: ArrayLike, *, return_clipped: Literal[False] = ...) -> FloatArray: ...

    @overload
    def predict(self, temp: ArrayLike, *, return_clipped: Literal[True]) -> tuple[FloatArray, BoolArray]: ...

    def predict(
        self, temp: ArrayLike, *, return_clipped: bool = False
    ) -> FloatArray | tuple[FloatArray, BoolArray]:
        """Bias (n, k) rad/s at temperatures ``temp`` (n,) °C; with ``return_clipped`` also the
        (n,) mask of the samples clipped to the calibrated range."""
        ...

    def derivative(self, temp: ArrayLike) -> FloatArray:
        """∂bias/∂T (n, k) rad/s/°C at temperatures ``temp`` (n,) °C; 0 where clipped."""
        ...

    def to_dict(self) -> ModelDict:
        """The kind-specific part of the model file: ``{"models": [...], ...}``."""
        ...

    @classmethod
    def from_dict(cls, d: ModelDict, range_c: tuple[float, float]) -> Self:
        """Inverse of :meth:`to_dict`, with the calibrated range ``range_c`` (°C)."""
        ...

    def save(self, path: str | os.PathLike[str], training: ModelDict | None = None) -> None:
        """Write the model file atomically (:func:`uasnav.thermal.modelfile.save_model`)."""
        ...


_M = TypeVar("_M", bound=type)

_REGISTRY: dict[str, type] = {}


def register_model(cls: _M) -> _M:
    """Class decorator: make ``cls`` loadable from model files whose ``"kind"`` is ``cls.kind``.

    Raises :class:`InputError` if another class already holds that kind.
    """
    kind = getattr(cls, "kind", None)
    if not isinstance(kind, str) or not kind:
        raise InputError(f"register_model: {cls.__name__} has no string attribute 'kind'")
    held = _REGISTRY.get(kind)
    # The same class defined again (a module reloaded) replaces itself; another class may not.
    same = held is not None and (held.__module__, held.__qualname__) == (cls.__module__, cls.__qualname__)
    if held is not None and not same:
        raise InputError(f"register_model: kind {kind!r} is already registered by {held.__name__}")
    _REGISTRY[kind] = cls
    return cls


def model_class(kind: str) -> type[BiasModel]:
    """The class registered for model ``kind``; :class:`InputError` if none is."""
    cls = _REGISTRY.get(kind)
    if cls is None:
        raise InputError(f"unknown model kind {kind!r} (known: {', '.join(sorted(_REGISTRY)) or 'none'})")
    return cls  # type: ignore[return-value]


def registered_kinds() -> tuple[str, ...]:
    """The model kinds that can be loaded, sorted."""
    return tuple(sorted(_REGISTRY))


__all__ = [
    "BiasModel",
    "BoolArray",
    "FloatArray",
    "ModelDict",
    "model_class",
    "register_model",
    "registered_kinds",
]
