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


#: Every catalogue chain (default rows), a hexapod leg tip, a Solo12 leg, and shapes beyond it.
CHAINS = [
    ("hexabot_leg", None, None),  # 3×3, G = Jᵀ J split {q1} ⊕ {q2, q3}
    ("coxa_tibia_leg", None, None),  # 3×2
    ("scara", None, None),  # 4×4 (x, y, z, wz), split {x, y, wz} ⊕ {z}
    ("pendulum", None, None),  # 3×1
    ("hexapod", "leg1_foot", None),  # 3×3, mount rotated in the base
    ("erd:solo12", "FL_FOOT", None),  # 3×3, lateral offsets: no split, joint range ±10 rad
    ("scara", None, ("x", "y", "wz")),  # 3×4: Cauchy–Binet over 4 minors
    ("scara", None, "all"),  # 6×4: 15 minors, 4×4 Jacobi
    ("five_dof", None, "all"),  # 6×5: m = 5, the per-configuration path
]


def _five_dof():
    rows = [KhalilRow("revolute", a, d, 0.0, r) for a, d, r in (
        (0.0, 0.0, 0.1), (math.pi / 2, 0.05, 0.0), (0.0, 0.2, 0.02), (-math.pi / 2, 0.01, 0.15),
        (math.pi / 2, 0.0, 0.0),
    )]
    return Chain(rows=(*rows, KhalilRow("fixed", 0.0, 0.0, 0.0, 0.08)), name="five_dof")


def _load_chain(source, tip):
    return load(_five_dof()) if source == "five_dof" else load(source, tip=tip)


@pytest.mark.parametrize(("source", "tip", "rows"), CHAINS)
def test_every_chain_equals_pinocchio(source, tip, rows):
    from hexapod_kin.singularity import _aligned, _first_joint_invariant, _gram_plan

    model = _load_chain(source, tip)
    names = ROW_NAMES if rows == "all" else (rows or default_rows(model))
    qs = model.random_q(1500, seed=21)  # two full blocks and a partial one
    det, manip, cond, smin = measures_batch(model, qs, rows)
    pdet, pmanip, smax, psmin = pin_measures(model, qs, names)
    if len(names) == model.nq:
        assert np.abs(det - pdet).max() < 1e-12
    else:
        assert np.isnan(det).all()
    assert np.abs(manip - pmanip).max() < 1e-12
    assert np.abs(smin - psmin).max() < 1e-12
    assert np.abs(1 / cond - psmin / smax).max() < 1e-12
    sel = tuple(ROW_NAMES.index(r) for r in names)
    plan = _gram_plan(model, sel, _first_joint_invariant(_aligned(model), sel))
    assert plan.use_block == (min(len(names), model.nq) <= 4)


def test_gram_plans_split_where_structure_allows():
    from hexapod_kin.singularity import _gram_plan

    def sizes(source, tip=None):
        model = load(source, tip=tip)
        return sorted(_gram_plan(model, (0, 1, 2, 5)[: 4 if source == "scara" else 3], True).csize)

    assert sizes("hexabot_leg") == [1, 2]
    assert sizes("hexapod", "leg1_foot") == [1, 2]
    assert sizes("scara") == [1, 3]
    assert sizes("erd:solo12", "FL_FOOT") == [3]
    assert sizes("coxa_tibia_leg") == [1, 1]


def test_wrong_split_guess_is_caught_per_block():
    # a plan claiming G = {0} ⊕ {1, 2} for the Solo12 leg (false: G[0, 2] != 0) must not
    # change the results: the kernel checks the dropped entries on every block
    from dataclasses import replace

    from hexapod_kin.singularity import _BLOCK, _aligned, _gram_plan, _measures_kernel

    model = load("erd:solo12", tip="FL_FOOT")
    al = _aligned(model)
    plan = _gram_plan(model, (0, 1, 2), True)
    perm = np.array([0, 1, 2])
    csize = np.array([1, 2])
    drop = np.array([1, 2])  # packed (0, 1), (0, 2)
    pack, rsub, csub, gram_t = plan.arrays[:4]
    bad = replace(plan, arrays=(pack, rsub, csub, False, perm, csize, drop))
    qs = model.random_q(1200, seed=5)
    out = tuple(np.empty(len(qs)) for _ in range(4))
    _measures_kernel(
        al.prot, al.ptr, al.pident, al.kind, al.col, qs, np.arange(3), True, bad.arrays, True,
        True, 2, _BLOCK, *out,
    )
    _, _, smax, psmin = pin_measures(model, qs, ("x", "y", "z"))
    assert np.abs(out[3] - psmin).max() < 1e-12
    assert np.abs(1 / out[2] - psmin / smax).max() < 1e-12


