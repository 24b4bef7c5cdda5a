"""Numerical IK (``ik.solve``): positions on the legs, 6-D poses on UR5 and Panda, statuses."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import hexapod_kin as hk
from hexapod_kin import ik, robots
from hexapod_kin.exceptions import ConfigurationError, IKError, ParameterError
from hexapod_kin.params import JointLimits


def _fk_many(model, qs):
    return np.array([model.position(q) for q in qs])


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


def _check(model, r, target):
    """A converged result, checked with Pinocchio's FK at the solution."""
    assert r.status == "converged", r.reason
    np.testing.assert_allclose(r.position, model.position(r.q), rtol=0, atol=1e-15)
    assert np.max(np.abs(r.position - target[..., :3])) <= 1e-9
    assert np.all(r.q >= model.lower) and np.all(r.q <= model.upper)
    assert np.all(np.diff(r.history) < 0)  # strictly decreasing, step by step


@pytest.mark.parametrize("name", ["hexabot_leg", "scara", "solo12_FL"])
def test_solve_many_and_solve_agree(models, name):
    """solve_many (compiled) on 3,000 targets; solve (numpy + Pinocchio) on 200 of them."""
    model = models[name]
    qs = model.random_q(3_000, seed=5)
    if name == "solo12_FL":  # ±10 rad limits in the URDF; sample one turn
        qs = np.random.default_rng(5).uniform(-np.pi, np.pi, size=(3_000, 3))
    targets = _fk_many(model, qs)
    many = ik.solve_many(model, targets)
    for r, t in zip(many, targets):
        _check(model, r, t)
    same = 0
    for r_many, t in zip(many[:200], targets[:200]):
        r = ik.solve(model, t)
        _check(model, r, t)
        same += bool(np.max(np.abs(r.q - r_many.q)) <= 1e-6)
    assert same >= 196  # the same branch from the same start (rounding may tip a rare one)


def test_convergence_is_monotonic_step_by_step(models):
    model = models["hexabot_leg"]
    r = ik.solve(model, model.position([1.0, -0.7, 2.0]), q0=[0.0, 0.3, 0.3])
    assert r.converged
    h = r.history
    assert len(h) == r.iterations + 1 >= 4
    assert h[0] == pytest.approx(
        np.linalg.norm(model.position([1.0, -0.7, 2.0]) - model.position([0.0, 0.3, 0.3]))
    )
    assert np.all(np.diff(h) < 0)
    # quadratic convergence at the end: each late error well below the previous one
    assert h[-1] < 1e-10 and h[-2] < 1e-3


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
    r = ik.solve(
        model, model.position([2.0, -1.0, 2.0]), q0=[0.0, 0.3, 0.3], max_iter=2, restarts=0
    )
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
    assert set(r.to_dict()) >= {"status", "q", "error", "iterations", "history"}
    assert r.status in ik.STATUSES


def test_solve_many(models):
    model = models["scara"]
    targets = _fk_many(model, model.random_q(20, seed=9))
    res = ik.solve_many(model, targets)
    assert all(r.converged for r in res)


# ------------------------------------------------------------------ 6-D poses (UR5, Panda)
@pytest.fixture(scope="module")
def arms():
    return {
        "ur5": hk.load("erd:ur5_robot", tip="tool0"),
        "panda": hk.load("erd:panda", tip="panda_hand"),
    }


def _pose_errors(model, q, target):
    """Position [m] and orientation [rad] errors from Pinocchio's own FK and log map."""
    pose = model.fk(q)
    return (
        float(np.linalg.norm(target[:3, 3] - pose[:3, 3])),
        float(np.linalg.norm(pin.log3(target[:3, :3] @ pose[:3, :3].T))),
    )


