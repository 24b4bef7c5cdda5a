"""Benchmark section ``symbolic``: ``derive`` times (issues 10 and 11).

Targets: a 4-DOF leg, PUMA 560 and UR5 each derived (transforms, Jacobians, det J factored,
families checked against σ_min) in <= 5 s; a cached derivation read back in a new call in
milliseconds. Peer, measured in the same run: the textbook sympy route that ``derive`` used
before (``simplify`` + ``trigsimp`` of every product and Jacobian entry, ``det`` of the
base-frame Jacobian, ``factor``), stopped at a cap (``>cap`` printed when it did not finish).

Usage: ``python tools/bench_symbolic.py [--cap S]`` (or ``python tools/bench.py --only symbolic``).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from collections.abc import Iterator
from typing import Any

import sympy as sp

from hexapod_kin import Chain, DHRow, KhalilRow, robots, symbolic
from hexapod_kin._budget import BudgetReached, cpu_limit
from hexapod_kin.jacobian_rows import choose_rows
from hexapod_kin.symbolic import core

PI = math.pi
TARGET_S = 5.0


def chains() -> dict[str, Chain]:
    """The benchmarked chains: leg, 4-DOF leg, SCARA, PUMA 560, UR5."""
    puma = [(0, 0, 0, PI / 2), (0, 0, 0.4318, 0), (0, 0.15005, 0.0203, -PI / 2),
            (0, 0.4318, 0, PI / 2), (0, 0, 0, -PI / 2), (0, 0, 0, 0)]  # fmt: skip
    ur5 = [(0, 0.089159, 0, PI / 2), (0, 0, -0.425, 0), (0, 0, -0.39225, 0),
           (0, 0.10915, 0, PI / 2), (0, 0.09465, 0, -PI / 2), (0, 0.0823, 0, 0)]  # fmt: skip
    leg4 = Chain(
        rows=(
            KhalilRow(0),
            KhalilRow(0, -PI / 2, 0.05),
            KhalilRow(0, 0, 0.1),
            KhalilRow(0, 0, 0.1),
            KhalilRow("fixed", 0, 0.05),
        ),  # fmt: skip
        name="leg4",
    )
    return {
        "hexabot_leg": robots.hexabot_leg(),
        "leg4": leg4,
        "scara": robots.scara(),
        "puma560": Chain.from_dh([DHRow(*r) for r in puma], name="puma560"),
        "ur5": Chain.from_dh([DHRow(*r) for r in ur5], name="ur5"),
    }


def _naive(chain: Chain) -> Iterator[tuple[str, Any]]:
    """The textbook route: simplify everything, det in the base frame, factor."""
    q = tuple(sp.Symbol(f"q{k}", real=True) for k in range(1, chain.nq + 1))
    syms = core.length_symbols(chain, None)
    kin = core.kinematics(chain, q, syms, simplify=False)

    def simp(e: Any) -> Any:
        return e.applyfunc(simp) if isinstance(e, sp.MatrixBase) else sp.trigsimp(sp.simplify(e))

    acc = sp.eye(4)
    frames = []
    for t in kin["transforms"]:
        acc = simp(acc * t)
        frames.append(acc)
    p = acc[:3, 3]
    cols = []
    for j in chain.joint_rows:
        z, o = frames[j][:3, 2], frames[j][:3, 3]
        cols.append(sp.Matrix.vstack(z.cross(p - o), z) if chain.rows[j].sigma == "revolute"
                    else sp.Matrix.vstack(z, sp.zeros(3, 1)))  # fmt: skip
    jac = simp(sp.Matrix.hstack(*cols))
    yield "J", True
    rows = choose_rows([any(e != 0 for e in jac.row(i)) for i in range(6)], chain.nq)
    sel = jac.extract([symbolic.ROW_NAMES.index(r) for r in rows], list(range(chain.nq)))
    mat = sel if sel.shape[0] == chain.nq else sel * sel.T
    yield "det", sp.factor(simp(mat.det(method="berkowitz")))


def run(quick: bool = False, cap: float | None = None) -> list[dict[str, Any]]:
    """Rows of the report: ours (cold, then cached), the peer, their ratio and the target."""
    cap = cap if cap is not None else (1.0 if quick else 20.0)
    rows = []
    old = os.environ.get("HEXAPOD_KIN_CACHE_DIR")
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["HEXAPOD_KIN_CACHE_DIR"] = tmp
        try:
            for name, chain in chains().items():
                if quick and name not in ("hexabot_leg", "puma560"):
                    continue
                t0 = time.perf_counter()
                d = symbolic.derive(chain, budget=TARGET_S)
                ours = time.perf_counter() - t0
                t0 = time.perf_counter()
                again = symbolic.derive(chain)
                cached = time.perf_counter() - t0
                t0 = time.perf_counter()
                reason = None
                try:
                    with cpu_limit(cap):  # CPU seconds, as every budget of the package
                        dict(_naive(chain))
                except BudgetReached:
                    reason = f"budget of {cap:g} s reached"
                peer = time.perf_counter() - t0
                peer_text = f"{peer:.2f}" if reason is None else f">{cap:g}"
                rows.append(
                    {
                        "chain": name,
                        "dof": chain.nq,
                        "derive_s": round(ours, 3),
                        "complete": d.complete,
                        "families": len(d.families),
                        "verified": sum(bool(f.verified) for f in d.families),
                        "cached_s": round(cached, 4),
                        "from_cache": again.cached,
                        "peer_s": peer_text,
                        "peer/ours": f"{peer / ours:.1f}"
                        if reason is None
                        else f">{cap / ours:.1f}",
                        "target_s": TARGET_S,
                        "ok": ours <= TARGET_S and d.complete,
                        "det_method": d.method,
                    }
                )
        finally:
            if old is None:
                os.environ.pop("HEXAPOD_KIN_CACHE_DIR", None)
            else:
                os.environ["HEXAPOD_KIN_CACHE_DIR"] = old
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cap", type=float, default=20.0, help="peer time cap [s]")
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args(argv)
    for row in run(args.quick, args.cap):
        print("  ".join(f"{k}={v}" for k, v in row.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
