"""Singular families as numbers: residuals, exact distances, labels — without waiting on sympy.

A family is the zero set of one factor of ``det J`` (or of ``det(J Jᵀ)``), derived by
:func:`hexapod_kin.symbolic.derive` from the chain's Khalil table (the model's own, or the one
:meth:`hexapod_kin.params.Chain.from_urdf` recovers). Deriving is sympy work, done only when
asked (:func:`families_for` with ``derive=True``, within a time budget); the result is checked
against the model's own Jacobian, turned into text (lengths substituted) and kept on disk
(:func:`cache_dir`), so later scans in any process read it back without importing sympy.

The text is parsed once and checked against a whitelist (numbers, ``q1..qn``, ``pi``,
``+ - * / **`` with a numeric exponent, ``sin cos tan sqrt Abs``), then turned into a tree of
numpy closures that evaluates the factor with its gradient and Hessian over a whole array of
configurations (forward-mode second-order derivatives): nothing is ever ``eval``-ed.
"""

from __future__ import annotations

import ast
import hashlib
import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._io import atomic_write, cache_root
from ..exceptions import HexapodKinError, ParameterError

__all__ = ["Family", "Families", "families_for", "cache_dir"]

_VERSION = 2
#: Largest relative difference between symbolic and numeric ``det`` accepted as equal.
_MATCH_RTOL = 1e-6
_TWO_PI = 2.0 * math.pi

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
    return (
        lambda x: x**c,
        lambda x: c * x ** (c - 1.0),
        lambda x: c * (c - 1.0) * x ** (c - 2.0),
    )


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


def _number(node: ast.AST) -> float | None:
    """The value of a numeric constant (``-2``, ``pi``, ``1/2`` stay non-numeric but ``2.5``)."""
    if isinstance(node, ast.Constant) and type(node.value) in (int, float):
        return float(node.value)
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        inner = _number(node.operand)
        return None if inner is None else (-inner if isinstance(node.op, ast.USub) else inner)
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
        return lambda env, hess, c=num: (c, None, None)
    if isinstance(node, ast.Name):
        if node.id == "pi":
            return lambda env, hess: (math.pi, None, None)
        k = int(node.id[1:]) - 1 if node.id[:1] == "q" and node.id[1:].isdigit() else -1
        if k not in pos:
            raise _refuse(text, f"the name {node.id!r}")
        i = pos[k]
        unit = np.zeros(len(pos))
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
            return lambda env, hess: _mul(
                left(env, hess), _chain(_RECIPROCAL, right(env, hess), hess), hess
            )
        raise _refuse(text, type(node.op).__name__)
    if (
        isinstance(node, ast.Call)
        and isinstance(node.func, ast.Name)
        and node.func.id in _UNARY
        and len(node.args) == 1
        and not node.keywords
    ):
        arg = _build(node.args[0], text, pos)
        fn = _UNARY[node.func.id]
        return lambda env, hess: _chain(fn, arg(env, hess), hess)
    raise _refuse(text, type(node).__name__)


def _compile(text: str, variables: tuple[int, ...]) -> Node:
    """Parse ``text`` once into a jet evaluator over ``variables`` (raises ParameterError)."""
    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError as err:
        raise ParameterError(f"family expression {text!r} does not parse: {err.msg}") from None
    return _build(tree.body, text, {k: i for i, k in enumerate(variables)})


# ------------------------------------------------------------------------ closest points
#: Stop when ``|f|/‖∇f‖`` and the tangential part of ``x − p`` are below this ([rad]/[m]).
_TOL = 1e-12
#: Longest step of one iteration in [rad]/[m] (no jumping across the torus).
_STEP_MAX = 0.5
_NEWTON = 12
#: Extra starts: radii as fractions of the first distance found, and how many of the
#: projected starts of a configuration go on to Newton.
_SHELLS = np.array([0.5, 1.0])
_KEEP = 3
_GN = 3
_NEAR = 1e-2
#: Configurations solved together (the work arrays stay in cache).
_CHUNK = 1024
Eval = Callable[[np.ndarray, bool], Jet]


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


