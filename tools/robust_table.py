"""The ``simulate --robust`` ensemble as a table: robot × member travel error (issue 31).

For each robot, the default walk is planned once and replayed under every member of
:data:`hexapod_kin.robust.ENSEMBLE` (or the bumpy ones and the first, ``--bumps``). One row
per robot: the travel error of each member in percent, ``*`` where the member fails a check;
then, per member, its failing checks, the largest slip, tilt and the touch-down delays
(``--detail``). The bumpy members walk under the controller (``controlled``, see
:mod:`hexapod_kin.robust`); the others replay the plan.

A touch-down delay is the time from a planned touch-down to the first sample at which the
foot carries 5 % of the robot's weight, looked for from 100 ms before it (negative: the foot
met the ground early, on a bump) — the figure behind issue 31's bump diagnosis (a foot
planned onto ``z = 0`` over a dip hovers until the next leg lifts and the body tips onto it).

Usage: ``python tools/robust_table.py [ROBOT ...] [--duration S] [--bumps|--flat] [--detail]``
(default: the eight example-robot-data quadrupeds, 10 s). Each robot costs 8 MuJoCo
replays and 3 closed-loop walks (about 40 s of CPU each for erd:go1's 10 s crawl).
"""

from __future__ import annotations

import argparse
import math
import time
from typing import Any

import numpy as np

QUADRUPEDS = ("a1", "anymal", "b1", "go1", "go2", "hyq", "laikago", "solo12")


def touchdown_delays(sim: Any, share: float = 0.05, early: float = 0.1) -> np.ndarray:
    """Delays [s] of every planned touch-down of a :class:`~hexapod_kin.simulate.SimRun`.

    The first sample from ``early`` seconds before the planned touch-down to the planned
    lift-off at which the foot's normal force reaches ``share`` of the weight (NaN: never).
    """
    t = np.asarray(sim.t)
    sup = np.asarray(sim.run.support, dtype=bool)
    force = np.asarray(sim.foot_forces)
    weight = float(sim.run.mass) * 9.81
    h = float(t[1] - t[0])
    back = int(round(early / h))
    out = []
    for leg in range(sup.shape[1]):
        s = sup[:, leg]
        ups = np.flatnonzero(s[1:] & ~s[:-1]) + 1
        downs = np.flatnonzero(~s[1:] & s[:-1]) + 1
        for i in ups:
            end = downs[downs > i]
            j = int(end[0]) if len(end) else len(t)
            lo = max(0, i - back)
            hit = np.flatnonzero(force[lo:j, leg] >= share * weight)
            out.append((lo + hit[0] - i) * h if len(hit) else math.nan)
    return np.asarray(out)


def main(argv: list[str] | None = None) -> int:
    """Print the table; 0 when every member of every robot passes, else 1."""
    from hexapod_kin.robust import ENSEMBLE, simulate_robust

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("robots", nargs="*", default=[f"erd:{n}" for n in QUADRUPEDS])
    p.add_argument("--duration", type=float, default=10.0, help="walk length [s]")
    p.add_argument("--bumps", action="store_true", help="the first member and the bumpy ones")
    p.add_argument("--flat", action="store_true", help="the flat members only (the replays)")
    p.add_argument("--detail", action="store_true", help="per member: checks, slip, delays")
    args = p.parse_args(argv)
    members = ENSEMBLE
    if args.bumps:
        members = (ENSEMBLE[0],) + tuple(m for m in ENSEMBLE if m.bumps)
    if args.flat:
        members = tuple(m for m in ENSEMBLE if not m.bumps)
    print("robot", *(f"m{k}" for k in range(len(members))), "cpu_s", sep="\t")
    ok = True
    for robot in args.robots:
        c0 = time.process_time()
        rr = simulate_robust(robot, members=members, stand=False, duration=args.duration)
        cells = []
        for r in rr.runs:
            bad = [k for k, row in r.checks().items() if not row["ok"]]
            cells.append(f"{100 * r.distance_error:+.2f}{'*' if bad else ''}")
        print(robot, *cells, f"{time.process_time() - c0:.0f}", sep="\t", flush=True)
        ok = ok and rr.ok
        if args.detail:
            for k, (m, r) in enumerate(zip(rr.members, rr.runs)):
                bad = [key for key, row in r.checks().items() if not row["ok"]]
                if m.controlled:  # the closed loop: no plan to land on, no slip measured
                    c = r.control
                    tilt = math.degrees(max(c.max_roll, c.max_pitch))
                    head = math.degrees(c.heading_error)
                    print(
                        f"  m{k} {m.name}: failed {bad or '-'}; heading {head:.2f} deg, "
                        f"tilt {tilt:.2f} deg, strikes {len(c.swing_strikes)}"
                    )
                    continue
                d = touchdown_delays(r) * 1e3
                tilt = math.degrees(max(r.max_roll, r.max_pitch))
                print(
                    f"  m{k} {m.name}: failed {bad or '-'}; slip {1e3 * r.max_slip:.1f} mm, "
                    f"tilt {tilt:.2f} deg; touch-down delay median {np.nanmedian(d):+.0f} ms, "
                    f"max {np.nanmax(d):+.0f} ms"
                )
    for k, m in enumerate(members):
        print(f"m{k}: {m.name} ({m.mode})")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
