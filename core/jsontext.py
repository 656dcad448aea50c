"""JSON text of EASE's values (:func:`dumps_json`): numpy arrays and numbers, paths; NaN refused."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np


def _json_default(obj):
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (np.floating,)):
        return float(obj)
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def dumps_json(obj, indent: int | None = 1) -> str:
    """``json.dumps`` of ``obj`` with numpy values and paths as JSON values; NaN and infinities
    raise ValueError (a file with them is not JSON)."""
    return json.dumps(obj, indent=indent, default=_json_default, allow_nan=False)
