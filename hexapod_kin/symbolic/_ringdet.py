"""Determinants of polynomial matrices in a sparse polynomial ring (exact, no expression swell).

sympy's expression route (``Matrix.det`` and then ``expand`` of the whole) builds the
unexpanded sum of products first: on a 6×6 Jacobian in a joint frame that takes seconds, most
of it in ``expand``. Here each entry is converted to an element of a polynomial ring over ℚ
(:func:`sympy.polys.rings.ring`) and the determinant is taken there, by cofactors along the
rows with every minor kept (a 6×6 needs at most 2⁶ of them): milliseconds. Expanding is a ring
homomorphism, so the result is *the same polynomial* the expression route gives.

Entries with a coefficient outside ℚ (a float, ``sqrt(3)``, ``pi``) are refused (``None``):
floats would round in another order than ``expand`` rounds them, so the caller keeps its own
route for them.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import sympy as sp
from sympy.polys.rings import ring


def ring_det(entries: Sequence[Any], n: int, gens: Sequence[sp.Symbol]) -> Any | None:
    """``det`` of the n×n matrix of expanded polynomial ``entries`` (row-major), expanded.

    Args:
        entries: n² sympy expressions, polynomials in ``gens`` and other symbols.
        n: The size.
        gens: The generators to put first (the other symbols follow, by name).

    Returns:
        The determinant as an expanded sympy expression, or ``None`` when an entry is not a
        polynomial with rational coefficients.

    """
    if any(e.has(sp.Float) for e in entries):
        return None
    others = set().union(*(e.free_symbols for e in entries)) - set(gens)
    r, *_ = ring([*gens, *sorted(others, key=str)], sp.QQ)
    try:
        rows = [[r.from_expr(e) if e != 0 else r.zero for e in entries[i * n : (i + 1) * n]]
                for i in range(n)]  # fmt: skip
    except ValueError:  # not a polynomial over QQ (sqrt(3), pi, a leftover sin)
        return None
    memo: dict[tuple[int, ...], Any] = {}

    def minor(cols: tuple[int, ...]) -> Any:
        """The minor of the last ``len(cols)`` rows and the columns ``cols``."""
        if not cols:
            return r.one
        if cols in memo:
            return memo[cols]
        row = rows[n - len(cols)]
        acc = r.zero
        for k, j in enumerate(cols):
            if row[j]:
                term = row[j] * minor(cols[:k] + cols[k + 1 :])
                acc = acc - term if k % 2 else acc + term
        memo[cols] = acc
        return acc

    return minor(tuple(range(n))).as_expr()
