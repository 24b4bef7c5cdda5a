"""Pinocchio FK / Jacobians of the generated URDFs against independent references."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import hexapod_kin as hk
from hexapod_kin import robots, table_fk
from hexapod_kin.exceptions import ConfigurationError, FrameNotFoundError, ParameterError
from hexapod_kin.kinematics import direct_jacobian, indirect_jacobian
from hexapod_kin.params import Chain, Hexapod

CHAINS = [n for n in robots.names() if isinstance(robots.get(n), Chain)]
REFERENCES = ["local", "world", "local_world_aligned"]


def _hexapod_fk(hexa: Hexapod, leg_index: int, q18):
    leg = hexa.legs[leg_index]
    q = q18[3 * leg_index : 3 * leg_index + 3]
    return leg.transform() @ table_fk(leg.chain, q)


@pytest.mark.parametrize("name", CHAINS)
def test_pinocchio_fk_equals_table_fk(name, preset_models):
    model = preset_models[name]
    chain = model.params
    rng = np.random.default_rng(0)
    for q in rng.uniform(model.lower, model.upper, (200, model.nq)):
        np.testing.assert_allclose(model.fk(q), table_fk(chain, q), atol=1e-12, rtol=0)


@pytest.mark.parametrize("name", CHAINS)
def test_transforms_are_the_table_rows(name, preset_models):
    model = preset_models[name]
    chain = model.params
    q = np.random.default_rng(1).uniform(model.lower, model.upper)
    rel = model.transforms(q)
    ref = hk.table_transforms(chain, q)
    assert len(rel) == len(chain.rows)
    for a, b in zip(rel, ref):
        np.testing.assert_allclose(a, b, atol=1e-12)
    cum = model.cumulative_transforms(q)
    np.testing.assert_allclose(cum[-1], model.fk(q), atol=1e-12)


def test_hexapod_every_foot_equals_mount_times_table(preset_models):
    model = preset_models["hexapod"]
    hexa = model.params
    rng = np.random.default_rng(2)
    for q in rng.uniform(model.lower, model.upper, (200, 18)):
        for i, foot in enumerate(hexa.foot_frames):
            np.testing.assert_allclose(
                model.placement(q, foot), _hexapod_fk(hexa, i, q), atol=1e-12
            )


@pytest.mark.parametrize("leg", ["leg1", "leg4"])
def test_hexapod_per_leg_urdf(leg):
    hexa = robots.hexapod()
    model = hk.load(hk.to_urdf(hexa, leg=leg), tip=f"{leg}_foot")
    i = int(leg[3:]) - 1
    for q in np.random.default_rng(3).uniform(-3, 3, (50, 3)):
        ref = hexa.legs[i].transform() @ table_fk(hexa.legs[i].chain, q)
        np.testing.assert_allclose(model.fk(q), ref, atol=1e-12)


@pytest.mark.parametrize("name", [*CHAINS, "hexapod"])
@pytest.mark.parametrize("reference", REFERENCES)
def test_jacobian_equals_central_differences(name, reference, preset_models):
    model = preset_models[name]
    rng = np.random.default_rng(4)
    h = 1e-6
    for q in rng.uniform(model.lower, model.upper, (10, model.nq)):
        jac = model.jacobian(q, reference)
        m0 = pin.SE3(model.fk(q))
        fd = np.zeros_like(jac)
        for j in range(model.nq):
            dq = np.zeros(model.nq)
            dq[j] = h
            mp, mm = pin.SE3(model.fk(q + dq)), pin.SE3(model.fk(q - dq))
            if reference == "local":
                tw = pin.log6(m0.inverse() * mp).vector - pin.log6(m0.inverse() * mm).vector
            elif reference == "world":
                tw = pin.log6(mp * m0.inverse()).vector - pin.log6(mm * m0.inverse()).vector
            else:
                v = mp.translation - mm.translation
                w = pin.log3(mp.rotation @ m0.rotation.T) - pin.log3(mm.rotation @ m0.rotation.T)
                tw = np.concatenate([v, w])
            fd[:, j] = tw / (2 * h)
        np.testing.assert_allclose(jac, fd, atol=1e-7)


@pytest.mark.parametrize("name", CHAINS)
def test_direct_and_indirect_methods_equal_pinocchio(name, preset_models):
    model = preset_models[name]
    for q in np.random.default_rng(5).uniform(model.lower, model.upper, (30, model.nq)):
        jp = model.position_jacobian(q)
        np.testing.assert_allclose(direct_jacobian(model, q), jp, atol=1e-12)
        np.testing.assert_allclose(indirect_jacobian(model, q), jp, atol=1e-12)


def test_seed001_eq15_jacobian(preset_models):
    model = preset_models["hexabot_leg"]
    l1, l2, l3 = 0.05, 0.10, 0.10
    for q1, q2, q3 in np.random.default_rng(6).uniform(-3, 3, (50, 3)):
        c1, s1, c2, s2 = math.cos(q1), math.sin(q1), math.cos(q2), math.sin(q2)
        c23, s23 = math.cos(q2 + q3), math.sin(q2 + q3)
        rho = l1 + c2 * l2 + c23 * l3
        ref = np.array(
            [
                [-s1 * rho, -c1 * (s2 * l2 + s23 * l3), -c1 * s23 * l3],
                [c1 * rho, -s1 * (s2 * l2 + s23 * l3), -s1 * s23 * l3],
                [0.0, -c2 * l2 - c23 * l3, -c23 * l3],
            ]
        )
        np.testing.assert_allclose(model.position_jacobian([q1, q2, q3]), ref, atol=1e-15)


def test_solo12_leg_equals_raw_pinocchio():
    from hexapod_kin.sources import erd_path

    model = hk.load("erd:solo12", tip="FL_FOOT")
    assert model.joint_names == ("FL_HAA", "FL_HFE", "FL_KFE")
    raw = pin.buildModelFromUrdf(str(erd_path("solo12")))
    data = raw.createData()
    fid = raw.getFrameId("FL_FOOT")
    idx = [raw.joints[raw.getJointId(n)].idx_q for n in model.joint_names]
    rng = np.random.default_rng(7)
    for q3 in rng.uniform(-2, 2, (50, 3)):
        q = pin.neutral(raw)
        q[idx] = q3
        pin.framesForwardKinematics(raw, data, q)
        np.testing.assert_allclose(model.fk(q3), data.oMf[fid].homogeneous, atol=1e-12)
        for ref in REFERENCES:
            jraw = pin.computeFrameJacobian(raw, data, q, fid, hk.kinematics.REFERENCES[ref])
            np.testing.assert_allclose(model.jacobian(q3, ref), jraw[:, idx], atol=1e-12)


def test_solo12_subchain_with_base_expresses_in_base():
    full = hk.load("erd:solo12", tip="FL_FOOT")
    sub = hk.load("erd:solo12", base="FL_SHOULDER", tip="FL_FOOT", q_ref=None)
    # FL_HAA locked at 0: the shoulder is fixed; the foot pose in the shoulder frame.
    q = np.array([0.0, 0.4, -0.9])
    o_m_s = full.placement(q, "FL_SHOULDER")
    np.testing.assert_allclose(sub.fk(q[1:]), np.linalg.solve(o_m_s, full.fk(q)), atol=1e-12)
    j_full = full.jacobian(q, "local_world_aligned")[:, 1:]
    rot = o_m_s[:3, :3].T
    np.testing.assert_allclose(sub.jacobian(q[1:])[:3], rot @ j_full[:3], atol=1e-12)
    np.testing.assert_allclose(
        sub.jacobian(q[1:], "local"), full.jacobian(q, "local")[:, 1:], atol=1e-12
    )


def test_bad_inputs_raise_clear_errors(preset_models):
    model = preset_models["hexabot_leg"]
    with pytest.raises(ConfigurationError, match=r"expected \(3,\)"):
        model.fk([0.0, 0.0])
    with pytest.raises(ConfigurationError, match="non-finite"):
        model.fk([0.0, float("nan"), 0.0])
    with pytest.raises(ConfigurationError, match="non-finite"):
        model.jacobian(np.array([0.0, np.inf, 0.0]))
    with pytest.raises(ParameterError, match="reference='base'"):
        model.jacobian([0, 0, 0], "base")
    with pytest.raises(FrameNotFoundError, match="'foot'"):
        model.placement([0, 0, 0], "toe")
    with pytest.raises(FrameNotFoundError, match="frames are"):
        hk.load("hexabot_leg", tip="toe")
    np.testing.assert_allclose(model.fk((0.0, 0.0, 0.0))[:3, 3], [0.25, 0, 0])


def test_outputs_are_fresh_arrays(preset_models):
    model = preset_models["hexabot_leg"]
    q = np.array([0.1, 0.2, 0.3])
    a = model.fk(q)
    a[:] = 0
    assert model.fk(q)[3, 3] == 1.0
    j = model.jacobian(q)
    kept = j.copy()
    j[:] = 0
    assert np.array_equal(model.jacobian(q), kept)  # the caller's zeros reached nothing inside
    # and that Jacobian is FK's: central differences of the foot position
    h = 1e-6
    fd = np.column_stack(
        [(model.fk(q + h * e)[:3, 3] - model.fk(q - h * e)[:3, 3]) / (2 * h) for e in np.eye(3)]
    )
    np.testing.assert_allclose(kept[:3], fd, atol=1e-8)


def test_text_and_file_load_to_the_same_model(tmp_path):
    text = hk.to_urdf(robots.scara())
    path = tmp_path / "scara.urdf"
    path.write_text(text)
    a, b, c = hk.load(text), hk.load(path), hk.load(str(path))
    q = np.array([0.3, -0.5, 0.2, 0.05])
    for m in (b, c):
        assert m.joint_names == a.joint_names
        np.testing.assert_array_equal(m.fk(q), a.fk(q))
        np.testing.assert_array_equal(m.jacobian(q), a.jacobian(q))


@pytest.mark.parametrize(
    "source,kw", [("hexapod", {"tip": "leg4_foot"}), ("erd:solo12", {"tip": "FL_FOOT"})]
)
def test_indirect_method_on_urdf_chains(source, kw):
    model = hk.load(source, **kw)
    for q in model.random_q(20, seed=8):
        np.testing.assert_allclose(
            indirect_jacobian(model, q), model.position_jacobian(q), atol=1e-12
        )
        np.testing.assert_allclose(
            direct_jacobian(model, q), model.position_jacobian(q), atol=1e-12
        )


def test_chain_from_rows_names_the_row():
    from hexapod_kin.params import chain_from_rows

    chain = chain_from_rows([(0, 0, 0, 0, 0), (0, -math.pi / 2, 0.05, 0, 0), (2, 0, 0.1, 0, 0)])
    assert chain.nq == 2
    with pytest.raises(ParameterError, match=r"row 2: KhalilRow.d=nan"):
        chain_from_rows([(0, 0, 0, 0, 0), (0, 0, float("nan"), 0, 0)])
    with pytest.raises(ParameterError, match=r"row 1: 4 values"):
        chain_from_rows([(0, 0, 0, 0)])


def test_model_and_data_cannot_be_repaired(preset_models):
    import pinocchio as pin

    model = preset_models["hexabot_leg"]
    other = hk.load("scara")
    with pytest.raises(ParameterError, match="read-only"):
        model.data = other.data
    with pytest.raises(ParameterError, match="read-only"):
        model.model = other.model
    assert isinstance(model.data, pin.Data) and model.data.oMi.__len__() == model.model.njoints


# ------------------------------------------------------------------ batch calls (issue 11)
@pytest.mark.parametrize(
    ("source", "kw"),
    [
        ("hexabot_leg", {}),
        ("scara", {}),
        ("hexapod", {"tip": "leg4_foot"}),
        ("erd:ur5_robot", {}),
        ("erd:panda", {}),
        ("erd:solo12", {"tip": "HR_FOOT"}),
    ],
)
def test_batch_calls_equal_a_pinocchio_loop(source, kw):
    model = hk.load(source, **kw)
    qs = model.random_q(150, seed=3)
    m, d = model.model, model.model.createData()  # raw Pinocchio, its own Data
    base_inv = model.baseMo
    poses = model.fk_batch(qs)
    assert poses.shape == (150, 4, 4)
    refs = {
        "local_world_aligned": pin.ReferenceFrame.LOCAL_WORLD_ALIGNED,
        "world": pin.ReferenceFrame.WORLD,
        "local": pin.ReferenceFrame.LOCAL,
    }
    jacs = {ref: model.jacobian_batch(qs, ref) for ref in refs}
    both = model.fk_jacobian_batch(qs, "world")
    for i, q in enumerate(qs):
        pin.forwardKinematics(m, d, q)
        omf = pin.updateFramePlacement(m, d, model.tip_id)
        np.testing.assert_allclose(poses[i], (base_inv * omf).homogeneous, rtol=0, atol=1e-12)
        for ref, pref in refs.items():
            jac = pin.computeFrameJacobian(m, d, q, model.tip_id, pref)
            if ref == "world":
                jac = base_inv.action @ jac
            elif ref == "local_world_aligned":
                rot = base_inv.rotation
                jac = np.vstack([rot @ jac[:3], rot @ jac[3:]])
            np.testing.assert_allclose(jacs[ref][i], jac, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(both[0], poses)
    np.testing.assert_array_equal(both[1], jacs["world"])


def test_batch_calls_check_their_input():
    from hexapod_kin.exceptions import ConfigurationError, ParameterError

    model = hk.load("hexabot_leg")
    assert model.fk_batch([0.1, 0.2, 0.3]).shape == (1, 4, 4)
    with pytest.raises(ConfigurationError, match="shape"):
        model.fk_batch(np.zeros((5, 4)))
    with pytest.raises(ConfigurationError, match="non-finite"):
        model.jacobian_batch([[0.0, np.nan, 0.0]])
    with pytest.raises(ParameterError, match="reference"):
        model.jacobian_batch(np.zeros((2, 3)), "body")
    assert model.fk_batch(np.zeros((0, 3))).shape == (0, 4, 4)


# ------------------------------------------------------------------ tool offsets
@pytest.mark.parametrize("source", ["hexabot_leg", "erd:ur5_robot"])
def test_tool_offset_composes_with_the_flange(source):
    xyz, rpy = np.array([0.01, -0.02, 0.15]), np.array([0.3, -0.2, 1.1])
    plain = hk.load(source)
    tooled = hk.load(source, tool=(xyz, rpy))
    tool = np.eye(4)
    tool[:3, :3] = pin.rpy.rpyToMatrix(*rpy)
    tool[:3, 3] = xyz
    np.testing.assert_allclose(tooled.tool, tool, atol=1e-15)
    assert tooled.flange == plain.tip and tooled.tip == f"{plain.tip}_tool"
    for q in plain.random_q(20, seed=4):
        np.testing.assert_allclose(tooled.fk(q), plain.fk(q) @ tool, atol=1e-12)
        # Jacobian of the tool point by finite differences of fk (independent of Pinocchio's J)
        jac = tooled.jacobian(q)
        eps = 1e-6
        for k in range(plain.nq):
            dq = np.zeros(plain.nq)
            dq[k] = eps
            dp = (tooled.fk(q + dq)[:3, 3] - tooled.fk(q - dq)[:3, 3]) / (2 * eps)
            np.testing.assert_allclose(jac[:3, k], dp, atol=1e-7)
    qs = plain.random_q(30, seed=5)
    np.testing.assert_allclose(tooled.fk_batch(qs), plain.fk_batch(qs) @ tool, atol=1e-12)
    same = hk.load(source, tool=tool)  # 4x4 form
    np.testing.assert_allclose(same.fk(qs[0]), tooled.fk(qs[0]), atol=1e-15)


@pytest.mark.parametrize(
    "bad",
    [
        np.eye(3),
        np.diag([1.0, 1.0, -1.0, 1.0]),
        [1, 2],
        "abc",
        [0, 0, 0, np.nan, 0, 0],
        {"xyz": [0, 0, 0], "rot": [0, 0, 0]},
    ],
)
def test_tool_offset_refuses_non_rigid(bad):
    from hexapod_kin.exceptions import ParameterError

    with pytest.raises(ParameterError) as info:
        hk.load("hexabot_leg", tool=bad)
    assert info.value.parameter == "tool"


def test_batch_out_buffers_are_filled_and_checked():
    from hexapod_kin.exceptions import ParameterError

    model = hk.load("scara")
    qs = model.random_q(40, seed=9)
    buf = np.full((40, 4, 4), np.nan)
    assert model.fk_batch(qs, out=buf) is buf
    np.testing.assert_array_equal(buf, model.fk_batch(qs))
    jbuf = np.empty((40, 6, model.nq))
    assert model.jacobian_batch(qs, "local", out=jbuf) is jbuf
    np.testing.assert_array_equal(jbuf, model.jacobian_batch(qs, "local"))
    for bad in (
        np.empty((39, 4, 4)),
        np.empty((40, 4, 4), dtype=np.float32),
        np.empty((40, 4, 4), order="F")[:, :, :],
        np.empty((4, 4, 40)).T,
    ):
        with pytest.raises(ParameterError, match="out"):
            model.fk_batch(qs, out=bad)
