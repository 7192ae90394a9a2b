"""Plain-JSON conversion of numpy results: one rule for the whole package.

Every JSON that uasnav writes (``--json`` output, ``report.json``, thermal model files) goes
through :func:`to_jsonable`. JSON has no NaN or infinity, so a non-finite float becomes
``null``: the reader sees "no value", never an invalid document or a silent number.

>>> import numpy as np
>>> to_jsonable({"a": np.array([1.0, np.nan]), "b": (np.int64(2), float("inf"))})
{'a': [1.0, None], 'b': [2, None]}
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

_PLAIN = (str, int, bool, type(None))


def to_jsonable(obj: Any) -> Any:
    """Convert numpy scalars/arrays (recursively) to plain JSON types; non-finite → None.

    Dict keys become strings; tuples and lists become lists.
    """
    if type(obj) in _PLAIN:  # the common leaves first: this runs over every value of a document
        return obj
    if type(obj) is float:
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        return to_jsonable(obj.item())
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


__all__ = ["to_jsonable"]
