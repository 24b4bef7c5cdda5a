"""Trigonometric polynomials of the joints as polynomials in ``s_k = sin q_k``, ``c_k = cos q_k``.

The change of variables (:func:`_to_poly`), the reduction modulo ``s_k² + c_k² = 1``
(:func:`_reduce`), rounding noise (:func:`_chop`) and determinants (:func:`_det_poly`,
:func:`ring_det`: in a sparse polynomial ring over ℚ, the same polynomial as ``Matrix.det``
then ``expand``, much faster).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import sympy as sp
from sympy.polys.rings import ring


def ring_det(entries: Sequence[Any], n: int, gens: Sequence[sp.Symbol]) -> Any | None:
    """``det`` of the n×n matrix of polynomial ``entries`` (n², row-major), expanded.

    The ring's generators are ``gens``, then the other symbols by name; ``None`` when an entry
    is not a polynomial with rational coefficients.
    """
    entries = [sp.sympify(e) for e in entries]
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
        row, acc = rows[n - len(cols)], r.zero
        for k, j in enumerate(cols):
            if row[j]:
                term = row[j] * minor(cols[:k] + cols[k + 1 :])
                acc = acc - term if k % 2 else acc + term
        memo[cols] = acc
        return acc

    return minor(tuple(range(n))).as_expr()


def _trig_symbols(q: Sequence[sp.Symbol]) -> tuple[tuple[sp.Symbol, ...], tuple[sp.Symbol, ...]]:
    s = tuple(sp.Symbol(f"_s{k}", real=True) for k in range(len(q)))
    c = tuple(sp.Symbol(f"_c{k}", real=True) for k in range(len(q)))
    return s, c


def _to_poly(expr: Any, q: Sequence[sp.Symbol], sigmas: Sequence[str]) -> Any:
    s, c = _trig_symbols(q)
    e = sp.expand(sp.expand_trig(expr))
    rev = [k for k in range(len(q)) if sigmas[k] == "revolute"]
    sub = {fn(q[k]): x[k] for k in rev for fn, x in ((sp.sin, s), (sp.cos, c))}
    return sp.expand(e.xreplace(sub))


def _reduce(poly: Any, q: Sequence[sp.Symbol]) -> Any:
    s, c = _trig_symbols(q)
    e = poly
    for sk, ck in zip(s, c):
        if e.has(sk):
            e = sp.rem(sp.Poly(e, sk), sp.Poly(sk**2 + ck**2 - 1, sk)).as_expr()
    return sp.expand(e)


def _chop(expr: Any, rel: float = 1e-12) -> Any:
    """Float coefficients below ``rel`` × the largest one (rounding noise), set to 0."""
    floats = expr.atoms(sp.Float)
    if not floats:
        return expr
    tiny = rel * max(abs(float(f)) for f in floats)
    zero = {f: sp.Integer(0) for f in floats if abs(float(f)) < tiny}
    return sp.expand(expr.xreplace(zero)) if zero else expr


def _det_poly(mat: sp.Matrix, q: Sequence[sp.Symbol], sigmas: Sequence[str],
              split: bool = False, memo: dict[Any, Any] | None = None) -> Any:  # fmt: skip
    """``_to_poly(det mat)`` (``split``: of ``det J11 · det J22``, block-triangular 6×6).

    By :func:`ring_det` when every entry is a polynomial over ℚ, else by expanding the
    expression. ``memo``: the entries' polynomials, shared between calls.
    """
    s, c = _trig_symbols(q)
    gens = [g for k, qk in enumerate(q)
            for g in ((s[k], c[k]) if sigmas[k] == "revolute" else (qk,))]  # fmt: skip
    memo = {} if memo is None else memo
    entries = []
    for e in mat:
        if e not in memo:
            memo[e] = _to_poly(e, q, sigmas)
        entries.append(memo[e])
    out = ring_det(entries, mat.rows, gens)
    if out is not None:
        return out
    if split:
        raw = mat[:3, :3].det(method="berkowitz") * mat[3:, 3:].det(method="berkowitz")
    else:
        raw = mat.det(method="berkowitz")
    return _to_poly(raw, q, sigmas)
