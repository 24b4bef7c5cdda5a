"""Any legged robot: legs from the kinematic tree, vectorised kinematics, per-leg IK, stand, walk.

References: raw Pinocchio (FK, centre of mass) on models built here from the URDF text, the
URDF's own numbers read with ElementTree (masses), hand lever rules for the standing forces,
and the closed-form leg IK for the numerical one.

PhantomX foot spec (the URDF has no foot links): the tibia collision mesh of
HumaRobotics/phantomx_description (``meshes/tibia_l_coll.STL``, used by all six legs, not
shipped here) reaches farthest along the tibia frame's +y at (0.0015, 0.1604, 0.0288) m; the
foot point is taken there, rounded: ``tibia_XX:0,0.16,0.029`` (a point foot, radius 0).
"""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import pytest

from hexapod_kin import robots
from hexapod_kin.dynamics import stand
from hexapod_kin.exceptions import ConfigurationError, HexapodKinError, ParameterError
from hexapod_kin.gait import GaitError, as_whole_body, body_pose, walk, whole_body
from hexapod_kin.gait.legs import parse_feet
from hexapod_kin.gait.stand import standing_pose
from hexapod_kin.params import Chain, Hexapod, KhalilRow, LegMount

pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")

PHX = Path(__file__).parent / "data" / "phantomx" / "phantomx.urdf"
SIDES = ("lf", "lm", "lr", "rf", "rm", "rr")
OFFSET = (0.0, 0.16, 0.029)
SPEC = " ".join(f"tibia_{s}:{','.join(map(str, OFFSET))}" for s in SIDES)
G = 9.81


@pytest.fixture(scope="module")
def phx():
    return as_whole_body(str(PHX), feet=SPEC)


def _raw_model(text: str) -> tuple[pin.Model, pin.Data]:
    m = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
    return m, m.createData()


def _urdf_mass(text: str) -> float:
    return sum(float(m.get("value")) for m in ET.fromstring(text).iter("mass"))


