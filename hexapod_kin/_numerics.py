"""Small per-call maths in plain numpy (never imports numba).

One home each: angle wrapping (:func:`wrap_angles`) and the chain's length scale
(:func:`chain_length` / :func:`chain_scale`, ONE formula). The compiled counterparts used
inside kernels (``wrap_angle``, ``dls_into``, eigenvalues, determinants...)
live in :mod:`hexapod_kin._kmath`, re-exported by :mod:`hexapod_kin._kernels`.

Angles in [rad], lengths in [m].
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["chain_length", "chain_scale", "wrap_angles"]

_TWO_PI = 2.0 * math.pi


def wrap_angles(a: Any) -> np.ndarray:
    """Wrap angles (any shape) to (−π, π] in [rad]; returns a new float array."""
    out = np.remainder(np.asarray(a, dtype=np.float64) + np.pi, _TWO_PI) - np.pi
    out = np.asarray(out)
    out[out == -np.pi] = np.pi
    return out


def chain_length(trans: Any) -> float:
    """Sum of the link offsets' lengths ``Σ‖tᵢ‖`` in [m] of an (m, 3) translation array.

    An upper bound of the base-to-tip distance (rows are the joint placements and the tip
    offset, e.g. ``Model.arrays.trans``; a Khalil row contributes ``‖(d, 0, r)‖``).
    """
    t = np.asarray(trans, dtype=np.float64).reshape(-1, 3)
    return float(np.sum(np.sqrt(np.sum(t * t, axis=1))))


def chain_scale(trans: Any) -> float:
    """The chain's length scale in [m] for tolerances: :func:`chain_length`, or 1.0 if zero.

    Args:
        trans: (m, 3) link translations in [m].

    Returns:
        ``Σ‖tᵢ‖`` if positive, else 1.0.

    """
    s = chain_length(trans)
    return s if s > 0.0 else 1.0
