"""Compiled loops of the whole-robot model (numba): IK branch picking, tree kinematics + CoM."""

from __future__ import annotations

import math

import numpy as np

from .._kernels import njit

__all__: list[str] = []


@njit(cache=True)
def _pick_branch(
    qk: np.ndarray, valid: np.ndarray, q0: np.ndarray, out: np.ndarray, ok: np.ndarray
) -> None:  # pragma: no cover - compiled
    """At each sample the valid slot nearest to the previous sample (angles unwrapped)."""
    prev = q0.copy()
    n, k, m = qk.shape
    for i in range(n):
        best = -1
        best_d = np.inf
        for s in range(k):
            if not valid[i, s]:
                continue
            d = 0.0
            for j in range(m):
                a = qk[i, s, j] - prev[j]
                a = (a + math.pi) % (2.0 * math.pi) - math.pi
                d += abs(a)
            if d < best_d:
                best_d = d
                best = s
        ok[i] = best >= 0
        if best >= 0:
            for j in range(m):
                a = qk[i, best, j] - prev[j]
                prev[j] = prev[j] + (a + math.pi) % (2.0 * math.pi) - math.pi
        for j in range(m):
            out[i, j] = prev[j]


@njit(cache=True)
def _tree_kernel(
    q: np.ndarray,
    base: np.ndarray,
    parents: np.ndarray,
    placements: np.ndarray,
    masses: np.ndarray,
    levers: np.ndarray,
    leg_joints: np.ndarray,
    foot: np.ndarray,
    foot_joint: np.ndarray,
    pts: np.ndarray,
    com: np.ndarray,
) -> None:  # pragma: no cover - compiled
    """Per sample: joint frames down the tree (revolute z), leg points and the CoM."""
    n, nj = q.shape
    nl = leg_joints.shape[0]
    T = np.empty((nj, 3, 4))
    loc = np.empty((3, 4))
    mtot = masses.sum()
    for i in range(n):
        B = base[i]
        for j in range(nj):
            c, s = math.cos(q[i, j]), math.sin(q[i, j])
            P = placements[j]
            for r in range(3):
                loc[r, 0] = c * P[r, 0] + s * P[r, 1]
                loc[r, 1] = -s * P[r, 0] + c * P[r, 1]
                loc[r, 2] = P[r, 2]
                loc[r, 3] = P[r, 3]
            par = parents[j]
            for r in range(3):
                for k in range(4):
                    if par < 0:
                        v = B[r, 0] * loc[0, k] + B[r, 1] * loc[1, k] + B[r, 2] * loc[2, k]
                    else:
                        v = (
                            T[par, r, 0] * loc[0, k]
                            + T[par, r, 1] * loc[1, k]
                            + T[par, r, 2] * loc[2, k]
                        )
                    if k == 3:
                        v += B[r, 3] if par < 0 else T[par, r, 3]
                    T[j, r, k] = v
        for r in range(3):
            acc = masses[0] * (
                B[r, 0] * levers[0, 0] + B[r, 1] * levers[0, 1] + B[r, 2] * levers[0, 2] + B[r, 3]
            )
            for j in range(nj):
                acc += masses[j + 1] * (
                    T[j, r, 0] * levers[j + 1, 0]
                    + T[j, r, 1] * levers[j + 1, 1]
                    + T[j, r, 2] * levers[j + 1, 2]
                    + T[j, r, 3]
                )
            com[i, r] = acc / mtot
        for leg in range(nl):
            for u in range(3):
                j = leg_joints[leg, u]
                for r in range(3):
                    pts[i, leg, u, r] = T[j, r, 3]
            j = foot_joint[leg]
            for r in range(3):
                pts[i, leg, 3, r] = (
                    T[j, r, 0] * foot[leg, 0]
                    + T[j, r, 1] * foot[leg, 1]
                    + T[j, r, 2] * foot[leg, 2]
                    + T[j, r, 3]
                )
