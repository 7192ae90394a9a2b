"""The trajectory predictors by name, the default one, and a model-file reader for all of them.

``"kinematic"`` (:class:`~uasnav.trajectory.kinematic.KinematicPredictor`, the default) and
``"lvq"`` (:class:`~uasnav.trajectory.predictor.TrajectoryPredictor`, the thesis' network). The
default is the method most accurate by leave-one-run-out on real flights (see
:mod:`uasnav.trajectory.kinematic` and BENCHMARKS.md), not on simulation.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from uasnav import jsoncheck as jc
from uasnav.errors import DataFormatError, InputError
from uasnav.trajectory import kinematic, predictor
from uasnav.trajectory.kinematic import KinematicPredictor
from uasnav.trajectory.predictor import MAX_MODEL_BYTES, TrajectoryPredictor

#: A fitted predictor of either method (same ``predict``/``feasibility``/``save`` interface).
Predictor = KinematicPredictor | TrajectoryPredictor

#: Method names → estimator classes.
METHODS: dict[str, type[KinematicPredictor] | type[TrajectoryPredictor]] = {
    "kinematic": KinematicPredictor,
    "lvq": TrajectoryPredictor,
}
#: The default method: the most accurate by leave-one-run-out on the real flights measured.
DEFAULT_METHOD = "kinematic"

_FORMATS: dict[str, type[KinematicPredictor] | type[TrajectoryPredictor]] = {
    kinematic.MODEL_FORMAT: KinematicPredictor,
    predictor.MODEL_FORMAT: TrajectoryPredictor,
}


def method_of(model: Predictor) -> str:
    """The method name of a predictor ("kinematic" or "lvq")."""
    return "kinematic" if isinstance(model, KinematicPredictor) else "lvq"


def make_predictor(method: str = DEFAULT_METHOD, **params: Any) -> Predictor:
    """An unfitted predictor of ``method`` with its constructor ``params``."""
    try:
        cls = METHODS[method]
    except KeyError:
        raise InputError(
            f"unknown trajectory method {method!r}; expected one of {', '.join(METHODS)}"
        ) from None
    return cls(**params)


def model_from_dict(d: Any, source: str = "<dict>") -> Predictor:
    """A fitted predictor from model-file data of either format (by its ``"format"``)."""
    fmt = d.get("format") if isinstance(d, dict) else None
    cls = _FORMATS.get(fmt) if isinstance(fmt, str) else None
    if cls is None:
        raise DataFormatError(
            f"not a trajectory model (format {jc.show(fmt)}; expected one of {', '.join(_FORMATS)})",
            path=source,
        )
    return cls.from_dict(d, source=source)


def load_model(path: str | Path) -> Predictor:
    """Read a model file of either method (at most :data:`MAX_MODEL_BYTES`), checked."""
    with jc.reraise_in(str(path)):
        d = jc.parse(jc.read_text(path, MAX_MODEL_BYTES), "invalid JSON")
    return model_from_dict(d, source=str(path))


__all__ = [
    "DEFAULT_METHOD",
    "METHODS",
    "Predictor",
    "load_model",
    "make_predictor",
    "method_of",
    "model_from_dict",
]
