"""Symbolic derivation (sympy) against closed forms and Pinocchio."""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

from hexapod_kin import load, robots, table_fk
from hexapod_kin.exceptions import ParameterError
from hexapod_kin.symbolic import derive

#: a fresh derivation cache for this module: derivations are computed, not read
pytestmark = pytest.mark.usefixtures("own_cache_dir")


@pytest.fixture(scope="module")
def leg():
    return derive("hexabot_leg", budget=None)


@pytest.fixture(scope="module")
def scara():
    return derive("scara", budget=None)


def test_leg_det_factored_closed_form(leg):
    l1, l2, l3 = sp.symbols("l1 l2 l3", positive=True)
    q2, q3 = sp.symbols("q2 q3", real=True)
    expected = l2 * l3 * sp.sin(q3) * (l1 + l2 * sp.cos(q2) + l3 * sp.cos(q2 + q3))
    assert leg.rows == ("x", "y", "z")
    assert sp.simplify(leg.det - expected) == 0 or sp.simplify(leg.det + expected) == 0
    # factored: a product whose factors show both families
    assert isinstance(leg.det, sp.Mul)
    assert sp.sin(q3) in leg.det.args
    names = [f.name for f in leg.families]
    assert names == [
        "q3 = 0 (mod 2*pi)",
        "q3 = pi (mod 2*pi)",
        "l1 + l2*cos(q2) + l3*cos(q2 + q3) = 0",
    ]
    assert leg.families[1].joint == 2 and leg.families[1].value == pytest.approx(math.pi)


def test_leg_equals_pinocchio_at_100_configurations(leg):
    model = load("hexabot_leg")
    qs = model.random_q(100, seed=3)
    det_sym = leg.function(leg.det)(qs)
    jac_sym = leg.function(leg.J)(qs)
    p_sym = leg.function(leg.p)(qs)[..., 0]
    for i, q in enumerate(qs):
        jac_pin = model.position_jacobian(q)
        assert np.abs(jac_sym[i] - jac_pin).max() < 1e-12
        assert abs(det_sym[i] - np.linalg.det(jac_pin)) < 1e-12
        assert np.abs(p_sym[i] - model.fk(q)[:3, 3]).max() < 1e-12


def test_direct_and_indirect_methods_agree(leg, scara):
    assert leg.methods_agree
    assert scara.methods_agree
    model = load("scara")
    qs = model.random_q(20, seed=1)
    jd = scara.function(scara.J_direct)(qs)
    for i, q in enumerate(qs):
        assert np.abs(jd[i] - model.jacobian(q)).max() < 1e-12


def test_transforms_multiply_to_table_fk(leg):
    chain = robots.hexabot_leg()
    q = np.array([0.3, -0.7, 1.1])
    total = leg.function(leg.cumulative[-1])(q)
    assert np.abs(total - table_fk(chain, q)).max() < 1e-14
    prod = np.eye(4)
    for t in leg.transforms:
        prod = prod @ leg.function(t)(q)
    assert np.abs(prod - total).max() < 1e-14


def test_scara_rows_det_and_families(scara):
    d2, d3 = sp.symbols("d2 d3", positive=True)
    q2 = sp.Symbol("q2", real=True)
    assert scara.rows == ("x", "y", "z", "wz")
    assert sp.simplify(sp.Abs(scara.det) - d2 * d3 * sp.Abs(sp.sin(q2))) == 0
    assert [(f.joint, f.value) for f in scara.families] == [(1, 0.0), (1, pytest.approx(math.pi))]
    model = load("scara")
    qs = model.random_q(50, seed=2)
    det_sym = scara.function(scara.det)(qs)
    for i, q in enumerate(qs):
        jac = model.jacobian(q)[[0, 1, 2, 5]]
        assert abs(det_sym[i] - np.linalg.det(jac)) < 1e-12


