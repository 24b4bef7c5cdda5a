"""Singular families as numbers: residuals, exact distances, labels — without waiting on sympy.

A family is the zero set of one factor of ``det J`` (or ``det(J Jᵀ)``) derived by
:func:`hexapod_kin.symbolic.derive` when asked, checked against the model's Jacobian, kept on
disk as text and compiled into numpy evaluators (:mod:`._zeroset`), never ``eval``-ed.
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import _cache as _disk
from .._fields import fields_dict
from .._numerics import wrap_angles
from ..exceptions import HexapodKinError, ParameterError, positive
from ._zeroset import closest_distance, compile_factor, project

__all__ = ["Family", "Families", "families_for", "cache_dir"]

_VERSION = 5
_THEN = "not used"
#: Largest relative difference between symbolic and numeric ``det`` accepted as equal.
_MATCH_RTOL = 1e-6
#: CPU seconds of a family derivation's process beyond the derivation's own budget: sympy's
#: import and the check's evaluation of the determinant.
_CHECK_BUDGET = 10.0


# ------------------------------------------------------------------------ one family
@dataclass(frozen=True)
class Family:
    """One singular family, as numbers: :class:`hexapod_kin.symbolic.SingularFamily`'s fields.

    No sympy objects: ``equation`` is text (lengths symbolic, e.g. ``"Eq(q3, 0)"``) and
    ``factor`` too (lengths substituted), compiled once (:func:`~._zeroset.compile_factor`).
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
        object.__setattr__(self, "_jet", compile_factor(self.factor, self.variables))

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickled as its fields (the compiled factor is rebuilt on loading)."""
        fields = (self.name, self.equation, self.variables, self.joint, self.value)
        return (Family, (*fields, self.periodic, self.factor))

    def residual(self, q: Any) -> np.ndarray:
        """Signed residual at ``q`` (…, nq): the factor; the wrapped offset for ``q_k = v``."""
        qa = np.asarray(q, dtype=float)
        if self.joint is not None and self.value is not None:
            d = qa[..., self.joint] - self.value
            return wrap_angles(d) if self.periodic else d
        x = qa[..., list(self.variables)].reshape(-1, len(self.variables))
        return np.asarray(self._jet(x, False)[0]).reshape(qa.shape[:-1])

    def distance(self, q: Any) -> np.ndarray:
        """Joint-space distance (…,) from ``q`` to the family, in [rad]/[m].

        ``q_k = value``: ``|q_k − value|`` (wrapped); implicit families: ``min ‖x − q‖`` over
        ``f(x) = 0`` (:func:`~._zeroset.closest_distance`).
        """
        qa = np.asarray(q, dtype=float)
        if self.joint is not None and self.value is not None:
            return np.abs(self.residual(qa))
        p = np.ascontiguousarray(qa[..., list(self.variables)].reshape(-1, len(self.variables)))
        return closest_distance(self._jet, p).reshape(qa.shape[:-1])

    def project(self, q: Any) -> np.ndarray | None:
        """A configuration on the family near ``q`` (nq,), or None when none is found.

        ``q_k`` moved onto the value, or the projection onto ``f = 0`` (:func:`~._zeroset.project`).
        """
        out = np.array(q, dtype=float)
        if self.joint is not None and self.value is not None:
            out[self.joint] -= float(self.residual(out))
            return out
        cols = list(self.variables)
        point = project(self._jet, out[cols][None])[0]
        if point is None:
            return None
        out[cols] = point
        return out

    def to_dict(self, joint_names: tuple[str, ...] | None = None) -> dict[str, Any]:
        """JSON-ready dict (joint by name when ``joint_names`` is given)."""
        out = fields_dict(self, "name", "equation", "variables", "joint", "value", "periodic")
        if self.joint is not None and joint_names is not None:
            out["joint"] = joint_names[self.joint]
        return out | {"factor": self.factor}


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
        """``(index, distance, second_index, second_distance)`` (M,) of ``q`` (M, nq).

        The nearest and second-nearest families; −1 / inf where there is no (second) family.
        """
        m = q.shape[0]
        none = np.full(m, -1, dtype=np.int64), np.full(m, np.inf)
        if not self.families or m == 0:
            return none[0], none[1], none[0].copy(), none[1].copy()
        dist = np.stack([fam.distance(q) for fam in self.families], axis=1)
        dist = np.where(np.isnan(dist), np.inf, dist)
        order = np.argsort(dist, axis=1, kind="stable")
        rows, best = np.arange(m), order[:, 0].astype(np.int64)
        if dist.shape[1] < 2:
            return best, dist[rows, best], none[0].copy(), none[1].copy()
        second = order[:, 1].astype(np.int64)
        return best, dist[rows, best], second, dist[rows, second]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        families = [f.to_dict() for f in self.families]
        return {"families": families, **fields_dict(self, "origin", "reason", "key")}


# ------------------------------------------------------------------------ tables and keys
def cache_dir() -> Path:
    """Where derived families are kept: :func:`hexapod_kin._cache.folder` ``("families")``."""
    return _disk.folder("families")


def _table(model: Any) -> tuple[Any, str]:
    """The model's Khalil chain (its own, or recovered from the URDF) and why not, if none."""

    def build() -> tuple[Any, str]:
        from .._fromurdf import chain_from_urdf
        from ..params import Chain

        params = model.params
        if isinstance(params, Chain) and model.nq == params.nq:
            return params, ""
        try:
            chain = chain_from_urdf(model)
        except HexapodKinError as err:
            return None, f"no Khalil table: chain_from_urdf refused the chain ({err})"
        if chain.nq != model.nq:
            return None, f"the recovered table has {chain.nq} joints, the model {model.nq}"
        return chain, ""

    return model.cached("singularity.table", build)


