"""The one thermal-model file format (JSON), read by Python and by Rust
(``nav_core::mlp::json``).

Layout (schema version 1)::

    {"format": "uasnav.thermal-model", "schema_version": 1,
     "kind": "polynomial" | "neural" | "px4",
     "quantity": "gyro_bias", "axes": ["x", "y", "z"],
     "units": {"input": "degC", "output": "rad/s", "derivative": "rad/s/degC"},
     "calibrated_range_c": [min, max],
     "models": [... one per axis, kind-specific ...],
     "derivative_models": [...] | null,          # neural only (thesis eq. 37)
     "training": {... free-form metadata ...},
     "checksum": {"algorithm": "sha256", "value": "<hex>"}}

The checksum is the SHA-256 of the file's bytes with its own hex value replaced by 64 ``0``
characters, so Python and Rust (``nav_core::mlp::json``) verify it byte-exactly without
re-serialising; any edit or truncation is detected on load. Files are written atomically.

The reader rebuilds the model with the class registered for the file's ``"kind"``
(:func:`uasnav.thermal.base.register_model`); it imports no concrete model.

Loading validates fully, after the checksum: every field's type, shape, finiteness and range
(:mod:`uasnav.jsoncheck`; the calibrated range within the physical −100…200 °C, scales > 0,
one model per named axis), each error naming its JSON path (``models[1].coefficients[0]``);
then the model is evaluated once over its calibrated range and must give finite biases within
±100 rad/s. At most :data:`MAX_MODEL_BYTES` are read.
"""

from __future__ import annotations

import hashlib
import json
import os
from datetime import datetime, timezone

import numpy as np

from uasnav import jsoncheck as jc
from uasnav.atomicfile import atomic_write_text
from uasnav.errors import DataFormatError, InputError
from uasnav.jsonable import to_jsonable
from uasnav.thermal._common import BIAS_MAX_RADS, TEMP_MAX_C, TEMP_MIN_C
from uasnav.thermal.base import BiasModel, ModelDict, model_class

FORMAT = "uasnav.thermal-model"
SCHEMA_VERSION = 1
UNITS = {"input": "degC", "output": "rad/s", "derivative": "rad/s/degC"}
AXES = ("x", "y", "z")


ZEROS = "0" * 64


def file_checksum(text: str, value: str) -> str:
    """SHA-256 hex of ``text`` with the one occurrence of ``value`` replaced by 64 zeros."""
    return hashlib.sha256(text.replace(value, ZEROS, 1).encode("utf-8")).hexdigest()


def _finite(x: object) -> bool:
    """True if every number in the nested dicts / lists / arrays ``x`` is finite."""
    if isinstance(x, dict):
        return all(_finite(v) for v in x.values())
    if isinstance(x, list | tuple):
        return all(_finite(v) for v in x)
    if isinstance(x, np.ndarray | np.generic | float):
        return bool(np.all(np.isfinite(x)))
    return True


def model_payload(model: BiasModel, training: ModelDict | None = None) -> ModelDict:
    """The file's content (with checksum) as a dict.

    Raises :class:`DataFormatError` if the model's numbers are not all finite: JSON has no NaN,
    and :func:`uasnav.jsonable.to_jsonable` would turn them into ``null`` (an unloadable model).
    """
    body = model.to_dict()
    if not _finite(body):
        raise DataFormatError(f"{model.kind} model holds non-finite numbers and cannot be saved")
    k = len(body["models"])
    payload: ModelDict = {
        "format": FORMAT,
        "schema_version": SCHEMA_VERSION,
        "kind": model.kind,
        "quantity": "gyro_bias",
        "axes": list(AXES[:k]) if k <= 3 else [str(i) for i in range(k)],
        "units": dict(UNITS),
        "calibrated_range_c": [float(model.range_c_[0]), float(model.range_c_[1])],
        "models": body["models"],
        "derivative_models": body.get("derivative_models"),
        "training": {
            "created_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
            **(training or {}),
        },
    }
    recs = getattr(model, "training_", None)
    if recs:
        payload["training"].setdefault("networks", [{**r.__dict__} for r in recs])
    payload = to_jsonable(payload)
    payload["checksum"] = {"algorithm": "sha256", "value": ZEROS}
    return payload


def dumps_model(model: BiasModel, training: ModelDict | None = None) -> str:
    """The model file text (checksum filled in)."""
    # model_payload refuses non-finite model numbers; allow_nan=False guards the rest.
    text = json.dumps(model_payload(model, training), indent=1, allow_nan=False) + "\n"
    return text.replace(ZEROS, file_checksum(text, ZEROS), 1)


def save_model(model: BiasModel, path: str | os.PathLike[str], training: ModelDict | None = None) -> None:
    """Write ``model`` (fitted) to ``path`` atomically."""
    atomic_write_text(path, dumps_model(model, training))


#: Largest model file read (bytes). Ours are a few kB (a 16-neuron, 3-axis network with its
#: derivative networks and training records is < 100 kB); the bound keeps ``--model /dev/zero``
#: or a mistaken multi-GB file from exhausting memory.
MAX_MODEL_BYTES = 16 * 2**20
#: Most axes a model file may hold (a gyro has 3; :func:`model_payload` names more by index).
MAX_AXES = 64
#: Temperatures (°C) over the calibrated range at which a loaded model is evaluated once: every
#: value must be finite and within ±BIAS_MAX_RADS, so coefficients that overflow (a scale of
#: 1e-300, a coefficient of 1e300) are refused at load, not turned into NaN later.
_PROBE_POINTS = 257
_TOP_KEYS = (
    "format", "schema_version", "kind", "quantity", "axes", "units", "calibrated_range_c",
    "models", "derivative_models", "training", "checksum",
)  # fmt: skip