def test_non_square_gram_and_numeric_substitution():
    d = derive("coxa_tibia_leg", budget=None)
    assert d.det is None
    l1, l2 = sp.symbols("l1 l2", positive=True)
    q2 = sp.Symbol("q2", real=True)
    assert sp.simplify(d.gram - l2**2 * (l1 + l2 * sp.cos(q2)) ** 2) == 0
    assert d.numeric(l1 + l2) == pytest.approx(15.0)


def test_printing(leg):
    text = leg.text()
    assert "det J[x,y,z]" in text and "l1 (d2) = 0.05 m" in text
    assert "singular families" in text
    tex = leg.latex()
    assert "\\det J" in tex and "\\begin{align*}" in tex and "\\sin{\\left(q_{3} \\right)}" in tex
    assert str(leg) == text


def test_bad_inputs():
    with pytest.raises(ParameterError, match="Hexapod"):
        derive(robots.hexapod())
    with pytest.raises(ParameterError, match="rows"):
        derive("pendulum", rows=("x", "q"))
    with pytest.raises(ParameterError, match="lengths"):
        derive("pendulum", lengths={"d9": "a"})
    with pytest.raises(ParameterError, match="no Khalil table"):
        derive(object())


# ------------------------------------------------------------------ 6-DOF arms, frames, budget
PI = math.pi
PUMA_DH = [(0, 0, 0, PI / 2), (0, 0, 0.4318, 0), (0, 0.15005, 0.0203, -PI / 2),
           (0, 0.4318, 0, PI / 2), (0, 0, 0, -PI / 2), (0, 0, 0, 0)]  # fmt: skip
UR5_DH = [(0, 0.089159, 0, PI / 2), (0, 0, -0.425, 0), (0, 0, -0.39225, 0),
          (0, 0.10915, 0, PI / 2), (0, 0.09465, 0, -PI / 2), (0, 0.0823, 0, 0)]  # fmt: skip


def _chain(table, name):
    from hexapod_kin import Chain, DHRow

    return Chain.from_dh([DHRow(*row) for row in table], name=name)


@pytest.fixture(scope="module")
def puma():
    chain = _chain(PUMA_DH, "puma560")
    return chain, derive(chain, budget=None)


@pytest.fixture(scope="module")
def ur5():
    chain = _chain(UR5_DH, "ur5")
    return chain, derive(chain, budget=None)


def _sigma_min(jac):
    return np.linalg.svd(jac, compute_uv=False)[-1]


def test_puma_det_equals_pinocchio_and_splits_elbow_shoulder_wrist(puma):
    chain, d = puma
    assert d.complete and d.rows == ROWS6 and "wrist centre" in d.method
    model = load(chain)
    qs = model.random_q(50, seed=5)
    det_sym = d.function(d.det)(qs)
    det_num = np.array([np.linalg.det(model.jacobian(q)) for q in qs])
    np.testing.assert_allclose(det_sym, det_num, atol=1e-12)
    # three separate families: wrist q5 in {0, pi}, the elbow in q3 alone, the shoulder
    q3 = [f for f in d.families if f.joint == 2]
    q5 = [f for f in d.families if f.joint == 4]
    implicit = [f for f in d.families if f.joint is None]
    assert sorted(f.value for f in q5) == pytest.approx([0.0, PI])
    assert len(implicit) == 1 and set(implicit[0].variables) == {1, 2}
    # the elbow: the wrist centre on the line of links 2-3; Corke's a3 = 0.0203, d4 = 0.4318:
    # the d4 cos q3 + a3 sin q3 = 0, solved by hand: tan q3 = -d4 / a3
    expect = sorted((math.atan2(-0.4318, 0.0203) + k * PI + PI) % (2 * PI) - PI for k in (0, 1))
    assert sorted(f.value for f in q3) == pytest.approx(expect, abs=1e-12)
    rng = np.random.default_rng(6)
    for fam in q3:
        q = rng.uniform(-PI, PI, 6)
        q[2] = fam.value
        assert _sigma_min(model.jacobian(q)) < 1e-9
        q[2] += 1e-3
        assert _sigma_min(model.jacobian(q)) > 1e-6
    assert all(f.verified for f in d.families)


