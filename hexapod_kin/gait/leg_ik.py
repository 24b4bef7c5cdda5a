"""The numerical leg IK, used where no closed form recognises the leg: the package's one loop.

Each leg is a chain view (:class:`~hexapod_kin._chain.ChainArrays`, body → foot) solved by
:func:`hexapod_kin.ik.solve_chain` (the compiled Levenberg–Marquardt loop on the position
rows) for all samples at once from the seed; a sample far from its predecessor (a branch
jump, > 0.5 rad) or not reached is solved again warm-started from the previous one, in time
order. *Reached*: a residual of at most :data:`REACH_TOL`; otherwise the residual is the
distance of the best point found to the target (the leg's ``excess``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .._chain import ChainArrays
from ..ik import solve_chain

__all__ = ["REACH_TOL", "leg_chain", "solve_legs"]

#: A foot is reached when the numerical IK residual is at most this [m].
REACH_TOL = 1e-10

#: A sample's joints farther than this from the previous sample's [rad] are a branch jump.
_JUMP = 0.5


def leg_chain(
    placements: np.ndarray, axes: np.ndarray, prismatic: np.ndarray, foot: np.ndarray
) -> ChainArrays:
    """One leg as a chain view: its m joints alone (``col = 0..m-1``), the foot its tip.

    Args:
        placements: (m, 4, 4) each joint's placement in the previous joint's frame (the
            first in the body frame).
        axes: (m, 3) unit joint axes in their joint frames.
        prismatic: (m,) True for prismatic joints.
        foot: (3,) the foot in the last joint's frame [m].

    """
    return ChainArrays.serial(
        placements[:, :3, :3], np.vstack([placements[:, :3, 3], foot]), axes, prismatic
    )


def solve_legs(
    chains: Sequence[ChainArrays],
    lower: np.ndarray,
    upper: np.ndarray,
    targets: np.ndarray,
    seed: np.ndarray,
    *,
    span: float,
    iterations: int = 60,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position IK of G legs of m joints at N samples (see the module doc).

    Args:
        chains: G leg chains (:func:`leg_chain`), each in the body frame.
        lower: (G, m) lower joint limits.
        upper: (G, m) upper joint limits.
        targets: (N, G, 3) body-frame foot targets [m].
        seed: (G, m) the joints before the first sample.
        span: The legs' length scale [m]: the loop stops at ``‖e‖ ≤ 10⁻¹³ span``.
        iterations: Cap on the accepted steps per solve.

    Returns:
        ``(q, residual, reached)``: (N, G, m), (N, G) [m], (N, G).

    """
    n, g, _ = targets.shape
    m = len(seed[0])
    seed_arr = np.asarray(seed, dtype=float)
    q = np.empty((n, g, m))
    res = np.empty((n, g))

    def run(leg: int, x: np.ndarray, q0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        out, r, _ok = solve_chain(
            chains[leg], x, q0, lower[leg], upper[leg], tol=1e-13 * span, max_iter=iterations
        )
        return out, r

    for leg in range(g):
        qg, rg = run(leg, targets[:, leg], np.broadcast_to(seed_arr[leg], (n, m)))
        # continuity: re-solve, warm-started from the previous sample, where a branch jumped
        # (or the foot was missed); only those samples are visited, in time order
        i = 0
        while True:
            before = seed_arr[leg] if i == 0 else qg[i - 1]
            prev = np.concatenate([before[None], qg[i:-1]])
            bad = (np.abs(qg[i:] - prev).max(axis=1) > _JUMP) | (rg[i:] > REACH_TOL)
            hits = np.flatnonzero(bad)
            if not hits.size:
                break
            i += int(hits[0])
            start = seed_arr[leg] if i == 0 else qg[i - 1]
            qi, ri = run(leg, targets[i : i + 1, leg], start[None])
            if ri[0] <= max(rg[i], REACH_TOL):
                qg[i], rg[i] = qi[0], ri[0]
            i += 1
            if i >= n:
                break
        q[:, leg], res[:, leg] = qg, rg
    return q, res, res <= REACH_TOL
