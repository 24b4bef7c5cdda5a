"""Dynamics against exact physics: the seed pendulum, leg torques, the standing hexapod.

References are independent of the code under test: the pendulum's I, m, l_c by hand (Steiner)
from the preset's inertials and the exact period with scipy's ellipk; a scipy ODE solver on the
scalar pendulum equation; finite differences of positions and potential energy; a hand
computation of the standing knee torque; a free-flyer Pinocchio model built here from the URDF
text (its base wrench must vanish under the contact forces).
"""

from __future__ import annotations

import json
import math
import warnings
from types import SimpleNamespace

import numpy as np
import pinocchio as pin
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ellipk

import hexapod_kin as hk
from hexapod_kin import robots
from hexapod_kin.cli import main
from hexapod_kin.dynamics import (
    check_inertials,
    contact_forces,
    leg_torques,
    pendulum_experiment,
    pendulum_run,
    physical_pendulum,
    simulate,
    stance_at,
    stand,
    standing_configuration,
)
from hexapod_kin.dynamics.pendulum import peaks
from hexapod_kin.exceptions import ConfigurationError, HexapodKinError, ParameterError
from hexapod_kin.seeds import step_torques

G = 9.81


# ============================================================================ the pendulum
def hand_pendulum(length: float = 0.5, mass: float = 1.0) -> tuple[float, float, float]:
    """I about the pivot, total mass, pivot→CoM distance, from the preset's inertials (Steiner).

    Frame 1 (the rod's) has z1 = the joint axis and the rod along x1; the bob's frame is frame 1
    moved by d = length along x1 (its row: alpha = 0, theta = 0).
    """
    chain = robots.pendulum(length=length, mass=mass)
    rod, bob = chain.inertials
    bob_offset = np.array([chain.rows[1].d, 0.0, 0.0])
    inertia, m_tot, moment = 0.0, 0.0, np.zeros(3)
    for inertial, origin in ((rod, np.zeros(3)), (bob, bob_offset)):
        c = origin + np.array(inertial.com)
        izz = inertial.inertia[2]
        inertia += izz + inertial.mass * (c[0] ** 2 + c[1] ** 2)
        m_tot += inertial.mass
        moment += inertial.mass * c
    return inertia, m_tot, float(np.hypot(moment[0], moment[1]) / m_tot)


def exact_period_by_hand(theta0: float) -> float:
    i, m, lc = hand_pendulum()
    return 4 * math.sqrt(i / (m * G * lc)) * float(ellipk(math.sin(theta0 / 2) ** 2))


def test_pendulum_geometry_and_mass_properties_match_hand_values() -> None:
    model = hk.load("pendulum")
    p = physical_pendulum(model)
    i, m, lc = hand_pendulum()
    assert p.inertia == pytest.approx(i, rel=1e-12)
    assert p.mass == pytest.approx(m, rel=1e-12)
    assert p.com_distance == pytest.approx(lc, rel=1e-12)
    # the hanging equilibrium puts the bob straight below the pivot (gravity -z)
    tip = model.position([p.q_hanging])
    assert tip == pytest.approx([0.0, 0.0, -0.5], abs=1e-12)
    assert p.q_hanging == pytest.approx(-math.pi / 2, abs=1e-12)


@pytest.fixture(scope="module")
def seed_experiment_run() -> object:
    return pendulum_experiment(math.radians(30), 0.01, dt=1e-3, duration=20.0)


def test_undamped_energy_constant_and_period_exact(seed_experiment_run: object) -> None:
    run = seed_experiment_run.undamped  # type: ignore[attr-defined]
    assert run.damping == 0.0
    # energy above the hanging rest, by hand: m g l_c (1 - cos theta0)
    i, m, lc = hand_pendulum()
    e0 = m * G * lc * (1 - math.cos(math.radians(30)))
    assert run.energy[0] == pytest.approx(e0, rel=1e-12)
    drift = np.max(np.abs(run.energy - e0)) / e0
    assert drift < 1e-8
    assert run.energy_drift < 1e-8
    assert run.simulation.t[-1] == pytest.approx(20.0)
    exact = exact_period_by_hand(math.radians(30))
    assert abs(run.period - exact) / exact < 1e-6
    # the large-amplitude period is longer than the small-angle one by ~1.7 % at 30 deg
    assert run.period / (2 * math.pi * math.sqrt(i / (m * G * lc))) == pytest.approx(
        1.0174, abs=1e-3
    )


