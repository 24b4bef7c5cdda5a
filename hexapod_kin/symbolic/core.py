"""The sympy work behind :func:`hexapod_kin.symbolic.derive`, in stages (no caching, no budget).

Speed comes from structure, not ``simplify``: products expanded step by step; ``det J`` in a
middle joint frame (a 6×6 at a wrist centre is block-triangular); the determinant as a
polynomial in ``s_i``, ``c_i`` (:func:`~._trigpoly.ring_det`) factored *before* reducing
modulo ``s_i² + c_i² = 1``, each factor then reduced and factored again; the finest split of a
few frames wins.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from fractions import Fraction
from typing import Any

import numpy as np
import sympy as sp
from sympy.simplify.fu import TR10i

from ..exceptions import ParameterError, choices
from ..jacobian_rows import ROW_NAMES
from ..params import Chain
from ._numbers import numeric_jacobian as numeric_jacobian
from ._numbers import sigma_ratio as sigma_ratio
from ._numbers import single_joint_roots as single_joint_roots
from ._trigpoly import _chop, _det_poly, _reduce, _to_poly, _trig_symbols


def khalil_matrix(alpha: Any, d: Any, theta: Any, r: Any) -> sp.Matrix:
    """Symbolic ``Rx(alpha)·Tx(d)·Rz(theta)·Tz(r)`` (4×4 sympy matrix)."""
    ca, sa, ct, st = sp.cos(alpha), sp.sin(alpha), sp.cos(theta), sp.sin(theta)
    return sp.Matrix(
        [
            [ct, -st, 0, d],
            [ca * st, ca * ct, -sa, -r * sa],
            [sa * st, sa * ct, ca, r * ca],
            [0, 0, 0, 1],
        ]
    )


def exact_angle(value: float) -> sp.Expr:
    """An angle as an exact multiple of π when within 1e-9 rad of one (denominator ≤ 24)."""
    if value == 0.0:
        return sp.Integer(0)
    frac = Fraction(value / math.pi).limit_denominator(24)
    if abs(float(frac) * math.pi - value) <= 1e-9:
        return sp.Rational(frac.numerator, frac.denominator) * sp.pi
    return sp.Float(value)


#: Sums with more terms than this are not folded (see :func:`cheap`).
_FOLD_TERMS = 32


def cheap(expr: Any) -> Any:
    """Expand, then fold sums of angle products (Fu's TR10i). Fast on kinematic entries."""
    if isinstance(expr, sp.MatrixBase):
        return expr.applyfunc(cheap)
    e = sp.expand(expr)
    if not e.has(sp.sin, sp.cos) or len(sp.Add.make_args(e)) > _FOLD_TERMS:
        return e  # TR10i is quadratic in the number of terms: long sums stay expanded
    return TR10i(e)


#: Above this many terms in a cumulative product, later products are left unexpanded.
_MAX_TERMS = 600


def _expand(expr: Any) -> Any:
    if isinstance(expr, sp.MatrixBase):
        return expr.applyfunc(sp.expand)
    return sp.expand(expr)


def _same(expr: Any) -> Any:
    return expr


# the budget's fallback (stage 1 unfinished): products as unevaluated sums (evaluate=False,
# zeros dropped, ones skipped), built in milliseconds, equal in value, never printed
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


def _rotation(rot: np.ndarray) -> sp.Matrix:
    """A numeric rotation as sympy, exact when its roll-pitch-yaw are nice angles."""
    from ..params import matrix_to_rpy

    roll, pitch, yaw = (exact_angle(a) for a in matrix_to_rpy(rot))
    out = sp.rot_ccw_axis3(yaw) * sp.rot_ccw_axis2(pitch) * sp.rot_ccw_axis1(roll)
    if float(np.abs(np.array(out.evalf(), dtype=float) - rot).max()) > 1e-9:
        return sp.Matrix(rot.tolist()).applyfunc(sp.Float)
    return out


def _homogeneous(rot: sp.Matrix, xyz: Sequence[Any]) -> sp.Matrix:
    t = sp.eye(4)
    t[:3, :3], t[:3, 3] = rot, sp.Matrix(list(xyz))
    return t


def _number(x: float) -> sp.Expr:
    return sp.Integer(0) if abs(x) < 1e-15 else sp.Float(x)


def length_symbols(chain: Chain, names: Mapping[str, str] | None) -> dict[str, Any]:
    """One symbol per non-zero ``d``/``r`` entry (and tool offset); values and sources.

    Returns ``{"per_row": [(d, r)], "values": {sym: m}, "sources": {sym: key}, "tool": [x, y,
    z]}``. Raises ParameterError: ``names`` keys that are not lengths of the table, or reused.
    """
    entries = []
    for j, row in enumerate(chain.rows, start=1):
        for kind in ("d", "r"):
            value = getattr(row, kind)
            if value != 0.0:
                entries.append((f"{kind}{j}", value))
    all_d = all(key.startswith("d") for key, _ in entries)
    tool_xyz = chain.tool.xyz if chain.tool is not None else (0.0, 0.0, 0.0)
    for axis, value in zip("xyz", tool_xyz):
        if abs(value) > 1e-15:
            entries.append((f"tool_{axis}", value))
    given, keys = dict(names or {}), [key for key, _ in entries]
    unknown = [k for k in given if k not in keys]
    if unknown:
        raise ParameterError(
            f"lengths={given!r}: entries {unknown} are not non-zero lengths of the table; "
            f"allowed keys are {choices(keys)}"
        )
    symbols: dict[str, sp.Symbol] = {}
    values: dict[sp.Symbol, float] = {}
    sources: dict[sp.Symbol, str] = {}
    k = 0
    for key, value in entries:
        if key.startswith("tool_"):
            default = "t" + key[-1]
        else:
            k += 1
            default = f"l{k}" if all_d else key
        label = given.get(key, default)
        sym = sp.Symbol(label, positive=True) if value > 0 else sp.Symbol(label, real=True)
        if sym in values or any(s.name == label for s in values):
            raise ParameterError(f"lengths: symbol name {label!r} is used twice")
        symbols[key] = sym
        values[sym] = float(value)
        sources[sym] = key
    per_row = [
        (symbols.get(f"d{j}", sp.Integer(0)), symbols.get(f"r{j}", sp.Integer(0)))
        for j in range(1, len(chain.rows) + 1)
    ]
    tool = [symbols.get(f"tool_{a}", sp.Integer(0)) for a in "xyz"]
    return {"per_row": per_row, "values": values, "sources": sources, "tool": tool}


def kinematics(
    chain: Chain, q: tuple[sp.Symbol, ...], syms: Mapping[str, Any], simplify: bool = True
) -> dict[str, Any]:
    """Stage 1: transforms, cumulative products, tip, both Jacobians (cheaply simplified).

    With ``simplify=False`` the products stay unexpanded and ``J_indirect`` is the direct
    method's linear rows (the fast fallback). Angle sums are folded later (:func:`tidy`).
    """
    cheap_ = _expand if simplify else _same
    transforms, k = [], 0
    for row, (d, r) in zip(chain.rows, syms["per_row"]):
        alpha, theta = exact_angle(row.alpha), exact_angle(row.theta)
        if row.sigma == "revolute":
            theta = theta + q[k]
            k += 1
        elif row.sigma == "prismatic":
            r = r + q[k]
            k += 1
        transforms.append(khalil_matrix(alpha, d, theta, r))
    base, tool = chain.base_pose, chain.tool
    base_t = sp.eye(4)
    if base is not None:
        base_t = _homogeneous(_rotation(np.array(base.rotation)), [_number(x) for x in base.xyz])
    tool_t = sp.eye(4)
    if tool is not None:
        tool_t = _homogeneous(_rotation(np.array(tool.rotation)), syms["tool"])
    cumulative, acc = [], base_t
    for t in transforms:
        acc = cheap_(acc * t) if simplify else product(acc, t)
        cumulative.append(acc)
        if cheap_ is not _same and sum(len(sp.Add.make_args(e)) for e in acc) > _MAX_TERMS:
            cheap_ = _same  # long chains without parallel axes: expanding only grows them
    tip = cheap_(acc * tool_t) if simplify else product(acc, tool_t)
    p = tip[:3, 3]
    # Direct method, column by column in its own joint frame: z_j x (p - o_j) = R_0j (z x ^jp),
    # with ^jp (the tip seen from frame j) built backwards from the tool.
    tip_in = [sp.zeros(3, 1)] * len(transforms)
    vec = tool_t[:3, 3]
    for j in range(len(transforms) - 1, -1, -1):
        tip_in[j] = vec
        if j > 0:
            t = transforms[j]
            if simplify:
                vec = cheap_(t[:3, :3] * vec + t[:3, 3])
            else:  # R v + o, unevaluated
                vec = product(t[:3, :], sp.Matrix([*vec, 1]))
    cols = []
    for j in chain.joint_rows:
        rot = cumulative[j][:3, :3]
        if chain.rows[j].sigma == "revolute":
            v = tip_in[j]
            if simplify:  # R (z × v) = R[:, 1] v_x − R[:, 0] v_y
                lin = cheap_(rot[:, 1] * v[0] - rot[:, 0] * v[1])
            else:
                lin = product(rot[:, :2], sp.Matrix([sp.Mul(-1, v[1], evaluate=False), v[0]]))
            cols.append(sp.Matrix.vstack(lin, rot[:, 2]))
        else:
            cols.append(sp.Matrix.vstack(rot[:, 2], sp.zeros(3, 1)))
    jd = sp.Matrix.hstack(*cols)
    # without simplification (the fallback) no derivative: the direct one's linear rows
    ji = _indirect(p, q, chain.sigmas) if simplify else jd[:3, :]
    return {"transforms": tuple(transforms), "base": base_t, "tool": tool_t,
            "cumulative": tuple(cumulative), "tip": tip, "p": p, "J_direct": jd,
            "J_indirect": ji}  # fmt: skip


def _indirect(p: sp.Matrix, q: Sequence[sp.Symbol], sigmas: Sequence[str]) -> sp.Matrix:
    """``∂p/∂q`` (the indirect method), as polynomials when ``p`` is one.

    When every ``sin``/``cos`` in ``p`` has a single joint as argument, ``∂/∂q_k = c_k ∂/∂s_k −
    s_k ∂/∂c_k`` is applied to ``p`` as a polynomial in ``s_k``, ``c_k``; otherwise ``diff``.
    """
    s, c = _trig_symbols(q)
    fwd: dict[Any, Any] = {}
    gens: list[Any] = []
    for k, qk in enumerate(q):
        if sigmas[k] == "revolute":
            fwd[sp.sin(qk)] = s[k]
            fwd[sp.cos(qk)] = c[k]
            gens += [s[k], c[k]]
        else:
            gens.append(qk)
    plain = all(f.args[0] in q for e in p for f in e.atoms(sp.sin, sp.cos) if e.has(*q))
    if not plain:
        return _expand(p.jacobian(sp.Matrix(q)))
    back, rows = {v: k for k, v in fwd.items()}, []
    for e in p:
        poly = sp.Poly(e.xreplace(fwd), *gens)
        row = []
        for k, qk in enumerate(q):
            if sigmas[k] == "revolute":
                d = poly.diff(s[k]) * sp.Poly(c[k], *gens) - poly.diff(c[k]) * sp.Poly(s[k], *gens)
            else:
                d = poly.diff(qk)
            row.append(d.as_expr().xreplace(back))
        rows.append(row)
    return sp.Matrix(rows)


def _frames_in(transforms: Sequence[sp.Matrix], m: int) -> list[sp.Matrix]:
    """``^mT_k`` for every Khalil frame k = 0..N (cheaply simplified)."""
    n_rows = len(transforms)
    frames: list[Any] = [None] * (n_rows + 1)
    frames[m] = sp.eye(4)
    for k in range(m - 1, -1, -1):
        rot, pos = transforms[k][:3, :3], transforms[k][:3, 3]
        frames[k] = cheap(frames[k + 1] * _homogeneous(rot.T, -rot.T * pos))
    for k in range(m + 1, n_rows + 1):
        frames[k] = cheap(frames[k - 1] * transforms[k - 1])
    return frames


def frame_jacobian(
    chain: Chain, frames: Sequence[sp.Matrix], point: sp.Matrix
) -> tuple[sp.Matrix, bool]:
    """``(J, block_triangular)``: the 6×n J at ``point`` in the axes ``frames`` are expressed in.

    Block-triangular: the last three columns have no linear part (a wrist seen from its centre).
    """
    cols = []
    for j in chain.joint_rows:
        z, o = frames[j + 1][:3, 2], frames[j + 1][:3, 3]
        if chain.rows[j].sigma == "revolute":
            cols.append(sp.Matrix.vstack(cheap(z.cross(point - o)), z))
        else:
            cols.append(sp.Matrix.vstack(z, sp.zeros(3, 1)))
    jac = sp.Matrix.hstack(*cols)
    n = jac.shape[1]
    block = n == 6 and all(jac[r, c] == 0 for r in range(3) for c in range(3, 6))
    return jac, block


def _candidates(
    chain: Chain, stage1: Mapping[str, Any], sel: Sequence[int], deadline: float
) -> list[tuple[int, str, sp.Matrix, bool]]:
    """Jacobians in a few joint frames and reference points, simplest first.

    The reference point is the tip, except for all six rows of a 6×6 J (any point gives the
    same determinant): the origins of the last joints' frames (a wrist centre makes J
    block-triangular).
    """
    joints = chain.joint_rows
    n, frame_of = len(joints), [j + 1 for j in joints]
    ms = [frame_of[k] for k in (n - 3, n - 2, n // 2, n - 4, 0) if 0 <= k < n]
    ms = list(dict.fromkeys(ms))
    if len(sel) != n:  # maximal minors: the frame only changes their length, one is enough
        ms = ms[:1]
    out: list[tuple[int, str, sp.Matrix, bool]] = []
    for m in ms:
        if out and time.process_time() > deadline:
            break
        frames = _frames_in(stage1["transforms"], m)
        if len(sel) == 3 or n != 6:  # det(J Jt) of a non-square J depends on the point
            points = [("tip", cheap(frames[-1] * stage1["tool"])[:3, 3])]
        else:
            points = [
                (f"origin of frame {frame_of[k]}", frames[frame_of[k]][:3, 3])
                for k in (n - 2, n - 3, n - 1)
                if 0 <= k < n
            ]
        for label, point in points:
            jac, block = frame_jacobian(chain, frames, point)
            jac = jac.extract(list(sel), list(range(n)))
            out.append((m, label, jac, block))
    out.sort(key=lambda c: (not c[3], sum(sp.count_ops(e) for e in c[2])))
    return out


# ---------------------------------------------------------------------- factoring
def _to_trig(poly: Any, q: Sequence[sp.Symbol]) -> Any:
    s, c = _trig_symbols(q)
    sub = {x: fn(qk) for k, qk in enumerate(q) for x, fn in ((s[k], sp.sin), (c[k], sp.cos))}
    return cheap(poly.xreplace(sub))


def _depends(expr: Any, q: Sequence[sp.Symbol]) -> bool:
    s, c = _trig_symbols(q)
    return any(expr.has(x) for x in (*q, *s, *c))


def trig_factor(
    expr: Any, q: Sequence[sp.Symbol], sigmas: Sequence[str]
) -> tuple[Any, list[tuple[Any, int]]]:
    """``(constant, [(factor, multiplicity), ...])``: a trig polynomial in ``q`` factored.

    The factors are irreducible, in compact trigonometric form; ``constant · Π factor**mult``
    equals ``expr``.
    """
    return _factor_poly(_to_poly(expr, q, sigmas), q)


def _factor_poly(poly: Any, q: Sequence[sp.Symbol]) -> tuple[Any, list[tuple[Any, int]]]:
    """:func:`trig_factor` of a polynomial in ``s_k``, ``c_k`` (:func:`_to_poly`'s form)."""
    const, raw = sp.factor_list(_chop(poly))
    found: list[tuple[Any, int]] = []

    def add(f: Any, mult: int) -> None:
        nonlocal const
        for i, (g, m) in enumerate(found):
            if sp.expand(f - g) == 0:
                found[i] = (g, m + mult)
                return
            if sp.expand(f + g) == 0:
                found[i] = (g, m + mult)
                const = const * (-1) ** mult
                return
        found.append((f, mult))

    for fac, mult in raw:
        red = _chop(_reduce(fac, q))
        if not _depends(red, q):
            const = const * red**mult
            continue
        c2, sub = sp.factor_list(red)
        const = const * c2**mult
        for g, m2 in sub:
            if _depends(g, q):
                add(g, m2 * mult)
            else:
                const = const * g ** (m2 * mult)
    out = [(_to_trig(f, q), m) for f, m in found]
    return sp.factor(const), out


def _split_score(factors: Sequence[tuple[Any, int]]) -> tuple[int, int]:
    return (len(factors), -sum(sp.count_ops(f) for f, _ in factors))


def factored_determinant(
    chain: Chain,
    stage1: Mapping[str, Any],
    q: tuple[sp.Symbol, ...],
    row_names: Sequence[str],
    deadline: float,
    minors_deadline: float | None = None,
) -> dict[str, Any]:
    """Stage 2: det J (square) factored, or the rank-deficiency factors of a non-square J.

    Square: ``det J`` factored, the finest split over frames tried until ``deadline``.
    Non-square: the common factors of the maximal minors (:func:`rank_deficiency`, until
    ``minors_deadline``); ``gram`` is then ``det(J Jᵀ)`` (or ``det(Jᵀ J)``).
    """
    n = len(q)
    sel = [ROW_NAMES.index(r) for r in row_names]
    sigmas = chain.sigmas
    invariant = tuple(sel) in ((0, 1, 2), (0, 1, 2, 3, 4, 5))
    jd = stage1["J_direct"]
    if invariant:
        candidates = [
            (f"frame {m}, point: {label}", jac)
            for m, label, jac, _ in _candidates(chain, stage1, sel, deadline)
        ]
    else:
        candidates = [("base frame", jd.extract(sel, list(range(n))))]
    if len(sel) != n:
        label, mat = candidates[0]
        end = deadline if minors_deadline is None else minors_deadline
        out = rank_deficiency(mat, q, sigmas, end)
        out["how"] = f"{label}, {out['how']}"
        return out
    best: dict[str, Any] | None = None
    seen: list[Any] = []  # the polynomials factored: another frame often gives the same one
    memo: dict[Any, Any] = {}  # entries' polynomials (the frames' points share the w rows)
    for label, mat in candidates:
        if best is not None and time.process_time() > deadline:
            break
        how = label
        split = mat.shape == (6, 6) and all(mat[r, c] == 0 for r in range(3) for c in range(3, 6))
        if split:
            how = f"{label} (wrist centre), det J11 * det J22"
        poly = _det_poly(mat, q, sigmas, split, memo)
        if poly in seen:
            continue  # the same factors, the same score: the first one stays
        seen.append(poly)
        const, factors = _factor_poly(poly, q)
        cand = {"const": const, "factors": factors, "how": how}
        if best is None or _split_score(factors) > _split_score(best["factors"]):
            best = cand
    assert best is not None
    const, fs = best["const"], tuple(best["factors"])
    det = const * sp.Mul(*[f**m for f, m in fs])
    gram = const**2 * sp.Mul(*[f ** (2 * m) for f, m in fs])
    return {"how": best["how"], "factors": fs, "const": const, "det": det, "gram": gram,
            "unconfirmed": ()}  # fmt: skip


def _plain_det(m: sp.Matrix) -> Any:
    """``det m`` by cofactors along the first row, left unexpanded (sympy's ``det`` simplifies)."""
    if m.rows == 1:
        return m[0, 0]
    terms = []
    for j in range(m.cols):
        if m[0, j] != 0:
            rest = m.extract(list(range(1, m.rows)), [c for c in range(m.cols) if c != j])
            terms.append((-1) ** j * m[0, j] * _plain_det(rest))
    return sp.Add(*terms)


def _same_factor(f: Any, g: Any) -> bool:
    return sp.expand(f - g) == 0 or sp.expand(f + g) == 0


def rank_deficiency(
    mat: sp.Matrix, q: Sequence[sp.Symbol], sigmas: Sequence[str], deadline: float
) -> dict[str, Any]:
    """Where a k×n ``mat`` (k ≠ n) loses rank: the common factors of its maximal minors.

    ``rank J < min(k, n)`` exactly where every maximal minor vanishes: a factor common to all
    is a family (none: rank drops only on sets of codimension ≥ 2). The minors are factored
    smallest first, keeping the common factors; at the deadline the factors kept are
    *candidates* (``unconfirmed``), which the families' σ_min check keeps or drops.

    Returns:
        ``{"factors", "const", "det": None, "gram", "how", "unconfirmed"}``: ``gram`` is
        ``const² · Π f^(2m) · rest`` (Cauchy–Binet, ``rest`` a sum of squares) when every
        minor was factored, else ``det(J Jᵀ)`` (``det(Jᵀ J)`` when k > n) unexpanded.

    """
    from itertools import combinations

    k, n = mat.shape
    small, subsets = min(k, n), []
    for sub in combinations(range(max(k, n)), small):
        rows_, cols_ = (list(range(k)), list(sub)) if k < n else (list(sub), list(range(n)))
        m = mat.extract(rows_, cols_)
        if any(all(e == 0 for e in m.col(j)) for j in range(small)) or any(
            all(e == 0 for e in m.row(i)) for i in range(small)
        ):
            continue  # a zero row or column: the minor is 0
        subsets.append((sum(sp.count_ops(e) for e in m), sub, m))
    subsets.sort(key=lambda t: (t[0], t[1]))
    total = len(subsets)
    common: list[tuple[Any, int]] | None = None
    memo: dict[Any, Any] = {}  # entries' polynomials, shared by the minors
    minors: list[tuple[Any, list[tuple[Any, int]]]] = []
    stopped = ""
    for _, _sub, m in subsets:
        if common is not None and not common:
            break
        if common is not None and time.process_time() > deadline:
            stopped = "deadline"
            break
        const, factors = _factor_poly(_det_poly(m, q, sigmas, memo=memo), q)
        if const == 0:
            continue
        minors.append((const, factors))
        if common is None:
            common = list(factors)
            continue
        kept = []
        for f, mult in common:
            hit = [m2 for g, m2 in factors if _same_factor(f, g)]
            if hit:
                kept.append((f, min(mult, hit[0])))
        common = kept
    gram_raw = _plain_det(mat * mat.T if k < n else mat.T * mat)
    what = f"{small}x{small} minors"
    if common is None:  # every maximal minor is zero: rank < min(k, n) everywhere
        how = f"every maximal minor ({what}) is zero: J never has full rank"
        return _deficiency((), sp.Integer(0), sp.Integer(0), how)
    if not common:
        how = (
            f"rank deficiency: the maximal minors ({what}) share no factor ({len(minors)} "
            f"of {total} non-zero minors factored): rank J drops only on sets of "
            "codimension >= 2, no family"
        )
        return _deficiency((), sp.Integer(1), gram_raw, how)
    if stopped:
        how = (
            f"rank deficiency: factors common to {len(minors)} of the {total} non-zero "
            f"maximal minors ({what}; time ran out for the others): candidates, kept "
            "only where the numeric J loses rank on them (sigma_min)"
        )
        return _deficiency(common, sp.Integer(1), gram_raw, how, tuple(range(len(common))))
    consts = [c for c, _ in minors]
    base = consts[0] if all(sp.expand(c**2 - consts[0] ** 2) == 0 for c in consts) else 1
    rest_terms = []
    for c, factors in minors:
        term = c / base
        for f, mult in factors:
            have = next((m for g, m in common if _same_factor(f, g)), 0)
            term = term * f ** (mult - have)
        rest_terms.append(term**2)
    rest = sp.Add(*rest_terms)
    if time.process_time() < deadline and sum(sp.count_ops(t) for t in rest_terms) < 400:
        reduced = _reduce(_to_poly(rest, q, sigmas), q)
        if not _depends(reduced, q):
            rest = sp.factor(reduced)
    gram = base**2 * sp.Mul(*[f ** (2 * m) for f, m in common]) * rest
    how = (
        f"rank deficiency: common factors of all {total} non-zero maximal minors ({what}); "
        "det(J Jt) = Cauchy-Binet sum of their squares"
    )
    return _deficiency(common, base, gram, how)


def _deficiency(
    factors: Sequence[tuple[Any, int]], const: Any, gram: Any, how: str,
    unconfirmed: tuple[int, ...] = (),
) -> dict[str, Any]:  # fmt: skip
    """:func:`rank_deficiency`'s answer (no ``det``: J is not square)."""
    return {"factors": tuple(factors), "const": const, "det": None, "gram": gram, "how": how,
            "unconfirmed": unconfirmed}  # fmt: skip


# ---------------------------------------------------------------------- printing
def _collect_trig(expr: Any) -> Any:
    """Terms grouped by their trigonometric part, each coefficient factored (an identity)."""
    groups: dict[Any, list[Any]] = {}
    for term in sp.Add.make_args(sp.expand(expr)):
        coeff, trig = sp.S.One, sp.S.One
        for f in sp.Mul.make_args(term):
            if f.has(sp.sin, sp.cos):
                trig = trig * f
            else:
                coeff = coeff * f
        groups.setdefault(trig, []).append(coeff)
    out = sp.Add(*[sp.factor(sp.Add(*cs)) * trig for trig, cs in groups.items()])
    return sp.factor_terms(out)


def tidy(expr: Any, q: Sequence[sp.Symbol], sigmas: Sequence[str], ops: int = 400) -> Any:
    """``expr`` shorter for printing, exactly equal: ``sin² + cos² = 1`` folded, terms grouped.

    The shortest (``count_ops``) of the reduced and the grouped forms; expressions over ``ops``
    operations are left as they are.
    """
    if not isinstance(expr, sp.Expr) or not expr.args or sp.count_ops(expr) > ops:
        return expr
    best, size = expr, sp.count_ops(expr)
    try:
        powers = (p.base.func in (sp.sin, sp.cos) and p.exp.is_Integer and p.exp > 1
                  for p in expr.atoms(sp.Pow))  # fmt: skip
        e = _reduce(_to_poly(expr, q, sigmas), q) if any(powers) else expr
        e = _to_trig(e, q) if e is not expr else cheap(e)  # folds angle sums
        forms = (e, _collect_trig(e))
    except (sp.PolynomialError, TypeError, ValueError):  # an entry outside the trig ring
        return expr
    for form in forms:
        n = sp.count_ops(form)
        if n < size:
            best, size = form, n
    return best