def _key(chain: Any, rows: tuple[str, ...]) -> str:
    table = [(r.sigma, repr(r.alpha), repr(r.d), repr(r.theta), repr(r.r)) for r in chain.rows]
    base, tool = repr(getattr(chain, "base_pose", None)), repr(getattr(chain, "tool", None))
    entry = {"v": _VERSION, "rows": list(rows), "table": table, "base": base, "tool": tool}
    return _disk.key(entry)[:32]


def _family(f: Any) -> Family:
    """A :class:`Family` from a mapping of its fields (JSON, or a derivation's family)."""
    joint = None if f["joint"] is None else int(f["joint"])
    value = None if f["value"] is None else float(f["value"])
    variables = tuple(int(v) for v in f["variables"])
    name, equation, factor = str(f["name"]), str(f["equation"]), str(f["factor"])
    return Family(name, equation, variables, joint, value, bool(f["periodic"]), factor)


def _holds(fams: tuple[Family, ...], model: Any, rows: tuple[str, ...]) -> None:
    """Families read from disk checked against the model before use, both ways.

    Every zero is singular (``σ_min ≤ 1e-7 σ_max`` at projections of three random
    configurations), and every sign change of a square ``det J`` along four random lines
    (:func:`_singular_points`) lies within 1e-6 of a family; else ``ValueError`` (an edited
    entry).
    """
    from .measure import measures

    qs = model.random_q(3, seed=20251202)
    size = max(float(measures(model, q, rows).singular_values[0]) for q in qs)
    for fam in fams:
        cols = list(fam.variables)
        on_zero = project(fam._jet, np.array([q[cols] for q in qs], dtype=float))
        for q, x in zip(qs, on_zero):
            if x is not None:
                on = np.array(q, dtype=float)
                on[cols] = x
                if not measures(model, on, rows).sigma_min <= 1e-7 * size:
                    raise ValueError(f"the model's J keeps its rank where {fam.name}'s factor is 0")
            if fam.joint is not None and fam.value is not None:
                on = np.array(q, dtype=float)
                on[fam.joint] = fam.value
                if not measures(model, on, rows).sigma_min <= 1e-9 * size:
                    raise ValueError(f"the model's J keeps its rank on {fam.name}")
    if len(rows) == model.nq:
        for q in _singular_points(model, rows):
            near = min((float(f.distance(q[None])[0]) for f in fams), default=np.inf)
            if not near <= 1e-6:
                raise ValueError(f"a singular configuration of the model is on no family: {q}")


def _singular_points(model: Any, rows: tuple[str, ...]) -> list[np.ndarray]:
    """Zeros of ``det J`` on four random lines (65 samples over ``[-π, π]``, 50 bisections)."""
    from .measure import measures

    rng = np.random.default_rng(20251203)
    starts = model.random_q(4, seed=20251203)
    ts = np.linspace(-math.pi, math.pi, 65)
    found = []
    for q0 in starts:
        u = rng.normal(size=model.nq)
        u /= np.linalg.norm(u)

        def det(t: float, q0: np.ndarray = q0, u: np.ndarray = u) -> float:
            return float(measures(model, q0 + t * u, rows).det)

        vals = [det(t) for t in ts]
        for a, b, fa, fb in zip(ts[:-1], ts[1:], vals[:-1], vals[1:]):
            if not (fa < 0 < fb or fb < 0 < fa):
                continue
            for _ in range(50):
                mid = 0.5 * (a + b)
                fm = det(mid)
                if (fm < 0) == (fa < 0):
                    a, fa = mid, fm
                else:
                    b = mid
            found.append(q0 + 0.5 * (a + b) * u)
    return found