def test_damped_energy_decreases_monotonically(seed_experiment_run: object) -> None:
    run = seed_experiment_run.damped  # type: ignore[attr-defined]
    assert run.damping == 0.01
    assert np.all(np.diff(run.energy) < 0)
    # loss rate equals b * omega^2 (dE/dt = -b q'^2), checked by the trapezoid rule
    sim = run.simulation
    loss = -np.trapezoid(0.01 * run.omega**2, sim.t)
    assert run.energy[-1] - run.energy[0] == pytest.approx(loss, rel=1e-6)


def test_small_amplitude_decay_rate_is_b_over_2i(seed_experiment_run: object) -> None:
    small = seed_experiment_run.small  # type: ignore[attr-defined]
    i, _, _ = hand_pendulum()
    expected = 0.01 / (2 * i)
    assert small.theta0 == pytest.approx(math.radians(1.0))
    assert abs(small.decay_rate - expected) / expected < 1e-3


def test_ode_solution_matches_scipy_reference() -> None:
    """ABA + RK4 against scipy's DOP853 on I th'' + b th' + m g l_c sin th = 0."""
    i, m, lc = hand_pendulum()
    b = 0.05
    run = pendulum_run(hk.load("pendulum", damping=b), math.radians(40), dt=2e-3, duration=5.0)

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        return [y[1], (-b * y[1] - m * G * lc * math.sin(y[0])) / i]

    ref = solve_ivp(
        rhs,
        (0, 5.0),
        [math.radians(40), 0.0],
        method="DOP853",
        rtol=1e-12,
        atol=1e-14,
        t_eval=run.simulation.t,
    )
    assert np.max(np.abs(run.theta - ref.y[0])) < 1e-9
    assert np.max(np.abs(run.omega - ref.y[1])) < 1e-8


def test_integrator_orders() -> None:
    """RK4 error falls ~16x per halving of dt; semi-implicit Euler's energy error ~2x."""
    i, m, lc = hand_pendulum()
    model = hk.load("pendulum", damping=0.0)
    q0 = [-math.pi / 2 + math.radians(30)]

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        return [y[1], -m * G * lc * math.sin(y[0] + math.pi / 2) / i]

    ref = solve_ivp(rhs, (0, 2.0), [q0[0], 0.0], method="DOP853", rtol=1e-13, atol=1e-15)
    errs, e_err = [], []
    for dt in (0.04, 0.02, 0.01):
        sim = simulate(model, q0, dt=dt, duration=2.0)
        errs.append(abs(sim.q[-1, 0] - ref.y[0, -1]))
        eul = simulate(model, q0, dt=dt / 4, duration=2.0, method="symplectic_euler")
        e_err.append(np.max(np.abs(eul.total - eul.total[0])))
    assert errs[0] / errs[1] == pytest.approx(16, rel=0.25)
    assert errs[1] / errs[2] == pytest.approx(16, rel=0.25)
    assert e_err[0] / e_err[1] == pytest.approx(2, rel=0.15)
    assert e_err[1] / e_err[2] == pytest.approx(2, rel=0.15)


