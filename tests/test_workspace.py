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


def test_workspace_plot(tmp_path, monkeypatch):
    """The figure draws the slab of the workspace and of the singular points, and the PNG shows
    them: the scatter data against the slab cut by hand, the pixels' colours counted."""
    import matplotlib.image as mpimg

    from hexapod_kin import plots

    leg = load("hexabot_leg")
    ws = workspace(leg, samples=50_000)
    res = scan(leg, samples=20_000, joints="all", families=False)
    sing = np.array([leg.position(q) for q in res.q[res.singular][:500]])
    drawn = []
    real_save = plots.save_figure

    def keep(fig, path, *args, **kwargs):
        ax = fig.axes[0]
        drawn.append([(c.get_offsets().data.copy(), c.get_facecolor()[0]) for c in ax.collections])
        drawn.append(fig.axes[0].get_title())
        return real_save(fig, path, *args, **kwargs)

    monkeypatch.setattr(plots, "save_figure", keep)
    path = plots.plot_workspace(ws, tmp_path / "ws.png", singular_points=sing)
    (reach_pts, blue), (sing_pts, red) = drawn[0]

    def slab(points):  # the xz plane, |y| within half of 1 % of the largest extent
        half = 0.005 * np.ptp(points, axis=0).max()
        return points[np.abs(points[:, 1]) <= half][:, [0, 2]]

    assert np.array_equal(reach_pts, slab(ws.points)) and len(reach_pts) > 100
    assert np.array_equal(sing_pts, slab(sing)) and len(sing_pts) > 0
    # every drawn point lies in the leg's closed-form reach: the disc of radius l2 + l3 = 0.2 m
    # centred l1 = 0.05 m from the hip axis (1 mm for the slab's thickness)
    rim = np.hypot(np.abs(reach_pts[:, 0]) - 0.05, reach_pts[:, 1])
    assert rim.max() <= 0.2 + 1e-3
    assert tuple(blue[:3]) == pytest.approx((0.122, 0.467, 0.706), abs=1e-3)  # tab:blue
    assert tuple(red[:3]) == pytest.approx((0.839, 0.153, 0.157), abs=1e-3)  # tab:red
    assert f"{ws.volume:.3g}" in drawn[1]
    # the PNG: a picture of that figure, with blue and red marks on a white page
    img = mpimg.imread(path)[..., :3]
    assert img.shape[0] > 300 and img.shape[1] > 300
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    assert np.mean(np.all(img > 0.98, axis=-1)) > 0.3  # mostly page
    assert np.count_nonzero((b > r + 0.15) & (b > g)) > 1000  # the reachable points
    assert np.count_nonzero((r > 0.6) & (g < 0.4) & (b < 0.4)) > 20  # the singular ones


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
