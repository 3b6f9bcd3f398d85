"""JSON output of results: strict JSON, NaN and infinities become ``null``.

Every JSON and JSON-lines file vgs writes (run metadata, summaries, journals, checkpoint
metadata, exported policy descriptions) and the JSON it prints go through :func:`dumps`, so a
strict parser (one that refuses the bare ``NaN``/``Infinity`` of Python's default) reads them.
"""

from __future__ import annotations

import json
import math
from typing import Any


def json_safe(value: Any) -> Any:
    """A copy of nested dicts/lists/tuples with non-finite floats replaced by None and NumPy
    scalars made Python numbers."""
    if type(value).__module__ == "numpy" and getattr(value, "shape", None) == ():
        value = value.item()  # a NumPy scalar (numpy is not imported here)
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(v) for v in value]
    return value


def dumps(value: Any, **kwargs: Any) -> str:
    """``json.dumps`` of :func:`json_safe` ``(value)`` with ``allow_nan=False``: strict JSON.

    Keyword arguments go to :func:`json.dumps` (``indent`` ...)."""
    return json.dumps(json_safe(value), allow_nan=False, **kwargs)