def test_spring_shortens_the_small_amplitude_period() -> None:
    i, m, lc = hand_pendulum()
    k = 3.0
    model = hk.load("pendulum", damping=0.0)
    qh = -math.pi / 2
    sim = simulate(model, [qh + math.radians(0.5)], dt=1e-3, duration=6.0, stiffness=k, q_rest=[qh])
    times, _ = peaks(sim.t, sim.q[:, 0] - qh, sim.v[:, 0], sim.a[:, 0])
    period = (times[-1] - times[0]) / (len(times) - 1)
    assert period == pytest.approx(2 * math.pi * math.sqrt(i / (m * G * lc + k)), rel=1e-4)
    # spring energy is in the potential: the total stays constant
    assert np.max(np.abs(sim.total - sim.total[0])) < 1e-9


def test_coulomb_friction_amplitude_drops_linearly() -> None:
    """Coulomb friction F: each half swing loses 2F/(m g l_c) of amplitude (small angles)."""
    i, m, lc = hand_pendulum()
    friction = 0.02
    model = hk.load("pendulum", damping=0.0)
    qh = -math.pi / 2
    sim = simulate(model, [qh + math.radians(5)], dt=1e-3, duration=6.0, friction=friction)
    _, values = peaks(sim.t, sim.q[:, 0] - qh, sim.v[:, 0], sim.a[:, 0])
    drops = -np.diff(values)
    assert len(drops) >= 3
    assert drops == pytest.approx(4 * friction / (m * G * lc), rel=5e-3)


def test_urdf_damping_and_friction_are_used_by_default() -> None:
    model = hk.load("pendulum", damping=0.3)
    sim = simulate(model, [-1.0], dt=1e-3, duration=0.01)
    assert sim.passive.damping.tolist() == [0.3]
    assert sim.passive.friction.tolist() == [0.0]
    # q'' = (-b q' - g(q)) / I at a state with velocity
    data = model.model.createData()
    v = np.array([2.0])
    q = np.array([-1.0])
    sim2 = simulate(model, q, v, dt=1e-3, duration=0.001)
    grav = pin.computeGeneralizedGravity(model.model, data, q)
    i, _, _ = hand_pendulum()
    assert sim2.a[0, 0] == pytest.approx((-0.3 * 2.0 - grav[0]) / i, rel=1e-12)


def test_pendulum_refuses_bad_input() -> None:
    with pytest.raises(ParameterError, match="theta0"):
        pendulum_run(theta0=math.pi)
    with pytest.raises(ParameterError, match="dt"):
        simulate(hk.load("pendulum"), [0.0], dt=0.0, duration=1.0)
    with pytest.raises(ParameterError, match="method"):
        simulate(hk.load("pendulum"), [0.0], method="euler")  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match="one revolute joint"):
        physical_pendulum(hk.load("hexabot_leg"))
    with pytest.raises(ParameterError, match="damping"):
        simulate(hk.load("pendulum"), [0.0], damping=-1.0)
    with pytest.raises(ConfigurationError):
        simulate(hk.load("pendulum"), [float("nan")])
    with pytest.raises(ParameterError, match="steps exceeds"):
        simulate(hk.load("pendulum"), [0.0], dt=1e-5, duration=1e3)


MASSLESS_URDF = """<?xml version="1.0"?>
<robot name="massless">
  <link name="base"/>
  <joint name="swing" type="revolute">
    <parent link="base"/><child link="arm"/>
    <axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="10" velocity="10"/>
  </joint>
  <link name="arm">
    <inertial><mass value="0"/><inertia ixx="0" iyy="0" izz="0" ixy="0" ixz="0" iyz="0"/>
    </inertial>
  </link>
</robot>
"""


def test_implausible_inertials_are_refused_naming_the_link() -> None:
    # a massless moving link: refused by the loader gate or else by dynamics, naming it
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            massless = hk.load(MASSLESS_URDF)
    except HexapodKinError as exc:
        assert "'arm'" in str(exc)
    else:
        with pytest.raises(HexapodKinError, match="'arm'"):
            simulate(massless, [0.1], duration=0.01)
        with pytest.raises(HexapodKinError, match="'arm'"):
            leg_torques(massless, [0.1])
    # models that reach dynamics another way are checked again, body by body
    good = hk.load("hexabot_leg")
    for bad, why in (
        (pin.Inertia.Zero(), "mass"),
        (pin.Inertia(0.1, np.zeros(3), np.diag([1e-4, 1e-4, 0.0])), "definite"),
    ):
        pm = pin.Model(good.model)
        pm.inertias[2] = bad
        fake = SimpleNamespace(model=pm, name="edited")
        with pytest.raises(ParameterError, match=f"'femur'.*{why}"):
            check_inertials(fake)
    check_inertials(good)
    check_inertials(hk.load("hexapod"))


