"""Benchmark: planning a walk with every check, rolling round feet included (issue 22).

Target: 10 s of tripod at 100 Hz (1,001 samples × 6 legs) with every check (body-pose IK,
IK ↔ rolling fixed point of the 12 mm feet, slip of the contact points, centre of mass,
margin, joint limits, joint speed and acceleration, leg clearance) in <= 0.05 s with the
closed-form legs. Also measured: point feet (``foot_radius=0``: no rolling passes), the
four-legged crawl with body sway, and the full inverse-dynamics torques of 2 s of wave.

Each case prints the median wall time and the median process CPU time
(``time.process_time``) of ``--repeat`` runs: on a shared machine the CPU time is the
better measure of the work done.

Usage: ``python tools/bench_walk.py [--repeat N]``.
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

from hexapod_kin.dynamics import gait_torques
from hexapod_kin.gait import walk, whole_body
from hexapod_kin.robots import hexapod

TARGET_S = 0.05

#: CPU seconds of the last :func:`rows` call, by label.
CPU: dict[str, float] = {}


def _median(fn: Any, repeat: int) -> tuple[float, float]:
    """Median wall and CPU seconds of ``repeat`` calls."""
    wall, cpu = [], []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return statistics.median(wall), statistics.median(cpu)


def rows(repeat: int = 5) -> list[tuple[str, float, str]]:
    """(label, wall seconds, target text) for each case (CPU seconds in :data:`CPU`)."""
    wb = whole_body()
    quad = whole_body(hexapod(mount_yaw_deg=(45.0, 135.0, -135.0, -45.0), name="quad"))
    walk(wb, duration=1.0)  # warm up
    run = walk(wb, pattern="wave", duration=2.0)
    cases = [
        (
            "tripod 10 s @ 100 Hz, 12 mm rolling feet, all checks",
            lambda: walk(wb, pattern="tripod"),
            repeat,
            f"<= {TARGET_S} s",
        ),
        (
            "tripod 10 s @ 100 Hz, point feet, all checks",
            lambda: walk(wb, pattern="tripod", foot_radius=0.0),
            repeat,
            f"<= {TARGET_S} s",
        ),
        (
            "quadruped crawl 10 s @ 100 Hz with body sway",
            lambda: walk(quad, pattern="crawl"),
            max(1, repeat // 2),
            "informative",
        ),
        (
            "full inverse dynamics, 2 s wave @ 100 Hz (201 samples)",
            lambda: gait_torques(run),
            max(1, repeat // 2),
            "informative",
        ),
    ]
    out = []
    CPU.clear()
    for label, fn, rep, target in cases:
        wall, cpu = _median(fn, rep)
        CPU[label] = cpu
        out.append((label, wall, target))
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    for label, sec, target in rows(args.repeat):
        print(f"{label:60s} {sec:8.4f} s wall {CPU[label]:8.4f} s CPU   ({target})")