def _read_cache(
    key: str, nq: int, check: Any = None
) -> tuple[tuple[Family, ...], str, float] | None:
    """``(families, why unfinished ("" if finished), budget of that run [s])`` or ``None``.

    ``None`` when missing; ``None`` with one ``CacheWarning`` when damaged, of another key, or
    failing ``check(families)``. Factors are parsed by a whitelist, never evaluated.
    """
    data = _disk.load("families", key, _VERSION, _THEN)
    if data is None:
        return None
    try:
        if not isinstance(data, dict) or data.get("nq") != nq:
            raise ValueError("not the entry of this table and rows (another key)")
        fams = tuple(_family(f) for f in data["families"])
        for fam in fams:  # every factor through the parser's whitelist now, never evaluated
            compile_factor(fam.factor, fam.variables)
        incomplete = str(data.get("incomplete", ""))
        if check is not None and not incomplete:
            check(fams)
        return fams, incomplete, float(data.get("budget", 0.0))
    except Exception as exc:  # noqa: BLE001 - any damage: derive again
        _disk.damaged("families", key, exc, _THEN, stacklevel=2)
        return None


def _write_cache(
    key: str, nq: int, fams: tuple[Family, ...], incomplete: str = "", budget: float = 0.0
) -> None:
    """Keep the families of ``key`` (best effort: a read-only cache costs a derivation)."""
    data: dict[str, Any] = {"nq": nq, "families": [f.to_dict() for f in fams]}
    if incomplete:
        data.update(incomplete=incomplete, budget=budget)
    _disk.store("families", key, json.loads(json.dumps(data)), _VERSION)


# ------------------------------------------------------------------------ deriving
_NO_FACTOR = (
    "no factor of det J (square J) nor common to its maximal minors (redundant J) depends on q"
)


class _Miss(Exception):
    """Not in the disk cache (nothing is stored in the model's cache then)."""


def _derive_errors() -> tuple[type[BaseException], ...]:
    """Errors a derivation may end with; anything else is a bug and propagates."""
    import sympy

    failed = sympy.polys.polyerrors.PolificationFailed
    return (HexapodKinError, TimeoutError, NotImplementedError, RecursionError,
            sympy.PolynomialError, failed)  # fmt: skip


def _derive_job(
    chain: Any, rows: tuple[str, ...], budget: float, qs: np.ndarray
) -> Iterator[tuple[str, Any]]:
    """The derivation's side of :func:`families_for`, yielding plain values only (no sympy).

    ``("derived", (incomplete, kind, values, families))`` with ``kind`` ``"det"`` (``|det J|``
    at ``qs``), ``"gram"`` (``|det(J Jᵀ)|``) or ``None``, the families' factors as text
    (lengths substituted); or ``("failed", "Error: message")`` on an expected error.
    """
    from .. import symbolic
    from ..symbolic.checks import evaluate

    try:
        deriv = symbolic.derive(chain, rows=rows, budget=float(budget), families_only=True)
        incomplete = "" if deriv.families_done else "; ".join(deriv.incomplete)
        if incomplete and not deriv.families:
            yield "derived", (incomplete, None, None, ())
            return
        # one pass over the expression (lambdify of a 7-joint Gram determinant takes seconds)
        at = {**deriv.lengths, **{s: qs[:, k] for k, s in enumerate(deriv.q)}}
        kind, expr = ("det", deriv.det) if deriv.det is not None else ("gram", deriv.gram)
        values = None
        if expr is not None:
            values = np.abs(np.broadcast_to(evaluate(expr, at), (len(qs),)))
        fields = ("name", "equation", "variables", "joint", "value", "periodic")
        fams = tuple(
            _family({**{k: getattr(f, k) for k in fields}, "factor": deriv.numeric(f.factor)})
            for f in deriv.families
        )
        yield "derived", (incomplete, kind if expr is not None else None, values, fams)
    except _derive_errors() as err:
        yield "failed", f"{type(err).__name__}: {err}"