def _newton(jet: Eval, p: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``‖x* − p‖`` (M,) from Newton on ``x − p + λ∇f = 0, f = 0`` started at ``x`` on ``f = 0``.

    Stops a row when ``|f|/‖∇f‖ ≤ _TOL`` and ``‖x − p + λ∇f‖ ≤ _TOL`` (the closest-point
    condition); ``inf`` where it does not within ``_NEWTON`` steps. Rows are independent (the
    same bits whatever the other rows).
    """
    m, v = x.shape
    out = np.full(m, np.inf)
    rows = np.arange(m)
    eye = np.eye(v)
    with np.errstate(all="ignore"):
        f, g, h = jet(x, True)
        lam = np.sum((p - x) * g, axis=1) / np.sum(g * g, axis=1)
        lam = np.where(np.isfinite(lam), lam, 0.0)
        for _ in range(_NEWTON):
            r1 = x - p[rows] + lam[:, None] * g
            gn = np.sqrt(np.sum(g * g, axis=1))
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


def _distance(jet: Eval, p: np.ndarray) -> np.ndarray:
    """Distance (M,) from each row of ``p`` (M, v) to ``f = 0``: the global closest point.

    Newton from the projection of ``p`` gives a distance ``d`` (or, where it does not
    converge, ``d`` is the distance to the projection); then starts at
    ``p + s·d·u`` (``s`` in ``_SHELLS``, ``u`` in :func:`_directions`) are projected onto
    ``f = 0`` and the ``_KEEP`` nearest per row refined by :func:`_newton` (a nearer branch
    of the family than the first one found); the nearest converged candidate counts.
    """
    m, v = p.shape
    x0 = _project(jet, p.copy(), 6)
    best = _newton(jet, p, x0)
    u = _directions(v)
    radius = np.where(np.isfinite(best), best, np.linalg.norm(x0 - p, axis=1))
    shell = _SHELLS[:, None, None, None] * radius[None, None, :, None]
    starts = (p[None, None] + shell * u[None, :, None, :]).reshape(-1, m, v)
    x = _project(jet, starts.reshape(-1, v), _GN).reshape(starts.shape)
    with np.errstate(invalid="ignore"):
        d = np.linalg.norm(x - p[None], axis=2)
        f, g, _h = jet(x.reshape(-1, v), False)
        on = (np.abs(f) < _NEAR * np.linalg.norm(g, axis=1)).reshape(d.shape)
    pick = np.argsort(np.where(on, d, np.inf), axis=0, kind="stable")[:_KEEP]  # (keep, M)
    cand = np.take_along_axis(x, pick[..., None], axis=0).reshape(-1, v)
    more = _newton(jet, np.tile(p, (_KEEP, 1)), cand).reshape(_KEEP, m)
    return np.minimum(best, more.min(axis=0))


# ------------------------------------------------------------------------ one family
@dataclass(frozen=True)
class Family:
    """One singular family, as numbers (no sympy objects).

    Attributes:
        name: A readable label, e.g. ``"q3 = 0 (mod 2*pi)"``.
        equation: The equation as text (lengths symbolic), e.g. ``"Eq(q3, 0)"``.
        variables: Indices (0-based) of the joints the factor depends on.
        joint: Index of the joint when the family is ``q_k = value``, else ``None``.
        value: That value in [rad] or [m] (``None`` for implicit families).
        periodic: True when ``value`` repeats every 2π (revolute joint).
        factor: The factor with the lengths substituted (text, in ``q1..qn`` of
            :attr:`variables` only), zero on the family.

    """

    name: str
    equation: str
    variables: tuple[int, ...]
    joint: int | None
    value: float | None
    periodic: bool
    factor: str
    _jet: Any = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        """Compile the factor once (refusing anything outside the grammar)."""
        object.__setattr__(self, "_jet", _compile(self.factor, self.variables))

    def _eval(self, x: np.ndarray, hess: bool) -> Jet:
        """Value (M,), gradient (M, v), Hessian (M, v, v) or None at the variables ``x``."""
        f, g, h = self._jet([x[:, i] for i in range(x.shape[1])], hess)
        m, v = x.shape
        f = np.broadcast_to(np.asarray(f, dtype=float), (m,))
        g = np.zeros((m, v)) if g is None else np.broadcast_to(g, (m, v))
        if hess:
            h = np.zeros((m, v, v)) if h is None else np.broadcast_to(h, (m, v, v))
        return f, g, h

    def residual(self, q: Any) -> np.ndarray:
        """Signed residual at ``q`` (…, nq): the factor; the wrapped offset for ``q_k = v``."""
        qa = np.asarray(q, dtype=float)
        if self.joint is not None and self.value is not None:
            d = qa[..., self.joint] - self.value
            return np.remainder(d + math.pi, _TWO_PI) - math.pi if self.periodic else d
        x = qa[..., list(self.variables)].reshape(-1, len(self.variables))
        return np.asarray(self._eval(x, False)[0]).reshape(qa.shape[:-1])

    def distance(self, q: Any) -> np.ndarray:
        """Joint-space distance (…,) from ``q`` to the family, in [rad]/[m]: the closest point.

        ``q_k = value``: ``|q_k − value|`` (wrapped for a revolute joint). Implicit families:
        ``min ‖x − q‖`` over ``f(x) = 0`` in the family's variables (the other joints do not
        change ``f``), found by :func:`_distance` to 1e-12. Revolute angles wrap by
        themselves: ``f`` is 2π-periodic in them, so the nearest point of the unwrapped zero
        set is the nearest of all its 2π copies.
        """
        qa = np.asarray(q, dtype=float)
        if self.joint is not None and self.value is not None:
            return np.abs(self.residual(qa))
        p = np.ascontiguousarray(qa[..., list(self.variables)].reshape(-1, len(self.variables)))
        if p.shape[0] == 0:
            return np.zeros(qa.shape[:-1])
        best = np.concatenate(
            [_distance(self._eval, p[i : i + _CHUNK]) for i in range(0, p.shape[0], _CHUNK)]
        )
        best[self._eval(p, False)[0] == 0.0] = 0.0
        return best.reshape(qa.shape[:-1])

    def to_dict(self, joint_names: tuple[str, ...] | None = None) -> dict[str, Any]:
        """JSON-ready dict (joint by name when ``joint_names`` is given)."""
        joint: Any = self.joint
        if joint is not None and joint_names is not None:
            joint = joint_names[joint]
        return {
            "name": self.name,
            "equation": self.equation,
            "variables": list(self.variables),
            "joint": joint,
            "value": self.value,
            "periodic": self.periodic,
            "factor": self.factor,
        }


@dataclass(frozen=True)
class Families:
    """The singular families of one model and row selection, and where they came from.

    Attributes:
        families: The families (empty when none are known).
        origin: ``"derived"`` (sympy, this call), ``"cache"`` (disk), or ``"none"``.
        reason: Why there are none (empty when there are).
        key: The cache key (table and rows), or ``""`` without a table.

    """

    families: tuple[Family, ...]
    origin: str
    reason: str
    key: str = ""

    def nearest(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The nearest and second-nearest families of ``q`` (M, nq) and the distances to them.

        Returns:
            ``(index, distance, second_index, second_distance)``, each (M,); −1 / inf where
            there is no (second) family.

        """
        m = q.shape[0]
        none = np.full(m, -1, dtype=np.int64), np.full(m, np.inf)
        if not self.families or m == 0:
            return none[0], none[1], none[0].copy(), none[1].copy()
        dist = np.stack([fam.distance(q) for fam in self.families], axis=1)
        dist = np.where(np.isnan(dist), np.inf, dist)
        order = np.argsort(dist, axis=1, kind="stable")
        rows = np.arange(m)
        best = order[:, 0].astype(np.int64)
        if dist.shape[1] < 2:
            return best, dist[rows, best], none[0].copy(), none[1].copy()
        second = order[:, 1].astype(np.int64)
        return best, dist[rows, best], second, dist[rows, second]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return {
            "families": [f.to_dict() for f in self.families],
            "origin": self.origin,
            "reason": self.reason,
            "key": self.key,
        }


