"""Issue #20 class 4: model files are validated fully at load, training inputs at fit.

Thermal model files carry a checksum verified first, so every hostile file here is re-signed
with the module's own :func:`file_checksum` (else the checksum, not the validation, would
refuse it); one test covers the invalid checksum itself. Each hostile file must give one
:class:`DataFormatError` naming the JSON path of the value at fault (and the file, once); a
control test shows the same harness loads the unmodified file, so the cases can fail.
"""

from __future__ import annotations

import copy
import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from uasnav.errors import DataFormatError, InputError
from uasnav.imu import ImuLog
from uasnav.io import write_log
from uasnav.thermal import (
    NeuralBiasModel,
    PolynomialBiasModel,
    Px4BiasModel,
    dumps_model,
    fit_hysteresis,
    load_model,
    load_training_data,
    loads_model,
    select_hidden_neurons,
    select_polynomial_order,
)
from uasnav.thermal.modelfile import ZEROS, file_checksum
from uasnav.trajectory.features import Features
from uasnav.trajectory.predictor import MIN_SEGMENT_M, N_FEATURES, TrajectoryPredictor
from uasnav.trajectory.samples import ElementSamples

# -- thermal model files ----------------------------------------------------------------------

T = np.linspace(-10.0, 40.0, 400)
B = np.stack([1e-3 * np.tanh((T - 15) / 10), 2e-4 * np.sin(T / 9), 3e-6 * (T - 5) ** 2], 1)


@pytest.fixture(scope="module")
def files() -> dict[str, dict[str, Any]]:
    """The parsed model file of each kind (a dict to mutate)."""
    nn = NeuralBiasModel(2, restarts=1, max_epochs=30, derivative_network=True).fit(T, B)
    models = {"polynomial": PolynomialBiasModel(3).fit(T, B), "px4": Px4BiasModel().fit(T, B), "neural": nn}
    return {k: json.loads(dumps_model(m)) for k, m in models.items()}


def sign(d: dict[str, Any]) -> str:
    """``d`` as model-file text with a valid checksum (NaN/Infinity written as JSON lets them)."""
    d = copy.deepcopy(d)
    d["checksum"] = {"algorithm": "sha256", "value": ZEROS}
    text = json.dumps(d, indent=1)
    return text.replace(ZEROS, file_checksum(text, ZEROS), 1)


def mutated(d: dict[str, Any], edit: Callable[[dict[str, Any]], Any]) -> dict[str, Any]:
    d = copy.deepcopy(d)
    edit(d)
    return d


def setter(path: str, value: Any) -> Callable[[dict[str, Any]], None]:
    """An edit setting the value at a dotted path (``models.0.coefficients.1``)."""

    def edit(d: dict[str, Any]) -> None:
        keys = [int(k) if k.lstrip("-").isdigit() else k for k in path.split(".")]
        node: Any = d
        for k in keys[:-1]:
            node = node[k]
        node[keys[-1]] = value

    return edit


def remover(key: str) -> Callable[[dict[str, Any]], None]:
    return lambda d: d.pop(key)


NAN, INF = float("nan"), float("inf")