def test_new_shapes_accurate_near_singularities():
    # coxa-tibia 3×2 with l1 < l2: sigma = {|l1 + l2 cos q2|, l2} (orthogonal columns), so
    # sigma_min -> 0 at cos q2 = -l1/l2; Cauchy–Binet keeps its relative accuracy
    from hexapod_kin import robots

    coxa = load(robots.coxa_tibia_leg(l1=5.0, l2=10.0))
    q2 = 2 * math.pi / 3 + np.array([1e-10, -1e-8, 1e-6, 0.5])
    qs = np.column_stack([np.full(4, 0.3), q2])
    _, manip, cond, smin = measures_batch(coxa, qs)
    rho = np.abs(5.0 + 10.0 * np.cos(q2))
    # absolute error ~ eps * sigma_max (q2 itself is rounded: rho is only known to ~4e-15)
    assert np.all(np.abs(smin - np.minimum(rho, 10.0)) <= 1e-14 + 1e-9 * rho)
    assert np.all(np.abs(manip - rho * 10.0) <= 1e-13 + 1e-9 * rho)
    assert np.all(np.abs(1 / cond - rho / 10.0) <= 1e-15 + 1e-9 * rho)
    # SCARA (4×4) arm stretched / folded, hexapod leg and Solo12 leg near q3 = 0: Pinocchio
    for source, tip, q in (
        ("scara", None, [[0.2, 1e-7, 0.3, 0.05], [0.2, math.pi - 1e-7, -1.0, 0.1]]),
        ("hexapod", "leg1_foot", [[0.3, 0.4, 1e-7], [0.1, -0.2, math.pi - 1e-8]]),
        ("erd:solo12", "FL_FOOT", [[0.1, 0.3, 1e-7], [-0.4, 1.0, 2e-8]]),
    ):
        model = load(source, tip=tip)
        qs = np.asarray(q)
        _, _, _, smin = measures_batch(model, qs)
        _, _, _, psmin = pin_measures(model, qs, default_rows(model))
        assert psmin.max() < 1e-6
        assert np.allclose(smin, psmin, rtol=1e-6, atol=0)


def test_output_buffers_reused_only_when_unreferenced(leg):
    qs1, qs2 = leg.random_q(3000, seed=1), leg.random_q(3000, seed=2)
    ref1 = [r.copy() for r in measures_batch(leg, qs1)]
    ref2 = [r.copy() for r in measures_batch(leg, qs2)]
    first = measures_batch(leg, qs1)
    second = measures_batch(leg, qs2)  # `first` is alive: a different buffer
    assert not any(np.shares_memory(a, b) for a in first for b in second)
    view = second[3][::2]
    del second
    third = measures_batch(leg, qs1)  # a view of `second` is alive: not reused either
    assert not np.shares_memory(view, third[3])
    base = id(third[3].base)  # the pooled buffer now
    assert all(np.array_equal(g, r, equal_nan=True) for g, r in zip(first, ref1))
    assert all(np.array_equal(g, r, equal_nan=True) for g, r in zip(third, ref1))
    assert np.array_equal(view, ref2[3][::2])
    del view, third
    again = measures_batch(leg, qs2)  # nothing references the pooled buffer: reused
    assert id(again[3].base) == base
    assert all(a.base is again[0].base for a in again)
    assert all(np.array_equal(g, r, equal_nan=True) for g, r in zip(again, ref2))


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


