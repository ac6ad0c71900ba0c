"""JSON text of the JSON-like arguments pacs accepts (dicts, lists, numpy arrays, paths)."""

import json
import os


def _default(value):
    if hasattr(value, "tolist"):  # numpy arrays and scalars
        return value.tolist()
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    raise TypeError(f"{type(value).__name__} is not JSON-like")


def to_json(value) -> str:
    """``json.dumps`` with numpy values and paths converted; NaN/inf refused."""
    return json.dumps(value, default=_default, allow_nan=False)