@pytest.mark.parametrize("arm", ["ur5", "panda"])
def test_pose_ik_random_reachable_poses(arms, arm):
    model = arms[arm]
    qs = model.random_q(300, seed=21)
    targets = np.array([model.fk(q) for q in qs])  # reachable: FK of q within the limits
    many = ik.solve_many(model, targets)
    failed = []
    same = 0
    for i, (target, r_many) in enumerate(zip(targets, many)):
        r = ik.solve(model, target) if i < 100 else r_many
        same += i < 100 and bool(np.max(np.abs(r.q - r_many.q)) <= 1e-6)
        pos_err, rot_err = _pose_errors(model, r.q, target)
        if not (r.converged and pos_err <= 1e-9 and rot_err <= 1e-9):
            failed.append((i, r.status))
            continue
        assert np.all(r.q >= model.lower) and np.all(r.q <= model.upper)
        assert r.error == pytest.approx(pos_err, abs=1e-15)
        assert r.rotation_error == pytest.approx(rot_err, abs=1e-12)
        assert np.all(np.diff(r.history) < 0)
    assert len(failed) <= 1, failed  # >= 99.6 % (tools/bench_ik.py: 2,000 poses)
    assert same >= 97  # solve (numpy) and solve_many (compiled) agree


def test_pose_ik_large_rotation_and_near_pi(arms):
    # the start is ~π away in orientation: the log map's branch near π is used
    model = arms["ur5"]
    q_target = np.array([0.3, -1.2, 1.4, 0.2, 1.1, 2.9])
    target = model.fk(q_target)
    r = ik.solve(model, target, q0=q_target + [0.0, 0.0, 0.0, 0.0, 0.0, -np.pi + 1e-6])
    assert r.converged
    assert max(_pose_errors(model, r.q, target)) <= 1e-9


def test_mask_and_weights(arms):
    model = arms["ur5"]
    target = model.fk(np.array([0.5, -1.0, 1.2, -0.4, 1.3, 0.2]))
    # position + rotation about z only: the tool's z axis stays free
    r = ik.solve(model, target, mask=[1, 1, 1, 0, 0, 1])
    assert r.converged and r.error <= 1e-9
    ew = pin.log3(target[:3, :3] @ model.fk(r.q)[:3, :3].T)
    assert abs(ew[2]) <= 1e-9 and r.rotation_error == pytest.approx(abs(ew[2]), abs=1e-12)
    # weights change the path, not the answer of a reachable pose
    r2 = ik.solve(model, target, weights=[1, 1, 1, 0.1, 0.1, 0.1])
    assert r2.converged and max(_pose_errors(model, r2.q, target)) <= 1e-9
    with pytest.raises(IKError, match="not both"):
        ik.solve(model, target, mask=[1] * 6, weights=[1] * 6)
    with pytest.raises(IKError, match="wx"):
        ik.solve(model, target[:3, 3], mask=[1, 1, 1, 1, 0, 0])
    with pytest.raises(IKError):
        ik.solve(model, target, weights=[0] * 6)


def test_bad_pose_targets(arms):
    model = arms["ur5"]
    bad = np.eye(4)
    bad[0, 0] = 1.1
    with pytest.raises(IKError, match="rigid"):
        ik.solve(model, bad)
    mirror = np.diag([1.0, 1.0, -1.0, 1.0])
    with pytest.raises(IKError, match="rigid"):
        ik.solve(model, mirror)
    with pytest.raises(IKError):
        ik.solve(model, np.zeros((3, 3)))


def test_position_plus_yaw_on_the_scara(models):
    scara = models["scara"]
    q = np.array([0.4, -0.9, 0.6, 0.12])
    pose = scara.fk(q)
    yaw = math.atan2(pose[1, 0], pose[0, 0])
    r = ik.solve(scara, np.append(pose[:3, 3], yaw))
    assert r.converged
    reached = scara.fk(r.q)
    assert np.max(np.abs(reached[:3, 3] - pose[:3, 3])) <= 1e-9
    assert abs(math.remainder(math.atan2(reached[1, 0], reached[0, 0]) - yaw, 2 * math.pi)) <= 1e-9


