"""The report's comparison rules: the seeds' expressions parsed, screened numerically, proved.

An entry agrees when it matches at :data:`POINTS` random points (:func:`screen`, :data:`RTOL`)
and ``a − b`` is exactly 0, cheapest proof first (:func:`_zero`).
"""

from __future__ import annotations

import builtins
import hashlib
import math
from collections.abc import Mapping, Sequence
from functools import lru_cache
from types import BuiltinFunctionType
from typing import Any

import numpy as np
import sympy as sp
from sympy.core.rules import Transform
from sympy.parsing.sympy_parser import parse_expr
from sympy.simplify.radsimp import collect_abs

from ..symbolic.checks import evaluate_matrix

__all__ = [
    "POINTS",
    "Q",
    "RTOL",
    "SYMS",
    "equal",
    "factored",
    "fmt",
    "fmt_matrix",
    "matrix_diff",
    "parse",
    "parse_matrix",
    "plain",
    "points_on",
    "screen",
    "tidy",
    "value_at",
    "values",
    "vanishes",
]

#: Random points per symbolic comparison.
POINTS = 8
#: Relative tolerance of a numeric entry comparison (scaled by 1 + |value|).
RTOL = 1e-9

#: The joint symbols ``q1`` … ``q4`` of the seeds' expressions.
Q = [sp.Symbol(f"q{i}", real=True) for i in range(1, 5)]
_NAMES = ["l1", "l2", "l3", "r1", "d2", "d3", "x", "y", "z", "theta", "alpha", "d", "r", "beta"]
#: Every symbol of the seeds' expressions by name (real).
SYMS: dict[str, sp.Symbol] = {s.name: s for s in Q}
SYMS.update({n: sp.Symbol(n, real=True) for n in _NAMES})


#: ``parse``'s names: the symbols, ``pi`` and the ``c23``/``s23`` abbreviations of the seeds.
_LOCALS: dict[str, Any] = {**SYMS, "pi": sp.pi}
for _combo in ("1", "2", "3", "12", "23", "123"):
    _angle = sum(Q[int(k) - 1] for k in _combo)
    _LOCALS.update({f"c{_combo}": sp.cos(_angle), f"s{_combo}": sp.sin(_angle)})


def parse(text: Any) -> sp.Expr:
    """Parse one seed expression (sympy syntax, ``c23``-style abbreviations expanded)."""
    return _parse(str(text))


@lru_cache(maxsize=1)
def _globals() -> dict[str, Any]:
    """``parse_expr``'s namespace, built once: sympy, the builtins, ``max``/``min`` as Max/Min."""
    out: dict[str, Any] = {}
    exec("from sympy import *", out)  # noqa: S102 - sympy's own namespace, as parse_expr does
    out.update({k: v for k, v in vars(builtins).items() if isinstance(v, BuiltinFunctionType)})
    out["max"], out["min"] = sp.Max, sp.Min
    return out


@lru_cache(maxsize=4096)
def _parse(text: str) -> sp.Expr:
    expr = parse_expr(text, local_dict=dict(_LOCALS), global_dict=dict(_globals()))
    return sp.sympify(expr)


def plain(expr: Any) -> Any:
    """``expr`` with every symbol renamed onto this module's real symbols (by name)."""
    expr = sp.sympify(expr)
    rename = {s: SYMS[s.name] for s in expr.free_symbols if SYMS.get(s.name, s) != s}
    return expr.xreplace(rename) if rename else expr


def _rng(key: str) -> np.random.Generator:
    """A generator seeded by ``key`` (SHA-256: the same points in every process)."""
    return np.random.default_rng(int.from_bytes(hashlib.sha256(key.encode()).digest()[:8], "big"))


def value_at(expr: Any, point: Mapping[sp.Symbol, float]) -> float:
    """``expr`` at ``point`` (symbols replaced by numbers), as a float."""
    return float(sp.N(sp.sympify(expr).xreplace(point)))


def _evaluate(exprs: Sequence[Any], env: Mapping[sp.Symbol, np.ndarray]) -> np.ndarray:
    """Real expressions at points: ``(len(exprs), points)``, complex dtype.

    By :func:`~hexapod_kin.symbolic.checks.evaluate_matrix`; what it cannot evaluate by
    ``sympy.lambdify``.
    """
    points = len(next(iter(env.values()))) if env else POINTS
    try:
        return evaluate_matrix([list(exprs)], env, points)[:, 0, :].T.astype(complex)
    except (ValueError, TypeError):  # sympy.lambdify for what the walk does not know
        syms = sorted(env, key=str)
        raw = sp.lambdify(syms, list(exprs), modules=np)(*[env[s] for s in syms])
        return np.array([np.broadcast_to(np.asarray(v, dtype=complex), (points,)) for v in raw])


