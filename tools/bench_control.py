"""Benchmark: the walking controller's tick and the closed loop's speed (issue 32).

Targets (issue 32): the controller's tick <= 1 ms median on one core, the QP solve measured
apart; the whole closed-loop simulation at least as fast as real time on a 2-core machine.

For each robot: a closed-loop walk of ``--duration`` simulated seconds (:func:`hexapod_kin.
control.run`), timed in CPU time (the process's, a shared machine's honest clock): the
median tick (QP included), the mean QP solve per tick, and the CPU seconds per simulated
second (below 1: faster than real time, whatever else runs on the machine).

The torque kind's stance forces come from the convex MPC (:mod:`hexapod_kin.control.mpc`),
solved every ``MPC_EVERY`` ticks (and when the stance changes): the median tick is a tick
without a solve; the MPC's own cost is measured apart, one solve of erd:anymal's trot problem
(10 steps, a diagonal pair standing) repeated, median CPU time per solve.

Usage: ``python tools/bench_control.py [--duration S] [--json]``.
"""

from __future__ import annotations

import argparse
import json
from typing import Any

CASES: tuple[tuple[str, Any, str, tuple[float, float, float]], ...] = (
    ("hexapod tripod (servo, 100 Hz)", None, "tripod", (0.2, 0.0, 0.0)),
    ("erd:anymal trot (torque, 500 Hz)", "erd:anymal", "trot", (0.5, 0.0, 0.0)),
    ("erd:solo12 trot (torque, 500 Hz)", "erd:solo12", "trot", (0.3, 0.0, 0.0)),
)


def measure(
    robot: Any, pattern: str, velocity: tuple[float, float, float], duration: float
) -> dict[str, Any]:
    """One closed-loop walk's costs (CPU time)."""
    from hexapod_kin.control import run

    res = run(robot, pattern=pattern, command=velocity, duration=duration)
    return {
        "tick_median_us": 1e6 * res.tick_cpu,
        "qp_mean_us": 1e6 * res.qp_cpu,
        "cpu_per_simulated_s": res.cpu_time / res.simulated,
        "fell": res.fell,
    }


def mpc_solve_us(repeats: int = 200) -> float:
    """The median CPU time [µs] of one MPC solve on erd:anymal's mid-trot problem."""
    import time

    import numpy as np

    from hexapod_kin.control import Controller
    from hexapod_kin.control.controller import MPC_DIV
    from hexapod_kin.control.mpc import schedule

    ctl = Controller("erd:anymal")
    mpc, tab = ctl.mpc, ctl._table
    N, dt = mpc.horizon, ctl.period / MPC_DIV
    x0 = np.zeros(12)
    x0[5] = ctl.height0
    x0[9] = 0.5
    ref = np.tile(x0, (N, 1))
    ref[:, 3] = 0.5 * dt * np.arange(1, N + 1)
    contact = schedule(0.1, np.asarray(tab.offsets), tab.duty_factor, dt / ctl.period, N)
    feet = ctl.feet_body - [0.0, 0.0, ctl.feet_body[0, 2]]
    levers = np.broadcast_to(feet - x0[3:6], (N, ctl.n_legs, 3))
    times = []
    for _ in range(repeats):
        t0 = time.process_time()
        mpc.solve(x0, ref, contact, levers, dt)
        times.append(time.process_time() - t0)
    return 1e6 * float(np.median(times))


def main(argv: list[str] | None = None) -> int:
    """Run the cases; print a table or JSON rows."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=3.0, help="simulated walk [s]")
    ap.add_argument("--json", action="store_true", help="one JSON row per case")
    args = ap.parse_args(argv)
    solve = mpc_solve_us()
    if args.json:
        print(json.dumps({"case": "erd:anymal MPC solve", "mpc_solve_median_us": solve}))
    else:
        print(f"{'erd:anymal MPC solve (10 steps)':36s} {solve:7.0f} us median per solve")
    for name, robot, pattern, vel in CASES:
        row = {"case": name, **measure(robot, pattern, vel, args.duration)}
        if args.json:
            print(json.dumps(row))
        else:
            print(
                f"{name:36s} tick {row['tick_median_us']:7.0f} us median (target <= 1000), "
                f"QP {row['qp_mean_us']:6.0f} us mean, {row['cpu_per_simulated_s']:.2f} s CPU "
                "per simulated s (target <= 1)"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
