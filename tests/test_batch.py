"""Batch FK / Jacobians (``fk_batch``, ``jacobian_batch``, ``fk_jacobian_batch``) vs Pinocchio.

Every result is compared with raw Pinocchio calls on the same model (its own ``Data``), in the
three reference frames, on random configurations spread over the kernel's blocks and threads,
with angles beyond the polynomial sin / cos range (the libm path, element by element).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import hexapod_kin as hk
from hexapod_kin import _chain
from hexapod_kin import _kernels as K
from hexapod_kin.exceptions import ConfigurationError

SOURCES = [
    ("hexabot_leg", {}),
    ("scara", {}),
    ("examples/leg4.toml", {}),
    ("erd:ur5_robot", {}),
    ("erd:solo12", {"tip": "FL_FOOT"}),
    ("erd:panda", {}),  # nq = 9 > 7 joints on the path: zero columns
    ("hexapod", {"tip": "leg2_femur"}),  # a frame inside the chain, mounted on a body
    ("hexabot_leg", {"tip": "base"}),  # no joint at all: nq = 0
]
REFS = {
    "local_world_aligned": pin.ReferenceFrame.LOCAL_WORLD_ALIGNED,
    "world": pin.ReferenceFrame.WORLD,
    "local": pin.ReferenceFrame.LOCAL,
}


def _pinocchio(model, q):
    """Pose and the three Jacobians of ``q`` by raw Pinocchio, in the model's base frame."""
    m, d = model.model, model.model.createData()
    base = model.baseMo
    pin.forwardKinematics(m, d, q)
    pose = (base * pin.updateFramePlacement(m, d, model.tip_id)).homogeneous
    jacs = {}
    for ref, pref in REFS.items():
        jac = pin.computeFrameJacobian(m, d, q, model.tip_id, pref)
        if ref == "world":
            jac = base.action @ jac
        elif ref == "local_world_aligned":
            jac = np.vstack([base.rotation @ jac[:3], base.rotation @ jac[3:]])
        jacs[ref] = jac
    return pose, jacs


def _configs(model, n, seed):
    qs = model.random_q(n, seed=seed)
    revolute = model.arrays.kind == 0
    if revolute.any():  # beyond the polynomial sin / cos range: libm for that element
        qs[n // 3, model.arrays.col[revolute]] = [2.5e5 * (-1) ** k for k in range(revolute.sum())]
    return qs


def _rows(n):
    """Rows to check: both ends of the threads' chunks and of some blocks, and random ones."""
    block, chunk = K.BLOCK, K.BLOCK * K.MIN_CHUNK_BLOCKS
    rows = {0, 1, n - 1, n // 2 - 1, n // 2, n // 3, block - 1, block, 2 * block + 7}
    rows |= {k * chunk + d for k in range(1, n // chunk + 1) for d in (-1, 0)}
    rows |= set(np.random.default_rng(0).integers(0, n, 40).tolist())
    return sorted(r for r in rows if 0 <= r < n)


@pytest.mark.parametrize(("source", "kw"), SOURCES)
def test_batch_equals_pinocchio_in_every_frame(source, kw):
    model = hk.load(source, **kw)
    n = 2 * K.MIN_PER_THREAD + 3 * K.BLOCK + 5  # two threads, chunks, a partial block
    qs = _configs(model, n, seed=11)
    poses = model.fk_batch(qs)
    jacs = {ref: model.jacobian_batch(qs, ref) for ref in REFS}
    both = model.fk_jacobian_batch(qs, "local")
    assert poses.shape == (n, 4, 4) and jacs["local"].shape == (n, 6, model.nq)
    np.testing.assert_array_equal(both[0], poses)
    np.testing.assert_array_equal(both[1], jacs["local"])
    for i in _rows(n):
        pose, ref_jacs = _pinocchio(model, qs[i])
        np.testing.assert_allclose(poses[i], pose, rtol=0, atol=1e-12, err_msg=f"row {i}")
        for ref, jac in ref_jacs.items():
            np.testing.assert_allclose(jacs[ref][i], jac, rtol=0, atol=1e-12, err_msg=ref)


def test_a_value_does_not_depend_on_its_neighbours():
    # the libm switch, the block and the thread of a row never change its bits
    model = hk.load("erd:ur5_robot")
    qs = _configs(model, 3 * K.BLOCK + 5, seed=4)
    poses, jacs = model.fk_jacobian_batch(qs, "local")
    for i in (0, qs.shape[0] // 3, K.BLOCK + 1, qs.shape[0] - 1):
        one_pose, one_jac = model.fk_jacobian_batch(qs[i : i + 1], "local")
        np.testing.assert_array_equal(one_pose[0], poses[i])
        np.testing.assert_array_equal(one_jac[0], jacs[i])


@pytest.mark.parametrize(
    ("bad", "message"), [(np.nan, "non-finite"), (-np.inf, "non-finite"), (1e151, "too large")]
)
def test_values_checked_inside_the_kernel_raise_the_model_message(bad, message):
    model = hk.load("hexabot_leg")
    qs = model.random_q(3 * K.MIN_PER_THREAD, seed=2)
    qs[-5, 1] = bad  # in the second thread's range
    for call in (model.fk_batch, model.jacobian_batch, model.fk_jacobian_batch):
        with pytest.raises(ConfigurationError, match=message):
            call(qs)
    out = np.empty((len(qs), 4, 4))
    with pytest.raises(ConfigurationError, match=message):
        model.fk_batch(qs, out=out)


def test_aligned_chain_rotations_map_z_to_the_axis():
    rng = np.random.default_rng(3)
    axes = [np.eye(3)[k] * s for k in range(3) for s in (1.0, -1.0)]
    axes += [v / np.linalg.norm(v) for v in rng.normal(size=(20, 3))]
    for u in axes:
        a = _chain._z_to(u)
        np.testing.assert_allclose(a @ [0.0, 0.0, 1.0], u, rtol=0, atol=1e-15)
        np.testing.assert_allclose(a.T @ a, np.eye(3), rtol=0, atol=1e-15)
        assert np.linalg.det(a) == pytest.approx(1.0, abs=1e-15)


@pytest.mark.slow
def test_the_tree_fk_benchmark_runs_and_its_engines_agree():
    """tools/bench_tree_fk.py (why fk_batch stays compiled) in quick mode: every row carries
    its peer's time and the engines agree to rounding (timings are not asserted)."""
    import json
    import subprocess
    import sys
    from pathlib import Path

    tool = Path(__file__).resolve().parent.parent / "tools" / "bench_tree_fk.py"
    res = subprocess.run(
        [sys.executable, str(tool), "--quick", "--json"],
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert res.returncode == 0, res.stderr[-2000:]
    rows = json.loads(res.stdout.strip().splitlines()[-1])
    assert len(rows) == 3
    # the engines agree (correctness columns); each ratio is the quotient of its row's times
    assert rows[0]["max_diff_m"] <= 1e-12 and all(r["max_diff_m"] <= 1e-12 for r in rows[1:])
    first = rows[0]
    assert first["speedup_vs_pinocchio"] == pytest.approx(
        first["pinocchio_loop_s"] / first["tree_fk_s"], rel=1e-9
    )
    for r in rows[1:]:
        assert r["ratio_tree_over_numba"] == pytest.approx(
            r["tree_fk_s"] / r["fk_batch_numba_s"], rel=1e-9
        )