def test_redundant_chain_posture_in_the_null_space(arms):
    # Panda (7 joints) on 6-D poses: the secondary task pulls toward the middle of the ranges
    model = arms["panda"]
    middle = 0.5 * (model.lower + model.upper)
    qs = model.random_q(40, seed=4)
    with_posture, without = [], []
    for q in qs:
        target = model.fk(q)
        a = ik.solve(model, target, posture="middle")
        b = ik.solve(model, target, posture=None)
        if a.converged and b.converged and a.attempts == b.attempts == 1:
            assert max(_pose_errors(model, a.q, target)) <= 1e-9
            with_posture.append(np.linalg.norm(a.q - middle))
            without.append(np.linalg.norm(b.q - middle))
    assert len(with_posture) >= 20
    assert np.mean(with_posture) < np.mean(without)
    # a preferred posture of the user's
    pref = model.random_q(seed=8)
    r = ik.solve(model, model.fk(qs[0]), posture=pref)
    assert r.converged
    with pytest.raises(ParameterError):
        ik.solve(model, model.fk(qs[0]), posture="upright")


def test_solve_many_poses_and_home(arms):
    model = arms["ur5"]
    qs = model.random_q(5, seed=2)
    poses = np.array([model.fk(q) for q in qs])
    res = ik.solve_many(model, poses, mask=[1, 1, 1, 1, 1, 0])
    for r, pose in zip(res, poses):  # the same answers as one by one, to rounding
        one = ik.solve(model, pose, mask=[1, 1, 1, 1, 1, 0])
        np.testing.assert_allclose(r.q, one.q, rtol=0, atol=1e-9)
        assert r.status == one.status == "converged"
    with pytest.raises(ConfigurationError):
        ik.solve_many(model, poses, q0=np.zeros((4, 6)))
    home = ik.home(model)
    assert np.all(home >= model.lower) and np.all(home <= model.upper)
    # the home pose is the most dexterous candidate: far from the position singularities
    sv = np.linalg.svd(model.jacobian(home)[:3], compute_uv=False)
    assert sv[-1] > 0.05 * sv[0]
    np.testing.assert_array_equal(ik.home(hk.load("hexabot_leg")), ik.LEG_HOME)
    assert ik.solve("hexabot_leg", [0.15, 0.0, -0.1]).converged  # any source
    with pytest.raises(ParameterError, match="valid"):
        ik.solve(model, poses[0], tolerance=1e-9)
    assert ik.IKOptions(tol=1e-8).to_dict()["tol"] == 1e-8


def test_threads_give_the_single_thread_answers(arms):
    import sys
    from concurrent.futures import ThreadPoolExecutor

    model = arms["ur5"]
    targets = [model.fk(q) for q in model.random_q(64, seed=6)]
    single = [ik.solve(model, t).q for t in targets]
    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    try:
        with ThreadPoolExecutor(8) as pool:
            multi = list(pool.map(lambda t: ik.solve(model, t).q, targets * 2))
    finally:
        sys.setswitchinterval(old)
    for a, b in zip(single * 2, multi):
        np.testing.assert_array_equal(a, b)


