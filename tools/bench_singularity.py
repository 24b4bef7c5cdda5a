"""Benchmark: singularity measures of 1,000,000 configurations (3-DOF leg, every chain, UR5).

Compares, in one run:

* ``kernel`` — :func:`hexapod_kin.singularity.measures_batch` (fused numba kernel, generic over
  any loaded chain: FK + Jacobian + det + manipulability + condition number + sigma_min);
  compile time excluded (warm-up call first; ``cache=True``); median of repeats. Measured on
  1e6 uniform random samples of the joint ranges AND on a 100×100×100 grid, the whole
  default ``scan(grid=100)`` call (the two default joints, 10,000 configurations, family
  labels with exact distances; target 0.1 s) and the 3-D ``scan(grid=100, joints="all")``
  (1e6), and the kernel with the first-joint invariance skip disabled (its effect);
* ``numpy`` — ``jacobian_batch`` for the Jacobians, numpy batched SVD for the measures;
* ``pinocchio loop`` — a Python loop of ``pin.computeFrameJacobian`` + ``np.linalg.svd`` /
  ``det``, timed on a subset and extrapolated linearly to 1,000,000 (said in the output).

The 1-minute load average before and after is printed (other processes skew the figures).
Accuracy: the kernel's measures are compared with Pinocchio's at sampled configurations.

Then one line per chain (:data:`CHAINS`: every catalogue chain, a hexapod leg tip, the Solo12
front-left leg), default rows, 1e6 random configurations: the median of
``measures_batch(model, Q, out=...)`` (preallocated outputs) and of ``measures_batch(model, Q)``
(fresh output arrays: on this VM first-touch page faults of 32 MB can cost up to ~40 ms when
the allocator hands back unmapped memory), the target, and the largest difference from
Pinocchio (det, manipulability, sigma_min, 1/condition) at sampled configurations.
"""

from __future__ import annotations

import os
import statistics
import time
from functools import partial

import numpy as np

N = 1_000_000


def _pin_loop(model, qs):
    import pinocchio as pin

    m, d, fid = model.model, model.data, model.tip_id
    ref = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    out = np.empty((len(qs), 4))
    with np.errstate(divide="ignore"):
        for i, q in enumerate(qs):
            jac = pin.computeFrameJacobian(m, d, q, fid, ref)[:3]
            sv = np.linalg.svd(jac, compute_uv=False)
            det = np.linalg.det(jac)
            out[i] = det, abs(det), sv[0] / sv[-1], sv[-1]
    return out


def _median_time(fn, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), min(times)


def _load() -> str:
    try:
        return f"{os.getloadavg()[0]:.2f}"
    except OSError:  # pragma: no cover
        return "n/a"


#: Every catalogue chain (default rows), a hexapod leg tip and a Solo12 leg.
CHAINS = (
    ("hexabot_leg", None),
    ("coxa_tibia_leg", None),
    ("scara", None),
    ("pendulum", None),
    ("hexapod", "leg1_foot"),
    ("erd:solo12", "FL_FOOT"),
)


def _pin_measures(model, qs, rows):
    """Pinocchio Jacobians (selected rows) + numpy SVD: (det, manipulability, 1/cond, smin)."""
    import pinocchio as pin

    from hexapod_kin.singularity import ROW_NAMES

    idx = [ROW_NAMES.index(r) for r in rows]
    m, d, fid = model.model, model.data, model.tip_id
    ref = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    # (6, nv) reshaped: eigenpy returns a 1-D array when nv = 1
    jac = np.array([pin.computeFrameJacobian(m, d, q, fid, ref).reshape(6, -1)[idx] for q in qs])
    sv = np.linalg.svd(jac, compute_uv=False)
    k, n = jac.shape[1:]
    det = np.linalg.det(jac) if k == n else np.full(len(qs), np.nan)
    return det, np.prod(sv, axis=1), sv[:, -1] / sv[:, 0], sv[:, -1]


