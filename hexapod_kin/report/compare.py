"""Computed verdicts for the seeds' claims (``claims.toml``): nothing here is written by hand.

Each claim of :data:`claims.toml <hexapod_kin.report>` is compared with hexapod_kin's own value:

* ``table`` — the seed's Khalil rows against the preset's rows (lengths scaled by the claim's
  ``unit``); a different α is reported with what it does to the FK (checked symbolically);
* ``matrix`` — a symbolic matrix (``^{j-1}T_j``, ``^0T_j``, ``p``, ``J``) against
  :func:`hexapod_kin.symbolic.derive`: every entry at :data:`POINTS` random points seeded by
  the claim (:func:`screen`: numpy, relative tolerance :data:`RTOL`), then
  ``sympy.simplify(a - b) == 0`` for the entries that agree; sympy simplifies a differing
  entry only to explain it;
  a wrong matrix is also tested against the other α2 sign, the product of the seed's own
  factors and the derivative of the seed's own ``p`` to say where the slip comes from;
* ``det`` — ``simplify(seed − det J) == 0`` (and ``±`` / scale when not);
* ``families`` — the seed's singular sets (residual expressions) against the factors of
  ``det J``: points sampled on every true family must zero a seed residual (else *missing*),
  points on every seed set must zero ``det J`` (else *not singular*);
* ``generic`` — the seed's generic transform against :func:`hexapod_kin.symbolic.khalil_matrix`;
* ``methods_equal`` — :attr:`Derivation.methods_agree`;
* ``fk`` / ``ik`` / ``schedule`` — numbers against the Pinocchio model and
  :func:`hexapod_kin.ik.analytic`; the seed's IK formulas are evaluated as written;
* ``bound`` — a measured quantity of an experiment (``step.*``, ``pendulum.*``) within ``tol``
  of the claimed value.

The symbolic verdicts are kept on disk (:mod:`.cache`), keyed by the claim, hexapod_kin's
expressions and the package source.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable, Mapping, Sequence
from functools import lru_cache
from typing import Any

import numpy as np
import sympy as sp
from sympy.parsing.sympy_parser import parse_expr

from .data import CLAIMS_FILE, Claim, Verdict, load_claims

__all__ = [
    "CLAIMS_FILE",
    "POINTS",
    "RTOL",
    "Claim",
    "Verdict",
    "evaluate",
    "load_claims",
    "parse",
]

#: Random points per symbolic comparison.
POINTS = 8
#: Relative tolerance of a numeric entry comparison (scaled by 1 + |value|).
RTOL = 1e-9

_Q = [sp.Symbol(f"q{i}", real=True) for i in range(1, 5)]
_NAMES = ["l1", "l2", "l3", "r1", "d2", "d3", "x", "y", "z", "theta", "alpha", "d", "r", "beta"]
_SYMS: dict[str, sp.Symbol] = {s.name: s for s in _Q}
_SYMS.update({n: sp.Symbol(n, real=True) for n in _NAMES})


def _locals() -> dict[str, Any]:
    loc: dict[str, Any] = dict(_SYMS)
    q = _Q
    for combo in ("1", "2", "3", "12", "23", "123"):
        angle = sum(q[int(k) - 1] for k in combo)
        loc[f"c{combo}"] = sp.cos(angle)
        loc[f"s{combo}"] = sp.sin(angle)
    loc["pi"] = sp.pi
    return loc


_LOCALS = _locals()


def parse(text: Any) -> sp.Expr:
    """Parse one seed expression (sympy syntax, ``c23``-style abbreviations expanded)."""
    return _parse(str(text))


@lru_cache(maxsize=4096)
def _parse(text: str) -> sp.Expr:
    return sp.sympify(parse_expr(text, local_dict=dict(_LOCALS)))


def plain(expr: Any) -> Any:
    """``expr`` with every symbol renamed onto this module's real symbols (by name)."""
    expr = sp.sympify(expr)
    return expr.xreplace({s: _SYMS.get(s.name, s) for s in expr.free_symbols})


