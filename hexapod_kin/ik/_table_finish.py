"""Leg solutions finished on the table itself (:func:`finish_on_table`).

A leg whose twists are within ``angle_tol`` of the closed-form pattern is solved by the exact
pattern's closed form (:mod:`hexapod_kin.ik.closed`), each solution then finished on the
table's own kinematics by the one numerical loop (:func:`hexapod_kin.ik.solve_chain` on
:func:`table_chain`): from ``O(deviation)`` away it converges quadratically.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._chain import ChainArrays
from .._numerics import wrap_angles
from ..params import Chain, khalil_transform
from .solver import solve_chain

__all__ = ["finish_on_table", "fit_angles", "table_chain"]

_TWO_PI = 2.0 * math.pi


def fit_angles(v: np.ndarray, lo: Any, hi: Any) -> tuple[np.ndarray, np.ndarray]:
    """Angles shifted by ±2π into [lo, hi] where that helps; (angles, inside)."""
    v = np.where((v < lo) & (v + _TWO_PI <= hi), v + _TWO_PI, v)
    v = np.where((v > hi) & (v - _TWO_PI >= lo), v - _TWO_PI, v)
    return v, (v >= lo) & (v <= hi)


def table_chain(ch: Chain, n: int) -> ChainArrays:
    """The table's first ``n`` joint rows as a chain view, in the mount frame.

    Row ``j``'s placement is its Khalil transform at ``q = 0`` (``Rx(α) Tx(d) Rz(θ) Tz(r)``;
    the joint then turns about, or slides along, its z axis); row 1's α1 and d1 are in the
    mount and left out. The tip is the product of the remaining rows and the tool.
    """
    rows = ch.rows
    ts = [row.transform() if j else khalil_transform(0.0, 0.0, row.theta, row.r)
          for j, row in enumerate(rows[:n])]  # fmt: skip
    rots, trans = [t[:3, :3] for t in ts], [t[:3, 3] for t in ts]
    tip = np.eye(4)
    for row in rows[n:]:
        tip = tip @ row.transform()
    tip = tip @ ch.tool_matrix
    trans.append(tip[:3, 3])
    kind = [int(r.sigma == "prismatic") for r in rows[:n]]
    return ChainArrays.serial(rots, trans, np.tile([0.0, 0.0, 1.0], (n, 1)), kind, tip[:3, :3])


def finish_on_table(
    ch: Chain, x: np.ndarray, q: np.ndarray, valid: np.ndarray, tol_abs: float, scale: float,
    limits: tuple[np.ndarray, np.ndarray] | None,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Finish the ``valid`` (N, K) slots of ``q`` (N, K, n) on the table itself (no limits).

    ``x``: (N, 3) targets [m] in the mount frame. A slot stays valid when its foot ends within
    ``tol_abs`` [m] of the target (2 DOF: the distance to the table's surface) and, with
    ``limits`` (lower, upper), inside them after ±2π shifts; the loop stops at ``‖e‖ ≤ 1e-15 ·
    scale``. Returns ``(q, valid)`` as :func:`~hexapod_kin.ik.leg_solutions` does.
    """
    n_t, k, n = q.shape
    q, idx = q.copy(), np.argwhere(valid)
    if len(idx):
        qa, xa, free = q[idx[:, 0], idx[:, 1]], x[idx[:, 0], :3], np.full(n, np.inf)
        chain = table_chain(ch, n)
        qa, miss, _ok = solve_chain(chain, xa, qa, -free, free, tol=1e-15 * scale, max_iter=12)
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
