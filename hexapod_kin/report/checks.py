"""One check per claim kind (:data:`CHECKS`), the :class:`Context` of hexapod_kin's values.

Every claim is compared with hexapod_kin's own value (rules in :mod:`.compare`); no verdict is
written by hand. Each ``_check_<kind>`` says what it compares.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Callable
from functools import cached_property
from typing import Any

import numpy as np
import sympy as sp

from .compare import (
    RTOL,
    SYMS,
    Q,
    equal,
    factored,
    fmt,
    fmt_matrix,
    matrix_diff,
    parse,
    parse_matrix,
    plain,
    points_on,
    tidy,
    value_at,
    values,
    vanishes,
)
from .data import Claim, Verdict
from .experiments import MODELS, Experiments

__all__ = ["CHECKS", "MODELS", "Context", "evaluate"]

_OTHER = {"leg": ("leg+", "+90°"), "leg+": ("leg", "−90°")}
_SIGMA = {"0": "revolute", "1": "prismatic", "fixed": "fixed"}
_COLUMN = {"σ": 0, "d": 1, "r": 3, "θ": 4}
#: The named items of a derivation (besides ``"T j"`` and ``"0T j"``).
_ITEMS: dict[str, Callable[[Any], Any]] = {
    "p": lambda d: d.p,
    "p - o2": lambda d: d.p - d.cumulative[1][:3, 3],
    "J": lambda d: d.J,
    "J_indirect": lambda d: d.J_indirect,
    "J x,y,wz": lambda d: d.J_direct.extract([0, 1, 5], [0, 1, 2]),
}


class Context(Experiments):
    """hexapod_kin's side of every comparison, computed on first use and kept.

    The derivations and the replayed schedule beside :class:`~.experiments.Experiments`'
    models and experiments (``quick``: smaller runs); ``claims``: all claims, by id.
    """

    def __init__(self, quick: bool = False, claims: list[Claim] | None = None) -> None:
        super().__init__(quick)
        self.claims = {c.id: c for c in claims or []}
        self._derived: dict[str, Any] = {}
        self._items: dict[tuple[str, str], sp.Matrix] = {}

    def derivation(self, key: str) -> Any:
        """:func:`hexapod_kin.symbolic.derive` of the model, kept (no budget: small tables)."""
        from ..symbolic import derive

        if key not in self._derived:
            self._derived[key] = derive(self.chain(key), budget=None)
        return self._derived[key]

    def printed(self, key: str) -> dict[str, Any]:
        """The derivation laid out for the report (:func:`.html.derivation_layout`)."""
        from .html import derivation_layout

        return derivation_layout(self.derivation(key))

    def lengths(self, key: str) -> dict[sp.Symbol, float]:
        """The preset's length values by plain symbol."""
        return {plain(k): sp.Float(v) for k, v in self.derivation(key).lengths.items()}

    def item(self, key: str, item: str) -> sp.Matrix:
        """A named symbolic item of the derivation (``"T 2"``, ``"0T 4"``, ``"p"``, ``"J"``…)."""
        if (key, item) not in self._items:
            self._items[key, item] = self._item(key, item)
        return self._items[key, item].copy()

    def _item(self, key: str, item: str) -> sp.Matrix:
        d = self.derivation(key)
        kind, _, k = item.partition(" ")
        if kind in ("T", "0T") and k.isdigit():
            out = (d.transforms if kind == "T" else d.cumulative)[int(k) - 1]
        elif item in _ITEMS:
            out = _ITEMS[item](d)
        else:
            raise KeyError(f"unknown item {item!r}")
        return sp.Matrix(plain(sp.Matrix(out)))

    @cached_property
    def schedule(self) -> dict[str, np.ndarray]:
        """Seed 002 Table I replayed: q(t), FK, the seed's IK and :func:`ik.analytic`."""
        from .. import ik
        from ..seeds import seed002_schedule

        sched = seed002_schedule()
        t = np.arange(0.0, 22.0 + 1e-9, 0.25 if self.quick else 0.05)
        q = np.asarray(sched.sample(t), dtype=float)
        mdl = self.model("coxa")
        feet = np.array([mdl.position(qi) for qi in q])
        sols = ik.analytic(self.chain("coxa"), feet)
        ours = np.array([s[np.argmin(np.abs(s - qi).sum(axis=1))] for s, qi in zip(sols, q)])
        back = np.array([mdl.position(qi) for qi in ours])
        claim = self.claims.get("002-table1")
        seed = np.full_like(q, np.nan)
        if claim is not None:
            seed = _seed_ik(claim.data["value"], feet, self.lengths("coxa"))
        knots = {"knots_t": sched.times, "knots_q": sched.values}
        return dict(t=t, q=q, feet=feet, ours=ours, back=back, seed=seed, **knots)

    def quantity(self, name: str) -> float:
        """A measured figure named in a ``bound`` claim."""
        if name == "step.drift_yz":
            return max(self.step.drift_y, self.step.drift_z)
        if name == "step.velocity_over_input":
            v = self.step.trajectory.foot_velocity[:, 0]
            return float(np.abs(v).max() / self.step.amplitude)
        if name == "step.phase_deg":
            tr = self.step.trajectory
            w = 2 * math.pi / self.step.period
            n = int(math.floor(tr.t[-1] / self.step.period) * self.step.period / tr.dt) + 1
            t, x, v = tr.t[:n], tr.foot[:n, 0], tr.foot_velocity[:n, 0]
            ph = np.angle(np.sum((x - x.mean()) * np.exp(-1j * w * t)))
            pv = np.angle(np.sum(v * np.exp(-1j * w * t)))
            return float(abs(math.degrees((pv - ph + math.pi) % (2 * math.pi) - math.pi)))
        p = self.pendulum
        if name == "pendulum.energy_drift":
            return float(p.undamped.energy_drift)
        if name == "pendulum.period_error":
            return float(abs(p.undamped.period - p.undamped.period_exact) / p.undamped.period_exact)
        if name == "pendulum.speed_at_zero":
            th, om = p.undamped.theta, p.undamped.omega
            k = np.flatnonzero(np.sign(th[:-1]) * np.sign(th[1:]) < 0)
            s = th[k] / (th[k] - th[k + 1])
            at_zero = np.abs(om[k] + s * (om[k + 1] - om[k]))
            return float(at_zero.min() / np.abs(om).max())
        if name == "pendulum.amplitude_ratio_10s":
            d = p.damped
            t = d.simulation.t
            win = (t >= 9.0) & (t <= 11.0)
            return float(np.abs(d.theta[win]).max() / d.theta0)
        raise KeyError(f"unknown quantity {name!r}")


