"""Leg solutions finished on the table itself (:func:`finish_on_table`).

A leg whose twists are within ``angle_tol`` of the closed-form pattern (``α2 = ±π/2``,
``α3 ∈ {0, π}``; e.g. a URDF's rounded constants) is first solved by the exact pattern's
closed form (:mod:`hexapod_kin.ik.closed`); each solution is then finished by damped Newton
steps ``Δq = (JᵀJ + λI)⁻¹ Jᵀ (x − p(q))`` on the table's own forward kinematics (numpy,
vectorised over all solutions; ``J = [z_j × (p − o_j)]``). From a start ``O(deviation)``
away, the steps converge quadratically (≤ 12 steps; they stop when a step is below 1e-15).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._numerics import wrap_angles
from ..params import Chain

__all__ = ["finish_on_table", "fit_angles"]

_TWO_PI = 2.0 * math.pi


def fit_angles(v: np.ndarray, lo: Any, hi: Any) -> tuple[np.ndarray, np.ndarray]:
    """Angles shifted by ±2π into [lo, hi] where that helps; (angles, inside)."""
    v = np.where((v < lo) & (v + _TWO_PI <= hi), v + _TWO_PI, v)
    v = np.where((v > hi) & (v - _TWO_PI >= lo), v - _TWO_PI, v)
    return v, (v >= lo) & (v <= hi)


def _khalil_many(alpha: float, d: float, theta: np.ndarray, r: float) -> np.ndarray:
    """(M, 4, 4) ``Rx(α)·Tx(d)·Rz(θ)·Tz(r)`` for an array of θ (see ``khalil_transform``)."""
    ca, sa = math.cos(alpha), math.sin(alpha)
    ct, st = np.cos(theta), np.sin(theta)
    t = np.zeros((len(theta), 4, 4))
    t[:, 0, 0], t[:, 0, 1], t[:, 0, 3] = ct, -st, d
    t[:, 1, 0], t[:, 1, 1], t[:, 1, 2], t[:, 1, 3] = ca * st, ca * ct, -sa, -r * sa
    t[:, 2, 0], t[:, 2, 1], t[:, 2, 2], t[:, 2, 3] = sa * st, sa * ct, ca, r * ca
    t[:, 3, 3] = 1.0
    return t


def _leg_fk(ch: Chain, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Foot (M, 3) and ∂foot/∂q (M, 3, n) of the table itself, in the mount frame."""
    n = q.shape[1]
    rows = ch.rows
    t = np.eye(4)
    for row in rows[n:]:
        t = t @ row.transform()
    foot = (t @ ch.tool_matrix)[:3, 3]
    acc = np.broadcast_to(np.eye(4), (len(q), 4, 4))
    axes, origins = [], []
    for j in range(n):
        row = rows[j]
        alpha, d = (0.0, 0.0) if j == 0 else (row.alpha, row.d)  # α1, d1: in the mount
        acc = acc @ _khalil_many(alpha, d, row.theta + q[:, j], row.r)
        axes.append(acc[:, :3, 2])
        origins.append(acc[:, :3, 3])
    p = acc[:, :3, :3] @ foot + acc[:, :3, 3]
    jac = np.stack([np.cross(z, p - o) for z, o in zip(axes, origins)], axis=2)
    return p, jac


def finish_on_table(
    ch: Chain,
    x: np.ndarray,
    q: np.ndarray,
    valid: np.ndarray,
    tol_abs: float,
    scale: float,
    limits: tuple[np.ndarray, np.ndarray] | None,
) -> tuple[np.ndarray, np.ndarray]:
    """Finish leg solutions with Newton steps on the table's own forward kinematics.

    Args:
        ch: The leg's chain (its joint rows first; α1 and d1 are taken as in the mount).
        x: (N, 3) targets [m] in the mount frame.
        q: (N, K, n) starting solutions (the exact pattern's closed form; NaN = none).
        valid: (N, K) the slots to finish.
        tol_abs: A slot stays valid when its foot ends within this distance [m] of the
            target (2 DOF: the target's distance to the table's surface, Gauss–Newton).
        scale: The chain's length scale [m] (damping ``1e-12 · scale²`` keeps steps finite).
        limits: Optional (lower, upper) (n,): slots outside (after ±2π shifts) are invalid.

    Returns:
        ``(q, valid)`` as :func:`~hexapod_kin.ik.leg_solutions` returns them.

    """
    n_t, k, n = q.shape
    q = q.copy()
    idx = np.argwhere(valid)
    if len(idx):
        qa = q[idx[:, 0], idx[:, 1]]
        xa = x[idx[:, 0], :3]
        damp = 1e-12 * scale**2 * np.eye(n)
        for _ in range(12):
            p, jac = _leg_fk(ch, qa)
            res = xa - p
            jt = np.swapaxes(jac, 1, 2)
            step = np.linalg.solve(jt @ jac + damp, (jt @ res[:, :, None]))[:, :, 0]
            qa = qa + step
            if float(np.abs(step).max()) < 1e-15:
                break
        p, _ = _leg_fk(ch, qa)
        miss = np.linalg.norm(xa - p, axis=1)
        qa = wrap_angles(qa)
        ok = miss <= max(tol_abs, 1e-12 * scale)
        if limits is not None:
            lo, hi = limits[0] - 1e-12, limits[1] + 1e-12
            for j in range(n):
                qa[:, j], inside = fit_angles(qa[:, j], lo[j], hi[j])
                ok &= inside
        q[idx[:, 0], idx[:, 1]] = qa
        valid = valid.copy()
        valid[idx[:, 0], idx[:, 1]] = ok
    q[~valid] = np.nan
    return q, valid
