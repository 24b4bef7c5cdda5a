"""The zero set ``f(q) = 0`` of a family's factor: the factor text compiled, exact distances.

:func:`compile_factor` parses the text once and checks it against a whitelist (numbers,
``q1..qn``, ``pi``, ``+ - * / **`` with a numeric exponent, ``sin cos tan sqrt Abs``), then
turns it into a tree of numpy closures that evaluates the factor with its gradient and Hessian
over a whole array of configurations (forward-mode second-order derivatives): nothing is ever
``eval``-ed. :func:`closest_distance` is the distance to the zero set: the closest point,
found by Newton on the Lagrange system from several starts.
"""

from __future__ import annotations

import ast
import math
import operator
from collections.abc import Callable
from typing import Any

import numpy as np

from ..exceptions import ParameterError

# ------------------------------------------------------------------------ jets
# A jet is (value (M,), gradient (M, v) or (v,) or None, Hessian (M, v, v) or None) over the
# family's v variables; None stands for zero (constants, linear leaves).
Jet = tuple[Any, Any, Any]


def _col(s: Any, k: int) -> Any:
    """``s`` with ``k`` trailing axes (to scale a gradient or Hessian per configuration)."""
    return np.asarray(s)[(...,) + (None,) * k]


def _add(a: Any, b: Any) -> Any:
    return b if a is None else a if b is None else a + b


def _outer(a: Any, b: Any) -> Any:
    return a[..., :, None] * b[..., None, :]


def _chain(fn: tuple[Callable[..., Any], ...], x: Jet, hess: bool) -> Jet:
    """``φ(x)`` for a scalar function with derivatives ``fn = (φ, φ', φ'')``."""
    f, g, h = x
    val = fn[0](f)
    if g is None:
        return val, None, None
    d1 = fn[1](f)
    if not hess:
        return val, _col(d1, 1) * g, None
    hh = _outer(g, g) * _col(fn[2](f), 2)
    if h is not None:
        hh = hh + _col(d1, 2) * h
    return val, _col(d1, 1) * g, hh


def _mul(a: Jet, b: Jet, hess: bool) -> Jet:
    fa, ga, ha = a
    fb, gb, hb = b
    g = _add(None if gb is None else _col(fa, 1) * gb, None if ga is None else _col(fb, 1) * ga)
    if not hess:
        return fa * fb, g, None
    h = _add(None if hb is None else _col(fa, 2) * hb, None if ha is None else _col(fb, 2) * ha)
    if ga is not None and gb is not None:
        h = _add(h, _outer(ga, gb) + _outer(gb, ga))
    return fa * fb, g, h


def _neg(a: Jet) -> Jet:
    return -a[0], None if a[1] is None else -a[1], None if a[2] is None else -a[2]


def _sum(a: Jet, b: Jet) -> Jet:
    return a[0] + b[0], _add(a[1], b[1]), _add(a[2], b[2])


def _power(c: float) -> tuple[Callable[..., Any], ...]:
    return (lambda x: x**c, lambda x: c * x ** (c - 1.0),
            lambda x: c * (c - 1.0) * x ** (c - 2.0))  # fmt: skip


_UNARY: dict[str, tuple[Callable[..., Any], ...]] = {
    "sin": (np.sin, np.cos, lambda x: -np.sin(x)),
    "cos": (np.cos, lambda x: -np.sin(x), lambda x: -np.cos(x)),
    "tan": (np.tan, lambda x: np.cos(x) ** -2.0, lambda x: 2.0 * np.tan(x) * np.cos(x) ** -2.0),
    "sqrt": (np.sqrt, lambda x: 0.5 / np.sqrt(x), lambda x: -0.25 * x**-1.5),
    "Abs": (np.abs, np.sign, np.zeros_like),
}
_RECIPROCAL = _power(-1.0)
_ALLOWED = "numbers, q1..qn, pi, + - * / ** (numeric exponent), sin cos tan sqrt Abs"
Node = Callable[[list[Any], bool], Jet]  # (variables' columns, with Hessian) -> jet
Eval = Callable[[np.ndarray, bool], Jet]  # (x (M, v), with Hessian) -> jet


_FOLD: dict[type, Callable[[float, float], float]] = {ast.Add: operator.add,
    ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
    ast.Pow: operator.pow}  # fmt: skip


