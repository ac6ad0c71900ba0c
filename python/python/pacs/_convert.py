"""JSON text of the JSON-like arguments pacs accepts (dicts, lists, numpy arrays, paths)."""

import json
import math
import os

from .errors import InputError


def _default(value):
    if hasattr(value, "tolist"):  # numpy arrays and scalars
        return value.tolist()
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    raise TypeError(f"{type(value).__name__} is not JSON-like")


def _check_finite(value, path):
    if isinstance(value, float) and not math.isfinite(value):
        raise InputError(f"{path}: value {value} is not finite")
    if isinstance(value, dict):
        for k, v in value.items():
            _check_finite(v, f"{path}.{k}")
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            _check_finite(v, f"{path}[{i}]")
    elif hasattr(value, "tolist"):
        _check_finite(value.tolist(), path)


def to_json(value, name="value") -> str:
    """``json.dumps`` with numpy values and paths converted; a NaN/inf raises
    :class:`pacs.InputError` naming its path (``config.safety_step``)."""
    _check_finite(value, name)
    return json.dumps(value, default=_default)
