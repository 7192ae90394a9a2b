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
"""

from __future__ import annotations

import hashlib
import json
import os
from datetime import datetime, timezone
from typing import Any

import numpy as np

from uasnav.atomicfile import atomic_write_text
from uasnav.errors import DataFormatError

FORMAT = "uasnav.thermal-model"
SCHEMA_VERSION = 1
UNITS = {"input": "degC", "output": "rad/s", "derivative": "rad/s/degC"}
AXES = ("x", "y", "z")


ZEROS = "0" * 64


def file_checksum(text: str, value: str) -> str:
    """SHA-256 hex of ``text`` with the one occurrence of ``value`` replaced by 64 zeros."""
    return hashlib.sha256(text.replace(value, ZEROS, 1).encode("utf-8")).hexdigest()


def _plain(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_plain(v) for v in x]
    if isinstance(x, np.ndarray):
        return _plain(x.tolist())
    if isinstance(x, np.generic):
        return x.item()
    return x


def model_payload(model: Any, training: dict[str, Any] | None = None) -> dict[str, Any]:
    """The file's content (with checksum) as a dict."""
    body = model.to_dict()
    k = len(body["models"])
    payload: dict[str, Any] = {
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
    payload = _plain(payload)
    payload["checksum"] = {"algorithm": "sha256", "value": ZEROS}
    return payload


def dumps_model(model: Any, training: dict[str, Any] | None = None) -> str:
    """The model file text (checksum filled in)."""
    try:
        text = json.dumps(model_payload(model, training), indent=1, allow_nan=False) + "\n"
    except ValueError as e:
        raise DataFormatError(f"model holds non-finite numbers and cannot be saved: {e}") from e
    return text.replace(ZEROS, file_checksum(text, ZEROS), 1)


def save_model(model: Any, path: str | os.PathLike[str], training: dict[str, Any] | None = None) -> None:
    """Write ``model`` (fitted) to ``path`` atomically."""
    atomic_write_text(path, dumps_model(model, training))


def loads_model(text: str, source: str = "<string>") -> Any:
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
    from uasnav.thermal.neural import NeuralBiasModel
    from uasnav.thermal.polynomial import PolynomialBiasModel
    from uasnav.thermal.px4 import Px4BiasModel

    kinds: dict[str, Any] = {
        "polynomial": PolynomialBiasModel,
        "neural": NeuralBiasModel,
        "px4": Px4BiasModel,
    }
    cls = kinds.get(str(d.get("kind")))
    if cls is None:
        raise DataFormatError(f"{source}: unknown model kind {d.get('kind')!r}", path=source)
    try:
        rng = d["calibrated_range_c"]
        model = cls.from_dict(d, (float(rng[0]), float(rng[1])))
    except (KeyError, IndexError, TypeError, ValueError) as e:
        raise DataFormatError(
            f"{source}: malformed {d.get('kind')} model ({type(e).__name__}: {e})", path=source
        ) from e
    model.training_meta_ = d.get("training", {})
    return model


def load_model(path: str | os.PathLike[str]) -> Any:
    """Load a model file written by :func:`save_model` (any kind)."""
    p = os.fspath(path)
    try:
        with open(p, encoding="utf-8") as fh:
            text = fh.read()
    except UnicodeDecodeError as e:
        raise DataFormatError(f"{p}: not a UTF-8 text file", path=p) from e
    return loads_model(text, p)
