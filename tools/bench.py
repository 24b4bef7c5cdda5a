"""Benchmarks: the issue's figures in one run, then the per-concern sections.

Usage: ``python tools/bench.py [--only SECTION ...] [--quick] [--json]``.

``headline`` (first, the default) prints, in one run: every command's start time cold and
warm (:mod:`bench_startup`), ``hexapod-kin precompile`` on fresh caches, and after it, in
child processes on those caches: the first leg ``fk_batch`` of 1e6 in a fresh process (three
processes: min / median / max), then
(one process) the default ``scan(grid=100)`` with family labels, ``measures_batch`` of 1e6
(leg, SCARA, Solo12 leg, UR5), leg ``fk_batch`` of 1e6, UR5 6-D IK through ``solve_many``
(mean µs per pose and success) and ``ik.solve`` (median µs per pose); ``ik.solve`` per call
on 1,000 random reachable targets (UR5 and Panda poses, the leg's positions: median µs and
success checked with Pinocchio) beside Robotics Toolbox's ``ik_LM`` (C++) on its own models,
timed in blocks of 100 targets (ours, then RTB's, alternated: ``median_us``, ``speedup``; the
blocks' CPU time per call: ``cpu_mean_us_blocked``), in turn target by target
(``interleaved_median_us``: each call finds the caches the other left), then ours back to
back (``tight_loop_median_us``; ``steps_median``: accepted LM steps), and whether those
results are byte-identical to the same targets' batch (``solve_many``) and to the first 100
solved in a fresh process;
with the ratio to a peer measured in the same run where one exists (a Pinocchio loop, numpy's
SVD, Pinocchio's IK example loop). A row that fails prints its error and the run goes on.

The other sections live in ``tools/bench_<section>.py`` (one per concern) and expose
``run(quick: bool) -> list[dict]``; each dict is one line of the report.
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

SECTIONS = [
    "headline",
    "percall",
    "spine",
    "singularity",
    "ik",
    "viewer",
    "sweep",
    "gait",
    "symbolic",
    "dynamics",
    "startup",
]
TOOLS = Path(__file__).resolve().parent

#: The speed rows, run in one child process after ``precompile`` (prints one JSON per row).
_SPEED = r"""
import json, os, sys, time
import numpy as np
import pinocchio as pin
import hexapod_kin as hk
from hexapod_kin import ik
from hexapod_kin.singularity import measures_batch, scan

QUICK = sys.argv[1] == "1"
N = 100_000 if QUICK else 1_000_000


def best(f, r=3):
    f()
    out = float("inf")
    for _ in range(r):
        t0 = time.perf_counter(); f(); out = min(out, time.perf_counter() - t0)
    return out


def row(name, fn):
    try:
        res = fn()
    except Exception as exc:  # noqa: BLE001 - printed on the row
        res = {"error": f"{type(exc).__name__}: {exc}"[:200]}
    print(json.dumps({"row": name, **res}), flush=True)


def svd_peer(model, k=10_000):
    qs = model.random_q(k, seed=9)
    m, d, fid = model.model, model.model.createData(), model.tip_id
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    t0 = time.perf_counter()
    jac = np.array([pin.computeFrameJacobian(m, d, q, fid, lwa)[:3] for q in qs])
    np.linalg.svd(jac, compute_uv=False)
    return (time.perf_counter() - t0) * N / k


def scan_row():
    leg = hk.load("hexabot_leg")
    t0 = time.perf_counter(); res = scan(leg, grid=100); first = time.perf_counter() - t0
    again = best(lambda: scan(leg, grid=100), 2)
    fams = [getattr(f, "name", str(f)) for f in getattr(res, "families", ())]
    return {"first_s": round(first, 4), "best_s": round(again, 4), "target_s": 0.1,
            "flagged": int(np.count_nonzero(res.singular)), "families": fams}