def _derived(chain: Any, rows: tuple[str, ...], budget: float, qs: np.ndarray) -> tuple[Any, ...]:
    """:func:`_derive_job`'s answer or ``("failed", message)``; own process unless sympy's here."""
    from .. import _budget

    args = (chain, rows, float(budget), qs)
    if "sympy" in sys.modules:
        done = dict(_derive_job(*args))
    else:  # its start-up is not counted: the derivation keeps its own budget inside
        done, reason = _budget.run(_derive_job, args, float(budget) + _CHECK_BUDGET)
        if not done:
            return ("failed", str(reason))
    if "failed" in done:
        return ("failed", done["failed"])
    return tuple(done["derived"])


def _numeric_families(
    kind: str | None, sym: Any, qs: np.ndarray, model: Any, rows: tuple[str, ...]
) -> None:
    """Check the derivation's ``|det|`` or ``|det(J Jᵀ)|`` (``kind``), ``sym`` at ``qs``, on J.

    Raises ParameterError: no determinant derived, or they differ (other frames or rows).
    """
    from .measure import measures

    res = [measures(model, q, rows) for q in qs]
    if kind == "det":
        num = np.abs([m.det for m in res])
    elif kind == "gram":
        num = np.array([m.manipulability for m in res]) ** 2
    else:
        raise ParameterError("the derivation has no determinant to check the families against")
    err = float(np.max(np.abs(sym - num))) / max(float(np.max(num)), 1e-300)
    if not err <= _MATCH_RTOL:
        msg = (
            f"the symbolic det of the table differs from the model's (relative {err:.1e}): "
            "the table's frames do not match the model's Jacobian rows"
        )
        raise ParameterError(msg, parameter="rows", value=rows)


def families_for(
    model: Any, rows: tuple[str, ...], *, derive: bool = False, budget: float = 10.0
) -> Families:
    """The singular families of a loaded ``model`` for the Jacobian rows ``rows`` (names).

    ``derive``: derive them with sympy within ``budget`` (CPU [s]; a stopped run is kept with
    its budget, a larger one carries on) when not on disk yet; else the call never waits.
    Raises ParameterError: ``budget`` not a finite value > 0.
    """
    positive("budget", budget)
    chain, why = _table(model)
    if chain is None:
        return Families((), "none", why)
    key = _key(chain, rows)
    mem = f"singularity.families.{key}"

    read: list[Any] = []  # the disk entry, read once (a damaged one warns once)

    def load() -> tuple[Family, ...]:
        read.append(_read_cache(key, model.nq, lambda fams: _holds(fams, model, rows)))
        found = read[0]
        if found is None or found[1]:
            raise _Miss  # unfinished runs are read from disk each time (a later one may finish)
        return found[0]

    try:
        hit = model.cached(mem, load)
        return Families(hit, "cache", "" if hit else _NO_FACTOR, key)
    except _Miss:
        pass
    partial = read[0] if read else _read_cache(key, model.nq, lambda f: _holds(f, model, rows))
    if partial is not None and (not derive or budget <= partial[2]):
        return Families(  # stopped at a budget at least this large: not spent again
            partial[0], "cache", f"{partial[1]} (kept; a larger family budget tries again)", key
        )
    if not derive:
        why = "families not derived yet (pass families=True, or run `hexapod-kin derive`; "
        return Families((), "none", why + "they are then kept on disk)", key)
    tried = max(float(budget), partial[2] if partial is not None else 0.0)
    qs = model.random_q(16, seed=4242)
    got = _derived(chain, rows, budget, qs)
    if got[0] == "failed":
        return Families((), "none", f"derivation failed: {got[1]}", key)
    incomplete, kind, sym, derived = got
    if incomplete and not derived:
        reason = f"derivation incomplete: {incomplete}"
        _write_cache(key, model.nq, (), reason, tried)
        return Families((), "none", reason, key)
    try:
        _numeric_families(kind, sym, qs, model, rows)
    except HexapodKinError as err:
        return Families((), "none", f"derivation failed: {type(err).__name__}: {err}", key)
    fams = tuple(derived)
    if incomplete:  # partial families: used and kept with the budget they had
        reason = f"derivation incomplete: {incomplete}"
        _write_cache(key, model.nq, fams, reason, tried)
        return Families(fams, "derived", reason, key)
    _write_cache(key, model.nq, fams)
    model.cached(mem, lambda: fams)
    return Families(fams, "derived", "" if fams else _NO_FACTOR, key)