def _seed_ik(
    formulas: dict[str, str], feet: np.ndarray, lengths: dict[sp.Symbol, float]
) -> np.ndarray:
    """The seed's IK formulas (assignments in order, symbols by name) at every foot: (N, 2)."""
    env: dict[str, Any] = {k.name: float(v) for k, v in lengths.items()}
    env.update(x=feet[:, 0], y=feet[:, 1], z=feet[:, 2])
    for name, text in formulas.items():
        expr = parse(text)
        syms = sorted(expr.free_symbols, key=lambda s: s.name)
        fn = sp.lambdify(syms, expr, np)  # np: no `from numpy import *` (0.15 s)
        with np.errstate(all="ignore"):
            value = np.asarray(fn(*[env[s.name] for s in syms]), dtype=float)
        env[name] = np.broadcast_to(value, (feet.shape[0],))
    return np.column_stack([env["theta1"], env["theta2"]])


def _verdict(
    c: Claim,
    claimed: str,
    computed: str,
    status: str,
    reason: str,
    method: str,
    cells: dict[str, Any] | None = None,
) -> Verdict:
    first, last = c.lines
    lines = f"{first}-{last}" if first else ""
    layout = json.dumps(cells, ensure_ascii=False) if cells else ""
    head = (c.id, c.seed, c.where, c.kind, claimed, computed)
    return Verdict(*head, status, reason, method, layout, lines)


def _judged(
    c: Claim, claimed: str, computed: str, problems: list[str], method: str, cells: Any = None
) -> Verdict:
    """*agrees* without ``problems``, else *wrong* with them as the reason."""
    status = "wrong" if problems else "agrees"
    return _verdict(c, claimed, computed, status, "; ".join(problems), method, cells)


_AT = re.compile(r"^\((\d+),(\d+)\):")