def measures_row(src, kw, target):
    model = hk.load(src, **kw)
    qs = model.random_q(N, seed=0)
    t = best(lambda: measures_batch(model, qs))
    peer = svd_peer(model)
    return {"n": N, "s": round(t, 4), "target_s": target,
            "peer_pinocchio_loop_numpy_svd_s": round(peer, 2), "speedup": round(peer / t, 1)}


def fk_row():
    leg = hk.load("hexabot_leg")
    qs = leg.random_q(N, seed=0)
    t = best(lambda: leg.fk_batch(qs))
    m, d, fid = leg.model, leg.model.createData(), leg.tip_id
    k = 20_000
    t0 = time.perf_counter()
    for q in qs[:k]:
        pin.forwardKinematics(m, d, q); pin.updateFramePlacement(m, d, fid).homogeneous
    peer = (time.perf_counter() - t0) * N / k
    return {"n": N, "s": round(t, 4), "target_s": 0.05, "peer_pinocchio_loop_s": round(peer, 2),
            "speedup": round(peer / t, 1)}


def ik_row():
    sys.path.insert(0, sys.argv[2])
    from bench_ik import _pin_pose_dls

    arm = hk.load("erd:ur5_robot")
    n = 200 if QUICK else 2000
    poses = np.array([arm.fk(q) for q in arm.random_q(n, seed=11)])
    ik.solve_many(arm, poses[:2])
    t0 = time.perf_counter(); many = ik.solve_many(arm, poses); t_many = time.perf_counter() - t0
    ok = 0
    qs = [r.q for r in many] if isinstance(many, (list, tuple)) else many.q
    for i, t in enumerate(poses):
        pose = arm.fk(qs[i])
        err = np.linalg.norm(pose[:3, 3] - t[:3, 3])
        rot = np.linalg.norm(pin.log3(t[:3, :3] @ pose[:3, :3].T))
        ok += bool(err <= 1e-9 and rot <= 1e-9)
    times = []
    for t in poses[:200]:
        t0 = time.perf_counter(); ik.solve(arm, t); times.append(time.perf_counter() - t0)
    ours = float(np.median(times)) * 1e6
    m, d, fid = arm.model, arm.model.createData(), arm.tip_id
    lo, hi = m.lowerPositionLimit, m.upperPositionLimit
    ptimes = []
    for t in poses[:100]:
        des = pin.SE3(t[:3, :3], t[:3, 3])
        t0 = time.perf_counter(); _pin_pose_dls(m, d, fid, des, pin.neutral(m), lo, hi)
        ptimes.append(time.perf_counter() - t0)
    peer = float(np.median(ptimes)) * 1e6
    # the median per pose: one pose per compiled call, less the same call started at the
    # answer (the call's own overhead); a batch's per-pose times are not observable
    qs_ok = np.array(qs)
    one, idle = [], []
    for i in range(200):
        t0 = time.perf_counter(); ik.solve_many(arm, poses[i:i + 1])
        one.append(time.perf_counter() - t0)
        t0 = time.perf_counter(); ik.solve_many(arm, poses[i:i + 1], q0=qs_ok[i:i + 1])
        idle.append(time.perf_counter() - t0)
    work = (float(np.median(one)) - float(np.median(idle))) * 1e6
    return {"n": n, "solve_many_mean_us": round(t_many / n * 1e6, 1),
            "one_pose_call_median_us": round(float(np.median(one)) * 1e6, 1),
            "call_overhead_median_us": round(float(np.median(idle)) * 1e6, 1),
            "solve_median_us_less_overhead": round(work, 1), "target_median_us": 50,
            "success": round(ok / n, 4), "target_success": 0.995,
            "solve_per_call_median_us": round(ours, 1),
            "peer_pinocchio_ik_example_median_us": round(peer, 1),
            "speedup": round(peer / ours, 1)}


