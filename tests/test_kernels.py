"""The kernel layer: batch FK/Jacobian kernels and the singularity kernel (its public functions).

Against Pinocchio (every catalogue chain, URDF legs, arms), numpy LAPACK and closed forms.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import hexapod_kin as hk
from hexapod_kin import Chain, KhalilRow, load
from hexapod_kin import _kernels as K
from hexapod_kin._kernels import njit
from hexapod_kin.exceptions import ConfigurationError
from hexapod_kin.singularity import ROW_NAMES, default_rows, measures_batch
from hexapod_kin.singularity._kernel import (
    JACOBI_TOL,
    POLY_TRIG_MAX,
    eig_block,
    measures_kernel,
    minor_big,
    sincos,
)
from hexapod_kin.singularity._plan import BLOCK, aligned, first_joint_invariant, gram_plan

SOURCES = [
    ("hexabot_leg", {}),
    ("coxa_tibia_leg", {}),
    ("scara", {}),
    ("pendulum", {}),
    ("hexapod", {"tip": "leg5_foot"}),
    ("erd:solo12", {"tip": "HR_FOOT"}),
]


@pytest.mark.parametrize("source,kw", SOURCES)
def test_batch_kernels_equal_pinocchio(source, kw):
    model = hk.load(source, **kw)
    qs = model.random_q(300, seed=3)
    pos = model.fk_batch(qs)
    jac = model.jacobian_batch(qs)
    for i, q in enumerate(qs):
        np.testing.assert_allclose(pos[i], model.fk(q), atol=1e-12)
        np.testing.assert_allclose(jac[i], model.jacobian(q), atol=1e-12)


def test_whole_hexapod_kernel_has_zero_columns_for_other_legs():
    model = hk.load("hexapod")
    arrays = K.ChainArrays.from_model(model, frame="leg2_foot")
    q = model.random_q(seed=1)
    _, jac = K.pose_jacobian_batch(
        K.aligned_chain(arrays), q[None], pose=False, jacobian="local_world_aligned"
    )
    assert jac is not None
    jac = jac[0]
    np.testing.assert_allclose(jac, model.jacobian(q, frame="leg2_foot"), atol=1e-12)
    assert np.all(jac[:, :3] == 0) and np.all(jac[:, 6:] == 0)


def test_kernel_input_checks():
    model = hk.load("hexabot_leg")
    with pytest.raises(ConfigurationError, match=r"\(N, 3\)"):
        model.fk_batch(np.zeros((4, 2)))
    with pytest.raises(ConfigurationError, match="non-finite"):
        model.jacobian_batch(np.full((2, 3), np.nan))
    assert not model.arrays.rot.flags.writeable


def pin_measures(model, qs, rows):
    idx = [ROW_NAMES.index(r) for r in rows]
    jac = np.array([model.jacobian(q)[idx] for q in qs])
    sv = np.linalg.svd(jac, compute_uv=False)
    k, n = jac.shape[1:]
    det = np.linalg.det(jac) if k == n else np.full(len(qs), np.nan)
    return det, np.prod(sv, axis=1), sv[:, 0], sv[:, -1]


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
    ("five_dof", None, "all"),  # 6×5: m = 5, 6 minors of 5×5 (Laplace 2 + 3)
    ("erd:ur5_robot", None, "all"),  # 6×6: generic block Jacobi, Laplace 3 + 3
    ("erd:panda", None, "all"),  # 6×9 (fingers: zero columns): 84 minors: Pinocchio + numpy
    ("erd:panda", None, ("x", "y", "z", "wx")),  # 4×9: 126 minors: Pinocchio + numpy
]


def _five_dof():
    rows = [
        KhalilRow("revolute", a, d, 0.0, r)
        for a, d, r in (
            (0.0, 0.0, 0.1),
            (math.pi / 2, 0.05, 0.0),
            (0.0, 0.2, 0.02),
            (-math.pi / 2, 0.01, 0.15),
            (math.pi / 2, 0.0, 0.0),
        )
    ]
    return Chain(rows=(*rows, KhalilRow("fixed", 0.0, 0.0, 0.0, 0.08)), name="five_dof")


def _load_chain(source, tip):
    return load(_five_dof()) if source == "five_dof" else load(source, tip=tip)


@pytest.mark.parametrize(("source", "tip", "rows"), CHAINS)
def test_every_chain_equals_pinocchio(source, tip, rows):
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
    plan = gram_plan(model, sel, first_joint_invariant(aligned(model), sel))
    k, n = len(names), model.nq
    assert plan.use_block == (min(k, n) <= 6 and math.comb(max(k, n), min(k, n)) <= 70)


def testgram_plans_split_where_structure_allows():
    def sizes(source, tip=None):
        model = load(source, tip=tip)
        return sorted(gram_plan(model, (0, 1, 2, 5)[: 4 if source == "scara" else 3], True).csize)

    assert sizes("hexabot_leg") == [1, 2]
    assert sizes("hexapod", "leg1_foot") == [1, 2]
    assert sizes("scara") == [1, 3]
    assert sizes("erd:solo12", "FL_FOOT") == [3]
    assert sizes("coxa_tibia_leg") == [1, 1]


@pytest.mark.parametrize("use_jacobi", [True, False])
def test_wrong_split_guess_is_caught_per_block(use_jacobi):
    # a plan claiming G = {0} ⊕ {1, 2} for the Solo12 leg (false: G[0, 2] != 0) must not
    # change the results: the kernel checks the dropped entries on every block
    from dataclasses import replace

    model = load("erd:solo12", tip="FL_FOOT")
    al = aligned(model)
    plan = gram_plan(model, (0, 1, 2), True)
    perm = np.array([0, 1, 2])
    csize = np.array([1, 2])
    drop = np.array([1, 2])  # packed (0, 1), (0, 2)
    pack, rsub, csub, gram_t = plan.arrays[:4]
    bad = replace(plan, arrays=(pack, rsub, csub, False, perm, csize, drop))
    qs = model.random_q(1200, seed=5)
    out = tuple(np.empty(len(qs)) for _ in range(4))
    measures_kernel(
        al.prot,
        al.ptr,
        al.flags,
        al.kind,
        al.col,
        qs,
        np.arange(3),
        bad.arrays,
        use_jacobi,  # False: no Jacobi (the 3×3 closed form where a split fails)
        np.empty((2, 1)),
        True,
        0,
        -(-len(qs) // BLOCK),
        BLOCK,
        *out,
    )
    _, _, smax, psmin = pin_measures(model, qs, ("x", "y", "z"))
    assert np.abs(out[3] - psmin).max() < 1e-12
    assert np.abs(1 / out[2] - psmin / smax).max() < 1e-12


def test_first_joint_invariance_rule():
    # S·blockdiag(R, R)·Sᵀ orthogonal <=> the measures do not depend on joint 0
    leg = aligned(load("hexabot_leg"))  # hip axis z
    assert first_joint_invariant(leg, (0, 1, 2))
    assert first_joint_invariant(leg, (0, 1, 2, 5))
    assert first_joint_invariant(leg, (0, 1, 2, 3, 4, 5))
    assert first_joint_invariant(leg, (0, 1))
    assert not first_joint_invariant(leg, (0, 2))
    assert not first_joint_invariant(leg, (0, 1, 2, 3))
    solo = aligned(load("erd:solo12", tip="FL_FOOT"))  # HAA axis x
    assert first_joint_invariant(solo, (0, 1, 2))
    assert first_joint_invariant(solo, (1, 2, 3))
    assert not first_joint_invariant(solo, (0, 1, 2, 5))
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


def test_polynomialsincos_matches_libm():
    @njit
    def both(x, s, c):
        for i in range(x.shape[0]):
            s[i], c[i] = sincos(x[i])

    rng = np.random.default_rng(5)
    k = np.arange(-400, 401)
    x = np.concatenate(
        [
            rng.uniform(-7, 7, 200_000),
            rng.uniform(-POLY_TRIG_MAX, POLY_TRIG_MAX, 200_000),
            k * (np.pi / 4),
            np.nextafter(k * (np.pi / 4), np.inf),
            [0.0, -0.0, 1e-300, -1e-300, POLY_TRIG_MAX, -POLY_TRIG_MAX],
        ]
    )
    s, c = np.empty_like(x), np.empty_like(x)
    both(x, s, c)
    assert np.abs(s - np.sin(x)).max() <= 2.3e-16
    assert np.abs(c - np.cos(x)).max() <= 2.3e-16


def _spectra_matrices(m, rng):
    """Symmetric PSD m×m matrices with clustered, repeated and zero eigenvalues, and random."""
    spectra = [
        (1.0, 1.0 - 1e-9, 0.5, 0.25, 0.1, 0.05),
        (1.0, 0.3, 0.3 - 1e-10, 0.1, 0.1, 1e-12),
        (1.0, 1.0, 1.0, 1.0, 1.0, 1.0),
        (1.0, 1e-20, 0.0, 0.0, 0.0, 0.0),
        (2.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        (0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        (1.0, 1.0 - 1e-6, 1.0 - 2e-6, 1e-8, 1e-8, 0.5),
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


@pytest.mark.parametrize("m", [3, 4, 5, 6])
def test_eig_block_clustered_and_rank_deficient(m):
    # Jacobi is backward stable for any eigenvalue clustering (the closed forms are not)
    g = _spectra_matrices(m, np.random.default_rng(9))
    iu = np.triu_indices(m)
    gb = np.ascontiguousarray(g[:, iu[0], iu[1]].T)
    eig_block(gb, g.shape[0], m, np.empty_like(gb), np.empty(g.shape[0], dtype=np.int64))
    diag = iu[0] == iu[1]
    got = np.sort(gb[diag].T, axis=1)
    ref = np.linalg.eigvalsh(g)
    scale = np.maximum(ref[:, -1], 1e-300)
    assert (np.abs(got - ref).max(axis=1) / scale).max() < 1e-14
    # the documented stopping rule holds: Weyl, or the quadratic bound for isolated eigenvalues
    off = np.abs(gb[~diag]).sum(axis=0)
    tol = JACOBI_TOL * gb[diag].sum(axis=0)
    d = gb[diag]
    gap = np.min([np.abs(d[a] - d[b]) for a in range(m) for b in range(a + 1, m)], axis=0)
    quad = (gap > 3 * off) & (2 * off**2 <= tol * (gap - off))
    assert np.all((off <= tol) | quad)


def test_minor_block_and_cauchy_binet():
    # explicit minors (m <= 4) against numpy det; det(J Jᵀ) = sum of squared maximal minors
    from itertools import combinations

    @njit
    def minors(jb, r, c, m, out):
        minor_big(jb, r, c, m, jb.shape[2], out, np.empty((2, jb.shape[2])))

    rng = np.random.default_rng(4)
    for m in (1, 2, 3, 4, 5, 6):
        jb = rng.normal(size=(m, 7, 64))
        total = np.zeros(64)
        for cols in combinations(range(7), m):
            out = np.empty(64)
            minors(jb, np.arange(m), np.array(cols), m, out)
            ref = np.linalg.det(np.moveaxis(jb[:, list(cols)], 2, 0))
            assert np.abs(out - ref).max() < 1e-12 * max(1.0, np.abs(ref).max())
            total += out**2
        jac = np.moveaxis(jb, 2, 0)
        gram = np.linalg.det(jac @ np.swapaxes(jac, 1, 2))
        assert np.allclose(total, gram, rtol=1e-10)


@pytest.mark.parametrize("source,kw", [("hexabot_leg", {}), ("scara", {}), ("erd:ur5_robot", {})])
def test_a_measure_does_not_depend_on_its_neighbours(source, kw):
    # per-element libm switch, split check and Jacobi sweeps: a row alone gives the same bits
    from hexapod_kin.singularity._plan import compute, output_arrays

    model = hk.load(source, **kw)
    qs = model.random_q(2 * BLOCK + 9, seed=8)
    qs[5, model.arrays.col[0]] = 3.0e5  # beyond the polynomial sin / cos range
    qs[BLOCK + 3] = 0.0  # a singular configuration among regular ones
    sel = np.arange(min(6, model.nq), dtype=np.int64)
    whole = [o.copy() for o in compute(model, qs, sel, output_arrays(len(qs)))]
    for i in (0, 5, BLOCK + 3, len(qs) - 1):
        one = compute(model, qs[i : i + 1].copy(), sel, output_arrays(1))
        for w, o in zip(whole, one):
            np.testing.assert_array_equal(o[0], w[i])


_SWEEPS = """
import numpy as np
from hexapod_kin.singularity import _blocks
for m in (3, 6):  # unrolled sweeps and the pair-by-pair ones
    k, nb = m * (m + 1) // 2, 8
    gb = np.zeros((k, nb))
    gb[[i * m - i * (i - 1) // 2 for i in range(m)]] = 1.0
    gb[1] = 0.5
    _blocks.eig_block(gb, nb, m, np.empty((k, nb)), np.empty(nb, np.int64))
print(len(_blocks._sweep_many.signatures), len(_blocks._sweep_gen.signatures))
"""


@pytest.mark.slow
def test_the_jacobi_sweeps_compile_once(tmp_path):
    """One specialisation per sweep on a fresh cache (the open count once was numba's literal
    0: each sweep compiled twice)."""
    import os
    import subprocess
    import sys

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    env["HEXAPOD_KIN_CACHE_DIR"] = str(tmp_path / "hk")
    res = subprocess.run(
        [sys.executable, "-c", _SWEEPS], env=env, capture_output=True, text=True, timeout=900
    )
    assert res.returncode == 0, res.stderr[-2000:]
    assert res.stdout.split() == ["1", "1"]


@pytest.mark.slow
def test_precompile_in_child_processes(monkeypatch: pytest.MonkeyPatch):
    """Areas in parallel children (their seconds, in the order asked), a failed child's area
    compiled here instead, and the arguments checked."""
    from hexapod_kin import precompile as pc
    from hexapod_kin.exceptions import ParameterError

    seconds = pc.precompile(["batch", "ik"], processes=2)
    assert list(seconds) == ["batch", "ik"] and all(v > 0 for v in seconds.values())
    called: list[str] = []
    monkeypatch.setattr(pc, "_CHILD", "raise SystemExit(3)")
    monkeypatch.setitem(pc.AREAS, "batch", lambda: called.append("batch"))
    monkeypatch.setitem(pc.AREAS, "ik", lambda: called.append("ik"))
    assert list(pc.precompile(["ik", "batch"], processes=2)) == ["ik", "batch"]
    assert called == ["ik", "batch"]  # both children failed: both compiled in this process
    with pytest.raises(ParameterError, match="processes"):
        pc.precompile(["batch"], processes=0)
    with pytest.raises(ParameterError):
        pc.precompile(["nope"])


def test_precompile_shares_and_progress(monkeypatch: pytest.MonkeyPatch, capsys):
    """The costliest area to the least busy worker (a child starts 1 s late), each area
    reported as it ends, and the first-use notice saying about how long it takes."""
    from hexapod_kin import _kernels
    from hexapod_kin import precompile as pc

    cost = {"a": 12.0, "b": 9.0, "c": 3.0}
    assert pc._shares(["c", "b", "a"], 2, cost) == [["a"], ["b", "c"]]  # 12 vs 1 + 9 + 3
    assert pc._shares(["c", "b", "a"], 1, cost) == [["a", "b", "c"]]
    assert pc._shares(["c"], 4, cost) == [["c"]]
    ran: list[str] = []
    monkeypatch.setitem(pc.AREAS, "batch", lambda: ran.append("batch"))
    monkeypatch.setitem(pc.AREAS, "ik", lambda: ran.append("ik"))
    said: list[str] = []
    pc.precompile(["batch", "ik"], done=lambda name, dt: said.append(name))
    assert said == ran == ["ik", "batch"]  # the costliest first
    monkeypatch.setattr(_kernels, "_stamp", lambda area: None)
    monkeypatch.setattr(_kernels, "_NOTICE", [True])
    assert _kernels._notice("singularity")
    err = capsys.readouterr().err
    assert f"about {_kernels.COMPILE_SECONDS['singularity']:.0f} s" in err


_THREADS = """
import numba
from hexapod_kin import _kernels as K
n = K.threads()
try:
    numba.threading_layer()
    started = True
except ValueError:
    started = False
numba.set_num_threads(1)
print(n, int(numba.config.NUMBA_NUM_THREADS), started, K.threads())
"""


def test_the_thread_count_starts_no_numba_pool_and_follows_set_num_threads():
    """``threads()`` is numba's count, without starting numba's threading layer (the
    kernels run on Python threads); once ``numba.set_num_threads(1)`` is called, 1."""
    import subprocess
    import sys

    out = subprocess.run(
        [sys.executable, "-c", _THREADS], capture_output=True, text=True, check=True
    ).stdout.split()
    assert out[0] == out[1] and int(out[0]) >= 1
    assert out[2] == "False" and out[3] == "1"


def test_a_first_call_pauses_the_garbage_collector_and_restores_its_state(monkeypatch):
    """The compile runs with Python's cyclic GC off (issue 34: a fifth of the compile's CPU);
    after it, enabled or disabled as it was, also when the compile fails."""
    import gc

    from hexapod_kin import _kernels

    seen: list[bool] = []

    def first_run(area, run):
        seen.append(gc.isenabled())
        if area == "failing":
            raise ValueError("planted")
        return 7

    monkeypatch.setattr(_kernels, "_first_run", first_run)
    monkeypatch.setattr(_kernels, "_NOTICE", [False])
    monkeypatch.setattr(_kernels, "seal_compiled", lambda: None)
    try:
        for enabled in (True, False):
            (gc.enable if enabled else gc.disable)()
            assert _kernels._first_call("no-such-area", lambda a, b: None) == 7
            assert gc.isenabled() is enabled
            with pytest.raises(ValueError, match="planted"):
                _kernels._first_call("failing", lambda a, b: None)
            assert gc.isenabled() is enabled
    finally:
        gc.enable()
    assert seen == [False, False, False, False]


def test_read_only_configurations_reuse_the_compiled_signature():
    """A read-only ``qs`` is copied, never compiled for: numba types a read-only array apart, and
    a second signature was a second compile (~5 s) after ``precompile`` (issue 34: once)."""
    from hexapod_kin._kernels import pose_jacobian_kernel
    from hexapod_kin.singularity._kernel import measures_kernel

    leg = load("hexabot_leg")
    qs = leg.random_q(300, seed=4)
    ref_fk, ref_m = leg.fk_batch(qs), list(measures_batch(leg, qs))
    before = len(pose_jacobian_kernel.overloads), len(measures_kernel.overloads)
    ro = qs.copy()
    ro.setflags(write=False)
    fk, m = leg.fk_batch(ro), list(measures_batch(leg, ro))
    assert (len(pose_jacobian_kernel.overloads), len(measures_kernel.overloads)) == before
    assert fk.tobytes() == ref_fk.tobytes()
    assert [a.tobytes() for a in m] == [a.tobytes() for a in ref_m]