def _random_state(wb, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    lo = np.where(np.isfinite(wb.lower), wb.lower, -np.pi)
    hi = np.where(np.isfinite(wb.upper), wb.upper, np.pi)
    q = lo + (hi - lo) * rng.uniform(size=(n, wb.nq))
    base = np.array([body_pose(rng.normal(size=3), rng.uniform(-1, 1, size=3)) for _ in range(n)])
    return q, base


def _raw_feet(wb, m: pin.Model, d: pin.Data, q: np.ndarray, base: np.ndarray, spec):
    """Feet by raw Pinocchio: the named frames' placements applied to the offsets."""
    Q = wb.pinocchio_q(q, base)
    out = np.empty((len(q), wb.n_legs, 3))
    for i, qi in enumerate(Q):
        pin.framesForwardKinematics(m, d, qi)
        for k, (frame, off) in enumerate(spec):
            out[i, k] = d.oMf[m.getFrameId(frame)].act(np.asarray(off, dtype=float))
    return out


# ----------------------------------------------------------------------------- PhantomX
def test_phantomx_legs_found_from_the_tree(phx):
    assert phx.n_legs == 6 and phx.nq == 18
    assert set(phx.leg_names) == set(SIDES)
    # counter-clockwise from the front-left, like the built-in hexapod's leg1..leg6
    assert phx.leg_names == ("lf", "lm", "lr", "rr", "rm", "rf")
    for name, cols in zip(phx.leg_names, phx._leg_cols):
        assert [phx.joint_names[j] for j in cols] == [
            f"j_{p}_{name}" for p in ("c1", "thigh", "tibia")
        ]
    assert phx.locked_joints == ()
    assert phx.foot_radius == 0.0
    assert np.allclose(phx.foot_offsets, OFFSET, atol=0)
    assert phx.mass == pytest.approx(_urdf_mass(PHX.read_text()), rel=1e-12)
    assert np.allclose(phx.velocity_limit, 5.6548668) and np.allclose(phx.effort_limit, 2.8)


def test_phantomx_feet_and_com_match_raw_pinocchio(phx):
    m, d = _raw_model(PHX.read_text())
    assert tuple(m.names[2:]) == phx.joint_names
    q, base = _random_state(phx, 40, 1)
    spec = [(f"tibia_{name}", OFFSET) for name in phx.leg_names]
    ref = _raw_feet(phx, m, d, q, base, spec)
    assert np.abs(phx.feet(q, base) - ref).max() <= 1e-12
    T = phx.joint_poses(q, base)
    Q = phx.pinocchio_q(q, base)
    com = phx.com(q, base)
    for i in (0, 17, 39):
        pin.forwardKinematics(m, d, Q[i])
        for j in range(phx.nq):
            assert np.abs(T[i, j] - d.oMi[j + 2].homogeneous).max() <= 1e-12
        assert np.abs(com[i] - pin.centerOfMass(m, d, Q[i])).max() <= 1e-12
    # the added contact frames are the feet in the robot's own Pinocchio model
    md = phx.model.createData()
    pin.framesForwardKinematics(phx.model, md, Q[3])
    for k, f in enumerate(phx.foot_frames):
        assert np.abs(md.oMf[phx.model.getFrameId(f)].translation - ref[3, k]).max() <= 1e-12


def test_phantomx_stands_by_the_lever_rule(phx):
    st = stand(str(PHX), feet=SPEC)
    mass = _urdf_mass(PHX.read_text())
    W = mass * G
    assert st.mass == pytest.approx(mass, rel=1e-12)
    assert st.forces[:, 2].sum() == pytest.approx(W, rel=1e-12)
    # force and moment balance about the CoM, by hand
    r = st.feet - st.com
    assert np.abs(st.forces.sum(axis=0) - [0.0, 0.0, W]).max() <= 1e-9 * W
    assert np.abs(np.cross(r, st.forces).sum(axis=0)).max() <= 1e-9 * W
    # the stance is point-symmetric about the CoM's ground projection (to the URDF's rounded
    # constants, 3.4e-7 m): each foot carries W/6 to that order
    assert np.abs(r[:, :2].sum(axis=0)).max() < 1e-6
    assert np.allclose(st.forces[:, 2], W / 6, rtol=0, atol=1e-5 * W)
    # three feet (a tripod): the vertical forces by hand from the lever equations
    tri = ["lf", "lr", "rm"]
    st3 = stand(str(PHX), feet=SPEC, legs=tri, shift=(0.01, 0.005))
    p = st3.feet
    A = np.vstack([np.ones(3), p[:, 0] - st3.com[0], p[:, 1] - st3.com[1]])
    fz = np.linalg.solve(A, [W, 0.0, 0.0])
    assert np.allclose(st3.forces[:, 2], fz, rtol=0, atol=1e-9 * W)
    # torques: g(q) − Σ Jᵀf on a raw Pinocchio model; its six base rows vanish
    pose = standing_pose(phx, shift=(0.01, 0.005))
    assert np.array_equal(pose.q, st3.q)
    m, d = _raw_model(PHX.read_text())
    qp = phx.pinocchio_q(pose.q[None], pose.base[None])[0]
    pin.computeJointJacobians(m, d, qp)
    pin.updateFramePlacements(m, d)
    tau = np.array(pin.computeGeneralizedGravity(m, d, qp))
    for name, f in zip(tri, st3.forces):
        fid = m.getFrameId(f"tibia_{name}")
        J = pin.getFrameJacobian(m, d, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        r = d.oMf[fid].rotation @ np.array(OFFSET)  # frame origin → foot
        Jp = J[:3] - pin.skew(r) @ J[3:]
        tau -= Jp.T @ f
    assert np.abs(tau[:6]).max() <= 1e-9 * W
    assert np.abs(tau[6:] - st3.torque).max() <= 1e-12


@pytest.mark.parametrize(("pattern", "period"), [("tripod", 1.0), ("wave", 2.0), ("ripple", 1.0)])
def test_phantomx_walks(phx, pattern, period):
    # the wave's swing is 1/6 of the cycle: a 2 s cycle keeps the AX-12's 5.65 rad/s limit
    run = walk(phx, pattern=pattern, period=period, duration=10.0, rate=100.0, strict=True)
    assert run.speed_ok and np.all(run.max_joint_speed <= phx.velocity_limit)
    assert run.min_margin > 0 and run.max_slip <= 1e-9 and run.min_limit_margin >= 0
    assert run.ik_ok.all() and run.ok
    assert np.all(run.q >= phx.lower) and np.all(run.q <= phx.upper)
    m, d = _raw_model(PHX.read_text())
    spec = [(f"tibia_{name}", OFFSET) for name in phx.leg_names]
    idx = np.array([0, 251, 500, 777, 1000])
    ref = _raw_feet(phx, m, d, run.q[idx], run.base_poses[idx], spec)
    assert np.abs(ref - run.feet_planned[idx]).max() <= 1e-9


def test_walk_takes_a_path_and_a_loaded_model():
    from hexapod_kin import load

    a = walk(as_whole_body(str(PHX), feet=SPEC), duration=1.0)
    b = as_whole_body(load(str(PHX)), feet=SPEC)
    assert b.leg_names == a.leg_names
    assert walk(b, duration=1.0).max_slip <= 1e-9


# ----------------------------------------------------------------------------- solo12
def test_solo12_legs_feet_and_standing():
    wb = as_whole_body("erd:solo12")
    assert wb.leg_names == ("FL", "HL", "HR", "FR") and wb.nq == 12
    st = stand("erd:solo12")
    W = st.mass * G
    assert st.forces[:, 2].sum() == pytest.approx(W, rel=1e-12)
    assert st.moment_residual < 1e-9 and st.feasible
    # front/hind lever rule: the CoM's x splits the weight between the two foot pairs
    x = st.feet[:, 0]
    front = x > st.com[0]
    xf, xh = x[front].mean(), x[~front].mean()
    share = W * (st.com[0] - xh) / (xf - xh)
    assert st.forces[front, 2].sum() == pytest.approx(share, rel=1e-9)
    assert st.mass == pytest.approx(float(pin.computeTotalMass(wb.model)), rel=1e-12)


def test_solo12_feet_match_raw_pinocchio():
    from hexapod_kin.sources import resolve_source

    wb = as_whole_body("erd:solo12")
    m, d = _raw_model(resolve_source("erd:solo12").text)
    q, base = _random_state(wb, 20, 3)
    spec = [(f"{name}_FOOT", (0, 0, 0)) for name in wb.leg_names]
    assert np.abs(wb.feet(q, base) - _raw_feet(wb, m, d, q, base, spec)).max() <= 1e-12


def test_solo12_crawls():
    """The issue's figure: erd:solo12 crawls 10 s, statically stable (body sway), every check."""
    run = walk("erd:solo12", pattern="crawl", duration=10.0, strict=True)
    assert run.ok and run.min_margin > 0 and run.ik_ok.all()
    assert run.max_slip <= 1e-9 and run.min_limit_margin >= 0 and run.speed_ok


# ----------------------------------------------------------------------------- Hexapods
def test_four_and_eight_legged_hexapods_walk():
    four = as_whole_body(robots.hexapod(mount_yaw_deg=(45, 135, -135, -45)))
    run = walk(four, pattern="crawl", duration=10.0, strict=True)
    assert run.ok and run.min_margin > 0 and run.max_slip <= 1e-9
    yaws = tuple(22.5 + 45 * k for k in range(4)) + tuple(-157.5 + 45 * k for k in range(4))
    eight = as_whole_body(robots.hexapod(body_radius=0.16, mount_yaw_deg=yaws))
    assert eight.n_legs == 8 and eight.ik_kind == ("closed",) * 8
    # one leg at a time: a 1.5 s cycle keeps the swing within the joints' 10 rad/s
    run8 = walk(eight, pattern="wave", period=1.5, duration=10.0, strict=True)
    assert run8.ok and run8.min_margin > 0 and run8.max_slip <= 1e-9
    assert run8.table.statically_stable


def test_hexapod_with_custom_leg_order_and_names_walks():
    base = robots.hexapod()
    names = ("zeta", "alpha", "mike", "bravo", "yankee", "echo")
    legs = tuple(replace(leg, name=n) for leg, n in zip(base.legs, names))
    hexa = Hexapod(legs=legs, name="custom")
    wb = whole_body(hexa)
    assert wb.leg_names == names
    assert list(wb.joint_names) != list(hexa.joint_names)  # Pinocchio orders the tree itself
    assert sorted(wb.joint_names) == sorted(hexa.joint_names)
    run = walk(wb, pattern="tripod", duration=3.0)
    assert run.ok
    # the same walk as the built-in robot's, joint by joint name (an independent pairing)
    ref = walk(pattern="tripod", duration=3.0)
    ref_cols = {n: i for i, n in enumerate(ref.joint_names)}
    for j, name in enumerate(wb.joint_names):
        leg, joint = name.rsplit("_", 1)
        other = f"leg{names.index(leg) + 1}_{joint}"
        assert np.allclose(run.q[:, j], ref.q[:, ref_cols[other]], atol=1e-12)


def test_a_head_joint_is_locked_and_reported():
    from hexapod_kin.urdf import to_urdf

    text = to_urdf(robots.hexapod())
    head = (
        '<link name="head"><inertial><mass value="0.05"/><inertia ixx="1e-5" ixy="0" ixz="0" '
        'iyy="1e-5" iyz="0" izz="1e-5"/></inertial></link>'
        '<joint name="head_pan" type="revolute"><parent link="body"/><child link="head"/>'
        '<origin xyz="0.1 0 0.03" rpy="0 0 0"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
        '<link name="camera"/><joint name="camera_fixed" type="fixed"><parent link="head"/>'
        '<child link="camera"/><origin xyz="0.02 0 0" rpy="0 0 0"/></joint></robot>'
    )
    wb = as_whole_body(text.replace("</robot>", head))
    assert wb.locked_joints == ("head_pan",) and wb.n_legs == 6 and wb.nq == 18
    assert wb.mass == pytest.approx(whole_body().mass + 0.05, rel=1e-12)
    assert walk(wb, duration=2.0).ok


# ----------------------------------------------------------------------------- any joint axis
def _tilted_quadruped() -> str:
    """Four 3-joint legs with unaligned revolute axes and one prismatic joint per leg."""
    inert = (
        '<inertial><mass value="0.1"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" '
        'izz="1e-4"/></inertial>'
    )
    parts = [f'<robot name="tilted"><link name="body">{inert}</link>']
    for k, (x, y) in enumerate([(0.2, 0.1), (-0.2, 0.1), (-0.2, -0.1), (0.2, -0.1)]):
        parts.append(
            f'<link name="a{k}">{inert}</link><link name="b{k}">{inert}</link>'
            f'<link name="c{k}">{inert}</link><link name="foot{k}"/>'
            f'<joint name="j{k}a" type="revolute"><parent link="body"/><child link="a{k}"/>'
            f'<origin xyz="{x} {y} 0" rpy="0.1 -0.2 0.3"/><axis xyz="0.6 0 0.8"/>'
            '<limit lower="-2" upper="2" effort="1" velocity="1"/></joint>'
            f'<joint name="j{k}b" type="revolute"><parent link="a{k}"/><child link="b{k}"/>'
            '<origin xyz="0.05 0 0" rpy="0 0 0"/><axis xyz="0 1 0"/>'
            '<limit lower="-2" upper="2" effort="1" velocity="1"/></joint>'
            f'<joint name="j{k}c" type="prismatic"><parent link="b{k}"/><child link="c{k}"/>'
            '<origin xyz="0 0 -0.1" rpy="0 0.2 0"/><axis xyz="0 0.28 -0.96"/>'
            '<limit lower="-0.05" upper="0.05" effort="1" velocity="1"/></joint>'
            f'<joint name="f{k}" type="fixed"><parent link="c{k}"/><child link="foot{k}"/>'
            '<origin xyz="0 0 -0.1" rpy="0 0 0"/></joint>'
        )
    return "".join(parts) + "</robot>"


def test_tree_kinematics_any_axis_and_prismatic_match_raw_pinocchio():
    text = _tilted_quadruped()
    wb = as_whole_body(text)
    m, d = _raw_model(text)
    kinds = {m.joints[j].shortname() for j in range(2, m.njoints)}
    assert {"JointModelRevoluteUnaligned", "JointModelRY", "JointModelPrismaticUnaligned"} <= kinds
    q, base = _random_state(wb, 30, 5)
    T = wb.joint_poses(q, base)
    Q = wb.pinocchio_q(q, base)
    for i in range(len(q)):
        pin.forwardKinematics(m, d, Q[i])
        for j in range(wb.nq):
            assert np.abs(T[i, j] - d.oMi[j + 2].homogeneous).max() <= 1e-12
    spec = [(name, (0, 0, 0)) for name in wb.leg_names]
    assert np.abs(wb.feet(q, base) - _raw_feet(wb, m, d, q, base, spec)).max() <= 1e-12
    # the numerical IK puts every foot back where Pinocchio put it
    ik = wb.body_ik(base[0], wb.feet(q[:1], base[:1])[0], q_prev=q[0] * 0.7, strict=False)
    assert ik.reached.all()
    assert np.abs(wb.feet(ik.q, base[:1]) - wb.feet(q[:1], base[:1])).max() <= 1e-10


# ----------------------------------------------------------------------------- leg IK
def test_numerical_leg_ik_equals_the_closed_form_on_the_builtin_leg():
    wb = whole_body()
    num = replace(wb, _closed=(None,) * 6, ik_kind=("numerical",) * 6)
    run = walk(pattern="ripple", duration=2.0)
    a = wb.body_ik(run.base_poses, run.feet_planned)
    b = num.body_ik(run.base_poses, run.feet_planned)
    assert np.abs(a.q - b.q).max() <= 1e-9
    assert b.reached.all()
    # out of reach: the numerical excess is the exact distance to the leg's annulus
    from hexapod_kin.ik import detect_family

    fam = detect_family(wb.params.legs[0].chain)
    B = body_pose([0.0, 0.0, 0.08])
    rng = np.random.default_rng(2)
    far = wb.neutral_feet(None) + B[:3, 3]
    far[:, :2] *= rng.uniform(1.6, 2.2, size=(6, 1))
    e_closed = wb.body_ik(B, far, strict=False)
    e_num = num.body_ik(B, far, strict=False)
    assert not e_closed.reached.any() and not e_num.reached.any()
    T0 = wb.mounts[0]
    p0 = (far[0] - B[:3, 3] - T0[:3, 3]) @ T0[:3, :3]
    assert e_num.excess[0, 0] == pytest.approx(float(fam.reach_excess(p0[None])[0]), abs=1e-9)
    assert np.allclose(e_num.excess, e_closed.excess, atol=1e-9)
    with pytest.raises(GaitError) as err:
        num.body_ik(B, far)
    assert err.value.check == "reach" and err.value.amount == pytest.approx(e_num.excess[0, 0])


def _four_joint_leg() -> Chain:
    return Chain(
        rows=(
            KhalilRow("revolute", 0.0, 0.0, 0.0, 0.0),
            KhalilRow("revolute", -math.pi / 2, 0.04, 0.0, 0.0),
            KhalilRow("revolute", 0.0, 0.07, 0.0, 0.0),
            KhalilRow("revolute", 0.0, 0.06, 0.0, 0.0),
            KhalilRow("fixed", 0.0, 0.06, 0.0, 0.0),
        ),
        joint_names=("hip", "knee", "ankle", "toe"),
        name="leg4",
        tip="foot",
        link_radius=0.006,
    )


def test_numerical_ik_reaches_legs_the_closed_form_refuses(phx):
    from hexapod_kin.ik import detect_family

    leg = _four_joint_leg()
    with pytest.raises(HexapodKinError):
        detect_family(leg)
    hexa = Hexapod(
        legs=tuple(
            LegMount(f"l{k}", leg, (0.1 * math.cos(y), 0.1 * math.sin(y), 0.0), y)
            for k, y in enumerate(np.radians([30, 90, 150, -150, -90, -30]))
        )
    )
    rng = np.random.default_rng(4)
    for wb in (as_whole_body(hexa), replace(phx, _closed=(None,) * 6)):
        q, base = _random_state(wb, 12, 11)
        q = 0.5 * q  # well inside the limits
        for i in range(len(q)):  # each from a start 0.3 rad away (a warm start)
            start = q[i] + rng.uniform(-0.3, 0.3, size=wb.nq)
            target = wb.feet(q[i : i + 1], base[i : i + 1])
            ik = wb.body_ik(base[i], target[0], q_prev=start, strict=False)
            assert ik.reached.all()
            assert np.abs(wb.feet(ik.q, base[i : i + 1]) - target).max() <= 1e-10
    assert as_whole_body(hexa).ik_kind == ("numerical",) * 6
    run = walk(as_whole_body(hexa), duration=2.0, stride=0.03, strict=False)
    assert run.ik_ok.all() and run.min_margin > 0 and run.min_limit_margin >= 0
    wb4 = as_whole_body(hexa)  # the stance feet by FK of the walk's joints: on the plan
    assert np.abs(wb4.feet(run.q, run.base_poses) - run.feet_planned).max() <= 1e-10


# ----------------------------------------------------------------------------- feet specs
def test_foot_specs_in_every_form_give_the_same_robot(tmp_path):
    forms = [
        SPEC,
        SPEC.replace(" ", ","),
        SPEC.split(),
        {f"tibia_{s}": OFFSET for s in SIDES},
    ]
    y = tmp_path / "feet.yaml"
    y.write_text("".join(f"tibia_{s}: [0, 0.16, 0.029]\n" for s in SIDES))
    t = tmp_path / "feet.toml"
    t.write_text(
        "".join(f'[[feet]]\nframe = "tibia_{s}"\noffset = [0, 0.16, 0.029]\n' for s in SIDES)
    )
    j = tmp_path / "feet.json"
    j.write_text(json.dumps({"feet": {f"tibia_{s}": list(OFFSET) for s in SIDES}}))
    forms += [str(y), t, str(j)]
    want = parse_feet(SPEC)
    for f in forms:
        assert sorted(parse_feet(f), key=lambda s: s.frame) == sorted(want, key=lambda s: s.frame)
    for bad in ("tibia_lf:0,0.1", "tibia_lf:a,b,c", "tibia_lf:0,0,0 tibia_lf:1,1,1"):
        with pytest.raises(ParameterError):
            parse_feet(bad)
    with pytest.raises(ConfigurationError, match="no foot link"):
        as_whole_body(str(PHX))
    with pytest.raises(ConfigurationError, match="tibia_xx"):
        as_whole_body(str(PHX), feet="tibia_xx:0,0,0")


def test_foot_radius_is_a_property_of_the_robot():
    assert whole_body().foot_radius == pytest.approx(1.5 * 0.008)
    from hexapod_kin.sources import resolve_source

    urdf = ET.fromstring(resolve_source("erd:anymal").text)
    radii = []
    for link in urdf.iter("link"):
        if link.get("name", "").endswith("_FOOT"):
            radii += [float(s.get("radius")) for s in link.iter("sphere")]
    assert as_whole_body("erd:anymal").foot_radius == pytest.approx(min(radii))
    r = as_whole_body(str(PHX), feet=SPEC, foot_radius=0.01)
    pose = standing_pose(r)
    assert np.allclose(pose.feet[:, 2], 0.01) and np.allclose(pose.contacts[:, 2], 0.0)
    with pytest.raises(ParameterError):
        as_whole_body(str(PHX), feet=SPEC, foot_radius=-1)


# ----------------------------------------------------------------------------- CLI
def test_cli_stand_and_gait_take_any_source(capsys):
    from hexapod_kin.cli import main

    feet = [a for s in SIDES for a in ("--foot", f"tibia_{s}:0,0.16,0.029")]
    assert main(["stand", str(PHX), *feet, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    W = _urdf_mass(PHX.read_text()) * G
    assert sum(f[2] for f in out["forces"]) == pytest.approx(W, rel=1e-12)
    argv = ["gait", str(PHX), *feet, "--pattern", "wave", "--period", "2", "--duration", "2"]
    assert main([*argv, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["ok"] is True and out["max_slip"] <= 1e-9
    assert main(["gait", "--foot-reach", "0.17", "--duration", "1", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["foot_reach"] == 0.17
    assert main(["stand", "erd:solo12", "--gait", "crawl", "--gait-duration", "1", "--json"]) == 0
    loads = json.loads(capsys.readouterr().out)["gait"]  # walking loads of a quadruped
    assert len(loads["peak_torque_full"]) == 12 and loads["walk"]["pattern"]["name"] == "crawl"
    for argv in (
        ["stand", str(PHX)],
        ["gait", str(PHX), "--foot", "tibia_lf:1,2"],
        ["gait", "erd:solo12", "--pattern", "tripod"],
        ["stand", "erd:solo12", "--gait", "tripod"],
    ):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len([line for line in err if line.startswith("hexapod-kin: error")]) == 1


# ----------------------------------------------------------------------------- building
def test_whole_body_is_cached_and_as_whole_body_takes_every_form():
    from hexapod_kin import load

    wb = whole_body()
    assert wb is whole_body() is as_whole_body(None) is as_whole_body(wb)
    assert as_whole_body("hexapod") is wb and as_whole_body(load("hexapod")) is wb
    p = robots.hexapod(l2=0.11)
    assert whole_body(p) is whole_body(p) is as_whole_body(p)
    assert as_whole_body(str(PHX), feet=SPEC) is as_whole_body(str(PHX), feet=SPEC)
    for bad in ((wb, {"feet": SPEC}), (robots.hexapod(), {"feet": SPEC}), ("hexabot_leg", {})):
        with pytest.raises(ParameterError):
            as_whole_body(bad[0], **bad[1])


def test_the_default_stance_rule_by_hand():
    """Built-in legs (l1, l2, l3) = (0.05, 0.1, 0.1), stretched at q = 0: span 0.25 m, so the
    neutral reach is 0.64 · 0.25 = 0.16 m and the body height √(ρ² − r²) = 0.32 · 0.25 m."""
    wb = whole_body()
    assert wb.foot_reach == pytest.approx(0.16, abs=1e-15)
    assert wb.body_height == pytest.approx(0.08, abs=1e-15)
    yaw = np.radians([30, 90, 150, -150, -90, -30])
    want = np.column_stack([(0.12 + 0.16) * np.cos(yaw), (0.12 + 0.16) * np.sin(yaw)])
    assert np.allclose(wb.neutral_feet(None)[:, :2], want, atol=1e-15)
    assert np.allclose(wb.neutral_feet(0.2)[:, :2], want / 0.28 * 0.32, atol=1e-15)
    # solo12 hangs its legs at q = 0: the feet stay under the hips, the body at 0.7155 span
    solo = as_whole_body("erd:solo12")
    pose = standing_pose(solo)
    assert pose.height == solo.body_height and np.allclose(pose.contacts[:, 2], 0.0)
    feet_q0 = solo.feet(np.zeros((1, 12)), np.eye(4)[None])[0]
    assert np.allclose(pose.feet[:, :2], feet_q0[:, :2], atol=1e-12)
    reached = solo.feet(pose.q[None], pose.base[None])[0]
    assert np.abs(reached - pose.feet).max() <= 1e-10


def _upturned_hexapod(masses: bool) -> str:
    """Six legs whose tibia bends upwards twice (0.22 and 0.35 rad), knee range [0, 2.136] rad:
    a real hexapod's shape, for which the geometric default stance puts the knee at the edge
    of its range."""

    def inert(m: float) -> str:
        i = 4e-5 * m
        return (
            (
                f'<inertial><mass value="{m}"/><inertia ixx="{i}" iyy="{i}" izz="{i}" '
                'ixy="0" ixz="0" iyz="0"/></inertial>'
            )
            if masses
            else ""
        )

    def link(name: str, m: float) -> str:
        return f'<link name="{name}">{inert(m)}</link>'

    def joint(
        name: str,
        kind: str,
        parent: str,
        child: str,
        xyz: str,
        rpy: str = "0 0 0",
        axis: str = "",
        lim: str = "",
    ) -> str:
        extra = f'<axis xyz="{axis}"/><limit {lim} effort="10" velocity="3"/>' if axis else ""
        return (
            f'<joint name="{name}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="{xyz}" rpy="{rpy}"/>{extra}</joint>'
        )

    out = ['<robot name="upturned">', link("body", 0.8)]
    for k, yaw in enumerate(np.radians([60, 90, 120, -120, -90, -60])):
        p = f"l{k}"
        r = 0.09
        out += [
            joint(
                f"{p}_mount",
                "fixed",
                "body",
                f"{p}_hip",
                f"{r * math.cos(yaw):.6f} {r * math.sin(yaw):.6f} 0",
                f"0 0 {yaw:.6f}",
            ),
            link(f"{p}_hip", 0.0),
            joint(
                f"{p}_coxa",
                "revolute",
                f"{p}_hip",
                f"{p}_c",
                "0 0 0",
                axis="0 0 1",
                lim='lower="-0.785" upper="0.785"',
            ),
            link(f"{p}_c", 0.04),
            joint(
                f"{p}_femur",
                "revolute",
                f"{p}_c",
                f"{p}_f",
                "0.053 0 0",
                axis="0 1 0",
                lim='lower="-1.789" upper="0"',
            ),
            link(f"{p}_f", 0.05),
            joint(
                f"{p}_knee",
                "revolute",
                f"{p}_f",
                f"{p}_t",
                "0.077 0 0",
                axis="0 1 0",
                lim='lower="0" upper="2.136"',
            ),
            link(f"{p}_t", 0.03),
            joint(f"{p}_bend1", "fixed", f"{p}_t", f"{p}_t2", "0.022358 0 0", "0 -0.2234 0"),
            link(f"{p}_t2", 0.03),
            joint(f"{p}_bend2", "fixed", f"{p}_t2", f"{p}_t3", "0.071518 0 0", "0 -0.3508 0"),
            link(f"{p}_t3", 0.01),
            joint(f"{p}_tip", "fixed", f"{p}_t3", f"{p}_foot", "0.03114 0 0"),
            link(f"{p}_foot", 0.0),
        ]
    return "\n".join([*out, "</robot>"])


def test_a_default_stance_with_no_joint_room_is_replaced_by_the_roomiest(tmp_path):
    """The geometric default (0.64 / 0.32 of the span) leaves the upturned knee beyond its
    range on the first step; the default becomes the grid stance that keeps the most range,
    checked here by raw Pinocchio: feet where planned, every joint ≥ 10 % inside its range
    over the default step box, and a strict 10 s tripod."""
    from hexapod_kin.gait.posture import MIN_ROOM, room

    path = tmp_path / "upturned.urdf"
    path.write_text(_upturned_hexapod(True))
    wb = as_whole_body(str(path))
    # the rule's own default, recomputed by hand, has no room
    span = wb.leg_span
    geo_reach = 0.64 * span  # q = 0 points the legs outwards, past 0.64 of the span
    geo_height = math.sqrt((math.hypot(0.64, 0.32) * span) ** 2 - geo_reach**2)
    assert room(wb, geo_height, geo_reach) < 0  # a joint leaves its range on the first step
    with pytest.raises(GaitError, match="joint limit"):
        walk(wb, duration=2.0, body_height=geo_height, foot_reach=geo_reach, strict=True)
    assert (wb.body_height, wb.foot_reach) != pytest.approx((geo_height, geo_reach))
    assert room(wb, wb.body_height) >= MIN_ROOM
    # independent check of the standing pose by raw Pinocchio
    pose = standing_pose(wb)
    m, d = _raw_model(path.read_text())
    qp = wb.pinocchio_q(pose.q[None], pose.base[None])[0]
    pin.framesForwardKinematics(m, d, qp)
    feet = np.array([d.oMf[m.getFrameId(f"l{k}_foot")].translation for k in range(6)])
    assert np.abs(feet - pose.feet).max() <= 1e-9
    rng = wb.upper - wb.lower
    assert np.all(np.minimum(pose.q - wb.lower, wb.upper - pose.q) >= MIN_ROOM * rng)
    run = walk(wb, pattern="tripod", duration=10.0, strict=True)
    assert run.min_margin > 0 and run.min_limit_margin > 0


@pytest.mark.slow
def test_a_robot_without_mass_is_refused_in_one_line(tmp_path):
    path = tmp_path / "massless.urdf"
    path.write_text(_upturned_hexapod(False))
    wb = as_whole_body(str(path))  # kinematics works without masses
    assert wb.mass == 0 and np.isfinite(wb.feet(wb.neutral_q()[None], np.eye(4)[None])).all()
    with pytest.raises(ConfigurationError, match="no mass"):
        walk(wb, duration=1.0)
    with pytest.raises(ConfigurationError, match="no mass"):
        stand(str(path))
    import subprocess
    import sys

    for cmd in (["gait", str(path), "--duration", "1"], ["stand", str(path)]):
        res = subprocess.run(
            [sys.executable, "-m", "hexapod_kin", *cmd], capture_output=True, text=True, timeout=600
        )
        errors = [ln for ln in res.stderr.splitlines() if "warning" not in ln]
        assert res.returncode == 2 and len(errors) == 1 and "no mass" in errors[0], res.stderr


@pytest.mark.parametrize("name", ["go1", "a1"])
def test_unitree_quadrupeds_stand_symmetric_and_crawl(name):
    """Unitree's knee range excludes 0, so at q = 0 clipped every foot is ~0.16 m forward of
    its hip; that shared offset is not a stance: the default feet are symmetric front/rear
    about the hips (by raw Pinocchio: the hips' mean equals the feet's mean), and the crawl
    holds 10 s strict (before: the centre of mass left the support polygon by 0.039 m)."""
    wb = as_whole_body(f"erd:{name}")
    pose = standing_pose(wb)
    m, d = _raw_model(_erd_text(name))
    qp = wb.pinocchio_q(pose.q[None], pose.base[None])[0]
    pin.framesForwardKinematics(m, d, qp)
    hips = np.array([d.oMi[m.getJointId(f"{leg}_hip_joint")].translation for leg in wb.leg_names])
    feet = np.array([d.oMf[m.getFrameId(f"{leg}_foot")].translation for leg in wb.leg_names])
    assert np.abs(feet - pose.feet).max() <= 1e-9  # the URDF foot links are the feet
    assert np.abs((feet - hips)[:, :2].mean(axis=0)).max() <= 1e-9
    run = walk(wb, pattern="crawl", duration=10.0, strict=True)
    assert run.min_margin > 0.001 and run.min_zmp_margin > -3e-3


def _erd_text(name: str) -> str:
    from hexapod_kin.sources import resolve_source

    return resolve_source(f"erd:{name}").text


# ----------------------------------------------------------------------------- joint kinds
def test_continuous_legs_match_raw_pinocchio_and_walk_like_revolute(tmp_path):
    text = PHX.read_text()
    assert text.count('type="revolute"') == 18
    (tmp_path / "rev.urdf").write_text(text)
    (tmp_path / "cont.urdf").write_text(text.replace('type="revolute"', 'type="continuous"'))
    rev = as_whole_body(str(tmp_path / "rev.urdf"), feet=SPEC)
    cont = as_whole_body(str(tmp_path / "cont.urdf"), feet=SPEC)
    m, d = _raw_model((tmp_path / "cont.urdf").read_text())
    assert m.nq == 7 + 2 * 18 and cont.model.nq == m.nq and cont.nq == 18
    assert {m.joints[j].shortname() for j in range(2, m.njoints)} == {"JointModelRUBX"}
    assert np.all(np.isinf(cont.lower)) and np.all(np.isinf(cont.upper))
    # the (cos, sin) pairs: feet, joint frames and CoM against raw Pinocchio
    q, base = _random_state(cont, 20, 3)
    spec = [(f"tibia_{name}", OFFSET) for name in cont.leg_names]
    ref = _raw_feet(cont, m, d, q, base, spec)
    assert np.abs(cont.feet(q, base) - ref).max() <= 1e-12
    Q = cont.pinocchio_q(q, base)
    T, com = cont.joint_poses(q, base), cont.com(q, base)
    for i in (0, 19):
        pin.forwardKinematics(m, d, Q[i])
        for j in range(cont.nq):
            assert np.abs(T[i, j] - d.oMi[j + 2].homogeneous).max() <= 1e-12
        assert np.abs(com[i] - pin.centerOfMass(m, d, Q[i])).max() <= 1e-12
    # the same stance and the same walk, joint angle for joint angle
    assert np.array_equal(standing_pose(cont).q, standing_pose(rev).q)
    a, b = walk(rev, duration=1.0), walk(cont, duration=1.0)
    assert a.ok and b.ok
    assert np.array_equal(a.q, b.q) and np.array_equal(a.com, b.com)
    assert a.pinocchio_q().shape[1] == 25 and b.pinocchio_q().shape[1] == 43
    s = stand(cont)
    r = stand(rev)
    assert s.feasible and np.allclose(s.forces, r.forces, atol=1e-9)
    assert np.allclose(s.torque, r.torque, atol=1e-9)
    pytest.importorskip("mujoco")
    from hexapod_kin.simulate import simulate

    assert simulate(walk(cont, duration=0.5)).ok


def test_a_leg_joint_of_another_kind_is_refused_by_name(tmp_path):
    text = PHX.read_text().replace(
        '<joint name="j_c1_lf" type="revolute">', '<joint name="j_c1_lf" type="floating">', 1
    )
    assert "floating" in text
    (tmp_path / "f.urdf").write_text(text)
    with pytest.raises(HexapodKinError, match="'j_c1_lf' is a JointModelFreeFlyer"):
        as_whole_body(str(tmp_path / "f.urdf"), feet=SPEC)


def test_the_whole_body_is_a_view_of_the_loaded_robot():
    from hexapod_kin import load

    km = load(str(PHX))
    wb = as_whole_body(km, feet=SPEC)
    assert wb.kinematic is km and wb.urdf == km.urdf
    assert as_whole_body(km, feet=SPEC) is wb  # kept in the loaded robot's cache
    ref = pin.buildModelFromXML(km.urdf, pin.JointModelFreeFlyer())
    assert km.floating_model == ref  # built from the loaded model, equal to a fresh parse
    assert wb.model is not km.floating_model  # its contact frames go on a copy
    assert km.floating_model.nframes == ref.nframes


# ----------------------------------------------------------------------------- URDF elsewhere
@pytest.fixture()
def elsewhere(tmp_path, monkeypatch):
    """PhantomX in ``robots/``, the cwd ``work/`` holding a decoy ``phx.urdf`` (the hexapod)."""
    from hexapod_kin.urdf import to_urdf

    (tmp_path / "robots").mkdir()
    (tmp_path / "work").mkdir()
    (tmp_path / "robots" / "phx.urdf").write_text(PHX.read_text())
    (tmp_path / "work" / "phx.urdf").write_text(to_urdf(robots.hexapod()))
    monkeypatch.chdir(tmp_path / "work")
    return tmp_path / "robots" / "phx.urdf"


@pytest.fixture()
def pages(monkeypatch):
    """The joint names of every model a walk page is drawn from (the page data is packed)."""
    import hexapod_kin.viewer.walk as walk_pages

    seen: list[tuple[str, ...]] = []
    real = walk_pages.render_html

    def spy(model, *args, **kwargs):
        seen.append(tuple(model.joint_names))
        return real(model, *args, **kwargs)

    monkeypatch.setattr(walk_pages, "render_html", spy)
    return seen


@pytest.mark.parametrize("how", ["relative", "absolute"])
def test_a_urdf_in_another_folder_walks_and_shows_itself(elsewhere, how, tmp_path, pages):
    from hexapod_kin.gait.show import run_model
    from hexapod_kin.simulate.scene import _robot_mjcf
    from hexapod_kin.viewer import walk_html

    path = "../robots/phx.urdf" if how == "relative" else str(elsewhere)
    run = walk(as_whole_body(path, feet=SPEC), duration=0.5)
    assert run.robot.urdf == PHX.read_text()
    km = run_model(run)
    assert km is run.robot.kinematic and "j_c1_lf" in km.joint_names
    assert walk_html(run, tmp_path / "walk.html").is_file()
    assert pages == [km.joint_names]  # PhantomX, not the decoy of the same name
    assert "j_c1_lf" in _robot_mjcf(run.robot)


def test_cli_gait_and_simulate_pages_of_a_urdf_in_another_folder(elsewhere, tmp_path, pages):
    from hexapod_kin.cli import main

    feet = [a for s in SIDES for a in ("--foot", f"tibia_{s}:0,0.16,0.029")]
    out = tmp_path / "gait.html"
    argv = ["gait", "../robots/phx.urdf", *feet, "--duration", "0.5", "--html", str(out)]
    assert main(argv) == 0 and out.is_file()
    assert len(pages) == 1 and "j_c1_lf" in pages[0]
    pytest.importorskip("mujoco")
    out = tmp_path / "sim.html"
    argv = ["simulate", str(elsewhere), "--foot", SPEC, "--duration", "0.5", "--html", str(out)]
    assert main(argv) == 0 and out.is_file()


# ----------------------------------------------------------------------------- centroidal
@pytest.mark.parametrize("source", ["hexapod", "erd:solo12"])
def test_com_equals_pinocchio_center_of_mass(source):
    """The vectorised CoM against Pinocchio's ``centerOfMass`` at random states, to 1e-9 (the
    ZMP's momentum is Pinocchio's own: tests/test_gait_physics.py)."""
    wb = as_whole_body(source)
    m, d = wb.model, wb.model.createData()
    q, base = _random_state(wb, 12, 5)
    Q = wb.pinocchio_q(q, base)
    com = wb.com(q, base)
    for i in range(len(q)):
        assert np.abs(com[i] - pin.centerOfMass(m, d, Q[i])).max() <= 1e-9


def test_the_same_relative_path_in_two_folders_is_two_robots(elsewhere):
    import os

    decoy = PHX.read_text().replace('name="j_c1_', 'name="j_coxa_')
    (elsewhere.parent.parent / "work" / "phx.urdf").write_text(decoy)
    st = os.stat(elsewhere)
    os.utime(elsewhere.parent.parent / "work" / "phx.urdf", ns=(st.st_atime_ns, st.st_mtime_ns))
    here = as_whole_body("phx.urdf", feet=SPEC)  # the cwd is work/
    os.chdir(elsewhere.parent)
    there = as_whole_body("phx.urdf", feet=SPEC)
    assert "j_coxa_lf" in here.joint_names and "j_c1_lf" in there.joint_names


def test_gait_torques_default_to_the_robot_that_walked():
    from hexapod_kin.dynamics.gait_loads import gait_torques

    four = as_whole_body(robots.hexapod(mount_yaw_deg=(45, 135, -135, -45)))
    run = walk(four, pattern="crawl", duration=1.0)
    loads = gait_torques(run)  # the four-legged robot, not the built-in six-legged one
    assert loads.joint_names == four.kinematic.joint_names and loads.forces.shape[1] == 4
    W = four.mass * G
    assert np.abs(loads.forces.sum(axis=1)[:, 2] - W).max() <= 1e-9 * W


def _belly_urdf(tmp_path: Path, dz: float = 0.2) -> tuple[Path, Path]:
    """The built-in hexapod's URDF, and the same robot whose root frame is ``dz`` below its body.

    Kraby's base frame is at its belly's level, below the legs' mounts (body height < 0).
    """
    from hexapod_kin import load

    text = load("hexapod").urdf
    i = text.index('<link name="body"')
    root = (
        '<link name="belly"/>\n  <joint name="belly_to_body" type="fixed"><parent link="belly"/>'
        f'<child link="body"/><origin xyz="0 0 {dz}" rpy="0 0 0"/></joint>\n  '
    )
    plain, belly = tmp_path / "plain.urdf", tmp_path / "belly.urdf"
    plain.write_text(text)
    belly.write_text(text[:i] + root + text[i:])
    return plain, belly


def test_a_base_frame_below_the_mounts_stands_and_walks(tmp_path, capsys):
    """Kraby-like: the body frame 0.2 m under the body; the same joints, the base 0.2 m lower."""
    from hexapod_kin.cli import main

    plain, belly = _belly_urdf(tmp_path)
    a, b = standing_pose(str(plain)), standing_pose(str(belly))
    assert b.height < 0 and b.height == pytest.approx(a.height - 0.2, abs=1e-12)
    assert np.array_equal(a.q, b.q)
    assert np.allclose(a.base[:3, 3] - b.base[:3, 3], [0.0, 0.0, 0.2], atol=1e-12)
    ra, rb = walk(str(plain), duration=2.0), walk(str(belly), duration=2.0)
    assert np.allclose(ra.q, rb.q, atol=1e-12) and rb.min_margin == pytest.approx(ra.min_margin)
    assert main(["stand", str(belly)]) == 0
    with pytest.raises(ParameterError, match="mount at or below the ground"):
        standing_pose(str(belly), height=-0.2)


def _knee_sides(path: Path, pose: Any) -> np.ndarray:
    """Per leg, the knee's height over the femur→foot line at its point, by raw Pinocchio."""
    model = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    data = model.createData()
    q = pose.robot.pinocchio_q(pose.q[None], pose.base[None])[0]
    pin.framesForwardKinematics(model, data, q)
    out = []
    for k in range(1, 7):
        hip = data.oMi[model.getJointId(f"leg{k}_knee")].translation
        knee = data.oMi[model.getJointId(f"leg{k}_ankle")].translation
        foot = data.oMf[model.getFrameId(f"leg{k}_foot")].translation
        u = (foot - hip) / np.linalg.norm(foot - hip)
        off = (knee - hip) - np.dot(knee - hip, u) * u
        out.append(off[2])
    return np.array(out)


def test_the_knee_branch_is_asked_reported_and_kept_inside_the_limits(tmp_path):
    """--knee picks the branch (checked by raw Pinocchio); limits that allow only one win."""
    from hexapod_kin.gait.knee import knee_directions

    plain, _ = _belly_urdf(tmp_path)
    up, down = standing_pose(str(plain), knee="up"), standing_pose(str(plain), knee="down")
    assert np.all(_knee_sides(plain, up) > 0.01) and np.all(_knee_sides(plain, down) < -0.01)
    assert knee_directions(up.robot, up.q) == ("up",) * 6
    assert knee_directions(down.robot, down.q) == ("down",) * 6
    # ankles limited to [-3, -0.2] rad: only the knee-down branch fits; taken by default
    text = plain.read_text()
    for k in range(1, 7):
        head = f'<joint name="leg{k}_ankle"'
        i = text.index(head)
        j = text.index("<limit ", i)
        e = text.index("/>", j)
        text = text[:j] + '<limit lower="-3.0" upper="-0.2" effort="10" velocity="10"' + text[e:]
    tight = tmp_path / "tight.urdf"
    tight.write_text(text)
    st = standing_pose(str(tight))
    assert np.allclose(st.q, down.q, atol=1e-9) and np.all(_knee_sides(tight, st) < -0.01)
    assert knee_directions(st.robot, standing_pose(str(tight), knee="up").q) == ("down",) * 6
    run = walk(str(tight), duration=1.0)
    assert run.settings["knees"] == ("down",) * 6 and run.min_limit_margin > 0
    with pytest.raises(ParameterError, match="knee='sideways' is not allowed"):
        standing_pose(str(plain), knee="sideways")


def test_gait_torques_of_any_legged_robot_equal_the_hexapod_rule(tmp_path):
    """The floating-base path (any robot) against the Hexapod's fixed-base path, one run."""
    from hexapod_kin import load
    from hexapod_kin.dynamics.gait_loads import gait_torques

    plain, belly = _belly_urdf(tmp_path)
    run = walk(str(plain), pattern="wave", duration=1.0)
    any_robot, hexa = gait_torques(run), gait_torques(run, load("hexapod"))
    cols = [any_robot.joint_names.index(n) for n in hexa.joint_names]
    assert np.allclose(any_robot.torque[:, cols], hexa.torque, atol=1e-12)
    assert np.allclose(any_robot.forces, hexa.forces, atol=1e-12)
    assert any_robot.force_residual < 1e-9 and any_robot.torque_full.shape == run.q.shape
    low = gait_torques(walk(str(belly), pattern="wave", duration=1.0))  # a base frame lower
    assert np.allclose(low.torque, any_robot.torque, atol=1e-9)
    with pytest.raises(ParameterError, match="not the robot that walked"):
        gait_torques(run, load(str(belly)))


def test_a_walk_page_traces_every_foot(monkeypatch):
    """The page of a quadruped's walk traces its four feet (not one tip): Pinocchio's feet."""
    pytest.importorskip("meshcat")
    import hexapod_kin.viewer.walk as vw

    run = walk("erd:solo12", duration=1.0)
    seen: dict = {}
    monkeypatch.setattr(vw, "render_html", lambda mdl, t, q, **kw: seen.update(kw) or "page")
    assert vw.walk_page(run) == "page"
    frames = seen["trace_frame"]
    assert len(frames) == 4
    wb = run.robot
    model = pin.Model(wb.model)
    data = model.createData()
    qp = run.pinocchio_q()
    for i in (0, 17, 49):
        pin.framesForwardKinematics(model, data, qp[i])
        traced = np.array([data.oMf[model.getFrameId(f)].translation for f in frames])
        assert np.allclose(traced, run.feet[i], atol=1e-9)  # leaf feet: the frames are feet


def test_absurd_inertias_keep_the_com_sway_and_fail_the_zmp_check(tmp_path, capsys):
    """Link inertias 1e5 times too large (SpotMicroAI's kind): the ZMP cannot be followed by
    the body's sway; the plan keeps the centre of mass's sway (every foot reached, the static
    margin positive) and its ZMP margin fails: not achieved, exit status 1."""
    import re

    from hexapod_kin.cli import main

    four = as_whole_body(robots.hexapod(mount_yaw_deg=(45, 135, -135, -45)))
    heavy = re.sub(
        r'i(xx|yy|zz)="([0-9.eE+-]+)"',
        lambda m: f'i{m.group(1)}="{float(m.group(2)) * 1e5 + 100:.6g}"',
        four.kinematic.urdf,
    )
    path = tmp_path / "heavy.urdf"
    path.write_text(heavy)
    run = walk(str(path), duration=2.0, strict=False)
    assert bool(np.all(run.ik_ok)) and run.min_margin > 0 and run.min_zmp_margin < -1.0
    sway = run.base_poses[:, 1, 3]  # straight along x: the sway is the body's y
    assert np.abs(sway).max() <= run.robot.leg_span
    assert main(["gait", str(path), "--duration", "2"]) == 1
    assert "needs a balance controller" in capsys.readouterr().err