def test_closed_forms_run_without_numba():
    """Size rule: ik.analytic and analytic_batch import no compiled layer (ik.solve does)."""
    import subprocess
    import sys

    code = (
        "import sys, hexapod_kin as hk\n"
        "hk.ik.analytic('hexabot_leg', [0.15, 0.0, -0.1])\n"
        "hk.ik.analytic_batch('scara', [[0.3, 0.2, 0.1]], within_limits=True)\n"
        "assert 'numba' not in sys.modules, 'numba imported'\n"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr


#: One target per call and the same targets as one batch, digested field by field.
_BITS = """
import hashlib, json, sys
import numpy as np
import hexapod_kin as hk
from hexapod_kin import ik

def digest(results):
    h = hashlib.sha256()
    for r in results:
        for k, v in sorted(r.to_dict().items()):
            h.update(k.encode() + repr(v).encode())
        for a in (r.q, r.history, r.position, r.rotation):
            h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()

def cases():
    leg, arm = hk.load("hexabot_leg"), hk.load("erd:ur5_robot")
    scara = hk.load("scara")
    pos = np.array([leg.position(q) for q in leg.random_q(12, seed=4)])
    pos[::4] *= 3.0  # unreachable ones too
    poses = np.array([arm.fk(q) for q in arm.random_q(12, seed=4)])
    yaw = np.array([np.append(scara.position(q), 0.2) for q in scara.random_q(6, seed=4)])
    return [(leg, pos, {}), (arm, poses, {}), (arm, poses[:4], {"max_iter": 3}),
            (scara, yaw, {}), (leg, pos[:4], {"restarts": 0, "tol": 1e-6})]

out = []
for model, targets, kw in cases():
    one = digest([ik.solve(model, t, **kw) for t in targets])  # per call first (cold)
    out.append([one, digest(ik.solve_many(model, targets, **kw))])
print(json.dumps(out))
"""


def test_per_call_and_batch_give_the_same_bits_fresh_and_warm():
    """ik.solve of one target == its row of solve_many, in a fresh process and a warm one."""
    import json
    import subprocess
    import sys

    runs = []
    for _ in range(2):  # the second process: everything loaded from the warm caches
        res = subprocess.run(
            [sys.executable, "-c", _BITS], capture_output=True, text=True, timeout=600
        )
        assert res.returncode == 0, res.stderr[-2000:]
        runs.append(json.loads(res.stdout.splitlines()[-1]))
    for one, many in runs[0]:
        assert one == many
    assert runs[1] == runs[0]


def test_solve_chain_is_the_loop_of_solve_many_on_a_chain_view():
    leg = hk.load("hexabot_leg")
    qs = leg.random_q(40, seed=8)
    targets = np.array([leg.position(q) for q in qs])
    seeds = qs + np.random.default_rng(8).normal(scale=0.2, size=qs.shape)
    q, residual, ok = ik.solve_chain(leg.arrays, targets, seeds, leg.lower, leg.upper)
    many = ik.solve_many(leg, targets, seeds, restarts=0)
    for i, r in enumerate(many):
        np.testing.assert_array_equal(q[i], r.q)
        assert ok[i] == r.converged
        assert residual[i] == r.history[-1]
    reached = np.array([leg.position(x) for x in q[ok]])
    assert np.abs(reached - targets[ok]).max() <= 1e-9  # Pinocchio's FK, independent
    assert ok.mean() >= 0.9
    with pytest.raises(IKError):
        ik.solve_chain(leg.arrays, targets, seeds[:3], leg.lower, leg.upper)


def test_build_tasks_equals_build_task_row_by_row():
    arm = hk.load("erd:ur5_robot")
    poses = np.array([arm.fk(q) for q in arm.random_q(20, seed=3)])
    for targets in (poses, poses[:, :3, 3]):
        fast = ik.build_tasks(targets)
        slow = [ik.build_task(t) for t in targets]
        assert [t.mode for t in fast] == [t.mode for t in slow]
        assert all(np.array_equal(a.pose, b.pose) for a, b in zip(fast, slow))
        assert all(np.array_equal(a.weights, b.weights) for a, b in zip(fast, slow))
        assert all(not t.pose.flags.writeable for t in fast)
    bad = poses.copy()
    bad[7, :3, :3] *= 1.01  # not a rotation: the row-by-row path names it
    with pytest.raises(IKError, match="rigid transform"):
        ik.build_tasks(bad)


@pytest.mark.parametrize("name", ["hexabot_leg", "erd:ur5_robot", "erd:panda", "scara"])
def test_reported_measures_against_pinocchio(name):
    """Position, rotation, errors and σ_min of the result (compiled) against Pinocchio + SVD."""
    model = hk.load(name)
    qs = model.random_q(60, seed=12)
    targets = np.array([model.fk(q) for q in qs])
    if model.nq != 6 and name != "erd:panda":
        targets = targets[:, :3, 3] * np.where(np.arange(60) % 7 == 0, 3.0, 1.0)[:, None]
    for r, t in zip(ik.solve_many(model, targets), targets):
        pose = model.fk(r.q)
        np.testing.assert_allclose(r.position, pose[:3, 3], rtol=0, atol=1e-15)
        np.testing.assert_allclose(r.rotation, pose[:3, :3], rtol=0, atol=1e-15)
        assert r.error == pytest.approx(
            np.linalg.norm(t[..., :3, 3] - pose[:3, 3])
            if t.ndim == 2
            else np.linalg.norm(t[:3] - pose[:3, 3]),
            abs=1e-15,
        )
        if t.ndim == 2:
            rot = np.linalg.norm(pin.log3(t[:3, :3] @ pose[:3, :3].T))
            assert r.rotation_error == pytest.approx(rot, abs=1e-14)
        sv = np.linalg.svd(model.jacobian(r.q)[:3], compute_uv=False)
        smin = sv[2] if model.nq >= 3 else 0.0
        assert r.sigma_min == pytest.approx(smin, rel=1e-9, abs=1e-15 * sv[0])
    # at an exact singularity (the stretched leg): 0 to rounding, as the SVD
    leg = hk.load("hexabot_leg")
    r = ik.solve(leg, [0.2, 0.0, 0.0], q0=[0.0, 0.0, 0.0], restarts=0)
    assert (
        r.sigma_min <= 1e-15 and np.linalg.svd(leg.jacobian(r.q)[:3], compute_uv=False)[-1] <= 1e-15
    )


def test_every_path_uses_the_one_compiled_loop(arms):
    """solve, solve_many, solve_chain, masks, strided weights, yaw, q0 and the statuses' checks
    all pass the loop the same argument types (one specialisation, never a second compile);
    the caller's weights stay writeable; the result equals the one its dataclass ``__init__``
    builds."""
    from dataclasses import fields

    from hexapod_kin.ik import step

    ur5, leg = arms["ur5"], hk.load("hexabot_leg")
    target = ur5.fk(np.array([0.5, -1.0, 1.2, -0.4, 1.3, 0.2]))
    strided = np.array([1.0, 0, 1, 0, 1, 0, 1, 0, 0.5, 0, 0.5, 0, 0.5, 0])[::2][:6]
    assert not strided.flags.c_contiguous
    ik.solve(ur5, target, weights=strided)
    assert strided.flags.writeable
    ik.solve(ur5, target, mask=[1, 1, 1, 0, 0, 1], q0=np.zeros(6))
    ik.solve(hk.load("scara"), [0.3, 0.1, 0.0, 0.4])
    ik.solve(ur5, target[:3, 3] * 5)  # unreachable: the local-minimum check runs the loop
    ik.solve_many(ur5, np.array([target, target]))
    q = leg.random_q(3, seed=1)
    ik.solve_chain(leg.arrays, [leg.position(x) for x in q], q, leg.lower, leg.upper)
    assert len(step.lm_loop.signatures) == 1
    res = ik.solve(ur5, target)
    built = ik.IKResult(**{f.name: getattr(res, f.name) for f in fields(ik.IKResult)})
    assert built == res and repr(built) == repr(res)
    assert vars(built).keys() == vars(res).keys()
    task = ik.build_task(target)
    assert ik.Task(task.mode, task.pose, task.yaw, task.weights) == task


def _bits(results):
    """Every field of every result, as ``to_dict`` gives it, and the arrays' bytes."""
    return [
        (sorted(r.to_dict().items()), *(np.asarray(a).tobytes() for a in (r.q, r.history)))
        for r in results
    ]


def test_the_loop_run_by_python_gives_the_compiled_bits(monkeypatch):
    """A process's first solves run the loop's own functions in Python (nothing to compile):
    the same bits as the compiled loop, statuses and their diagnosis included."""
    from hexapod_kin.ik import solver

    leg, ur5, panda = hk.load("hexabot_leg"), hk.load("erd:ur5_robot"), hk.load("erd:panda")
    scara = hk.load("scara")
    narrow = hk.load(robots.hexabot_leg(limits=tuple(JointLimits(-0.5, 0.5) for _ in range(3))))
    pos = np.array([leg.position(q) for q in leg.random_q(10, seed=5)])
    pos[::5] *= 3.0  # unreachable: the local-minimum check runs the loop too
    poses = np.array([ur5.fk(q) for q in ur5.random_q(6, seed=5)])
    seven = np.array([panda.fk(q) for q in panda.random_q(4, seed=5)])  # posture task
    yaw = np.array([np.append(scara.position(q), 0.3) for q in scara.random_q(4, seed=5)])
    cases = [
        (leg, pos, {}),
        (narrow, leg.position([0.0, 1.2, 1.0])[None], {}),  # joint_limits
        (ur5, poses, {}),
        (ur5, poses[:2], {"mask": [1, 1, 1, 0, 0, 1], "max_iter": 3}),
        (ur5, poses[2:4], {"q0": np.full(6, 0.3)}),
        (panda, seven, {}),
        (scara, yaw, {}),
    ]
    statuses = set()
    for model, targets, kw in cases:
        monkeypatch.setattr(solver, "_LOADED", [])
        monkeypatch.setattr(solver, "_LEFT", [len(targets)])
        python = [ik.solve(model, t, **kw) for t in targets]
        assert solver._LEFT == [0] and not solver._LOADED  # nothing loaded or compiled
        compiled = ik.solve_many(model, targets, **kw)
        assert solver._LOADED
        assert _bits(python) == _bits(compiled)
        statuses |= {r.status for r in python}
    assert {"converged", "unreachable", "not_converged", "joint_limits"} <= statuses


def test_a_command_solving_one_target_compiles_nothing(tmp_path):
    """`ik` on fresh caches: no compile notice, the answer of the compiled loop (issue 34)."""
    import json
    import os
    import subprocess
    import sys

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "n"), HEXAPOD_KIN_CACHE_DIR=str(tmp_path))
    argv = [sys.executable, "-m", "hexapod_kin", "ik", "hexabot_leg", "--json", "--target"]
    res = subprocess.run([*argv, "0.25", "0.05", "-0.1"], capture_output=True, text=True, env=env)
    assert res.returncode == 1 and "compiling" not in res.stderr, res.stderr
    got = json.loads(res.stdout)["numerical"]
    assert not any(tmp_path.joinpath("n").rglob("*.nbc"))  # no machine code written
    leg = hk.load("hexabot_leg")
    want = ik.solve_many(leg, np.array([[0.25, 0.05, -0.1]]))[0].to_dict()
    assert got["status"] == "unreachable" and got == json.loads(json.dumps(want))


