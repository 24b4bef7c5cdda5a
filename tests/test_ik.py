"""Inverse kinematics: closed forms checked by Pinocchio FK, the DLS solver and its statuses."""

from __future__ import annotations

import math

import numpy as np
import pytest

import hexapod_kin as hk
from hexapod_kin import ik, robots
from hexapod_kin.exceptions import ConfigurationError, IKError, ParameterError
from hexapod_kin.params import JointLimits


def _fk_many(model, qs):
    return np.array([model.position(q) for q in qs])


def _wrapdiff(a, b):
    return np.remainder(a - b + np.pi, 2 * np.pi) - np.pi


# ------------------------------------------------------------------ family detection
@pytest.mark.parametrize(
    ("preset", "family"),
    [("coxa_tibia_leg", "coxa_tibia"), ("hexabot_leg", "leg3"), ("scara", "scara")],
)
def test_family_from_table(preset, family):
    chain = robots.get(preset)
    assert ik.detect_family(chain).family == family
    # same table, another name and other lengths: still recognised (pattern, not name)
    renamed = chain.replace(name="renamed_robot")
    assert ik.detect_family(renamed).family == family
    assert ik.detect_family(hk.load(chain)).family == family


def test_no_closed_form_is_a_clear_error():
    with pytest.raises(IKError, match="no closed-form IK"):
        ik.detect_family(robots.pendulum())
    leg = robots.hexabot_leg(alpha2=0.3)  # not a ±π/2 twist: no closed form
    with pytest.raises(IKError, match="leg3"):
        ik.analytic(leg, [0.1, 0.0, 0.0])
    from_urdf = hk.load(hk.to_urdf(robots.hexabot_leg()))  # URDF text: no table
    with pytest.raises(IKError, match="ik.solve"):
        ik.analytic(from_urdf, [0.1, 0.0, 0.0])


# ------------------------------------------------------------------ seed 002 (2-DOF)
def test_seed002_points_and_tibia_sign():
    chain = robots.coxa_tibia_leg()
    c30 = 10 + 5 * math.cos(math.radians(30))
    # the seed's P1 (0°, −30°) and P2 (20°, −30°)
    p1 = [c30, 0.0, -2.5]
    p2 = [c30 * math.cos(math.radians(20)), c30 * math.sin(math.radians(20)), -2.5]
    np.testing.assert_allclose(p2, [13.4659, 4.9012, -2.5], atol=1e-4)
    s1 = ik.analytic(chain, p1)
    s2 = ik.analytic(chain, p2)
    np.testing.assert_allclose(s1, np.radians([[0.0, -30.0]]), atol=1e-12)
    np.testing.assert_allclose(s2, np.radians([[20.0, -30.0]]), atol=1e-12)
    # +30° lifts the foot: the seed's θ2 = 180° − β gives the same value for both; we do not
    s_up = ik.analytic(chain, [c30, 0.0, +2.5])
    np.testing.assert_allclose(s_up, np.radians([[0.0, 30.0]]), atol=1e-12)
    beta = lambda p: math.degrees(  # noqa: E731 - the seed's formula (11)
        math.acos((10**2 + 5**2 - sum(v * v for v in p)) / (2 * 10 * 5))
    )
    assert beta(p1) == pytest.approx(beta([c30, 0.0, 2.5]))


def test_coxa_tibia_off_surface_has_no_solution():
    chain = robots.coxa_tibia_leg()
    assert ik.analytic(chain, [14.0, 0.0, -2.5]).shape == (0, 2)  # not on the reachable surface


# ------------------------------------------------------------------ FK(IK(x)) = x, 10,000 targets
@pytest.mark.parametrize("preset", ["coxa_tibia_leg", "hexabot_leg", "scara"])
def test_closed_form_roundtrip_10000(preset):
    chain = robots.get(preset)
    model = hk.load(chain)
    qs = model.random_q(10_000, seed=11)
    targets = _fk_many(model, qs)
    batch = ik.analytic_batch(chain, targets)
    assert batch.reachable.all()
    scale = ik.detect_family(chain).scale
    worst = 0.0
    found = np.zeros(len(qs), dtype=bool)
    for i in range(len(qs)):
        sols = batch.q[i][batch.valid[i]]
        back = _fk_many(model, sols)
        worst = max(worst, float(np.max(np.abs(back - targets[i]))))
        d = _wrapdiff(sols, qs[i])
        if preset == "scara":
            d = d[:, [0, 1, 3]]  # θ3 is free for a position target (we return θ3 = 0)
            d[:, 2] = sols[:, 3] - qs[i, 3]
        found[i] = np.any(np.max(np.abs(d), axis=1) < 1e-7)
    assert worst <= 1e-9 * max(scale, 1.0)
    # the configuration the target came from is among the solutions (all branches are there)
    assert found.all()


