"""Benchmark section ``sweep``: leg design sweeps (issue 16).

Target: 1,000 designs x 10,000 Monte-Carlo configurations each (plus the stride search and
the σ evaluation along the stride) in <= 10 s on this machine, end to end (chunks written,
tables merged). Peer measured in the same run: the same scores for a few designs with a plain
loop over the package's vectorised numpy closed-form IK (``ik.analytic_batch`` with limits)
and Pinocchio Jacobians + ``np.linalg.svd``, scaled to 1,000 designs.

Usage: ``python tools/bench_sweep.py [--quick]`` (or ``python tools/bench.py --only sweep``).
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

import numpy as np

import hexapod_kin as hk
from hexapod_kin.ik import analytic_batch
from hexapod_kin.sweep import (
    DesignSpace,
    Range,
    design_chain,
    score_designs,
    sweep,
    volume_closed_form,
)
from hexapod_kin.sweep.scores import unit_samples

SPACE = DesignSpace(
    {
        "l1": Range(0.02, 0.08),
        "l2": Range(0.06, 0.14),
        "l3": Range(0.06, 0.14),
        "height": Range(0.05, 0.15),
        "q1_lower": Range(-math.pi, -0.4),
        "q1_upper": Range(0.4, math.pi),
        "q2_lower": Range(-math.pi, -1.0),
    }
)


def _peer_design(r: np.ndarray, unit: np.ndarray) -> dict[str, float]:
    """One design's scores, plain numpy + Pinocchio (same conventions as the kernel)."""
    l1, l2, l3, h, _, yaw = r[:6]
    chain = design_chain(r)
    model = hk.load(chain)
    big, reach = l1 + l2 + l3, l2 + l3

    def member(p: np.ndarray) -> np.ndarray:
        return analytic_batch(chain, p.reshape(-1, 3), within_limits=True).reachable

    rho = big * np.sqrt(unit[:, 0])
    phi = 2 * math.pi * unit[:, 1] - math.pi
    pts = np.stack([rho * np.cos(phi), rho * np.sin(phi), reach * (2 * unit[:, 2] - 1)], 1)
    vol = math.pi * big * big * 2 * reach * member(pts).mean()
    volume_closed_form(l1, l2, l3, *r[6:12])
    a = math.sqrt(reach**2 - h * h)
    b = math.sqrt(max((l2 - l3) ** 2 - h * h, 0))
    rho0 = l1 + b + r[12] * (a - b)
    q1m = 0.5 * (r[6] + r[7])
    p0 = np.array([rho0 * math.cos(q1m), rho0 * math.sin(q1m), -h])
    d = np.array([math.cos(yaw), -math.sin(yaw), 0.0])
    ends = []
    step = 2 * big / 256
    for sg in (1.0, -1.0):
        ts = step * np.arange(1, 257)
        ok = member(p0 + sg * ts[:, None] * d)
        k = int(np.argmin(ok)) if not ok.all() else 256
        good, bad = (ts[k - 1] if k else 0.0), ts[min(k, 255)]
        for _ in range(64):
            mid = 0.5 * (good + bad)
            if mid <= good or mid >= bad:
                break
            if member(p0 + sg * mid * d)[0]:
                good = mid
            else:
                bad = mid
        ends.append(good)
    centre, half = 0.5 * (ends[0] - ends[1]), 0.45 * (ends[0] + ends[1])
    smin = math.inf
    for t in np.linspace(centre - half, centre + half, 64):
        sol = analytic_batch(chain, p0 + t * d, within_limits=True)
        best = 0.0
        for q, v in zip(sol.q[0], sol.valid[0]):
            if v:
                jp = np.asarray(model.jacobian(q, "local_world_aligned"))[:3]
                best = max(best, float(np.linalg.svd(jp, compute_uv=False)[-1]))
        smin = min(smin, best)
    return {"volume_mc": vol, "stride": ends[0] + ends[1], "sigma_min": smin}


def run(quick: bool = False) -> list[dict]:
    n_designs, n_mc = (100, 2_000) if quick else (1000, 10_000)
    designs = SPACE.designs("lhs", samples=n_designs, seed=0)
    score_designs(designs[:2], mc_samples=100)  # warm up (imports)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        times = []
        for rep in range(1 if quick else 3):
            t0 = time.perf_counter()
            res = sweep(
                SPACE,
                method="lhs",
                samples=n_designs,
                mc_samples=n_mc,
                out=Path(tmp) / f"b{rep}.csv",
                progress=False,
            )
            times.append(time.perf_counter() - t0)
        ours = min(times)
    t0 = time.perf_counter()
    score_designs(designs, mc_samples=n_mc)
    scores = time.perf_counter() - t0
    unit = unit_samples(0, n_mc)
    n_peer = 2 if quick else 4
    t0 = time.perf_counter()
    peer = [_peer_design(designs[i], unit) for i in range(n_peer)]
    peer_per = (time.perf_counter() - t0) / n_peer
    tab = res.table
    dv = max(
        abs(p["volume_mc"] - tab["volume_mc"][i]) / tab["volume_mc"][i] for i, p in enumerate(peer)
    )
    ds = max(abs(p["stride"] - tab["stride"][i]) for i, p in enumerate(peer))
    dsig = max(abs(p["sigma_min"] - tab["sigma_min"][i]) for i, p in enumerate(peer))
    rows.append(
        {
            "case": f"{n_designs} designs x {n_mc} MC configs (LHS over 7 parameters)",
            "sweep_s": round(ours, 3),
            "target_s": 10.0,
            "scores_s": round(scores, 3),
            "peer_numpy_pinocchio_s_scaled": round(peer_per * n_designs, 1),
            "ratio_peer_over_ours": round(peer_per * n_designs / ours, 1),
            "peer_max_rel_dvolume": f"{dv:.1e}",
            "peer_max_dstride_m": f"{ds:.1e}",
            "peer_max_dsigma": f"{dsig:.1e}",
        }
    )
    return rows


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true")
    for r in run(ap.parse_args().quick):
        print("  ".join(f"{k}={v}" for k, v in r.items()))
