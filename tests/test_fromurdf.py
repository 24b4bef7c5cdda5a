"""chain_from_urdf: Khalil tables recovered from URDFs, FK checked against Pinocchio."""

from __future__ import annotations

import math

import numpy as np
import pytest

import hexapod_kin as hk
from hexapod_kin import Chain, DHRow, KhalilRow, chain_from_urdf, robots, table_fk, to_urdf
from hexapod_kin._table_kin import table_position_jacobian
from hexapod_kin.exceptions import ConfigurationError, HexapodKinError
from hexapod_kin.params import Hexapod


def _fk_error(chain, model, n=50, seed=0):
    qs = model.random_q(n, seed=seed)
    return max(float(np.abs(table_fk(chain, q) - model.fk(q)).max()) for q in qs)


def _jac_error(chain, model, n=20, seed=1):
    qs = model.random_q(n, seed=seed)
    return max(
        float(
            np.abs(
                table_position_jacobian(chain, q) - model.jacobian(q, "local_world_aligned")[:3]
            ).max()
        )
        for q in qs
    )


def _catalogue():
    """(URDF text, base, tip) of every catalogue chain; each hexapod leg from the body."""
    out = []
    for name in robots.names():
        built = robots.get(name)
        if isinstance(built, Hexapod):
            out += [(to_urdf(built, leg=leg.name), None, f"{leg.name}_{leg.chain.tip}")
                    for leg in built.legs]  # fmt: skip
        else:
            out.append((to_urdf(built), None, None))
    return out


@pytest.mark.parametrize("text,base,tip", _catalogue())
def test_catalogue_urdfs_round_trip(text, base, tip):
    chain = chain_from_urdf(text, base=base, tip=tip)
    model = hk.load(text, base=base, tip=tip)
    assert chain.nq == model.nq
    assert _fk_error(chain, model) < 1e-12
    assert _jac_error(chain, model) < 1e-12


@pytest.mark.parametrize(
    "name", [n for n in robots.names() if not isinstance(robots.get(n), Hexapod)]
)
def test_own_exports_give_back_the_joint_rows(name):
    original = robots.get(name)
    chain = chain_from_urdf(to_urdf(original))
    joint_rows = [r for r in original.rows if r.is_joint]
    for got, want in zip(chain.rows, joint_rows):
        assert got.sigma == want.sigma
        # the same geometry: |d| and alpha up to the sign conventions of a free x axis
        assert abs(abs(got.d) - abs(want.d)) < 1e-12


@pytest.mark.parametrize(
    "source,tip",
    [
        ("erd:solo12", "FL_FOOT"),
        ("erd:solo12", "HR_FOOT"),
        ("erd:ur5_robot", None),
        ("erd:panda", "panda_link8"),
        ("erd:panda", "panda_hand"),
    ],
)
def test_example_robot_data_round_trip(source, tip):
    chain = chain_from_urdf(source, tip=tip)
    model = hk.load(source, tip=tip)
    assert chain.nq == model.nq and chain.joint_names == model.joint_names
    assert _fk_error(chain, model, n=100) < 1e-12
    assert _jac_error(chain, model) < 1e-12


def _urdf(joints):
    """A serial URDF from (type, xyz, rpy, axis) tuples; links with a unit mass."""
    inertial = (
        '<inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" '
        'ixz="0" iyz="0"/></inertial>'
    )
    lines = ['<robot name="t">', f'<link name="l0">{inertial}</link>']
    for k, (jtype, xyz, rpy, axis) in enumerate(joints, start=1):
        lim = '<limit lower="-1" upper="1" effort="1" velocity="1"/>' if axis else ""
        ax = f'<axis xyz="{axis}"/>' if axis else ""
        lines.append(
            f'<joint name="j{k}" type="{jtype}"><parent link="l{k - 1}"/><child link="l{k}"/>'
            f'<origin xyz="{xyz}" rpy="{rpy}"/>{ax}{lim}</joint>'
        )
        lines.append(f'<link name="l{k}">{inertial}</link>')
    lines.append("</robot>")
    return "\n".join(lines)


