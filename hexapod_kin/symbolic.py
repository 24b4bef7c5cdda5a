"""The same Khalil–Kleinfinger table, derived with sympy: transforms, Jacobians, det J, factored.

:func:`derive` builds, from a chain's table and with *symbolic* lengths,

* every ``^{j-1}T_j`` and ``^0T_j`` (4×4 sympy matrices),
* the tip position ``p(q)`` in the base frame,
* the Jacobian by the **direct** method (columns ``z_j × (p − o_j)`` and ``z_j``; 6×n, rows
  ``vx vy vz wx wy wz``) and by the **indirect** method (``∂p/∂q``, 3×n), checked equal,
* ``det J`` of a square row selection (the position rows for a 3-DOF leg; ``x, y, z, wz`` for
  the SCARA), factored, or the Gram determinant ``det(J Jᵀ)`` (manipulability²) otherwise,
* the singular *families*: one per factor of the determinant that depends on ``q``, solved
  for the joint value when the factor involves a single joint (``sin q3 = 0`` gives the two
  families ``q3 = 0`` and ``q3 = π``), else kept as the equation ``factor = 0``.

For the 3-DOF leg (``hexabot_leg``) the factored determinant is
``l2·l3·sin(q3)·(l1 + l2 cos q2 + l3 cos(q2 + q3))``.

Lengths are symbols (``l1, l2, ...`` when every length of the table is a ``d``, as for the legs;
else Khalil's own names ``d2, r1, ...``); :meth:`Derivation.numeric` substitutes the chain's
numbers, :meth:`Derivation.function` returns a vectorised numpy function of ``q``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import numpy as np
import sympy as sp

from .exceptions import ParameterError, choices
from .params import Chain, Hexapod

__all__ = [
    "ROW_NAMES",
    "Derivation",
    "SingularFamily",
    "derive",
    "khalil_matrix",
    "default_rows",
    "row_indices",
]

#: Names of the six rows of a ``local_world_aligned`` Jacobian ``[v; ω]``.
ROW_NAMES: tuple[str, ...] = ("x", "y", "z", "wx", "wy", "wz")


def row_indices(rows: str | Sequence[str] | None, nq: int | None = None) -> tuple[int, ...]:
    """Turn a row selection into indices of ``[vx vy vz wx wy wz]``.

    Args:
        rows: ``None`` or ``"position"`` (x, y, z), ``"all"`` (the six rows), or a sequence of
            names from :data:`ROW_NAMES` (e.g. ``("x", "y", "z", "wz")``).
        nq: Unused here; kept for symmetry with callers that check squareness.

    Returns:
        The row indices (0..5), in the given order.

    Raises:
        ParameterError: Unknown or repeated row names, or an empty selection.

    """
    del nq
    if rows is None or rows == "position":
        return (0, 1, 2)
    if rows == "all":
        return tuple(range(6))
    if isinstance(rows, str):
        rows = [r.strip() for r in rows.split(",")]
    names = [str(r).lower() for r in rows]
    bad = [r for r in names if r not in ROW_NAMES]
    if bad or not names or len(set(names)) != len(names):
        raise ParameterError(
            f"rows={tuple(rows)!r} is not allowed; give distinct names from "
            f"{choices(ROW_NAMES)}, or 'position' / 'all'"
        )
    return tuple(ROW_NAMES.index(r) for r in names)


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


def _exact_angle(value: float) -> sp.Expr:
    """An angle as an exact multiple of π when it is one (denominator ≤ 24), else a Float."""
    if value == 0.0:
        return sp.Integer(0)
    frac = Fraction(value / math.pi).limit_denominator(24)
    if abs(float(frac) * math.pi - value) <= 1e-12 * max(1.0, abs(value)):
        return sp.Rational(frac.numerator, frac.denominator) * sp.pi
    return sp.Float(value)


@dataclass(frozen=True)
class SingularFamily:
    """One family of singular configurations (the zero set of one factor of det J).

    Attributes:
        name: A readable label, e.g. ``"q3 = 0"`` or ``"l1 + l2*cos(q2) + ... = 0"``.
        factor: The factor of the determinant (sympy, symbolic lengths) that vanishes.
        equation: ``Eq(q_k, value)`` when solved for one joint, else ``Eq(factor, 0)``.
        variables: Indices (0-based) of the joints the factor depends on.
        joint: Index of the joint when the family is ``q_k = value``, else ``None``.
        value: That value in [rad] or [m] (``None`` for implicit families).
        periodic: True when ``value`` repeats every 2π (revolute joint).

    """

    name: str
    factor: sp.Expr
    equation: sp.Eq
    variables: tuple[int, ...]
    joint: int | None = None
    value: float | None = None
    periodic: bool = False


@dataclass(frozen=True)
class Derivation:
    """Symbolic kinematics of one chain (all sympy objects; lengths symbolic).

    Attributes:
        chain: The chain it was derived from.
        q: The joint symbols ``q1..qn``.
        joint_names: The chain's joint names, in the same order.
        lengths: Length symbol → value in [m] (what :meth:`numeric` substitutes).
        length_sources: Length symbol → the table entry it stands for (e.g. ``"d2"``).
        transforms: ``^{j-1}T_j`` for every table row (4×4 each).
        cumulative: ``^0T_j`` for every table row (4×4 each, simplified).
        p: Tip position in the base frame (3×1).
        J_direct: 6×n Jacobian by the direct method, rows ``vx vy vz wx wy wz``.
        J_indirect: 3×n Jacobian ``∂p/∂q`` by the indirect method.
        J: The 3×n position Jacobian (equal to both methods; they are checked).
        rows: The row names of :attr:`J_rows` (the selection used for :attr:`det`).
        J_rows: The selected rows of ``J_direct`` (k×n).
        det: ``det J_rows`` factored (``None`` when k ≠ n).
        gram: ``det(J_rows J_rowsᵀ)`` (k ≤ n) or ``det(J_rowsᵀ J_rows)`` (k > n), factored —
            the squared Yoshikawa manipulability; equal to ``det²`` when square.
        families: The singular families read off :attr:`det` (or :attr:`gram`).

    """

    chain: Chain
    q: tuple[sp.Symbol, ...]
    joint_names: tuple[str, ...]
    lengths: Mapping[sp.Symbol, float]
    length_sources: Mapping[sp.Symbol, str]
    transforms: tuple[sp.Matrix, ...]
    cumulative: tuple[sp.Matrix, ...]
    p: sp.Matrix
    J_direct: sp.Matrix
    J_indirect: sp.Matrix
    J: sp.Matrix
    rows: tuple[str, ...]
    J_rows: sp.Matrix
    det: sp.Expr | None
    gram: sp.Expr
    families: tuple[SingularFamily, ...] = field(default=())

    # ------------------------------------------------------------------ numbers
    def numeric(self, expr: Any) -> Any:
        """Substitute the chain's length values into ``expr`` (a sympy object)."""
        return sp.sympify(expr).subs(dict(self.lengths))

    def function(self, expr: Any) -> Callable[[np.ndarray], np.ndarray]:
        """A vectorised numpy function of ``q`` for ``expr`` (lengths substituted).

        Args:
            expr: A sympy expression or matrix in the joint symbols.

        Returns:
            ``f(Q)`` with ``Q`` of shape (n,) or (N, n); returns the expression's value(s)
            (scalar expressions give shape () or (N,); matrices (…, rows, cols)).

        """
        num = self.numeric(expr)
        is_matrix = isinstance(num, sp.MatrixBase)
        shape = num.shape if is_matrix else ()
        entries = list(num) if is_matrix else [num]
        raws = [sp.lambdify(self.q, e, modules="numpy") for e in entries]

        def f(q: np.ndarray) -> np.ndarray:
            arr = np.asarray(q, dtype=float)
            lead = arr.shape[:-1]
            cols = [arr[..., k] for k in range(len(self.q))]
            res = np.empty(lead + (len(raws),))
            for i, raw in enumerate(raws):
                res[..., i] = np.broadcast_to(np.asarray(raw(*cols), dtype=float), lead)
            return res.reshape(lead + shape)

        return f

    @property
    def methods_agree(self) -> bool:
        """True when the direct and indirect position Jacobians simplify to the same matrix."""
        diff = (self.J_direct[:3, :] - self.J_indirect).applyfunc(
            lambda e: sp.simplify(sp.expand_trig(e))
        )
        return bool(diff.is_zero_matrix)

    # ------------------------------------------------------------------ printing
    def _items(self) -> list[tuple[str, str, Any]]:
        n = len(self.transforms)
        items: list[tuple[str, str, Any]] = []
        for j in range(n):
            items.append((f"^{j}T_{j + 1}", f"{{}}^{{{j}}}T_{{{j + 1}}}", self.transforms[j]))
        for j in range(1, n):
            items.append((f"^0T_{j + 1}", f"{{}}^{{0}}T_{{{j + 1}}}", self.cumulative[j]))
        items.append(("p(q)", "p(q)", self.p))
        items.append(("J (indirect, dp/dq)", "J_{\\mathrm{indirect}}", self.J_indirect))
        items.append(("J (direct, [v; w])", "J_{\\mathrm{direct}}", self.J_direct))
        if self.det is not None:
            items.append((f"det J[{','.join(self.rows)}]", "\\det J", self.det))
        else:
            items.append((f"det(J Jt) [{','.join(self.rows)}]", "\\det(J J^T)", self.gram))
        return items

    def _header(self) -> list[str]:
        joints = ", ".join(f"{s} ({n})" for s, n in zip(self.q, self.joint_names))
        lens = ", ".join(
            f"{s} = {self.length_sources[s]} = {v:g} m" for s, v in self.lengths.items()
        )
        return [
            f"{self.chain.name}: Khalil-Kleinfinger table, T = Rx(alpha) Tx(d) Rz(theta) Tz(r)",
            f"joints: {joints}",
            f"lengths: {lens or '(none)'}",
        ]

    def text(self) -> str:
        """The derivation as plain text (sympy pretty-printing, unicode)."""
        lines = self._header()
        for label, _, expr in self._items():
            lines.append("")
            lines.append(f"{label} =")
            lines.append(sp.pretty(expr, use_unicode=True, wrap_line=False))
        lines.append("")
        lines.append(f"direct and indirect Jacobians agree: {self.methods_agree}")
        lines.append("singular families:")
        for fam in self.families or ():
            lines.append(f"  {fam.name}")
        if not self.families:
            lines.append("  (none: the determinant has no factor depending on q)")
        return "\n".join(lines)

    def latex(self) -> str:
        """The derivation as LaTeX (one ``align*`` environment)."""
        out = ["% " + h for h in self._header()]
        out.append("\\begin{align*}")
        body = [f"{tex} &= {sp.latex(expr)}" for _, tex, expr in self._items()]
        for fam in self.families:
            body.append(f"&\\text{{singular: }} {sp.latex(fam.equation)}")
        out.append(" \\\\\n".join(body))
        out.append("\\end{align*}")
        return "\n".join(out)

    def __str__(self) -> str:
        return self.text()