ROWS6 = ("x", "y", "z", "wx", "wy", "wz")


def test_ur5_det_and_families(ur5):
    chain, d = ur5
    assert d.complete and d.rows == ROWS6
    model = load(chain)
    qs = model.random_q(50, seed=7)
    det_sym = d.function(d.det)(qs)
    det_num = np.array([np.linalg.det(model.jacobian(q)) for q in qs])
    np.testing.assert_allclose(det_sym, det_num, atol=1e-12)
    joints = sorted({f.joint for f in d.families if f.joint is not None})
    assert joints == [2, 4]  # elbow q3 in {0, pi}, wrist q5 in {0, pi}
    assert sum(f.joint is None for f in d.families) == 1  # the shoulder
    assert all(f.verified for f in d.families)


@pytest.mark.slow
def test_ur5_from_example_robot_data_urdf():
    model = load("erd:ur5_robot")
    d = derive("erd:ur5_robot", budget=None)
    assert d.reference == model.base and d.tip == model.tip
    qs = model.random_q(30, seed=8)
    det_sym = d.function(d.det)(qs)
    det_num = np.array([np.linalg.det(model.jacobian(q)) for q in qs])
    np.testing.assert_allclose(det_sym, det_num, atol=1e-9)
    jac_sym = d.function(d.J_direct)(qs)
    for i, q in enumerate(qs):
        np.testing.assert_allclose(jac_sym[i], model.jacobian(q), atol=1e-9)


def test_hexapod_leg_is_derived_in_the_frame_asked_for():
    model = load("hexapod", tip="leg2_foot")
    d = derive(model, budget=None)
    assert d.reference == "body" and d.tip == "leg2_foot"
    qs = model.random_q(30, seed=9)
    jac = d.function(d.J_rows)(qs)
    p = d.function(d.p)(qs)[..., 0]
    for i, q in enumerate(qs):
        np.testing.assert_allclose(jac[i], model.jacobian(q)[:3], atol=1e-12)
        np.testing.assert_allclose(p[i], model.fk(q)[:3, 3], atol=1e-12)
    same = derive(robots.hexapod(), tip="leg2_foot", budget=None)
    assert same.reference == "body" and sp.simplify(same.det - d.det) == 0


def test_urdf_sources_are_read_back():
    from pathlib import Path

    path = Path(__file__).resolve().parent.parent / "urdf" / "hexabot_leg.urdf"
    d = derive(str(path), budget=None)
    model = load(str(path))
    qs = model.random_q(30, seed=10)
    det_sym = d.function(d.det)(qs)
    for i, q in enumerate(qs):
        assert abs(det_sym[i] - np.linalg.det(model.jacobian(q)[:3])) < 1e-12
    solo = derive("erd:solo12", tip="FL_FOOT", budget=None)
    assert solo.complete and len(solo.families) >= 2


def test_four_dof_leg_gram_families():
    from hexapod_kin import Chain, KhalilRow

    leg4 = Chain(
        rows=(
            KhalilRow(0),
            KhalilRow(0, -PI / 2, 0.05),
            KhalilRow(0, 0, 0.1),
            KhalilRow(0, 0, 0.1),
            KhalilRow("fixed", 0, 0.05),
        ),  # fmt: skip
        name="leg4",
    )
    d = derive(leg4, budget=None)
    assert d.complete and d.det is None and d.rows == ("x", "y", "z")
    model = load(leg4)
    qs = model.random_q(40, seed=11)
    gram = d.function(d.gram)(qs)
    for i, q in enumerate(qs):
        jac = model.jacobian(q)[:3]
        assert abs(gram[i] - np.linalg.det(jac @ jac.T)) < 1e-12
    # the foot on the hip axis: l1 + l2 c2 + l3 c23 + l4 c234 = 0
    assert len(d.families) == 1 and d.families[0].variables == (1, 2, 3)
    assert d.families[0].verified


