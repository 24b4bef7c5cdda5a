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

from dataclasses import dataclass, fields
from functools import cached_property
from typing import Any

import numpy as np

__all__ = [
    "REACH_TOL",
    "Tree",
    "axis_rotation",
    "leg_fk",
    "poses_of",
    "solve_legs",
    "tree_frames",
    "tree_poses",
]

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

    @cached_property
    def levels(self) -> tuple[tuple[np.ndarray, np.ndarray | None], ...]:
        """The joints by depth: per level ``(joints, their parents)`` (parents ``None``: the body).

        Pinocchio numbers a parent before its children, so one pass gives every depth.
        """
        par = np.asarray(self.parents)
        depth = np.zeros(len(par), dtype=int)
        for j, p in enumerate(par):
            depth[j] = 0 if p < 0 else depth[p] + 1
        out = []
        for d in range(int(depth.max()) + 1 if len(par) else 0):
            idx = np.flatnonzero(depth == d)
            out.append((idx, None if d == 0 else par[idx]))
        return tuple(out)

    @cached_property
    def groups(self) -> tuple[tuple[np.ndarray, np.ndarray | None, int, np.ndarray], ...]:
        """:attr:`levels` split by axis: ``(joints, parents, k, sign)``.

        ``k`` = 0, 1, 2 for revolute joints about ``±x, ±y, ±z`` of their frame (``sign``
        (n_g, 1): ±1), 3 for the others (unaligned axes, prismatic joints).
        """
        a = np.asarray(self.axes, dtype=float)
        pr = np.asarray(self.prismatic, dtype=bool)
        kind = np.full(len(a), 3)
        for k in range(3):
            kind[(np.abs(a[:, k]) == 1.0) & ~pr] = k
        out = []
        for idx, par in self.levels:
            for k in range(4):
                sel = kind[idx] == k
                if sel.any():
                    sub = idx[sel]
                    sign = np.where(a[sub, min(k, 2)] < 0, -1.0, 1.0)[:, None]
                    out.append((sub, None if par is None else par[sel], k, sign))
        return tuple(out)

    @cached_property
    def soa_terms(self) -> tuple[np.ndarray, ...]:
        """:attr:`local_terms` components first, for :func:`tree_frames`: (3, 3, n, 1), (3, n, 1).

        The third matrix is ``(P_R a) aᵀ − P_R`` (so ``M = P_R + sin q K1 + (1 − cos q) K2``).
        """
        Pr, Pt, K1, K2, Pa = self.local_terms
        mat = [np.ascontiguousarray(x.transpose(1, 2, 0)[..., None]) for x in (Pr, K1, K2 - Pr)]
        vec = [np.ascontiguousarray(x.T[..., None]) for x in (Pt, Pa)]
        return mat[0], vec[0], mat[1], mat[2], vec[1]

    @cached_property
    def local_terms(self) -> tuple[np.ndarray, ...]:
        """``(P_R, P_t, P_R[a]×, (P_R a) aᵀ, P_R a)`` per joint (n, 3, 3) / (n, 3).

        With ``P`` the placement (rotation ``P_R``, translation ``P_t``) and ``a`` the axis:
        ``P_R R(a, q) = cos q P_R + sin q P_R[a]× + (1 − cos q)(P_R a) aᵀ`` (Rodrigues), and a
        prismatic joint's frame is at ``P_t + (P_R a) q``.
        """
        Pr = np.ascontiguousarray(self.placements[:, :3, :3])
        a = np.asarray(self.axes, dtype=float)
        skew = np.zeros(a.shape + (3,))
        skew[:, 0, 1], skew[:, 0, 2] = -a[:, 2], a[:, 1]
        skew[:, 1, 0], skew[:, 1, 2] = a[:, 2], -a[:, 0]
        skew[:, 2, 0], skew[:, 2, 1] = -a[:, 1], a[:, 0]
        Pa = np.einsum("nij,nj->ni", Pr, a)
        return (
            Pr,
            np.ascontiguousarray(self.placements[:, :3, 3]),
            Pr @ skew,
            Pa[:, :, None] * a[:, None, :],
            Pa,
        )


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


