"""Resolved-rate motion, the seed experiment, schedules (seed 002 Table I) and foot steps."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

import hexapod_kin as hk
from hexapod_kin import gait, motion, robots, seeds
from hexapod_kin._numerics import dls_step3
from hexapod_kin.cli import main
from hexapod_kin.exceptions import ConfigurationError, ParameterError
from hexapod_kin.motion._law import _sigma3
from hexapod_kin.params import JointLimits

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.fixture(scope="module")
def leg():
    return hk.load("hexabot_leg")


@pytest.fixture(scope="module")
def seed_run(leg):
    return seeds.seed_experiment(leg)


# ------------------------------------------------------------------ the seeds' experiment
def test_seed_experiment_drift(seed_run):
    assert seed_run.drift_y <= 1e-9
    assert seed_run.drift_z <= 1e-9
    assert seed_run.error_x <= 1e-9
    tr = seed_run.trajectory
    assert tr.t.size == 10_001 and tr.t[-1] == pytest.approx(10.0)
    # the seeds' plain Euler + np.linalg.solve drifts by orders of magnitude more
    assert seed_run.baseline["drift_z"] > 1e-6
    assert seed_run.baseline["drift_z"] > 1e4 * max(seed_run.drift_z, 1e-15)


def test_trajectory_is_consistent_with_pinocchio(seed_run, leg):
    tr = seed_run.trajectory
    idx = np.arange(0, tr.t.size, 997)
    for i in idx:
        np.testing.assert_allclose(tr.foot[i], leg.position(tr.q[i]), atol=1e-15)
        jac = leg.position_jacobian(tr.q[i])
        np.testing.assert_allclose(tr.foot_velocity[i], jac @ tr.qdot[i], atol=1e-15)
        sv = np.linalg.svd(jac, compute_uv=False)
        assert tr.sigma_min[i] == pytest.approx(sv[-1], rel=1e-9)
        assert tr.condition[i] == pytest.approx(sv[0] / sv[-1], rel=1e-8)
    # commanded vs actual foot velocity
    np.testing.assert_allclose(tr.foot_velocity, tr.command, atol=1e-9)
    # qdot is the time derivative of q (central differences)
    fd = (tr.q[2:] - tr.q[:-2]) / (2 * tr.dt)
    np.testing.assert_allclose(fd, tr.qdot[1:-1], atol=1e-5)
    assert not tr.q.flags.writeable


def test_rk4_is_fourth_order_and_euler_first_order(leg):
    def v(t):
        t = np.asarray(t, float)
        out = np.zeros(t.shape + (3,))
        out[..., 0] = 0.05 * np.sin(np.pi * t)
        out[..., 2] = 0.02 * np.cos(np.pi * t)
        return out

    errs = {}
    for method in ("euler", "rk4"):
        for dt in (0.02, 0.01):
            tr = motion.resolved_rate(leg, v, motion.SEED_Q0, dt, 2.0, method=method)
            errs[method, dt] = np.max(tr.tracking_error)
    assert 1.7 < errs["euler", 0.02] / errs["euler", 0.01] < 2.3
    assert errs["rk4", 0.02] / errs["rk4", 0.01] > 12  # ~16 for fourth order


def test_closed_loop_recovers_from_an_offset_start(leg):
    # reference starts 1 mm away from the foot: the closed loop pulls it in (e ~ exp(-K t))
    p0 = leg.position(motion.SEED_Q0) + np.array([0.0, 0.0, 1e-3])
    tr = motion.resolved_rate(
        leg,
        np.zeros(3),
        motion.SEED_Q0,
        1e-3,
        1.0,
        gain=20.0,
        path=lambda t: np.broadcast_to(p0, np.shape(t) + (3,)),
    )
    assert tr.tracking_error[0] == pytest.approx(1e-3, rel=1e-9)
    assert tr.tracking_error[-1] < 1e-3 * np.exp(-20.0 * 1.0) * 1.5


# ------------------------------------------------------------------ into a singularity
def test_stretching_outward_no_nan_within_speed_limits():
    lim = tuple(JointLimits(-np.pi, np.pi, velocity=2.0) for _ in range(3))
    model = hk.load(robots.hexabot_leg(limits=lim))
    tr = motion.resolved_rate(model, [0.05, 0.0, 0.0], motion.SEED_Q0, 1e-3, 3.0)
    assert np.all(np.isfinite(tr.q)) and np.all(np.isfinite(tr.qdot))
    assert np.all(np.abs(tr.qdot) <= 2.0 + 1e-12)
    reach = np.linalg.norm(tr.foot - [0, 0, 0], axis=1)
    assert np.all(reach <= 0.25 + 1e-12)
    ca = tr.closest_approach
    assert ca.sigma_min < 1e-3  # it got (close to) the stretched singularity
    assert ca.sigma_min == pytest.approx(float(tr.sigma_min.min()))
    assert ca.to_dict()["t"] == tr.t[ca.index]
    assert tr.damping.max() > 0  # the damping switched on


def test_joint_position_limits_hold(leg):
    lim = (JointLimits(-1, 1), JointLimits(0.2, 0.5), JointLimits(0.5, 1.5))
    model = hk.load(robots.hexabot_leg(limits=lim))
    tr = motion.resolved_rate(model, [0.0, 0.0, 0.05], motion.SEED_Q0, 1e-3, 2.0)
    assert np.all(tr.q >= model.lower) and np.all(tr.q <= model.upper)
    assert tr.limited.any()


def test_argument_errors(leg):
    with pytest.raises(ParameterError):
        motion.resolved_rate(leg, [0, 0, 0], motion.SEED_Q0, 0.0, 1.0)
    with pytest.raises(ParameterError):
        motion.resolved_rate(leg, [0, 0, 0], motion.SEED_Q0, 1e-3, 1.0, method="midpoint")
    with pytest.raises(ConfigurationError):
        motion.resolved_rate(leg, [0, 0], motion.SEED_Q0, 1e-3, 1.0)
    with pytest.raises(ConfigurationError):
        motion.resolved_rate(leg, [np.nan, 0, 0], motion.SEED_Q0, 1e-3, 1.0)


# ------------------------------------------------------------------ 6-D twists (UR5)
@pytest.fixture(scope="module")
def ur5():
    return hk.load("erd:ur5_robot", tip="tool0")


def _exact(pose0, twist, t, frame):
    """Independent of motion: Pinocchio's exp maps of the constant twist."""
    import pinocchio as pin

    T0 = pin.SE3(pose0)
    out = []
    for tk in t:
        if frame == "tip":
            out.append((T0 * pin.exp6(pin.Motion(np.asarray(twist) * tk))).homogeneous)
        else:
            m = np.eye(4)
            m[:3, :3] = pin.exp3(np.asarray(twist[3:]) * tk) @ T0.rotation
            m[:3, 3] = T0.translation + np.asarray(twist[:3]) * tk
            out.append(m)
    return np.array(out)