def test_budget_stops_and_says_what_is_missing():
    chain = _chain(UR5_DH, "ur5_budget")
    d = derive(chain, budget=0.05, cache=False)
    assert d.incomplete and any("budget of 0.05 s" in x for x in d.incomplete)
    assert d.det is None and not d.families and not d.complete
    model = load(chain)
    q = model.random_q(1, seed=12)[0]
    np.testing.assert_allclose(d.function(d.J_direct)(q), model.jacobian(q), atol=1e-12)
    assert "NOT DONE" in d.text()
    with pytest.raises(ParameterError, match="budget"):
        derive("scara", budget=0)


def test_disk_cache_round_trip_and_corrupt_file(tmp_path, monkeypatch):
    from hexapod_kin import symbolic
    from hexapod_kin.symbolic import cache as symbolic_cache

    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(tmp_path))
    symbolic.clear_memory()
    first = derive("scara", budget=None)
    files = list((tmp_path / "symbolic").glob("*.json"))
    assert not first.cached and len(files) == 1
    memo = derive("scara", budget=None)  # this process: from memory
    assert memo.cached and memo.det == first.det
    symbolic.clear_memory()  # a new process: from the disk
    second = derive("scara", budget=None)
    assert second.cached and sp.simplify(second.det - first.det) == 0
    assert [f.name for f in second.families] == [f.name for f in first.families]
    assert second.families[0].verified == first.families[0].verified
    files[0].write_text("{ not json", encoding="utf-8")
    symbolic.clear_memory()
    third = derive("scara", budget=None)
    assert not third.cached and sp.simplify(third.det - first.det) == 0
    assert symbolic_cache.load(files[0].stem) is not None  # rewritten


def test_numeric_families_vanish_on_the_symbolic_families(leg, tmp_path, monkeypatch):
    # the scans' numeric form of the families (singularity.families) is the derivation's
    from hexapod_kin.singularity import families_for

    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(tmp_path))
    fams = families_for(load("hexabot_leg"), leg.rows, derive=True).families
    assert [f.name for f in fams] == [f.name for f in leg.families]
    q = np.array([[0.3, -0.4, 0.0], [0.3, -0.4, PI], [0.2, 0.1, 0.7]])
    assert fams[0].distance(q)[0] == pytest.approx(0.0, abs=1e-15)
    assert fams[1].distance(q)[1] == pytest.approx(0.0, abs=1e-12)
    sym = leg.function(leg.families[2].factor)(q)
    np.testing.assert_allclose(fams[2].residual(q), sym, rtol=1e-13, atol=1e-15)


def test_whole_hexapod_model_is_refused_with_the_feet_listed():
    model = load("hexapod")  # 18 joints, default tip leg1_foot
    with pytest.raises(ParameterError, match="moves 18 joints.*leg2_foot"):
        derive(model)


def test_cached_never_derives(tmp_path, monkeypatch):
    from hexapod_kin import symbolic
    from hexapod_kin.symbolic import cached

    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(tmp_path))
    symbolic.clear_memory()
    assert cached("coxa_tibia_leg") is None
    d = derive("coxa_tibia_leg", budget=None)
    symbolic.clear_memory()
    again = cached("coxa_tibia_leg")
    assert again is not None and again.cached and sp.simplify(again.gram - d.gram) == 0


def test_table_file_keeps_its_own_table():
    from pathlib import Path

    from hexapod_kin.sources import resolve_source

    path = str(Path(__file__).resolve().parent.parent / "examples" / "leg4.toml")
    d = derive(path, budget=None)
    assert d.chain == resolve_source(path).params
    model = load(path)
    qs = model.random_q(20, seed=13)
    gram = d.function(d.gram)(qs)
    for i, q in enumerate(qs):
        jac = model.jacobian(q)[:3]
        assert abs(gram[i] - np.linalg.det(jac @ jac.T)) < 1e-12