def screen(a: Sequence[Any], b: Sequence[Any], key: str = "") -> tuple[np.ndarray, np.ndarray]:
    """Numeric screening of entry pairs: ``(a == b, a == −b)`` at :data:`POINTS` random points.

    Points seeded by ``key``: angles uniform in [−π, π] rad, lengths in [0.5, 2]. A pair agrees
    when ``|a − b| ≤ RTOL·(1 + |a| + |b|)`` at every point (NaN or complex never agrees).
    Returns two boolean arrays of ``len(a)``.
    """
    ea, eb = [plain(x) for x in a], [plain(x) for x in b]
    ordered = sorted(set().union(*(e.free_symbols for e in ea + eb)), key=str)
    rng = _rng(key)
    angle = [s.name.startswith("q") or s.name in ("theta", "alpha") for s in ordered]
    spans = [(-math.pi, math.pi) if a else (0.5, 2.0) for a in angle]
    pts = [{s: float(rng.uniform(*w)) for s, w in zip(ordered, spans)} for _ in range(POINTS)]
    args = [np.array([p[s] for p in pts]) for s in ordered]
    with np.errstate(all="ignore"):
        vals = _evaluate(ea + eb, dict(zip(ordered, args))).reshape(2, len(ea), POINTS)
    real = np.all(np.isfinite(vals) & (vals.imag == 0), axis=(0, 2))
    va, vb = vals.real
    tol = RTOL * (1.0 + np.abs(va) + np.abs(vb))
    same = real & np.all(np.abs(va - vb) <= tol, axis=1)
    opposite = real & np.all(np.abs(va + vb) <= tol, axis=1)
    return same, opposite


@lru_cache(maxsize=4096)
def simplified(expr: Any) -> Any:
    """``sympy.simplify(expr)``, remembered for the process (the same truths recur)."""
    return sp.simplify(expr)


def _hollow(x: Any) -> bool:
    """A number times a sum (``2*(a + b)``), which :data:`_HOLLOW` multiplies out."""
    pair = x.is_Mul and len(x.args) == 2
    return bool(pair and x.args[0].is_Number and x.args[1].is_Add and x.is_commutative)


_HOLLOW = Transform(lambda x: sp.Mul(*x.args), _hollow)


@lru_cache(maxsize=4096)
def tidy(expr: Any) -> Any:
    """``expr`` as printed in a verdict: common factors out, the sign in front (exactly equal).

    ``sympy.simplify``'s non-trigonometric steps (the original kept when 1.7 times shorter);
    a power of ``sin``/``cos`` goes to ``simplify`` itself. Print only.
    """
    expr = sp.sympify(expr)
    if not expr.args:
        return expr
    if any(p.base.func in (sp.sin, sp.cos) and p.exp.is_Integer for p in expr.atoms(sp.Pow)):
        return simplified(expr)  # sin² + cos² to fold: that is trigsimp's work
    original = e = collect_abs(sp.signsimp(expr))
    e = sp.factor_terms(e, sign=False).xreplace(_HOLLOW)
    if e.could_extract_minus_sign():
        n, d = sp.fraction(e)
        if d != 0:
            e = sp.signsimp(-n / (-d))
    return original if sp.count_ops(e) > 1.7 * sp.count_ops(original) else e


def _reduces_to_zero(poly: Any) -> bool:
    """True when the expanded ``poly`` is 0 modulo ``sin(x)² + cos(x)² = 1`` (a proof).

    Its remainder by ``s² + c² − 1`` in ``s = sin x``, angle by angle; a non-zero one proves
    nothing (False), as does anything but ``sin``/``cos`` of plain symbols.
    """
    trig = poly.atoms(sp.sin, sp.cos)
    if not trig or any(not f.args[0].is_Symbol for f in trig):
        return False
    angles = sorted({f.args[0] for f in trig}, key=str)
    s = [sp.Dummy(f"s_{x}") for x in angles]
    c = [sp.Dummy(f"c_{x}") for x in angles]
    rep = {sp.sin(x): sk for x, sk in zip(angles, s)}
    rep.update({sp.cos(x): ck for x, ck in zip(angles, c)})
    e = sp.expand(poly.xreplace(rep))
    if e.has(sp.sin, sp.cos):
        return False
    try:
        for sk, ck in zip(s, c):
            if e.has(sk):
                e = sp.expand(sp.rem(sp.Poly(e, sk), sp.Poly(sk**2 + ck**2 - 1, sk)).as_expr())
    except Exception:  # noqa: BLE001 - not a polynomial sympy divides: simplify decides
        return False
    return bool(e == 0 or (e.is_Number and e.is_zero))