def _cells(seed_rows: Any, ours: sp.Matrix, diffs: list[str], note: str = "") -> dict[str, Any]:
    """The matrix layout of a verdict: the seed's entries as written, ours, the differing ones."""
    found = [_AT.match(d) for d in diffs]
    differ = [[int(m.group(1)) - 1, int(m.group(2)) - 1] for m in found if m]
    rows = [[str(v) for v in row] for row in seed_rows]
    mine = [[fmt(tidy(ours[i, j])) for j in range(ours.cols)] for i in range(ours.rows)]
    return {"seed": rows, "ours": mine, "differ": differ, "note": note}


def _at(m: Any, subs: dict[sp.Symbol, float]) -> Any:
    """``m.xreplace(subs)``; ``m`` itself when there is nothing to replace (no tree walk)."""
    return m.xreplace(subs) if subs else m


def _subs(c: Claim) -> dict[sp.Symbol, float]:
    return {SYMS[k]: sp.Float(v) for k, v in c.data.get("subs", {}).items()}


_SYMBOLIC = f"symbolic: every entry at random points (rel. tol {RTOL:g}) then simplify(a - b) == 0"


def _raw(rows: Any) -> str:
    """The seed's matrix as written in the claims file."""
    return "[" + "; ".join(", ".join(str(v) for v in row) for row in rows) + "]"


def _with(c: Claim) -> str:
    subs = c.data.get("subs")
    return " with " + ", ".join(f"{k} = {v:g}" for k, v in subs.items()) if subs else ""


def _check_matrix(c: Claim, ctx: Context) -> Verdict:
    """``matrix`` claims (transforms, p, J)."""
    key, item, subs = c.data["model"], c.data["item"], _subs(c)
    seed = _at(parse_matrix(c.data["value"]), subs)
    truth = _at(ctx.item(key, item), subs)
    claimed = _raw(c.data["value"]) + _with(c)
    computed = fmt_matrix(truth.applyfunc(tidy))
    if seed.shape != truth.shape:
        return _judged(c, claimed, computed, [f"shape {seed.shape} vs {truth.shape}"], _SYMBOLIC)
    diffs = matrix_diff(seed, truth, c.id)
    cells = _cells(c.data["value"], truth, diffs, _with(c).strip())
    if not diffs:
        return _judged(c, claimed, computed, [], _SYMBOLIC, cells)
    notes = [f"{len(diffs)} of {truth.rows * truth.cols} entries differ: " + "; ".join(diffs)]
    if key in _OTHER:
        other, label = _OTHER[key]
        if not matrix_diff(seed, _at(ctx.item(other, item), subs), c.id, explain=False):
            notes.append(f"it is the α2 = {label} matrix (the other sign of row 2)")
    if item.startswith("0T "):
        notes.append(_own_product(c, ctx, seed, subs))
    if "derivative_of" in c.data:
        p = _at(parse_matrix(ctx.claims[c.data["derivative_of"]].data["value"]), subs)
        dp = p.jacobian(Q[: seed.cols])
        own = matrix_diff(seed, dp, c.id + "d")
        nor = "nor is it the derivative of the seed's own p: " + "; ".join(own)
        notes.append(nor if own else "it is the derivative of the seed's own p")
    return _judged(c, claimed, computed, [" — ".join(n for n in notes if n)], _SYMBOLIC, cells)


def _own_factors(c: Claim, ctx: Context) -> list[Claim]:
    """The seed's own ``^{k-1}T_k`` claims (k = 1 … j) whose product a ``^0T_j`` claim is."""
    own: dict[Any, Claim] = {}
    for x in ctx.claims.values():
        if (x.seed, x.kind, x.data.get("model")) == (c.seed, "matrix", c.data["model"]):
            own.setdefault(x.data.get("item"), x)
    found = [own.get(f"T {k}") for k in range(1, int(c.data["item"][3:]) + 1)]
    return [] if None in found else [f for f in found if f is not None]


def _own_product(c: Claim, ctx: Context, seed: sp.Matrix, subs: dict) -> str:
    factors = _own_factors(c, ctx)
    if not factors:
        return ""
    prod = sp.eye(4)
    for f in factors:
        prod = prod * _at(parse_matrix(f.data["value"]), subs)
    own = matrix_diff(seed, prod, c.id + "p", explain=False)
    ids = "·".join(f"^{k - 1}T_{k}" for k in range(1, len(factors) + 1))
    if not own:
        return f"it is the product {ids} of the seed's own factors"
    return f"it is not the product {ids} of the seed's own factors either ({len(own)} entries)"