COMMON = [
    # Ranges: the string "27..34" was read as [2, 7]; reversed, NaN, absurd, strings, wrong length.
    (setter("calibrated_range_c", "27..34"), r'calibrated_range_c: expected \[min, max\].*got "27\.\.34"'),
    (
        setter("calibrated_range_c", [34.0, 27.0]),
        r"calibrated_range_c: minimum 34\.0 is not below maximum 27",
    ),
    (setter("calibrated_range_c", [27.0, 27.0]), r"calibrated_range_c: minimum 27\.0 is not below"),
    (
        setter("calibrated_range_c", [NAN, 34.0]),
        r"calibrated_range_c\[0\]: expected a finite number, got NaN",
    ),
    (
        setter("calibrated_range_c", [27.0, 1e308]),
        r"calibrated_range_c\[1\]: 1e\+308 °C is outside .*\[-100, 200\]",
    ),
    (
        setter("calibrated_range_c", ["27", "34"]),
        r'calibrated_range_c\[0\]: expected a number, got the string "27"',
    ),
    (setter("calibrated_range_c", [27.0]), r"calibrated_range_c: expected \[min, max\]"),
    (setter("calibrated_range_c", [27.0, 30.0, 34.0]), r"calibrated_range_c: expected \[min, max\]"),
    (remover("calibrated_range_c"), r"calibrated_range_c: missing"),
    # Axes and models: counts, empty, wrong types, absurd sizes.
    (setter("axes", ["x", "y"]), r"axes: 2 axes named but 3 models given"),
    (setter("axes", ["x", "x", "y"]), r"axes: axis names repeat"),
    (setter("axes", ["x", "y", 3]), r"axes\[2\]: expected a string, got 3"),
    (setter("models", []), r"models: empty array"),
    (setter("models", {"x": 1}), r"models: expected an array, got an object"),
    (
        lambda d: d.update(models=d["models"] * 22, axes=[str(i) for i in range(66)]),
        r"models: 66 entries, at most 64",
    ),
    (setter("models.0", [1.0, 2.0]), r"models\[0\]: expected an object, got an array"),
    # Other fields and types.
    (setter("extra", 1), r"extra: unknown key"),
    (setter("quantity", "accel_bias"), r'quantity: expected one of "gyro_bias", got "accel_bias"'),
    (setter("training", [1, 2]), r"training: expected an object, got an array"),
    (setter("kind", 5), r"kind: expected a string, got 5"),
    (setter("schema_version", True), r"schema_version true is not supported"),
    (setter("units", {"input": "degF", "output": "rad/s", "derivative": "rad/s/degC"}), r"units: .*degF"),
    # Absurd nesting inside the free-form metadata (the parser's depth is bounded at 64).
    (setter("training", {"x": json.loads("[" * 80 + "]" * 80)}), r"nested deeper than 64 levels"),
]

POLY = [
    (
        setter("models.0.coefficients.1", NAN),
        r"models\[0\]\.coefficients\[1\]: expected a finite number, got NaN",
    ),
    (
        setter("models.2.coefficients.0", INF),
        r"models\[2\]\.coefficients\[0\]: expected a finite number, got Infinity",
    ),
    (setter("models.1.coefficients.0", -INF), r"models\[1\]\.coefficients\[0\]: expected a finite number"),
    (
        setter("models.0.coefficients", "1,2,3"),
        r'models\[0\]\.coefficients: expected an array, got the string "1,2,3"',
    ),
    (setter("models.0.coefficients", []), r"models\[0\]\.coefficients: empty array"),
    (
        setter("models.0.coefficients", [[1e-3], [2e-3]]),
        r"models\[0\]\.coefficients\[0\]: expected a number, got an array",
    ),
    (
        setter("models.0.coefficients.0", "1.5"),
        r'models\[0\]\.coefficients\[0\]: expected a number, got the string "1\.5"',
    ),
    (
        setter("models.0.coefficients.0", True),
        r"models\[0\]\.coefficients\[0\]: expected a number, got the boolean true",
    ),
    (setter("models.0.coefficients.0", None), r"models\[0\]\.coefficients\[0\]: expected a number, got null"),
    (setter("models.0.coefficients", [0.0] * 22), r"models\[0\]\.coefficients: 22 entries, at most 21"),
    (
        setter("models.1.coefficients", [0.0] * 3),
        r"models\[1\]\.coefficients: 3 coefficients, models\[0\] has 4",
    ),
    (setter("models.0.scale_c", -25.0), r"models\[0\]\.scale_c: expected a number > 0 °C, got -25\.0"),
    (setter("models.0.scale_c", 0), r"models\[0\]\.scale_c: expected a number > 0"),
    (setter("models.1.center_c", 20.0), r"models\[1\]: center_c/scale_c differ from models\[0\]"),
    (
        setter("models.0.center_c", 1e6),
        r"models\[0\]\.center_c: 1000000\.0 °C is outside the accepted range \[-100, 200\] °C",
    ),
    (setter("models.0.foo", 1), r"models\[0\]\.foo: unknown key"),
    (lambda d: d["models"][0].pop("center_c"), r"models\[0\]\.center_c: missing"),
    (setter("derivative_models", [{}, {}, {}]), r"derivative_models: a polynomial model has none"),
    (setter("derivative_models", []), r"derivative_models: empty array"),
    # Finite numbers that overflow or are absurd when evaluated: caught by the probe at load.
    (
        lambda d: [m.update(scale_c=1e-300) for m in d["models"]],
        r"models\[0\]: the model's bias at .* is non-finite",
    ),
    (setter("models.2.coefficients.0", 1e300), r"models\[2\]: the model's bias at .* beyond ±100 rad/s"),
]