@pytest.mark.parametrize("name", ["hexabot_leg", "erd:ur5_robot"])
def test_the_default_start_is_the_nearest_candidate(name):
    """Without q0 the first attempt starts from the candidate (home, then seeded samples) whose
    tip pose is nearest the target: its residual, from Pinocchio's FK and log map, is the
    result's first history value whenever that attempt converged."""
    model = hk.load(name)
    prep = ik.prepared(model)
    assert prep.near.shape == (ik.prepare.N_NEAR, model.nq)
    np.testing.assert_array_equal(prep.near[0], ik.home(model))
    poses = np.array([model.fk(q) for q in model.random_q(40, seed=9)])
    position = model.nq == 3
    first = 0
    for pose, r in zip(poses, ik.solve_many(model, poses[:, :3, 3] if position else poses)):
        reached = np.array([model.fk(q) for q in prep.near])
        d = np.sum((pose[:3, 3] - reached[:, :3, 3]) ** 2, axis=1)
        if not position:
            d = d + np.sum((pose[:3, :3] - reached[:, :3, :3]) ** 2, axis=(1, 2))
        k = int(np.argmin(d))
        e = np.linalg.norm(pose[:3, 3] - reached[k, :3, 3])
        if not position:
            e = math.hypot(e, np.linalg.norm(pin.log3(pose[:3, :3] @ reached[k, :3, :3].T)))
        if r.attempts == 1 and r.converged:
            first += 1
            assert r.history[0] == pytest.approx(e, rel=1e-9, abs=1e-15)
    assert first >= 30