def _check_table(c: Claim, ctx: Context) -> Verdict:
    """``table`` claims: the seed's rows vs the preset's rows."""
    key, unit = c.data["model"], float(c.data.get("unit", 1.0))
    chain = ctx.chain(key)
    lengths = ctx.lengths(key)
    subs = _subs(c)
    problems, alpha_rows, differ = [], [], []
    rows = c.data["rows"]
    for i, (row, (sig, d, alpha, r, theta)) in enumerate(zip(chain.rows, rows), start=1):
        if _SIGMA.get(sig) != row.sigma:
            problems.append(f"row {i}: σ {sig} vs {row.sigma}")
            differ.append([i - 1, 0])
        for name, text, mine, var in (
            ("d", d, row.d, False),
            ("r", r, row.r, row.sigma == "prismatic"),
            ("θ", theta, row.theta, row.sigma == "revolute"),
        ):
            e = parse(text).xreplace(subs)
            if any(s in Q for s in e.free_symbols):
                if not var:
                    problems.append(
                        f"row {i}: {name} = {text} is a joint variable here, not in hexapod_kin"
                    )
                    differ.append([i - 1, _COLUMN[name]])
                continue
            val = value_at(e.xreplace(lengths), {}) * (
                unit if not (e.free_symbols & set(lengths)) else 1.0
            )
            if abs(val - mine) > 1e-9:
                problems.append(f"row {i}: {name} = {text} ({val:g} m) vs {mine:g} m")
                differ.append([i - 1, _COLUMN[name]])
        if abs(math.radians(float(alpha)) - row.alpha) > 1e-12:
            alpha_rows.append((i, float(alpha), math.degrees(row.alpha)))
            differ.append([i - 1, 2])
    extra = chain.rows[len(rows) :]
    if len(rows) > len(chain.rows) or any(
        r.sigma != "fixed" or (r.alpha, r.d, r.theta, r.r) != (0, 0, 0, 0) for r in extra
    ):
        problems.append(f"{len(rows)} rows vs {len(chain.rows)}")
    computed = "; ".join(
        f"{r.sigma} α={math.degrees(r.alpha):g}° d={r.d:g} θ={r.theta:g} r={r.r:g}"
        for r in chain.rows
    )
    claimed = "; ".join("(" + ", ".join(str(v) for v in row) + ")" for row in rows)
    method = "numeric, per entry (|Δ| ≤ 1e-9 m or rad), lengths × unit"
    q = iter(range(1, len(chain.rows) + 1))
    cells = {
        "header": ["σ", "d", "α [°]", "r", "θ"],
        "seed": [[str(v) for v in row] for row in rows],
        "ours": [
            [
                {"revolute": "0", "prismatic": "1"}.get(r.sigma, "fixed"),
                f"{r.d:g} m",
                f"{math.degrees(r.alpha):g}",
                f"q{next(q)}" if r.sigma == "prismatic" else f"{r.r:g} m",
                f"q{next(q)}" if r.sigma == "revolute" else f"{r.theta:g}",
            ]
            for r in chain.rows
        ],
        "differ": differ,
        "note": f"seed lengths × {unit:g} m" if unit != 1.0 else "",
    }
    if problems or not alpha_rows:
        return _judged(c, claimed, computed, problems, method, cells)
    (i, seed_a, ours_a), *_ = alpha_rows
    p_minus, p_plus = ctx.item("leg", "p"), ctx.item("leg+", "p")
    mirror = all(equal(p_plus[k], s * p_minus[k], c.id) for k, s in enumerate((1, 1, -1)))
    if not mirror:
        fk = f"α{i} = {seed_a:+g}° vs {ours_a:+g}° changes the FK to p = {fmt_matrix(p_plus.T)}"
    else:
        fk = (
            f"with α{i} = {seed_a:+g}° the foot is (x, y, −z) of the α{i} = {ours_a:+g}° leg "
            f"(checked symbolically: {mirror}): p_z = {fmt(p_plus[2])}, a positive knee "
            f"angle lifts the foot; the lengths agree"
        )
    why = f"row {i}: α = {seed_a:+g}° vs hexabot_leg's {ours_a:+g}° (seeds 000/001) — {fk}"
    return _verdict(c, claimed, computed, "differs", why, method, cells)


