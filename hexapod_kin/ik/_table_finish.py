"""Leg solutions finished on the table itself (:func:`finish_on_table`).

A leg whose twists are within ``angle_tol`` of the closed-form pattern (``α2 = ±π/2``,
``α3 ∈ {0, π}``; e.g. a URDF's rounded constants) is first solved by the exact pattern's
closed form (:mod:`hexapod_kin.ik.closed`); each solution is then finished by damped Newton
steps ``Δq = (JᵀJ + λI)⁻¹ Jᵀ (x − p(q))`` on the table's own forward kinematics (numpy,
vectorised over all solutions; ``J = [z_j × (p − o_j)]``). From a start ``O(deviation)``
away, the steps converge quadratically (≤ 12 steps; a solution stops moving once its step is
below 1e-14 rad).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._numerics import dls_step, wrap_angles
from ..params import Chain

__all__ = ["finish_on_table", "fit_angles"]

_TWO_PI = 2.0 * math.pi


def fit_angles(v: np.ndarray, lo: Any, hi: Any) -> tuple[np.ndarray, np.ndarray]:
    """Angles shifted by ±2π into [lo, hi] where that helps; (angles, inside)."""
    v = np.where((v < lo) & (v + _TWO_PI <= hi), v + _TWO_PI, v)
    v = np.where((v > hi) & (v - _TWO_PI >= lo), v - _TWO_PI, v)
    return v, (v >= lo) & (v <= hi)


def _leg_fk(ch: Chain, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Foot (M, 3) and ∂foot/∂q (M, 3, n) of the table itself, in the mount frame.

    The rows ``Rx(α)·Tx(d)·Rz(θ + q)·Tz(r)`` are applied to the frame's columns
    ``(x, y, z)`` and origin ``p`` as (M, 3) arrays (row 1's α1, d1 are in the mount).
    """
    n, m = q.shape[1], len(q)
    rows = ch.rows
    t = np.eye(4)
    for row in rows[n:]:
        t = t @ row.transform()
    foot = (t @ ch.tool_matrix)[:3, 3]
    eye = np.eye(3)
    cx, cy, cz = (np.broadcast_to(eye[k], (m, 3)) for k in range(3))
    p = np.zeros((m, 3))
    axes, origins = [], []
    for j in range(n):
        row = rows[j]
        if j > 0:
            ca, sa = math.cos(row.alpha), math.sin(row.alpha)
            p = p + row.d * cx
            cy, cz = ca * cy + sa * cz, ca * cz - sa * cy
        phi = row.theta + q[:, j]
        c, s = np.cos(phi)[:, None], np.sin(phi)[:, None]
        cx, cy = c * cx + s * cy, c * cy - s * cx
        if row.r:
            p = p + row.r * cz
        axes.append(cz)
        origins.append(p)
    tip = p + foot[0] * cx + foot[1] * cy + foot[2] * cz
    jac = np.empty((m, 3, n))
    for j, (z, o) in enumerate(zip(axes, origins)):
        v = tip - o  # z × v, by components (np.cross is slow on (M, 3))
        jac[:, 0, j] = z[:, 1] * v[:, 2] - z[:, 2] * v[:, 1]
        jac[:, 1, j] = z[:, 2] * v[:, 0] - z[:, 0] * v[:, 2]
        jac[:, 2, j] = z[:, 0] * v[:, 1] - z[:, 1] * v[:, 0]
    return tip, jac


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
        damp = 1e-12 * scale**2
        act = np.arange(len(qa))  # the slots still moving
        for _ in range(12):
            p, jac = _leg_fk(ch, qa[act])
            res = xa[act] - p
            step = dls_step(jac, res, damp)
            qa[act] += step
            act = act[np.abs(step).max(axis=1) >= 1e-14]
            if not len(act):
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