@pytest.mark.parametrize(
    "joints",
    [
        # skew axes in arbitrary directions, a fixed joint between
        [
            ("revolute", "0.1 0.2 0.3", "0.3 0.2 0.1", "0.3 -0.5 0.8"),
            ("revolute", "0.2 0 0.1", "0 0.4 0", "1 0 0"),
            ("fixed", "0 0.1 0.05", "0.5 0 0", ""),
            ("prismatic", "0.1 0 0", "0 0 0.3", "0 1 1"),
            ("revolute", "0 0 0.2", "0.1 0.1 0.1", "-1 2 0.5"),
        ],
        # parallel, coincident and intersecting axes
        [
            ("revolute", "0 0 0", "0 0 0", "0 0 1"),
            ("revolute", "0.3 0.1 0", "0 0 0", "0 0 1"),
            ("revolute", "0 0 0.2", "0 0 0", "0 0 1"),
            ("revolute", "0 0 0", "0 0 0", "1 0 0"),
            ("prismatic", "0 0 0.1", "0 0 0", "1 0 0"),
        ],
        # a single joint off the base frame
        [("revolute", "0.4 -0.3 0.2", "1 2 3", "0 1 0")],
    ],
    ids=["skew-fixed-prismatic", "parallel-coincident-intersecting", "single-offset"],
)
def test_synthetic_chains_any_axes(joints):
    text = _urdf(joints)
    chain = chain_from_urdf(text, tip=f"l{len(joints)}")
    model = hk.load(text, tip=f"l{len(joints)}")
    assert _fk_error(chain, model, n=100) < 1e-12
    assert _jac_error(chain, model) < 1e-12
    assert not any(r.sigma == "fixed" for r in chain.rows)


@pytest.mark.parametrize(
    "source,base,tip",
    [
        ("erd:solo12", "FL_SHOULDER", "FL_FOOT"),
        ("erd:ur5_robot", "shoulder_link", "wrist_2_link"),
        ("erd:ur5_robot", "upper_arm_link", "tool0"),
    ],
)
def test_sub_chains_between_named_frames(source, base, tip):
    chain = chain_from_urdf(source, base=base, tip=tip)
    model = hk.load(source, base=base, tip=tip)
    assert chain.base == base and chain.tip == tip and chain.nq == model.nq
    assert _fk_error(chain, model) < 1e-12
    assert _jac_error(chain, model) < 1e-12


def test_recovered_chain_exports_and_reloads_equal():
    chain = chain_from_urdf("erd:ur5_robot")
    again = hk.load(chain)
    model = hk.load("erd:ur5_robot")
    for q in model.random_q(20, seed=3):
        np.testing.assert_allclose(again.fk(q), model.fk(q), atol=1e-12)


def test_dh_chain_through_urdf_keeps_a_dh_like_table():
    dh = Chain.from_dh([DHRow(0, 0.3, 0, math.pi / 2), DHRow(0, 0, 0.4, 0), DHRow(0, 0, 0.3, 0)])
    back = chain_from_urdf(to_urdf(dh))
    assert [r.sigma for r in back.rows] == ["revolute"] * 3
    assert back.rows[0] == KhalilRow("revolute", 0, 0, 0, 0.3)


def test_not_serial_or_unsupported_says_why():
    with pytest.raises(ConfigurationError, match="not a serial chain"):
        chain_from_urdf("hexapod")  # the whole robot: six branches
    planar = _urdf([("planar", "0 0 0", "0 0 0", "0 0 1")])
    with pytest.raises(ConfigurationError, match="joint 'j1' is a JointModelPlanar"):
        chain_from_urdf(planar, tip="l1")
    floating = _urdf([("revolute", "0 0 0", "0 0 0", "0 0 1"), ("floating", "0 0 1", "0 0 0", "")])
    with pytest.raises(HexapodKinError, match="joint 'j2' is a JointModelFreeFlyer"):
        chain_from_urdf(floating, tip="l2")


def test_continuous_joint_is_a_revolute_row():
    text = _urdf(
        [("continuous", "0 0 0.1", "0 0 0", "0 1 0"), ("revolute", "0.2 0 0", "0 0 0", "0 1 0")]
    )
    chain = chain_from_urdf(text, tip="l2")
    model = hk.load(text, tip="l2")
    assert chain.sigmas == ("revolute", "revolute")
    assert _fk_error(chain, model, n=50) < 1e-12


# ------------------------------------------------------------------ real files: snapping
PHANTOMX = "tests/data/phantomx/phantomx.urdf"
#: The centre of the tibia mesh's spherical tip (tibia_l.STL, fitted), in the tibia frame.
PHANTOMX_FOOT = ((0.00155, 0.1535, 0.0288), (0.0, 0.0, 0.0))
LEGS = ["lf", "lm", "lr", "rf", "rm", "rr"]


