"""The sympy work behind :func:`hexapod_kin.symbolic.derive`, in stages (no caching, no budget).

Speed comes from structure, not from ``simplify``:

* each cumulative product ``^0T_j`` is simplified step by step with a cheap rule set
  (``expand`` then Fu's ``TR10i``, which folds ``c2 c3 − s2 s3`` into ``cos(q2 + q3)``);
* ``det J`` of the position rows or of the full 6×6 is computed in a *middle* joint frame
  ``m`` (the determinant is invariant under a rotation of both rows blocks and, for the 6×6,
  under a change of reference point), which keeps every entry short; with a spherical wrist
  the reference point is the wrist centre, the Jacobian is block-triangular and
  ``det J = det J11 · det J22``;
* the determinant is factored as a polynomial in ``s_i = sin q_i``, ``c_i = cos q_i``
  *before* reducing modulo ``s_i² + c_i² = 1`` (reducing first can glue families together,
  e.g. PUMA's elbow and shoulder), then each factor is reduced, factored again and turned
  back into compact trigonometry. A few frames ``m`` are tried; the finest split wins.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from fractions import Fraction
from typing import Any

import numpy as np
import sympy as sp
from sympy.simplify.fu import TR10i

from .._table_kin import table_transforms
from ..exceptions import ParameterError, choices
from ..params import Chain
from ..singularity.rows import ROW_NAMES


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
    """An angle as an exact multiple of π when within 1e-9 rad of one (denominator ≤ 24).

    URDFs round π/2 to 11 digits (``1.57079632679``); such angles are snapped, which moves
    the kinematics by at most that rounding.
    """
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


def _terms(mat: sp.Matrix) -> int:
    return sum(len(sp.Add.make_args(e)) for e in mat)


def has_parallel_axes(chain: Chain) -> bool:
    """True when two consecutive joint axes are parallel (only then do angle sums fold)."""
    joints = chain.joint_rows
    for a, b in zip(joints, joints[1:]):
        twist = sum(chain.rows[k].alpha for k in range(a + 1, b + 1))
        if abs(math.sin(twist)) < 1e-9:
            return True
    return False


def _expand(expr: Any) -> Any:
    if isinstance(expr, sp.MatrixBase):
        return expr.applyfunc(sp.expand)
    return sp.expand(expr)


def _same(expr: Any) -> Any:
    return expr


def _rotation(rot: np.ndarray) -> sp.Matrix:
    """A numeric rotation as sympy, exact when its roll-pitch-yaw are nice angles."""
    from ..params import matrix_to_rpy

    roll, pitch, yaw = (exact_angle(a) for a in matrix_to_rpy(rot))
    rx = sp.Matrix([[1, 0, 0], [0, sp.cos(roll), -sp.sin(roll)], [0, sp.sin(roll), sp.cos(roll)]])
    ry = sp.Matrix(
        [[sp.cos(pitch), 0, sp.sin(pitch)], [0, 1, 0], [-sp.sin(pitch), 0, sp.cos(pitch)]]
    )
    rz = sp.Matrix([[sp.cos(yaw), -sp.sin(yaw), 0], [sp.sin(yaw), sp.cos(yaw), 0], [0, 0, 1]])
    out = rz * ry * rx
    if float(np.abs(np.array(out.evalf(), dtype=float) - rot).max()) > 1e-9:
        return sp.Matrix(rot.tolist()).applyfunc(sp.Float)
    return out


def _homogeneous(rot: sp.Matrix, xyz: Sequence[Any]) -> sp.Matrix:
    t = sp.eye(4)
    t[:3, :3] = rot
    t[:3, 3] = sp.Matrix(list(xyz))
    return t


def _number(x: float) -> sp.Expr:
    return sp.Integer(0) if abs(x) < 1e-15 else sp.Float(x)


def length_symbols(chain: Chain, names: Mapping[str, str] | None) -> dict[str, Any]:
    """One symbol per non-zero ``d``/``r`` entry (and tool offset); values and sources.

    Returns:
        ``{"per_row": [(d, r)], "values": {sym: m}, "sources": {sym: key}, "tool": [x, y, z]}``.

    Raises:
        ParameterError: ``names`` keys that are not lengths of the table, or reused names.

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
    given = dict(names or {})
    keys = [key for key, _ in entries]
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

    With ``simplify=False`` the products are left as they come (fast fallback).
    """
    cheap_ = (cheap if has_parallel_axes(chain) else _expand) if simplify else _same
    transforms = []
    k = 0
    for row, (d, r) in zip(chain.rows, syms["per_row"]):
        alpha, theta = exact_angle(row.alpha), exact_angle(row.theta)
        if row.sigma == "revolute":
            theta = theta + q[k]
            k += 1
        elif row.sigma == "prismatic":
            r = r + q[k]
            k += 1
        transforms.append(khalil_matrix(alpha, d, theta, r))
    base_t = sp.eye(4)
    if chain.base_pose is not None:
        base_t = _homogeneous(
            _rotation(np.array(chain.base_pose.rotation)),
            [_number(x) for x in chain.base_pose.xyz],
        )
    tool_t = sp.eye(4)
    if chain.tool is not None:
        tool_t = _homogeneous(_rotation(np.array(chain.tool.rotation)), syms["tool"])
    cumulative = []
    acc = base_t
    for t in transforms:
        acc = cheap_(acc * t)
        cumulative.append(acc)
        if cheap_ is not _same and _terms(acc) > _MAX_TERMS:
            cheap_ = _same  # long chains without parallel axes: expanding only grows them
    tip = cheap_(acc * tool_t)
    p = tip[:3, 3]
    cols = []
    for j in chain.joint_rows:
        z = cumulative[j][:3, 2]
        o = cumulative[j][:3, 3]
        if chain.rows[j].sigma == "revolute":
            cols.append(sp.Matrix.vstack(cheap_(z.cross(p - o)), z))
        else:
            cols.append(sp.Matrix.vstack(z, sp.zeros(3, 1)))
    return {
        "transforms": tuple(transforms),
        "base": base_t,
        "tool": tool_t,
        "cumulative": tuple(cumulative),
        "tip": tip,
        "p": p,
        "J_direct": sp.Matrix.hstack(*cols),
        "J_indirect": cheap_(p.jacobian(sp.Matrix(q))),
    }


def _inverse(t: sp.Matrix) -> sp.Matrix:
    rot, pos = t[:3, :3], t[:3, 3]
    out = sp.eye(4)
    out[:3, :3] = rot.T
    out[:3, 3] = -rot.T * pos
    return out


def _frames_in(transforms: Sequence[sp.Matrix], m: int) -> list[sp.Matrix]:
    """``^mT_k`` for every Khalil frame k = 0..N (cheaply simplified)."""
    n_rows = len(transforms)
    frames: list[Any] = [None] * (n_rows + 1)
    frames[m] = sp.eye(4)
    for k in range(m - 1, -1, -1):
        frames[k] = cheap(frames[k + 1] * _inverse(transforms[k]))
    for k in range(m + 1, n_rows + 1):
        frames[k] = cheap(frames[k - 1] * transforms[k - 1])
    return frames


def frame_jacobian(
    chain: Chain, frames: Sequence[sp.Matrix], point: sp.Matrix
) -> tuple[sp.Matrix, bool]:
    """6×n Jacobian with the axes of the frame ``frames`` are expressed in, at ``point``.

    Returns:
        ``(J, block_triangular)``; block-triangular when the last three columns have no
        linear part (a spherical wrist seen from its centre).

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

    Position rows, or all six rows of a non-square J: the reference point is the tip (a
    rotation of both row blocks keeps det(J Jᵀ); moving the point does not). All six rows
    of a 6×6 J: any point gives the same determinant, so origins of the last joints' frames
    are tried (the wrist centre when
    there is one, which makes J block-triangular).
    """
    joints = chain.joint_rows
    n = len(joints)
    frame_of = [j + 1 for j in joints]
    ms = [frame_of[k] for k in (n - 3, n - 2, n // 2, n - 4, 0) if 0 <= k < n]
    ms = list(dict.fromkeys(ms))
    out: list[tuple[int, str, sp.Matrix, bool]] = []
    for m in ms:
        if out and time.perf_counter() > deadline:
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
def _trig_symbols(q: Sequence[sp.Symbol]) -> tuple[tuple[sp.Symbol, ...], tuple[sp.Symbol, ...]]:
    s = tuple(sp.Symbol(f"_s{k}", real=True) for k in range(len(q)))
    c = tuple(sp.Symbol(f"_c{k}", real=True) for k in range(len(q)))
    return s, c


def _to_poly(expr: Any, q: Sequence[sp.Symbol], sigmas: Sequence[str]) -> Any:
    s, c = _trig_symbols(q)
    e = sp.expand(sp.expand_trig(expr))
    sub = {}
    for k, qk in enumerate(q):
        if sigmas[k] == "revolute":
            sub[sp.sin(qk)] = s[k]
            sub[sp.cos(qk)] = c[k]
    return sp.expand(e.xreplace(sub))


def _reduce(poly: Any, q: Sequence[sp.Symbol]) -> Any:
    s, c = _trig_symbols(q)
    e = poly
    for sk, ck in zip(s, c):
        if e.has(sk):
            e = sp.rem(sp.Poly(e, sk), sp.Poly(sk**2 + ck**2 - 1, sk)).as_expr()
    return sp.expand(e)


def _chop(expr: Any, rel: float = 1e-12) -> Any:
    """Float coefficients below ``rel`` × the largest one, set to 0.

    They are rounding noise of tables with inexact angles (1e-17 terms from a URDF's table)
    that would otherwise factor as real terms.
    """
    floats = expr.atoms(sp.Float)
    if not floats:
        return expr
    tiny = rel * max(abs(float(f)) for f in floats)
    zero = {f: sp.Integer(0) for f in floats if abs(float(f)) < tiny}
    return sp.expand(expr.xreplace(zero)) if zero else expr


def _to_trig(poly: Any, q: Sequence[sp.Symbol]) -> Any:
    s, c = _trig_symbols(q)
    sub = {}
    for k, qk in enumerate(q):
        sub[s[k]] = sp.sin(qk)
        sub[c[k]] = sp.cos(qk)
    return cheap(poly.xreplace(sub))


def _depends(expr: Any, q: Sequence[sp.Symbol]) -> bool:
    s, c = _trig_symbols(q)
    return any(expr.has(x) for x in (*q, *s, *c))


def trig_factor(
    expr: Any, q: Sequence[sp.Symbol], sigmas: Sequence[str]
) -> tuple[Any, list[tuple[Any, int]]]:
    """Factor a trigonometric polynomial in ``q`` into irreducible factors.

    Returns:
        ``(constant, [(factor, multiplicity), ...])`` with factors in compact trigonometric
        form; the product ``constant · Π factor**mult`` equals ``expr``.

    """
    poly = _chop(_to_poly(expr, q, sigmas))
    const, raw = sp.factor_list(poly)
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


def _const(jac: sp.Matrix) -> Callable[[], sp.Matrix]:
    def make() -> sp.Matrix:
        return jac

    return make


def _split_score(factors: Sequence[tuple[Any, int]]) -> tuple[int, int]:
    return (len(factors), -sum(sp.count_ops(f) for f, _ in factors))


def factored_determinant(
    chain: Chain,
    stage1: Mapping[str, Any],
    q: tuple[sp.Symbol, ...],
    row_names: Sequence[str],
    deadline: float,
) -> dict[str, Any]:
    """Stage 2: det J (square) or det(J Jᵀ), factored; the finest split over a few frames."""
    n = len(q)
    sel = [ROW_NAMES.index(r) for r in row_names]
    sigmas = chain.sigmas
    invariant = tuple(sel) in ((0, 1, 2), (0, 1, 2, 3, 4, 5))
    jd = stage1["J_direct"]
    candidates: list[tuple[str, Callable[[], sp.Matrix]]] = []
    if invariant:
        for m, label, jac, _ in _candidates(chain, stage1, sel, deadline):
            candidates.append((f"frame {m}, point: {label}", _const(jac)))
    else:
        candidates.append(("base frame", lambda: jd.extract(sel, list(range(n)))))
    best: dict[str, Any] | None = None
    for label, make in candidates:
        if best is not None and time.perf_counter() > deadline:
            break
        mat = make()
        square = mat.shape[0] == n
        if (
            square
            and mat.shape == (6, 6)
            and all(mat[r, c] == 0 for r in range(3) for c in range(3, 6))
        ):
            raw = mat[:3, :3].det(method="berkowitz") * mat[3:, 3:].det(method="berkowitz")
            how = f"{label} (wrist centre), det J11 * det J22"
        elif square:
            raw = mat.det(method="berkowitz")
            how = label
        else:
            const, factors, rest = _gram_by_minors(mat, q, sigmas)
            how = (
                f"{label}, Gram determinant by Cauchy-Binet: common factors of the maximal "
                "minors; the remaining sum of squares vanishes only where every minor does"
            )
            cand = {"const": const, "factors": factors, "how": how, "square": False, "rest": rest}
            if best is None or _split_score(factors) > _split_score(best["factors"]):
                best = cand
            continue
        const, factors = trig_factor(raw, q, sigmas)
        cand = {"const": const, "factors": factors, "how": how, "square": square}
        if best is None or _split_score(factors) > _split_score(best["factors"]):
            best = cand
    assert best is not None
    product = best["const"] * sp.Mul(*[f**m for f, m in best["factors"]])
    out = {"how": best["how"], "factors": tuple(best["factors"]), "const": best["const"]}
    if best["square"]:
        out["det"] = product
        out["gram"] = best["const"] ** 2 * sp.Mul(*[f ** (2 * m) for f, m in best["factors"]])
    else:
        out["det"] = None
        out["gram"] = (
            best["const"] ** 2 * sp.Mul(*[f ** (2 * m) for f, m in best["factors"]]) * best["rest"]
        )
    return out


def _gram_by_minors(
    mat: sp.Matrix, q: Sequence[sp.Symbol], sigmas: Sequence[str]
) -> tuple[Any, list[tuple[Any, int]], Any]:
    """``det(J Jᵀ)`` (or ``det(Jᵀ J)``) = Σ minors² (Cauchy–Binet), factored by common factors.

    Returns:
        ``(constant, common factors with multiplicity, rest)`` with
        ``gram = constant² · Π factor^(2m) · rest`` and ``rest`` a sum of squares.

    """
    from itertools import combinations

    k, n = mat.shape
    small = min(k, n)
    subsets = combinations(range(max(k, n)), small)
    minors = []
    for sub in subsets:
        rows_, cols_ = (list(range(k)), list(sub)) if k < n else (list(sub), list(range(n)))
        m = mat.extract(rows_, cols_)
        val = m.det(method="berkowitz")
        if val != 0:
            minors.append(trig_factor(val, q, sigmas))
    minors = [(c, f) for c, f in minors if c != 0]
    if not minors:
        return sp.Integer(0), [], sp.Integer(0)
    common: list[tuple[Any, int]] = []
    for f, mult in minors[0][1]:
        least = mult
        for _, others in minors[1:]:
            hit = [m2 for g, m2 in others if sp.expand(f - g) == 0 or sp.expand(f + g) == 0]
            least = min(least, hit[0]) if hit else 0
        if least > 0:
            common.append((f, least))
    consts = [c for c, _ in minors]
    base = consts[0] if all(sp.simplify(c**2 - consts[0] ** 2) == 0 for c in consts) else 1
    rest_terms = []
    for c, factors in minors:
        term = c / base
        for f, mult in factors:
            have = next((m for g, m in common if sp.expand(f - g) == 0 or sp.expand(f + g) == 0), 0)
            term = term * f ** (mult - have)
        rest_terms.append(term**2)
    rest = sp.Add(*rest_terms)
    reduced = _reduce(_to_poly(rest, q, sigmas), q)
    if not _depends(reduced, q):
        rest = sp.factor(reduced)
    return base, common, rest


# ---------------------------------------------------------------------- numbers
def numeric_jacobian(chain: Chain, q: np.ndarray, sel: Sequence[int]) -> np.ndarray:
    """Independent numeric Jacobian (base frame, tool point) from the table, rows ``sel``."""
    ts = table_transforms(chain, q)
    acc = chain.base_matrix
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


def import_ahead() -> None:
    """Import what the stages import on first use (``scipy.optimize``).

    Called before a derivation runs in a forked child: the child inherits the module instead
    of importing it again, once per derivation.
    """
    import scipy.optimize  # noqa: F401


def single_joint_roots(
    func: Callable[[np.ndarray], np.ndarray], lo: float, hi: float
) -> list[float]:
    """Real roots of a scalar function of one joint on ``[lo, hi]`` (sign changes, brentq)."""
    from scipy.optimize import brentq

    grid = np.linspace(lo, hi, 3601)
    vals = np.asarray(func(grid), dtype=float)
    roots: list[float] = []
    scale = max(1e-300, float(np.abs(vals).max()))
    for i in range(len(grid) - 1):
        a, b = vals[i], vals[i + 1]
        if a == 0.0:
            roots.append(float(grid[i]))
        elif a * b < 0:
            roots.append(
                float(
                    brentq(
                        lambda x: float(func(np.array([x]))[0]), grid[i], grid[i + 1], xtol=1e-15
                    )
                )
            )
        elif abs(a) < 1e-12 * scale and i > 0 and (vals[i - 1] - a) * (b - a) > 0:
            roots.append(float(grid[i]))  # a tangency at a grid point
    if vals[-1] == 0.0:
        roots.append(float(grid[-1]))
    out: list[float] = []
    for r in sorted(roots):
        if not out or abs(r - out[-1]) > 1e-9:
            out.append(r)
    return out
