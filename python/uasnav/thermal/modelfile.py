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
"""

from __future__ import annotations

import hashlib
import json
import os
from datetime import datetime, timezone

import numpy as np

from uasnav.atomicfile import atomic_write_text
from uasnav.errors import DataFormatError, InputError
from uasnav.jsonable import to_jsonable
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


def loads_model(text: str, source: str = "<string>") -> BiasModel:
    """Parse model file text; verifies format, schema version, units and checksum."""
    try:
        d = json.loads(text)
    except json.JSONDecodeError as e:
        raise DataFormatError(
            f"{source}: not valid JSON ({e.msg})", path=source, line=e.lineno, column=str(e.colno)
        ) from e
    if not isinstance(d, dict):
        raise DataFormatError(f"{source}: expected a JSON object at the top level", path=source)
    if d.get("format") != FORMAT:
        raise DataFormatError(f"{source}: format is {d.get('format')!r}, expected {FORMAT!r}", path=source)
    if d.get("schema_version") != SCHEMA_VERSION:
        raise DataFormatError(
            f"{source}: schema_version {d.get('schema_version')!r} is not supported (this version reads "
            f"{SCHEMA_VERSION})",
            path=source,
        )
    ck = d.pop("checksum", None)
    if not isinstance(ck, dict) or ck.get("algorithm") != "sha256":
        raise DataFormatError(f"{source}: missing or unknown checksum", path=source)
    value = ck.get("value")
    if not (isinstance(value, str) and len(value) == 64 and text.count(value) == 1):
        raise DataFormatError(f"{source}: checksum value is not a unique 64-digit hex string", path=source)
    digest = file_checksum(text, value)
    if digest != value:
        raise DataFormatError(
            f"{source}: checksum mismatch (file edited or corrupted): expected {value}, got {digest}",
            path=source,
        )
    if d.get("units") != UNITS:
        raise DataFormatError(f"{source}: units {d.get('units')!r}, expected {UNITS!r}", path=source)
    try:
        cls = model_class(str(d.get("kind")))
    except InputError:
        raise DataFormatError(f"{source}: unknown model kind {d.get('kind')!r}", path=source) from None
    try:
        rng = d["calibrated_range_c"]
        model = cls.from_dict(d, (float(rng[0]), float(rng[1])))
    except (KeyError, IndexError, TypeError, ValueError) as e:
        raise DataFormatError(
            f"{source}: malformed {d.get('kind')} model ({type(e).__name__}: {e})", path=source
        ) from e
    # The file's free-form training metadata, kept for the user (not part of BiasModel).
    model.training_meta_ = d.get("training", {})  # type: ignore[attr-defined]
    return model


def load_model(path: str | os.PathLike[str]) -> BiasModel:
    """Load a model file written by :func:`save_model` (any kind)."""
    p = os.fspath(path)
    try:
        with open(p, encoding="utf-8") as fh:
            text = fh.read()
    except UnicodeDecodeError as e:
        raise DataFormatError(f"{p}: not a UTF-8 text file", path=p) from e
    return loads_model(text, p)