def _span(model):
    """Path length base origin -> joint origins -> tip at q = 0, from Pinocchio's placements."""
    import pinocchio as pin

    m, d = model.model, pin.Data(model.model)
    pin.forwardKinematics(m, d, np.zeros(m.nq))
    pin.updateFramePlacements(m, d)
    base = d.oMf[model.base_id].inverse()
    pts = [np.zeros(3)] + [(base * d.oMi[i]).translation for i in range(1, m.njoints)]
    pts.append((base * d.oMf[model.tip_id]).translation)
    return sum(float(np.linalg.norm(b - a)) for a, b in zip(pts[:-1], pts[1:]))


@pytest.mark.filterwarnings("ignore::hexapod_kin.UrdfWarning")
@pytest.mark.parametrize("leg", LEGS)
def test_phantomx_legs_are_clean_tables(leg):
    tip = f"tibia_{leg}"
    rec = hk.recover_chain(PHANTOMX, base="base_link", tip=tip, tool=PHANTOMX_FOOT)
    chain = rec.chain
    model = hk.load(PHANTOMX, base="base_link", tip=tip, tool=PHANTOMX_FOOT)
    # one snap: thigh/tibia anti-parallel, off by the rounding of π to 3.14159 in the tibia yaw
    assert [(s.joints, s.kind) for s in rec.snaps] == [
        ((f"j_thigh_{leg}", f"j_tibia_{leg}"), "anti-parallel")
    ]
    assert rec.snaps[0].angle == pytest.approx(math.pi - 3.14159, rel=1e-6)
    alpha3 = chain.rows[2].alpha
    assert alpha3 == round(alpha3 / (math.pi / 2)) * (math.pi / 2) and abs(alpha3) == math.pi
    # the lengths are the URDF's: coxa 0.054 m, femur |(0.0645, 0.0145)|; none over the chain
    assert chain.rows[1].d == pytest.approx(0.054, abs=1e-12)
    assert chain.rows[2].d == pytest.approx(math.hypot(0.0645, 0.0145), abs=1e-12)
    span = _span(model)
    lengths = [abs(v) for r in chain.rows for v in (r.d, r.r)]
    assert max(lengths + [float(np.linalg.norm(chain.tool.xyz))]) <= span
    # FK vs Pinocchio, 100 random q: the snap moves the foot by angle × |foot − tibia axis|
    bound = rec.snaps[0].angle * float(np.linalg.norm(PHANTOMX_FOOT[0]))
    assert rec.fk_bound == pytest.approx(bound, rel=1e-9)
    err = max(
        float(np.linalg.norm(table_fk(chain, q)[:3, 3] - model.fk(q)[:3, 3]))
        for q in model.random_q(100, seed=2)
    )
    assert 0.5 * bound <= err <= bound * (1 + 1e-9) + 1e-12  # ≈ 4.1e-7 m: the snap, no more
    assert "anti-parallel by 2.65e-06 rad" in rec.summary() and "snapped" in chain.description
    assert rec.to_dict()["snaps"][0]["kind"] == "anti-parallel"


@pytest.mark.filterwarnings("ignore::hexapod_kin.UrdfWarning")
def test_phantomx_without_snapping_is_a_clear_error_and_a_wider_tolerance_snaps_more():
    with pytest.raises(ConfigurationError, match=r"larger than the chain itself.*j_thigh_lf"):
        chain_from_urdf(PHANTOMX, base="base_link", tip="tibia_lf", angle_tol=0.0)
    with pytest.raises(hk.ParameterError, match="angle_tol"):
        chain_from_urdf(PHANTOMX, base="base_link", tip="tibia_lf", angle_tol=-1.0)
    # 1e-3 rad also snaps 1.5704 (for π/2): the coxa/thigh twist becomes exactly -π/2
    rec = hk.recover_chain(
        PHANTOMX, base="base_link", tip="tibia_lf", tool=PHANTOMX_FOOT, angle_tol=1e-3
    )
    assert [s.kind for s in rec.snaps] == ["perpendicular", "anti-parallel"]
    assert rec.snaps[0].angle == pytest.approx(math.pi / 2 - 1.5704, rel=1e-6)
    assert rec.chain.rows[1].alpha == -math.pi / 2
    model = hk.load(PHANTOMX, base="base_link", tip="tibia_lf", tool=PHANTOMX_FOOT)
    err = max(
        float(np.linalg.norm(table_fk(rec.chain, q)[:3, 3] - model.fk(q)[:3, 3]))
        for q in model.random_q(100, seed=3)
    )
    assert err <= rec.fk_bound * (1 + 1e-9)