@pytest.mark.parametrize("frame", ["base", "tip"])
@pytest.mark.parametrize("gain", [0.0, 10.0])
def test_constant_twist_for_one_second_on_ur5(ur5, frame, gain):
    import pinocchio as pin

    twist = np.array([0.05, -0.03, 0.02, 0.2, -0.1, 0.3])
    q0 = np.array([0.8, -1.2, 1.5, -0.3, 1.1, -1.5])
    tr = motion.resolved_rate(ur5, twist, q0, 1e-3, 1.0, frame=frame, gain=gain)
    assert not tr.limited.any()
    exact = _exact(ur5.fk(q0), twist, tr.t, frame)
    reached = np.array([ur5.fk(q) for q in tr.q])  # Pinocchio FK of the joint trajectory
    drift_p = np.max(np.linalg.norm(reached[:, :3, 3] - exact[:, :3, 3], axis=1))
    drift_r = max(np.linalg.norm(pin.log3(e[:3, :3] @ r[:3, :3].T)) for e, r in zip(exact, reached))
    assert drift_p <= 1e-9 and drift_r <= 1e-9
    # the reported tip pose and velocity agree with Pinocchio
    i = 500
    np.testing.assert_allclose(tr.poses[i], reached[i], atol=1e-13)
    jac = ur5.jacobian(tr.q[i], "local" if frame == "tip" else "local_world_aligned")
    np.testing.assert_allclose(jac @ tr.qdot[i], twist, atol=1e-9 if gain == 0 else 1e-6)
    sv = np.linalg.svd(ur5.jacobian(tr.q[i]), compute_uv=False)
    assert tr.sigma_min[i] == pytest.approx(sv[-1], rel=1e-6)
    assert tr.rotation_error.max() <= 1e-9


