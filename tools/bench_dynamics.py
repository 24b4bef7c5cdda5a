"""Benchmark of hexapod_kin.dynamics against bare Pinocchio calls measured in the same run.

* simulate (RK4, ABA, damping, energies, storage) vs a bare Python RK4 loop of ``pin.aba``
  calls (no damping, no storage, no energies): the ratio is the package's overhead per step.
* leg_torques (Jᵀ F, g(q), the RNEA cross-check) vs the bare ``computeFrameJacobian`` +
  ``computeGeneralizedGravity`` it needs at least.

Usage: ``python tools/bench_dynamics.py [--quick]`` (or ``tools/bench.py --only dynamics``).
"""

from __future__ import annotations

import sys
import time
from typing import Any

import numpy as np
import pinocchio as pin

import hexapod_kin as hk
from hexapod_kin.dynamics import leg_torques, simulate


def _best(fn: Any, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def run(quick: bool = False) -> list[dict[str, Any]]:
    rows: list[dict[str, Any]] = []
    repeat = 2 if quick else 5
    steps = 500 if quick else 5000
    dt = 1e-3
    for source in ("pendulum", "hexabot_leg", "hexapod"):
        model = hk.load(source)
        pm = model.model
        data = pm.createData()
        q0 = model.neutral() + 0.3
        tau = np.zeros(model.nq)

        def bare(
            pm: Any = pm, data: Any = data, q0: np.ndarray = q0, tau: np.ndarray = tau
        ) -> None:
            q, v = q0.copy(), np.zeros_like(q0)
            h2 = dt / 2
            for _ in range(steps):
                a1 = pin.aba(pm, data, q, v, tau).copy()
                q2, v2 = q + h2 * v, v + h2 * a1
                a2 = pin.aba(pm, data, q2, v2, tau).copy()
                q3, v3 = q + h2 * v2, v + h2 * a2
                a3 = pin.aba(pm, data, q3, v3, tau).copy()
                q4, v4 = q + dt * v3, v + dt * a3
                a4 = pin.aba(pm, data, q4, v4, tau).copy()
                q = q + dt / 6 * (v + 2 * v2 + 2 * v3 + v4)
                v = v + dt / 6 * (a1 + 2 * a2 + 2 * a3 + a4)

        def ours(model: Any = model, q0: np.ndarray = q0) -> None:
            simulate(model, q0, dt=dt, duration=steps * dt)

        t_bare = _best(bare, repeat) / steps
        t_ours = _best(ours, repeat) / steps
        rows.append(
            {
                "case": f"simulate rk4 {source} (nq={model.nq})",
                "us_per_step": round(t_ours * 1e6, 2),
                "bare_rk4_us": round(t_bare * 1e6, 2),
                "ratio": round(t_ours / t_bare, 2),
            }
        )
    leg = hk.load("hexabot_leg")
    q = np.array([0.1, 0.4, -0.8])
    force = np.array([1.0, 2.0, -3.0])
    n = 200 if quick else 2000
    d = leg.model.createData()

    def ours_t() -> None:
        for _ in range(n):
            leg_torques(leg, q, force)

    def bare_t() -> None:
        for _ in range(n):
            jac = pin.computeFrameJacobian(
                leg.model, d, q, leg.tip_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
            )
            jac[:3].T @ force + pin.computeGeneralizedGravity(leg.model, d, q)

    t_o = _best(ours_t, repeat) / n
    t_b = _best(bare_t, repeat) / n
    rows.append(
        {
            "case": "leg_torques hexabot_leg (with RNEA cross-check)",
            "us_per_call": round(t_o * 1e6, 2),
            "bare_us": round(t_b * 1e6, 2),
            "ratio": round(t_o / t_b, 2),
        }
    )
    return rows


if __name__ == "__main__":
    for row in run("--quick" in sys.argv):
        print("  ".join(f"{k}={v}" for k, v in row.items()))