PX4 = [
    (
        setter("models.0.coefficients", [1e-3, 0.0, 0.0]),
        r"models\[0\]\.coefficients: expected 4 numbers, got 3",
    ),
    (setter("models.1.tref_c", 3.0), r"models\[1\]\.tref_c: 3 °C differs from models\[0\]'s 15 °C"),
    (setter("models.0.tref_c", "15"), r'models\[0\]\.tref_c: expected a number, got the string "15"'),
    (setter("models.0.coefficients.3", NAN), r"models\[0\]\.coefficients\[3\]: expected a finite number"),
    (setter("derivative_models", [{}, {}, {}]), r"derivative_models: a px4 model has none"),
]

NEURAL = [
    (
        setter("models.0.layers.0.weights.1.0", NAN),
        r"models\[0\]\.layers\[0\]\.weights\[1\]\[0\]: expected a finite number",
    ),
    (
        setter("models.2.layers.2.biases.0", INF),
        r"models\[2\]\.layers\[2\]\.biases\[0\]: expected a finite number",
    ),
    (setter("models.1.input_norm.scale", -0.04), r"models\[1\]\.input_norm\.scale: expected a number > 0"),
    (setter("models.0.output_norm.scale", 0.0), r"models\[0\]\.output_norm\.scale: expected a number > 0"),
    (setter("models.0.output_norm.offset", "0"), r"models\[0\]\.output_norm\.offset: expected a number"),
    (lambda d: d["models"][0]["layers"].pop(1), r"models\[0\]\.layers: expected 3 layers"),
    (
        setter("models.0.layers.1.activation", "relu"),
        r'models\[0\]\.layers\[1\]\.activation: expected one of "tanh"',
    ),
    (
        setter("models.0.layers.1.weights.0", [0.5]),
        r"models\[0\]\.layers\[1\]\.weights\[0\]: expected 2 numbers, got 1",
    ),
    (
        setter("models.0.layers.1.weights", [[0.5, 0.1]]),
        r"models\[0\]\.layers\[1\]\.weights: expected 2 rows, got 1",
    ),
    (
        setter("models.0.layers.0.weights", [0.5, 0.1]),
        r"models\[0\]\.layers\[0\]\.weights\[0\]: expected an array, got 0\.5",
    ),
    (
        setter("models.0.layers.0.weights", [[[0.5]], [[0.1]]]),
        r"weights\[0\]\[0\]: expected a number, got an array",
    ),
    (
        setter("models.0.layers.0.biases", [0.0] * 17),
        r"models\[0\]\.layers\[0\]\.biases: 17 entries, at most 16",
    ),
    (
        setter("models.0.layers.2.biases", [0.0, 0.0]),
        r"models\[0\]\.layers\[2\]\.biases: 2 entries, at most 1",
    ),
    (setter("models.0.layers", []), r"models\[0\]\.layers: empty array"),
    (lambda d: d["derivative_models"].pop(), r"derivative_models: 2 networks for 3 axes"),
    (
        setter("derivative_models.1.input_norm.scale", NAN),
        r"derivative_models\[1\]\.input_norm\.scale: expected a finite",
    ),
    (
        setter("models.0.layers.2.weights.0.0", 1e300),
        r"models\[0\]: the model's bias at .* beyond ±100 rad/s",
    ),
]

