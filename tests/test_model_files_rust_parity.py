"""Issue #20 class 4, Rust side: the thermal-model loader of nav-core (``nav_core::mlp::json``,
reached through ``uasnav._core.mlp_evaluate_model``) refuses every hostile neural file that
Python's :func:`uasnav.thermal.loads_model` refuses, each error naming the same JSON key.

Every hostile file is re-signed with :func:`uasnav.thermal.modelfile.file_checksum`, so the
validation, not the checksum, refuses it; a control shows the unmodified re-signed file loads in
both and that Rust evaluates it as the NumPy reference does.
"""

from __future__ import annotations

import copy
import json
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from uasnav import _core
from uasnav.errors import DataFormatError
from uasnav.thermal import NeuralBiasModel, dumps_model, loads_model
from uasnav.thermal.modelfile import ZEROS, file_checksum
from uasnav.thermal.neural import forward

T = np.linspace(-10.0, 40.0, 400)
B = np.stack([1e-3 * np.tanh((T - 15) / 10), 2e-4 * np.sin(T / 9), 3e-6 * (T - 5) ** 2], 1)
PROBE_T = np.array([-10.0, 0.0, 15.5, 40.0])

Edit = Callable[[dict[str, Any]], object]


@pytest.fixture(scope="module")
def neural() -> dict[str, Any]:
    """A Python-written neural model file (3 axes, derivative networks), parsed."""
    nn = NeuralBiasModel(2, restarts=1, max_epochs=30, derivative_network=True).fit(T, B)
    return json.loads(dumps_model(nn))


def sign(d: dict[str, Any]) -> str:
    """``d`` as model-file text with a valid checksum."""
    d = copy.deepcopy(d)
    d["checksum"] = {"algorithm": "sha256", "value": ZEROS}
    text = json.dumps(d, indent=1)
    return text.replace(ZEROS, file_checksum(text, ZEROS), 1)


def setter(path: str, value: object) -> Edit:
    """An edit setting the value at the dotted ``path`` (list indices as numbers)."""

    def edit(d: dict[str, Any]) -> None:
        *parents, last = path.split(".")
        node: Any = d
        for key in parents:
            node = node[int(key)] if isinstance(node, list) else node[key]
        if isinstance(node, list):
            node[int(last)] = value
        else:
            node[last] = value

    return edit


def _65_models(d: dict[str, Any]) -> None:
    d["models"] = [copy.deepcopy(d["models"][0]) for _ in range(65)]
    d["axes"] = [str(i) for i in range(65)]
    d["derivative_models"] = None


CASES: list[tuple[str, Edit, str]] = [
    ("input scale 0", setter("models.1.input_norm.scale", 0.0), "models[1].input_norm.scale"),
    ("input scale < 0", setter("models.0.input_norm.scale", -0.04), "models[0].input_norm.scale"),
    ("output scale < 0", setter("models.2.output_norm.scale", -1e-4), "models[2].output_norm.scale"),
    (
        "derivative output scale 0",
        setter("derivative_models.1.output_norm.scale", 0),
        "derivative_models[1].output_norm.scale",
    ),
    ("range reversed", setter("calibrated_range_c", [40.0, -10.0]), "calibrated_range_c"),
    ("range empty", setter("calibrated_range_c", [10.0, 10.0]), "calibrated_range_c"),
    ("range 1e308", setter("calibrated_range_c", [27.0, 1e308]), "calibrated_range_c[1]"),
    ("range below -100", setter("calibrated_range_c", [-273.15, 40.0]), "calibrated_range_c[0]"),
    ("range as string", setter("calibrated_range_c", "27..34"), "calibrated_range_c"),
    ("range of strings", setter("calibrated_range_c", ["27", 34]), "calibrated_range_c[0]"),
    ("axes too few", setter("axes", ["x", "y"]), "axes"),
    ("axes too many", setter("axes", ["x", "y", "z", "w"]), "axes"),
    ("axes repeated", setter("axes", ["x", "y", "x"]), "axes"),
    ("axes non-string", setter("axes", ["x", 1, "z"]), "axes[1]"),
    ("derivative_models count", lambda d: d["derivative_models"].pop(), "derivative_models"),
    ("derivative_models empty", setter("derivative_models", []), "derivative_models"),
    ("65 models", _65_models, "models: 65 entries"),
    ("unknown top-level key", setter("extra", 1), "extra"),
    ("quantity", setter("quantity", "accel_bias"), "quantity"),
    ("quantity missing", lambda d: d.pop("quantity"), "quantity"),
    ("training not an object", setter("training", [1, 2]), "training"),
    ("training null", setter("training", None), "training"),
    ("unknown network key", setter("models.0.extra", 1), "models[0]"),
    ("bias beyond 100 rad/s", setter("models.0.layers.2.weights.0.0", 1e300), "models[0]: the model's bias"),
    ("bias offset 150 rad/s", setter("models.2.output_norm.offset", 150.0), "models[2]: the model's bias"),
]


def test_control_file_loads_in_both_and_evaluates_alike(neural) -> None:
    text = sign(neural)
    model = loads_model(text, "m.json")
    assert isinstance(model, NeuralBiasModel)
    v, d, clipped = _core.mlp_evaluate_model(text, PROBE_T)
    assert v.shape == d.shape == (PROBE_T.size, 3) and not clipped.any()
    for k, net in enumerate(model.networks_):
        ref_v, ref_d = forward(net, PROBE_T)
        np.testing.assert_allclose(v[:, k], ref_v, rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(d[:, k], ref_d, rtol=1e-9, atol=1e-16)
    dv, _, _ = _core.mlp_evaluate_model(text, PROBE_T, True, True)
    assert dv.shape == (PROBE_T.size, 3) and np.isfinite(dv).all()


@pytest.mark.parametrize(("edit", "key"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_hostile_file_is_refused_by_python_and_rust(neural, edit: Edit, key: str) -> None:
    d = copy.deepcopy(neural)
    edit(d)
    text = sign(d)
    with pytest.raises(DataFormatError) as py_err:
        loads_model(text, "m.json")
    with pytest.raises(DataFormatError) as rust_err:
        _core.mlp_evaluate_model(text, PROBE_T)
    for msg in (str(py_err.value), str(rust_err.value)):
        assert key in msg, msg
        assert "\n" not in msg and "panicked" not in msg
    assert str(rust_err.value).startswith("thermal model file: ")