# ============================================================================ leg torques
def rnea_with_foot_force(model: object, q: np.ndarray, frame: str, force: np.ndarray) -> np.ndarray:
    """RNEA, gravity off, q' = q'' = 0, the reaction -F (world) at the frame, built here."""
    pm = pin.Model(model.model)  # type: ignore[attr-defined]
    pm.gravity = pin.Motion.Zero()
    data = pm.createData()
    pin.framesForwardKinematics(pm, data, q)
    fid = pm.getFrameId(frame)
    joint = pm.frames[fid].parentJoint
    on_foot = pin.Force(-force, np.zeros(3))  # at the foot point, world axes
    world_at_foot = pin.SE3(np.eye(3), data.oMf[fid].translation)
    f_world_origin = world_at_foot.act(on_foot)  # the same force as a wrench at the origin
    fext = [pin.Force.Zero() for _ in range(pm.njoints)]
    fext[joint] = data.oMi[joint].actInv(f_world_origin)
    return np.array(pin.rnea(pm, data, q, np.zeros(pm.nv), np.zeros(pm.nv), fext))


@pytest.mark.parametrize(
    ("source", "kwargs", "frame"),
    [
        ("hexabot_leg", {}, None),
        ("hexabot_leg", {}, "femur"),
        ("erd:solo12", {"tip": "FL_FOOT"}, None),
        ("scara", {}, None),
    ],
)
def test_jt_f_equals_rnea_with_external_force(source: str, kwargs: dict, frame: str | None) -> None:
    model = hk.load(source, **kwargs)
    rng = np.random.default_rng(3)
    for _ in range(5):
        q = model.random_q(seed=int(rng.integers(1 << 30)))
        force = rng.normal(size=3) * 10
        r = leg_torques(model, q, force, frame=frame)
        ref = rnea_with_foot_force(model, q, r.frame, model.oMbase.rotation @ force)
        assert np.max(np.abs(r.force_torque - ref)) < 1e-9
        assert r.crosscheck_error < 1e-9
        # virtual work: tau_i = F . dp/dq_i, by central differences of the frame position
        h = 1e-6
        for j in range(model.nq):
            dq = np.zeros(model.nq)
            dq[j] = h
            dp = (
                model.placement(q + dq, r.frame)[:3, 3] - model.placement(q - dq, r.frame)[:3, 3]
            ) / (2 * h)
            assert r.force_torque[j] == pytest.approx(force @ dp, abs=1e-7)


def test_gravity_torque_is_gradient_of_potential() -> None:
    model = hk.load("hexabot_leg")
    data = model.model.createData()
    q = np.array([0.3, 0.4, -0.9])
    r = leg_torques(model, q)
    h = 1e-6
    for j in range(3):
        dq = np.zeros(3)
        dq[j] = h
        vp = pin.computePotentialEnergy(model.model, data, q + dq)
        vm = pin.computePotentialEnergy(model.model, data, q - dq)
        assert r.gravity[j] == pytest.approx((vp - vm) / (2 * h), abs=1e-8)
    assert r.total == pytest.approx(r.gravity + r.force_torque)


def leg_masses(chain: object) -> tuple[object, object, object, float, float]:
    """Femur, tibia and foot inertials of a hexabot_leg (the foot sits l3 from the ankle)."""
    femur, tibia, foot = (chain.link_inertial(j) for j in (1, 2, 3))  # type: ignore[attr-defined]
    return femur, tibia, foot, chain.rows[2].d, chain.rows[3].d  # type: ignore[attr-defined]