def test_pose_path_is_the_se3_geodesic_and_is_followed(ur5):
    import pinocchio as pin

    qa, qb = np.array([0.2, -1.0, 1.2, -0.4, 1.0, 0.1]), np.array([0.7, -1.3, 1.6, -0.2, 1.3, 0.9])
    A, B = ur5.fk(qa), ur5.fk(qb)
    path = motion.PosePath([0.0, 0.5], [A, B])
    np.testing.assert_allclose(path.sample(0.0), A, atol=1e-15)
    np.testing.assert_allclose(path.sample(0.5), B, atol=1e-12)
    mid = path.sample(0.25)
    half = np.linalg.solve(A, mid)  # A⁻¹ M: its square is A⁻¹ B (geodesic midpoint)
    np.testing.assert_allclose(half @ half, np.linalg.solve(A, B), atol=1e-12)
    # the twist is the derivative of the path (central differences)
    h = 1e-6
    d = pin.log6(pin.SE3(path.sample(0.2 - h)).actInv(pin.SE3(path.sample(0.2 + h)))).vector
    np.testing.assert_allclose(d / (2 * h), path.twist(0.2), atol=1e-6)
    tr = motion.follow_pose_path(ur5, path, qa, dt=1e-3, gain=20.0)
    assert tr.frame == "tip"
    assert np.max(tr.tracking_error) <= 1e-9 and np.max(tr.rotation_error) <= 1e-9
    np.testing.assert_allclose(ur5.fk(tr.q[-1]), B, atol=1e-9)
    with pytest.raises(ParameterError):
        motion.PosePath([0.0, 0.0], [A, B])


def test_twist_argument_errors(ur5):
    with pytest.raises(ParameterError, match="frame"):
        motion.resolved_rate(ur5, np.zeros(6), None, 1e-3, 0.01, frame="world")
    with pytest.raises(ConfigurationError, match="5 values"):
        motion.resolved_rate(ur5, np.zeros(5), None, 1e-3, 0.01)


# ------------------------------------------------------------------ seed 002 Table I
def test_table_i_replayed_through_fk_and_ik():
    sched = seeds.seed002_schedule()
    model = hk.load("coxa_tibia_leg")
    t = np.arange(0.0, 22.0 + 1e-9, 0.01)
    q_plan = sched.sample(t)
    np.testing.assert_allclose(
        np.degrees(sched.sample([0, 4.5, 9, 13, 17.5, 25])),
        [[0, -90], [0, -70], [10, -50], [20, -50], [10, -70], [0, -90]],
        atol=1e-12,
    )
    feet = np.array([model.position(q) for q in q_plan])
    back = motion.track(model, feet, q_plan[0])
    assert back.reached.all()
    np.testing.assert_allclose(back.q, q_plan, atol=1e-9)