def _spectra_matrices(m, rng):
    """Symmetric PSD m×m matrices with clustered, repeated and zero eigenvalues, and random."""
    spectra = [
        (1.0, 1.0 - 1e-9, 0.5, 0.25),
        (1.0, 0.3, 0.3 - 1e-10, 0.1),
        (1.0, 1.0, 1.0, 1.0),
        (1.0, 1e-20, 0.0, 0.0),
        (2.0, 0.0, 0.0, 0.0),
        (0.0, 0.0, 0.0, 0.0),
        (1.0, 1.0 - 1e-6, 1.0 - 2e-6, 1e-8),
    ]
    mats = []
    for lam in spectra:
        rot, _ = np.linalg.qr(rng.normal(size=(200, m, m)))
        mats.append(rot @ (np.asarray(lam[:m])[:, None] * np.swapaxes(rot, 1, 2)))
    a = rng.normal(size=(2000, m, m))
    mats.append(a @ np.swapaxes(a, 1, 2))
    g = np.concatenate(mats)
    g[-1] = np.diag(np.arange(m, 0, -1.0)[[1, 0, *range(2, m)]])
    return g


@pytest.mark.parametrize("m", [3, 4])
def test_eig_block_clustered_and_rank_deficient(m):
    # Jacobi is backward stable for any eigenvalue clustering (the closed forms are not)
    from hexapod_kin.singularity import _JACOBI_TOL, _eig3_block, _eig_block

    g = _spectra_matrices(m, np.random.default_rng(9))
    iu = np.triu_indices(m)
    gb = np.ascontiguousarray(g[:, iu[0], iu[1]].T)
    if m == 3:
        _eig3_block(gb, g.shape[0], np.empty(g.shape[0], dtype=np.int64))
    else:
        _eig_block(gb, g.shape[0], m, np.empty_like(gb), np.empty(g.shape[0], dtype=np.int64))
    diag = iu[0] == iu[1]
    got = np.sort(gb[diag].T, axis=1)
    ref = np.linalg.eigvalsh(g)
    scale = np.maximum(ref[:, -1], 1e-300)
    assert (np.abs(got - ref).max(axis=1) / scale).max() < 1e-14
    # the documented stopping rule holds: Weyl, or the quadratic bound for isolated eigenvalues
    off = np.abs(gb[~diag]).sum(axis=0)
    tol = _JACOBI_TOL * gb[diag].sum(axis=0)
    d = gb[diag]
    gap = np.min([np.abs(d[a] - d[b]) for a in range(m) for b in range(a + 1, m)], axis=0)
    quad = (gap > 3 * off) & (2 * off**2 <= tol * (gap - off))
    assert np.all((off <= tol) | quad)


def test_minor_block_and_cauchy_binet():
    # explicit minors (m <= 4) against numpy det; det(J Jᵀ) = sum of squared maximal minors
    from itertools import combinations

    from hexapod_kin.singularity import _minor_block, njit

    @njit
    def minors(jb, r, c, m, out):
        _minor_block(jb, r, c, m, jb.shape[2], out)

    rng = np.random.default_rng(4)
    for m in (1, 2, 3, 4):
        jb = rng.normal(size=(m, 6, 64))
        total = np.zeros(64)
        for cols in combinations(range(6), m):
            out = np.empty(64)
            minors(jb, np.arange(m), np.array(cols), m, out)
            ref = np.linalg.det(np.moveaxis(jb[:, list(cols)], 2, 0))
            assert np.abs(out - ref).max() < 1e-12 * max(1.0, np.abs(ref).max())
            total += out**2
        jac = np.moveaxis(jb, 2, 0)
        gram = np.linalg.det(jac @ np.swapaxes(jac, 1, 2))
        assert np.allclose(total, gram, rtol=1e-10)


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


def test_default_heat_map_joints_move_the_tip():
    from hexapod_kin import load
    from hexapod_kin.singularity import plot_joints

    model = load("hexapod")  # 18 joints, tip leg1_foot: 15 joints do not move it
    a, b = plot_joints(model)
    q = model.random_q(seed=3)
    jac = model.position_jacobian(q)
    assert np.linalg.norm(jac[:, a]) > 1e-6 and np.linalg.norm(jac[:, b]) > 1e-6
    assert {model.joint_names[a], model.joint_names[b]} <= {"leg1_hip", "leg1_knee", "leg1_ankle"}