# ---------------------------------------------------------------------- comparison helpers
def _rng(key: str) -> np.random.Generator:
    """A generator seeded by ``key`` (SHA-256: the same points in every process)."""
    return np.random.default_rng(int.from_bytes(hashlib.sha256(key.encode()).digest()[:8], "big"))


def _point(symbols: Any, rng: np.random.Generator) -> dict[sp.Symbol, float]:
    out = {}
    for s in symbols:
        if s.name.startswith("q") or s.name in ("theta", "alpha"):
            out[s] = float(rng.uniform(-math.pi, math.pi))
        else:
            out[s] = float(rng.uniform(0.5, 2.0))
    return out


def _num(expr: Any, point: Mapping[sp.Symbol, float]) -> float:
    return float(sp.N(sp.sympify(expr).xreplace(point)))


def screen(a: Sequence[Any], b: Sequence[Any], key: str = "") -> tuple[np.ndarray, np.ndarray]:
    """Numeric screening of entry pairs: ``(a == b, a == −b)`` at :data:`POINTS` random points.

    Every expression is evaluated (``sympy.lambdify`` to numpy, float64) at the same
    :data:`POINTS` points, seeded by ``key``: joint angles, ``theta`` and ``alpha`` uniform in
    [−π, π] rad, every other symbol (a length) uniform in [0.5, 2]. A pair agrees when
    ``|a − b| ≤ RTOL·(1 + |a| + |b|)`` at every point (a NaN or complex value never agrees).

    Args:
        a: Expressions (a flat sequence, e.g. a matrix in row-major order).
        b: Expressions, as many as ``a``.
        key: Seed text of the points.

    Returns:
        Two boolean arrays of ``len(a)``: equal, and equal with the opposite sign.

    """
    ea, eb = [plain(x) for x in a], [plain(x) for x in b]
    syms: set[sp.Symbol] = set()
    for e in ea + eb:
        syms |= e.free_symbols
    ordered = sorted(syms, key=str)
    rng = _rng(key)
    pts = [_point(ordered, rng) for _ in range(POINTS)]
    args = [np.array([p[s] for p in pts]) for s in ordered]
    with np.errstate(all="ignore"):
        raw = sp.lambdify(ordered, ea + eb, modules="numpy")(*args)
        vals = np.array([np.broadcast_to(np.asarray(v, dtype=complex), (POINTS,)) for v in raw])
    vals = vals.reshape(2, len(ea), POINTS)
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


@lru_cache(maxsize=4096)
def _zero(diff: Any) -> bool:
    """``expand(expand_trig(diff)) == 0`` or ``simplify(...) == 0``."""
    d = sp.expand(sp.expand_trig(diff))
    return bool(d == 0 or simplified(d) == 0)


def equal(a: Any, b: Any, key: str = "") -> bool:
    """True when ``a == b`` at :data:`POINTS` random points and ``simplify(a − b) == 0``.

    The symbolic proof runs only when the numeric screening (:func:`screen`) passes.
    """
    a, b = plain(a), plain(b)
    return bool(screen([a], [b], key)[0][0]) and _zero(a - b)


def _fmt(expr: Any) -> str:
    return sp.sstr(sp.sympify(expr), full_prec=False)


def _fmt_matrix(m: sp.Matrix) -> str:
    return "[" + "; ".join(", ".join(_fmt(v) for v in m.row(i)) for i in range(m.rows)) + "]"


def matrix_diff(seed: sp.Matrix, truth: sp.Matrix, key: str, explain: bool = True) -> list[str]:
    """Differing entries of two same-shape matrices, 1-based, with a sign-slip note.

    An entry agrees when it passes the numeric screening and ``simplify(a − b) == 0``; sympy
    simplifies only the entries that differ (their explanation). With ``explain=False`` the
    list holds one empty string per differing entry (only the count is wanted).
    """
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
        out.append(f"({i + 1},{j + 1}): seed {_fmt(x)} vs {_fmt(simplified(y))}{note}")
    return out


def parse_matrix(rows: Any) -> sp.Matrix:
    """A sympy matrix from the claim's nested list of strings."""
    return sp.Matrix([[parse(v) for v in row] for row in rows])


