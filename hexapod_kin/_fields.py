"""Helpers of the result dataclasses: JSON-ready field dictionaries, read-only arrays."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["fields_dict", "read_only"]


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


def read_only(*arrays: np.ndarray) -> None:
    """Mark arrays read-only (results handed to users are protected)."""
    for a in arrays:
        a.setflags(write=False)