PER_CALL_ONLY = sys.argv[3:] == ["percall"]
if not PER_CALL_ONLY:
    row("scan(grid=100) hexabot_leg", scan_row)
    for src, kw, target in [("hexabot_leg", {}, 0.05), ("scara", {}, 0.1),
                            ("erd:solo12", {"tip": "FL_FOOT"}, 0.1), ("erd:ur5_robot", {}, 0.3)]:
        row(f"measures_batch {src}", lambda: measures_row(src, kw, target))
    row("fk_batch hexabot_leg", fk_row)
    row("6-D IK erd:ur5_robot", ik_row)


def rtb_robot(name):
    import roboticstoolbox as rtb
    if name != "leg":
        return getattr(rtb.models.DH, name)()
    from spatialmath import SE3
    links = [rtb.RevoluteMDH(alpha=a, a=d, qlim=[-np.pi, np.pi])
             for a, d in ((0.0, 0.0), (-np.pi / 2, 0.05), (0.0, 0.1))]
    return rtb.DHRobot(links, tool=SE3.Tx(0.1), name="hexabot_leg")


DIGEST = '''
import hashlib

def digest(results):
    # every field of every result as to_dict gives it, and the arrays' bytes
    h = hashlib.sha256()
    for r in results:
        for k, v in sorted(r.to_dict().items()):
            h.update(k.encode() + repr(v).encode())
        for a in (r.q, r.history, r.position, r.rotation):
            h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()
'''
exec(DIGEST)

#: The first targets of a per-call row solved one by one in a fresh process (its first 16
#: calls run the loop in Python, the next loads the compiled loop): their digest on stdout.
FRESH = '''
import json, sys
import numpy as np
import hexapod_kin as hk
from hexapod_kin import ik
''' + DIGEST + '''
src, kw, position = sys.argv[1], json.loads(sys.argv[2]), sys.argv[3] == "1"
n, k = int(sys.argv[4]), int(sys.argv[5])
model = hk.load(src, **kw)
poses = [model.fk(q) for q in model.random_q(n, seed=21)]
targets = [p[:3, 3].copy() for p in poses] if position else poses
print(digest([ik.solve(model, t) for t in targets[:k]]))
'''


def per_call_targets(src, kw, position, n):
    model = hk.load(src, **kw)
    poses = [model.fk(q) for q in model.random_q(n, seed=21)]  # reachable, within the limits
    return model, poses, ([p[:3, 3].copy() for p in poses] if position else poses)


def fresh_digest(src, kw, position, n, k):
    import subprocess
    res = subprocess.run([sys.executable, "-c", FRESH, src, json.dumps(kw), str(int(position)),
                          str(n), str(k)], capture_output=True, text=True, check=False)
    return res.stdout.strip().splitlines()[-1] if res.returncode == 0 else "failed"