def _check_generic(c: Claim, ctx: Context) -> Verdict:
    """``generic``: the seed's generic transform vs :func:`khalil_matrix`."""
    from ..symbolic import khalil_matrix

    s = SYMS
    truth = sp.Matrix(khalil_matrix(s["alpha"], s["d"], s["theta"], s["r"]))
    seed = parse_matrix(c.data["value"])
    diffs = matrix_diff(seed, truth, c.id)
    cells = _cells(c.data["value"], truth, diffs)
    return _judged(c, fmt_matrix(seed), fmt_matrix(truth), diffs, _SYMBOLIC, cells)


def _check_methods(c: Claim, ctx: Context) -> Verdict:
    """``methods_equal``: direct and indirect Jacobians equal."""
    agree = bool(ctx.derivation(c.data["model"]).methods_agree)
    wrong = [] if agree == bool(c.data["value"]) else [f"hexapod_kin finds methods_agree = {agree}"]
    claimed = f"J_indirect − J_direct = 0: {c.data['value']}"
    method = "exact: trig polynomials reduced modulo sin² + cos² = 1"
    return _judged(c, claimed, f"Derivation.methods_agree = {agree}", wrong, method)


def _det_truth(c: Claim, ctx: Context) -> sp.Expr:
    key = c.data["model"]
    if c.data.get("item"):
        return plain(ctx.item(key, c.data["item"]).det())
    return plain(ctx.derivation(key).det)


def _check_det(c: Claim, ctx: Context) -> Verdict:
    """``det``: the seed's det J vs hexapod_kin's factored det J."""
    subs = _subs(c)
    seed = parse(c.data["value"]).xreplace(subs)
    d = ctx.derivation(c.data["model"])
    truth = factored(_det_truth(c, ctx).xreplace(subs), d.q, d.chain.sigmas, c.id)
    claimed, computed = str(c.data["value"]) + _with(c), fmt(truth)
    method = "symbolic: random points (rel. tol 1e-9), then simplify(a - b) == 0"
    if equal(seed, truth, c.id):
        return _judged(c, claimed, computed, [], method)
    why = "opposite sign" if equal(seed, -truth, c.id) else f"differs from {computed}"
    return _judged(c, claimed, computed, [why], method)


def _check_families(c: Claim, ctx: Context) -> Verdict:
    """``families``: the seed's singular sets vs the factors of det J."""
    key = c.data["model"]
    d = ctx.derivation(key)
    nq = d.chain.nq
    lengths = ctx.lengths(key)
    det = plain(d.numeric(d.det))
    det_scale = float(
        np.median(np.abs(values(det, np.random.default_rng(7).uniform(-3, 3, (20, nq)))))
    )
    seeds = [parse(v).xreplace(lengths) for v in c.data["value"]]
    missing, spurious = [], []
    for fam in d.families:
        if fam.joint is not None:
            pts = points_on(sp.Integer(0), nq, c.id + fam.name, fixed={fam.joint: fam.value})
        else:
            pts = points_on(plain(d.numeric(fam.factor)), nq, c.id + fam.name)
        if not any(vanishes(s, pts) for s in seeds):
            missing.append(fam.name)
    for s, text in zip(seeds, c.data["value"]):
        pts = points_on(s, nq, c.id + text)
        if len(pts) and not vanishes(det, pts, det_scale, 1e-9):
            q = np.round(pts[0], 3).tolist()
            val = float(values(det, pts[:1])[0])
            spurious.append(f"{text} = 0 is not singular (det J = {val:.3g} at q = {q})")
    claimed = ", ".join(f"{v} = 0" for v in c.data["value"]) or "no singularity"
    computed = f"det J = {fmt(d.det)}; families: " + ", ".join(f.name for f in d.families)
    method = (
        "numeric on sampled points: a seed set covers a family when its residual is "
        "< 1e-7 on 5 points of the family; a seed set is singular when |det J| < 1e-9 "
        "(relative) on 5 of its points"
    )
    parts = [f"misses the family {m}" for m in missing] + spurious
    return _judged(c, claimed, computed, parts, method)