CASES = (
    [("polynomial", e, m) for e, m in COMMON + POLY]
    + [("px4", e, m) for e, m in PX4]
    + [("neural", e, m) for e, m in NEURAL]
    + [("neural", e, m) for e, m in COMMON[:6]]
)


@pytest.mark.parametrize("kind", ["polynomial", "px4", "neural"])
def test_control_signed_file_loads(files, kind) -> None:
    """The harness itself: an unmodified re-signed file loads (so the cases below can fail)."""
    m = loads_model(sign(files[kind]), "m.json")
    assert m.kind == kind and m.range_c_ == (-10.0, 40.0)


@pytest.mark.parametrize(("kind", "edit", "match"), CASES, ids=[f"{k}-{m[:40]}" for k, _, m in CASES])
def test_hostile_thermal_file_is_refused_naming_the_key(files, kind, edit, match) -> None:
    with pytest.raises(DataFormatError, match=match) as ei:
        loads_model(sign(mutated(files[kind], edit)), "m.json")
    msg = str(ei.value)
    assert msg.startswith("m.json: ") and msg.count("m.json") == 1 and "\n" not in msg


def test_checksum_is_checked_before_the_content(files) -> None:
    bad = mutated(files["polynomial"], setter("models.0.coefficients.1", NAN))
    text = sign(bad)
    edited = text.replace('"quantity": "gyro_bias"', '"quantity": "gyro_bias" ')
    with pytest.raises(DataFormatError, match="checksum mismatch"):
        loads_model(edited)
    value = json.loads(text)["checksum"]["value"]
    with pytest.raises(DataFormatError, match="not a unique 64-digit hex string"):
        loads_model(text.replace(value, "z" * 64))
    with pytest.raises(DataFormatError, match="missing or unknown checksum"):
        loads_model(json.dumps({k: v for k, v in bad.items() if k != "checksum"}))


def test_pathological_json_text(files, tmp_path) -> None:
    # Nested far beyond the recursion limit: json.loads raises RecursionError, not a traceback.
    with pytest.raises(DataFormatError, match="nested deeper than 64"):
        loads_model("[" * 100_000 + "]" * 100_000, "deep.json")
    # An integer literal beyond Python's int-conversion limit (a ValueError from json.loads).
    text = sign(mutated(files["polynomial"], setter("training.n", 12345)))
    with pytest.raises(DataFormatError, match="not valid JSON"):
        loads_model(text.replace("12345", "9" * 5000))
    # An integer too large for a float in a numeric field (re-signed after the edit).
    d = mutated(files["polynomial"], setter("models.0.coefficients.0", 7**500))
    with pytest.raises(
        DataFormatError, match=r"models\[0\]\.coefficients\[0\]: number 354013\d+… is out of range"
    ):
        loads_model(sign(d))
    with pytest.raises(DataFormatError, match="expected a JSON object at the top level"):
        loads_model("[1, 2]")


def test_load_model_reads_a_bounded_number_of_bytes(files, tmp_path, monkeypatch) -> None:
    if os.path.exists("/dev/zero"):
        with pytest.raises(InputError, match="size limit"):
            load_model("/dev/zero")
    import uasnav.thermal.modelfile as mf

    p = tmp_path / "m.json"
    p.write_text(sign(files["polynomial"]))
    monkeypatch.setattr(mf, "MAX_MODEL_BYTES", 100)
    with pytest.raises(InputError, match=f"{p}: larger than the size limit of 100 bytes"):
        load_model(p)


def test_cli_refuses_a_hostile_model_in_one_line(files, tmp_path) -> None:
    from uasnav.cli import main

    p = tmp_path / "m.json"
    p.write_text(sign(mutated(files["polynomial"], setter("calibrated_range_c", "27..34"))))
    log = ImuLog(t=np.arange(50.0), gyro=np.zeros((50, 3)), accel=np.zeros((50, 3)), temp=np.full(50, 20.0))
    write_log(log, tmp_path / "s.csv")
    r = CliRunner().invoke(main, ["calibrate", "--model", str(p), "--test", str(tmp_path / "s.csv")])
    assert r.exit_code == 1, r.output
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "calibrated_range_c" in lines[0]
    assert "Traceback" not in r.output


