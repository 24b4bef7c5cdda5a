"""Benchmark: the walking controller's tick and the closed loop's speed (issue 32).

Targets (issue 32): the controller's tick <= 1 ms median on one core, the QP solve measured
apart; the whole closed-loop simulation at least as fast as real time on a 2-core machine.

For each robot: a closed-loop walk of ``--duration`` simulated seconds (:func:`hexapod_kin.
control.run`), timed in CPU time (the process's, a shared machine's honest clock): the
median tick (QP included), the mean QP solve per tick, and the CPU seconds per simulated
second (below 1: faster than real time, whatever else runs on the machine).

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


def main(argv: list[str] | None = None) -> int:
    """Run the cases; print a table or JSON rows."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=3.0, help="simulated walk [s]")
    ap.add_argument("--json", action="store_true", help="one JSON row per case")
    args = ap.parse_args(argv)
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
