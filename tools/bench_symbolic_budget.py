"""Benchmark: symbolic budgets on the command line (issues 23 and 25).

Targets: ``hexapod-kin derive SOURCE --budget 5`` ends within 5 + 1 s of wall time (Python's
start-up and imports included), for the 5-DOF leg of ``examples/leg5.yaml``, Panda, and the
7- and 12-joint chains of ``tests/data`` that sympy cannot finish in seconds; a second
``hexapod-kin scan`` of the same robot (its family derivation, finished or stopped at its
budget, read back from the disk cache) within 2 s; the first ``scan`` within its 10 s family
budget + the scan without families + 1.5 s.

Each command runs as a fresh process (``python -m hexapod_kin``) with an empty cache folder
of its own; wall time is measured around the process. The machine's load is printed with
the rows (the targets assume an idle machine; a loaded one stretches the imports).

Usage: ``python tools/bench_symbolic_budget.py [--runs N]``.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
LEG5 = str(ROOT / "examples" / "leg5.yaml")
PANDA = ["erd:panda", "--tip", "panda_hand_tcp"]
ARM7 = str(ROOT / "tests" / "data" / "arm7.yaml")
CHAIN12 = str(ROOT / "tests" / "data" / "chain12.yaml")
BUDGET = 5.0


def _wall(args: list[str], cache: str) -> float:
    """Seconds of wall time of ``python -m hexapod_kin ARGS`` (exit status 0 or 1 required:
    1 when the budget ran out first)."""
    env = {**os.environ, "HEXAPOD_KIN_CACHE_DIR": cache, "PYTHONPATH": str(ROOT)}
    t0 = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-m", "hexapod_kin", *args], env=env, capture_output=True, text=True
    )
    wall = time.perf_counter() - t0
    if done.returncode not in (0, 1):
        raise RuntimeError(f"{' '.join(args)}: exit {done.returncode}: {done.stderr[-500:]}")
    return wall


def rows(runs: int = 3) -> list[tuple[str, float, str]]:
    """(label, seconds, target) rows: the worst of ``runs`` fresh-cache runs of each command."""
    out: list[tuple[str, float, str]] = []
    derive_target = f"<= {BUDGET + 1:g} s (budget {BUDGET:g} s + 1 s)"
    robots = (("leg5", [LEG5]), ("panda", PANDA), ("arm7", [ARM7]), ("chain12", [CHAIN12]))
    for name, src in robots:
        worst_derive = worst_first = worst_second = 0.0
        for _ in range(runs):
            with tempfile.TemporaryDirectory() as tmp:
                worst_derive = max(
                    worst_derive, _wall(["derive", *src, "--budget", f"{BUDGET:g}"], tmp)
                )
            with tempfile.TemporaryDirectory() as tmp:
                worst_first = max(worst_first, _wall(["scan", *src], tmp))
                worst_second = max(worst_second, _wall(["scan", *src], tmp))
        out.append(
            (f"derive {name} --budget {BUDGET:g} (fresh cache)", worst_derive, derive_target)
        )
        out.append((f"scan {name}, first (derives within 10 s)", worst_first, "(reference)"))
        out.append((f"scan {name}, second (cache)", worst_second, "<= 2 s"))
    return out


def main() -> None:
    """Print the rows."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3, help="runs per command (worst kept)")
    args = parser.parse_args()
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"load average (1 min): {load:.1f} on {os.cpu_count()} cores")
    for label, seconds, target in rows(args.runs):
        print(f"{label:<48} {seconds:7.2f} s   target {target}")


if __name__ == "__main__":
    main()