# -- thermal training inputs -----------------------------------------------------------------


@pytest.mark.parametrize(
    "fit",
    [
        lambda t, b: PolynomialBiasModel(2).fit(t, b),
        lambda t, b: Px4BiasModel().fit(t, b),
        lambda t, b: NeuralBiasModel(2).fit(t, b),
        lambda t, b: fit_hysteresis(t, b, np.arange(t.size) < t.size // 2),
        lambda t, b: select_polynomial_order(t, b),
        lambda t, b: select_hidden_neurons(t, b),
    ],
    ids=["poly", "px4", "neural", "hysteresis", "select-order", "select-neurons"],
)
def test_training_inputs_are_checked(fit) -> None:
    t, b = np.linspace(27.0, 34.0, 60), np.zeros((60, 3))
    t_hot = t.copy()
    t_hot[5] = 1e308
    with pytest.raises(
        InputError, match=r"temp: 1e\+308 °C at row 5 is outside the physical range \[-100, 200\]"
    ):
        fit(t_hot, b)
    t_cold = t.copy()
    t_cold[7] = -300.0
    with pytest.raises(InputError, match=r"-300 °C at row 7"):
        fit(t_cold, b)
    t_nan = t.copy()
    t_nan[3] = np.nan
    with pytest.raises(InputError, match="non-finite temperature at row 3"):
        fit(t_nan, b)
    b_big = b.copy()
    b_big[9, 1] = 1e308
    with pytest.raises(InputError, match=r"bias: 1e\+308 rad/s at row 9, column 1 exceeds ±100 rad/s"):
        fit(t, b_big)
    b_inf = b.copy()
    b_inf[2, 2] = -np.inf
    with pytest.raises(InputError, match="bias: non-finite value at row 2, column 2"):
        fit(t, b_inf)
    with pytest.raises(InputError, match="need at least"):
        fit(t[:2], b[:2])
    with pytest.raises(InputError, match=r"expected shape \(60, k\)"):
        fit(t, np.zeros((60, 0)))


def test_training_log_with_an_absurd_temperature_names_the_log_row(tmp_path) -> None:
    n = 200
    temp = np.linspace(27.0, 34.0, n)
    temp[120] = 1e308  # one corrupt row: without the check, a "valid" model over [27, 1e308] °C
    # written as text: ImuLog itself refuses such a temperature, so a file is the only way in
    rows = "".join(f"{i:.1f},0,0,0,0,0,0,{float(x)!r}\n" for i, x in enumerate(temp))
    (tmp_path / "ramp.csv").write_text("t,gx,gy,gz,ax,ay,az,temp\n" + rows)
    with pytest.raises(InputError, match=r"ramp\.csv: temp: 1e\+308 °C at row 120 is outside"):
        load_training_data(tmp_path / "ramp.csv", average_s=1.0)
    from uasnav.cli import main

    r = CliRunner().invoke(
        main, ["calibrate", str(tmp_path / "ramp.csv"), "--method", "poly", "--out", str(tmp_path / "m.json")]
    )
    assert r.exit_code == 1 and "1e+308 °C" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "m.json").exists()


# -- trajectory model files ------------------------------------------------------------------


def _samples(n: int = 60, seed: int = 0) -> ElementSamples:
    rng = np.random.default_rng(seed)
    theta = rng.choice([0.0, 45.0, 90.0], n)
    f = Features(
        theta_deg=theta,
        theta_w_deg=rng.choice([0.0, 90.0, 180.0], n),
        wind_ms=rng.uniform(2.0, 6.0, n),
        kind=np.where(theta == 0, 1, 0),
        mirrored=np.zeros(n, bool),
    )
    dv = -0.02 * theta + rng.normal(0, 0.1, n)
    return ElementSamples(
        features=f,
        length_m=np.full(n, 20.0),
        t_real_s=20.0 / (5.0 + dv),
        v_init_ms=np.full(n, 5.0),
        v_ref_ms=np.full(n, 5.0),
        dv_ms=dv,
        flight=np.zeros(n, int),
        element=np.arange(n),
    )