def test_gravity_torque_by_hand_for_a_horizontal_leg() -> None:
    """Leg straight out (q = 0): the knee holds femur, tibia and foot; the ankle the last two."""
    femur, tibia, foot, l2, l3 = leg_masses(robots.hexabot_leg())
    r = leg_torques(hk.load("hexabot_leg"), [0.0, 0.0, 0.0])
    ankle = G * (tibia.mass * tibia.com[0] + foot.mass * l3)
    knee = G * (femur.mass * femur.com[0]) + G * (tibia.mass + foot.mass) * l2 + ankle
    assert np.abs(r.gravity) == pytest.approx([0.0, knee, ankle], abs=1e-12)


def test_torques_along_the_resolved_rate_step() -> None:
    model = hk.load("hexabot_leg")
    force = np.array([0.0, 0.0, -5.0])
    st = step_torques(model, force, dt=2e-3, duration=2.0)
    assert st.crosscheck_error < 1e-9
    assert st.q.shape == (1001, 3)
    for k in (0, 500, 1000):
        jac = model.position_jacobian(st.q[k])
        assert st.force_torque[k] == pytest.approx(jac.T @ force, abs=1e-12)
    assert st.peak == pytest.approx(np.max(np.abs(st.total), axis=0))
    # slow motion: the inertial part is small against gravity + force
    assert np.max(np.abs(st.inertial)) < 0.01 * np.max(np.abs(st.total))
    with pytest.raises(ParameterError, match="3-joint"):
        step_torques(hk.load("pendulum"))


# ============================================================================ standing
def free_flyer(model: object) -> pin.Model:
    return pin.buildModelFromXML(model.urdf, pin.JointModelFreeFlyer())  # type: ignore[attr-defined]


def test_standing_forces_balance_and_match_a_floating_base_model() -> None:
    model = hk.load("hexapod")
    st = stand(model, height=0.1)
    params = model.params
    # mass by hand: body + every leg link
    mass = params.body_mass + sum(
        leg.chain.link_inertial(j).mass for leg in params.legs for j in range(len(leg.chain.rows))
    )
    assert st.mass == pytest.approx(mass, rel=1e-12)
    weight = mass * G
    # sum of forces = weight, moments about the CoM vanish
    assert np.abs(st.forces.sum(axis=0) - [0, 0, weight]).max() < 1e-9
    moments = np.cross(st.feet - st.com, st.forces).sum(axis=0)
    assert np.abs(moments).max() < 1e-9
    assert st.force_residual < 1e-9 and st.moment_residual < 1e-9
    assert np.abs(st.feet[:, 2]).max() < 1e-12  # feet on the ground
    # a floating-base model built here: mass, CoM, zero base wrench, same joint torques
    ff = free_flyer(model)
    data = ff.createData()
    qf = np.concatenate([[0, 0, 0.1, 0, 0, 0, 1], st.q])
    assert pin.computeTotalMass(ff) == pytest.approx(mass, rel=1e-12)
    assert np.array(pin.centerOfMass(ff, data, qf)) == pytest.approx(st.com, abs=1e-12)
    pin.framesForwardKinematics(ff, data, qf)
    fext = [pin.Force.Zero() for _ in range(ff.njoints)]
    for name, f in zip(params.foot_frames, st.forces):
        fid = ff.getFrameId(name)
        wrench = pin.SE3(np.eye(3), data.oMf[fid].translation).act(pin.Force(f, np.zeros(3)))
        j = ff.frames[fid].parentJoint
        fext[j] = fext[j] + data.oMi[j].actInv(wrench)
    tau = pin.rnea(ff, data, qf, np.zeros(ff.nv), np.zeros(ff.nv), fext)
    assert np.abs(tau[:6]).max() < 1e-9  # the contact forces hold the robot
    names = [ff.names[i] for i in range(2, ff.njoints)]
    assert names == list(st.joint_names)
    assert np.abs(tau[6:] - st.torque).max() < 1e-9