def _check_fk(c: Claim, ctx: Context) -> Verdict:
    """``fk``: the seed's foot position vs Pinocchio (and the table product)."""
    from .. import table_fk

    q = np.radians(c.data["q_deg"])
    ours = ctx.model(c.data["model"]).position(q)
    table = table_fk(ctx.chain(c.data["model"]), q)[:3, 3]
    seed = np.asarray(c.data["value"], float)
    tol = float(c.data["tol"])
    err = float(np.max(np.abs(seed - ours)))
    computed = (
        f"{np.round(ours, 6).tolist()} (table product: |Δ| = {np.max(np.abs(table - ours)):.1e})"
    )
    method = f"numeric, max |Δ| ≤ {tol:g} (the seed's 4 decimals)"
    bad = [] if err <= tol else [f"max |Δ| = {err:.3g} > {tol:g}"]
    return _judged(c, str(seed.tolist()), computed, bad, method)


def _ik_reason(seed: np.ndarray, q: np.ndarray, ours: np.ndarray, tol: float) -> list[str]:
    bad = []
    for k, (s, t, o) in enumerate(zip(np.degrees(seed), np.degrees(q), np.degrees(ours)), 1):
        if abs(s - t) > tol:
            sign = " — the sign is lost (acos gives |θ|)" if abs(s + t) <= tol else ""
            bad.append(
                f"θ{k}: the seed's formulas give {s:+.4f}°, the leg is at {t:+.4f}° "
                f"(ik.analytic: {o:+.4f}°){sign}"
            )
    return bad


def _check_ik(c: Claim, ctx: Context) -> Verdict:
    """``ik``: the seed's IK formulas, evaluated as written, at FK(q)."""
    from .. import ik

    key = c.data["model"]
    q = np.radians(c.data["q_deg"])
    mdl = ctx.model(key)
    foot = mdl.position(q)
    seed = _seed_ik(c.data["value"], np.asarray(foot)[None, :], ctx.lengths(key))[0]
    sols = ik.analytic(ctx.chain(key), foot)[0]
    ours = sols[np.argmin(np.abs(sols - q).sum(axis=1))]
    back = float(np.max(np.abs(mdl.position(ours) - foot)))
    tol = float(c.data["tol_deg"])
    claimed = "; ".join(f"{k} = {v}" for k, v in c.data["value"].items())
    computed = (
        f"P = {np.round(foot, 4).tolist()}; "
        f"seed formulas → {np.round(np.degrees(seed), 4).tolist()}°; "
        f"ik.analytic → {np.round(np.degrees(ours), 4).tolist()}° (FK back: |Δ| = {back:.1e})"
    )
    method = f"numeric, |Δθ| ≤ {tol:g}° against the angles P was made from"
    return _judged(c, claimed, computed, _ik_reason(seed, q, ours, tol), method)


def _check_schedule(c: Claim, ctx: Context) -> Verdict:
    """``schedule``: seed 002 Table I replayed, FK then IK (seed's formulas and ours)."""
    s = ctx.schedule
    knots = np.asarray(c.data["knots"], float)
    same = np.allclose(knots[:, 0], s["knots_t"]) and np.allclose(
        np.radians(knots[:, 1:]), s["knots_q"]
    )
    tol = float(c.data["tol_deg"])
    ours_err = float(np.degrees(np.max(np.abs(s["ours"] - s["q"]))))
    seed_err = np.degrees(np.abs(s["seed"] - s["q"]))
    worst = np.unravel_index(np.argmax(seed_err), seed_err.shape)
    n_bad = int(np.count_nonzero(seed_err.max(axis=1) > tol))
    computed = (
        f"{len(s['t'])} samples; ik.analytic max |Δθ| = {ours_err:.2e}°, FK back "
        f"max |Δ| = {np.max(np.abs(s['back'] - s['feet'])):.1e}; the seed's formulas: "
        f"max |Δθ| = {seed_err.max():.4f}°; Table I = seed002_schedule: {same}"
    )
    claimed = "IK output = input pattern (θ1 0..20°, θ2 −90..−50°)"
    method = f"numeric, every sample, |Δθ| ≤ {tol:g}°"
    if ours_err > tol or not same:
        return _verdict(c, claimed, computed, "error", "hexapod_kin's own replay failed", method)
    if n_bad == 0:
        return _judged(c, claimed, computed, [], method)
    t, j = float(s["t"][worst[0]]), int(worst[1])
    why = (
        f"the seed's IK (Eqs. 9-12) returns the wrong angle at {n_bad} of {len(s['t'])} samples: "
        f"at t = {t:g} s θ{j + 1} = {np.degrees(s['seed'][worst]):+.3f}° for an input of "
        f"{np.degrees(s['q'][worst]):+.3f}° — acos loses the sign of the tibia angle"
    )
    return _verdict(c, claimed, computed, "wrong", why, method)