# ---------------------------------------------------------------------- building
def _chain_of(source: Any) -> Chain:
    if isinstance(source, Chain):
        return source
    if isinstance(source, Hexapod):
        raise ParameterError(
            f"derive: source is the robot {source.name!r} (a Hexapod); derive one leg's chain, "
            f"e.g. robot.legs[0].chain (legs {choices(leg.name for leg in source.legs)})"
        )
    if isinstance(source, str):
        from . import robots

        return _chain_of(robots.get(source))
    params = getattr(source, "params", None)
    if isinstance(params, (Chain, Hexapod)):
        if isinstance(params, Hexapod):
            name = str(getattr(source, "tip", ""))
            for leg in params.legs:
                if name.startswith(leg.name + "_"):
                    return leg.chain
        return _chain_of(params)
    raise ParameterError(
        f"derive: source={source!r} has no Khalil table; give a Chain, a preset name or a "
        "model loaded from one (URDF files carry no table)"
    )


def _length_symbols(
    chain: Chain, names: Mapping[str, str] | None
) -> tuple[list[tuple[Any, Any]], dict[sp.Symbol, float], dict[sp.Symbol, str]]:
    """One symbol per non-zero ``d``/``r`` entry; returns per-row (d, r) and the value maps."""
    entries = []
    for j, row in enumerate(chain.rows, start=1):
        for kind in ("d", "r"):
            value = getattr(row, kind)
            if value != 0.0 and not (kind == "r" and row.sigma == "prismatic" and False):
                entries.append((f"{kind}{j}", value))
    all_d = all(key.startswith("d") for key, _ in entries)
    given = dict(names or {})
    unknown = [k for k in given if k not in {key for key, _ in entries}]
    if unknown:
        raise ParameterError(
            f"lengths={given!r}: entries {unknown} are not non-zero lengths of the table; "
            f"allowed keys are {choices(key for key, _ in entries)}"
        )
    symbols: dict[str, sp.Symbol] = {}
    values: dict[sp.Symbol, float] = {}
    sources: dict[sp.Symbol, str] = {}
    for k, (key, value) in enumerate(entries, start=1):
        label = given.get(key, f"l{k}" if all_d else key)
        sym = sp.Symbol(label, positive=True) if value > 0 else sp.Symbol(label, real=True)
        if sym in values:
            raise ParameterError(f"lengths: symbol name {label!r} is used twice")
        symbols[key] = sym
        values[sym] = float(value)
        sources[sym] = key
    per_row = [
        (symbols.get(f"d{j}", sp.Integer(0)), symbols.get(f"r{j}", sp.Integer(0)))
        for j in range(1, len(chain.rows) + 1)
    ]
    return per_row, values, sources


