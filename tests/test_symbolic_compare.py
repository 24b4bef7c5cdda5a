"""The report's symbolic comparisons without ``sympy.simplify``, against sympy and numbers.

The cheap steps of :mod:`hexapod_kin.report.compare` (printing form, numpy screening, exact
zero test, factored det) are checked against what they replace (``sympy.simplify``,
``sympy.lambdify``, ``factor(simplify(...))``) and against numbers; the derivation memo and
the in-process mode of :mod:`hexapod_kin.symbolic` against a plain derivation.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

from hexapod_kin import robots, symbolic
from hexapod_kin.report import compare
from hexapod_kin.report.checks import Context, _det_truth, _subs
from hexapod_kin.report.data import load_claims
from hexapod_kin.symbolic import derive

Q = [sp.Symbol(f"q{k}", real=True) for k in range(1, 5)]


#: a fresh derivation cache for this module: derivations are computed, not read
pytestmark = pytest.mark.usefixtures("own_cache_dir")


@pytest.fixture(scope="module")
def leg():
    return derive("hexabot_leg", budget=None)


def _entries(d):
    """Every entry of the leg's T, 0T, p and J (plain symbols), once each."""
    out = []
    for m in (*d.transforms, *d.cumulative, d.p, d.J, d.J_direct):
        out += [compare.plain(e) for e in m]
    return list(dict.fromkeys(out))


# ---------------------------------------------------------------------- printing form
def test_tidy_prints_what_simplify_prints_on_derived_entries(leg):
    entries = _entries(leg)
    floats = {compare.plain(s): sp.Float(v * 1000) for s, v in leg.lengths.items()}
    entries += [e.xreplace(floats) for e in entries[:25]]  # the seeds' mm numbers
    for e in entries:
        assert sp.sstr(compare.tidy(e)) == sp.sstr(sp.simplify(e)), e


def test_tidy_is_an_identity():
    rng = np.random.default_rng(1)
    s1, c1, s23 = sp.sin(Q[0]), sp.cos(Q[0]), sp.sin(Q[1] + Q[2])
    exprs = [
        -3 * s1 * c1 - 6 * s1 * s23,
        sp.Float(2.5) * c1 * s23 + sp.Float(5.0) * c1,
        (s1 - c1) / (2 * s1 - 2 * c1 * s23),
        -(Q[0] ** 2) * s1 - Q[0] * s23,
    ]
    for e in exprs:
        t = compare.tidy(e)
        for _ in range(5):
            pt = {q: float(v) for q, v in zip(Q, rng.uniform(-3, 3, 4))}
            assert float(t.xreplace(pt)) == pytest.approx(float(e.xreplace(pt)), rel=1e-12)


# ---------------------------------------------------------------------- numpy screening
def test_evaluate_equals_lambdify(leg):
    entries = _entries(leg) + [sp.sqrt(Q[0] ** 2 + 1) / 3, sp.atan2(Q[1], Q[0]), sp.pi * Q[2]]
    syms = sorted(set().union(*[e.free_symbols for e in entries]), key=str)
    rng = np.random.default_rng(2)
    env = {s: rng.uniform(0.5, 2.0, 8) for s in syms}
    ours = compare._evaluate(entries, env)
    ref = sp.lambdify(syms, entries, "numpy")(*[env[s] for s in syms])
    for k in range(len(entries)):
        expected = np.broadcast_to(np.asarray(ref[k], dtype=float), (8,))
        np.testing.assert_allclose(ours[k].real, expected, rtol=1e-13, atol=1e-15)
        assert not ours[k].imag.any()


def test_evaluate_falls_back_on_what_it_does_not_know_and_screen_uses_it():
    # what the fast rules do not know (the imaginary unit, sinh) goes to sympy.lambdify
    x = np.array([0.5, 1.0, 2.0])
    np.testing.assert_array_equal(compare._evaluate([sp.I * Q[0]], {Q[0]: x})[0], 1j * x)
    np.testing.assert_allclose(compare._evaluate([sp.sinh(Q[0])], {Q[0]: x})[0], np.sinh(x))
    same, opposite = compare.screen(
        [2 * sp.sinh(Q[0]), sp.sqrt(-(Q[0] ** 2) - 1)],
        [sp.exp(Q[0]) - sp.exp(-Q[0]), 0],
        "sinh",
    )
    assert same.tolist() == [True, False]  # 2 sinh x = eˣ − e⁻ˣ; √(−1 − x²) is not real
    assert opposite.tolist() == [False, False]