def _check_header(text: str) -> tuple[ModelDict, type[BiasModel], tuple[float, float]]:
    """The parsed file with its checksum verified and its kind-independent part checked.

    Order matters: format and checksum first (a file that is not ours, or edited, is refused
    as such), then every field; errors name the JSON path (no file: the caller adds it).
    """
    d = jc.parse(text)
    if not isinstance(d, dict):
        raise DataFormatError("expected a JSON object at the top level")
    if d.get("format") != FORMAT:
        raise jc.fail("format", f"{jc.show(d.get('format'))}, expected {jc.show(FORMAT)}")
    sv = d.get("schema_version")
    if isinstance(sv, bool) or sv != SCHEMA_VERSION or not isinstance(sv, int):
        raise DataFormatError(
            f"schema_version {jc.show(sv)} is not supported (this version reads {SCHEMA_VERSION})"
        )
    ck = d.pop("checksum", None)
    if not isinstance(ck, dict) or ck.get("algorithm") != "sha256":
        raise jc.fail("checksum", "missing or unknown checksum")
    value = ck.get("value")
    if not (
        isinstance(value, str)
        and len(value) == 64
        and all(c in "0123456789abcdefABCDEF" for c in value)
        and text.count(value) == 1
    ):
        raise jc.fail("checksum", "checksum value is not a unique 64-digit hex string")
    digest = file_checksum(text, value)
    if digest != value:
        raise jc.fail(
            "checksum", f"checksum mismatch (file edited or corrupted): expected {value}, got {digest}"
        )
    jc.only(d, _TOP_KEYS)
    kind = jc.string(jc.field(d, "kind"), "kind")
    try:
        cls = model_class(kind)
    except InputError:
        raise jc.fail("kind", f"unknown model kind {kind!r}") from None
    jc.string(jc.field(d, "quantity"), "quantity", ("gyro_bias",))
    if d.get("units") != UNITS:
        raise jc.fail("units", f"{jc.show(d.get('units'), 120)}, expected {jc.show(UNITS, 120)}")
    rng = jc.interval(
        jc.field(d, "calibrated_range_c"), "calibrated_range_c", lo=TEMP_MIN_C, hi=TEMP_MAX_C, unit="°C"
    )
    k = len(jc.array(jc.field(d, "models"), "models", max_len=MAX_AXES))
    axes = jc.array(jc.field(d, "axes"), "axes", max_len=MAX_AXES)
    names = [jc.string(a, jc.at("axes", i)) for i, a in enumerate(axes)]
    if len(names) != k:
        raise jc.fail("axes", f"{len(names)} axes named but {k} models given (one model per axis)")
    if len(set(names)) != k:
        raise jc.fail("axes", f"axis names repeat: {jc.show(names)}")
    dm = d.get("derivative_models")
    if dm is not None and len(jc.array(dm, "derivative_models", max_len=MAX_AXES)) != k:
        raise jc.fail("derivative_models", f"{len(dm)} networks for {k} axes (one per axis, or null)")
    jc.obj(d.get("training", {}), "training")
    return d, cls, rng


def _probe(model: BiasModel, rng: tuple[float, float]) -> None:
    """Evaluate ``model`` once over its calibrated range: values finite and within
    ±:data:`BIAS_MAX_RADS`, derivatives finite (else :class:`DataFormatError`)."""
    t = np.linspace(rng[0], rng[1], _PROBE_POINTS)
    with np.errstate(all="ignore"):
        b = model.predict(t)
        db = model.derivative(t)
    for what, v, limit in (("bias", b, BIAS_MAX_RADS), ("bias derivative", db, np.inf)):
        bad = np.argwhere(~(np.abs(v) <= limit))  # also catches NaN
        if bad.size:
            i, j = int(bad[0][0]), int(bad[0][1])
            x = v[i, j]
            shown = f"{x:g} rad/s, beyond ±{limit:g} rad/s" if np.isfinite(x) else "non-finite"
            raise jc.fail(f"models[{j}]", f"the model's {what} at {t[i]:g} °C is {shown}")


def loads_model(text: str, source: str = "<string>") -> BiasModel:
    """Parse model file text, validated fully: format, schema version, checksum, then every
    field's type, shape, finiteness and range (each error names its JSON path, e.g.
    ``models[1].layers[0].weights[3][0]``), and the model evaluated once over its calibrated
    range. Raises :class:`DataFormatError` naming ``source``."""
    with jc.reraise_in(source):
        d, cls, rng = _check_header(text)
        try:
            model = cls.from_dict(d, rng)
        except DataFormatError:
            raise
        except (KeyError, IndexError, TypeError, ValueError) as e:
            # Every kind validates its own part; this is the safety net for a kind that does not.
            raise DataFormatError(f"malformed {d.get('kind')} model ({type(e).__name__}: {e})") from None
        _probe(model, rng)
    # The file's free-form training metadata, kept for the user (not part of BiasModel).
    model.training_meta_ = d.get("training", {})  # type: ignore[attr-defined]
    return model


def load_model(path: str | os.PathLike[str]) -> BiasModel:
    """Load a model file written by :func:`save_model` (any kind); at most
    :data:`MAX_MODEL_BYTES` are read."""
    p = os.fspath(path)
    return loads_model(jc.read_text(p, MAX_MODEL_BYTES), p)