def _simplify(expr: Any) -> Any:
    if isinstance(expr, sp.MatrixBase):
        return expr.applyfunc(_simplify)
    return sp.trigsimp(sp.simplify(expr))


def default_rows(derivation_or_jacobian: Any, nq: int | None = None) -> tuple[str, ...]:
    """The default row selection: position rows, plus the angular rows that are not zero.

    When ``x, y, z`` plus the angular rows that are not identically zero make exactly ``n``
    rows, those are used (SCARA: ``x, y, z, wz``); otherwise the position rows.

    Args:
        derivation_or_jacobian: A :class:`Derivation`, or a boolean array of 6 flags "row is
            not identically zero" (numeric callers).
        nq: Number of joints (needed with the flags).

    Returns:
        Row names.

    """
    if isinstance(derivation_or_jacobian, Derivation):
        jd = derivation_or_jacobian.J_direct
        flags = [not all(sp.simplify(e) == 0 for e in jd.row(i)) for i in range(6)]
        n = jd.shape[1]
    else:
        flags = [bool(x) for x in derivation_or_jacobian]
        n = int(nq if nq is not None else 0)
    chosen = [0, 1, 2] + [i for i in (3, 4, 5) if flags[i]]
    if len(chosen) == n and n > 3:
        return tuple(ROW_NAMES[i] for i in chosen)
    return ("x", "y", "z")