@pytest.fixture(scope="module")
def traj() -> dict[str, Any]:
    p = TrajectoryPredictor(n_prototypes=12, max_iter=300, random_state=0).fit(_samples())
    assert p.lvq_ is not None
    return p.to_dict()


def test_feature_width_matches_the_network_input() -> None:
    assert _samples(5).features.matrix().shape[1] == N_FEATURES


def _first(d: dict[str, Any], key: str) -> str:
    return next(iter(d[key]))


TRAJ_CASES = [
    (
        setter("params.segment_m", 1e-9),
        r"params\.segment_m: 1e-09 m is outside the accepted range \[1, 10000\] m",
    ),
    (setter("params.segment_m", 0.0), r"params\.segment_m: 0\.0 m is outside"),
    (setter("params.segment_m", -10.0), r"params\.segment_m: -10\.0 m is outside"),
    (setter("params.segment_m", NAN), r"params\.segment_m: expected a finite number, got NaN"),
    (setter("params.segment_m", "10"), r'params\.segment_m: expected a number, got the string "10"'),
    (setter("params.n_prototypes", 10**9), r"params\.n_prototypes: 1000000000 is outside the accepted range"),
    (setter("params.n_prototypes", 2.5), r"params\.n_prototypes: expected an integer, got 2\.5"),
    (setter("params.target", "speed"), r'params\.target: expected one of "cell", "dv", got "speed"'),
    (setter("params.dv_bin_ms", -0.1), r"params\.dv_bin_ms: expected a number > 0"),
    (setter("params.bogus", 1), r"params\.bogus: unknown key"),
    (setter("params", [1]), r"params: expected an object, got an array"),
    (setter("lvq.prototypes.0.1", NAN), r"lvq\.prototypes\[0\]\[1\]: expected a finite number, got NaN"),
    (lambda d: [r.pop() for r in d["lvq"]["prototypes"]], r"lvq\.prototypes\[0\]: expected 5 numbers, got 4"),
    (setter("lvq.prototypes", [[[0.0]] * 5]), r"lvq\.prototypes\[0\]\[0\]: expected a number, got an array"),
    (setter("lvq.prototypes", []), r"lvq\.prototypes: empty array"),
    (setter("lvq.prototype_labels.0", 99), r"lvq\.prototype_labels\[0\]: 99 is outside the accepted range"),
    (setter("lvq.prototype_labels.0", -1), r"lvq\.prototype_labels\[0\]: -1 is outside"),
    (
        lambda d: d["lvq"]["prototype_labels"].pop(),
        r"lvq: prototype_labels: expected \d+ integers \(one per prototype\)",
    ),
    (setter("lvq.classes.0", "a"), r'lvq\.classes\[0\]: expected an integer, got the string "a"'),
    (lambda d: d["lvq"]["classes"].append(383), r"lvq\.classes: a class has no ΔV entry"),
    (
        lambda d: d["dv_table_ms"].update({_first(d, "dv_table_ms"): NAN}),
        r"dv_table_ms\.\d+: expected a finite number",
    ),
    (
        lambda d: d["dv_table_ms"].update({"999": 0.1}),
        r"dv_table_ms\.999: 999 is outside the accepted range \[0, 383\]",
    ),
    (lambda d: d["dv_table_ms"].update({"-1": 0.1}), r"dv_table_ms\.-1: -1 is outside the accepted range"),
    (lambda d: d["dv_table_ms"].update({"1e2": 0.1}), r"dv_table_ms\.1e2: key is not an integer"),
    (lambda d: d["dv_table_ms"].update({" 7": 0.1}), r"dv_table_ms\. 7: key is not an integer"),
    (
        lambda d: d["label_dv_ms"].update({_first(d, "label_dv_ms"): 1e308}),
        r"label_dv_ms\.\d+: 1e\+308 m/s is outside",
    ),
    (
        lambda d: d["label_dv_ms"].update({"400": 0.0}),
        r"label_dv_ms\.400: 400 is outside the accepted range \[0, 383\]",
    ),
    (lambda d: d["count_table"].pop(_first(d, "count_table")), r"count_table: cell \d+ is in only one of"),
    (lambda d: d["count_table"].update({_first(d, "count_table"): 0}), r"count_table\.\d+: 0 is outside"),
    (setter("n_train", 7), r"count_table: counts sum to 60, n_train is 7"),
    (setter("n_train", "60"), r'n_train: expected an integer, got the string "60"'),
    (setter("dv_table_ms", {}), r"dv_table_ms: empty"),
    (setter("cruise_ms", 0.0), r"cruise_ms: expected a number > 0"),
    (setter("cruise_ms", 1e308), r"cruise_ms: 1e\+308 is above the accepted maximum 150"),
    (setter("wind_range_ms", [6.0, 2.0]), r"wind_range_ms: minimum 6\.0 exceeds maximum 2\.0"),
    (setter("wind_range_ms", "2..6"), r"wind_range_ms: expected \[min, max\]"),
    (setter("dv_global_ms", NAN), r"dv_global_ms: expected a finite number"),
    (setter("single_cell", 3), r"lvq: a model holds exactly one of 'lvq' and 'single_cell'"),
    (remover("lvq"), r"lvq: a model holds exactly one of"),
    (setter("extra", 1), r"extra: unknown key"),
]


