"""Workspace sampling and volume, against closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hexapod_kin import Chain, KhalilRow, load
from hexapod_kin.exceptions import ParameterError
from hexapod_kin.singularity import reach, scan
from hexapod_kin.workspace import cross_section, workspace


def test_workspace_volume_against_closed_forms():
    # l1 = 0: the reachable set is a spherical shell |l2 - l3| <= r <= l2 + l3
    shell = Chain(
        rows=(
            KhalilRow("revolute", 0, 0, 0, 0),
            KhalilRow("revolute", -math.pi / 2, 0, 0, 0),
            KhalilRow("revolute", 0, 0.1, 0, 0),
            KhalilRow("fixed", 0, 0.06, 0, 0),
        ),
        name="shell",
    )
    exact = 4 / 3 * math.pi * (0.16**3 - 0.04**3)
    ws = workspace(shell, samples=1_500_000, seed=2)
    assert ws.volume == pytest.approx(exact, rel=0.06)
    assert ws.volume_occupied > ws.volume
    r = np.linalg.norm(ws.points, axis=1)
    assert r.min() >= 0.04 - 1e-12 and r.max() <= 0.16 + 1e-12
    # hexabot leg: the disc of radius l2 + l3 centred l1 from the hip axis, revolved
    from scipy.integrate import quad

    c, rad = 0.05, 0.2
    exact_leg = quad(
        lambda x: 2 * math.pi * x * 2 * math.sqrt(max(rad**2 - (x - c) ** 2, 0.0)), 0, c + rad
    )[0]
    ws = workspace("hexabot_leg", samples=1_500_000, seed=3)
    assert ws.volume == pytest.approx(exact_leg, rel=0.06)
    assert reach(load("hexabot_leg")) == pytest.approx(0.25)
    sec = cross_section(ws.points, "xz")
    assert sec.shape[1] == 2 and len(sec) > 1000


def test_workspace_plot(tmp_path):
    leg = load("hexabot_leg")
    from hexapod_kin.plots import plot_workspace

    ws = workspace(leg, samples=50_000)
    res = scan(leg, samples=20_000, joints="all", families=False)
    sing = np.array([leg.position(q) for q in res.q[res.singular][:500]])
    path = plot_workspace(ws, tmp_path / "ws.png", singular_points=sing)
    assert path.read_bytes()[:4] == b"\x89PNG"


def test_workspace_errors_and_dict():
    with pytest.raises(ParameterError, match="plane"):
        cross_section(np.zeros((3, 3)), "ab")
    with pytest.raises(ParameterError, match="samples"):
        workspace("hexabot_leg", samples=0)
    with pytest.raises(ParameterError, match="voxel"):
        workspace("hexabot_leg", samples=10, voxel=-1.0)
    ws = workspace("hexabot_leg", samples=2000, seed=1)
    d = ws.to_dict()
    assert d["volume"] == ws.volume and len(d["points"]) == 2000
    # the points are the model's own tip positions
    assert np.allclose(ws.points[:5], [load("hexabot_leg").position(q) for q in ws.q[:5]])
