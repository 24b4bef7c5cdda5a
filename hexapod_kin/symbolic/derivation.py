"""The same Khalil–Kleinfinger table, derived with sympy: transforms, Jacobians, det J, factored.

:func:`derive` builds, with symbolic lengths, every ``^{j-1}T_j`` and ``^0T_j``, the tip
position ``p(q)``, the Jacobian by the direct method (rows ``vx vy vz wx wy wz``, base axes) and
by the indirect one (``∂p/∂q``), ``det J`` factored (else ``det(J Jᵀ)``; a redundant chain's
families are the factors common to its maximal minors), and the singular families, one per
factor depending on ``q``, each checked against the numeric σ_min. For ``hexabot_leg``:
``det J = l2·l3·sin(q3)·(l1 + l2 cos q2 + l3 cos(q2 + q3))``. It runs within a CPU ``budget``
and is cached on disk (:mod:`.cache`), unfinished runs included. Lengths are ``l1, l2, ...``
when every length is a ``d``, else Khalil's names (``d2, r1``; tool ``tx, ty, tz``).
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import sympy as sp

from .. import _budget
from .._fields import fields_dict
from ..exceptions import CacheWarning, ParameterError
from ..jacobian_rows import choose_rows, row_indices
from ..params import Chain
from . import cache as _cache
from . import core as _core
from ._limits import DEFAULT_BUDGET
from .core import ROW_NAMES, khalil_matrix
from .families import SingularFamily, check_families, families_of
from .printing import expr_text, matrix_lines, wrap
from .sources import chain_of as _chain_of

__all__ = ["ROW_NAMES", "Derivation", "SingularFamily", "derive", "cached", "khalil_matrix",
           "row_indices"]  # fmt: skip

#: A Gram determinant (redundant chain) longer than this is described, not printed.
_GRAM_OPS = 300


@dataclass(frozen=True)
class Derivation:
    """Symbolic kinematics of one chain (all sympy objects; lengths symbolic).

    ``chain`` is the chain it was derived from, ``q`` its joint symbols ``q1..qn`` (named
    ``joint_names``), ``tip`` the tip frame's name, ``cached`` True when read from the disk cache.

    Attributes:
        lengths: Length symbol → value in [m] (what :meth:`numeric` substitutes).
        length_sources: Length symbol → the table entry it stands for (e.g. ``"d2"``).
        transforms: ``^{j-1}T_j`` for every table row (4×4 each).
        cumulative: ``T_base_j`` for every table row (4×4 each; base pose included).
        p: Tip position (tool included) in the base frame (3×1).
        J_direct: 6×n Jacobian by the direct method, rows ``vx vy vz wx wy wz`` (base axes).
        J_indirect: 3×n Jacobian ``∂p/∂q`` by the indirect method.
        J: The 3×n position Jacobian (equal to both methods).
        rows: The row names of :attr:`J_rows` (the selection used for :attr:`det`).
        J_rows: The selected rows of ``J_direct`` (k×n).
        det: ``det J_rows`` factored (``None`` when k ≠ n or not finished).
        gram: ``det(J_rows J_rowsᵀ)`` (or ``det(J_rowsᵀ J_rows)``), factored (``None``: not
            finished).
        families: The singular families read off :attr:`det` (or :attr:`gram`).
        reference: Name of the frame whose axes ``p`` and ``J`` are expressed in (the base).
        base_transform: ``T_base_0`` (4×4; identity without a base pose).
        tool_transform: ``T_n_tip`` (4×4; identity without a tool).
        method: How the determinant was computed (frame, wrist-centre split, Gram).
        incomplete: What could not be done, and why (empty when complete).
        seconds: CPU time of the derivation in [s] (0 when read from the cache).
        agree: Whether the direct and indirect position Jacobians are equal (``None``: not
            compared within the budget; :attr:`methods_agree` compares them).
        families_done: True when the determinant, the families and their checks were reached.
        formed: False when stage 1 was not reached (unexpanded products, not printed).

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
    gram: sp.Expr | None
    families: tuple[SingularFamily, ...] = field(default=())
    reference: str = "base"
    tip: str = "foot"
    base_transform: sp.Matrix = field(default_factory=lambda: sp.eye(4))
    tool_transform: sp.Matrix = field(default_factory=lambda: sp.eye(4))
    method: str = ""
    incomplete: tuple[str, ...] = ()
    seconds: float = 0.0
    cached: bool = False
    agree: bool | None = None
    families_done: bool = False
    formed: bool = True

    # ------------------------------------------------------------------ numbers
    def numeric(self, expr: Any) -> Any:
        """Substitute the chain's length values into ``expr`` (a sympy object)."""
        return sp.sympify(expr).subs(dict(self.lengths))

    def function(self, expr: Any) -> Callable[[np.ndarray], np.ndarray]:
        """``f(Q)`` of a sympy expression or matrix in ``q``, lengths substituted, vectorised.

        ``Q`` (n,) or (N, n) gives shape () or (N,); matrices (…, rows, cols).
        """
        num = self.numeric(expr)
        is_matrix = isinstance(num, sp.MatrixBase)
        shape = num.shape if is_matrix else ()
        entries = list(num) if is_matrix else [num]
        raw = sp.lambdify(self.q, entries, modules="numpy")  # one code object for all

        def f(q: np.ndarray) -> np.ndarray:
            arr = np.asarray(q, dtype=float)
            lead = arr.shape[:-1]
            cols = [arr[..., k] for k in range(len(self.q))]
            res = np.empty(lead + (len(entries),))
            for i, value in enumerate(raw(*cols)):
                res[..., i] = np.broadcast_to(np.asarray(value, dtype=float), lead)
            return res.reshape(lead + shape)

        return f

    @property
    def methods_agree(self) -> bool:
        """True when the direct and indirect position Jacobians are the same trig polynomial."""
        if self.agree is not None:
            return self.agree
        return _agree({"J_direct": self.J_direct, "J_indirect": self.J_indirect}, self.q,
                      self.chain.sigmas)  # fmt: skip

    @property
    def complete(self) -> bool:
        """True when every stage finished (nothing in :attr:`incomplete`)."""
        return not self.incomplete

    # ------------------------------------------------------------------ printing
    def _items(self) -> list[tuple[str, str, Any]]:
        n = len(self.transforms)
        items: list[tuple[str, str, Any]] = []
        if self.base_transform != sp.eye(4):
            items.append((f"T_{self.reference}_0", f"T_{{\\mathrm{{{self.reference}}},0}}",
                          self.base_transform))  # fmt: skip
        for j in range(n):
            items.append((f"^{j}T_{j + 1}", f"{{}}^{{{j}}}T_{{{j + 1}}}", self.transforms[j]))
        if self.tool_transform != sp.eye(4):
            tex = f"{{}}^{{{n}}}T_{{\\mathrm{{tool}}}}"
            items.append((f"^{n}T_tool", tex, self.tool_transform))
        if not self.formed:
            return items
        for j in range(1, n):
            items.append((f"^0T_{j + 1}", f"{{}}^{{0}}T_{{{j + 1}}}", self.cumulative[j]))
        items.append(("p(q)", "p(q)", self.p))
        items.append(("J (indirect, dp/dq)", "J_{\\mathrm{indirect}}", self.J_indirect))
        items.append(("J (direct, [v; w])", "J_{\\mathrm{direct}}", self.J_direct))
        if self.det is not None:
            items.append((f"det J[{','.join(self.rows)}]", "\\det J", self.det))
        elif self.gram is not None:
            items.append((f"det(J Jt) [{','.join(self.rows)}]", "\\det(J J^T)", self.gram))
        return items

    def _header(self) -> list[str]:
        joints = ", ".join(f"{s} ({n})" for s, n in zip(self.q, self.joint_names))
        lens = ", ".join(
            f"{s} = {v:g} m"
            if str(s) == self.length_sources[s]
            else f"{s} ({self.length_sources[s]}) = {v:g} m"
            for s, v in self.lengths.items()
        )
        head = [
            f"{self.chain.name}: Khalil-Kleinfinger table, T = Rx(alpha) Tx(d) Rz(theta) Tz(r)",
            f"joints: {joints}",
            f"lengths: {lens or '(none)'}",
            f"reference: p and J in the axes of {self.reference!r}, tip {self.tip!r}",
        ]
        return [line for h in head for line in wrap(h, indent=4)]

    def text(self) -> str:
        """The derivation as plain text, one formula a line (see :mod:`.printing`)."""
        return "\n".join(self.text_parts())

    def text_parts(self) -> Iterator[str]:
        """:meth:`text` in pieces, one per formula (a command prints what its budget allows)."""
        yield "\n".join(self._header())
        for label, _, expr in self._items():
            lines = [""]
            if isinstance(expr, sp.MatrixBase):
                lines.append(f"{label} =")
                lines.extend(matrix_lines(expr))
            elif self.det is None and sp.count_ops(expr) > _GRAM_OPS:
                lines.append(
                    f"{label} = sum of the squares of the maximal minors (Cauchy-Binet; "
                    f"{sp.count_ops(expr)} operations, not printed)"
                )
            else:
                lines.extend(wrap(f"{label} = {expr_text(expr)}", indent=4))
            yield "\n".join(lines)
        lines = [""]
        agree = {True: "yes", False: "NO", None: "not compared within the budget"}[self.agree]
        lines.append(f"direct and indirect Jacobians agree: {agree}")
        if self.method:
            lines.extend(wrap(f"determinant: {self.method}", indent=4))
        lines.append("singular families:")
        for fam in self.families or ():
            mark = {True: "checked", False: "CHECK FAILED", None: "not checked"}[fam.verified]
            text = f"  {fam.name}   [{mark}: {fam.check}]" if fam.check else f"  {fam.name}"
            lines.extend(wrap(text, indent=6))
        if not self.families and not self.incomplete:
            lines.append("  (none: no factor depending on q)")
        for what in self.incomplete:
            lines.extend(wrap(f"NOT DONE: {what}", indent=4))
        yield "\n".join(lines)

    def latex(self) -> str:
        """The derivation as LaTeX (one ``align*`` environment)."""
        out = ["% " + h for h in self._header()]
        out += ["% NOT DONE: " + w for w in self.incomplete]
        out.append("\\begin{align*}")
        body = [f"{tex} &= {sp.latex(expr)}" for _, tex, expr in self._items()]
        for fam in self.families:
            body.append(f"&\\text{{singular: }} {sp.latex(fam.equation)}")
        out.append(" \\\\\n".join(body))
        out.append("\\end{align*}")
        return "\n".join(out)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary: det, families (with checks), reference, incomplete, seconds."""
        return {
            "chain": self.chain.name,
            **fields_dict(self, "reference", "tip"),
            "joints": list(self.joint_names),
            "lengths_m": {str(k): v for k, v in self.lengths.items()},
            **fields_dict(self, "rows"),
            "det": None if self.det is None else str(self.det),
            "gram": None if self.gram is None else str(self.gram),
            "method": self.method,
            "families": [f.to_dict(self.joint_names) for f in self.families],
            **fields_dict(self, "incomplete", "seconds", "cached"),
        }

    def __str__(self) -> str:
        return self.text()


# ---------------------------------------------------------------------- stages
def _tidied(kin: Mapping[str, Any], q: tuple[sp.Symbol, ...], sigmas: Sequence[str],
            end: float) -> dict[str, Any]:  # fmt: skip
    """The printed matrices with each entry :func:`~.core.tidy`-ed, until ``end``."""

    def one(mat: sp.Matrix) -> sp.Matrix:
        out = mat.copy()
        for i in range(mat.rows):
            for j in range(mat.cols):
                if time.process_time() > end:
                    return out
                out[i, j] = _core.tidy(mat[i, j], q, sigmas)
        return out

    out = {k: one(kin[k]) for k in ("p", "J_indirect", "J_direct")}
    return out | {"cumulative": tuple(one(t) for t in kin["cumulative"])}


def _agree(kin: Mapping[str, Any], q: tuple[sp.Symbol, ...], sigmas: Sequence[str]) -> bool:
    """Direct and indirect position Jacobians equal as trigonometric polynomials (exact)."""
    for a, b in zip(kin["J_direct"][:3, :], kin["J_indirect"]):
        diff = sp.expand(a - b)
        if diff != 0 and _core._reduce(_core._to_poly(diff, q, sigmas), q) != 0:
            return False
    return True


#: The pace [s] of the optional work (extra determinant frames, tidied printing) when no
#: budget is given: the required stages are never cut, the optional ones do not run for hours.
UNBOUNDED_PACE = 30.0


def _stages(
    chain: Chain, rows: Any, lengths: Any, start: float, budget: float | None,
    have: Mapping[str, Any], families_only: bool = False,
) -> Iterator[tuple[str, Any]]:  # fmt: skip
    """The derivation's stages in order, skipping those in ``have`` (a cached partial run).

    ``budget`` (``None``: :data:`UNBOUNDED_PACE`) paces the optional work: extra determinant
    frames in its first 15 %, maximal minors in 70 %, tidied forms until 80 % (never past 90 %).
    """
    n = chain.nq
    q = tuple(sp.Symbol(f"q{k}", real=True) for k in range(1, n + 1))
    syms = _core.length_symbols(chain, lengths)
    span = UNBOUNDED_PACE if budget is None else budget
    t0, kin = time.process_time(), have.get("kinematics")
    if kin is None:
        kin = _core.kinematics(chain, q, syms)
        yield "kinematics", kin
    row_names = have.get("rows")
    if row_names is None:
        row_names = _row_names(rows, kin, n)
        yield "rows", row_names
    det = have.get("determinant")
    if det is None:
        det = _core.factored_determinant(
            chain, kin, q, row_names, start + 0.15 * span, start + 0.7 * span
        )
        yield "determinant", det
    fams = have.get("families")
    if fams is None:
        fams = families_of(det["factors"], q, chain, syms["values"])
        yield "families", fams
    if "checks" not in have:
        checked = check_families(fams, q, chain, syms["values"], row_names)
        unconfirmed = {det["factors"][i][0] for i in det.get("unconfirmed", ())}
        # a candidate factor (not common to every minor factored) that the numeric J does
        # not lose rank on is no family
        kept = tuple(f for f in checked if not (f.factor in unconfirmed and f.verified is False))
        yield "checks", kept
    if families_only:
        return
    if "agree" not in have:
        yield "agree", _agree(kin, q, chain.sigmas)
    if "tidy" not in have:
        end = min(max(time.process_time() + 0.2 * span, start + 0.8 * span), start + 0.9 * span)
        yield "tidy", _tidied(kin, q, chain.sigmas, end)
    yield "seconds", float(have.get("seconds", 0.0)) + time.process_time() - t0


# ---------------------------------------------------------------------- derive
def _row_names(rows: Any, kin: Mapping[str, Any], n: int) -> tuple[str, ...]:
    """The names of ``rows``; None: the default (:func:`~hexapod_kin.jacobian_rows.choose_rows`)."""
    if rows is not None:
        return tuple(ROW_NAMES[i] for i in row_indices(rows))
    jd = kin["J_direct"]
    return choose_rows([not all(e == 0 for e in jd.row(i)) for i in range(6)], n)


def _numeric_default_rows(chain: Chain) -> tuple[str, ...]:
    """The default rows from the numeric Jacobian (not zero at three random q), before sympy."""
    rng = np.random.default_rng(20260101)
    qs = rng.uniform(-math.pi, math.pi, (3, chain.nq))
    jac = np.array([_core.numeric_jacobian(chain, q, range(6)) for q in qs])
    return choose_rows([bool(np.abs(jac[:, i]).max() > 1e-12) for i in range(6)], chain.nq)


def _cache_key(chain: Chain, rows: Any, lengths: Any) -> str:
    """The key of a derivation: the table and the row names (``None``: the default ones)."""
    if rows is None:
        rows = _numeric_default_rows(chain)
    return _cache.key(
        {
            "rows": [
                [r.sigma, repr(r.alpha), repr(r.d), repr(r.theta), repr(r.r)] for r in chain.rows
            ],
            "sigmas": list(chain.sigmas),
            "base": None if chain.base_pose is None else chain.base_pose.matrix.tolist(),
            "tool": None if chain.tool is None else chain.tool.matrix.tolist(),
            "select": [ROW_NAMES[i] for i in row_indices(rows)],
            "lengths": sorted((lengths or {}).items()),
            "limits": [[lim.lower, lim.upper] for lim in chain.limits or ()],
        }
    )


#: Derivations of this process, complete or not, by cache key (in front of the disk cache).
_MEMO: dict[str, Mapping[str, Any]] = {}


#: The key of the stages dict recording an unfinished run: ``(reason, budget in s)``.
ATTEMPT = "__attempt__"


def clear_memory() -> None:
    """Forget the derivations memoised in this process (the disk cache stays)."""
    _MEMO.clear()


#: The mark of an entry while its derivation runs (or of one whose process died): it answers
#: no call; a later call carries on from the stages it holds.
IN_PROGRESS = "in progress (or its process ended) before the end"
#: The reason kept by a run stopped after the families on purpose (``families_only``).
FAMILIES_ONLY = "stopped after the families (families_only); a later call carries on"


def _usable(
    stages: Mapping[str, Any] | None, budget: float | None, families_only: bool = False
) -> bool:
    """A cached run answers a call: complete, or stopped at a budget at least as large.

    With ``families_only``: also any run that reached the families' checks.
    """
    if stages is None:
        return False
    attempt = stages.get(ATTEMPT)
    if attempt is None or (families_only and "checks" in stages):
        return True
    tried = attempt[1]
    return budget is not None and tried is not None and budget <= tried


def _checked_load(
    chain: Chain, lengths: Any, digest: str, then: str, stacklevel: int = 2
) -> dict[str, Any] | None:
    """The disk cache's entry ``digest`` if what it claims holds for the table (else a warning)."""
    from .checks import claims_hold

    found = _cache.load(digest)
    values = _core.length_symbols(chain, lengths)["values"]
    if found is None or claims_hold(found, chain, values):
        return found
    warnings.warn(
        f"symbolic cache entry {digest[:12]}: its kinematics, determinant or families do not "
        f"match the table (edited); {then}",
        CacheWarning,
        stacklevel=stacklevel,
    )
    return None


