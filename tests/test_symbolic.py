"""Symbolic derivation (sympy) against closed forms and Pinocchio."""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

from hexapod_kin import load, robots, table_fk
from hexapod_kin.exceptions import ParameterError
from hexapod_kin.symbolic import derive


@pytest.fixture(scope="module")
def leg():
    return derive("hexabot_leg")


@pytest.fixture(scope="module")
def scara():
    return derive("scara")


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
    d = derive("coxa_tibia_leg")
    assert d.det is None
    l1, l2 = sp.symbols("l1 l2", positive=True)
    q2 = sp.Symbol("q2", real=True)
    assert sp.simplify(d.gram - l2**2 * (l1 + l2 * sp.cos(q2)) ** 2) == 0
    assert d.numeric(l1 + l2) == pytest.approx(15.0)


def test_printing(leg):
    text = leg.text()
    assert "det J[x,y,z]" in text and "l1 = d2 = 0.05 m" in text
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
