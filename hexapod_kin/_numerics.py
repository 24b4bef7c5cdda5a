"""Small per-call maths in plain numpy (never imports numba).

One home each: angle wrapping (:func:`wrap_angles`, :func:`wrap_diff`), the chain's length
scale (:func:`chain_length` / :func:`chain_scale`, ONE formula) and the damped-least-squares
step as a pure function (:func:`dls_step`). The compiled counterparts used inside kernels
(``wrap_angle``, ``dls_into``, ``sigma_bounds``, eigenvalues, determinants...) live in
:mod:`hexapod_kin._kernels`, the one compiled layer.

Angles in [rad], lengths in [m].
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .exceptions import ConfigurationError

__all__ = ["chain_length", "chain_scale", "dls_step", "wrap_angles", "wrap_diff"]

_TWO_PI = 2.0 * math.pi


def dls_step(jac: Any, error: Any, damping: float, free: Any = None) -> np.ndarray:
    """One damped-least-squares step ``Δq = Jᵀ(JJᵀ + λ²I)⁻¹ e`` (pure function).

    The smaller system is solved: ``(JᵀJ + λ²I)⁻¹ Jᵀ e`` when n ≤ m, else
    ``Jᵀ (JJᵀ + λ²I)⁻¹ e`` (the same Δq), by Cholesky.

    Args:
        jac: Task Jacobian (m, n): position rows in [m/rad] (or [m/m]), rotation rows in
            [rad/rad].
        error: Task error (m,) (``target − current``) in the task's units.
        damping: ``λ² ≥ 0`` in the task's units squared.
        free: Optional (n,) booleans; joints marked False are frozen (Δq = 0).

    Returns:
        Δq (n,) in [rad]/[m].

    Raises:
        ConfigurationError: If the shapes disagree, the values are not finite, ``damping`` is
            negative, or ``damping = 0`` at a singular Jacobian (no unique step).

    """
    j = np.asarray(jac, dtype=np.float64)
    e = np.asarray(error, dtype=np.float64)
    if j.ndim != 2 or e.shape != (j.shape[0],):
        raise ConfigurationError(
            f"dls_step: jac {j.shape} and error {e.shape} disagree; (m, n) and (m,) are needed",
            parameter="error",
            value=e.shape,
            allowed=f"shape ({j.shape[0] if j.ndim == 2 else 'm'},)",
        )
    lam2 = float(damping)
    if not (math.isfinite(lam2) and lam2 >= 0.0):
        raise ConfigurationError(
            f"dls_step: damping={damping!r}; a finite λ² ≥ 0 is needed",
            parameter="damping",
            value=damping,
            allowed="finite, >= 0",
        )
    if not (np.all(np.isfinite(j)) and np.all(np.isfinite(e))):
        raise ConfigurationError(
            "dls_step: jac or error has non-finite values",
            parameter="jac",
            value="non-finite",
            allowed="finite numbers",
        )
    m, n = j.shape
    fr = np.ones(n, dtype=np.bool_) if free is None else np.asarray(free, dtype=np.bool_)
    if fr.shape != (n,):
        raise ConfigurationError(
            f"dls_step: free has shape {fr.shape}; ({n},) booleans are needed",
            parameter="free",
            value=fr.shape,
            allowed=f"shape ({n},)",
        )
    jf = j * fr
    try:
        if n <= m:
            low = np.linalg.cholesky(jf.T @ jf + lam2 * np.eye(n))
            dq = np.linalg.solve(low.T, np.linalg.solve(low, jf.T @ e))
        else:
            low = np.linalg.cholesky(jf @ jf.T + lam2 * np.eye(m))
            dq = jf.T @ np.linalg.solve(low.T, np.linalg.solve(low, e))
    except np.linalg.LinAlgError:
        dq = None
    if dq is None or not np.all(np.isfinite(dq)):
        raise ConfigurationError(
            "dls_step: the Jacobian is singular and damping=0; use damping > 0",
            parameter="damping",
            value=damping,
            allowed="> 0 at a singular Jacobian",
        )
    dq[~fr] = 0.0
    return dq


def wrap_angles(a: Any) -> np.ndarray:
    """Wrap angles (any shape) to (−π, π] in [rad]; returns a new float array."""
    out = np.remainder(np.asarray(a, dtype=np.float64) + np.pi, _TWO_PI) - np.pi
    out = np.asarray(out)
    out[out == -np.pi] = np.pi
    return out


def wrap_diff(a: Any, b: Any) -> np.ndarray:
    """Shortest signed angle ``a − b`` in (−π, π] [rad] (elementwise)."""
    return wrap_angles(np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64))


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