def _families(
    expr: sp.Expr, q: tuple[sp.Symbol, ...], sigmas: Sequence[str]
) -> list[SingularFamily]:
    _, factors = sp.factor_list(expr)
    fams: list[SingularFamily] = []
    seen: set[Any] = set()
    for fac, _mult in factors:
        vars_ = tuple(k for k, s in enumerate(q) if fac.has(s))
        if not vars_:
            continue
        key = sp.simplify(fac)
        if key in seen or sp.simplify(-fac) in seen:
            continue
        seen.add(key)
        if len(vars_) == 1:
            k = vars_[0]
            revolute = sigmas[k] == "revolute"
            domain = sp.Interval.Lopen(-sp.pi, sp.pi) if revolute else sp.S.Reals
            try:
                sols = sp.solveset(fac, q[k], domain)
            except Exception:  # noqa: BLE001 - sympy may raise anything on hard equations
                sols = None
            if isinstance(sols, sp.FiniteSet) and all(s.is_number for s in sols):
                for sol in sorted(sols, key=lambda s: float(s)):
                    fams.append(
                        SingularFamily(
                            name=f"{q[k]} = {sp.sstr(sol)}" + (" (mod 2*pi)" if revolute else ""),
                            factor=fac,
                            equation=sp.Eq(q[k], sol),
                            variables=vars_,
                            joint=k,
                            value=float(sol),
                            periodic=revolute,
                        )
                    )
                continue
        fams.append(
            SingularFamily(
                name=f"{sp.sstr(fac)} = 0", factor=fac, equation=sp.Eq(fac, 0), variables=vars_
            )
        )
    return fams


