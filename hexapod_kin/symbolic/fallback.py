"""The budget's fallback kinematics: products left as unevaluated sums, built in milliseconds.

When not even stage 1 finishes within the budget, :func:`~hexapod_kin.symbolic.core.kinematics`
with ``simplify=False`` builds the products with these helpers (``evaluate=False``: zeros
dropped, ones skipped), equal in value, never printed.
"""

from __future__ import annotations

from typing import Any

import sympy as sp

__all__ = ["affine", "product", "z_cross"]


def product(a: sp.Matrix, b: sp.Matrix) -> sp.Matrix:
    """``a·b`` as unevaluated sums of unevaluated products."""

    def entry(i: int, j: int) -> Any:
        terms = []
        for k in range(a.cols):
            x, y = a[i, k], b[k, j]
            if x == 0 or y == 0:
                continue
            terms.append(x if y == 1 else y if x == 1 else sp.Mul(x, y, evaluate=False))
        if not terms:
            return sp.Integer(0)
        return terms[0] if len(terms) == 1 else sp.Add(*terms, evaluate=False)

    return sp.Matrix(a.rows, b.cols, entry)


def affine(t: sp.Matrix, v: sp.Matrix) -> sp.Matrix:
    """``R v + o`` for the homogeneous transform ``t`` = [R o; 0 1] and a 3-vector ``v``."""
    return product(t[:3, :], sp.Matrix([*v, 1]))


def z_cross(rot: sp.Matrix, v: sp.Matrix) -> sp.Matrix:
    """``R (z × v)`` = ``R[:, 1] v_x − R[:, 0] v_y`` (a revolute column of the Jacobian)."""
    return product(rot[:, :2], sp.Matrix([sp.Mul(-1, v[1], evaluate=False), v[0]]))
