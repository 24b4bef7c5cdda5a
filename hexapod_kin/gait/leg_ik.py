"""The numerical leg IK (numpy only), used where no closed form recognises the leg.

Damped least squares on the leg's own joints, vectorised over samples and legs, with the
analytic position Jacobian ``J_k = w_k × (p − o_k)`` (revolute; ``w_k`` for prismatic) from
the batch tree kinematics (:func:`hexapod_kin._tree.leg_fk_soa`)::

    Δq = (JᵀJ + λ²I)⁻¹ Jᵀ e,   λ² = 10⁻² ‖e‖² + 10⁻¹⁴ s²   (s: the leg's span)

each step scaled to at most 0.5 rad and clipped to the joint limits, until
``‖e‖ ≤ 10⁻¹³ s`` or the step stalls. All samples start from the seed; a sample whose
solution is far from its predecessor's (a branch jump, > 0.5 rad) or not reached is solved
again warm-started from the previous sample. A foot is *reached* when the residual is at
most :data:`REACH_TOL`; otherwise the residual is the distance of the best reachable point
found to the target (the leg's ``excess``).

:func:`solve_legs` is the one entry point (called from one place,
:meth:`~hexapod_kin.gait.robot.WholeBody.body_ik`); its loop is the one to replace by the
package's DLS loop.
"""

from __future__ import annotations

import numpy as np

from .._tree import LegConsts, leg_fk_soa, leg_subset

__all__ = ["REACH_TOL", "solve_legs"]

#: A foot is reached when the numerical IK residual is at most this [m].
REACH_TOL = 1e-10


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
            sub = leg_subset(c, idx)
            ri = _dls(sub, lower[idx], upper[idx], targets[i, idx][None], qi, span, iterations)[0]
            better = (ri <= np.maximum(res[i, idx], REACH_TOL)) | (ri <= REACH_TOL)
            q[i, idx] = np.where(better[:, None], qi[0], q[i, idx])
            res[i, idx] = np.where(better, ri, res[i, idx])
        todo = suspects(i + 1) if i + 1 < n else todo[:0]
    return q, res, res <= REACH_TOL


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
    o, w, p = leg_fk_soa(c, qs)
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
        o2, w2, p2 = leg_fk_soa(c, new)
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