def test_exact_urdf_has_no_snaps_and_fk_to_1e12():
    built = robots.hexapod()
    for leg in built.legs[:2]:
        text = to_urdf(built, leg=leg.name)
        rec = hk.recover_chain(text, tip=f"{leg.name}_{leg.chain.tip}")
        assert rec.snaps == () and rec.zeroed == () and rec.fk_bound == 0.0
        assert rec.fk_error <= 1e-12
        assert _fk_error(rec.chain, hk.load(text, tip=f"{leg.name}_{leg.chain.tip}")) <= 1e-12
        assert "no axis snapped" in rec.summary()


def test_near_perpendicular_axis_is_snapped_with_its_bound():
    eps = 5e-5  # a rounded constant: the second axis 5e-5 rad off perpendicular
    text = _urdf(
        [
            ("revolute", "0 0 0.1", "0 0 0", "0 0 1"),
            ("revolute", "0.05 0 0", f"{math.pi / 2 + eps} 0 0", "0 0 1"),
            ("revolute", "0.1 0 0", "0 0 0", "0 0 1"),
            ("fixed", "0.12 0.01 0", "0 0 0", ""),
        ]
    )
    rec = hk.recover_chain(text, tip="l4")
    assert [s.kind for s in rec.snaps] == ["perpendicular"]
    assert rec.snaps[0].angle == pytest.approx(eps, rel=1e-9)
    assert rec.chain.rows[1].alpha in (math.pi / 2, -math.pi / 2)
    reach = 0.1 + math.hypot(0.12, 0.01)  # joint 2 -> joint 3 -> tip
    assert rec.fk_bound == pytest.approx(eps * reach, rel=1e-9)
    model = hk.load(text, tip="l4")
    err = max(
        float(np.linalg.norm(table_fk(rec.chain, q)[:3, 3] - model.fk(q)[:3, 3]))
        for q in model.random_q(100, seed=4)
    )
    assert err <= rec.fk_bound * (1 + 1e-9)
    exact = hk.recover_chain(text, tip="l4", angle_tol=1e-5)  # below the tolerance: kept
    assert exact.snaps == () and _fk_error(exact.chain, model) < 1e-12


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore::hexapod_kin.UrdfWarning")
def test_phantomx_derive_and_scan_from_the_cli(capsys, tmp_path, monkeypatch):
    import json

    from hexapod_kin.cli import main

    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(tmp_path))
    code = main(["derive", PHANTOMX, "--base", "base_link", "--tip", "tibia_lf", "--json",
                 "--budget", "2"])  # fmt: skip
    out = json.loads(capsys.readouterr().out)
    assert code == 0 or (code == 1 and out["incomplete"])  # 1: the budget ran out first
    assert out["lengths_m"]["l1"] == pytest.approx(0.054, abs=1e-12)
    assert out["lengths_m"]["l2"] == pytest.approx(math.hypot(0.0645, 0.0145), abs=1e-12)
    assert "anti-parallel by 2.65e-06 rad" in out["table_from_urdf"]
    foot = ["--tool", *map(str, PHANTOMX_FOOT[0]), "0", "0", "0"]
    code = main(["scan", PHANTOMX, "--tip", "tibia_lf", *foot, "--grid", "9", "--json",
                 "--family-budget", "2"])  # fmt: skip
    scan = json.loads(capsys.readouterr().out)
    assert code == 0 or (code == 1 and "incomplete" in scan["family_reason"])
    assert len(scan["q"]) == 81
    model = hk.load(PHANTOMX, tip="tibia_lf", tool=PHANTOMX_FOOT)
    # the scan's manipulability is Pinocchio's sqrt(det(J Jᵀ)) of the position rows
    for q, w in list(zip(scan["q"], scan["manipulability"]))[::10]:
        jac = model.jacobian(np.array(q))[:3]
        assert w == pytest.approx(math.sqrt(np.linalg.det(jac @ jac.T)), rel=1e-9, abs=1e-15)


@pytest.mark.filterwarnings("ignore::hexapod_kin.UrdfWarning")
def test_snapped_recovery_keeps_the_robot_name():
    rec = hk.recover_chain(PHANTOMX, base="base_link", tip="tibia_lf", tool=PHANTOMX_FOOT)
    assert rec.snaps and rec.chain.name == hk.load(PHANTOMX).model.name != "chain"