def _job(
    chain: Chain, rows: Any, lengths: Any, digest: str, budget: float | None,
    families_only: bool, found: Mapping[str, Any] | None, read: bool, write: bool,
) -> Iterator[tuple[str, Any]]:  # fmt: skip
    """What a derivation does within its budget (in its child process, or inline).

    With ``read``: the checked disk entry first (``"__found__"``); unless it answers, the
    stages, each written to the cache (``write``) before it is yielded.
    """
    start = time.process_time()
    if read:
        found = _checked_load(chain, lengths, digest, "recomputing it")
        yield "__found__", found
    if _usable(found, budget, families_only):
        return
    have = {k: v for k, v in (found or {}).items() if k != ATTEMPT}
    # what the file says until the last stage is written: unfinished, answering no budget (a
    # concurrent call carries on from its stages); the caller marks a budget stop
    stop = (IN_PROGRESS, None)
    writer = _cache.Writer(digest, have) if write else None
    for name, value in _stages(chain, rows, lengths, start, budget, have, families_only):
        if writer is not None:  # on disk before the caller hears of it
            mark = (FAMILIES_ONLY, None) if families_only and name == "checks" else stop
            writer.add(name, value, None if name == "seconds" else mark, ATTEMPT)
        yield name, value


def derive(
    source: Any,
    rows: str | Sequence[str] | None = None,
    lengths: Mapping[str, str] | None = None,
    *,
    base: str | None = None,
    tip: str | None = None,
    budget: float | None = DEFAULT_BUDGET,
    cache: bool = True,
    within: float | None = None,
    families_only: bool = False,
) -> Derivation:
    """Derive transforms, ``p``, Jacobians, ``det J`` factored and the singular families.

    Args:
        source: A :class:`~hexapod_kin.params.Chain`, a preset name, a URDF (path, text,
            ``erd:NAME``; :func:`~hexapod_kin.chain_from_urdf`), a :class:`Hexapod` with
            ``tip=``, or a loaded model (its own base and tip frames).
        rows: Rows of ``J_direct`` whose determinant is taken (default
            :func:`~hexapod_kin.jacobian_rows.choose_rows`; ``"position"``, ``"all"``, names).
        lengths: Names for the length symbols, keyed by table entry (``{"d2": "a"}``).
        base: Base frame (URDF sources, hexapods): the frame ``p`` and ``J`` are expressed in.
        tip: Tip frame (URDF sources; a hexapod's foot, e.g. ``"leg2_foot"``).
        budget: CPU budget in [s] (``None``: no limit), in one child process; at the budget
            it stops and :attr:`Derivation.incomplete` says what is missing.
        cache: Read and write the on-disk cache (an unfinished derivation is kept with its
            budget: a larger one carries on).
        within: CPU seconds this call may spend (``budget`` still decides the cache reuse).
        families_only: Stop once the families are derived and checked.

    Raises:
        ParameterError: No table, or invalid ``rows`` / ``lengths`` / ``budget``.
        ConfigurationError: A URDF chain that a Khalil table cannot express.

    """
    if budget is not None and (not isinstance(budget, (int, float)) or not budget > 0):
        raise ParameterError(f"budget={budget!r} is not allowed; a time in seconds > 0 or None")
    chain, reference, tip_name, syms, digest = _start(source, base, tip, rows, lengths)
    found = _MEMO.get(digest) if cache else None
    run_for = budget if within is None else min(within, budget or math.inf)
    done: dict[str, Any] = {}
    reason: str | None = None
    unread = False  # an entry not read within the budget is neither used nor overwritten
    if not _usable(found, budget, families_only):
        read = cache and found is None and (_cache.cache_dir() / f"{digest}.json").exists()
        kept = _cache.snapshot(digest) if cache else None
        args = (chain, rows, lengths, digest, budget, families_only, found, read, cache)
        try:
            done, reason = _budget.run(_job, args, None if run_for is None else max(run_for, 0.0))
        except KeyboardInterrupt:  # the entry as it was before (not the worker's part-run)
            if cache:
                _cache.restore(digest, kept)
            raise
        if "__found__" in done:
            found = done.pop("__found__")
        else:
            unread = read
    if _usable(found, budget, families_only):
        assert found is not None
        stages: dict[str, Any] = dict(found)
        reason = _kept_reason(stages)
        if reason is not None and stages[ATTEMPT][0] == FAMILIES_ONLY:
            reason = FAMILIES_ONLY
        from_cache = True
    else:
        write = cache and not unread
        have = {k: v for k, v in (found or {}).items() if k != ATTEMPT}
        before = (found or {}).get(ATTEMPT)  # kept with the larger of this budget and the last
        tried = budget
        if budget is not None and before is not None and before[1] is not None:
            tried = max(budget, before[1])
        if reason is not None and cache:
            _cache.sweep(digest)
        stages = {**have, **done}
        if reason is None and families_only and "seconds" not in stages:  # kept as unfinished
            reason = FAMILIES_ONLY  # (the file says so since the "checks" stage)
            stages[ATTEMPT] = (reason, None)
        elif reason is not None:
            if budget is not None and reason.startswith("budget of"):
                reason = f"budget of {budget:g} s reached"  # the call's budget, not the rest
            stages[ATTEMPT] = (reason, tried)
            if write:  # the worker's file says "in progress": now why it stopped
                _cache.store(digest, stages)
        from_cache = False
    if cache:
        if len(_MEMO) > 64:
            _MEMO.clear()
        _MEMO[digest] = stages
    return _assemble(chain, reference, tip_name, syms, stages, reason, from_cache, rows)