def per_call_row(src, kw, rtb_name, position, target_us, target_ok):
    # ik.solve and RTB's ik_LM one target at a time (both see the same load), timed twice:
    # interleaved (ours, RTB's, target by target: each call finds the caches the other left)
    # and in blocks (100 targets ours, the same 100 RTB's, alternated: as a loop calls them);
    # the blocks' CPU time (process_time) per call as well (a busy machine's waits left out)
    n = 200 if QUICK else 1000
    model, poses, targets = per_call_targets(src, kw, position, n)
    try:
        robot = rtb_robot(rtb_name)
    except ImportError:
        robot = None
    if robot is not None:
        ets, mask = robot.ets(), [1, 1, 1, 0, 0, 0] if position else [1] * 6
        qs = np.random.default_rng(21).uniform(robot.qlim[0], robot.qlim[1], size=(n, robot.n))
        teps = [ets.eval(q) for q in qs]
    ik.solve(model, targets[0])
    clock, results, sols = time.perf_counter, [None] * n, [None] * n

    def ours(i):
        t0 = clock()
        results[i] = ik.solve(model, targets[i])
        return clock() - t0

    def peer(i):
        t0 = clock()
        sols[i] = ets.ik_LM(teps[i], tol=1e-18, ilimit=60, slimit=100, joint_limits=True,
                            mask=mask)
        return clock() - t0

    inter = [(ours(i), peer(i) if robot is not None else 0.0) for i in range(n)]
    blocked, pblocked, cpu, pcpu = [], [], 0.0, 0.0
    for a in range(0, n, 100):
        c0 = time.process_time()
        blocked += [ours(i) for i in range(a, min(a + 100, n))]
        c1 = time.process_time()
        pblocked += [peer(i) for i in range(a, min(a + 100, n))] if robot is not None else []
        cpu, pcpu = cpu + c1 - c0, pcpu + time.process_time() - c1
    ok = pok = 0
    for r, p in zip(results, poses):  # checked with Pinocchio's FK and log map
        got = model.fk(r.q)
        rot = 0.0 if position else np.linalg.norm(pin.log3(p[:3, :3] @ got[:3, :3].T))
        ok += bool(r.converged and np.linalg.norm(got[:3, 3] - p[:3, 3]) <= 1e-9 and rot <= 1e-9)
    ours_us = float(np.median(blocked)) * 1e6
    us = lambda ts: round(float(np.median(ts)) * 1e6, 1)  # noqa: E731
    tight = [ours(i) for i in range(n)]  # ours back to back (nothing else between them)
    # the same bits: these per-call results (warm), the batch of the same targets, and the
    # first 100 targets solved one by one in a fresh process
    warm = digest(results)
    batch = digest(ik.solve_many(model, np.array(targets)))
    fresh = fresh_digest(src, kw, position, n, 100)
    out = {"n": n, "timing": "median_us: blocks of 100 (ours, then RTB's), alternated",
           "median_us": round(ours_us, 1), "target_us": target_us,
           "interleaved_median_us": us([t for t, _ in inter]),
           "cpu_mean_us_blocked": round(cpu / n * 1e6, 1), "tight_loop_median_us": us(tight),
           "steps_median": float(np.median([r.iterations for r in results])),
           "success": round(ok / n, 4), "target_success": target_ok,
           "same_bits_batch": warm == batch, "same_bits_fresh": fresh == digest(results[:100]),
           "load_1min": round(os.getloadavg()[0], 1)}
    if robot is None:
        return out | {"peer_rtb": "not installed (pip install hexapod-kin[bench])"}
    for sol, tep in zip(sols, teps):
        got = ets.eval(sol[0])
        rot = 0.0 if position else np.linalg.norm(pin.log3(tep[:3, :3] @ got[:3, :3].T))
        pok += bool(np.linalg.norm(got[:3, 3] - tep[:3, 3]) <= 1e-9 and rot <= 1e-9)
    peer_us = float(np.median(pblocked)) * 1e6
    return out | {"peer_rtb_ik_LM_median_us": round(peer_us, 1),
                  "rtb_interleaved_median_us": us([t for _, t in inter]),
                  "peer_cpu_mean_us_blocked": round(pcpu / n * 1e6, 1),
                  "peer_success": round(pok / n, 4), "speedup": round(peer_us / ours_us, 2),
                  "speedup_interleaved": round(us([t for _, t in inter]) /
                                               us([t for t, _ in inter]), 2)}


for name, src, kw, rtb_name, position, target_us, target_ok in (
    ("UR5 6-D", "erd:ur5_robot", {}, "UR5", False, 30, 0.999),
    ("Panda 6-D", "erd:panda", {}, "Panda", False, 40, 0.999),
    ("hexabot_leg position", "hexabot_leg", {}, "leg", True, 10, 1.0),
):
    row(f"ik.solve per call, {name}", lambda: per_call_row(src, kw, rtb_name, position,
                                                            target_us, target_ok))
