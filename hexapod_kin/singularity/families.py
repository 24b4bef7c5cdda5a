"""Singular families as numbers: residuals, distances, labels — without waiting on sympy.

A family is the zero set of one factor of ``det J`` (or of ``det(J Jᵀ)``), derived by
:func:`hexapod_kin.symbolic.derive` from the chain's Khalil table: the model's own table, or
the one :meth:`hexapod_kin.params.Chain.from_urdf` recovers from a URDF chain (a hexapod leg
on its mount, Solo12, UR5, ...). Deriving is sympy work, so it happens only when asked
(:func:`families_for` with ``derive=True``, within a time budget); the result is validated
against the model's own Jacobian (the symbolic ``det`` must equal the numeric one at random
configurations), turned into plain text expressions (lengths substituted) and kept on disk
(:func:`cache_dir`, keyed by the table and the rows), so
later scans — in any process — read them back without importing sympy. The text is
evaluated by a small whitelisting evaluator (numbers, ``q1..qn``, ``+ - * / **``, ``sin``,
``cos``, ``tan``, ``sqrt``, ``pi``), never by ``eval``.

When no family is available the result says why (:attr:`Families.reason`).
"""

from __future__ import annotations

import ast
import hashlib
import inspect
import json
import math
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._io import atomic_write
from .._numerics import wrap_angles
from ..exceptions import HexapodKinError, ParameterError

__all__ = ["Family", "Families", "families_for", "cache_dir"]

_VERSION = 1
#: Largest relative difference between symbolic and numeric ``det`` accepted as equal.
_MATCH_RTOL = 1e-6


# ------------------------------------------------------------------------ safe evaluation
_FUNCS: dict[str, Callable[[Any], Any]] = {
    "sin": np.sin,
    "cos": np.cos,
    "tan": np.tan,
    "sqrt": np.sqrt,
    "Abs": np.abs,
}
_BINOPS: dict[type, Callable[[Any, Any], Any]] = {
    ast.Add: np.add,
    ast.Sub: np.subtract,
    ast.Mult: np.multiply,
    ast.Div: np.divide,
    ast.Pow: np.power,
}


def _compile(text: str, nq: int) -> ast.Expression:
    """Parse ``text`` and check it uses only the whitelisted grammar (raises ParameterError)."""
    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError as err:
        raise ParameterError(f"family expression {text!r} does not parse: {err.msg}") from None
    allowed_names = {f"q{k}" for k in range(1, nq + 1)} | {"pi"}
    for node in ast.walk(tree):
        ok = isinstance(node, (ast.Expression, ast.Load, ast.UAdd, ast.USub, *_BINOPS))
        ok = ok or isinstance(node, (ast.BinOp, ast.UnaryOp))
        ok = ok or (isinstance(node, ast.Constant) and isinstance(node.value, (int, float)))
        ok = ok or (isinstance(node, ast.Name) and node.id in allowed_names | set(_FUNCS))
        ok = ok or (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id in _FUNCS
            and len(node.args) == 1
            and not node.keywords
        )
        if not ok:
            raise ParameterError(
                f"family expression {text!r}: {type(node).__name__} is not allowed",
                parameter="expression",
                value=text,
                allowed="numbers, q1..qn, pi, + - * / **, sin cos tan sqrt Abs",
            )
    return tree