def _start(source: Any, base: Any, tip: Any, rows: Any, lengths: Any) -> tuple[Any, ...]:
    """``(chain, reference, tip, length symbols, cache key)``, the arguments checked first."""
    chain, reference, tip_name = _chain_of(source, base, tip)
    if rows is not None:
        row_indices(rows)
    syms = _core.length_symbols(chain, lengths)  # validates names early
    return chain, reference, tip_name, syms, _cache_key(chain, rows, lengths)


def _assemble(
    chain: Chain, reference: str, tip: str, syms: Mapping[str, Any], stages: Mapping[str, Any],
    reason: str | None, from_cache: bool, rows: Any,
) -> Derivation:  # fmt: skip
    n = chain.nq
    q = tuple(sp.Symbol(f"q{k}", real=True) for k in range(1, n + 1))
    incomplete: list[str] = []
    kin = stages.get("kinematics")
    if kin is None:  # not even stage 1 in time: plain products, no simplification
        kin = _core.kinematics(chain, q, syms, simplify=False)
        incomplete.append(
            f"products, p and Jacobians ({reason}); kept as unexpanded products (J_indirect "
            "not derived: the direct one's rows) and not printed"
        )
    kin = {**kin, **(stages.get("tidy") or {})}  # the tidied forms are equal, shorter
    row_names = stages.get("rows")
    if row_names is None and rows is None and "kinematics" not in stages:
        row_names = _numeric_default_rows(chain)  # the fallback's sums are unevaluated
    elif row_names is None:
        row_names = _row_names(rows, kin, n)
    sel = [ROW_NAMES.index(r) for r in row_names]
    det_stage = stages.get("determinant")
    det, gram, method = (None, None, "") if det_stage is None else (
        det_stage["det"], det_stage["gram"], det_stage["how"])  # fmt: skip
    if det_stage is None:
        incomplete.append(f"det J factored and singular families ({reason})")
    fams = stages.get("checks")
    if fams is None:
        fams = stages.get("families")
        if fams is not None:
            incomplete.append(f"numeric check of the families against sigma_min ({reason})")
        elif det_stage is not None:
            incomplete.append(f"singular families ({reason})")
    agree = stages.get("agree")
    if agree is None and det_stage is not None and fams is not None:
        incomplete.append(f"direct = indirect Jacobian, exactly ({reason})")
    jd = kin["J_direct"]
    return Derivation(
        chain, q, tuple(chain.joint_names or ()), dict(syms["values"]), dict(syms["sources"]),
        tuple(kin["transforms"]), tuple(kin["cumulative"]), kin["p"], jd, kin["J_indirect"],
        kin["J_indirect"], tuple(row_names), jd.extract(sel, list(range(n))), det, gram,
        tuple(fams or ()), reference, tip, kin["base"], kin["tool"], method, tuple(incomplete),
        0.0 if from_cache else float(stages.get("seconds", 0.0)), from_cache, agree,
        det_stage is not None and stages.get("checks") is not None, "kinematics" in stages,
    )  # fmt: skip


def cached(source: Any, rows: str | Sequence[str] | None = None) -> Derivation | None:
    """The derivation of ``source`` if this process or the disk cache has it, else ``None``.

    Never runs sympy's derivation; ``source``, ``rows`` and the errors
    (:class:`~hexapod_kin.exceptions.ParameterError`) are those of :func:`derive`.
    """
    chain, reference, tip_name, syms, digest = _start(source, None, None, rows, None)
    stages = _MEMO.get(digest)
    if stages is None:
        stages = _checked_load(chain, None, digest, "not used", stacklevel=3)
    if stages is None:
        return None
    _MEMO[digest] = stages
    return _assemble(chain, reference, tip_name, syms, stages, _kept_reason(stages), True, rows)


def _kept_reason(stages: Mapping[str, Any]) -> str | None:
    """Why a kept entry is unfinished (None: complete)."""
    attempt = stages.get(ATTEMPT)
    return None if attempt is None else f"{attempt[0]}; kept, a larger budget carries on"