"""

_FIRST = r"""
import json, time
import hexapod_kin as hk
leg = hk.load("hexabot_leg")
qs = leg.random_q(1_000_000, seed=0)
c0, t0 = time.process_time(), time.perf_counter()
leg.fk_batch(qs)
dt, cpu = time.perf_counter() - t0, time.process_time() - c0
print(json.dumps({"row": "first fk_batch 1e6 in a fresh process", "s": round(dt, 4),
                  "cpu_s": round(cpu, 4), "target_s": 0.5}))
"""


def _child(code: str, env: dict[str, str], *args: str) -> list[dict[str, Any]]:
    res = subprocess.run(
        [sys.executable, "-c", code, *args], env=env, capture_output=True, text=True, check=False
    )
    rows = [json.loads(ln) for ln in res.stdout.splitlines() if ln.startswith("{")]
    if res.returncode != 0:
        rows.append({"row": "child", "error": res.stderr.strip()[-300:]})
    return rows


def headline(quick: bool) -> list[dict[str, Any]]:
    """The issue's figures (see the module docstring)."""
    import bench_startup

    rows: list[dict[str, Any]] = []
    env = dict(os.environ)
    if not quick:  # quick (a smoke test): no start-up rows (their own section) and the caches
        try:  # of the environment, so that precompile only loads what is there
            rows += bench_startup.measure(list(bench_startup.COMMANDS), 1, ("cold", "warm"))
        except Exception as exc:  # noqa: BLE001 - printed on the row
            rows.append({"row": "startup", "error": f"{type(exc).__name__}: {exc}"})
        cache = Path(tempfile.mkdtemp(prefix="hk_bench_"))
        env["NUMBA_CACHE_DIR"] = str(cache / "numba")
        env["HEXAPOD_KIN_CACHE_DIR"] = str(cache / "hexapod_kin")
    t0 = time.perf_counter()
    pre = subprocess.run(
        [sys.executable, "-m", "hexapod_kin", "precompile"],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    rows.append(
        {
            "row": "precompile" + ("" if quick else " (fresh caches)"),
            "s": round(time.perf_counter() - t0, 2),
        }
        | ({"error": pre.stderr.strip()[-300:]} if pre.returncode else {})
    )
    firsts = [r for _ in range(1 if quick else 3) for r in _child(_FIRST, env)]
    times = sorted(r["s"] for r in firsts if "s" in r)
    if times and len(times) == len(firsts):  # each a fresh process after precompile
        rows.append(
            {
                "row": "first fk_batch 1e6 in a fresh process",
                "runs": len(times),
                "min_s": times[0],
                "median_s": times[len(times) // 2],
                "max_s": times[-1],
                "cpu_median_s": sorted(r["cpu_s"] for r in firsts)[len(times) // 2],
                "target_s": 0.5,
            }
        )
    else:
        rows += firsts
    rows += _child(_SPEED, env, "1" if quick else "0", str(TOOLS))
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--only", nargs="+", choices=SECTIONS, default=["headline"])
    parser.add_argument("--quick", action="store_true", help="fewer repetitions (smoke test)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    sys.path.insert(0, str(TOOLS))
    results = []
    for name in args.only:
        try:
            if name == "headline":
                rows = headline(args.quick)
            elif name == "percall":  # the headline's ik.solve per-call rows alone
                rows = _child(_SPEED, dict(os.environ), "1" if args.quick else "0", str(TOOLS),
                              "percall")  # fmt: skip
            else:
                rows = importlib.import_module(f"bench_{name}").run(args.quick)
        except Exception as exc:  # noqa: BLE001 - one failing section does not end the run
            rows = [{"error": f"{type(exc).__name__}: {exc}"}]
        for row in rows:
            row = {"section": name, **row}
            results.append(row)
            if not args.json:
                fields = (f"{k}={v}" for k, v in row.items() if k != "section")
                print(f"[{name}] " + "  ".join(fields), flush=True)
    if args.json:
        print(json.dumps(results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