def _admissible(c: Claim, ctx: Context, val: float) -> str | None:
    """Why a failed ``bound`` claim with ``unstated`` holds for an admissible value (else None)."""
    if "unstated" not in c.data:
        return None
    name, tol = c.data["quantity"], float(c.data["tol"])
    if name == "pendulum.amplitude_ratio_10s":
        d, s = ctx.pendulum.damped, ctx.pendulum.small
        i_max = d.damping * 10.0 / (2 * math.log(1 / tol))
        mass = d.pendulum.mass
        measured = f"{s.decay_rate:.4f}" if s.decay_rate is not None else "n/a"
        return (
            f"with hexapod_kin's stand-in link (I = {d.pendulum.inertia:.3g} kg·m², "
            f"{mass:g} kg) the amplitude at 10 s is {val:.3g} θ0; the envelope e^(−bt/(2I)) "
            f"(decay rate measured {measured} 1/s vs b/(2I) = "
            f"{s.decay_rate_exact:.4f} 1/s) falls below {tol:g} θ0 by 10 s with the seed's "
            f"b = {d.damping:g} N·m·s/rad for any I < {i_max:.2g} kg·m² (e.g. a {mass:g} kg "
            f"bob at less than {math.sqrt(i_max / mass):.2f} m); the seed does not give "
            f"{c.data['unstated']}. Its damping unit 'Nm/s^2' should be N·m·s/rad"
        )
    if name == "step.velocity_over_input":
        return (
            f"hexapod_kin's foot velocity amplitude equals the commanded one (ratio {val:.4f}); "
            f"a ratio of {float(c.data['value']):g} is what an input of 1/"
            f"{float(c.data['value']):g} the amplitude (or in a unit "
            f"{float(c.data['value']):g}× larger) shows, and the seed does not give "
            f"{c.data['unstated']}"
        )
    return None


def _check_bound(c: Claim, ctx: Context) -> Verdict:
    """``bound``: a measured quantity within ``tol`` (else underdetermined or wrong)."""
    val = ctx.quantity(c.data["quantity"])
    target, tol, unit = float(c.data["value"]), float(c.data["tol"]), c.data.get("unit", "")
    claimed = f"{c.data['quantity']} = {target:g} {unit}"
    computed = f"{val:.4g} {unit}"
    method = f"numeric, |measured − claimed| ≤ {tol:g} {unit}"
    if abs(val - target) <= tol:
        return _judged(c, claimed, computed, [], method)
    why = _admissible(c, ctx, val)
    if why is not None:
        return _verdict(c, claimed, computed, "underdetermined", why, method)
    why = f"measured {val:.4g} {unit}, |Δ| = {abs(val - target):.3g} > {tol:g}"
    return _verdict(c, claimed, computed, "wrong", why, method)


CHECKS: dict[str, Callable[[Claim, Context], Verdict]] = {
    "bound": _check_bound,
    "det": _check_det,
    "families": _check_families,
    "fk": _check_fk,
    "generic": _check_generic,
    "ik": _check_ik,
    "matrix": _check_matrix,
    "methods_equal": _check_methods,
    "schedule": _check_schedule,
    "table": _check_table,
}


def evaluate(claims: list[Claim], ctx: Context) -> list[Verdict]:
    """Every claim's verdict against ``ctx`` (one that raises: status ``"error"``, not skipped)."""
    out = []
    for claim in claims:
        try:
            out.append(CHECKS[claim.kind](claim, ctx))
        except Exception as exc:  # recorded, reported, and failed by the CLI and the test
            why = f"{type(exc).__name__}: {exc}"
            value = claim.data.get("value")
            if isinstance(value, dict):
                value = "; ".join(f"{k} = {v}" for k, v in value.items())
            out.append(_verdict(claim, str(value), "", "error", why, ""))
    return out