# ------------------------------------------------------------------------ tables and keys
def cache_dir() -> Path:
    """Where derived families are kept: :func:`hexapod_kin._io.cache_root` ``("families")``."""
    return cache_root("families")


def _table(model: Any) -> tuple[Any, str]:
    """The model's Khalil chain (its own, or recovered from the URDF) and why not, if none."""

    def build() -> tuple[Any, str]:
        from ..params import Chain

        params = model.params
        if isinstance(params, Chain) and model.nq == params.nq:
            return params, ""
        try:
            chain = Chain.from_urdf(model)
        except HexapodKinError as err:
            return None, f"no Khalil table: Chain.from_urdf refused the chain ({err})"
        if chain.nq != model.nq:
            return None, f"the recovered table has {chain.nq} joints, the model {model.nq}"
        return chain, ""

    return model.cached("singularity.table", build)


def _key(chain: Any, rows: tuple[str, ...]) -> str:
    table = [(r.sigma, repr(r.alpha), repr(r.d), repr(r.theta), repr(r.r)) for r in chain.rows]
    text = json.dumps(
        {
            "v": _VERSION,
            "rows": list(rows),
            "table": table,
            "base": repr(getattr(chain, "base_pose", None)),
            "tool": repr(getattr(chain, "tool", None)),
        },
        sort_keys=True,
    )
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def _from_json(data: dict[str, Any], nq: int) -> tuple[Family, ...]:
    return tuple(
        Family(
            name=str(f["name"]),
            equation=str(f["equation"]),
            variables=tuple(int(v) for v in f["variables"]),
            joint=None if f["joint"] is None else int(f["joint"]),
            value=None if f["value"] is None else float(f["value"]),
            periodic=bool(f["periodic"]),
            factor=str(f["factor"]),
        )
        for f in data["families"]
    )


def _read_cache(key: str, nq: int) -> tuple[Family, ...] | None:
    try:
        data = json.loads((cache_dir() / f"{key}.json").read_text(encoding="utf-8"))
        if data.get("v") != _VERSION or data.get("nq") != nq:
            return None
        return _from_json(data, nq)
    except (OSError, KeyError, TypeError, ValueError):  # missing or corrupt: derive again
        return None