def test_leg3_all_four_solutions_distinct_and_correct():
    chain = robots.hexabot_leg()
    model = hk.load(chain)
    target = model.position([0.4, 1.0, 1.5])  # foot close to the hip axis: reachable reversed
    sols = ik.analytic(chain, target)
    assert sols.shape == (4, 3)  # hip toward/reversed × both knee branches
    np.testing.assert_allclose(_fk_many(model, sols), np.tile(target, (4, 1)), atol=1e-15)
    assert len({tuple(np.round(s, 9)) for s in sols}) == 4


def test_scara_yaw_target_sets_tool_yaw():
    chain = robots.scara()
    model = hk.load(chain)
    target = [0.3, 0.2, 0.4, 0.7]
    sols = ik.analytic(chain, target)
    assert sols.shape == (2, 4)
    for s in sols:
        pose = model.fk(s)
        np.testing.assert_allclose(pose[:3, 3], target[:3], atol=1e-14)
        assert math.atan2(pose[1, 0], pose[0, 0]) == pytest.approx(0.7, abs=1e-12)
    # position only: θ3 = 0
    assert np.all(ik.analytic(chain, target[:3])[:, 2] == 0.0)


def test_unreachable_closed_form_and_limits_filter():
    chain = robots.hexabot_leg()
    assert ik.analytic(chain, [1.0, 0.0, 0.0]).shape == (0, 3)
    assert ik.analytic(robots.scara(), [1.0, 0.0, 0.4]).shape == (0, 4)
    lim = tuple(JointLimits(-0.5, 1.6) for _ in range(3))
    limited = robots.hexabot_leg(limits=lim)
    target = hk.load(chain).position([0.4, 0.3, 1.2])
    sols = ik.analytic(limited, target, within_limits=True)
    assert sols.shape == (1, 3)
    np.testing.assert_allclose(sols[0], [0.4, 0.3, 1.2], atol=1e-12)


def test_vectorised_list_and_batch_shapes():
    chain = robots.hexabot_leg()
    model = hk.load(chain)
    targets = _fk_many(model, model.random_q(5, seed=2))
    out = ik.analytic(chain, targets)
    assert isinstance(out, list) and len(out) == 5
    b = ik.analytic_batch(chain, targets)
    assert b.q.shape == (5, 4, 3) and b.valid.shape == (5, 4)
    assert not b.q.flags.writeable
    assert np.all(np.isnan(b.q[~b.valid]))


@pytest.mark.parametrize("bad", [[np.nan, 0, 0], [0, np.inf, 0], [1, 2], "abc"])
def test_bad_targets_refused(bad):
    with pytest.raises(IKError):
        ik.analytic(robots.hexabot_leg(), bad)
    with pytest.raises(IKError):
        ik.solve(hk.load("hexabot_leg"), bad)


# ------------------------------------------------------------------ numerical solver
def _models():
    return {
        "hexabot_leg": hk.load("hexabot_leg"),
        "scara": hk.load("scara"),
        "solo12_FL": hk.load("erd:solo12", tip="FL_FOOT"),
    }


@pytest.fixture(scope="module")
def models():
    return _models()


@pytest.mark.parametrize("name", ["hexabot_leg", "scara", "solo12_FL"])
def test_numerical_roundtrip_10000(models, name):
    model = models[name]
    qs = model.random_q(10_000, seed=5)
    if name == "solo12_FL":  # ±10 rad limits in the URDF; sample one turn
        qs = np.random.default_rng(5).uniform(-np.pi, np.pi, size=(10_000, 3))
    targets = _fk_many(model, qs)
    bad = []
    for i, t in enumerate(targets):
        r = ik.solve(model, t)
        if r.status != "converged":
            bad.append((i, r.status))
            continue
        # equal to Pinocchio: the reported position is Pinocchio's FK of q
        np.testing.assert_array_equal(r.position, model.position(r.q))
        assert np.max(np.abs(r.position - t)) <= 1e-9
        assert np.all(r.q >= model.lower) and np.all(r.q <= model.upper)
        assert np.all(np.diff(r.history) < 0)  # strictly decreasing, step by step
    assert bad == []


def test_convergence_is_monotonic_step_by_step(models):
    model = models["hexabot_leg"]
    r = ik.solve(model, model.position([1.0, -0.7, 2.0]), q0=[0.0, 0.3, 0.3])
    assert r.converged
    h = r.history
    assert len(h) == r.iterations + 1 >= 4
    assert h[0] == pytest.approx(np.linalg.norm(model.position([1.0, -0.7, 2.0])
                                                - model.position([0.0, 0.3, 0.3])))
    assert np.all(np.diff(h) < 0)
    # quadratic convergence at the end: each late error well below the previous one
    assert h[-1] < 1e-10 and h[-2] < 1e-3


