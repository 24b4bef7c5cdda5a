"""JSON-ready dictionaries of the result dataclasses' fields."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["fields_dict"]


def fields_dict(obj: Any, *names: str) -> dict[str, Any]:
    """``{name: getattr(obj, name)}`` in order: arrays as nested lists, tuples as lists."""
    out: dict[str, Any] = {}
    for name in names:
        v = getattr(obj, name)
        if isinstance(v, np.ndarray):
            v = v.tolist()
        elif isinstance(v, tuple):
            v = list(v)
        out[name] = v
    return out