# ---------------------------------------------------------------------- family sampling
def _roots(f: Callable[[np.ndarray], np.ndarray], grid: np.ndarray) -> list[float]:
    vals = f(grid)
    out: list[float] = []
    for k in np.flatnonzero(vals == 0.0):
        out.append(float(grid[k]))
    for k in np.flatnonzero(np.sign(vals[:-1]) * np.sign(vals[1:]) < 0):
        lo, hi = float(grid[k]), float(grid[k + 1])
        flo = float(f(np.array([lo]))[0])
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            fm = float(f(np.array([mid]))[0])
            if np.sign(fm) == np.sign(flo):
                lo, flo = mid, fm
            else:
                hi = mid
        out.append(0.5 * (lo + hi))
    return out


def points_on(
    expr: Any, nq: int, key: str, count: int = 5, fixed: Mapping[int, float] | None = None
) -> np.ndarray:
    """Up to ``count`` joint vectors (nq,) on the zero set of ``expr`` (numbers for lengths).

    Random values for every joint but the last one ``expr`` depends on, which is found by
    bracketing on ``[−π, π]`` and bisection; ``fixed`` pins joints (0-based) to values.
    """
    expr = plain(expr)
    rng = _rng(key)
    deps = [k for k in range(nq) if _Q[k] in expr.free_symbols]
    pts: list[np.ndarray] = []
    for _ in range(40 * count):
        q = rng.uniform(-math.pi, math.pi, nq)
        for k, v in (fixed or {}).items():
            q[k] = v
        if deps:
            var = deps[-1]
            sub = {_Q[k]: float(q[k]) for k in range(nq) if k != var}
            g = sp.lambdify(_Q[var], expr.xreplace(sub), "numpy")

            def f(x: np.ndarray, g: Any = g) -> np.ndarray:
                return np.broadcast_to(np.asarray(g(x), dtype=float), x.shape)

            roots = _roots(f, np.linspace(-math.pi, math.pi, 721))
            if not roots:
                continue
            q[var] = roots[int(rng.integers(len(roots)))]
        elif abs(_num(expr, {})) > 1e-12:
            break
        pts.append(q)
        if len(pts) >= count:
            break
    return np.array(pts).reshape(-1, nq)


def vanishes(expr: Any, pts: np.ndarray, scale: float = 1.0, tol: float = 1e-7) -> bool:
    """True when ``expr`` is ~0 at every point (relative to ``scale``)."""
    expr = plain(expr)
    for q in pts:
        val = _num(expr, {_Q[k]: float(v) for k, v in enumerate(q)})
        if abs(val) > tol * max(scale, 1e-300):
            return False
    return len(pts) > 0


# ---------------------------------------------------------------------- entry point
def evaluate(claims: list[Claim], ctx: Any, cache: bool = True) -> list[Verdict]:
    """Compute every claim's verdict against ``ctx`` (a :class:`~.checks.Context`).

    A comparison that raises gives status ``"error"`` with the exception (never skipped).
    With ``cache`` the symbolic verdicts are read from (and written to) the disk cache of
    :mod:`.cache`, keyed by the claim's data and hexapod_kin's expressions.
    """
    from . import cache as _cache
    from .checks import CHECKS

    out = []
    for claim in claims:
        try:
            check = CHECKS[claim.kind]
            digest = None
            if cache:
                try:
                    digest = _cache.key(claim, ctx)
                except Exception:  # noqa: BLE001 - no key: the check runs (and reports)
                    digest = None
            verdict = _cache.load(digest, claim) if digest else None
            if verdict is None:
                verdict = check(claim, ctx)
                if digest:
                    _cache.store(digest, verdict)
            out.append(verdict)
        except Exception as exc:  # recorded, reported, and failed by the CLI and the test
            out.append(
                Verdict(
                    claim.id,
                    claim.seed,
                    claim.where,
                    claim.kind,
                    str(claim.data.get("value")),
                    "",
                    "error",
                    f"{type(exc).__name__}: {exc}",
                    "",
                )
            )
    return out