def test_standing_knee_torque_by_hand() -> None:
    """Default pose: femur horizontal, tibia vertical; equal vertical shares W/6."""
    model = hk.load("hexapod")
    st = stand(model, height=0.1)
    femur, tibia, foot, l2, _ = leg_masses(model.params.legs[0].chain)
    share = st.weight / 6
    assert st.forces == pytest.approx(np.tile([0, 0, share], (6, 1)), abs=1e-12)
    knee = share * l2 - G * (femur.mass * femur.com[0] + (tibia.mass + foot.mass) * l2)
    for i in range(6):
        assert st.torque[3 * i : 3 * i + 3] == pytest.approx([0.0, knee, 0.0], abs=1e-12)


def test_standing_pose_puts_feet_at_the_height() -> None:
    model = hk.load("hexapod")
    for height, reach in ((0.08, 0.14), (0.12, 0.16)):
        q = standing_configuration(model, height, reach, (0.01, -0.02))
        for name in model.params.foot_frames:
            assert model.placement(q, name)[2, 3] == pytest.approx(-height, abs=1e-9)
    with pytest.raises(ConfigurationError, match="cannot reach"):
        standing_configuration(model, 0.5)


def test_tripod_and_outside_support_polygon() -> None:
    model = hk.load("hexapod")
    st = stand(model, legs=[1, 3, 5], shift=(0.02, 0.0))
    assert st.stance_legs == ("leg1", "leg3", "leg5")
    assert np.abs(st.forces.sum(axis=0) - [0, 0, st.weight]).max() < 1e-9
    assert np.abs(np.cross(st.feet - st.com, st.forces).sum(axis=0)).max() < 1e-9
    assert st.feasible
    # legs 2, 3, 4 (left and rear): the CoM is outside their triangle -> a foot must pull
    far = stand(model, legs=[2, 3, 4])
    assert np.abs(far.forces.sum(axis=0) - [0, 0, far.weight]).max() < 1e-9
    assert not far.feasible and far.forces[:, 2].min() < 0
    with pytest.raises(ConfigurationError, match="friction cone"):
        stand(model, legs=[2, 3, 4], method="friction", mu=0.8)
    with pytest.raises(ConfigurationError, match="cannot balance"):
        stand(model, legs=[1, 2])
    with pytest.raises(ParameterError, match="leg7"):
        stand(model, legs=["leg7"])
    with pytest.raises(ParameterError, match="Hexapod"):
        stand(hk.load("hexabot_leg"))


def test_friction_cone_distribution_on_uneven_ground() -> None:
    feet = np.array([[0.2, 0.0, 0.05], [-0.1, 0.17, -0.03], [-0.1, -0.17, 0.0], [0.0, 0.0, 0.1]])
    com = np.array([0.02, 0.01, 0.25])
    weight = 20.0
    mn = contact_forces(feet, com, weight)
    mu = 0.02
    tang = np.hypot(mn.forces[:, 0], mn.forces[:, 1])
    assert np.any(tang > mu * mn.forces[:, 2])  # min-norm leaves the cone here
    fr = contact_forces(feet, com, weight, method="friction", mu=mu)
    f = fr.forces
    assert np.abs(f.sum(axis=0) - [0, 0, weight]).max() < 1e-9
    assert np.abs(np.cross(feet - com, f).sum(axis=0)).max() < 1e-9
    assert np.all(f[:, 2] >= -1e-9)
    assert np.all(np.hypot(f[:, 0], f[:, 1]) <= mu * f[:, 2] + 1e-8)
    assert np.sum(f**2) >= np.sum(mn.forces**2) - 1e-9  # min-norm is the unconstrained optimum


def test_stance_at_given_configuration() -> None:
    model = hk.load("hexapod")
    q = standing_configuration(model, 0.1)
    a = stance_at(model, q, 0.1)
    assert a.force_residual < 1e-9
    with pytest.raises(ParameterError, match="method"):
        stance_at(model, q, 0.1, method="lp")  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match="mu"):
        stance_at(model, q, 0.1, method="friction")


