"""Numbers from a sympy expression in one pass over it, and the checks made with them.

:func:`evaluate` walks the expression once, bottom up, each distinct sub-expression once, with
numpy arrays at the leaves: no ``subs`` and no generated code (``lambdify``), so checks stay
within a time budget. :func:`claims_hold` checks a cached derivation against its table.
"""

from __future__ import annotations

import functools
import math
import operator
from collections.abc import Mapping
from typing import Any

import numpy as np
import sympy as sp

from ..jacobian_rows import ROW_NAMES
from ..params import Chain

__all__ = ["NUMPY_FUNCTIONS", "claims_hold", "evaluate", "evaluate_matrix"]

#: sympy functions and their numpy twins (also the seed report's numeric comparison).
NUMPY_FUNCTIONS: dict[Any, Any] = {
    sp.sin: np.sin, sp.cos: np.cos, sp.tan: np.tan, sp.exp: np.exp, sp.log: np.log,
    sp.Abs: np.abs, sp.atan2: np.arctan2, sp.asin: np.arcsin, sp.acos: np.arccos,
    sp.atan: np.arctan,
}  # fmt: skip


def evaluate(expr: Any, values: Mapping[Any, Any]) -> Any:
    """``expr`` at ``values``: a float or an array (broadcasting together) per symbol.

    ``expr`` is built of numbers, symbols, ``+``, ``*``, powers and the functions ``sin cos tan
    exp log Abs atan2 asin acos atan``; the value is a float or an array of the broadcast shape.
    Raises ValueError: a symbol without a value, or a function outside the list.
    """
    return _value(sp.sympify(expr), values, {})


def _value(root: Any, values: Mapping[Any, Any], memo: dict[Any, Any]) -> Any:
    """:func:`evaluate` with ``memo`` (node → value) shared between calls."""
    stack: list[tuple[Any, bool]] = [(root, False)]
    while stack:
        node, ready = stack.pop()
        if node in memo:
            continue
        if not ready:
            if node.is_Symbol:
                if node not in values:
                    raise ValueError(f"no value for the symbol {node}")
                memo[node] = values[node]
            elif node.is_Number or node.is_NumberSymbol:
                memo[node] = float(node)
            else:
                stack.append((node, True))
                stack.extend((a, False) for a in node.args if a not in memo)
            continue
        args = [memo[a] for a in node.args]
        if node.is_Add or node.is_Mul:
            out = functools.reduce(operator.add if node.is_Add else operator.mul, args)
        elif node.is_Pow:
            out = np.power(args[0], args[1])
        elif node.func in NUMPY_FUNCTIONS:
            out = NUMPY_FUNCTIONS[node.func](*args)
        else:
            raise ValueError(f"cannot evaluate {node.func} here")
        memo[node] = out
    return memo[root]


def evaluate_matrix(
    mat: Any, values: Mapping[Any, Any], points: int, memo: dict[Any, Any] | None = None
) -> np.ndarray:
    """A sympy matrix at ``points`` points: shape (points, rows, cols) (see :func:`evaluate`).

    ``memo`` (node → value) may be shared between calls on the same ``values``.
    """
    mat = sp.Matrix(mat)
    rows, cols = mat.shape
    out = np.empty((points, rows, cols))
    memo = {} if memo is None else memo  # entries share sub-expressions
    for i in range(rows):
        for j in range(cols):
            value = np.asarray(_value(sp.sympify(mat[i, j]), values, memo), dtype=float)
            out[:, i, j] = np.broadcast_to(value, (points,))
    return out


