"""The catalogue: closed forms and the seeds' published numbers."""

from __future__ import annotations

import inspect
import math

import numpy as np
import pytest

from hexapod_kin import Chain, Hexapod, robots, table_fk
from hexapod_kin.exceptions import ParameterError


def test_registry_sorted_and_documented():
    assert list(robots.PRESETS) == sorted(robots.PRESETS)
    for name, func in robots.PRESETS.items():
        doc = inspect.getdoc(func) or ""
        assert "seed" in doc.lower() or name == "hexapod", name
        built = func()
        assert isinstance(built, (Chain, Hexapod))


def hexabot_closed_form(q, l1=0.05, l2=0.10, l3=0.10):
    q1, q2, q3 = q
    rho = l1 + l2 * math.cos(q2) + l3 * math.cos(q2 + q3)
    return np.array(
        [math.cos(q1) * rho, math.sin(q1) * rho, -(l2 * math.sin(q2) + l3 * math.sin(q2 + q3))]
    )


def test_hexabot_leg_closed_form():
    leg = robots.hexabot_leg()
    rng = np.random.default_rng(0)
    for q in rng.uniform(-math.pi, math.pi, (200, 3)):
        np.testing.assert_allclose(table_fk(leg, q)[:3, 3], hexabot_closed_form(q), atol=1e-15)


def test_hexabot_leg_seed001_eq8_rotation():
    # Seed 001 eq. (8): rotation part of T04.
    q1, q2, q3 = 0.2, 0.4, -0.9
    c1, s1, c23, s23 = math.cos(q1), math.sin(q1), math.cos(q2 + q3), math.sin(q2 + q3)
    ref = np.array([[c1 * c23, -c1 * s23, -s1], [s1 * c23, -s1 * s23, c1], [-s23, -c23, 0]])
    np.testing.assert_allclose(
        table_fk(robots.hexabot_leg(), [q1, q2, q3])[:3, :3], ref, atol=1e-15
    )


@pytest.mark.parametrize(
    "t1,t2,expected",
    [(0.0, -30.0, (14.3301, 0.0, -2.5)), (20.0, -30.0, (13.4659, 4.9012, -2.5))],
)
def test_coxa_tibia_seed002_numbers(t1, t2, expected):
    leg = robots.coxa_tibia_leg(10, 5)
    p = table_fk(leg, np.radians([t1, t2]))[:3, 3]
    np.testing.assert_allclose(np.round(p, 4), expected, atol=1e-12)


def test_coxa_tibia_closed_form():
    leg = robots.coxa_tibia_leg(10, 5)
    for t1, t2 in np.random.default_rng(1).uniform(-3, 3, (100, 2)):
        ref = [
            math.cos(t1) * (10 + 5 * math.cos(t2)),
            math.sin(t1) * (10 + 5 * math.cos(t2)),
            5 * math.sin(t2),
        ]
        np.testing.assert_allclose(table_fk(leg, [t1, t2])[:3, 3], ref, atol=1e-13)


def test_scara_closed_form():
    arm = robots.scara(stroke=0.3)
    for t1, t2, t3, d in np.random.default_rng(2).uniform(0, 1, (100, 4)) * [6, 6, 6, 0.3]:
        t = table_fk(arm, [t1, t2, t3, d])
        ref = [
            0.22 * math.cos(t1) + 0.24 * math.cos(t1 + t2),
            0.22 * math.sin(t1) + 0.24 * math.sin(t1 + t2),
            0.4524 - d,
        ]
        np.testing.assert_allclose(t[:3, 3], ref, atol=1e-15)
        # alpha = pi: the tool z axis points down; yaw = -(t1 + t2 + t3) about the tool axis.
        np.testing.assert_allclose(t[:3, 2], [0, 0, -1], atol=1e-15)
        yaw = math.atan2(t[1, 0], t[0, 0])
        assert math.isclose(math.remainder(yaw - (t1 + t2 + t3), 2 * math.pi), 0, abs_tol=1e-12)


def test_pendulum_hangs_down_at_minus_half_pi():
    pend = robots.pendulum(length=0.5)
    np.testing.assert_allclose(table_fk(pend, [-math.pi / 2])[:3, 3], [0, 0, -0.5], atol=1e-15)
    assert pend.joint_damping() == (0.01,)


def test_hexapod_layout():
    hexa = robots.hexapod()
    assert len(hexa.legs) == 6 and hexa.nq == 18
    yaws = [math.degrees(leg.yaw) for leg in hexa.legs]
    np.testing.assert_allclose(yaws, [30, 90, 150, -150, -90, -30])
    for leg in hexa.legs:
        np.testing.assert_allclose(np.linalg.norm(leg.xyz[:2]), 0.12)


def test_get_rejects_unknown_names_and_parameters():
    with pytest.raises(ParameterError, match="presets are"):
        robots.get("nope")
    with pytest.raises(ParameterError, match="parameters are"):
        robots.get("hexabot_leg", l9=1)
    with pytest.raises(ParameterError, match="l1=-1"):
        robots.hexabot_leg(l1=-1)
    assert robots.get("hexabot_leg", l1=0.06).rows[1].d == 0.06