def test_trajectory_control_file_loads(traj, tmp_path) -> None:
    p = tmp_path / "m.json"
    p.write_text(json.dumps(traj))
    back = TrajectoryPredictor.load(p)
    assert back.to_dict() == traj


@pytest.mark.parametrize(("edit", "match"), TRAJ_CASES, ids=[m[:40] for _, m in TRAJ_CASES])
def test_hostile_trajectory_file_is_refused_naming_the_key(traj, tmp_path, edit, match) -> None:
    p = tmp_path / "m.json"
    p.write_text(json.dumps(mutated(traj, edit)))
    with pytest.raises(DataFormatError, match=match) as ei:
        TrajectoryPredictor.load(p)
    msg = str(ei.value)
    assert msg.startswith(f"{p}: ") and msg.count(str(p)) == 1


def test_trajectory_single_cell_and_dv_target_files(tmp_path) -> None:
    s = _samples()
    one = s.subset(s.features.theta_deg == 45.0)
    one = one.subset(np.isin(one.cell, one.cell[:1]))
    d = TrajectoryPredictor().fit(one).to_dict()
    assert "single_cell" in d and TrajectoryPredictor.from_dict(d).single_cell_ == d["single_cell"]
    with pytest.raises(DataFormatError, match=r"single_cell: 7 is not the one class"):
        TrajectoryPredictor.from_dict(mutated(d, setter("single_cell", 7)))
    dv = TrajectoryPredictor(target="dv", n_prototypes=12, max_iter=300).fit(s).to_dict()
    TrajectoryPredictor.from_dict(dv)  # ΔV-bin keys may be negative
    with pytest.raises(
        DataFormatError, match=r"label_dv_ms\.99999: 99999 is outside the accepted range \[-1500, 1500\]"
    ):
        TrajectoryPredictor.from_dict(mutated(dv, lambda x: x["label_dv_ms"].update({"99999": 0.0})))


def test_trajectory_pathological_files(tmp_path) -> None:
    p = tmp_path / "m.json"
    p.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(DataFormatError, match="nested deeper than 64"):
        TrajectoryPredictor.load(p)
    p.write_bytes(b"\xff\xfe{}")
    with pytest.raises(DataFormatError, match="not a UTF-8"):
        TrajectoryPredictor.load(p)
    if os.path.exists("/dev/zero"):
        with pytest.raises(InputError, match="size limit"):
            TrajectoryPredictor.load("/dev/zero")