def claims_hold(stages: Mapping[str, Any], chain: Chain, values: Mapping[Any, Any]) -> bool:
    """A cached derivation checked against what it claims, before use.

    At three seeded configurations, as stored and tidied: every matrix against the table's own
    numbers, ``det`` and ``const · Π fᵐ`` against ``|det J|``, the Gram determinant, and each
    family's factor against the determinant's factors.
    """
    kin = stages.get("kinematics")
    if kin is None:
        return True  # nothing stored that could be wrong
    tidy = stages.get("tidy") or {}
    forms = [kin, {**kin, **tidy}] if tidy else [kin]  # as stored, and as used (_assemble)
    with np.errstate(all="ignore"):  # an edited entry may overflow: it then fails
        return all(_claims(stages, k, chain, values) for k in forms)


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal values, relatively to 1e-9."""
    return bool(np.all(np.abs(a - b) <= 1e-9 * np.maximum(np.abs(a), np.abs(b)) + 1e-300))


def _reference(chain: Chain, qv: np.ndarray) -> dict[str, np.ndarray]:
    """The table's own numbers at ``qv`` (plain numpy), named as the stored matrices."""
    from .._table_kin import table_transforms
    from ._numbers import numeric_jacobian

    ts = table_transforms(chain, qv)
    base, tool = chain.base_matrix, chain.tool_matrix
    out, acc = {"base": base, "tool": tool}, base
    for j, t in enumerate(ts):
        out[f"transforms.{j}"] = t
        acc = acc @ t
        out[f"cumulative.{j}"] = acc
    out["tip"] = acc @ tool
    out["p"] = out["tip"][:3, 3:4]
    out["J_direct"] = numeric_jacobian(chain, qv, range(6))
    out["J_indirect"] = out["J_direct"][:3]
    return out


def _claims(stages: Mapping[str, Any], kin: Any, chain: Chain, values: Mapping[Any, Any]) -> bool:
    """:func:`claims_hold` for one form of an entry with kinematics."""
    n = chain.nq
    q = tuple(sp.Symbol(f"q{k}", real=True) for k in range(1, n + 1))
    rng = np.random.default_rng(20251202)
    qs = rng.uniform(-math.pi, math.pi, (3, n))
    scale = 1.0 + float(sum(abs(float(v)) for v in values.values()))
    at = {**{s: float(v) for s, v in values.items()}, **{s: qs[:, k] for k, s in enumerate(q)}}
    names = ("base", "tool", "tip", "p", "J_indirect", "J_direct")
    mats: dict[str, Any] = {name: kin[name] for name in names if name in kin}
    for name in ("transforms", "cumulative"):
        mats.update({f"{name}.{j}": m for j, m in enumerate(kin.get(name) or ())})
    if "p" not in mats or "J_direct" not in mats:
        return False
    try:
        memo: dict[Any, Any] = {}  # the matrices share sub-expressions (products, columns)
        got = {name: evaluate_matrix(m, at, 3, memo) for name, m in mats.items()}
    except (ValueError, TypeError, KeyError, AttributeError):
        return False  # a symbol or a function the table has not, or not a matrix
    jac = got["J_direct"]
    for k, qv in enumerate(qs):
        want = _reference(chain, qv)
        for name, vals in got.items():
            if name not in want or vals[k].shape != want[name].shape:
                return False
            if not np.allclose(vals[k], want[name], atol=1e-9 * scale, rtol=0.0):
                return False
    det, rows = stages.get("determinant"), stages.get("rows")
    try:
        sel_rows = [ROW_NAMES.index(r) for r in rows] if rows is not None else None
        if det is not None and sel_rows is not None:
            square, tol = len(sel_rows) == n, 1e-8 * scale**4
            gram = det.get("gram")
            gram_v = None if gram is None else np.broadcast_to(evaluate(gram, at), (3,))
            dets = [np.broadcast_to(evaluate(det["det"], at), (3,))] if square else []
            if square:
                const = np.broadcast_to(evaluate(det.get("const", 1), at), (3,))
                prod = const.astype(float)
                for f, m in det.get("factors", ()):
                    prod = prod * np.power(np.broadcast_to(evaluate(f, at), (3,)), int(m))
                dets.append(prod)
            for k in range(3):
                sel = jac[k][sel_rows]
                gram_k = sel @ sel.T if sel.shape[0] <= sel.shape[1] else sel.T @ sel
                want_g = float(np.linalg.det(gram_k))
                off = abs(float(gram_v[k]) - want_g) if gram_v is not None else 0.0
                if off > tol * max(1.0, abs(want_g)):
                    return False
                if square:
                    size = abs(float(np.linalg.det(sel)))
                    for d in dets:
                        if abs(abs(float(d[k])) - size) > 1e-8 * max(1.0, size) * scale**n:
                            return False
        if det is not None:
            factors = [np.broadcast_to(evaluate(f, at), (3,)) for f, _m in det.get("factors", ())]
            for fam in (*(stages.get("families") or ()), *(stages.get("checks") or ())):
                f = np.broadcast_to(evaluate(fam.factor, at), (3,))
                if factors and not any(_same(f, g) or _same(f, -g) for g in factors):
                    return False
    except (ValueError, TypeError, KeyError, AttributeError):
        return False
    return True