# ============================================================================ CLI
def run_cli(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_cli_pendulum_json_figures(capsys: pytest.CaptureFixture[str], tmp_path: object) -> None:
    png = f"{tmp_path}/p.png"
    code, out, _ = run_cli(
        ["pendulum", "--json", "--duration", "8", "--theta0-deg", "45", "--plot", png], capsys
    )
    assert code == 0
    d = json.loads(out)
    exact = exact_period_by_hand(math.radians(45))
    assert d["period_exact"] == pytest.approx(exact, rel=1e-12)
    assert abs(d["period"] - exact) / exact < 1e-6
    assert d["energy_drift"] < 1e-8
    assert d["damped_energy_monotone"] is True
    i, _, _ = hand_pendulum()
    assert d["decay_rate_exact"] == pytest.approx(0.01 / (2 * i), rel=1e-12)
    assert abs(d["decay_rate"] - 0.01 / (2 * i)) / (0.01 / (2 * i)) < 1e-3
    assert d["written"] == [png]
    with open(png, "rb") as fh:
        assert fh.read(8) == b"\x89PNG\r\n\x1a\n"


def test_cli_torques_and_stand(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(
        [
            "torques",
            "hexabot_leg",
            "--q",
            "10",
            "20",
            "-60",
            "--deg",
            "--force",
            "1",
            "2",
            "-3",
            "--json",
        ],
        capsys,
    )
    assert code == 0
    d = json.loads(out)
    model = hk.load("hexabot_leg")
    jac = model.position_jacobian(np.radians([10, 20, -60]))
    assert d["force_torque"] == pytest.approx(jac.T @ [1, 2, -3], abs=1e-12)
    assert d["crosscheck_error"] < 1e-9
    code, out, _ = run_cli(["stand", "--height", "0.09", "--json"], capsys)
    assert code == 0
    d = json.loads(out)
    assert d["force_sum"] == pytest.approx([0, 0, d["mass"] * G], abs=1e-9)
    assert d["force_residual"] < 1e-9 and d["moment_residual"] < 1e-9
    code, out, _ = run_cli(
        ["torques", "hexabot_leg", "--step", "--duration", "1", "--json"], capsys
    )
    assert code == 0 and json.loads(out)["crosscheck_error"] < 1e-9


@pytest.mark.parametrize(
    "argv",
    [
        ["pendulum", "--theta0-deg", "0"],
        ["pendulum", "--dt", "-1"],
        ["pendulum", "--plot", "x.txt"],
        ["stand", "--legs", "9"],
        ["stand", "--method", "friction"],
        ["torques", "hexabot_leg", "--q", "1", "2"],
    ],
)
def test_cli_errors_are_one_line(argv: list[str], capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run_cli(argv, capsys)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith("hexapod-kin: error:")


def test_errors_are_of_the_family() -> None:
    with pytest.raises(HexapodKinError):
        contact_forces([[0, 0, 0]] * 3, [0, 0, 1], -1.0)


# ============================================================================ along a gait
def test_gait_loads_balance_and_match_a_floating_base_model() -> None:
    gait = pytest.importorskip("hexapod_kin.gait")
    from hexapod_kin.dynamics import gait_torques

    model = hk.load("hexapod")
    run = gait.walk(pattern="tripod", duration=1.0, rate=50.0, velocity=(0.04, 0.0, 0.2))
    loads = gait_torques(run, model)
    assert loads.force_residual < 1e-9 and loads.moment_residual < 1e-9
    assert loads.peak == pytest.approx(np.max(np.abs(loads.torque), axis=0))
    ff = free_flyer(model)
    data = ff.createData()
    names = [ff.names[i] for i in range(2, ff.njoints)]
    assert names == list(loads.joint_names) == list(run.joint_names)
    qff = run.pinocchio_q()
    weight = loads.mass * G
    for i in range(0, len(run.t), 7):
        f = loads.forces[i]
        assert f.sum(axis=0) == pytest.approx([0, 0, weight], abs=1e-9)
        assert np.all(f[~run.support[i]] == 0)
        pin.framesForwardKinematics(ff, data, qff[i])
        fext = [pin.Force.Zero() for _ in range(ff.njoints)]
        for name, fk in zip(model.params.foot_frames, f):
            fid = ff.getFrameId(name)
            wrench = pin.SE3(np.eye(3), data.oMf[fid].translation).act(pin.Force(fk, np.zeros(3)))
            j = ff.frames[fid].parentJoint
            fext[j] = fext[j] + data.oMi[j].actInv(wrench)
        tau = pin.rnea(ff, data, qff[i], np.zeros(ff.nv), np.zeros(ff.nv), fext)
        # the base wrench is expressed in the base frame: zero means the forces hold the robot
        assert np.abs(tau[:6]).max() < 1e-9
        assert np.abs(tau[6:] - loads.torque[i]).max() < 1e-9


def test_cli_pendulum_html_and_short_runs(
    capsys: pytest.CaptureFixture[str], tmp_path: object, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("meshcat")
    import re

    from scipy.special import ellipj

    from hexapod_kin import viewer

    shown = []
    real_export = viewer.export_html

    def spy(model, t, q, path, **kw):
        shown.append((np.array(t), np.array(q)))
        return real_export(model, t, q, path, **kw)

    monkeypatch.setattr(viewer, "export_html", spy)
    page = f"{tmp_path}/p.html"
    code, out, _ = run_cli(
        ["pendulum", "--json", "--duration", "0.5", "--damping", "0", "--html", page], capsys
    )
    assert code == 0
    d = json.loads(out)
    # half a second is less than one period: no period measured, said as null (never NaN)
    assert d["period"] is None and d["period_error"] is None
    assert d["decay_rate_exact"] == 0.0
    # the page animates the undamped swing from 30 deg: the exact solution (Jacobi sn),
    # theta(t) = 2 asin(k sn(K - w t, k^2)), k = sin(theta0 / 2), w^2 = m g l_c / I
    ((t, q),) = shown
    i, m, lc = hand_pendulum()
    k = math.sin(math.radians(30) / 2)
    sn = ellipj(float(ellipk(k**2)) - math.sqrt(m * G * lc / i) * t, k**2)[0]
    assert t[0] == 0.0 and t[-1] == pytest.approx(0.5, abs=1 / 30)
    assert np.abs(q[:, 0] + math.pi / 2 - 2 * np.arcsin(k * sn)).max() < 1e-6  # q = 0: level
    assert np.diff(t) == pytest.approx(0.033, abs=1e-9)  # every 33rd step of 1 ms (~30 fps)
    # and the page's own data says so: its title, its animation of that length
    with open(page, encoding="utf-8") as fh:
        text = fh.read()
    data = json.loads(re.search(r"var DATA = (\{.*?\});\n", text).group(1))
    assert data["title"].startswith("pendulum: theta0 = 30 deg, damping 0 N m s/rad")
    assert data["animation"] is True and data["duration"] == pytest.approx(t[-1] - t[0])


@pytest.mark.parametrize("method", ["rk4", "symplectic_euler"])
def test_damping_only_and_an_explicit_zero_torque_give_the_same_bits(method):
    """The damping-only acceleration and the general one (τ + passive) are the same physics."""
    model = hk.load("pendulum", damping=0.01)
    fast = simulate(model, [0.5], [0.2], dt=1e-3, duration=3.0, method=method)
    slow = simulate(model, [0.5], [0.2], dt=1e-3, duration=3.0, method=method, tau=[0.0])
    for name in ("q", "v", "a", "kinetic", "potential", "total"):
        assert np.array_equal(getattr(fast, name), getattr(slow, name)), name