@pytest.mark.parametrize("name", ["hexabot_leg", "scara"])
def test_all_six_rows_gram_equals_numeric(name):
    d = derive(name, rows="all", budget=None)
    model = load(name)
    qs = model.random_q(20, seed=14)
    gram = d.function(d.gram)(qs)
    for i, q in enumerate(qs):
        jac = model.jacobian(q)
        assert abs(gram[i] - np.linalg.det(jac.T @ jac)) < 1e-12


# ------------------------------------------------------------------ the exact and numeric tools
@pytest.mark.slow
def test_ring_determinant_equals_the_expanded_one_and_numpy():
    """The ring route gives the polynomial the expression route gives; both equal numpy's det."""
    from hexapod_kin.symbolic._trigpoly import _det_poly, _to_poly, _trig_symbols, ring_det

    q = sp.symbols("q1:4", real=True)
    a, b = sp.symbols("a b", positive=True)
    sigmas = ("revolute", "revolute", "prismatic")
    rng = np.random.default_rng(8)
    atoms = [sp.sin(q[0]), sp.cos(q[0] + q[1]), sp.sin(q[1]), q[2], a, b * sp.cos(q[1])]
    entries = [
        sum(sp.Rational(int(rng.integers(-3, 4)), 2) * atoms[int(rng.integers(6))]
            * atoms[int(rng.integers(6))] for _ in range(3))
        for _ in range(16)
    ]  # fmt: skip
    mat = sp.Matrix(4, 4, entries)
    poly = _det_poly(mat, q, sigmas)
    assert poly == _to_poly(mat.det(method="berkowitz"), q, sigmas)
    s, c = _trig_symbols(q)
    for qv in rng.uniform(-3, 3, (5, 3)):
        vals = {a: 0.7, b: 1.3, q[0]: qv[0], q[1]: qv[1], q[2]: qv[2]}
        vals.update({s[k]: math.sin(qv[k]) for k in range(2)})
        vals.update({c[k]: math.cos(qv[k]) for k in range(2)})
        want = np.linalg.det(np.array(mat.subs(vals).evalf(), dtype=float))
        # xreplace: the same numbers put in for the symbols, without subs' search for
        # patterns through the ~30,000-character polynomial (1 s a point, xreplace 0.2 s)
        got = poly.xreplace({k: sp.Float(v) for k, v in vals.items()})
        assert float(got) == pytest.approx(want, rel=1e-12, abs=1e-12)
    x = sp.Symbol("x")
    assert ring_det([x, sp.Float(0.5)], 1, [x]) is None  # floats keep the expression route
    assert ring_det([sp.sqrt(3) * x], 1, [x]) is None  # so do algebraic numbers
    assert ring_det([x, 1, 2, x], 2, [x]) == x**2 - 2


def test_root_finder_is_scipy_brentq_to_the_bit():
    from scipy.optimize import brentq

    from hexapod_kin.symbolic._numbers import brent_root

    rng = np.random.default_rng(11)
    solved = 0
    for _ in range(100):
        c = rng.normal(size=4)
        ph = float(rng.uniform(-3, 3))

        def f(x, c=c, ph=ph):
            return c[0] + c[1] * math.cos(x + ph) + c[2] * math.sin(2 * x) + c[3] * x**3

        grid = np.linspace(-math.pi, math.pi, 40)
        vals = [f(x) for x in grid]
        for lo, hi, flo, fhi in zip(grid, grid[1:], vals, vals[1:]):
            if flo * fhi < 0:
                for xtol in (1e-15, 2e-12):
                    assert brent_root(f, lo, hi, xtol) == brentq(f, lo, hi, xtol=xtol)
                solved += 1
    assert solved > 100