def _number(node: ast.AST) -> float | None:
    """The value of a constant sub-expression (``2.5``, ``-2``, ``pi``, ``3/2``), else None."""
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)):
        return None if isinstance(node.value, bool) else float(node.value)
    if isinstance(node, ast.Name) and node.id == "pi":
        return math.pi
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        inner = _number(node.operand)
        return None if inner is None else (-inner if isinstance(node.op, ast.USub) else inner)
    if isinstance(node, ast.BinOp) and type(node.op) in _FOLD:
        a, b = _number(node.left), _number(node.right)
        if a is not None and b is not None:
            try:
                return _FOLD[type(node.op)](a, b)
            except ArithmeticError:  # 1/0, 10.0**400: left to numpy (inf, nan)
                return None
    return None


def _refuse(text: str, what: str) -> ParameterError:
    return ParameterError(
        f"family expression {text!r}: {what} is not allowed",
        parameter="expression",
        value=text,
        allowed=_ALLOWED,
    )


def _build(node: ast.AST, text: str, pos: dict[int, int]) -> Node:
    """A closure ``(cols, hess) -> jet`` for the AST node, checking it against the whitelist.

    ``pos`` maps a joint index to its column among the family's variables; a name outside
    them is refused (the factor depends on its variables only).
    """
    num = _number(node)
    if num is not None:
        const = np.float64(num)  # numpy arithmetic: 1/0 is inf (with a warning), not an error
        return lambda env, hess: (const, None, None)
    if isinstance(node, ast.Name):
        k = int(node.id[1:]) - 1 if node.id[:1] == "q" and node.id[1:].isdigit() else -1
        if k not in pos:
            raise _refuse(text, f"the name {node.id!r}")
        i, unit = pos[k], np.zeros(len(pos))
        unit[i] = 1.0
        return lambda env, hess: (env[i], unit, None)
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        inner = _build(node.operand, text, pos)
        if isinstance(node.op, ast.UAdd):
            return inner
        return lambda env, hess: _neg(inner(env, hess))
    if isinstance(node, ast.BinOp):
        left = _build(node.left, text, pos)
        if isinstance(node.op, ast.Pow):
            expo = _number(node.right)
            if expo is None:
                raise _refuse(text, "a non-numeric exponent")
            if expo == 1.0:
                return left
            fn = _power(expo)
            return lambda env, hess: _chain(fn, left(env, hess), hess)
        right = _build(node.right, text, pos)
        if isinstance(node.op, ast.Add):
            return lambda env, hess: _sum(left(env, hess), right(env, hess))
        if isinstance(node.op, ast.Sub):
            return lambda env, hess: _sum(left(env, hess), _neg(right(env, hess)))
        if isinstance(node.op, ast.Mult):
            return lambda env, hess: _mul(left(env, hess), right(env, hess), hess)
        if isinstance(node.op, ast.Div):
            inv: Node = lambda env, hess: _chain(_RECIPROCAL, right(env, hess), hess)  # noqa: E731
            return lambda env, hess: _mul(left(env, hess), inv(env, hess), hess)
        raise _refuse(text, type(node.op).__name__)
    fname = node.func.id if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) else ""
    if isinstance(node, ast.Call) and fname in _UNARY and len(node.args) == 1 and not node.keywords:
        arg = _build(node.args[0], text, pos)
        fn = _UNARY[fname]
        return lambda env, hess: _chain(fn, arg(env, hess), hess)
    raise _refuse(text, type(node).__name__)


def compile_factor(text: str, variables: tuple[int, ...]) -> Eval:
    """Parse ``text`` once into ``jet(x, hess)`` over the columns of ``x`` = ``variables``.

    ``jet(x, hess)`` with ``x`` (M, v) returns the value (M,), the gradient (M, v) and, with
    ``hess``, the Hessian (M, v, v) (else ``None``).
    Raises ParameterError: ``text`` does not parse or leaves the whitelist.
    """
    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError as err:
        raise ParameterError(f"family expression {text!r} does not parse: {err.msg}") from None
    node = _build(tree.body, text, {k: i for i, k in enumerate(variables)})

    def jet(x: np.ndarray, hess: bool) -> Jet:
        m, v = x.shape
        f, g, h = node([x[:, i] for i in range(v)], hess)
        f = np.broadcast_to(np.asarray(f, dtype=float), (m,))
        g = np.zeros((m, v)) if g is None else np.broadcast_to(g, (m, v))
        if hess:
            h = np.zeros((m, v, v)) if h is None else np.broadcast_to(h, (m, v, v))
        return f, g, h

    return jet