def tree_frames(tree: Tree, q: np.ndarray, base: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The joints' world frames, components first: rotations (3, 3, n, N), origins (3, n, N).

    Args:
        tree: The tree.
        q: (N, n) joint values.
        base: (N, 4, 4) body poses.

    One product per depth of the tree and axis kind (:attr:`Tree.groups`): for a joint about
    ``±x, ±y, ±z`` the parent's rotation times the placement, then two columns mixed by
    ``cos q, ±sin q``; other joints by Rodrigues (:attr:`Tree.soa_terms`). The samples are
    the last (contiguous) axis, so every step is a long vector operation.

    """
    qt = np.ascontiguousarray(np.asarray(q, dtype=float).T)  # (n, N)
    nj, n = qt.shape
    Pr, Pt, K1, K2, Pa = tree.soa_terms
    R = np.empty((3, 3, nj, n))
    p = np.empty((3, nj, n))
    Rb = np.ascontiguousarray(base[:, :3, :3].transpose(1, 2, 0))[:, :, None, :]
    pb = np.ascontiguousarray(base[:, :3, 3].T)[:, None, :]
    for idx, par, k, sign in tree.groups:
        Rp, pp = (Rb, pb) if par is None else (R[:, :, par], p[:, par])
        qi = qt[idx]
        if k < 3:  # X = R_parent P_R, then X R_k(±q) mixes two columns
            P = Pr[:, :, idx]
            X = Rp[:, 0, None] * P[None, 0] + Rp[:, 1, None] * P[None, 1]
            X += Rp[:, 2, None] * P[None, 2]
            c, s_ = np.cos(qi), np.sin(qi) * sign
            u, v = (k + 1) % 3, (k + 2) % 3
            R[:, k, idx] = X[:, k]
            R[:, u, idx] = c * X[:, u] + s_ * X[:, v]
            R[:, v, idx] = c * X[:, v] - s_ * X[:, u]
            ti = Pt[:, idx]
        else:  # P_R R(a, q) = P_R + sin q P_R[a]× + (1 − cos q)((P_R a) aᵀ − P_R)
            pris = np.asarray(tree.prismatic, dtype=bool)[idx][:, None]
            qr = np.where(pris, 0.0, qi)
            Mi = np.sin(qr) * K1[:, :, idx]
            Mi += (1.0 - np.cos(qr)) * K2[:, :, idx]
            Mi += Pr[:, :, idx]
            R[:, :, idx] = Rp[:, 0, None] * Mi[None, 0] + Rp[:, 1, None] * Mi[None, 1]
            R[:, :, idx] += Rp[:, 2, None] * Mi[None, 2]
            ti = Pt[:, idx] + np.where(pris, Pa[:, idx] * qi, 0.0)
        p[:, idx] = Rp[:, 0] * ti[0] + Rp[:, 1] * ti[1] + Rp[:, 2] * ti[2] + pp
    return R, p


def poses_of(R: np.ndarray, p: np.ndarray) -> np.ndarray:
    """(N, n, 4, 4) homogeneous poses from :func:`tree_frames`' (3, 3, n, N) and (3, n, N)."""
    out = np.empty((R.shape[-1], R.shape[2], 4, 4))
    out[..., :3, :3] = R.transpose(3, 2, 0, 1)
    out[..., :3, 3] = p.transpose(2, 1, 0)
    out[..., 3, :3] = 0.0
    out[..., 3, 3] = 1.0
    return out


def tree_poses(tree: Tree, q: np.ndarray, base: np.ndarray) -> np.ndarray:
    """World poses (N, n, 4, 4) of the joints' frames at joints ``q`` (N, n), bodies ``base``."""
    return poses_of(*tree_frames(tree, q, base))


def _mv(A: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Stacked 3×3 matrix times 3-vector (..., 3) (broadcast sums: faster than matmul here)."""
    return np.asarray(
        A[..., :, 0] * v[..., 0, None]
        + A[..., :, 1] * v[..., 1, None]
        + A[..., :, 2] * v[..., 2, None]
    )


@dataclass(frozen=True)
class LegConsts:
    """Per-leg constants of G serial legs of m joints, for :func:`leg_fk_of`.

    With ``P`` the placement rotation and ``a`` the axis: ``P R(a, q) = c P + s P[a]× +
    (1 − c) (P a) aᵀ``, so each joint costs one 3×3 product per sample.
    """

    Pr: np.ndarray  # (G, m, 3, 3)
    Pt: np.ndarray  # (G, m, 3)
    K1: np.ndarray  # (G, m, 3, 3) P [a]×
    K2: np.ndarray  # (G, m, 3, 3) (P a) aᵀ
    Pa: np.ndarray  # (G, m, 3)
    prismatic: np.ndarray  # (G, m)
    foot: np.ndarray  # (G, 3)

    @classmethod
    def of(
        cls, placements: np.ndarray, axes: np.ndarray, prismatic: np.ndarray, foot: np.ndarray
    ) -> LegConsts:
        """From (G, m, 4, 4) placements, (G, m, 3) axes, (G, m) flags and (G, 3) feet."""
        Pr = np.ascontiguousarray(placements[..., :3, :3])
        a = np.asarray(axes, dtype=float)
        skew = np.zeros(a.shape + (3,))
        skew[..., 0, 1], skew[..., 0, 2] = -a[..., 2], a[..., 1]
        skew[..., 1, 0], skew[..., 1, 2] = a[..., 2], -a[..., 0]
        skew[..., 2, 0], skew[..., 2, 1] = -a[..., 1], a[..., 0]
        Pa = _mv(Pr, a)
        return cls(
            Pr,
            np.ascontiguousarray(placements[..., :3, 3]),
            Pr @ skew,
            Pa[..., :, None] * a[..., None, :],
            Pa,
            np.asarray(prismatic, dtype=bool),
            np.asarray(foot, dtype=float),
        )


def _subset(c: LegConsts, idx: np.ndarray) -> LegConsts:
    return LegConsts(*(getattr(c, f.name)[idx] for f in fields(LegConsts)))


def leg_fk_of(c: LegConsts, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`leg_fk` of the G legs of ``c`` at ``q`` (..., G, m) (constants broadcast)."""
    m = q.shape[-1]
    shape = q.shape[:-1]
    origins = np.empty(shape + (m, 3))
    waxes = np.empty(shape + (m, 3))
    any_p = bool(c.prismatic.any())
    R: np.ndarray | None = None
    t = np.zeros(shape + (3,))
    for k in range(m):
        qk = q[..., k]
        pk = c.prismatic[:, k]
        qr = np.where(pk, 0.0, qk) if any_p else qk
        co, si = np.cos(qr)[..., None, None], np.sin(qr)[..., None, None]
        M = co * c.Pr[:, k] + si * c.K1[:, k] + (1.0 - co) * c.K2[:, k]
        if R is None:
            o = np.broadcast_to(c.Pt[:, k], shape + (3,))
            w = np.broadcast_to(c.Pa[:, k], shape + (3,))
            R = M
        else:
            o = t + _mv(R, c.Pt[:, k])
            w = _mv(R, c.Pa[:, k])
            R = R @ M
        origins[..., k, :] = o
        waxes[..., k, :] = w
        t = o + np.where(pk[:, None], w * qk[..., None], 0.0) if any_p else o
    assert R is not None
    feet = t + _mv(R, c.foot)
    return origins, waxes, feet


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
    return leg_fk_of(LegConsts.of(placements, axes, prismatic, foot), q)


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
    c = LegConsts.of(placements, axes, prismatic, foot)
    seed_arr = np.asarray(seed, dtype=float)
    q = np.broadcast_to(seed_arr, (n, g, m)).copy()
    res = _dls(c, lower, upper, targets, q, span, iterations)
    # continuity: re-solve, warm-started from the previous sample, where a branch jumped
    # (or the foot was missed); only those samples are visited, in time order

    def suspects(start: int) -> np.ndarray:
        prev = np.concatenate([seed_arr[None], q[:-1]])[start:]
        jump = np.abs(q[start:] - prev).max(axis=2) > 0.5
        return np.flatnonzero((jump | (res[start:] > REACH_TOL)).any(axis=1)) + start

    todo = suspects(0)
    while todo.size:
        i = int(todo[0])
        prev = seed_arr if i == 0 else q[i - 1]
        jump = np.abs(q[i] - prev).max(axis=1) > 0.5
        idx = np.flatnonzero(jump | (res[i] > REACH_TOL))
        if idx.size:
            qi = prev[idx][None].copy()
            sub = _subset(c, idx)
            ri = _dls(sub, lower[idx], upper[idx], targets[i, idx][None], qi, span, iterations)[0]
            better = (ri <= np.maximum(res[i, idx], REACH_TOL)) | (ri <= REACH_TOL)
            q[i, idx] = np.where(better[:, None], qi[0], q[i, idx])
            res[i, idx] = np.where(better, ri, res[i, idx])
        todo = suspects(i + 1) if i + 1 < n else todo[:0]
    return q, res, res <= REACH_TOL


def _fk_soa(c: LegConsts, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`leg_fk_of` components first: q (m, G, N) → (3, m, G, N) ×2 and feet (3, G, N)."""
    m = q.shape[0]
    origins = np.empty((3,) + q.shape)
    waxes = np.empty((3,) + q.shape)
    any_p = bool(c.prismatic.any())
    R: np.ndarray | None = None
    t: Any = 0.0
    for k in range(m):
        qk = q[k]
        pk = c.prismatic[:, k][:, None]
        qr = np.where(pk, 0.0, qk) if any_p else qk
        Pr = c.Pr[:, k].transpose(1, 2, 0)[..., None]  # (3, 3, G, 1)
        M = np.sin(qr) * c.K1[:, k].transpose(1, 2, 0)[..., None]
        M += (1.0 - np.cos(qr)) * (c.K2[:, k] - c.Pr[:, k]).transpose(1, 2, 0)[..., None]
        M += Pr
        Pt = c.Pt[:, k].T[..., None]
        Pa = c.Pa[:, k].T[..., None]
        if R is None:
            o = np.broadcast_to(Pt, (3,) + qk.shape)
            w = np.broadcast_to(Pa, (3,) + qk.shape)
            R = M
        else:
            o = t + R[:, 0] * Pt[0] + R[:, 1] * Pt[1] + R[:, 2] * Pt[2]
            w = R[:, 0] * Pa[0] + R[:, 1] * Pa[1] + R[:, 2] * Pa[2]
            R = R[:, 0, None] * M[None, 0] + R[:, 1, None] * M[None, 1] + R[:, 2, None] * M[None, 2]
        origins[:, k] = o
        waxes[:, k] = w
        t = o + np.where(pk, w * qk, 0.0) if any_p else o
    assert R is not None
    f = c.foot.T[..., None]
    return origins, waxes, t + R[:, 0] * f[0] + R[:, 1] * f[1] + R[:, 2] * f[2]


def _dls(
    c: LegConsts,
    lower: np.ndarray,
    upper: np.ndarray,
    tgt: np.ndarray,
    q: np.ndarray,
    span: float,
    iterations: int,
) -> np.ndarray:
    """Iterate DLS in place on ``q`` (N, G, m) towards ``tgt`` (N, G, 3); residuals (N, G).

    Levenberg–Marquardt acceptance: a step is kept only when it lowers the residual (then
    the damping factor μ shrinks ×0.3), else it is refused and μ grows ×10; an element stops
    at ``‖e‖ ≤ 10⁻¹³ s`` or when μ passes 10¹⁰ (no step lowers the residual). Each element
    is independent: an iteration only visits the samples with a leg still running, and the
    arrays are components first with the samples last (long vector operations).
    """
    m = q.shape[-1]
    lam_floor = 1e-14 * span * span
    done_tol = 1e-13 * span
    qs = np.ascontiguousarray(np.transpose(q, (2, 1, 0)))  # (m, G, N)
    ts = np.ascontiguousarray(np.transpose(tgt, (2, 1, 0)))  # (3, G, N)
    lo = np.asarray(lower, dtype=float).T[..., None]
    hi = np.asarray(upper, dtype=float).T[..., None]
    pr = c.prismatic.T[None, :, :, None]  # (1, m, G, 1)
    o, w, p = _fk_soa(c, qs)
    err = ts - p
    norm = np.sqrt(np.einsum("i...,i...->...", err, err))
    mu = np.full(norm.shape, 1e-2)
    for _ in range(iterations):
        live = (norm > done_tol) & (mu < 1e10)
        cols = np.flatnonzero(live.any(axis=0))
        if not cols.size:
            break
        lv, nm, e_, q_ = live[:, cols], norm[:, cols], err[..., cols], qs[..., cols]
        o_, w_, p_ = o[..., cols], w[..., cols], p[..., cols]
        d = p_[:, None] - o_
        J = np.stack(
            [w_[1] * d[2] - w_[2] * d[1], w_[2] * d[0] - w_[0] * d[2], w_[0] * d[1] - w_[1] * d[0]]
        )
        J = np.where(pr, w_, J)  # (3, m, G, n')
        A = np.einsum("iagn,ibgn->abgn", J, J)
        lam2 = mu[:, cols] * nm * nm + lam_floor
        for a in range(m):
            A[a, a] += lam2
        b = np.einsum("iagn,ign->agn", J, e_)
        dq = _solve_spd(A, b)
        big = np.abs(dq).max(axis=0)
        dq *= np.minimum(1.0, 0.5 / np.maximum(big, 1e-300))
        new = np.clip(q_ + dq, lo, hi)
        o2, w2, p2 = _fk_soa(c, new)
        err2 = ts[..., cols] - p2
        norm2 = np.sqrt(np.einsum("i...,i...->...", err2, err2))
        acc = lv & (norm2 < nm)
        qs[..., cols] = np.where(acc, new, q_)
        o[..., cols] = np.where(acc, o2, o_)
        w[..., cols] = np.where(acc, w2, w_)
        p[..., cols] = np.where(acc, p2, p_)
        err[..., cols] = np.where(acc, err2, e_)
        norm[:, cols] = np.where(acc, norm2, nm)
        mu[:, cols] = np.where(
            acc, np.maximum(mu[:, cols] * 0.3, 1e-9), np.where(lv, mu[:, cols] * 10.0, mu[:, cols])
        )
    q[:] = np.transpose(qs, (2, 1, 0))
    return np.ascontiguousarray(norm.T)


def _solve_spd(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve stacked symmetric positive-definite systems ``A x = b``, A (m, m, ...), b (m, ...).

    m = 3: by the adjugate (element-wise, faster than a batched LAPACK call for 3×3);
    otherwise ``numpy.linalg.solve``.
    """
    if A.shape[0] != 3:
        x = np.linalg.solve(np.moveaxis(A, (0, 1), (-2, -1)), np.moveaxis(b, 0, -1)[..., None])
        return np.moveaxis(x[..., 0], -1, 0)
    a, bb, c = A[0, 0], A[0, 1], A[0, 2]
    d, e, f = A[1, 1], A[1, 2], A[2, 2]
    c00, c01, c02 = d * f - e * e, c * e - bb * f, bb * e - c * d
    c11, c12, c22 = a * f - c * c, bb * c - a * e, a * d - bb * bb
    det = a * c00 + bb * c01 + c * c02
    x = np.empty(b.shape)
    x[0] = c00 * b[0] + c01 * b[1] + c02 * b[2]
    x[1] = c01 * b[0] + c11 * b[1] + c12 * b[2]
    x[2] = c02 * b[0] + c12 * b[1] + c22 * b[2]
    x /= det
    return x
