"""Spine benchmark: per-call fk + jacobian through hexapod_kin vs raw Pinocchio calls.

Both sides use the same Pinocchio model and configurations, measured in the same run; the
ratio (hexapod_kin / raw) is the API's overhead. Target: <= 2x (the model keeps one Pinocchio
``Data`` per thread; that lookup is included).

Batch section: ``fk_batch`` / ``jacobian_batch`` of 1e6 configurations beside a raw Pinocchio
Python loop measured in the same run (1e5 calls, scaled to 1e6). Targets: leg <= 0.05 s,
UR5 (``erd:ur5_robot``) <= 0.3 s. Import section: ``python -X importtime -c "import
hexapod_kin"`` in a child process (target < 0.3 s).
"""

from __future__ import annotations

import re
import subprocess
import sys
import time

import numpy as np
import pinocchio as pin

import hexapod_kin as hk


def _best_per_call(func, qs, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        for q in qs:
            func(q)
        best = min(best, (time.perf_counter() - t0) / len(qs))
    return best


def run(quick: bool = False) -> list[dict]:
    """Per-call rows, batch rows and the import time (tools/bench.py's ``spine`` section)."""
    return run_all(quick)


def run_per_call(quick: bool = False) -> list[dict]:
    """Per-call fk + jacobian vs raw Pinocchio."""
    rows = []
    n, repeat = (2_000, 3) if quick else (20_000, 7)
    for source, kw in [("hexabot_leg", {}), ("scara", {}), ("erd:solo12", {"tip": "FL_FOOT"})]:
        model = hk.load(source, **kw)
        m, d, fid = model.model, model.model.createData(), model.tip_id
        lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        qs = list(model.random_q(n, seed=0))

        def raw(q, m=m, d=d, fid=fid, lwa=lwa):
            pin.forwardKinematics(m, d, q)
            pose = pin.updateFramePlacement(m, d, fid).homogeneous
            jac = pin.computeFrameJacobian(m, d, q, fid, lwa)
            return pose, jac

        def api(q, model=model):
            return model.fk(q), model.jacobian(q)

        def api_fused(q, model=model):
            return model.fk_jacobian(q)

        # Interleave the three so that machine load affects them alike; keep the best of each.
        t_raw = t_api = t_fused = float("inf")
        for _ in range(repeat):
            t_raw = min(t_raw, _best_per_call(raw, qs, 1))
            t_api = min(t_api, _best_per_call(api, qs, 1))
            t_fused = min(t_fused, _best_per_call(api_fused, qs, 1))
        rows.append(
            {
                "chain": source,
                "raw_pin_fk+jac_us": round(t_raw * 1e6, 3),
                "hexapod_kin_fk+jacobian_us": round(t_api * 1e6, 3),
                "ratio": round(t_api / t_raw, 2),
                "hexapod_kin_fk_jacobian_fused_us": round(t_fused * 1e6, 3),
                "ratio_fused": round(t_fused / t_raw, 2),
                "target": "ratio <= 2",
            }
        )
    return rows


def _best(func, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        func()
        best = min(best, time.perf_counter() - t0)
    return best


def run_batch(quick: bool = False) -> list[dict]:
    """1e6-configuration batch calls vs a raw Pinocchio loop (1e5 calls, scaled).

    Fresh output arrays (``fk_batch_s``: the page faults of 128 MB are part of it) and a reused
    ``out=`` buffer; the load average is printed beside (the machine is shared). The last
    column is a 10-configuration call (the kernel's fixed cost).
    """
    import os

    rows = []
    n = 100_000 if quick else 1_000_000
    n_loop = 10_000 if quick else 100_000
    repeat = 2 if quick else 3
    for source, target in [("hexabot_leg", 0.05), ("erd:ur5_robot", 0.3)]:
        model = hk.load(source)
        qs = model.random_q(n, seed=0)
        small = qs[:10].copy()
        # compile (cached on disk after the first run)
        model.fk_jacobian_batch(small)
        t_small = _best(lambda model=model, small=small: model.fk_jacobian_batch(small), 20)
        m, d, fid = model.model, model.model.createData(), model.tip_id
        lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        loop_q = list(qs[:n_loop])

        def raw_fk(m=m, d=d, fid=fid, loop_q=loop_q):
            for q in loop_q:
                pin.forwardKinematics(m, d, q)
                _ = pin.updateFramePlacement(m, d, fid).homogeneous

        def raw_jac(m=m, d=d, fid=fid, loop_q=loop_q, lwa=lwa):
            for q in loop_q:
                pin.computeFrameJacobian(m, d, q, fid, lwa)

        scale = n / n_loop
        t_raw_fk = _best(raw_fk, repeat) * scale
        t_raw_jac = _best(raw_jac, repeat) * scale
        t_fk = _best(lambda model=model, qs=qs: model.fk_batch(qs), repeat)
        buf = np.empty((n, 4, 4))
        t_fk_out = _best(lambda model=model, qs=qs, buf=buf: model.fk_batch(qs, out=buf), repeat)
        t_jac = _best(lambda model=model, qs=qs: model.jacobian_batch(qs), repeat)
        jbuf = np.empty((n, 6, model.nq))
        t_jac_out = _best(
            lambda model=model, qs=qs, jbuf=jbuf: model.jacobian_batch(qs, out=jbuf), repeat
        )
        t_both = _best(lambda model=model, qs=qs: model.fk_jacobian_batch(qs), repeat)
        check = slice(0, 200)
        err = max(
            float(np.abs(model.fk_batch(qs[check]) - [model.fk(q) for q in qs[check]]).max()),
            float(
                np.abs(
                    model.jacobian_batch(qs[check]) - [model.jacobian(q) for q in qs[check]]
                ).max()
            ),
        )
        rows.append(
            {
                "batch": source,
                "n": n,
                "fk_batch_s": round(t_fk, 4),
                "fk_batch_reused_out_s": round(t_fk_out, 4),
                "jacobian_batch_s": round(t_jac, 4),
                "jacobian_batch_reused_out_s": round(t_jac_out, 4),
                "fk_jacobian_batch_s": round(t_both, 4),
                "raw_pin_loop_fk_s": round(t_raw_fk, 3),
                "raw_pin_loop_jac_s": round(t_raw_jac, 3),
                "speedup_fk": round(t_raw_fk / t_fk, 1),
                "speedup_jac": round(t_raw_jac / t_jac, 1),
                "max_err_vs_pin": f"{err:.1e}",
                "target_s": f"<= {target} (for n = 1e6)",
                "fk_jac_10_compiled_us": round(t_small * 1e6, 1),
                "load_avg_1min": round(os.getloadavg()[0], 2),
            }
        )
    return rows


def run_import() -> list[dict]:
    """Cumulative import time of hexapod_kin from ``-X importtime`` (best of 3 children)."""
    best = float("inf")
    for _ in range(3):
        out = subprocess.run(
            [sys.executable, "-X", "importtime", "-c", "import hexapod_kin"],
            capture_output=True,
            text=True,
            check=True,
        )
        line = [ln for ln in out.stderr.splitlines() if re.search(r"\|\s*hexapod_kin$", ln)]
        best = min(best, int(line[-1].split("|")[1]) * 1e-6)
    return [{"import": "hexapod_kin", "seconds": round(best, 3), "target": "< 0.3 s"}]


def run_all(quick: bool = False) -> list[dict]:
    """Every section of this file (what tools/bench.py calls)."""
    return run_per_call(quick) + run_batch(quick) + run_import()


if __name__ == "__main__":
    for row in run():
        print(row)