# ---------------------------------------------------------------------- exact zero test
def test_reduction_proves_pythagorean_identities_only():
    s, c = sp.sin, sp.cos
    q1, q2, q3 = Q[:3]
    l1, l2 = sp.symbols("l1 l2", positive=True)
    zeros = [
        s(q1) ** 2 + c(q1) ** 2 - 1,
        52800 * s(q1) ** 2 * s(q2) + 52800 * s(q2) * c(q1) ** 2 - sp.Float(52800.0) * s(q2),
        (s(q1) ** 2 + c(q1) ** 2) * (s(q2) ** 2 + c(q2) ** 2) - 1,
        l1 * (s(q3) ** 4 - c(q3) ** 4) - l1 * (s(q3) ** 2 - c(q3) ** 2) + l2 * 0,
    ]
    for z in zeros:
        assert compare._reduces_to_zero(sp.expand(z)), z
    not_zeros = [
        s(q1) ** 2 - c(q1) ** 2,
        s(q1) ** 2 + c(q2) ** 2 - 1,  # two different angles
        s(q1) * c(q1) - sp.Rational(1, 2),
        l1 * s(q1) ** 2 + l2 * c(q1) ** 2 - l1,
        s(q1 / 2) ** 2 + c(q1 / 2) ** 2 - 1,  # true, but not of the form handled: no claim
    ]
    rng = np.random.default_rng(3)
    for e in not_zeros:
        assert not compare._reduces_to_zero(sp.expand(e)), e
    for e in not_zeros[:4]:  # and they are indeed not identically zero
        vals = [
            abs(float(e.xreplace({q1: a, q2: b, l1: 1.3, l2: 0.7})))
            for a, b in rng.uniform(-3, 3, (5, 2))
        ]
        assert max(vals) > 1e-3


@pytest.mark.parametrize(
    "count",
    [3, pytest.param(12, marks=pytest.mark.slow)],  # 12: ~30 s of sympy's simplify
)
@pytest.mark.slow
def test_zero_decides_as_simplify_on_random_trig_polynomials(count: int) -> None:
    rng = np.random.default_rng(4)
    s1, c1, s2, c2 = sp.sin(Q[0]), sp.cos(Q[0]), sp.sin(Q[1]), sp.cos(Q[1])
    monomials = [s1, c1, s2, c2, s1 * c2, c1 * s2, s1**2, c2**2, sp.Integer(1)]
    for k in range(count):  # the three identity shapes in turn (once each, or four times)
        coef = rng.integers(-3, 4, len(monomials))
        p = sum(int(a) * m for a, m in zip(coef, monomials))
        identity = p * (s1**2 + c1**2 - 1) + (k % 3) * (s2**2 + c2**2 - 1)
        assert compare._zero(sp.expand(identity)) is True
        assert bool(sp.simplify(identity) == 0)
        if p != 0:
            off = identity + sp.expand(p * s1 * c2) / 7
            assert compare._zero(sp.expand(off)) is bool(sp.simplify(off) == 0)


# ---------------------------------------------------------------------- det J factored
def test_factored_det_equals_factor_of_simplify():
    claims, _ = load_claims()
    ctx = Context(claims=claims)
    dets = [c for c in claims if c.kind == "det"]
    assert dets
    for c in dets:
        raw = _det_truth(c, ctx).xreplace(_subs(c))
        d = ctx.derivation(c.data["model"])
        ours = compare.factored(raw, d.q, d.chain.sigmas, c.id)
        assert sp.srepr(ours) == sp.srepr(sp.factor(sp.simplify(raw)))


# ---------------------------------------------------------------------- derivations
def test_default_rows_and_named_rows_share_one_derivation():
    symbolic.clear_memory()
    chain = robots.hexabot_leg()
    first = derive(chain, budget=None)
    named = derive(chain, rows=("x", "y", "z"), budget=None)  # the default rows, named
    assert named.cached and named.det == first.det and named.rows == first.rows
    symbolic.clear_memory()
    scara = robots.get("scara")
    a = derive(scara, rows=("x", "y", "z", "wz"), budget=None)
    b = derive(scara, budget=None)
    assert b.cached and b.det == a.det and b.rows == ("x", "y", "z", "wz")
    other = derive(scara, rows="position", budget=None)  # not the default: derived anew
    assert not other.cached and other.rows == ("x", "y", "z") and other.det is None


@pytest.mark.slow
def test_without_fork_the_stages_run_inline_with_the_same_result(monkeypatch):
    import multiprocessing

    from hexapod_kin import Chain, DHRow

    chain = robots.hexabot_leg(alpha2=math.pi / 2)
    forked = derive(chain, budget=60.0, cache=False)

    def no_fork(method=None):
        raise ValueError("no fork on this platform")

    monkeypatch.setattr(multiprocessing, "get_context", no_fork)
    inline = derive(chain, budget=60.0, cache=False)
    ur5_dh = [(0, 0.089159, 0, math.pi / 2), (0, 0, -0.425, 0), (0, 0, -0.39225, 0),
              (0, 0.10915, 0, math.pi / 2), (0, 0.09465, 0, -math.pi / 2),
              (0, 0.0823, 0, 0)]  # fmt: skip
    ur5 = Chain.from_dh([DHRow(*row) for row in ur5_dh], name="ur5_inline")
    short = derive(ur5, budget=0.05, cache=False)
    assert inline.text() == forked.text()
    assert short.incomplete and any("budget of 0.05 s" in x for x in short.incomplete)