def derive(
    source: Any,
    rows: str | Sequence[str] | None = None,
    lengths: Mapping[str, str] | None = None,
) -> Derivation:
    """Derive transforms, ``p``, Jacobians (direct and indirect), ``det J`` and singular families.

    Args:
        source: A :class:`~hexapod_kin.params.Chain`, a preset name (``"hexabot_leg"``) or a
            model loaded from a chain (its ``params``).
        rows: Rows of ``J_direct`` whose determinant is taken: ``None`` for the default
            (:func:`default_rows`: ``x, y, z`` for a 3-DOF leg, ``x, y, z, wz`` for the SCARA),
            ``"position"``, ``"all"`` or names such as ``("x", "y", "z", "wz")``.
        lengths: Names for the length symbols, keyed by table entry (``{"d2": "a"}``);
            default ``l1, l2, ...`` when every length is a ``d``, else ``d2``, ``r1``, ...

    Returns:
        The :class:`Derivation`.

    Raises:
        ParameterError: The source has no table, or ``rows`` / ``lengths`` are invalid.

    """
    chain = _chain_of(source)
    n = chain.nq
    q = tuple(sp.Symbol(f"q{k}", real=True) for k in range(1, n + 1))
    per_row, values, sources = _length_symbols(chain, lengths)
    transforms = []
    k = 0
    for row, (d, r) in zip(chain.rows, per_row):
        alpha, theta = _exact_angle(row.alpha), _exact_angle(row.theta)
        if row.sigma == "revolute":
            theta = theta + q[k]
            k += 1
        elif row.sigma == "prismatic":
            r = r + q[k]
            k += 1
        transforms.append(khalil_matrix(alpha, d, theta, r))
    cumulative = []
    acc = sp.eye(4)
    for t in transforms:
        acc = _simplify(acc * t)
        cumulative.append(acc)
    p = acc[:3, 3]
    # direct method: joint frame j is the frame of its row
    cols = []
    for j in chain.joint_rows:
        z = cumulative[j][:3, 2]
        o = cumulative[j][:3, 3]
        if chain.rows[j].sigma == "revolute":
            lin = z.cross(p - o)
            ang = z
        else:
            lin = z
            ang = sp.zeros(3, 1)
        cols.append(sp.Matrix.vstack(lin, ang))
    j_direct = _simplify(sp.Matrix.hstack(*cols))
    j_indirect = _simplify(p.jacobian(sp.Matrix(q)))
    deriv = Derivation(
        chain=chain,
        q=q,
        joint_names=tuple(chain.joint_names or ()),
        lengths=values,
        length_sources=sources,
        transforms=tuple(transforms),
        cumulative=tuple(cumulative),
        p=p,
        J_direct=j_direct,
        J_indirect=j_indirect,
        J=j_indirect,
        rows=(),
        J_rows=sp.zeros(0, n),
        det=None,
        gram=sp.Integer(0),
    )
    row_names = default_rows(deriv) if rows is None else tuple(
        ROW_NAMES[i] for i in row_indices(rows)
    )
    sel = j_direct.extract(list(row_indices(row_names)), list(range(n)))
    det = None
    if sel.shape[0] == n:
        det = sp.factor(_simplify(sel.det(method="berkowitz")))
        gram = sp.factor(det**2)
        fam_expr = det
    else:
        g = sel * sel.T if sel.shape[0] <= n else sel.T * sel
        gram = sp.factor(_simplify(g.det(method="berkowitz")))
        fam_expr = gram
    fams = _families(fam_expr, q, chain.sigmas) if fam_expr != 0 else []
    return Derivation(
        chain=chain,
        q=q,
        joint_names=deriv.joint_names,
        lengths=values,
        length_sources=sources,
        transforms=deriv.transforms,
        cumulative=deriv.cumulative,
        p=p,
        J_direct=j_direct,
        J_indirect=j_indirect,
        J=j_indirect,
        rows=row_names,
        J_rows=sel,
        det=det,
        gram=gram,
        families=tuple(fams),
    )