# ------------------------------------------------------------------ foot steps
def test_foot_path_shape():
    c = np.array([0.15, 0.0, -0.12])
    kw = dict(center=c, length=0.04, height=0.03, duty_factor=0.6)
    np.testing.assert_allclose(gait.foot_path(0.0, **kw), c + [0.02, 0, 0], atol=1e-15)
    np.testing.assert_allclose(gait.foot_path(0.6, **kw), c - [0.02, 0, 0], atol=1e-15)
    np.testing.assert_allclose(gait.foot_path(0.8, **kw), c + [0, 0, 0.03], atol=1e-15)
    ph = np.linspace(0, 1, 2001)
    for shape in ("ellipse", "cycloid"):
        p = gait.foot_path(ph, shape=shape, **kw)
        assert np.max(np.abs(np.diff(p, axis=0))) < 1e-3  # continuous
        stance = ph < 0.6
        np.testing.assert_allclose(p[stance, 2], c[2])
        assert np.all(np.diff(p[stance, 0]) < 0)  # straight line, front to back
        assert np.all(p[~stance, 2] >= c[2] - 1e-15)
    with pytest.raises(ParameterError):
        gait.foot_path(0.1, center=c, length=0.04, height=0.03, duty_factor=1.0)


@pytest.mark.parametrize("preset", ["hexabot_leg", "erd:solo12"])
def test_foot_step_joint_trajectory(preset):
    model = hk.load(preset, tip="FL_FOOT") if preset.startswith("erd") else hk.load(preset)
    step = gait.foot_step(
        model, length=0.04, height=0.02, duration=1.0, duty_factor=0.5, dt=0.005, cycles=2
    )
    assert step.reached.all()
    assert step.max_error < 1e-9
    assert step.within_limits
    assert step.max_joint_step < 0.05  # continuous joint trajectories
    assert np.all(np.isfinite(step.qdot))


