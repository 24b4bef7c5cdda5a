"""Parameter tables: transforms, validation, standard DH -> Khalil conversion."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hexapod_kin import (
    Chain,
    DHRow,
    HexapodKinError,
    Inertial,
    JointLimits,
    KhalilRow,
    table_fk,
    table_transforms,
)
from hexapod_kin._table_kin import table_position_jacobian
from hexapod_kin.exceptions import ConfigurationError, ParameterError
from hexapod_kin.params import dh_transform, khalil_transform, rod_inertial


def rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def tx(d):
    t = np.eye(4)
    t[0, 3] = d
    return t


def tz(d):
    t = np.eye(4)
    t[2, 3] = d
    return t


def test_khalil_transform_is_product_of_elementary_transforms():
    rng = np.random.default_rng(0)
    for _ in range(50):
        a, d, th, r = rng.uniform(-3, 3, 4)
        ref = rx(a) @ tx(d) @ rz(th) @ tz(r)
        np.testing.assert_allclose(khalil_transform(a, d, th, r), ref, atol=1e-15)


def test_dh_transform_is_product_of_elementary_transforms():
    rng = np.random.default_rng(1)
    for _ in range(50):
        th, d, a, al = rng.uniform(-3, 3, 4)
        ref = rz(th) @ tz(d) @ tx(a) @ rx(al)
        np.testing.assert_allclose(dh_transform(th, d, a, al), ref, atol=1e-15)


def test_seed_001_equation_3_row_2():
    # Seed 001 eq. (3): T12 with alpha = -pi/2, d = L1.
    q2, l1 = 0.3, 0.05
    t = KhalilRow("revolute", -math.pi / 2, l1, 0.0, 0.0).transform(q2)
    c, s = math.cos(q2), math.sin(q2)
    ref = np.array([[c, -s, 0, l1], [0, 0, 1, 0], [-s, -c, 0, 0], [0, 0, 0, 1]])
    np.testing.assert_allclose(t, ref, atol=1e-15)


@pytest.mark.parametrize(
    "sigma,expected",
    [(0, "revolute"), (1, "prismatic"), (2, "fixed"), ("Revolute", "revolute"), ("p", "prismatic")],
)
def test_sigma_accepts_codes_and_names(sigma, expected):
    assert KhalilRow(sigma).sigma == expected


def test_prismatic_variable_adds_to_r():
    row = KhalilRow("prismatic", 0.2, 0.1, 0.3, 0.05)
    np.testing.assert_allclose(row.transform(0.2), khalil_transform(0.2, 0.1, 0.3, 0.25))


@pytest.mark.parametrize(
    "make,fragment",
    [
        (lambda: KhalilRow(3), "sigma=3"),
        (lambda: KhalilRow("revolute", float("nan")), "KhalilRow.alpha=nan"),
        (lambda: KhalilRow("revolute", 0, float("inf")), "KhalilRow.d=inf"),
        (lambda: KhalilRow("revolute", 0, "x"), "not a number"),
        (lambda: JointLimits(1.0, -1.0), "lower=1.0 > upper=-1.0"),
        (lambda: JointLimits(velocity=-1), "must be >= 0"),
        (lambda: Inertial(mass=-1.0), "mass=-1.0"),
        (lambda: Inertial(mass=1.0, inertia=(1, 1, -1, 0, 0, 0)), "not positive definite"),
        (lambda: Inertial(mass=1.0, inertia=(1, 1, 3, 0, 0, 0)), "triangle"),
        (lambda: Chain(rows=()), "empty"),
        (lambda: Chain(rows=(KhalilRow("fixed"),)), "nothing moves"),
        (lambda: Chain(rows=(KhalilRow(0),), joint_names=("a", "b")), "2 names"),
        (lambda: Chain(rows=(KhalilRow(0),), joint_names=("bad name",)), "not a valid name"),
        (lambda: Chain(rows=(KhalilRow(0),), link_mass=0), "link_mass=0"),
        (lambda: Chain(rows=(KhalilRow(0), KhalilRow(0)), joint_names=("a", "a")), "unique"),
        (lambda: Chain(rows=(DHRow(),)), "not a KhalilRow"),
    ],
)
def test_validation_errors_name_field_and_value(make, fragment):
    with pytest.raises(ParameterError) as info:
        make()
    assert fragment in str(info.value)
    assert isinstance(info.value, HexapodKinError)


def test_table_fk_checks_q():
    chain = Chain(rows=(KhalilRow(0), KhalilRow(0, 0, 1.0)))
    with pytest.raises(ConfigurationError, match="2 joints"):
        table_fk(chain, [0.0])
    with pytest.raises(ConfigurationError, match="non-finite"):
        table_fk(chain, [0.0, float("nan")])


def _random_dh(rng, n):
    rows = []
    for _ in range(n):
        sigma = rng.choice(["revolute", "prismatic"])
        rows.append(DHRow(*rng.uniform(-2, 2, 4), sigma=sigma))
    return rows


def test_standard_dh_to_khalil_gives_identical_fk():
    rng = np.random.default_rng(7)
    for _ in range(50):
        n = int(rng.integers(1, 7))
        dh = _random_dh(rng, n)
        chain = Chain.from_dh(dh)
        assert chain.nq == n and len(chain.rows) == n + 1
        for _ in range(4):
            q = rng.uniform(-3, 3, n)
            ref = np.eye(4)
            for row, qi in zip(dh, q):
                ref = ref @ row.transform(qi)
            np.testing.assert_allclose(table_fk(chain, q), ref, atol=1e-12)


def test_table_transforms_product_equals_table_fk():
    chain = Chain.from_dh(_random_dh(np.random.default_rng(3), 4))
    q = np.linspace(-1, 1, 4)
    prod = np.eye(4)
    for t in table_transforms(chain, q):
        prod = prod @ t
    np.testing.assert_allclose(prod, table_fk(chain, q), atol=1e-15)


def test_rod_inertial_matches_closed_form():
    inn = rod_inertial(np.zeros(3), np.array([0.0, 0.0, 2.0]), 3.0, 0.1)
    assert inn.com == (0.0, 0.0, 1.0)
    ixx = 3.0 * (3 * 0.01 + 4.0) / 12
    np.testing.assert_allclose(inn.matrix(), np.diag([ixx, ixx, 0.5 * 3.0 * 0.01]), atol=1e-15)


def test_chain_is_frozen():
    chain = Chain(rows=(KhalilRow(0),))
    with pytest.raises(AttributeError):
        chain.name = "x"  # type: ignore[misc]


def test_readme_example_khalil_equals_dh():
    from math import pi

    khalil = Chain(
        rows=(
            KhalilRow(0, 0, 0, 0, 0),
            KhalilRow(0, -pi / 2, 0.05, 0, 0),
            KhalilRow(0, 0, 0.10, 0, 0),
            KhalilRow("fixed", 0, 0.10, 0, 0),
        )
    )
    dh = Chain.from_dh([DHRow(0, 0, 0.05, -pi / 2), DHRow(0, 0, 0.10, 0), DHRow(0, 0, 0.10, 0)])
    for q in np.random.default_rng(9).uniform(-3, 3, (20, 3)):
        np.testing.assert_allclose(table_fk(khalil, q), table_fk(dh, q), atol=1e-15)


# ------------------------------------------------------------------ poses, base and tool
def _rot_x(a):
    return rx(a)[:3, :3]


def _rot_y(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rot_z(a):
    return rz(a)[:3, :3]


def test_rpy_is_fixed_axis_xyz_as_urdf():
    from hexapod_kin.params import matrix_to_rpy, rpy_to_matrix

    rng = np.random.default_rng(11)
    for _ in range(50):
        r, p, y = rng.uniform(-3, 3, 3)
        ref = _rot_z(y) @ _rot_y(p) @ _rot_x(r)  # fixed axes: x first, then y, then z
        np.testing.assert_allclose(rpy_to_matrix(r, p, y), ref, atol=1e-15)
        np.testing.assert_allclose(rpy_to_matrix(*matrix_to_rpy(ref)), ref, atol=1e-14)


def test_pose_from_matrix_and_xyz_rpy_agree():
    from hexapod_kin.params import Pose

    xyz, rpy = (0.1, -0.2, 0.3), (0.4, -0.5, 0.6)
    t = np.eye(4)
    t[:3, :3] = _rot_z(0.6) @ _rot_y(-0.5) @ _rot_x(0.4)
    t[:3, 3] = xyz
    a, b = Pose.of(t), Pose.of((xyz, rpy))
    np.testing.assert_allclose(a.matrix, t, atol=0)
    np.testing.assert_allclose(b.matrix, t, atol=1e-15)
    np.testing.assert_allclose(a.rpy, rpy, atol=1e-14)
    assert Pose.of(a) is a and Pose().is_identity
    d = a.to_dict()
    assert d["xyz"] == list(xyz) and len(d["matrix"]) == 4


@pytest.mark.parametrize(
    "value,fragment",
    [
        (np.eye(3), "give a 4x4"),
        ("abc", "give a 4x4"),
        (np.diag([1.0, 1.0, 2.0, 1.0]), "not a rotation"),
        (np.diag([1.0, 1.0, -1.0, 1.0]), "not a rotation"),
        (np.vstack([np.eye(4)[:3], [0, 0, 1, 1]]), "0 0 0 1"),
        (((0, 0, float("nan")), (0, 0, 0)), "finite"),
    ],
)
def test_pose_refuses_non_poses(value, fragment):
    with pytest.raises(ParameterError, match=fragment):
        Chain(rows=(KhalilRow(0),), tool=value)


def _pose(xyz, rpy):
    t = np.eye(4)
    t[:3, :3] = _rot_z(rpy[2]) @ _rot_y(rpy[1]) @ _rot_x(rpy[0])
    t[:3, 3] = xyz
    return t


def test_base_and_tool_wrap_the_table_product():
    rng = np.random.default_rng(5)
    base, tool = _pose((0.1, 0.2, 0.3), (0.3, -0.2, 1.0)), _pose((0, 0.05, 0.1), (0, 0.7, 0))
    for _ in range(10):
        dh = _random_dh(rng, 4)
        plain = Chain.from_dh(dh)
        framed = Chain.from_dh(dh, base=base, tool=(tool[:3, 3], (0, 0.7, 0)), tip="tcp")
        assert framed.base == "base" and framed.tip == "tcp" and framed.base_pose is not None
        assert framed.link_names[-1] == "link5" and framed.frame0_link == "base_frame0"
        q = rng.uniform(-2, 2, 4)
        ref = np.eye(4)
        for row, qi in zip(dh, q):
            ref = ref @ row.transform(qi)
        np.testing.assert_allclose(table_fk(framed, q), base @ ref @ tool, atol=1e-12)
        np.testing.assert_allclose(table_fk(plain, q), ref, atol=1e-12)


def test_position_jacobian_with_base_and_tool_matches_finite_differences():

    rng = np.random.default_rng(6)
    rows = tuple(KhalilRow(s, *rng.uniform(-2, 2, 4)) for s in (0, 1, 0, 0, 0))  # ends on a joint
    chain = Chain(
        rows=rows, base=((0.1, 0, 0.2), (0.5, 0.1, -0.3)), tool=((0.1, 0.2, 0.3), (1, 2, 3))
    )
    q = rng.uniform(-2, 2, 5)
    h = 1e-6
    fd = np.column_stack(
        [
            (table_fk(chain, q + h * e)[:3, 3] - table_fk(chain, q - h * e)[:3, 3]) / (2 * h)
            for e in np.eye(5)
        ]
    )
    np.testing.assert_allclose(table_position_jacobian(chain, q), fd, atol=1e-8)


def test_identity_base_is_no_base_and_base_given_twice_is_refused():
    chain = Chain(rows=(KhalilRow(0),), base=np.eye(4))
    assert chain.base_pose is None and chain.base == "base"
    with pytest.raises(ParameterError, match="once"):
        Chain(rows=(KhalilRow(0),), base=np.eye(4), base_pose=((1, 0, 0), (0, 0, 0)))
    with pytest.raises(ParameterError, match="unique"):
        Chain(rows=(KhalilRow(0),), tool=np.eye(4), tip="link1")


def test_rodrigues_matches_pinocchio_exp3():
    import pinocchio as pin

    from hexapod_kin._pose import rodrigues

    rng = np.random.default_rng(3)
    for _ in range(20):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        angle = rng.uniform(-math.pi, math.pi)
        got = rodrigues(axis, math.sin(angle), math.cos(angle))
        np.testing.assert_allclose(got, pin.exp3(axis * angle), atol=1e-14)


@pytest.mark.parametrize("value", [True, "x", None, float("nan"), float("inf")])
def test_finite_refuses_non_numbers_naming_the_parameter(value):
    from hexapod_kin.exceptions import finite

    with pytest.raises(ParameterError, match="^speed=") as err:
        finite("speed", value)
    assert err.value.parameter == "speed"
    assert err.value.allowed == "finite"


def test_finite_and_positive_return_floats():
    from hexapod_kin.exceptions import finite, positive

    assert finite("x", np.float32(0.5)) == 0.5 and type(finite("x", 2)) is float
    assert positive("x", 0, allow_zero=True) == 0.0
    with pytest.raises(ParameterError, match=r"> 0"):
        positive("x", 0)
    assert positive("x", 2, at_most=2.0) == 2.0
    with pytest.raises(ParameterError, match=r"^x=2\.5 .*> 0 and <= 2 ") as err:
        positive("x", 2.5, at_most=2.0)
    assert err.value.allowed == "finite > 0 and <= 2"
    with pytest.raises(ParameterError, match="not a number"):
        KhalilRow("revolute", True)
