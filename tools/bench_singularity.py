"""Benchmark: singularity measures of 1,000,000 configurations of the 3-DOF leg.

Compares, in one run:

* ``kernel`` — :func:`hexapod_kin.singularity.measures_batch` (fused numba kernel, generic over
  any loaded chain: FK + Jacobian + det + manipulability + condition number + sigma_min);
  compile time excluded (warm-up call first; ``cache=True``); median of repeats;
* ``numpy`` — the same chain kernel for the Jacobians, numpy batched SVD for the measures;
* ``pinocchio loop`` — a Python loop of ``pin.computeFrameJacobian`` + ``np.linalg.svd`` /
  ``det``, timed on a subset and extrapolated linearly to 1,000,000 (said in the output).

Accuracy: the kernel's measures are compared with Pinocchio's at sampled configurations.
"""

from __future__ import annotations

import statistics
import time

import numpy as np

N = 1_000_000


def _pin_loop(model, qs):
    import pinocchio as pin

    m, d, fid = model.model, model.data, model.tip_id
    ref = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    out = np.empty((len(qs), 4))
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


def run(quick: bool) -> list[dict]:
    from hexapod_kin import _kernels, load
    from hexapod_kin.singularity import measures_batch

    try:
        import numba

        threads = numba.get_num_threads()
    except ImportError:  # pragma: no cover
        threads = 1
    model = load("hexabot_leg")
    qs = model.random_q(N, seed=0)
    out = tuple(np.empty(N) for _ in range(4))
    measures_batch(model, qs[:1000], out=tuple(o[:1000] for o in out))  # warm-up / compile
    repeats = 5 if quick else 15
    t_kernel, t_kernel_min = _median_time(lambda: measures_batch(model, qs, out=out), repeats)

    n_np = 100_000 if quick else 200_000
    t_np, _ = _median_time(lambda: measures_batch(model, qs[:n_np], engine="numpy"), 3)
    t_np *= N / n_np

    n_pin = 5_000 if quick else 20_000
    _pin_loop(model, qs[:200])
    t0 = time.perf_counter()
    ref = _pin_loop(model, qs[:n_pin])
    t_pin = (time.perf_counter() - t0) * N / n_pin

    # accuracy at the Pinocchio-evaluated configurations
    det, manip, cond, smin = out
    err = max(
        np.abs(det[:n_pin] - ref[:, 0]).max(),
        np.abs(manip[:n_pin] - ref[:, 1]).max(),
        np.abs(smin[:n_pin] - ref[:, 3]).max(),
        np.abs(1 / cond[:n_pin] - 1 / ref[:, 2]).max(),
    )
    del _kernels
    rows = [
        {
            "case": "hexabot_leg 1e6 configs: J + det + manipulability + condition + sigma_min",
            "engine": "kernel (numba, fused, generic chain)",
            "threads": threads,
            "median_s": round(t_kernel, 4),
            "min_s": round(t_kernel_min, 4),
            "target_s": 0.1,
            "meets_target": t_kernel <= 0.1,
            "speedup_vs_pinocchio_loop": round(t_pin / t_kernel, 1),
            "max_abs_err_vs_pinocchio": f"{err:.1e} (at {n_pin} configs; 1/condition compared)",
        },
        {
            "case": "hexabot_leg 1e6 configs",
            "engine": "numpy SVD on kernel Jacobians",
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
    return rows


if __name__ == "__main__":
    for row in run(quick=False):
        print("  ".join(f"{k}={v}" for k, v in row.items()))