def _write_cache(key: str, nq: int, fams: tuple[Family, ...]) -> None:
    data = {"v": _VERSION, "nq": nq, "families": [f.to_dict() for f in fams]}
    try:
        cache_dir().mkdir(parents=True, exist_ok=True)
        atomic_write(cache_dir() / f"{key}.json", json.dumps(data, indent=1))
    except (OSError, HexapodKinError):
        pass  # a read-only cache only costs the next process a derivation


# ------------------------------------------------------------------------ deriving
_NO_FACTOR = "the factored det has no factor that depends on q"


class _Miss(Exception):
    """Not in the disk cache (nothing is stored in the model's cache then)."""


def _derive_errors() -> tuple[type[BaseException], ...]:
    """Errors a derivation may end with; anything else is a bug and propagates."""
    import sympy

    return (
        HexapodKinError,
        TimeoutError,
        NotImplementedError,
        RecursionError,
        sympy.PolynomialError,
        sympy.polys.polyerrors.PolificationFailed,
    )


def _numeric_families(deriv: Any, model: Any, rows: tuple[str, ...]) -> tuple[Family, ...]:
    """Check ``deriv`` against the model's Jacobian and turn its families into text forms."""
    from .measure import measures

    qs = model.random_q(16, seed=4242)
    res = [measures(model, q, rows) for q in qs]
    if deriv.det is not None:
        sym = np.abs(deriv.function(deriv.det)(qs))
        num = np.abs([m.det for m in res])
    elif deriv.gram is not None:
        sym = np.abs(deriv.function(deriv.gram)(qs))
        num = np.array([m.manipulability for m in res]) ** 2
    else:
        raise ParameterError("the derivation has no determinant to check the families against")
    err = float(np.max(np.abs(sym - num))) / max(float(np.max(num)), 1e-300)
    if not err <= _MATCH_RTOL:
        raise ParameterError(
            f"the symbolic det of the table differs from the model's (relative {err:.1e}): "
            "the table's frames do not match the model's Jacobian rows",
            parameter="rows",
            value=rows,
        )
    return tuple(
        Family(
            name=str(fam.name),
            equation=str(fam.equation),
            variables=tuple(int(v) for v in fam.variables),
            joint=fam.joint,
            value=None if fam.value is None else float(fam.value),
            periodic=bool(fam.periodic),
            factor=str(deriv.numeric(fam.factor)),
        )
        for fam in deriv.families
    )


def families_for(
    model: Any, rows: tuple[str, ...], *, derive: bool = False, budget: float = 10.0
) -> Families:
    """The singular families of ``model`` for the Jacobian rows ``rows``.

    Args:
        model: A loaded model.
        rows: Row names (see :mod:`.rows`).
        derive: Derive them with sympy (within ``budget``) when they are not on disk yet.
            Without it, only families already derived (this process or the disk cache) are
            returned, so the call never waits on sympy.
        budget: Time budget of the derivation in [s].

    Returns:
        The :class:`Families` (empty with a reason when none are available).

    Raises:
        ParameterError: ``budget`` not a finite value > 0.

    """
    if not (isinstance(budget, (int, float)) and math.isfinite(budget) and budget > 0):
        raise ParameterError(
            f"budget={budget!r}: a finite time > 0 s is required",
            parameter="budget",
            value=budget,
            allowed="> 0 s",
        )
    chain, why = _table(model)
    if chain is None:
        return Families((), "none", why)
    key = _key(chain, rows)
    mem = f"singularity.families.{key}"

    def load() -> tuple[Family, ...]:
        fams = _read_cache(key, model.nq)
        if fams is None:
            raise _Miss
        return fams

    try:
        hit = model.cached(mem, load)
        return Families(hit, "cache", "" if hit else _NO_FACTOR, key)
    except _Miss:
        pass
    if not derive:
        return Families(
            (),
            "none",
            "families not derived yet (pass families=True, or run `hexapod-kin derive`; "
            "they are then kept on disk)",
            key,
        )
    from .. import symbolic

    try:
        deriv = symbolic.derive(chain, rows=rows, budget=float(budget))
        incomplete = "; ".join(deriv.incomplete)
        if incomplete and not deriv.families:
            return Families((), "none", f"derivation incomplete: {incomplete}", key)
        fams = _numeric_families(deriv, model, rows)
    except _derive_errors() as err:
        return Families((), "none", f"derivation failed: {type(err).__name__}: {err}", key)
    if incomplete:  # partial families: used, but not kept (a later call may finish)
        return Families(fams, "derived", f"derivation incomplete: {incomplete}", key)
    _write_cache(key, model.nq, fams)
    model.cached(mem, lambda: fams)
    return Families(fams, "derived", "" if fams else _NO_FACTOR, key)