def test_dls_step_matches_formula_and_lstsq():
    rng = np.random.default_rng(0)
    for n in (2, 3, 4, 6):
        jac = rng.normal(size=(3, n))
        e = rng.normal(size=3)
        lam2 = 0.3
        expected = jac.T @ np.linalg.solve(jac @ jac.T + lam2 * np.eye(3), e)
        np.testing.assert_allclose(ik.dls_step(jac, e, lam2), expected, atol=1e-12)
        np.testing.assert_allclose(
            ik.dls_step(jac, e, 1e-14), np.linalg.lstsq(jac, e, rcond=None)[0], atol=1e-6
        )


def test_sigma_bounds_match_svd():
    rng = np.random.default_rng(1)
    for n in (1, 2, 3, 4, 7):
        for _ in range(50):
            jac = np.ascontiguousarray(rng.normal(size=(3, n)))
            sv = np.linalg.svd(jac, compute_uv=False)
            smin, smax = ik.sigma_bounds(jac)
            assert smax == pytest.approx(sv[0], rel=1e-9)
            assert smin == pytest.approx(sv[min(n, 3) - 1], rel=1e-6, abs=1e-9)
    singular = np.array([[1.0, 2.0, 3.0], [0.0, 0.0, 0.0], [2.0, 4.0, 6.0]])
    assert ik.sigma_bounds(singular)[0] == pytest.approx(0.0, abs=1e-12)


def test_unreachable_reports_nearest_point_and_never_winds(models):
    model = models["hexabot_leg"]
    for target, nearest in (([1.0, 0.0, 0.0], [0.25, 0, 0]), ([0.0, 0.6, 0.0], [0, 0.25, 0])):
        r = ik.solve(model, target)
        assert r.status == "unreachable"
        assert r.distance == pytest.approx(np.linalg.norm(np.subtract(target, nearest)), abs=1e-6)
        np.testing.assert_allclose(r.nearest, nearest, atol=1e-6)
        assert np.all(np.abs(r.q) <= np.pi)  # no winding to ±1000 rad
        assert np.all(np.diff(r.history) < 0)
    scara = models["scara"]
    r = ik.solve(scara, [1.0, 0.0, 0.3])
    assert r.status == "unreachable"
    assert r.distance == pytest.approx(1.0 - 0.46, abs=1e-6)
    solo = models["solo12_FL"]
    r = ik.solve(solo, [2.0, 1.0, -2.0])
    assert r.status == "unreachable"
    assert np.all(np.abs(r.q) <= 10.0)


def test_joint_limits_status():
    lim = tuple(JointLimits(-0.5, 0.5) for _ in range(3))
    model = hk.load(robots.hexabot_leg(limits=lim))
    reachable_without_limits = hk.load("hexabot_leg").position([0.0, 1.2, 1.0])
    r = ik.solve(model, reachable_without_limits)
    assert r.status == "joint_limits"
    assert np.all(r.q >= -0.5) and np.all(r.q <= 0.5)
    assert r.distance > 0.05
    np.testing.assert_allclose(r.nearest, model.position(r.q), atol=1e-15)


def test_singular_status_without_restarts(models):
    model = models["hexabot_leg"]
    # stretched leg (q3 = 0), target inward along the leg: e is outside the range of J
    r = ik.solve(model, [0.2, 0.0, 0.0], q0=[0.0, 0.0, 0.0], restarts=0)
    assert r.status == "singular"
    assert r.sigma_min < 1e-12
    r2 = ik.solve(model, [0.2, 0.0, 0.0], q0=[0.0, 0.0, 0.0])
    assert r2.converged


def test_not_converged_with_tiny_budget(models):
    model = models["hexabot_leg"]
    r = ik.solve(model, model.position([2.0, -1.0, 2.0]), q0=[0.0, 0.3, 0.3], max_iter=2,
                 restarts=0)
    assert r.status == "not_converged"
    assert r.iterations == 2


def test_solver_argument_errors(models):
    model = models["hexabot_leg"]
    with pytest.raises(ParameterError):
        ik.solve(model, [0.1, 0, 0], tol=-1.0)
    with pytest.raises(ParameterError):
        ik.solve(model, [0.1, 0, 0], max_iter=0)
    with pytest.raises(ConfigurationError):
        ik.solve(model, [0.1, 0, 0], q0=[0.0, 0.0])
    r = ik.solve(model, [0.15, 0.0, -0.1])
    assert not r.q.flags.writeable and not r.history.flags.writeable
    assert set(r.as_dict()) >= {"status", "q", "error", "iterations", "history"}
    assert r.status in ik.STATUSES


def test_solve_many(models):
    model = models["scara"]
    targets = _fk_many(model, model.random_q(20, seed=9))
    res = ik.solve_many(model, targets)
    assert all(r.converged for r in res)
