"""Small per-call maths in plain numpy (never imports numba).

One home each: angle wrapping (:func:`wrap_angles`), the chain's length scale
(:func:`chain_length` / :func:`chain_scale`, ONE formula) and the damped-least-squares step
(:func:`dls_step`, the per-call IK and the resolved-rate law). The compiled counterparts used
inside kernels (``wrap_angle``, ``dls_into``, eigenvalues, determinants...)
live in :mod:`hexapod_kin._kmath`, re-exported by :mod:`hexapod_kin._kernels`.

Angles in [rad], lengths in [m].
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["chain_length", "chain_scale", "dls_step", "wrap_angles"]

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


def dls_step(jac: np.ndarray, error: Any, lam2: float, free: Any = None) -> np.ndarray:
    """One damped-least-squares step ``Δq = Jfᵀ(Jf Jfᵀ + λ²I)⁻¹ e`` (pure function).

    The smaller system is solved: ``(JfᵀJf + λ²I)⁻¹ Jfᵀ e`` when n ≤ m, else
    ``Jfᵀ(JfJfᵀ + λ²I)⁻¹ e`` (the same Δq). ``Jf`` is ``jac`` with the columns of frozen
    joints (``free`` False or 0) zeroed, so they get Δq = 0.

    Args:
        jac: Task Jacobian (m, n).
        error: Task error or velocity (m,), in the task's units.
        lam2: Damping ``λ² ≥ 0`` in the task's units squared.
        free: Optional (n,) booleans or 0/1 weights of the joints.

    Returns:
        Δq (n,); zeros when the system is singular (``λ² = 0`` at a singularity).

    """
    jf = jac if free is None else jac * np.asarray(free, dtype=float)
    m, n = jf.shape
    e = np.asarray(error, dtype=float)
    try:
        if n <= m:
            return np.linalg.solve(jf.T @ jf + lam2 * np.eye(n), jf.T @ e)
        return jf.T @ np.linalg.solve(jf @ jf.T + lam2 * np.eye(m), e)
    except np.linalg.LinAlgError:
        return np.zeros(n)