def test_trajectory_training_inputs_are_checked(tmp_path) -> None:
    s = _samples()
    with pytest.raises(
        InputError, match=rf"segment_m: 1e-09 m is outside the accepted range \[{MIN_SEGMENT_M:g}"
    ):
        TrajectoryPredictor(segment_m=1e-9).fit(s)
    with pytest.raises(InputError, match="n_prototypes: expected an integer"):
        TrajectoryPredictor(n_prototypes=2.5).fit(s)  # type: ignore[arg-type]
    TrajectoryPredictor(n_prototypes=np.int64(12), max_iter=50).fit(s)  # NumPy integers are integers
    bad = _samples()
    bad.dv_ms[4] = 1e308
    with pytest.raises(InputError, match=r"training element 4: ΔV 1e\+308 m/s is outside \[-150, 150\] m/s"):
        TrajectoryPredictor().fit(bad)
    bad = _samples()
    bad.v_ref_ms[2] = 0.0
    with pytest.raises(InputError, match=r"training element 2: commanded speed 0 m/s is outside \(0, 150\]"):
        TrajectoryPredictor().fit(bad)
    # A fitted model with a NaN is never written (JSON has no NaN), and nothing is left behind.
    m = TrajectoryPredictor(n_prototypes=12, max_iter=50).fit(s)
    m.label_dv_[0] = np.nan
    with pytest.raises(InputError, match="non-finite"):
        m.save(tmp_path / "m.json")
    assert list(Path(tmp_path).iterdir()) == []


# -- thermal fit parameters that would ask for unbounded memory or time ------------------------


def test_binning_memory_is_bounded_by_the_samples() -> None:
    from uasnav.thermal import bin_by_temperature, bin_by_time

    t = np.arange(1000) * 0.01  # 10 s at 100 Hz
    temp, v = np.linspace(20.0, 30.0, t.size), np.ones((t.size, 3))
    # Blocks of 1e-12 s: 10¹³ block indices, but only 1000 non-empty blocks (each one sample).
    tm, vm = bin_by_time(t, temp, v, 1e-12)
    np.testing.assert_array_equal(tm, temp)
    assert vm.shape == (1000, 3)
    with pytest.raises(InputError, match="block length 1e-300 s is too short"):
        bin_by_time(t, temp, v, 1e-300)
    with pytest.raises(InputError, match="finite block length"):
        bin_by_time(t, temp, v, float("nan"))
    with pytest.raises(InputError, match=r"temperature bins of 1e-12 °C needs about"):
        bin_by_temperature(temp, v, 1e-12)
    with pytest.raises(InputError, match="non-finite temperature"):
        bin_by_temperature(np.r_[temp[:-1], np.inf], v, 1.0)


@pytest.mark.parametrize(
    ("model", "match"),
    [
        (lambda: Px4BiasModel(bin_c=1e-12), r"temperature bins of 1e-12 °C needs about"),
        (lambda: Px4BiasModel(bin_c=0.0), r"bin_c: expected a bin width > 0 °C"),
        (lambda: Px4BiasModel(bin_c=float("nan")), r"bin_c: expected a bin width > 0 °C"),
        (lambda: Px4BiasModel(median_window=2.5), r"median_window: expected an integer"),
        (lambda: NeuralBiasModel(2, restarts=10**9), r"restarts: expected an integer in 1…100"),
        (lambda: NeuralBiasModel(2, max_epochs=0), r"max_epochs: expected an integer in 1…100000"),
        (lambda: NeuralBiasModel(2, max_samples=0), r"max_samples: expected an integer in 20…"),
        (lambda: NeuralBiasModel(2, derivative_bin_c=0.0), r"derivative_bin_c: expected a bin width > 0"),
        (lambda: NeuralBiasModel(2, engine="gpu"), r"engine: expected 'rust' or 'numpy'"),
        (lambda: PolynomialBiasModel(21), r"order: expected an integer in 0…20"),
    ],
)
def test_fit_parameters_are_checked_before_work(model, match) -> None:
    with pytest.raises(InputError, match=match):
        model().fit(T, B)