def _evaluate(node: ast.AST, q: np.ndarray) -> Any:
    if isinstance(node, ast.Expression):
        return _evaluate(node.body, q)
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)):
        return float(node.value)
    if isinstance(node, ast.Name):
        return math.pi if node.id == "pi" else q[..., int(node.id[1:]) - 1]
    if isinstance(node, ast.UnaryOp):
        val = _evaluate(node.operand, q)
        return -val if isinstance(node.op, ast.USub) else val
    if isinstance(node, ast.BinOp):
        return _BINOPS[type(node.op)](_evaluate(node.left, q), _evaluate(node.right, q))
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
        return _FUNCS[node.func.id](_evaluate(node.args[0], q))
    raise ParameterError(f"family expression node {type(node).__name__} is not allowed")


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
        factor: The factor with the lengths substituted (text), zero on the family.
        gradient: Its partial derivatives along :attr:`variables` (text).

    """

    name: str
    equation: str
    variables: tuple[int, ...]
    joint: int | None
    value: float | None
    periodic: bool
    factor: str
    gradient: tuple[str, ...]
    nq: int
    _code: Any = field(default=None, repr=False, compare=False)

    def _compiled(self) -> tuple[ast.Expression, tuple[ast.Expression, ...]]:
        if self._code is None:
            code = (
                _compile(self.factor, self.nq),
                tuple(_compile(g, self.nq) for g in self.gradient),
            )
            object.__setattr__(self, "_code", code)
        return self._code

    def residual(self, q: Any) -> np.ndarray:
        """Signed residual at ``q`` (…, nq): the factor; the wrapped offset for ``q_k = v``."""
        qa = np.asarray(q, dtype=float)
        if self.joint is not None and self.value is not None:
            d = qa[..., self.joint] - self.value
            return wrap_angles(d) if self.periodic else np.asarray(d)
        val = _evaluate(self._compiled()[0], qa)
        return np.asarray(np.broadcast_to(val, qa.shape[:-1]), dtype=float)

    def distance(self, q: Any, steps: int = 30) -> np.ndarray:
        """Joint-space distance (…,) from ``q`` to the family, in [rad]/[m].

        Exact for ``q_k = value`` families. For implicit ones, the foot point of ``p = q``: the
        iteration ``x ← p − ∇f(x) [f(x) + ∇f(x)·(p − x)] / ‖∇f(x)‖²`` (project ``p`` on the
        tangent plane of ``f = 0`` at ``x``; a fixed point is on the family with ``p − x``
        along the normal, the closest-point condition), run from ``x = p`` and from the end
        of three gradient projections ``x ← x − f ∇f / ‖∇f‖²``; the nearer converged foot
        point counts. Where neither converges within ``steps``, the first-order
        ``|f| / ‖∇f‖``. Checked against a brute-force distance to the densely sampled
        hexabot-leg family (tests): equal to the sampling resolution up to 0.2 rad away.
        """
        qa = np.asarray(q, dtype=float)
        if self.joint is not None and self.value is not None:
            return np.abs(self.residual(qa))
        fcode, gcode = self._compiled()
        var = list(self.variables)
        lead = qa.shape[:-1]
        p = np.array(qa[..., var], dtype=float)
        full = np.array(qa, dtype=float)

        def fg(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            full[..., var] = x
            f = np.broadcast_to(np.asarray(_evaluate(fcode, full), float), lead)
            g = np.stack(
                [np.broadcast_to(np.asarray(_evaluate(c, full), float), lead) for c in gcode],
                axis=-1,
            )
            return f, g

        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            f0, g0 = fg(p)
            g20 = np.sum(g0 * g0, axis=-1)
            first = np.where(g20 > 0, np.abs(f0) / np.sqrt(g20), np.inf)
            tol_f = 1e-9 * np.abs(f0) + 1e-14
            best = np.full(lead, np.inf)
            starts = [p.copy(), p.copy()]
            for _ in range(3):  # the second start: gradient projections onto f = 0
                f, g = fg(starts[1])
                g2 = np.sum(g * g, axis=-1)
                step = np.where(g2 > 0, f / g2, 0.0)[..., None] * g
                starts[1] = starts[1] - np.nan_to_num(step, nan=0.0, posinf=0.0, neginf=0.0)
            for x, alpha, count in ((starts[0], 1.0, steps), (starts[1], 1.0, steps),
                                    (starts[1], 0.5, 2 * steps)):  # fmt: skip
                for _ in range(max(count, 1)):
                    f, g = fg(x)
                    g2 = np.sum(g * g, axis=-1)
                    lam = np.where(g2 > 0, (f + np.sum(g * (p - x), axis=-1)) / g2, 0.0)
                    new = x + alpha * (p - lam[..., None] * g - x)
                    x = np.where(np.isfinite(new), new, x)
                f_end = np.abs(fg(x)[0])
                dist = np.linalg.norm(x - p, axis=-1)
                best = np.where((f_end <= tol_f) & (dist < best), dist, best)
        return np.asarray(np.where(np.isfinite(best), best, first))

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
            "gradient": list(self.gradient),
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
    """Where derived families are kept: ``families/`` beside :mod:`hexapod_kin.symbolic`'s cache.

    ``$HEXAPOD_KIN_CACHE_DIR``, else ``platformdirs.user_cache_dir("hexapod_kin")`` when
    platformdirs is installed, else ``~/.cache/hexapod_kin``.
    """
    from .._io import cache_root

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
    fams = []
    for f in data["families"]:
        fam = Family(
            name=str(f["name"]),
            equation=str(f["equation"]),
            variables=tuple(int(v) for v in f["variables"]),
            joint=None if f["joint"] is None else int(f["joint"]),
            value=None if f["value"] is None else float(f["value"]),
            periodic=bool(f["periodic"]),
            factor=str(f["factor"]),
            gradient=tuple(str(g) for g in f["gradient"]),
            nq=nq,
        )
        fam._compiled()  # refuse anything outside the grammar now, not mid-scan
        fams.append(fam)
    return tuple(fams)


def _read_cache(key: str, nq: int) -> tuple[Family, ...] | None:
    path = cache_dir() / f"{key}.json"
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return None
    except (OSError, ValueError):
        return None  # unreadable or corrupt: derive again (and overwrite)
    if data.get("v") != _VERSION or data.get("nq") != nq:
        return None
    try:
        return _from_json(data, nq)
    except (KeyError, TypeError, ValueError):  # ParameterError is a ValueError
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


#: Errors a derivation may end with; anything else is a bug and propagates.
def _derive_errors() -> tuple[type[BaseException], ...]:
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
    import sympy as sp

    from .measure import measures

    qs = model.random_q(16, seed=4242)
    # Pinocchio's Jacobians and numpy (16 calls): no batch kernel compiled for this check.
    res = [measures(model, q, rows) for q in qs]
    if deriv.det is not None:
        sym = np.abs(deriv.function(deriv.det)(qs))
        num = np.abs([m.det for m in res])
    elif getattr(deriv, "gram", None) is not None:
        sym = np.abs(deriv.function(deriv.gram)(qs))
        num = np.array([m.manipulability for m in res]) ** 2
    else:
        raise ParameterError("the derivation has no determinant to check the families against")
    scale = max(float(np.max(num)), 1e-300)
    err = float(np.max(np.abs(sym - num))) / scale
    if not err <= _MATCH_RTOL:
        raise ParameterError(
            f"the symbolic det of the table differs from the model's (relative {err:.1e}): "
            "the table's frames do not match the model's Jacobian rows",
            parameter="rows",
            value=rows,
        )
    q = deriv.q
    fams = []
    for fam in deriv.families:
        factor = deriv.numeric(fam.factor)
        grads = tuple(str(sp.diff(factor, q[v])) for v in fam.variables)
        fams.append(
            Family(
                name=str(fam.name),
                equation=str(fam.equation),
                variables=tuple(int(v) for v in fam.variables),
                joint=fam.joint,
                value=None if fam.value is None else float(fam.value),
                periodic=bool(fam.periodic),
                factor=str(factor),
                gradient=grads,
                nq=model.nq,
            )
        )
    out = tuple(fams)
    for f in out:
        f._compiled()
    return out


def _derive(chain: Any, rows: tuple[str, ...], budget: float) -> Any:
    """``symbolic.derive(chain, rows)`` within ``budget`` seconds (raises TimeoutError)."""
    from .. import symbolic

    params = inspect.signature(symbolic.derive).parameters
    if "budget" in params:
        return symbolic.derive(chain, rows=rows, budget=budget)
    # No budget in symbolic.derive: run it aside and stop waiting at the budget.
    box: dict[str, Any] = {}

    def work() -> None:
        try:
            box["value"] = symbolic.derive(chain, rows=rows)
        except BaseException as err:  # noqa: BLE001 - handed to the waiting thread below
            box["error"] = err

    thread = threading.Thread(target=work, name="hexapod_kin-derive", daemon=True)
    thread.start()
    thread.join(budget)
    if thread.is_alive():
        raise TimeoutError(f"symbolic.derive did not finish within the budget of {budget:g} s")
    if "error" in box:
        raise box["error"]
    return box["value"]


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
    except _Miss:
        hit = None
    if hit is not None:
        return Families(hit, "cache", "" if hit else _NO_FACTOR, key)
    if not derive:
        return Families(
            (),
            "none",
            "families not derived yet (pass families=True, or run `hexapod-kin derive`; "
            "they are then kept on disk)",
            key,
        )
    try:
        deriv = _derive(chain, rows, float(budget))
        incomplete = str(getattr(deriv, "incomplete", "") or "")
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
