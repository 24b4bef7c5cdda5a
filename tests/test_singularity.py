"""Singularity measures, scans, families and workspace, against Pinocchio and closed forms."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from hexapod_kin import Chain, KhalilRow, load
from hexapod_kin.cli import main
from hexapod_kin.exceptions import ConfigurationError, FrameNotFoundError, ParameterError
from hexapod_kin.singularity import (
    ROW_NAMES,
    cross_section,
    default_rows,
    measures,
    measures_batch,
    plot_joints,
    reach,
    scan,
    workspace,
)


def pin_measures(model, qs, rows):
    idx = [ROW_NAMES.index(r) for r in rows]
    jac = np.array([model.jacobian(q)[idx] for q in qs])
    sv = np.linalg.svd(jac, compute_uv=False)
    k, n = jac.shape[1:]
    det = np.linalg.det(jac) if k == n else np.full(len(qs), np.nan)
    return det, np.prod(sv, axis=1), sv[:, 0], sv[:, -1]


@pytest.fixture(scope="module")
def leg():
    return load("hexabot_leg")


@pytest.fixture(scope="module")
def scara():
    return load("scara")


@pytest.mark.parametrize(
    ("source", "tip", "rows"),
    [
        ("hexabot_leg", None, None),
        ("scara", None, None),
        ("scara", None, ("x", "y", "z")),
        ("coxa_tibia_leg", None, None),
        ("erd:solo12", "FL_FOOT", None),
        ("hexabot_leg", None, "all"),
        ("hexabot_leg", None, ("x", "z")),
        ("erd:solo12", "FL_FOOT", ("x", "y", "z", "wz")),
        ("erd:solo12", "FL_FOOT", ("y", "z", "wx")),
    ],
)
def test_kernel_equals_pinocchio(source, tip, rows):
    model = load(source, tip=tip)
    names = ROW_NAMES if rows == "all" else (rows or default_rows(model))
    qs = model.random_q(500, seed=7)
    if source == "hexabot_leg":  # both vectorised blocks and a partial one; angles beyond 2*pi
        qs = np.concatenate([qs, model.random_q(700, seed=8) * 3.0])
    if source == "coxa_tibia_leg":  # |q| > _POLY_TRIG_MAX: the libm sin / cos path
        qs = qs + 2 * np.pi * 40_000
    det, manip, cond, smin = measures_batch(model, qs, rows)
    pdet, pmanip, smax, psmin = pin_measures(model, qs, names)
    if np.isnan(pdet).all():
        assert np.isnan(det).all()
    else:
        assert np.abs(det - pdet).max() < 1e-12
    assert np.abs(manip - pmanip).max() < 1e-12
    assert np.abs(smin - psmin).max() < 1e-12
    assert np.abs(1 / cond - psmin / smax).max() < 1e-12
    # the numpy engine agrees too
    ndet, nmanip, ncond, nsmin = measures_batch(model, qs, rows, engine="numpy")
    assert np.abs(nsmin - psmin).max() < 1e-12


def test_first_joint_invariance_rule():
    # S·blockdiag(R, R)·Sᵀ orthogonal <=> the measures do not depend on joint 0
    from hexapod_kin.singularity import _aligned, _first_joint_invariant

    leg = _aligned(load("hexabot_leg"))  # hip axis z
    assert _first_joint_invariant(leg, (0, 1, 2))
    assert _first_joint_invariant(leg, (0, 1, 2, 5))
    assert _first_joint_invariant(leg, (0, 1, 2, 3, 4, 5))
    assert _first_joint_invariant(leg, (0, 1))
    assert not _first_joint_invariant(leg, (0, 2))
    assert not _first_joint_invariant(leg, (0, 1, 2, 3))
    solo = _aligned(load("erd:solo12", tip="FL_FOOT"))  # HAA axis x
    assert _first_joint_invariant(solo, (0, 1, 2))
    assert _first_joint_invariant(solo, (1, 2, 3))
    assert not _first_joint_invariant(solo, (0, 1, 2, 5))
    # and the measures really are independent of q0 where the rule says so (Pinocchio)
    model = load("erd:solo12", tip="FL_FOOT")
    q = model.random_q(50, seed=3)
    q2 = q.copy()
    q2[:, 0] += 1.234
    for rows, same in (
        ("position", True),
        (("y", "z", "wx"), True),
        (("x", "y", "z", "wz"), False),
    ):
        names = ROW_NAMES[:3] if rows == "position" else rows
        a = pin_measures(model, q, names)[3]
        b = pin_measures(model, q2, names)[3]
        assert (np.abs(a - b).max() < 1e-12) == same


def test_polynomial_sincos_matches_libm():
    from hexapod_kin.singularity import _POLY_TRIG_MAX, _sincos, njit

    @njit
    def both(x, s, c):
        for i in range(x.shape[0]):
            s[i], c[i] = _sincos(x[i])

    rng = np.random.default_rng(5)
    k = np.arange(-400, 401)
    x = np.concatenate(
        [
            rng.uniform(-7, 7, 200_000),
            rng.uniform(-_POLY_TRIG_MAX, _POLY_TRIG_MAX, 200_000),
            k * (np.pi / 4),
            np.nextafter(k * (np.pi / 4), np.inf),
            [0.0, -0.0, 1e-300, -1e-300, _POLY_TRIG_MAX, -_POLY_TRIG_MAX],
        ]
    )
    s, c = np.empty_like(x), np.empty_like(x)
    both(x, s, c)
    assert np.abs(s - np.sin(x)).max() <= 2.3e-16
    assert np.abs(c - np.cos(x)).max() <= 2.3e-16


def test_eig3_block_clustered_and_rank_deficient():
    # Jacobi is backward stable for any eigenvalue clustering (the closed forms are not)
    from hexapod_kin.singularity import _eig3_block

    rng = np.random.default_rng(9)
    spectra = [
        (1.0, 1.0 - 1e-9, 0.5),
        (1.0, 0.3, 0.3 - 1e-10),
        (1.0, 1.0, 1.0),
        (1.0, 1e-20, 0.0),
        (2.0, 0.0, 0.0),
        (0.0, 0.0, 0.0),
    ]
    mats = []
    for lam in spectra:
        rot, _ = np.linalg.qr(rng.normal(size=(200, 3, 3)))
        mats.append(rot @ (np.asarray(lam)[:, None] * np.swapaxes(rot, 1, 2)))
    a = rng.normal(size=(2000, 3, 3))
    mats.append(a @ np.swapaxes(a, 1, 2))
    g = np.concatenate(mats)
    g[-1] = np.diag([3.0, 1.0, 2.0])
    gb = np.ascontiguousarray(
        np.stack([g[:, 0, 0], g[:, 0, 1], g[:, 0, 2], g[:, 1, 1], g[:, 1, 2], g[:, 2, 2]])
    )
    _eig3_block(gb, g.shape[0], np.empty(g.shape[0], dtype=np.int64))
    got = np.sort(gb[[0, 3, 5]].T, axis=1)
    ref = np.linalg.eigvalsh(g)
    scale = np.maximum(ref[:, -1], 1e-300)
    assert (np.abs(got - ref).max(axis=1) / scale).max() < 1e-14
    assert np.abs(gb[[1, 2, 4]]).max() <= 1e-15 * np.abs(ref).max()


def test_kernel_accurate_near_singularities(leg):
    # q3 -> 0 and the foot near the hip axis: sigma_min keeps its relative accuracy
    qs = np.array(
        [[0.3, 0.4, 1e-7], [0.1, -0.2, math.pi - 1e-8], [0.0, 2.0943951023931957, -2.0943951e0]]
    )
    _, _, _, smin = measures_batch(leg, qs)
    _, _, _, psmin = pin_measures(leg, qs, ("x", "y", "z"))
    assert np.allclose(smin, psmin, rtol=1e-6, atol=1e-15)
    m = measures(leg, qs[0])
    assert m.sigma_min == pytest.approx(psmin[0], rel=1e-6)
    assert m.singular_values.shape == (3,) and not m.singular_values.flags.writeable


def test_default_rows(leg, scara):
    assert default_rows(leg) == ("x", "y", "z")
    assert default_rows(scara) == ("x", "y", "z", "wz")
    assert plot_joints(leg) == (1, 2)
    assert plot_joints(scara) == (0, 1)


def test_leg_scan_finds_both_families_and_nothing_spurious(leg):
    res = scan(leg, grid=73, joints=["knee", "ankle"], q_fixed=[0.4, 0, 0])
    counts = res.family_counts()
    assert counts["q3 = 0 (mod 2*pi)"] > 0
    assert counts["q3 = pi (mod 2*pi)"] > 0
    assert counts["l1 + l2*cos(q2) + l3*cos(q2 + q3) = 0"] > 0
    assert not res.unexplained.any()
    flagged = res.q[res.singular]
    _, _, _, psmin = pin_measures(leg, flagged, res.rows)
    assert (psmin < res.threshold).all()
    rng = np.random.default_rng(0)
    unflagged = res.q[~res.singular]
    pick = unflagged[rng.choice(len(unflagged), 300, replace=False)]
    _, _, _, psmin = pin_measures(leg, pick, res.rows)
    assert (psmin >= res.threshold).all()
    # the hip-axis family: the flagged points satisfy l1 + l2 c2 + l3 c23 ~ 0
    fam = [f.name for f in res.families].index("l1 + l2*cos(q2) + l3*cos(q2 + q3) = 0")
    on = res.q[res.family == fam]
    rho = 0.05 + 0.1 * np.cos(on[:, 1]) + 0.1 * np.cos(on[:, 1] + on[:, 2])
    assert np.abs(rho).max() < 0.01


def test_leg_random_scan_3d(leg):
    res = scan(leg, samples=100_000, seed=1)
    assert res.grid_shape is None and res.q.shape == (100_000, 3)
    assert not res.unexplained.any()
    assert all(v > 0 for v in res.family_counts().values())


def test_scara_scan_finds_stretched_and_folded(scara):
    res = scan(scara, grid=(9, 73, 5, 3))
    counts = res.family_counts()
    assert counts == {
        "q2 = 0 (mod 2*pi)": counts["q2 = 0 (mod 2*pi)"],
        "q2 = pi (mod 2*pi)": counts["q2 = pi (mod 2*pi)"],
    }
    assert min(counts.values()) > 0
    assert not res.unexplained.any()
    flagged = res.q[res.singular]
    assert np.all(np.minimum(np.abs(flagged[:, 1]), math.pi - np.abs(flagged[:, 1])) < 0.2)
    _, _, _, psmin = pin_measures(scara, flagged, res.rows)
    assert (psmin < res.threshold).all()


def test_scan_result_is_read_only_and_json(leg):
    res = scan(leg, grid=7, joints=("knee", "ankle"))
    with pytest.raises(ValueError):
        res.det[0] = 1.0
    assert res.grid("det").shape == (7, 7)
    out = json.loads(json.dumps(res.to_json(), allow_nan=False))
    for name in ("q", "det", "manipulability", "condition", "sigma_min", "singular"):
        assert len(out[name]) == 49
    assert out["joints"] == ["knee", "ankle"]


def test_scan_errors(leg):
    with pytest.raises(ParameterError, match="not both"):
        scan(leg, grid=5, samples=10)
    with pytest.raises(FrameNotFoundError, match="knee"):
        scan(leg, grid=5, joints=["elbow"])
    with pytest.raises(ParameterError, match="rows"):
        scan(leg, grid=5, rows=("x", "v"))
    with pytest.raises(ParameterError, match="grid"):
        scan(leg, grid=1)
    with pytest.raises(ConfigurationError):
        measures_batch(leg, np.zeros((4, 2)))
    with pytest.raises(ParameterError, match="plane"):
        cross_section(np.zeros((3, 3)), "ab")


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


def test_cli_scan_json_and_plot(tmp_path, capsys):
    png = tmp_path / "map.png"
    assert main(["scan", "hexabot_leg", "--grid", "25", "--json", "--plot", str(png)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["joints"] == ["knee", "ankle"] and len(out["det"]) == 625
    assert {f["name"] for f in out["families"]} >= {"q3 = 0 (mod 2*pi)"}
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["scan", "scara", "--samples", "2000"]) == 0
    text = capsys.readouterr().out
    assert "family q2 = pi" in text


def test_cli_derive(capsys):
    assert main(["derive", "hexabot_leg"]) == 0
    text = capsys.readouterr().out
    assert "max |det_sym - det_pin|" in text
    assert main(["derive", "scara", "--latex"]) == 0
    assert "\\det J" in capsys.readouterr().out


def test_workspace_plot(tmp_path, leg):
    from hexapod_kin.plots import plot_workspace

    ws = workspace(leg, samples=50_000)
    res = scan(leg, samples=20_000)
    from hexapod_kin import _kernels

    sing = _kernels.fk_batch(_kernels.ChainArrays.from_model(leg), res.q[res.singular])
    path = plot_workspace(ws, tmp_path / "ws.png", singular_points=sing)
    assert path.read_bytes()[:4] == b"\x89PNG"