def test_the_quick_per_call_path_gives_the_general_paths_results():
    """A float64 position or pose without options takes the quick path (its converged results
    filled when first read): every field and array byte equals the general path's (a list, or
    an option) and the batch's; a read field is the dataclass's; pickling and copying fill it;
    a name that is no field raises AttributeError."""
    import copy
    import pickle
    from dataclasses import fields

    from hexapod_kin.ik import solver

    leg, ur5 = hk.load("hexabot_leg"), hk.load("erd:ur5_robot")
    pos = np.array([leg.position(q) for q in leg.random_q(12, seed=8)])
    pos[::4] *= 3.0  # unreachable: the quick path hands it to the diagnosis
    poses = np.array([ur5.fk(q) for q in ur5.random_q(8, seed=8)])
    for model, targets in ((leg, pos), (ur5, poses)):
        ik.solve_many(model, targets[:2])  # the loop loaded: the quick path is open
        quick = [ik.solve(model, t) for t in targets]
        lazy = ["_lazy" in vars(r) for r in quick]  # before any field is read
        assert lazy == [r.converged for r in quick]
        assert {r.status for r in quick} >= ({"converged", "unreachable"} if model is leg else
                                             {"converged"})  # fmt: skip
        general = [ik.solve(model, t.tolist()) for t in targets]
        optioned = [ik.solve(model, t, tol=1e-10) for t in targets]
        batch = ik.solve_many(model, targets)
        assert _bits(quick) == _bits(general) == _bits(optioned) == _bits(batch)
        q0 = model.random_q(len(targets), seed=9)  # a given start: the same through both paths
        warm = [ik.solve(model, t, q) for t, q in zip(targets, q0)]
        assert ["_lazy" in vars(r) for r in warm] == [r.converged for r in warm]
        given = [ik.solve(model, t, q, tol=1e-10) for t, q in zip(targets, q0)]
        assert _bits(warm) == _bits(given) == _bits(ik.solve_many(model, targets, q0))
        with pytest.raises(ConfigurationError, match="q0"):
            ik.solve(model, targets[1], q0[0][:2])
        r = ik.solve(model, targets[1])
        for f in fields(ik.IKResult):
            a, b = getattr(r, f.name), getattr(general[1], f.name)
            assert type(a) is type(b) and (np.array_equal(a, b) if f.name != "task" else
                                            a.to_dict() == b.to_dict())  # fmt: skip
        assert list(vars(r)) == [f.name for f in fields(ik.IKResult)]
        assert not r.q.flags.writeable and not r.task.pose.flags.writeable
        for fresh in (pickle.loads(pickle.dumps(ik.solve(model, targets[1]))),
                      copy.copy(ik.solve(model, targets[1]))):  # fmt: skip
            assert _bits([fresh]) == _bits([r]) and "_lazy" not in vars(fresh)
        with pytest.raises(AttributeError, match="no_such_field"):
            ik.solve(model, targets[1]).no_such_field  # noqa: B018
        with pytest.raises(AttributeError):
            ik.solve(model, targets[1]).q = np.zeros(model.nq)
        assert solver._quick(model, targets[1].astype(np.float32)) is None