def run_chains(quick: bool) -> list[dict]:
    """One line per chain: ``measures_batch(model, Q)`` on 1e6 random configurations."""
    from hexapod_kin import load
    from hexapod_kin import singularity as sing
    from hexapod_kin.singularity import _plan as kplan

    repeats = 5 if quick else 11
    n_err = 2_000 if quick else 5_000
    rows_out = []
    for source, tip in CHAINS:
        load_before = _load()
        model = load(source, tip=tip)
        rows = sing.default_rows(model)
        qs = model.random_q(N, seed=0)
        out = tuple(np.empty(N) for _ in range(4))
        sing.measures_batch(model, qs[:1000])  # warm-up / compile
        with_out = partial(sing.measures_batch, model, qs, out=out)
        t_out, t_out_min = _median_time(with_out, repeats)
        t_new, _ = _median_time(partial(sing.measures_batch, model, qs), repeats)
        pick = np.random.default_rng(3).choice(N, n_err, replace=False)
        pdet, pmanip, pinv, psmin = _pin_measures(model, qs[pick], rows)
        det, manip, cond, smin = (o[pick] for o in out)
        errs = [np.abs(manip - pmanip).max(), np.abs(smin - psmin).max()]
        errs.append(np.abs(1 / cond - pinv).max())
        if not np.isnan(pdet).all():
            errs.append(np.abs(det - pdet).max())
        sel = tuple(sing.ROW_NAMES.index(r) for r in rows)
        skip0 = kplan.first_joint_invariant(kplan.aligned(model), sel)
        plan = kplan.gram_plan(model, sel, skip0)
        gram = "Jt J" if plan.gram_t else "J Jt"
        blocks = "+".join(str(int(c)) for c in plan.csize)
        name = source + (f" tip={tip}" if tip else "")
        rows_out.append(
            {
                "case": f"{name} 1e6 random configs, rows {','.join(rows)} "
                f"({len(rows)}x{model.nq} J, G = {gram} blocks {blocks}, skip0={skip0})",
                "engine": "measures_batch (kernel)",
                "median_s": round(t_out, 4),
                "min_s": round(t_out_min, 4),
                "median_s_fresh_outputs": round(t_new, 4),
                "target_s": 0.1,
                "meets_target": t_out <= 0.1 and t_new <= 0.1,
                "max_abs_err_vs_pinocchio": f"{max(errs):.1e} (det, manip, sigma_min, 1/cond at "
                f"{n_err} configs)",
                "load_avg_1min": f"{load_before} -> {_load()}",
            }
        )
    return rows_out


