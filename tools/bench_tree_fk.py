"""Benchmark: the batch tree FK (numpy, ``hexapod_kin._tree``) against its peers.

Two questions (issue 30, "one batched kinematics path"):

1. Every joint pose of a walk: the built-in hexapod's 18 joints at the 1,001 samples of a
   10 s tripod at 100 Hz, by :func:`hexapod_kin._tree.tree_frames` against a loop of
   Pinocchio's ``forwardKinematics`` read back into numpy (the same free-flyer model).
2. Tip poses of a serial chain (``hexabot_leg``, 3 joints; ``erd:ur5_robot``, 6 joints) for
   N configurations: the compiled block kernel behind ``KinematicModel.fk_batch`` (numba,
   warm, every core) against ``tree_frames`` on the same chain (one core). ``fk_batch`` keeps
   the compiled kernel where this ratio says it pays.

Every row also gives the largest difference to the peer in [m] (the engines agree to
rounding). Times are the best of ``--repeat`` runs of the process's CPU time (``--wall``:
wall clock), so a shared machine does not distort them; the compiled kernel runs on
``numba.get_num_threads()`` threads, whose CPU time adds up.

Usage: ``python tools/bench_tree_fk.py [--repeat N] [--wall] [--quick]``.
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
from bench_legs import best_of  # tools/ is the script's folder

CLOCK: Callable[[], float] = time.process_time


def _best(fn: Callable[[], Any], repeat: int) -> float:
    return best_of(fn, repeat, CLOCK)


def walk_rows(repeat: int, samples: int) -> list[dict[str, Any]]:
    """Question 1: every joint pose of a tripod's samples, tree FK vs a Pinocchio loop."""
    import pinocchio as pin

    from hexapod_kin._tree import tree_poses
    from hexapod_kin.gait import walk, whole_body

    wb = whole_body()
    run = walk(wb, duration=(samples - 1) / 100.0, rate=100.0)
    q, base = np.ascontiguousarray(run.q), np.ascontiguousarray(run.base_poses)
    Q = wb.pinocchio_q(q, base)
    m = wb.model
    d = m.createData()

    def pin_loop() -> np.ndarray:
        out = np.empty((len(Q), wb.nq, 4, 4))
        for i, qi in enumerate(Q):
            pin.forwardKinematics(m, d, qi)
            for j in range(wb.nq):
                out[i, j] = d.oMi[j + 2].homogeneous
        return out

    tree = wb._tree
    ours = tree_poses(tree, q, base)
    err = float(np.abs(ours - pin_loop()).max())
    t_tree = _best(lambda: tree_poses(tree, q, base), repeat)
    t_pin = _best(pin_loop, max(1, repeat // 2))
    return [
        {
            "case": f"hexapod tripod, {len(q)} samples x {wb.nq} joints",
            "tree_fk_s": t_tree,
            "pinocchio_loop_s": t_pin,
            "speedup_vs_pinocchio": t_pin / t_tree,
            "max_diff_m": err,
        }
    ]


def _tip_poses_by_tree(km: Any) -> Callable[[np.ndarray], np.ndarray]:
    """The tip poses ``baseMtip`` of ``km``'s chain by :func:`~hexapod_kin._tree.tree_frames`."""
    from hexapod_kin._tree import Tree, tree_frames

    tree = Tree.of_model(km.model, first=1, label=km.name)
    base_m = np.asarray(km.baseMo.homogeneous)  # the chain's base in front
    tip = np.asarray(km.model.frames[km.tip_id].placement.homogeneous)  # its tip behind
    last = int(km.model.frames[km.tip_id].parentJoint) - 1

    def poses(qs: np.ndarray) -> np.ndarray:
        n = len(qs)
        R, p = tree_frames(tree, qs, np.broadcast_to(base_m, (n, 4, 4)))
        out = np.empty((n, 4, 4))
        Rl, pl = R[:, :, last], p[:, last]  # (3, 3, N), (3, N)
        out[:, :3, :3] = np.einsum("ikn,kj->nij", Rl, tip[:3, :3])
        out[:, :3, 3] = np.einsum("ikn,k->ni", Rl, tip[:3, 3]) + pl.T
        out[:, 3] = (0.0, 0.0, 0.0, 1.0)
        return out

    return poses


def chain_rows(repeat: int, sizes: tuple[int, ...]) -> list[dict[str, Any]]:
    """Question 2: tip poses of a chain, the compiled fk_batch vs the tree FK."""
    import numba

    from hexapod_kin import load

    rows = []
    for source in ("hexabot_leg", "erd:ur5_robot"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            km = load(source)
        by_tree = _tip_poses_by_tree(km)
        for n in sizes:
            qs = km.random_q(n, seed=3)
            km.fk_batch(qs[:2])  # compiled (or read from numba's cache) before timing
            err = float(np.abs(by_tree(qs) - km.fk_batch(qs)).max())
            t_tree = _best(lambda qs=qs: by_tree(qs), repeat)  # noqa: B023
            t_numba = _best(lambda qs=qs: km.fk_batch(qs), repeat)  # noqa: B023
            rows.append(
                {
                    "case": f"{km.name} ({km.nq} joints) tip poses, N={n}",
                    "fk_batch_numba_s": t_numba,
                    "tree_fk_s": t_tree,
                    "ratio_tree_over_numba": t_tree / t_numba,
                    "numba_threads": numba.get_num_threads(),
                    "max_diff_m": err,
                }
            )
    return rows


def main(argv: list[str] | None = None) -> int:
    """Print the rows (a table, or JSON with ``--json``)."""
    global CLOCK
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--wall", action="store_true", help="wall clock instead of CPU time")
    ap.add_argument("--quick", action="store_true", help="small sizes (a smoke test)")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    if args.wall:
        CLOCK = time.perf_counter
    repeat = 1 if args.quick else max(1, args.repeat)
    rows = walk_rows(repeat, 101 if args.quick else 1001)
    rows += chain_rows(repeat, (100,) if args.quick else (1_000, 100_000))
    if args.json:
        print(json.dumps(rows))
        return 0
    for r in rows:
        print(
            " | ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in r.items())
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