@lru_cache(maxsize=4096)
def _zero(diff: Any) -> bool:
    """True when ``diff`` is exactly 0: expanded, then :func:`_reduces_to_zero`, then simplify."""
    d = sp.expand(sp.expand_trig(diff))
    return bool(d == 0 or _reduces_to_zero(d) or simplified(d) == 0)


def equal(a: Any, b: Any, key: str = "") -> bool:
    """True when ``a == b`` at :data:`POINTS` random points (:func:`screen`), then exactly."""
    a, b = plain(a), plain(b)
    return bool(screen([a], [b], key)[0][0]) and _zero(a - b)


def factored(det: Any, q: Sequence[Any], sigmas: Sequence[str], key: str = "") -> Any:
    """``det`` factored as :func:`~hexapod_kin.symbolic.derive` does (else factor(simplify))."""
    from ..symbolic.core import trig_factor

    qs = tuple(plain(s) for s in q)
    try:
        const, factors = trig_factor(det, qs, sigmas)
        out = sp.factor(const * sp.Mul(*[f**m for f, m in factors]))
        if equal(det, out, key + " factored"):
            return out
    except Exception:  # noqa: BLE001 - cannot factor that way: factor(simplify(det))
        pass
    return sp.factor(sp.simplify(det))


@lru_cache(maxsize=4096)
def fmt(expr: Any) -> str:
    """``expr`` as text (``sympy.sstr``, short floats), remembered (the same entries recur)."""
    return sp.sstr(sp.sympify(expr), full_prec=False)


def fmt_matrix(m: sp.Matrix) -> str:
    """A matrix as ``[a, b; c, d]`` (:func:`fmt` entries)."""
    return "[" + "; ".join(", ".join(fmt(v) for v in m.row(i)) for i in range(m.rows)) + "]"


def matrix_diff(seed: sp.Matrix, truth: sp.Matrix, key: str, explain: bool = True) -> list[str]:
    """Differing entries, 1-based, with a sign-slip note (``explain=False``: empty strings)."""
    a, b = [plain(x) for x in seed], [plain(x) for x in truth]
    same, opposite = screen(a, b, key)
    out = []
    for k, (x, y) in enumerate(zip(a, b)):
        if same[k] and _zero(x - y):
            continue
        if not explain:
            out.append("")
            continue
        i, j = divmod(k, truth.cols)
        note = " (sign slip)" if opposite[k] and _zero(x + y) else ""
        out.append(f"({i + 1},{j + 1}): seed {fmt(x)} vs {fmt(tidy(y))}{note}")
    return out


def parse_matrix(rows: Any) -> sp.Matrix:
    """A sympy matrix from the claim's nested list of strings."""
    return sp.Matrix([[parse(v) for v in row] for row in rows])


def values(expr: Any, qs: np.ndarray) -> np.ndarray:
    """A real expression of ``q1 … q4`` at each row of ``qs`` (an imaginary value is NaN)."""
    expr = plain(expr)
    qs = np.atleast_2d(np.asarray(qs, dtype=float))
    env = {s: qs[:, k] for k, s in enumerate(Q[: qs.shape[1]])}
    with np.errstate(all="ignore"):
        v = _evaluate([expr], env)[0]
    return np.where(v.imag == 0, v.real, np.nan)


def points_on(
    expr: Any, nq: int, key: str, count: int = 5, fixed: Mapping[int, float] | None = None
) -> np.ndarray:
    """Up to ``count`` joint vectors (nq,) on the zero set of ``expr`` (``fixed``: 0-based pins).

    Random joints; the last one ``expr`` depends on, a random root in [−π, π].
    """
    from ..symbolic.core import single_joint_roots

    expr = plain(expr)
    rng = _rng(key)
    deps = [k for k in range(nq) if Q[k] in expr.free_symbols]
    pts: list[np.ndarray] = []
    for _ in range(40 * count):
        q = rng.uniform(-math.pi, math.pi, nq)
        for k, v in (fixed or {}).items():
            q[k] = v
        if deps:
            var = deps[-1]

            def f(x: np.ndarray, q: np.ndarray = q, var: int = var) -> np.ndarray:
                qs = np.repeat(q[None, :], len(x), axis=0)
                qs[:, var] = x
                return values(expr, qs)

            roots = single_joint_roots(f, -math.pi, math.pi)
            if not roots:
                continue
            q[var] = roots[int(rng.integers(len(roots)))]
        elif abs(value_at(expr, {})) > 1e-12:
            break
        pts.append(q)
        if len(pts) >= count:
            break
    return np.array(pts).reshape(-1, nq)


def vanishes(expr: Any, pts: np.ndarray, scale: float = 1.0, tol: float = 1e-7) -> bool:
    """True when ``expr`` is ~0 at every point (relative to ``scale``)."""
    if not len(pts):
        return False
    return bool(np.all(np.abs(values(expr, pts)) <= tol * max(scale, 1e-300)))
