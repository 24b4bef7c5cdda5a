"""Small per-call maths in plain numpy (never numba; twins in :mod:`hexapod_kin._kmath`).

Angle wrapping, the chain's length scale and the damped-least-squares step. [rad], [m].
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["chain_length", "chain_scale", "dls_step", "dls_step3", "wrap_angles"]

_TWO_PI = 2.0 * math.pi
_dot = np.dot


def wrap_angles(a: Any) -> np.ndarray:
    """Wrap angles (any shape) to (−π, π] in [rad]; returns a new float array."""
    out = np.remainder(np.asarray(a, dtype=np.float64) + np.pi, _TWO_PI) - np.pi
    out = np.asarray(out)
    out[out == -np.pi] = np.pi
    return out


def chain_length(trans: Any) -> float:
    """``Σ‖tᵢ‖`` [m] of (m, 3) offsets (``Model.arrays.trans``): bounds the base-to-tip distance."""
    t = np.asarray(trans, dtype=np.float64).reshape(-1, 3)
    return float(np.sum(np.sqrt(np.sum(t * t, axis=1))))


def chain_scale(trans: Any) -> float:
    """The chain's length scale in [m] for tolerances: :func:`chain_length`, or 1.0 if zero."""
    s = chain_length(trans)
    return s if s > 0.0 else 1.0


def dls_step(jac: np.ndarray, error: Any, lam2: float, free: Any = None) -> np.ndarray:
    """The damped-least-squares step ``Δq = Jfᵀ(Jf Jfᵀ + λ²I)⁻¹ e`` (twin of ``_kmath.dls_into``).

    The smaller system (``(JfᵀJf + λ²I)⁻¹ Jfᵀ e`` when n ≤ m), by Cholesky (Eigen's LLT);
    ``Jf``: ``jac`` (m, n) with the columns of frozen joints (``free``: (n,) False or 0) zeroed;
    ``error`` (m,) in the task's units, ``lam2`` ``λ² ≥ 0`` in those squared. A stack (..., m, n)
    of tasks (n ≤ m) at once (``np.linalg.solve``). Zeros when not positive definite.
    """
    jf = jac if free is None else jac * np.asarray(free, dtype=float)
    e = np.asarray(error, dtype=float)
    if jf.ndim > 2:
        jt = np.swapaxes(jf, -1, -2)
        return np.linalg.solve(jt @ jf + lam2 * np.eye(jf.shape[-1]), jt @ e[..., None])[..., 0]
    m, n = jf.shape
    jt, k = jf.T, (n if n <= m else m)
    held = _HELD[0]  # (λ², λ² I) of the last call: an RK4 step's stages share it
    if held[0] != lam2 or len(held[1]) != k:
        held = _HELD[0] = (lam2, lam2 * np.eye(k))
    import eigenpy  # Eigen's small dense decompositions (Pinocchio's own), here: on first use

    llt = eigenpy.LLT(_dot(jt, jf) + held[1] if n <= m else _dot(jf, jt) + held[1])
    if llt.info() != eigenpy.ComputationInfo.Success:  # not SPD
        return np.zeros(n)
    x = llt.solve(_dot(jt, e) if n <= m else e).reshape(k)  # eigenpy: (1, 1) when k = 1
    return x if n <= m else _dot(jt, x)


#: ``(λ², λ² I)`` of :func:`dls_step`'s last call (never written; replaced whole).
_HELD: list[tuple[float, np.ndarray]] = [(math.nan, np.zeros((0, 0)))]


def dls_step3(j: list[list[float]], x: list[float], lam2: float) -> list[float] | None:
    """:func:`dls_step` of a 3×3 ``J`` on floats (``dls_into``'s Cholesky); None: not SPD."""
    (a, b, c), (d, e, f), (g, h, i) = j
    x0, x1, x2 = x
    r0, r1, r2 = a * x0 + d * x1 + g * x2, b * x0 + e * x1 + h * x2, c * x0 + f * x1 + i * x2
    w00 = a * a + d * d + g * g + lam2
    w10, w20 = b * a + e * d + h * g, c * a + f * d + i * g
    w11 = b * b + e * e + h * h + lam2
    w21 = c * b + f * e + i * h
    w22 = c * c + f * f + i * i + lam2
    if not w00 > 0.0:
        return None
    l00 = math.sqrt(w00)
    l10, l20 = w10 / l00, w20 / l00
    s = w11 - l10 * l10
    if not s > 0.0:
        return None
    l11 = math.sqrt(s)
    l21 = (w21 - l20 * l10) / l11
    s = w22 - l20 * l20 - l21 * l21
    if not s > 0.0:
        return None
    l22 = math.sqrt(s)
    y0 = r0 / l00
    y1 = (r1 - l10 * y0) / l11
    z2 = (r2 - l20 * y0 - l21 * y1) / l22 / l22
    z1 = (y1 - l21 * z2) / l11
    return [(y0 - l10 * z1 - l20 * z2) / l00, z1, z2]