# ------------------------------------------------------------------------ closest points
#: Stop when ``|f|/‖∇f‖`` and the tangential part of ``x − p`` are below this ([rad]/[m]).
_TOL = 1e-12
#: Longest step of one iteration in [rad]/[m] (no jumping across the torus).
_STEP_MAX = 0.5
_NEWTON = 12
#: Extra starts: radii as fractions of the first distance found; their Gauss–Newton steps; a
#: projected start is on the family when ``|f| < _NEAR ‖∇f‖``; ``_KEEP`` of them go on to
#: Newton.
_SHELLS = np.array([0.5, 1.0])
_GN = 3
_NEAR = 1e-2
_KEEP = 3
#: Picked starts lie at least this fraction of the first distance apart.
_APART = 0.1
#: Configurations solved together (the work arrays stay in cache).
_CHUNK = 1024


def _directions(v: int) -> np.ndarray:
    """Unit directions of the extra starts: 16 around the circle when v = 2, else ±axes."""
    if v == 2:
        a = np.arange(16) * (math.pi / 8)
        return np.column_stack([np.cos(a), np.sin(a)])
    return np.concatenate([np.eye(v), -np.eye(v)])


def _solve(mat: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """``mat⁻¹ rhs`` per row (LAPACK per matrix); a singular row gets NaN (no step)."""
    try:
        return np.linalg.solve(mat, rhs[..., None])[..., 0]
    except np.linalg.LinAlgError:
        bad = ~(np.abs(np.linalg.det(mat)) > 1e-300)
        safe = np.where(bad[:, None, None], np.eye(mat.shape[1]), mat)
        out = np.linalg.solve(safe, rhs[..., None])[..., 0]
        out[bad] = np.nan
        return out


def _project(jet: Eval, x: np.ndarray, steps: int) -> np.ndarray:
    """Gauss–Newton projections ``x ← x − f ∇f / ‖∇f‖²`` towards ``f = 0`` (steps capped)."""
    with np.errstate(all="ignore"):
        for _ in range(steps):
            f, g, _h = jet(x, False)
            step = (f / np.sum(g * g, axis=1))[:, None] * g
            norm = np.linalg.norm(step, axis=1)
            step *= np.minimum(1.0, _STEP_MAX / np.where(norm > 0, norm, 1.0))[:, None]
            x = np.where(np.isfinite(step), x - step, x)
    return x


def project(jet: Eval, x: np.ndarray, steps: int = 60) -> list[np.ndarray | None]:
    """Points of ``f = 0`` reached from the rows of ``x`` (M, v) by :func:`_project`.

    A row that does not reach ``|f| ≤ 1e-12 ‖∇f‖`` within ``steps`` capped steps is ``None``.
    """
    out = _project(jet, np.array(x, dtype=float), steps)
    with np.errstate(all="ignore"):
        f, g, _h = jet(out, False)
        ok = np.abs(f) <= _TOL * np.linalg.norm(g, axis=1)
    return [row if good else None for row, good in zip(out, ok)]


def _newton(jet: Eval, p: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``‖x* − p‖`` (M,) from Newton on ``x − p + λ∇f = 0, f = 0`` started at ``x`` on ``f = 0``.

    Stops a row when ``|f|/‖∇f‖ ≤ _TOL`` and ``‖x − p + λ∇f‖ ≤ _TOL`` (the closest-point
    condition); ``inf`` where it does not within ``_NEWTON`` steps. Rows are independent (the
    same bits whatever the other rows).
    """
    m, v = x.shape
    out, rows = np.full(m, np.inf), np.arange(m)
    eye = np.eye(v)
    with np.errstate(all="ignore"):
        f, g, h = jet(x, True)
        lam = np.sum((p - x) * g, axis=1) / np.sum(g * g, axis=1)
        lam = np.where(np.isfinite(lam), lam, 0.0)
        for _ in range(_NEWTON):
            r1, gn = x - p[rows] + lam[:, None] * g, np.sqrt(np.sum(g * g, axis=1))
            ok = (np.abs(f) <= _TOL * gn) & (np.linalg.norm(r1, axis=1) <= _TOL)
            out[rows[ok]] = np.linalg.norm(x[ok] - p[rows[ok]], axis=1)
            keep = ~ok
            if not keep.any():
                break
            rows, x, lam, f, g, h, r1 = (a[keep] for a in (rows, x, lam, f, g, h, r1))
            mat = np.zeros((rows.size, v + 1, v + 1))
            mat[:, :v, :v] = eye + lam[:, None, None] * h
            mat[:, :v, v] = g
            mat[:, v, :v] = g
            delta = _solve(mat, -np.concatenate([r1, f[:, None]], axis=1))
            norm = np.linalg.norm(delta[:, :v], axis=1)
            scale = np.minimum(1.0, _STEP_MAX / np.where(norm > 0, norm, 1.0))[:, None] * delta
            good = np.isfinite(delta).all(axis=1)
            rows, x, lam = rows[good], x[good] + scale[good, :v], lam[good] + scale[good, v]
            f, g, h = jet(x, True)
    return out


def closest_distance(jet: Eval, p: np.ndarray) -> np.ndarray:
    """Distance (M,) from each row of ``p`` (M, v) to the zero set ``f = 0`` of ``jet``.

    The nearest of several closest-point candidates converged to 1e-12 (:func:`_closest`),
    ``inf`` where none converges, 0 where ``f(p) = 0``. Each distinct row is solved once, on
    its own (the same bits whatever the other rows).
    """
    rows, back = np.unique(p, axis=0, return_inverse=True)
    parts = [_closest(jet, rows[i : i + _CHUNK]) for i in range(0, len(rows), _CHUNK)]
    out = np.concatenate(parts or [np.zeros(0)])
    out[jet(rows, False)[0] == 0.0] = 0.0
    return out[back.reshape(-1)]


def _closest(jet: Eval, p: np.ndarray) -> np.ndarray:
    """Distance (M,) from each row of ``p`` (M, v) to ``f = 0`` (see :func:`closest_distance`).

    Newton from the projection of ``p`` gives a distance ``d`` (where it does not converge,
    ``d`` is the distance to the projection, or ``_STEP_MAX`` where ``∇f(p) = 0``); then
    starts at ``p + s·d·u`` (``s`` in ``_SHELLS``, ``u`` in :func:`_directions`) are
    projected onto ``f = 0``; the nearest, then the nearest ``_APART`` from those picked
    (``_KEEP`` in all), are refined by :func:`_newton`: a nearer branch of the zero set than
    the first one found.
    """
    m, v = p.shape
    x0 = _project(jet, p.copy(), 6)
    best, u = _newton(jet, p, x0), _directions(v)
    moved = np.linalg.norm(x0 - p, axis=1)  # 0 where ∇f(p) = 0: no first step at all
    radius = np.where(np.isfinite(best), best, np.where(moved > 0, moved, _STEP_MAX))
    shell = _SHELLS[:, None, None, None] * radius[None, None, :, None]
    starts = (p[None, None] + shell * u[None, :, None, :]).reshape(-1, m, v)
    x = _project(jet, starts.reshape(-1, v), _GN).reshape(starts.shape)
    with np.errstate(invalid="ignore"):
        d = np.linalg.norm(x - p[None], axis=2)
        f, g, _h = jet(x.reshape(-1, v), False)
        on = (np.abs(f) < _NEAR * np.linalg.norm(g, axis=1)).reshape(d.shape)
    picks, cols = [], np.arange(m)
    for _ in range(_KEEP):  # the nearest, then the nearest apart from those picked
        pick = np.argmin(np.where(on, d, np.inf), axis=0)
        picks.append(x[pick, cols])
        on &= np.linalg.norm(x - picks[-1][None], axis=2) > _APART * radius[None]
    cand = np.concatenate(picks)
    more = _newton(jet, np.tile(p, (_KEEP, 1)), cand).reshape(_KEEP, m)
    return np.minimum(best, more.min(axis=0))
