"""Singularity measures, scans and families (public API), against Pinocchio and closed forms."""

from __future__ import annotations

import json
import math
import pickle

import numpy as np
import pytest

from hexapod_kin import load
from hexapod_kin.cli import main
from hexapod_kin.exceptions import ConfigurationError, FrameNotFoundError, ParameterError
from hexapod_kin.singularity import (
    ROW_NAMES,
    default_joints,
    default_rows,
    measures,
    measures_batch,
    scan,
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
    assert default_joints(leg) == (1, 2)
    assert 1 in default_joints(scara)  # theta2: the only joint in the families (det = l1 l2 sin q2)


def test_leg_scan_finds_both_families_and_nothing_spurious(leg):
    res = scan(leg, grid=73, joints=["knee", "ankle"], q_fixed=[0.4, 0, 0], families=True)
    counts = res.family_counts
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
    res = scan(leg, samples=100_000, seed=1, joints="all", families=True)
    assert res.grid_shape is None and res.q.shape == (100_000, 3)
    assert not res.unexplained.any()
    assert all(v > 0 for v in res.family_counts.values())


def test_scara_scan_finds_stretched_and_folded(scara):
    res = scan(scara, grid=(9, 73, 5, 3), joints="all", families=True)
    counts = res.family_counts
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


def test_scan_defaults_are_the_commands_and_small_scans_skip_the_kernel(leg, capsys):
    import subprocess
    import sys

    from hexapod_kin.singularity.scans import DEFAULT_GRID, SMALL_SCAN

    res = scan(leg, families=False)
    assert res.joints == default_joints(leg) and res.grid_shape == (DEFAULT_GRID, DEFAULT_GRID)
    assert main(["scan", "hexabot_leg", "--families", "off", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["grid_shape"] == [DEFAULT_GRID] * 2 and out["joints"] == ["knee", "ankle"]
    assert out["sigma_min"] == [None if not math.isfinite(v) else v for v in res.sigma_min]
    assert scan(leg, grid=4, joints="all", families=False).q.shape == (64, 3)
    # small scans: Pinocchio + numpy, equal to the kernel to rounding
    small = scan(leg, samples=SMALL_SCAN, seed=5, joints="all", families=False)
    kernel = measures_batch(leg, small.q)
    assert np.allclose(small.sigma_min, kernel.sigma_min, rtol=1e-12, atol=1e-15)
    assert np.allclose(small.det, kernel.det, rtol=1e-12, atol=1e-15)
    code = (
        "import sys; from hexapod_kin import load; from hexapod_kin.singularity import scan; "
        "scan(load('hexabot_leg'), families=False); "
        "print(any(f'hexapod_kin.singularity.{m}' in sys.modules for m in ('_plan', '_kernel')))"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert run.stdout.split() == ["False"]


def test_scan_result_is_read_only_and_json(leg):
    res = scan(leg, grid=7, joints=("knee", "ankle"))
    with pytest.raises(ValueError):
        res.det[0] = 1.0
    assert res.grid("det").shape == (7, 7)
    out = json.loads(json.dumps(res.to_dict(), allow_nan=False))
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


def test_cli_scan_json_and_plot(tmp_path, capsys, fresh_cache, drawn):
    # families derived once through the API (kept on disk), then shown by the CLI
    scan(load("hexabot_leg"), grid=5, joints=("knee", "ankle"), families=True)
    scan(load("scara"), samples=10, families=True)
    png = tmp_path / "map.png"
    assert main(["scan", "hexabot_leg", "--grid", "25", "--json", "--plot", str(png)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["joints"] == ["knee", "ankle"] and len(out["det"]) == 625
    assert {f["name"] for f in out["families"]} >= {"q3 = 0 (mod 2*pi)"}
    # the heat map is det J at the scanned configurations: the closed form (seed 001),
    # det = l2 l3 sin(q3) (l1 + l2 cos q2 + l3 cos(q2 + q3)), up to one sign for the whole map
    q = np.asarray(out["q"])
    reach = 0.05 + 0.1 * np.cos(q[:, 1]) + 0.1 * np.cos(q[:, 1] + q[:, 2])
    closed = 0.1 * 0.1 * np.sin(q[:, 2]) * reach
    (heat,) = [c for c in drawn[-1].axes[0].collections if hasattr(c, "get_coordinates")]
    shown = np.asarray(heat.get_array()).T.ravel()  # drawn as det.T on (knee, ankle) axes
    sign = np.sign(shown @ closed)
    np.testing.assert_allclose(sign * shown, closed, atol=1e-12)
    edges = heat.get_coordinates()  # cell corners, degrees: knee along x, ankle along y
    assert np.allclose(np.radians(edges[0, :-1, 0] + edges[0, 1:, 0]) / 2, np.unique(q[:, 1]))
    assert np.allclose(np.radians(edges[:-1, 0, 1] + edges[1:, 0, 1]) / 2, np.unique(q[:, 2]))
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


def test_default_heat_map_joints_move_the_tip():
    from hexapod_kin import load
    from hexapod_kin.singularity import default_joints

    model = load("hexapod")  # 18 joints, tip leg1_foot: 15 joints do not move it
    a, b = default_joints(model)
    q = model.random_q(seed=3)
    jac = model.position_jacobian(q)
    assert np.linalg.norm(jac[:, a]) > 1e-6 and np.linalg.norm(jac[:, b]) > 1e-6
    assert {model.joint_names[a], model.joint_names[b]} <= {"leg1_hip", "leg1_knee", "leg1_ankle"}


# ------------------------------------------------------------------ families, defaults, plots
def test_import_singularity_loads_neither_sympy_nor_numba():
    import subprocess
    import sys

    code = (
        "import sys, hexapod_kin.singularity as s; s.ROW_NAMES; "
        "print('sympy' in sys.modules, 'numba' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "False"]


@pytest.fixture
def fresh_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(tmp_path))
    return tmp_path


def test_families_only_when_asked_then_from_disk_without_sympy(fresh_cache):
    import subprocess
    import sys

    from hexapod_kin.singularity import families_for

    res = scan(load("hexabot_leg"), grid=9, joints=("knee", "ankle"), families="cached")
    assert res.families == () and "not derived" in res.family_reason
    assert (res.family == -1).all() and res.unexplained.sum() == res.singular.sum()
    res = scan(load("hexabot_leg"), grid=9, joints=("knee", "ankle"), families=True)
    assert len(res.families) == 3 and res.family_reason == ""
    fams = families_for(load("hexabot_leg"), res.rows)  # a fresh model: from the disk
    assert fams.origin == "cache" and [f.name for f in fams.families] == [
        f.name for f in res.families
    ]
    code = (
        "import sys; from hexapod_kin import load; from hexapod_kin.singularity import scan; "
        "r = scan(load('hexabot_leg'), grid=9, joints=('knee', 'ankle'), families='cached'); "
        "print(len(r.families), 'sympy' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["3", "False"]


@pytest.mark.slow
def test_families_derived_in_a_child_leave_the_caller_without_sympy(tmp_path):
    """A process that derives families (sympy, in a child) never imports sympy itself, and
    gets the same families as a process holding sympy (the derivation in a child of its own)."""
    import os
    import subprocess
    import sys

    code = (
        "import sys, json; {pre}from hexapod_kin import load; "
        "from hexapod_kin.singularity import scan; "
        "r = scan(load('hexabot_leg'), grid=9, joints=('knee', 'ankle'), families=True); "
        "print(json.dumps([[f.to_dict() for f in r.families], r.family_reason, "
        "r.family.tolist(), 'sympy' in sys.modules]))"
    )
    answers = []
    for k, pre in enumerate(("", "import sympy; ")):
        env = {**os.environ, "HEXAPOD_KIN_CACHE_DIR": str(tmp_path / str(k))}
        out = subprocess.run(
            [sys.executable, "-c", code.format(pre=pre)],
            capture_output=True, text=True, check=True, env=env,
        )  # fmt: skip
        answers.append(json.loads(out.stdout))
    assert answers[0][3] is False and answers[1][3] is True
    assert len(answers[0][0]) == 3 and answers[0][1] == ""
    assert answers[0][:3] == answers[1][:3]


def test_derivation_failures_are_recorded_and_bugs_propagate(fresh_cache, monkeypatch):
    from hexapod_kin import symbolic

    def refuse(chain, rows=None, budget=None, deadline=None, families_only=False):
        raise ParameterError("no table for you")

    monkeypatch.setattr(symbolic, "derive", refuse)
    res = scan(load("hexabot_leg"), grid=5, joints=("knee", "ankle"), families=True)
    assert res.families == () and "no table for you" in res.family_reason

    def bug(chain, rows=None, budget=None, deadline=None, families_only=False):
        raise KeyError("a bug")

    monkeypatch.setattr(symbolic, "derive", bug)
    with pytest.raises(KeyError):
        scan(load("hexabot_leg"), grid=5, joints=("knee", "ankle"), families=True)


def test_family_text_is_evaluated_by_a_whitelist():
    from hexapod_kin.singularity import Family

    for evil in ("__import__('os').getcwd()", "q2.real", "q2 ** q2", "q1 + q2", "exp(q2)"):
        with pytest.raises(ParameterError, match="not allowed"):
            Family("x", "x", (1,), None, None, False, evil)
    ok = Family("f", "f", (1,), None, None, False, "0.05 + 0.1*cos(q2)")
    assert ok.residual(np.array([0.0, math.pi, 0.0])) == pytest.approx(-0.05)
    again = pickle.loads(pickle.dumps(ok))  # the compiled factor is rebuilt
    assert again == ok and again.residual(np.array([0.0, 0.0, 0.0])) == pytest.approx(0.15)


def test_family_jets_equal_finite_differences():
    # value, gradient and Hessian of every operator of the grammar against central differences
    from hexapod_kin.singularity import Family

    text = "sqrt(2 + sin(q1)**2*q3**2) / (3 - cos(q1 - q3)) + tan(q3/4) - Abs(q1) + pi*q3**-1"
    fam = Family("f", "f", (0, 2), None, None, False, text)
    x = np.array([[0.3, 0.7], [-0.8, 1.9], [1.2, -0.6]])
    f, g, h = fam._jet(x, True)
    h_step = 1e-5
    for i in range(2):
        e = np.zeros(2)
        e[i] = h_step
        fp, gp, _ = fam._jet(x + e, True)
        fm, gm, _ = fam._jet(x - e, True)
        assert np.allclose(g[:, i], (fp - fm) / (2 * h_step), rtol=1e-8, atol=1e-9)
        assert np.allclose(h[:, :, i], (gp - gm) / (2 * h_step), rtol=1e-7, atol=1e-8)
    assert np.allclose(fam.residual(np.column_stack([x[:, 0], np.zeros(3), x[:, 1]])), f)


_L1, _L2, _L3 = 0.05, 0.1, 0.1  # the hexabot leg's lengths in [m]


def _hip_axis_branch(x, by_q2, sign):
    """A point (q2, q3) of l1 + l2 cos q2 + l3 cos(q2 + q3) = 0 on one branch, or None.

    By q2: q3 = ±acos(-(l1 + l2 cos q2)/l3) - q2; by phi = q2 + q3: q2 = ±acos(-(l1 + l3
    cos phi)/l2), q3 = phi - q2.
    """
    a, b = (_L2, _L3) if by_q2 else (_L3, _L2)
    c = -(_L1 + a * np.cos(x)) / b
    s = sign * np.arccos(np.clip(c, -1, 1))
    return ((x, s - x) if by_q2 else (s, x - s)), np.abs(c) <= 1


_BRANCHES = [(by_q2, sign) for by_q2 in (True, False) for sign in (1, -1)]
_T = np.linspace(-math.pi, math.pi, 10_001)
_SAMPLED = [_hip_axis_branch(_T, *br) for br in _BRANCHES]


def _closest_on_hip_axis_family(p2, p3):
    """Brute force: the distance (torus metric) from (p2, p3) to the hip-axis family.

    Both dense parametrisations, both signs; the best sample of each branch within 1e-3 of
    the best is refined by scipy's bounded scalar search inside the branch's range.
    """
    from scipy.optimize import minimize_scalar

    def wrap(a):
        return a - 2 * math.pi * np.round(a / (2 * math.pi))

    def dist(x, by_q2, sign):
        (u, w), ok = _hip_axis_branch(x, by_q2, sign)
        return np.where(ok, np.hypot(wrap(u - p2), wrap(w - p3)), 10.0)

    grid = [np.where(ok, np.hypot(wrap(u - p2), wrap(w - p3)), 10.0) for (u, w), ok in _SAMPLED]
    best = min(float(d.min()) for d in grid)
    for d, br in zip(grid, _BRANCHES):
        if d.min() < best + 1e-3:
            x0 = _T[int(np.argmin(d))]
            res = minimize_scalar(
                lambda x, br=br: float(dist(x, *br)),
                bounds=(x0 - 1.3e-3, x0 + 1.3e-3),
                method="bounded",
                options={"xatol": 1e-15},
            )
            best = min(best, res.fun)
    return best


def test_family_distance_is_the_closest_point_against_brute_force(fresh_cache):
    # 1,000 uniform random configurations of the hexabot leg (l1 = 0.05, l2 = l3 = 0.1): the
    # hip-axis family l1 + l2 c2 + l3 c23 = 0, to 1e-9 of a brute-force closest point
    res = scan(load("hexabot_leg"), grid=5, joints=("knee", "ankle"), families=True)
    fam = next(f for f in res.families if f.joint is None)
    q = np.random.default_rng(3).uniform(-math.pi, math.pi, (1000, 3))
    q[:4, 1:] = [[0, 0], [0, math.pi], [math.pi, 0], [math.pi, math.pi]]  # grad f = 0 there
    got = fam.distance(q)
    ref = np.array([_closest_on_hip_axis_family(a, b) for a, b in q[:, 1:]])
    assert np.abs(got - ref).max() < 1e-9
    assert np.array_equal(fam.distance(q[::-1]), got[::-1])  # row by row: same bits
    # the joint families: the wrapped offset
    q3 = next(f for f in res.families if f.joint == 2 and f.value == 0)
    assert np.allclose(q3.distance(q), np.abs(np.angle(np.exp(1j * q[:, 2]))), atol=1e-15)


def test_family_distance_is_the_radius_of_the_first_circle_to_touch_the_family():
    # Solo12's knee family l1 c2 + l2 c23 = 0 with l1 = l2: crossing lines (grad f = 0 where
    # they cross). The distance d is exact when no zero lies inside the circle of radius
    # d (1 - 1e-9) around q and one lies on the circle of radius d (1 + 1e-9).
    from hexapod_kin.singularity import Family

    fam = Family("knee", "knee", (1, 2), None, None, False, "0.16*cos(q2) + 0.16*cos(q2 + q3)")
    q = np.zeros((25, 3))
    q[:, 1:] = np.random.default_rng(5).uniform(-math.pi, math.pi, (25, 2))
    got = fam.distance(q)
    angle = np.linspace(0, 2 * math.pi, 250_001)
    ring = np.column_stack([np.cos(angle), np.sin(angle)])
    for p, d in zip(q[:, 1:], got):
        inner = fam.residual(np.column_stack([np.zeros(len(ring)), p + d * (1 - 1e-9) * ring]))
        outer = fam.residual(np.column_stack([np.zeros(len(ring)), p + d * (1 + 1e-9) * ring]))
        assert np.all(np.sign(inner) == np.sign(inner[0])) and inner[0] != 0
        assert np.any(np.sign(outer) != np.sign(outer[0]))


def test_every_flagged_sample_labelled_with_a_distance(fresh_cache, leg):
    res = scan(leg, samples=20_000, seed=4, joints="all", families=True)
    flagged = res.singular
    assert flagged.any() and (res.family[flagged] >= 0).all()
    assert np.isfinite(res.family_distance[flagged]).all()
    assert np.isnan(res.family_distance[~flagged]).all()
    # labels agree with the family equations: the residual of the labelled family is smallest
    dists = np.stack([f.distance(res.q[flagged]) for f in res.families], axis=1)
    assert np.array_equal(np.argmin(dists, axis=1), res.family[flagged])
    assert sum(res.family_counts.values()) + res.unexplained.sum() == flagged.sum()


def _puma():
    from hexapod_kin.params import Chain, DHRow

    pi = math.pi
    dh = [(0, 0, 0, pi / 2), (0, 0, 0.4318, 0), (0, 0.15005, 0.0203, -pi / 2),
          (0, 0.4318, 0, pi / 2), (0, 0, 0, -pi / 2), (0, 0, 0, 0)]  # fmt: skip
    return load(Chain.from_dh([DHRow(*row) for row in dh], name="puma560"))


def test_default_fixed_joints_avoid_singular_values():
    # PUMA 560, all six rows: q5 = 0 (wrist) is singular for every q2, q3 — the old default
    puma = _puma()
    zero = scan(puma, grid=15, joints=(1, 2), rows="all", q_fixed=np.zeros(6), families=False)
    assert zero.singular.all()
    res = scan(puma, grid=15, joints=(1, 2), rows="all", families=False)
    assert res.singular.mean() < 0.3
    q5 = res.q_fixed[4]
    assert min(abs(math.sin(q5)), abs(q5)) > 0.1  # away from the wrist family sin q5 = 0
    assert not np.allclose(res.q_fixed, 0.0)


def test_default_joints_are_those_that_change_sigma_min():
    from hexapod_kin.singularity import default_joints

    assert default_joints(load("hexabot_leg")) == (1, 2)  # the hip yaw only rotates J
    panda = load("erd:panda")
    chosen = default_joints(panda)
    # joint 7 turns the flange about the TCP's own axis and the fingers do not move it:
    # neither changes the position Jacobian's sigma_min
    jac = panda.position_jacobian(panda.random_q(seed=2))
    assert np.abs(jac[:, 6]).max() < 1e-12
    assert not set(chosen) & {6, 7, 8}


def test_scan_refuses_huge_grids_and_bad_options(leg):
    with pytest.raises(ParameterError, match="at most"):
        scan(leg, grid=10**9)
    with pytest.raises(ParameterError, match="families"):
        scan(leg, grid=5, families="sometimes")
    with pytest.raises(ParameterError, match="samples"):
        scan(leg, samples=0)


def test_measures_batch_is_a_frozen_dataclass(leg):
    from dataclasses import FrozenInstanceError

    res = measures_batch(leg, leg.random_q(4, seed=1))
    with pytest.raises(FrozenInstanceError):
        res.det = None
    d = json.loads(json.dumps(res.to_dict(), allow_nan=False))
    assert d["rows"] == ["x", "y", "z"] and len(d["sigma_min"]) == 4
    m = measures(leg, np.zeros(3))  # stretched leg: singular, condition inf -> null
    assert json.loads(json.dumps(m.to_dict(), allow_nan=False))["condition"] is None


def test_heat_map_units_and_legend_outside(tmp_path, scara, fresh_cache):
    from hexapod_kin.plots import singularity_map_figure

    res = scan(scara, grid=(31, 11), joints=("theta2", "q4"), families=True)
    fig = singularity_map_figure(res)
    ax = fig.axes[0]
    assert ax.get_xlabel().endswith("[deg]") and ax.get_ylabel().endswith("[m]")
    x0, x1 = ax.get_xlim()
    assert x1 - x0 == pytest.approx(360, rel=0.1)  # degrees
    y0, y1 = ax.get_ylim()
    assert y1 - y0 == pytest.approx(0.2, rel=0.2)  # 0..0.2 m, in metres (not as radians)
    fig.canvas.draw()
    legend = ax.get_legend()
    assert legend is not None
    box, axes_box = legend.get_window_extent(), ax.get_window_extent()
    assert box.y1 <= axes_box.y0 + 1e-6  # below the axes, over no data
    import matplotlib.pyplot as plt

    plt.close(fig)
    from hexapod_kin.plots import plot_singularity_map

    assert plot_singularity_map(res, tmp_path / "m.svg").read_text().lstrip().startswith("<?xml")
    with pytest.raises(ParameterError, match="suffix"):
        plot_singularity_map(res, tmp_path / "m.bmp")


@pytest.mark.parametrize(("source", "tip"), [("hexapod", "leg3_foot"), ("erd:solo12", "FL_FOOT")])
def test_urdf_and_mounted_legs_get_families_from_their_recovered_table(source, tip, fresh_cache):
    # no Khalil table of their own: chain_from_urdf recovers one (the mount as base pose)
    model = load(source, tip=tip)
    res = scan(model, samples=30_000, seed=2, joints="all", families=True)
    assert len(res.families) >= 3, res.family_reason
    assert res.singular.any() and not res.unexplained.any()
    # an independent check of the labels: the q3 families are where the knee is stretched or
    # folded, i.e. the foot-to-hip-pitch distance is extremal
    q3 = [f for f, fam in enumerate(res.families) if fam.joint == 2]
    on = np.isin(res.family, q3) & res.explained
    assert on.any()
    wrapped = np.abs(np.angle(np.exp(1j * res.q[on, 2])))
    assert np.all(np.minimum(wrapped, np.pi - wrapped) < 0.7)
