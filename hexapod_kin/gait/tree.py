"""Vectorised kinematics of a floating-base tree and the numerical leg IK (numpy only).

* **Tree kinematics** (any revolute axis, RX/RY/RZ or unaligned, and prismatic joints): joint
  ``j``'s frame is ``parent · P_j · M_j(q_j)`` with ``P_j`` its placement at q = 0
  (Pinocchio's ``jointPlacements``) and ``M_j`` the rotation
  ``R(a, q) = cos q I + sin q [a]× + (1 − cos q) a aᵀ`` (Rodrigues) or the translation ``a q``
  along its unit axis ``a``. Raw Pinocchio FK is the reference in the tests.
* **Numerical leg IK** (:func:`solve_legs`), used where no closed form recognises the leg:
  damped least squares on the leg's own joints, vectorised over samples and legs, with the
  analytic position Jacobian ``J_k = w_k × (p − o_k)`` (revolute; ``w_k`` for prismatic)::

      Δq = (JᵀJ + λ²I)⁻¹ Jᵀ e,   λ² = 10⁻² ‖e‖² + 10⁻¹⁴ s²   (s: the leg's span)

  each step scaled to at most 0.5 rad and clipped to the joint limits, until
  ``‖e‖ ≤ 10⁻¹³ s`` or the step stalls. All samples start from the seed; a sample whose
  solution is far from its predecessor's (a branch jump, > 0.5 rad) or not reached is solved
  again warm-started from the previous sample. A foot is *reached* when the residual is at
  most :data:`REACH_TOL`; otherwise the residual is the distance of the best reachable point
  found to the target (the leg's ``excess``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["REACH_TOL", "Tree", "axis_rotation", "leg_fk", "solve_legs", "tree_poses"]

#: A foot is reached when the numerical IK residual is at most this [m].
REACH_TOL = 1e-10


# ============================================================================ the tree
@dataclass(frozen=True)
class Tree:
    """The actuated joints of a floating-base tree as arrays (joint order = Pinocchio's q).

    Attributes:
        parents: (n,) index of each joint's parent joint (−1: the floating body).
        placements: (n, 4, 4) joint placements in the parent joint's frame at q = 0.
        axes: (n, 3) unit joint axes in the joint's own frame.
        prismatic: (n,) True for prismatic joints.

    """

    parents: np.ndarray
    placements: np.ndarray
    axes: np.ndarray
    prismatic: np.ndarray


def axis_rotation(axes: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Rotations (..., 3, 3) about unit ``axes`` (..., 3) by ``q`` (...) [rad] (Rodrigues)."""
    c, s = np.cos(q), np.sin(q)
    x, y, z = axes[..., 0], axes[..., 1], axes[..., 2]
    v = 1.0 - c
    R = np.empty(np.shape(q) + (3, 3))
    R[..., 0, 0] = c + v * x * x
    R[..., 0, 1] = v * x * y - s * z
    R[..., 0, 2] = v * x * z + s * y
    R[..., 1, 0] = v * x * y + s * z
    R[..., 1, 1] = c + v * y * y
    R[..., 1, 2] = v * y * z - s * x
    R[..., 2, 0] = v * x * z - s * y
    R[..., 2, 1] = v * y * z + s * x
    R[..., 2, 2] = c + v * z * z
    return R


def _local(P: np.ndarray, axis: np.ndarray, prismatic: Any, q: np.ndarray) -> np.ndarray:
    """``P · M(q)`` (N, 4, 4) for one joint (placement P (..., 4, 4), axis (..., 3))."""
    n = q.shape[0]
    out = np.empty((n, 4, 4))
    out[:, 3] = (0.0, 0.0, 0.0, 1.0)
    Pr = P[..., :3, :3]
    if np.ndim(prismatic) == 0 and not prismatic:
        out[:, :3, :3] = Pr @ axis_rotation(np.broadcast_to(axis, (n, 3)), q)
        out[:, :3, 3] = P[..., :3, 3]
        return out
    pr = np.broadcast_to(np.asarray(prismatic, dtype=bool), (n,))
    rot = axis_rotation(np.broadcast_to(axis, (n, 3)), np.where(pr, 0.0, q))
    out[:, :3, :3] = Pr @ rot
    shift = np.where(pr[:, None], np.broadcast_to(axis, (n, 3)) * q[:, None], 0.0)
    out[:, :3, 3] = P[..., :3, 3] + (Pr @ shift[..., None])[..., 0]
    return out


def tree_poses(tree: Tree, q: np.ndarray, base: np.ndarray) -> np.ndarray:
    """World poses (N, n, 4, 4) of the joints' frames at joints ``q`` (N, n), bodies ``base``."""
    n, nj = q.shape
    out = np.empty((n, nj, 4, 4))
    for j in range(nj):
        local = _local(tree.placements[j], tree.axes[j], bool(tree.prismatic[j]), q[:, j])
        par = int(tree.parents[j])
        out[:, j] = (base if par < 0 else out[:, par]) @ local
    return out


def leg_fk(
    placements: np.ndarray, axes: np.ndarray, prismatic: np.ndarray, foot: np.ndarray, q: Any
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Body-frame kinematics of E leg instances (one serial chain each, m joints).

    Args:
        placements: (E, m, 4, 4) each joint's placement in the previous joint's frame (the
            first in the body frame).
        axes: (E, m, 3) unit axes.
        prismatic: (E, m) True for prismatic joints.
        foot: (E, 3) the foot in the last joint's frame.
        q: (E, m) joint values.

    Returns:
        ``(origins, world_axes, feet)``: (E, m, 3) joint origins, (E, m, 3) joint axes in the
        body frame, (E, 3) feet.

    """
    q = np.asarray(q, dtype=float)
    e, m = q.shape
    T = np.broadcast_to(np.eye(4), (e, 4, 4))
    origins = np.empty((e, m, 3))
    waxes = np.empty((e, m, 3))
    any_p = bool(np.any(prismatic))
    for k in range(m):
        T = T @ placements[:, k]
        origins[:, k] = T[:, :3, 3]
        waxes[:, k] = (T[:, :3, :3] @ axes[:, k, :, None])[..., 0]
        R = axis_rotation(axes[:, k], np.where(prismatic[:, k], 0.0, q[:, k]) if any_p else q[:, k])
        Tn = np.empty((e, 4, 4))
        Tn[:, :3, :3] = T[:, :3, :3] @ R
        Tn[:, :3, 3] = T[:, :3, 3]
        if any_p:
            Tn[:, :3, 3] += np.where(prismatic[:, k, None], waxes[:, k] * q[:, k, None], 0.0)
        Tn[:, 3] = (0.0, 0.0, 0.0, 1.0)
        T = Tn
    feet = (T[:, :3, :3] @ foot[..., None])[..., 0] + T[:, :3, 3]
    return origins, waxes, feet


# ============================================================================ numerical IK
def solve_legs(
    placements: np.ndarray,
    axes: np.ndarray,
    prismatic: np.ndarray,
    foot: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    targets: np.ndarray,
    seed: np.ndarray,
    *,
    span: float,
    iterations: int = 60,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Damped least squares for G legs of m joints at N samples (see the module doc).

    Args:
        placements: (G, m, 4, 4) the legs' joint placements (see :func:`leg_fk`).
        axes: (G, m, 3) unit joint axes.
        prismatic: (G, m) True for prismatic joints.
        foot: (G, 3) the feet in their last joint's frame.
        lower: (G, m) lower joint limits.
        upper: (G, m) upper joint limits.
        targets: (N, G, 3) body-frame foot targets [m].
        seed: (G, m) the joints before the first sample.
        span: The legs' length scale [m] (tolerances).
        iterations: Cap on the steps per solve.

    Returns:
        ``(q, residual, reached)``: (N, G, m), (N, G) [m], (N, G).

    """
    n, g, _ = targets.shape
    m = placements.shape[1]
    q = np.broadcast_to(seed, (n, g, m)).reshape(n * g, m).copy()
    gi = np.tile(np.arange(g), n)
    tgt = targets.reshape(n * g, 3)
    res = _dls(placements, axes, prismatic, foot, lower, upper, tgt, q, gi, span, iterations)
    q = q.reshape(n, g, m)
    res = res.reshape(n, g)
    # continuity: re-solve, warm-started from the previous sample, where a branch jumped
    prev = np.asarray(seed, dtype=float)
    for i in range(n):
        jump = np.abs(q[i] - prev).max(axis=1) > 0.5
        bad = jump | (res[i] > REACH_TOL)
        if bad.any():
            idx = np.flatnonzero(bad)
            qi = prev[idx].copy()
            ri = _dls(
                placements, axes, prismatic, foot, lower, upper,
                targets[i, idx], qi, idx, span, iterations,
            )  # fmt: skip
            better = (ri <= np.maximum(res[i, idx], REACH_TOL)) | (ri <= REACH_TOL)
            q[i, idx] = np.where(better[:, None], qi, q[i, idx])
            res[i, idx] = np.where(better, ri, res[i, idx])
        prev = q[i]
    return q, res, res <= REACH_TOL


def _dls(
    placements: np.ndarray,
    axes: np.ndarray,
    prismatic: np.ndarray,
    foot: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    tgt: np.ndarray,
    q: np.ndarray,
    gi: np.ndarray,
    span: float,
    iterations: int,
) -> np.ndarray:
    """Iterate DLS in place on ``q`` (E, m) for leg indices ``gi`` (E,); residuals (E,)."""
    e_n, m = q.shape
    res = np.full(e_n, np.inf)
    active = np.arange(e_n)
    lam_floor = 1e-14 * span * span
    done_tol = 1e-13 * span
    eye = np.eye(m)
    for _ in range(iterations):
        g = gi[active]
        o, w, p = leg_fk(placements[g], axes[g], prismatic[g], foot[g], q[active])
        err = tgt[active] - p
        norm = np.linalg.norm(err, axis=1)
        res[active] = norm
        keep = norm > done_tol
        if not keep.any():
            break
        active, g, o, w, p, err, norm = (
            a[keep] for a in (active, g, o, w, p, err, norm)
        )  # fmt: skip
        J = np.where(prismatic[g][:, None, :], np.swapaxes(w, 1, 2), 0.0)
        rev = np.cross(w, p[:, None, :] - o)  # (E, m, 3)
        J = np.where(prismatic[g][:, None, :], J, np.swapaxes(rev, 1, 2))  # (E, 3, m)
        Jt = np.swapaxes(J, 1, 2)
        lam2 = 1e-2 * norm * norm + lam_floor
        A = Jt @ J + lam2[:, None, None] * eye
        dq = np.linalg.solve(A, (Jt @ err[..., None]))[..., 0]
        big = np.abs(dq).max(axis=1)
        dq *= np.minimum(1.0, 0.5 / np.maximum(big, 1e-300))[:, None]
        new = np.clip(q[active] + dq, lower[g], upper[g])
        moved = np.abs(new - q[active]).max(axis=1) > 1e-15
        q[active] = new
        active = active[moved]
        if active.size == 0:
            break
    if active.size:  # the last step's residual
        g = gi[active]
        _o, _w, p = leg_fk(placements[g], axes[g], prismatic[g], foot[g], q[active])
        res[active] = np.linalg.norm(tgt[active] - p, axis=1)
    return res
