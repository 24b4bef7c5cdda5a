"""PUMA 560, UR5 and Panda from their published DH tables against independent references.

* UR5 and Panda: the example-robot-data URDFs (``erd:ur5_robot``, ``erd:panda``) loaded in
  Pinocchio. The constant base and tool transforms between the published table's frames and
  the URDF's are *fitted* from a few configurations (a hand-eye ``AX = XB`` solve), printed
  (``pytest -s``), then FK and Jacobians compared at 200 random configurations.
* PUMA 560: example-robot-data has no PUMA; the reference is a plain numpy product of the
  published matrices ``Rz(θ)·Tz(d)·Tx(a)·Rx(α)`` written here from elementary rotations, and
  the geometric Jacobian built from it (plus Robotics Toolbox's model when installed).

Tables: standard DH as in Corke's Robotics Toolbox (PUMA 560: ``mdl_puma560``; UR5: Universal
Robots' published DH, d1 = 0.089159 m as in the URDF — the Toolbox's 0.089459 differs by 0.3
mm); Panda: Franka's modified DH (Craig = Khalil–Kleinfinger), flange d = 0.107 m.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import hexapod_kin as hk
from hexapod_kin import Chain, DHRow, KhalilRow, table_fk

PI = math.pi
# (theta offset, d, a, alpha), standard DH
PUMA_DH = [(0, 0, 0, PI / 2), (0, 0, 0.4318, 0), (0, 0.15005, 0.0203, -PI / 2),
           (0, 0.4318, 0, PI / 2), (0, 0, 0, -PI / 2), (0, 0, 0, 0)]  # fmt: skip
UR5_DH = [(0, 0.089159, 0, PI / 2), (0, 0, -0.425, 0), (0, 0, -0.39225, 0),
          (0, 0.10915, 0, PI / 2), (0, 0.09465, 0, -PI / 2), (0, 0.0823, 0, 0)]  # fmt: skip
# Franka: (a_{i-1}, d_i, alpha_{i-1}), modified DH; then the flange (fixed)
PANDA_MDH = [(0, 0.333, 0), (0, 0, -PI / 2), (0, 0.316, PI / 2), (0.0825, 0, PI / 2),
             (-0.0825, 0.384, -PI / 2), (0, 0, PI / 2), (0.088, 0, PI / 2)]  # fmt: skip
PANDA_FLANGE = (0, 0.107, 0)


def _rz(t):
    c, s = math.cos(t), math.sin(t)
    m = np.eye(4)
    m[:2, :2] = [[c, -s], [s, c]]
    return m


def _rx(t):
    c, s = math.cos(t), math.sin(t)
    m = np.eye(4)
    m[1:3, 1:3] = [[c, -s], [s, c]]
    return m


def _tr(x, y, z):
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def _dh_frames(table, q):
    """Independent: frames ^0T_i of a standard-DH table by elementary products."""
    out, t = [np.eye(4)], np.eye(4)
    for (th, d, a, al), qi in zip(table, q):
        t = t @ _rz(th + qi) @ _tr(0, 0, d) @ _tr(a, 0, 0) @ _rx(al)
        out.append(t)
    return out


def _geometric_jacobian(frames, tip):
    """6×n [v; ω] Jacobian of point ``tip`` for revolute joints on the z axes of frames[:-1]."""
    cols = []
    for f in frames[:-1]:
        z, o = f[:3, 2], f[:3, 3]
        cols.append(np.concatenate([np.cross(z, tip - o), z]))
    return np.column_stack(cols)


def _hand_eye(a_list, b_list):
    """Solve ``A X = X B`` for the rigid X (4×4) from pairs (Park–Martin style, linear)."""
    rows = []
    for a, b in zip(a_list, b_list):
        rows.append(np.kron(np.eye(3), a[:3, :3]) - np.kron(b[:3, :3].T, np.eye(3)))
    _, _, vt = np.linalg.svd(np.vstack(rows))
    rx = vt[-1].reshape(3, 3, order="F")
    u, _, vt2 = np.linalg.svd(rx)
    rx = u @ vt2
    if np.linalg.det(rx) < 0:
        rx = -rx
        u, _, vt2 = np.linalg.svd(rx)
        rx = u @ vt2
    lhs = np.vstack([a[:3, :3] - np.eye(3) for a in a_list])
    rhs = np.concatenate([rx @ b[:3, 3] - a[:3, 3] for a, b in zip(a_list, b_list)])
    t = np.linalg.lstsq(lhs, rhs, rcond=None)[0]
    x = np.eye(4)
    x[:3, :3], x[:3, 3] = rx, t
    return x


def _fit_base_tool(table_fk_fn, urdf_fk_fn, qs):
    """Constant B, E with urdf(q) = B · table(q) · E, from a few configurations."""
    ys = [urdf_fk_fn(q) for q in qs]
    cs = [table_fk_fn(q) for q in qs]
    # Y_k^{-1} Y_0 E^{-1} = E^{-1} C_k^{-1} C_0  =>  A X = X B with X = E^{-1}
    a_list = [np.linalg.inv(ys[k]) @ ys[0] for k in range(1, len(qs))]
    b_list = [np.linalg.inv(cs[k]) @ cs[0] for k in range(1, len(qs))]
    e_inv = _hand_eye(a_list, b_list)
    tool = np.linalg.inv(e_inv)
    base = ys[0] @ e_inv @ np.linalg.inv(cs[0])
    return base, tool


def _print_pose(label, t):
    rpy = hk.params.matrix_to_rpy(t[:3, :3])
    print(
        f"{label}: xyz = {np.round(t[:3, 3], 9).tolist()} m, rpy = {np.round(rpy, 9).tolist()} rad"
    )


def _check_arm(name, chain_plain, urdf_source, tip=None, tol=1e-12):
    model = hk.load(urdf_source, tip=tip)
    fit_qs = model.random_q(6, seed=100)
    base, tool = _fit_base_tool(lambda q: table_fk(chain_plain, q), model.fk, fit_qs)
    _print_pose(f"{name}: fitted base T_urdfbase_0", base)
    _print_pose(f"{name}: fitted tool T_n_urdftip", tool)
    fitted = chain_plain.replace(base_pose=base, tool=tool, tip="tcp", link_names=None)
    again = hk.load(fitted)  # through our URDF export and Pinocchio
    worst_fk = worst_jac = worst_again = 0.0
    for q in model.random_q(200, seed=7):
        ref = model.fk(q)
        worst_fk = max(worst_fk, float(np.abs(table_fk(fitted, q) - ref).max()))
        jac_ref = model.jacobian(q, "local_world_aligned")
        worst_again = max(worst_again, float(np.abs(again.fk(q) - ref).max()))
        worst_jac = max(
            worst_jac, float(np.abs(again.jacobian(q, "local_world_aligned") - jac_ref).max())
        )
    print(f"{name}: 200 q: max|FK - URDF| = {worst_fk:.1e}, via our URDF {worst_again:.1e}, "
          f"max|J - J_URDF| = {worst_jac:.1e}")  # fmt: skip
    assert worst_fk < tol and worst_again < tol and worst_jac < tol
    return model, fitted, base, tool


def test_ur5_dh_equals_example_robot_data():
    chain = Chain.from_dh([DHRow(*row) for row in UR5_DH], name="ur5")
    # The URDF writes pi/2 as 1.57079632679 (5e-12 rad off): agreement to 1e-10, not 1e-12.
    model, fitted, base, tool = _check_arm("UR5", chain, "erd:ur5_robot", tol=1e-10)
    # Jacobian by an independent numpy product of the published matrices, mapped by the fit
    for q in model.random_q(200, seed=8):
        frames = [base @ f for f in _dh_frames(UR5_DH, q)]
        tip = (frames[-1] @ tool)[:3, 3]
        np.testing.assert_allclose(
            _geometric_jacobian(frames, tip), model.jacobian(q, "local_world_aligned"), atol=1e-10
        )
    # the URDF's base is the DH base turned by pi about z (a known UR convention)
    assert abs(abs(hk.params.matrix_to_rpy(base[:3, :3])[2]) - PI) < 1e-9


def test_panda_modified_dh_equals_example_robot_data():
    rows = [KhalilRow("revolute", al, a, 0.0, d) for a, d, al in PANDA_MDH]
    rows.append(KhalilRow("fixed", PANDA_FLANGE[2], PANDA_FLANGE[0], 0.0, PANDA_FLANGE[1]))
    chain = Chain(rows=tuple(rows), name="panda")
    _, _, base, tool = _check_arm("Panda", chain, "erd:panda", tip="panda_link8")
    # Franka's table is the URDF's frames: base and tool fit to the identity
    np.testing.assert_allclose(base, np.eye(4), atol=1e-9)
    np.testing.assert_allclose(tool, np.eye(4), atol=1e-9)


def test_puma560_dh_equals_numpy_product_of_published_matrices():
    chain = Chain.from_dh([DHRow(*row) for row in PUMA_DH], name="puma560")
    model = hk.load(chain)
    rng = np.random.default_rng(9)
    for q in rng.uniform(-PI, PI, (200, 6)):
        frames = _dh_frames(PUMA_DH, q)
        np.testing.assert_allclose(table_fk(chain, q), frames[-1], atol=1e-12)
        np.testing.assert_allclose(model.fk(q), frames[-1], atol=1e-12)
        jac = _geometric_jacobian(frames, frames[-1][:3, 3])
        np.testing.assert_allclose(model.jacobian(q, "local_world_aligned"), jac, atol=1e-12)


def test_puma560_against_robotics_toolbox_with_fitted_base():
    rtb = pytest.importorskip("roboticstoolbox")
    puma = rtb.models.DH.Puma560()
    chain = Chain.from_dh([DHRow(*row) for row in PUMA_DH], name="puma560")
    qs = np.random.default_rng(10).uniform(-PI, PI, (6, 6))
    base, tool = _fit_base_tool(lambda q: table_fk(chain, q), lambda q: puma.fkine(q).A, qs)
    _print_pose("PUMA 560 vs Robotics Toolbox: fitted base", base)
    _print_pose("PUMA 560 vs Robotics Toolbox: fitted tool", tool)
    fitted = chain.replace(base_pose=base, tool=tool, tip="tcp", link_names=None)
    model = hk.load(fitted)
    for q in np.random.default_rng(11).uniform(-PI, PI, (200, 6)):
        np.testing.assert_allclose(model.fk(q), puma.fkine(q).A, atol=1e-12)
        np.testing.assert_allclose(
            model.jacobian(q, "local_world_aligned"), puma.jacob0(q), atol=1e-12
        )
    # Corke's model stands the shoulder 26.45 inch above the mounting surface
    np.testing.assert_allclose(base[:3, 3], (0, 0, 26.45 * 0.0254), atol=1e-9)


def test_fit_recovers_a_known_base_and_tool():
    chain = Chain.from_dh([DHRow(*row) for row in UR5_DH])
    b = hk.Pose.of(((0.1, -0.2, 0.3), (0.4, -0.5, 0.6))).matrix
    e = hk.Pose.of(((0.01, 0.02, 0.15), (1.0, 0.2, -0.3))).matrix
    qs = np.random.default_rng(12).uniform(-PI, PI, (6, 6))
    base, tool = _fit_base_tool(
        lambda q: table_fk(chain, q), lambda q: b @ table_fk(chain, q) @ e, qs
    )
    np.testing.assert_allclose(base, b, atol=1e-10)
    np.testing.assert_allclose(tool, e, atol=1e-10)
