"""URDF generation: determinism, structure, rpy conversion, the generator's --check."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from lxml import etree

from hexapod_kin import robots, to_urdf
from hexapod_kin.exceptions import ParameterError
from hexapod_kin.urdf import matrix_to_rpy, rpy_to_matrix, write_urdf

ROOT = Path(__file__).resolve().parent.parent


@pytest.mark.parametrize("name", robots.names())
def test_deterministic_and_well_formed(name):
    built = robots.get(name)
    a, b = to_urdf(built), to_urdf(robots.get(name))
    assert a == b
    root = etree.fromstring(a.encode())
    assert root.tag == "robot"
    links = {x.get("name") for x in root.findall("link")}
    for joint in root.findall("joint"):
        assert joint.find("parent").get("link") in links
        assert joint.find("child").get("link") in links
        if joint.get("type") != "fixed":
            assert joint.find("limit") is not None and joint.find("axis").get("xyz") == "0 0 1"
    # every moving link has an inertial and a visual
    for link in root.findall("link"):
        if link.find("inertial") is not None:
            assert float(link.find("inertial/mass").get("value")) > 0


def test_rpy_roundtrip_including_gimbal_lock():
    rng = np.random.default_rng(0)
    angles = list(rng.uniform(-3, 3, (200, 3)))
    angles += [np.array([0.3, math.pi / 2, 0.2]), np.array([-1.0, -math.pi / 2, 0.7])]
    for rpy in angles:
        rot = rpy_to_matrix(*rpy)
        np.testing.assert_allclose(rpy_to_matrix(*matrix_to_rpy(rot)), rot, atol=1e-14)


def test_hexapod_leg_urdf_has_body_and_one_leg():
    text = to_urdf(robots.hexapod(), leg="leg2")
    root = etree.fromstring(text.encode())
    names = [x.get("name") for x in root.findall("joint")]
    assert "leg2_mount" in names and "leg2_knee" in names and not any("leg1" in n for n in names)
    with pytest.raises(ParameterError, match="legs are"):
        to_urdf(robots.hexapod(), leg="leg9")
    with pytest.raises(ParameterError, match="only applies to a Hexapod"):
        to_urdf(robots.hexabot_leg(), leg="leg1")


def test_pendulum_urdf_carries_damping():
    root = etree.fromstring(to_urdf(robots.pendulum(damping=0.01)).encode())
    assert float(root.find("joint/dynamics").get("damping")) == 0.01


def test_write_urdf_atomic_and_loadable(tmp_path):
    path = write_urdf(robots.scara(), tmp_path / "scara.urdf")
    assert path.read_text() == to_urdf(robots.scara())
    assert not list(tmp_path.glob(".*tmp"))


def test_generator_check_passes_on_committed_files():
    res = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "generate_urdf.py"), "--check"],
        capture_output=True,
        text=True,
    )
    assert res.returncode == 0, res.stdout + res.stderr


def test_generator_check_detects_drift(tmp_path):
    gen = [sys.executable, str(ROOT / "tools" / "generate_urdf.py"), "--dir", str(tmp_path)]
    assert subprocess.run(gen, capture_output=True).returncode == 0
    victim = tmp_path / "hexabot_leg.urdf"
    victim.write_text(victim.read_text().replace('velocity="10"', 'velocity="11"', 1))
    res = subprocess.run(gen + ["--check"], capture_output=True, text=True)
    assert res.returncode == 1 and "differs" in res.stdout and "hexabot_leg.urdf" in res.stdout


def test_committed_files_have_headers():
    for path in sorted((ROOT / "urdf").glob("*.urdf")):
        head = path.read_text().splitlines()[1:3]
        assert any("made by: python tools/generate_urdf.py" in h for h in head), path


def test_base_offset_and_tool_exported_as_fixed_joints_and_loaded_equal():
    from hexapod_kin import Chain, DHRow, load, table_fk

    chain = Chain.from_dh(
        [DHRow(0.1, 0.2, 0.3, math.pi / 2), DHRow(0, 0, 0.4, 0), DHRow(0, 0.1, 0, -math.pi / 2)],
        base=((0.1, -0.2, 0.3), (0.2, 0.3, -0.4)),
        tool=((0.0, 0.02, 0.12), (0.0, math.pi / 2, 0.0)),
        tip="tcp",
        name="arm",
    )
    root = etree.fromstring(to_urdf(chain).encode())
    joints = {j.get("name"): j for j in root.findall("joint")}
    off = joints["arm_base_offset"]
    assert off.get("type") == "fixed" and off.find("parent").get("link") == "base"
    assert off.find("child").get("link") == "base_frame0"
    # the origin written is the pose given (xyz, rpy): an independent read of the text
    xyz = [float(v) for v in off.find("origin").get("xyz").split()]
    rpy = [float(v) for v in off.find("origin").get("rpy").split()]
    np.testing.assert_allclose(xyz, (0.1, -0.2, 0.3), atol=1e-15)
    np.testing.assert_allclose(rpy, (0.2, 0.3, -0.4), atol=1e-14)
    tool = joints["tcp_fixed"]
    assert tool.get("type") == "fixed" and tool.find("child").get("link") == "tcp"
    model = load(chain)
    assert model.base == "base" and model.tip == "tcp"
    rng = np.random.default_rng(4)
    for q in rng.uniform(-2, 2, (20, 3)):
        np.testing.assert_allclose(model.fk(q), table_fk(chain, q), atol=1e-13)


def test_one_rpy_convention_for_the_package():
    from hexapod_kin import params, urdf

    assert urdf.rpy_to_matrix is params.rpy_to_matrix
    assert urdf.matrix_to_rpy is params.matrix_to_rpy