def run(quick: bool) -> list[dict]:
    import numba

    from hexapod_kin import load
    from hexapod_kin import singularity as sing
    from hexapod_kin.singularity import _plan as kplan
    from hexapod_kin.singularity._kernel import measures_kernel

    threads = numba.get_num_threads()
    load_before = _load()
    model = load("hexabot_leg")
    qs = model.random_q(N, seed=0)
    axes = [np.linspace(model.lower[j], model.upper[j], 100) for j in range(3)]
    grid_q = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    out = tuple(np.empty(N) for _ in range(4))
    sing.measures_batch(model, qs[:1000], out=tuple(o[:1000] for o in out))  # warm-up / compile
    repeats = 5 if quick else 15
    t_grid, t_grid_min = _median_time(lambda: sing.measures_batch(model, grid_q, out=out), repeats)
    grid_out = tuple(o.copy() for o in out)
    t_kernel, t_kernel_min = _median_time(lambda: sing.measures_batch(model, qs, out=out), repeats)

    # the same kernel with the first-joint invariance skip off (hip sin/cos + rotation kept)
    al = kplan.aligned(model)
    sel = np.arange(3)
    assert kplan.first_joint_invariant(al, (0, 1, 2))
    out_ns = tuple(np.empty(N) for _ in range(4))

    plans = {skip: kplan.gram_plan(model, (0, 1, 2), skip) for skip in (False, True)}

    def raw(skip0: bool) -> None:
        measures_kernel(
            al.prot,
            al.ptr,
            al.flags,
            al.kind,
            al.col,
            qs,
            sel,
            plans[skip0].arrays,
            False,
            np.empty((2, 1)),
            skip0,
            0,
            -(-N // kplan.BLOCK),
            kplan.BLOCK,
            *out_ns,
        )

    t_noskip, _ = _median_time(lambda: raw(False), repeats)
    t_skip, _ = _median_time(lambda: raw(True), repeats)
    t_noskip2, _ = _median_time(lambda: raw(False), repeats)
    t_noskip = min(t_noskip, t_noskip2)  # interleaved, to not favour the skip
    sing.scan(model, grid=20, families=True)  # warm-up (families derived once, then cached)
    t_scan, _ = _median_time(lambda: sing.scan(model, grid=100), 5 if quick else 15)
    flagged = int(sing.scan(model, grid=100).singular.sum())
    t_scan3, _ = _median_time(lambda: sing.scan(model, grid=100, joints="all"), 3)

    n_np = 100_000 if quick else 200_000

    def numpy_measures() -> None:
        np.linalg.svd(model.jacobian_batch(qs[:n_np])[:, :3, :], compute_uv=False)

    t_np, _ = _median_time(numpy_measures, 3)
    t_np *= N / n_np

    n_pin = 5_000 if quick else 20_000
    _pin_loop(model, qs[:200])
    t0 = time.perf_counter()
    ref = _pin_loop(model, qs[:n_pin])
    t_pin = (time.perf_counter() - t0) * N / n_pin
    pick = np.random.default_rng(1).choice(N, n_pin, replace=False)
    ref_grid = _pin_loop(model, grid_q[pick])
    load_after = _load()

    def max_err(res: tuple[np.ndarray, ...], idx: np.ndarray, ref: np.ndarray) -> float:
        det, manip, cond, smin = (r[idx] for r in res)
        with np.errstate(divide="ignore"):
            return float(
                max(
                    np.abs(det - ref[:, 0]).max(),
                    np.abs(manip - ref[:, 1]).max(),
                    np.abs(smin - ref[:, 3]).max(),
                    np.abs(1 / cond - 1 / ref[:, 2]).max(),
                )
            )

    err = max_err(out, np.arange(n_pin), ref)
    err_grid = max_err(grid_out, pick, ref_grid)
    err_ns = max(float(np.abs(a - b)[np.isfinite(b)].max()) for a, b in zip(out_ns[:2], out[:2]))
    loads = f"{load_before} -> {load_after}"
    case = "hexabot_leg 1e6 configs: J + det + manipulability + condition + sigma_min"
    rows = [
        {
            "case": case + " (uniform random samples)",
            "engine": "kernel (numba, fused, generic chain; measures_batch)",
            "threads": threads,
            "median_s": round(t_kernel, 4),
            "min_s": round(t_kernel_min, 4),
            "target_s": 0.1,
            "meets_target": t_kernel <= 0.1,
            "speedup_vs_pinocchio_loop": round(t_pin / t_kernel, 1),
            "max_abs_err_vs_pinocchio": f"{err:.1e} (at {n_pin} configs; 1/condition compared)",
            "load_avg_1min": loads,
        },
        {
            "case": case + " (100x100x100 grid, the input of scan(grid=100))",
            "engine": "kernel (same call, grid configurations)",
            "threads": threads,
            "median_s": round(t_grid, 4),
            "min_s": round(t_grid_min, 4),
            "target_s": 0.1,
            "meets_target": t_grid <= 0.1,
            "speedup_vs_pinocchio_loop": round(t_pin / t_grid, 1),
            "max_abs_err_vs_pinocchio": f"{err_grid:.1e} (at {n_pin} grid configs)",
        },
        {
            "case": case + " (random samples)",
            "engine": "raw kernel call (one thread, no input checks): invariance skip off vs on",
            "median_s_skip_off": round(t_noskip, 4),
            "median_s_skip_on": round(t_skip, 4),
            "skip_saves_s": round(t_noskip - t_skip, 4),
            "max_abs_diff_det_manip_vs_skip": f"{err_ns:.1e}",
            "speedup_vs_pinocchio_loop": round(t_pin / t_noskip, 1),
        },
        {
            "case": f"hexabot_leg scan(grid=100): 100x100 default joints, {flagged} flagged "
            "labelled with exact family distances",
            "engine": "singularity.scan (whole call)",
            "median_s": round(t_scan, 4),
            "target_s": 0.1,
            "meets_target": t_scan <= 0.1,
        },
        {
            "case": "hexabot_leg scan(grid=100, joints='all'): 1e6 configs, family labels",
            "engine": "singularity.scan (whole call)",
            "median_s": round(t_scan3, 3),
            "note": "includes building q (24 MB) and exact distances of 53,400 flagged samples",
        },
        {
            "case": "hexabot_leg 1e6 configs",
            "engine": "numpy SVD on jacobian_batch Jacobians",
            "time_s": round(t_np, 3),
            "note": f"timed on {n_np} configs, extrapolated x{N // n_np}",
            "kernel_speedup": round(t_np / t_kernel, 1),
        },
        {
            "case": "hexabot_leg 1e6 configs",
            "engine": "pinocchio Python loop (computeFrameJacobian + svd + det)",
            "time_s": round(t_pin, 3),
            "note": f"timed on {n_pin} configs, extrapolated x{N // n_pin}",
            "ratio_to_kernel": round(t_pin / t_kernel, 1),
        },
    ]
    return rows + run_chains(quick) + run_arm(quick)


def _pin_loop6(model, qs):
    """Pinocchio loop for a 6×6 arm Jacobian: J, SVD, det per configuration."""
    import pinocchio as pin

    m, d, fid = model.model, model.data, model.tip_id
    ref = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    out = np.empty((len(qs), 4))
    with np.errstate(divide="ignore"):
        for i, q in enumerate(qs):
            jac = pin.computeFrameJacobian(m, d, q, fid, ref)
            sv = np.linalg.svd(jac, compute_uv=False)
            det = np.linalg.det(jac)
            out[i] = det, abs(det), sv[0] / sv[-1], sv[-1]
    return out


def run_arm(quick: bool) -> list[dict]:
    """UR5 (example-robot-data), all six rows: the 6×6 Jacobian, 1e6 configurations."""
    from hexapod_kin import load
    from hexapod_kin import singularity as sing

    load_before = _load()
    model = load("erd:ur5_robot")
    qs = model.random_q(N, seed=0)
    out = tuple(np.empty(N) for _ in range(4))
    sing.measures_batch(model, qs[:1000], "all")  # warm-up / compile
    t_k, t_k_min = _median_time(
        partial(sing.measures_batch, model, qs, "all", out=out), 3 if quick else 7
    )
    n_pin = 5_000 if quick else 20_000
    _pin_loop6(model, qs[:200])
    t0 = time.perf_counter()
    ref = _pin_loop6(model, qs[:n_pin])
    t_pin = (time.perf_counter() - t0) * N / n_pin
    det, manip, cond, smin = (o[:n_pin] for o in out)
    err = max(
        float(np.abs(det - ref[:, 0]).max()),
        float(np.abs(smin - ref[:, 3]).max()),
        float(np.abs(1 / cond - 1 / ref[:, 2]).max()),
    )
    return [
        {
            "case": "erd:ur5_robot 1e6 random configs, rows all (6x6 J)",
            "engine": "measures_batch (kernel)",
            "median_s": round(t_k, 4),
            "min_s": round(t_k_min, 4),
            "target_s": 0.3,
            "meets_target": t_k <= 0.3,
            "pinocchio_loop_s": round(t_pin, 3),
            "speedup_vs_pinocchio_loop": round(t_pin / t_k, 1),
            "max_abs_err_vs_pinocchio": f"{err:.1e} (det, sigma_min, 1/cond at {n_pin} configs)",
            "load_avg_1min": f"{load_before} -> {_load()}",
        }
    ]


if __name__ == "__main__":
    import sys

    for row in run(quick="--quick" in sys.argv):
        print("  ".join(f"{k}={v}" for k, v in row.items()))
