"""Numbers beside the symbolic work: the table's own Jacobian, σ ratios, roots of one joint.

Part of :mod:`hexapod_kin.symbolic.core` (which re-exports them): plain numpy, the independent
side of the families' checks.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence

import numpy as np

from .._table_kin import table_transforms
from ..params import Chain


def numeric_jacobian(chain: Chain, q: np.ndarray, sel: Sequence[int]) -> np.ndarray:
    """Independent numeric Jacobian (base frame, tool point) from the table, rows ``sel``."""
    ts, acc = table_transforms(chain, q), chain.base_matrix
    frames = []
    for t in ts:
        acc = acc @ t
        frames.append(acc)
    tip = (acc @ chain.tool_matrix)[:3, 3]
    cols = []
    for j in chain.joint_rows:
        z, o = frames[j][:3, 2], frames[j][:3, 3]
        if chain.rows[j].sigma == "revolute":
            cols.append(np.concatenate([np.cross(z, tip - o), z]))
        else:
            cols.append(np.concatenate([z, np.zeros(3)]))
    return np.column_stack(cols)[list(sel)]


def sigma_ratio(jac: np.ndarray) -> float:
    """``σ_min / max(1, σ_max)`` of a k×n matrix (min(k, n) singular values)."""
    s = np.linalg.svd(jac, compute_uv=False)
    return float(s[-1] / max(1.0, s[0]))


def brent_root(f: Callable[[float], float], xa: float, xb: float, xtol: float,
               rtol: float = 4 * sys.float_info.epsilon, maxiter: int = 100) -> float:  # fmt: skip
    """A root of ``f`` in ``[xa, xb]`` (``f(xa)``, ``f(xb)`` of opposite signs or zero).

    Brent's method in the same floating-point operations as :func:`scipy.optimize.brentq` (the
    same root to the bit) without importing scipy; stops at ``(xtol + rtol |x|) / 2``.
    """
    x_prev, x_cur = float(xa), float(xb)
    f_prev, f_cur = float(f(x_prev)), float(f(x_cur))
    if f_prev == 0.0:
        return x_prev
    if f_cur == 0.0:
        return x_cur
    x_blk = f_blk = s_prev = s_cur = 0.0
    for _ in range(maxiter):
        if f_prev * f_cur < 0.0:  # the bracket is [x_blk, x_cur]
            x_blk, f_blk = x_prev, f_prev
            s_prev = s_cur = x_cur - x_prev
        if abs(f_blk) < abs(f_cur):  # x_cur: the end with the smaller |f|
            x_prev, x_cur, x_blk = x_cur, x_blk, x_cur
            f_prev, f_cur, f_blk = f_cur, f_blk, f_cur
        delta, s_bis = (xtol + rtol * abs(x_cur)) / 2, (x_blk - x_cur) / 2
        if f_cur == 0.0 or abs(s_bis) < delta:
            return x_cur
        step = s_bis
        if abs(s_prev) > delta and abs(f_cur) < abs(f_prev):
            if x_prev == x_blk:  # secant
                s_try = -f_cur * (x_cur - x_prev) / (f_cur - f_prev)
            else:  # inverse quadratic
                d_prev = (f_prev - f_cur) / (x_prev - x_cur)
                d_blk = (f_blk - f_cur) / (x_blk - x_cur)
                s_try = (
                    -f_cur * (f_blk * d_blk - f_prev * d_prev) / (d_blk * d_prev * (f_blk - f_prev))
                )
            if 2 * abs(s_try) < min(abs(s_prev), 3 * abs(s_bis) - delta):
                step = s_try
                s_prev, s_cur = s_cur, s_try
            else:
                s_prev = s_cur = s_bis
        else:
            s_prev = s_cur = s_bis
        x_prev, f_prev = x_cur, f_cur
        x_cur += step if abs(step) > delta else (delta if s_bis > 0 else -delta)
        f_cur = float(f(x_cur))
    return x_cur


def single_joint_roots(
    func: Callable[[np.ndarray], np.ndarray], lo: float, hi: float
) -> list[float]:
    """Real roots of a scalar function of one joint on ``[lo, hi]`` (sign changes, Brent)."""
    grid = np.linspace(lo, hi, 3601)
    vals = np.asarray(func(grid), dtype=float)
    roots: list[float] = []
    scale = max(1e-300, float(np.abs(vals).max()))
    for i in range(len(grid) - 1):
        a, b = vals[i], vals[i + 1]
        if a == 0.0:
            roots.append(float(grid[i]))
        elif a * b < 0:
            one = lambda x: float(func(np.array([x]))[0])  # noqa: E731
            roots.append(brent_root(one, grid[i], grid[i + 1], 1e-15))
        elif abs(a) < 1e-12 * scale and i > 0 and (vals[i - 1] - a) * (b - a) > 0:
            roots.append(float(grid[i]))  # a tangency at a grid point
    if vals[-1] == 0.0:
        roots.append(float(grid[-1]))
    out: list[float] = []
    for r in sorted(roots):
        if not out or abs(r - out[-1]) > 1e-9:
            out.append(r)
    return out
