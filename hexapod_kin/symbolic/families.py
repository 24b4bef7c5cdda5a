"""Singular families: read off the factored determinant, checked against the numeric Jacobian.

Part of :mod:`hexapod_kin.symbolic` (which re-exports :class:`SingularFamily`). Their numeric
form for scans (residuals, distances) is :mod:`hexapod_kin.singularity.families`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import sympy as sp

from .._fields import fields_dict
from ..params import Chain
from . import core as _core
from .core import ROW_NAMES


@dataclass(frozen=True)
class SingularFamily:
    """One family of singular configurations (the zero set of one factor of det J).

    Attributes:
        name: A readable label, e.g. ``"q3 = 0 (mod 2*pi)"`` or ``"l1 + ... = 0"``.
        factor: The factor of the determinant (sympy, symbolic lengths) that vanishes.
        equation: ``Eq(q_k, value)`` when solved for one joint, else ``Eq(factor, 0)``.
        variables: Indices (0-based) of the joints the factor depends on.
        joint: Index of the joint when the family is ``q_k = value``, else ``None``.
        value: That value in [rad] or [m] (``None`` for implicit families).
        periodic: True when ``value`` repeats every 2π (revolute joint).
        verified: ``True`` when the numeric Jacobian is singular on the family and not 1e-3
            off it; ``False`` when that failed; ``None`` when not checked.
        check: What the check measured, in words.

    """

    name: str
    factor: sp.Expr
    equation: sp.Eq
    variables: tuple[int, ...]
    joint: int | None = None
    value: float | None = None
    periodic: bool = False
    verified: bool | None = None
    check: str = ""

    def to_dict(self, joint_names: Sequence[str] | None = None) -> dict[str, Any]:
        """JSON-ready dict (sympy objects as text; the joint by name with ``joint_names``)."""
        out = {"name": self.name, "equation": str(self.equation), "factor": str(self.factor)}
        out |= fields_dict(self, "variables", "joint", "value", "periodic", "verified", "check")
        if self.joint is not None and joint_names is not None:
            out["joint"] = joint_names[self.joint]
        return out


def families_of(
    factors: Sequence[tuple[Any, int]], q: tuple[sp.Symbol, ...], chain: Chain,
    values: Mapping[sp.Symbol, float],
) -> tuple[SingularFamily, ...]:  # fmt: skip
    """One family per factor of ``det J`` that depends on ``q`` (solved for one joint if it can)."""
    sigmas = chain.sigmas
    fams: list[SingularFamily] = []
    for fac, _mult in factors:
        vars_ = tuple(k for k, s in enumerate(q) if fac.has(s))
        if not vars_:
            continue
        if len(vars_) == 1:
            k = vars_[0]
            revolute = sigmas[k] == "revolute"
            sols: list[tuple[Any, float]] = []
            if not (fac.free_symbols - {q[k]}):
                domain = sp.Interval.Lopen(-sp.pi, sp.pi) if revolute else sp.S.Reals
                try:
                    found = sp.solveset(fac, q[k], domain)
                except Exception:  # noqa: BLE001 - sympy may raise anything on hard equations
                    found = None
                if isinstance(found, sp.FiniteSet) and all(s.is_number for s in found):
                    sols = [(s, float(s)) for s in sorted(found, key=lambda s: float(s))]
            mod, numeric = (" (mod 2*pi)" if revolute else ""), not sols
            if numeric:
                lo, hi = (-math.pi, math.pi) if revolute else _prismatic_range(chain, k)
                func = sp.lambdify(q[k], fac.subs(dict(values)), np)  # np: no `from numpy import *`

                def one(x: np.ndarray, func: Any = func) -> np.ndarray:
                    return np.broadcast_to(np.asarray(func(x), float), np.shape(x))

                roots = _core.single_joint_roots(one, lo, hi)
                if revolute:
                    from .._numerics import wrap_angles  # the one angle wrapping

                    roots = sorted({round(float(r), 15) for r in wrap_angles(roots)})
                sols = [(sp.Float(r, 12), r) for r in roots]
                mod += f", from {sp.sstr(fac)} = 0 (roots {', '.join(f'{r:.6g}' for r in roots)})"
            for sol, r in sols:
                name = f"{q[k]} = {f'{r:.6g}' if numeric else sp.sstr(sol)}{mod}"
                fams.append(SingularFamily(name, fac, sp.Eq(q[k], sol), vars_, k, r, revolute))
            if sols:
                continue
        fams.append(SingularFamily(f"{sp.sstr(fac)} = 0", fac, sp.Eq(fac, 0), vars_))
    return tuple(fams)


def _prismatic_range(chain: Chain, k: int) -> tuple[float, float]:
    lim = (chain.limits or ())[k]
    return (lim.lower, lim.upper) if lim.upper > lim.lower else (-1.0, 1.0)


def check_families(
    fams: Sequence[SingularFamily], q: tuple[sp.Symbol, ...], chain: Chain,
    values: Mapping[sp.Symbol, float], row_names: Sequence[str],
) -> tuple[SingularFamily, ...]:  # fmt: skip
    """Each family against the numeric Jacobian: singular on it, regular 1e-3 off it."""
    sel = [ROW_NAMES.index(r) for r in row_names]
    rng = np.random.default_rng(20260101)
    lo, hi = chain.lower(), chain.upper()
    lo = np.where(np.isfinite(lo), lo, -math.pi)
    hi = np.where(np.isfinite(hi), hi, math.pi)
    out = []
    for fam in fams:
        func = sp.lambdify(q, fam.factor.subs(dict(values)), np)
        on, off, points = [], [], 0
        for _ in range(12):
            if points == 3:
                break
            q0 = rng.uniform(lo, hi)
            if fam.joint is not None and fam.value is not None:
                q0[fam.joint] = fam.value
                var = fam.joint
            else:
                var = None
                for v in rng.permutation(list(fam.variables)):

                    def along(
                        x: np.ndarray, v: int = int(v), q0: np.ndarray = q0, func: Any = func
                    ) -> np.ndarray:
                        qs = np.repeat(q0[None, :], np.size(x), axis=0)
                        qs[:, v] = x
                        return np.broadcast_to(np.asarray(func(*qs.T), float), np.shape(x))

                    a, b = (-math.pi, math.pi) if chain.sigmas[v] == "revolute" else (lo[v], hi[v])
                    roots = _core.single_joint_roots(along, a, b)
                    if roots:
                        q0[v] = roots[int(rng.integers(len(roots)))]
                        var = int(v)
                        break
                if var is None:
                    continue
            points += 1
            on.append(_core.sigma_ratio(_core.numeric_jacobian(chain, q0, sel)))
            q1 = q0.copy()
            q1[var] += 1e-3
            off.append(_core.sigma_ratio(_core.numeric_jacobian(chain, q1, sel)))
        if not on:
            out.append(replace(fam, verified=None, check="no real point found on the family"))
            continue
        ok = max(on) <= 1e-9 and min(off) > 1e-9
        out.append(replace(fam, verified=ok, check=(
            f"sigma_min/sigma_max <= {max(on):.1e} at {len(on)} points on it, "
            f">= {min(off):.1e} at 1e-3 off"
        )))  # fmt: skip
    return tuple(out)
