"""Benchmark section ``gait``: the hexapod walks (issue 12).

Target: 10 s of tripod gait at 100 Hz (1,001 samples × 6 legs) with every check (body-pose
IK, forward kinematics of every foot and link, slip, centre of mass, support-polygon margin,
joint-limit margin, leg clearance, joint rates) in <= 0.05 s. Peer measured in the same run:
Pinocchio in a per-sample Python loop computing only part of that work (free-flyer
``centerOfMass`` + ``framesForwardKinematics`` for the six feet) for the same samples.

Usage: ``python tools/bench_gait.py [--repeat N]`` (or ``python tools/bench.py --only gait``).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from typing import Any

import pinocchio as pin

from hexapod_kin.gait import walk, whole_body

TARGET_S = 0.05


def _median(fn: Any, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def run(quick: bool = False, repeat: int | None = None) -> list[dict[str, Any]]:
    """Rows of the report: ours, the peer, their ratio and the target."""
    reps = repeat if repeat is not None else (3 if quick else 15)
    wb = whole_body()
    run0 = walk(wb, pattern="tripod", duration=10.0, rate=100.0)  # compile and warm up
    Q = run0.pinocchio_q()
    data = wb.model.createData()
    feet = [wb.model.getFrameId(f"{leg}_foot") for leg in wb.leg_names]

    def peer() -> None:
        for q in Q:
            pin.centerOfMass(wb.model, data, q)
            pin.framesForwardKinematics(wb.model, data, q)
            for f in feet:
                data.oMf[f].translation  # noqa: B018 - the read is the work

    rows = []
    for pattern in ("tripod", "wave", "ripple"):
        ours = _median(lambda p=pattern: walk(wb, pattern=p, duration=10.0, rate=100.0), reps)
        row: dict[str, Any] = {
            "case": f"{pattern} 10 s @ 100 Hz (1001 samples x 6 legs, all checks)",
            "ours_s": round(ours, 5),
        }
        if pattern == "tripod":
            theirs = _median(peer, max(1, reps // 3))
            row.update(
                peer="pinocchio loop: CoM + feet FK only",
                peer_s=round(theirs, 5),
                ratio=round(ours / theirs, 3),
                target_s=TARGET_S,
                meets_target=ours <= TARGET_S,
            )
        rows.append(row)
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=15, help="timed runs per case (median)")
    args = parser.parse_args(argv)
    for row in run(repeat=args.repeat):
        print("  ".join(f"{k}={v}" for k, v in row.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