# ------------------------------------------------------------------ command line and pictures
def test_cli_step_json(capsys):
    assert main(["step", "hexabot_leg", "--json", "--duration", "2", "--no-baseline"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["drift_y"] <= 1e-9 and out["drift_z"] <= 1e-9 and out["error_x"] <= 1e-9


def test_cli_ik_pose_mask_tool_and_step_twist(capsys):
    import pinocchio as pin

    ur5 = hk.load("erd:ur5_robot", tip="tool0")
    pose = ur5.fk(np.array([0.3, -1.1, 1.3, -0.5, 1.2, 0.4]))
    rpy = pin.rpy.matrixToRpy(pose[:3, :3])
    xyz_rpy = [*map(str, pose[:3, 3]), *map(str, np.degrees(rpy))]
    args = ["ik", "erd:ur5_robot", "--tip", "tool0", "--pose", *xyz_rpy, "--deg", "--json"]
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["numerical"]["status"] == "converged"
    q = np.array(out["numerical"]["q"])
    assert np.max(np.abs(ur5.fk(q) - pose)) <= 1e-9
    # a tool 0.1 m along z: the tool frame reaches the pose
    assert main(args + ["--tool", "0", "0", "0.1", "0", "0", "0"]) == 0
    out = json.loads(capsys.readouterr().out)
    tooled = hk.load("erd:ur5_robot", tip="tool0", tool=((0, 0, 0.1), (0, 0, 0)))
    np.testing.assert_allclose(tooled.fk(np.array(out["numerical"]["q"])), pose, atol=1e-9)
    assert main(args + ["--mask", "1", "1", "1", "0", "0", "0"]) == 0
    assert json.loads(capsys.readouterr().out)["numerical"]["error"] <= 1e-9
    # step: a constant twist, checked against the exact motion
    argv = "step erd:ur5_robot --tip tool0 --twist 0.02 0 0 0 0 30 --deg --frame tip"
    assert main([*argv.split(), "--duration", "0.5", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["position_drift"] <= 1e-9 and out["rotation_drift"] <= 1e-9
    assert out["velocity"][5] == pytest.approx(np.radians(30.0))
    # --deg converts revolute joints only: the SCARA's prismatic joint stays in metres
    argv = "step scara --velocity 0 0 0 --q 10 20 30 0.1 --deg --duration 0.01 --json"
    assert main(argv.split()) == 0
    q0 = json.loads(capsys.readouterr().out)["q0"]
    np.testing.assert_allclose(q0, [*np.radians([10, 20, 30]), 0.1], atol=1e-15)


def test_cli_ik(capsys):
    assert main(["ik", "hexabot_leg", "--target", "0.15", "0.02", "-0.1", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["family"] == "leg3" and out["numerical"]["status"] == "converged"
    assert len(out["analytic"]) == 2
    # unreachable: answered (the nearest point is printed), not achieved: exit status 1
    assert main(["ik", "hexabot_leg", "--target", "1", "0", "0"]) == 1
    assert "unreachable" in capsys.readouterr().out


def test_plots_and_html(tmp_path, leg, drawn):
    """The figures draw the run: the plotted foot is FK of the plotted joints; the page's data."""
    import re

    import matplotlib.image as mpimg

    from hexapod_kin.plots import plot_motion, plot_step

    run = seeds.seed_experiment(leg, duration=1.0)
    png = plot_motion(run, tmp_path / "run.png")
    feet, _, joints, _ = drawn[-1].axes[:4]
    q = np.column_stack([line.get_ydata() for line in joints.lines[:3]])
    foot = np.column_stack([line.get_ydata() for line in feet.lines[:3]])
    assert len(q) == len(run.trajectory.t)  # 1,001 samples: drawn unthinned
    np.testing.assert_allclose(foot, [leg.position(qi) for qi in q], atol=1e-12)
    np.testing.assert_allclose(feet.lines[0].get_xdata(), run.trajectory.t)
    img = mpimg.imread(png)[..., :3]
    assert img.shape[1] > 1000 and np.count_nonzero(img.std(axis=-1) > 0.1) > 2000  # colour
    step = gait.foot_step(leg, dt=0.01)
    plot_step(step, tmp_path / "step.png")
    planned = drawn[-1].axes[0].lines[0]
    np.testing.assert_allclose(planned.get_xdata(), np.asarray(step.foot)[:, 0])
    np.testing.assert_allclose(planned.get_ydata(), np.asarray(step.foot)[:, 2])
    html = tmp_path / "step.html"
    argv = ["step", "hexabot_leg", "--duration", "1", "--no-baseline"]
    assert main([*argv, "--html", str(html), "--plot", str(tmp_path / "cli.png")]) == 0
    data = json.loads(re.search(r"var DATA = (\{.*?\});\n", html.read_text()).group(1))
    assert data["animation"] is True and data["duration"] == pytest.approx(1.0, abs=0.05)
    assert "hexabot_leg" in data["title"] or "step" in data["title"]
    assert len(drawn) == 3 and drawn[-1].axes  # the CLI's figure went through the same writer


def test_default_stance_is_far_from_singularities_for_any_chain():
    # The SCARA's default start must let the seed experiment run cleanly (its IK home is
    # 5 mm from the workspace boundary, where the arm stretches and x motion is impossible).
    scara = hk.load("scara")
    q0 = motion.default_stance(scara)
    assert np.all(q0 >= scara.lower) and np.all(q0 <= scara.upper)
    # closed form: the planar block's determinant is d2*d3*sin(theta2)
    assert abs(0.22 * 0.24 * np.sin(q0[1])) > 0.5 * 0.22 * 0.24
    run = seeds.seed_experiment(scara, duration=4.0, baseline=False)
    assert run.drift_y <= 1e-9 and run.drift_z <= 1e-9 and run.error_x <= 1e-9
    np.testing.assert_array_equal(motion.default_stance(hk.load("hexabot_leg")), motion.SEED_Q0)


def test_twist_through_a_wrist_singularity_stays_finite(ur5):
    # UR5's wrist is singular at wrist_2 = 0: drive wrist_2 through it with an angular twist
    q0 = np.array([0.3, -1.2, 1.4, -0.5, 0.15, 0.2])
    axis = ur5.jacobian(q0)[3:, 4]  # the wrist_2 axis (base frame)
    twist = np.concatenate([np.zeros(3), -0.3 * axis / np.linalg.norm(axis)])
    tr = motion.resolved_rate(ur5, twist, q0, 1e-3, 1.0)
    assert np.all(np.isfinite(tr.q)) and np.all(np.isfinite(tr.qdot))
    assert tr.damping.max() > 0  # the damping switched on near the singularity
    i = int(np.argmin(tr.sigma_min))
    sv = np.linalg.svd(ur5.jacobian(tr.q[i]), compute_uv=False)
    assert tr.sigma_min[i] == pytest.approx(sv[-1], rel=1e-6, abs=1e-9)
    assert tr.sigma_min[i] < 0.02 * sv[0]


# ------------------------------------------------------------ the law vs independent references
def test_closed_forms_of_the_3x3_law_match_numpy():
    rng = np.random.default_rng(7)
    for k in range(300):
        jac = rng.normal(size=(3, 3))
        if k % 3 == 1:  # nearly singular: one row almost a combination of the others
            jac[2] = jac[0] + 0.5 * jac[1] + 10.0 ** -rng.uniform(3, 12) * rng.normal(size=3)
        sv = np.linalg.svd(jac, compute_uv=False)
        smin, smax = _sigma3(jac.tolist())
        assert smax == pytest.approx(sv[0], rel=1e-12)
        assert smin == pytest.approx(sv[-1], rel=1e-6, abs=1e-15 * sv[0])
        x, lam2 = rng.normal(size=3), 10.0 ** -rng.uniform(2, 14)
        u, s, vt = np.linalg.svd(jac)
        ref = vt.T @ (s / (s * s + lam2) * (u.T @ x))  # the DLS solution by the SVD
        cond = (s[0] ** 2 + lam2) / (s[-1] ** 2 + lam2)  # of the Cholesky's matrix
        got = np.array(dls_step3(jac.tolist(), x.tolist(), lam2))
        assert np.abs(got - ref).max() <= 1e-14 * cond * np.abs(ref).max()
    assert _sigma3([[0.0] * 3] * 3) == (0.0, 0.0)


def _commanded(model, tr, rows=3):
    """Pinocchio's own Jacobian at every sample times the recorded q̇ (base axes)."""
    return np.array([model.jacobian(q)[:rows] @ qd for q, qd in zip(tr.q, tr.qdot)])


@pytest.mark.parametrize(
    ("source", "kw", "velocity"),
    [
        ("hexabot_leg", {}, [0.02, -0.01, 0.01]),
        ("scara", {}, [0.01, 0.02, -0.02]),  # a prismatic joint
        (str(EXAMPLES / "leg4.toml"), {}, [0.02, 0.0, 0.01]),  # 3 rows, 4 joints
        ("hexapod", {"tip": "leg3_foot"}, [0.01, 0.01, 0.0]),  # a leg on the body
    ],
)
def test_pinocchio_jacobian_times_qdot_returns_the_command(source, kw, velocity):
    model = hk.load(source, **kw)
    v = np.array(velocity)
    for method in ("rk4", "euler"):
        tr = motion.resolved_rate(model, v, None, 2e-3, 0.4, method=method)
        assert not tr.limited.any()
        assert np.abs(_commanded(model, tr) - v).max() < 1e-9
        # the foot is Pinocchio's FK of q and moved by v t
        np.testing.assert_allclose(tr.foot[-1], model.position(tr.q[-1]), atol=1e-15)
        drift = np.abs(tr.foot - tr.foot[0] - np.outer(tr.t, v)).max()
        assert drift < (1e-9 if method == "rk4" else 1e-5)  # 4th / 1st order, open loop
        sv = np.linalg.svd(model.jacobian(tr.q[50])[:3], compute_uv=False)
        assert tr.sigma_min[50] == pytest.approx(sv[min(model.nq, 3) - 1], rel=1e-9)
        assert tr.sigma_max[50] == pytest.approx(sv[0], rel=1e-12)


def test_panda_twist_six_rows_seven_joints():
    panda = hk.load("erd:panda")
    twist = np.array([0.02, 0.0, 0.01, 0.1, 0.0, 0.1])
    tr = motion.resolved_rate(panda, twist, None, 5e-3, 0.5)
    exact = _exact(panda.fk(tr.q[0]), twist, tr.t, "base")
    reached = np.array([panda.fk(q) for q in tr.q])
    assert np.abs(reached[:, :3, 3] - exact[:, :3, 3]).max() < 1e-9
    assert np.abs(_commanded(panda, tr, 6) - twist).max() < 1e-9
    sv = np.linalg.svd(panda.jacobian(tr.q[40]), compute_uv=False)
    assert tr.sigma_min[40] == pytest.approx(sv[-1], rel=1e-9)


def test_a_leg_pushed_out_of_reach_is_damped_then_held_by_its_limits(leg):
    # [0.3, 0, 0] m/s for 1 s leaves the workspace: damping near the boundary, never a NaN
    tr = motion.resolved_rate(leg, [0.3, 0.0, 0.0], motion.SEED_Q0, 2e-3, 1.0)
    assert np.all(np.isfinite(tr.q)) and np.all(np.isfinite(tr.qdot))
    assert np.all(tr.q >= leg.lower) and np.all(tr.q <= leg.upper)
    assert tr.damping.max() > 0 and tr.sigma_min.min() < 1e-2 * tr.sigma_max[0]
    # the damping law from σ_min by SVD of Pinocchio's Jacobian at each recorded q, and
    # ε = 1 % of σ_max at q0
    sv = np.linalg.svd(np.array([leg.position_jacobian(q) for q in tr.q]), compute_uv=False)
    eps = 0.01 * sv[0, 0]
    np.testing.assert_allclose(tr.sigma_min, sv[:, -1], rtol=1e-9, atol=1e-15)
    law = np.where(sv[:, -1] < eps, eps**2 * (1 - (sv[:, -1] / eps) ** 2), 0.0)
    np.testing.assert_allclose(tr.damping, law, rtol=1e-9, atol=1e-18)


def test_narrow_limits_freeze_the_joint_pushed_outward():
    base = robots.get("hexabot_leg")
    narrow = dataclasses.replace(
        base, limits=tuple(dataclasses.replace(lim, lower=-0.2, upper=1.3) for lim in base.limits)
    )
    model = hk.load(narrow)
    for v in ([-0.05, 0.0, 0.0], [0.0, 0.0, 0.05]):
        tr = motion.resolved_rate(model, v, motion.SEED_Q0, 2e-3, 1.0)
        assert tr.limited.any()
        assert np.all(tr.q >= model.lower) and np.all(tr.q <= model.upper)
        at_low, at_high = tr.q <= model.lower, tr.q >= model.upper
        assert at_low.any() or at_high.any()
        # a joint at a limit never moves outward (the freeze rule)
        assert np.all(tr.qdot[at_low] >= 0.0) and np.all(tr.qdot[at_high] <= 0.0)


def test_a_singular_start_is_damped_never_divided_by_zero(leg):
    q0 = np.zeros(3)  # the straight leg: a singular position Jacobian
    tr = motion.resolved_rate(leg, [0.0, 0.0, 0.02], q0, 2e-3, 0.3)
    assert np.all(np.isfinite(tr.q)) and np.all(np.isfinite(tr.qdot))
    sv = np.linalg.svd(leg.position_jacobian(q0), compute_uv=False)
    assert tr.sigma_min[0] < 1e-12 * sv[0]
    assert tr.damping[0] == pytest.approx((0.01 * sv[0]) ** 2, rel=1e-9)  # λ²_max = ε²


def test_one_joint_and_more_rows_than_joints():
    # one joint (3 rows, n = 1): the best fit moves the pendulum's tip along its circle
    pend = hk.load("pendulum")
    tr = motion.resolved_rate(pend, [0.0, 0.0, 0.01], [-1.5], 1e-3, 0.2)
    jac = pend.position_jacobian(tr.q[0])[:, 0]
    assert tr.qdot[0, 0] == pytest.approx(jac @ [0.0, 0.0, 0.01] / (jac @ jac), rel=1e-9)
    assert tr.sigma_min[0] == pytest.approx(np.linalg.norm(jac), rel=1e-12)
    # a 6-D twist on a 3-joint leg: the damped least-squares fit, finite, FK-consistent
    leg = hk.load("hexabot_leg")
    twist = [0.01, 0, 0, 0, 0, 0.1]
    tr = motion.resolved_rate(leg, twist, motion.SEED_Q0, 1e-3, 0.2, frame="tip", gain=5.0)
    assert np.isfinite(tr.q).all()
    np.testing.assert_allclose(tr.poses[-1], leg.fk(tr.q[-1]), atol=1e-15)


def test_a_continuous_joint_passes_pi_without_a_limit():
    model = hk.load("erd:double_pendulum_continuous")
    q0 = np.array([3.0, 0.8])
    v = model.jacobian(q0)[:3] @ np.array([0.5, 0.0])
    tr = motion.resolved_rate(model, v, q0, 1e-3, 0.5)
    assert tr.q[-1, 0] > np.pi and not tr.limited.any()
    np.testing.assert_allclose(tr.foot, [model.position(q) for q in tr.q], atol=1e-15)


def test_the_same_bits_again_and_from_another_thread(leg):
    def run():
        return motion.resolved_rate(leg, [0.02, 0.0, 0.01], motion.SEED_Q0, 2e-3, 0.2, gain=5.0)

    a, b = run(), run()
    out = []
    th = threading.Thread(target=lambda: out.append(run()))
    th.start()
    th.join()
    for other in (b, out[0]):
        for name in ("q", "qdot", "foot", "rotation", "sigma_min", "damping"):
            assert getattr(a, name).tobytes() == getattr(other, name).tobytes(), name


def test_the_step_command_never_imports_numba():
    code = (
        "import sys; from hexapod_kin.cli import main; "
        "main(['step', 'hexabot_leg', '--duration', '0.2']); "
        "print('numba' in sys.modules)"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr[-2000:]
    assert res.stdout.strip().splitlines()[-1] == "False"


def test_cli_step_velocity_plot_draws_the_run(tmp_path, capsys, monkeypatch):
    """``step --velocity --plot`` writes the figure; its curves against raw Pinocchio."""
    import pinocchio as pin

    from hexapod_kin import plots

    drawn: list = []
    real = plots.save_figure

    def keep(fig, path, **kw):
        drawn.append(
            [[(ln.get_xdata(), ln.get_ydata()) for ln in ax.get_lines()] for ax in fig.axes]
        )
        return real(fig, path, **kw)

    monkeypatch.setattr(plots, "save_figure", keep)
    png = tmp_path / "v.png"
    v = np.array([0.01, 0.005, 0.0])
    argv = ["step", "hexabot_leg", "--velocity", *map(str, v), "--duration", "0.5"]
    assert main([*argv, "--plot", str(png), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["written"] == [str(png)] and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    qs, rates, sigma, drift = drawn[0]
    q = np.array([y for _, y in qs]).T
    assert q.shape == (501, 3) and len(rates) == 3
    np.testing.assert_allclose(q[0], out["q0"], atol=0)
    np.testing.assert_allclose(q[-1], out["q_end"], atol=0)
    leg = hk.load("hexabot_leg")
    model, data = leg.model, leg.model.createData()
    feet, sig = [], []
    for qi in q:
        jac = pin.computeFrameJacobian(model, data, qi, leg.tip_id, pin.LOCAL_WORLD_ALIGNED)[:3]
        pin.framesForwardKinematics(model, data, qi)
        feet.append(data.oMf[leg.tip_id].translation.copy())
        sig.append(np.linalg.svd(jac, compute_uv=False)[-1])
    t = drift[0][0]
    feet = np.array(feet)
    exact = feet[0] + t[:, None] * v  # a straight line at constant speed
    np.testing.assert_allclose(drift[0][1], np.maximum(np.linalg.norm(feet - exact, axis=1), 1e-18),
                               atol=1e-12)  # fmt: skip
    assert max(drift[0][1]) == pytest.approx(out["position_drift"], abs=1e-15)
    np.testing.assert_allclose(sigma[0][1], sig, rtol=1e-9)
