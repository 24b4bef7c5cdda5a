"""Start times of every ``hexapod-kin`` subcommand, as whole processes: cold and warm.

* **cold**: a fresh ``NUMBA_CACHE_DIR`` and ``HEXAPOD_KIN_CACHE_DIR`` (empty temp folders), so
  neither the compiled kernels nor the symbolic derivations can be reused: what a new user's
  first command pays. Python bytecode stays as it is (written by the first import of each
  module; a cold bytecode cache adds about 0.3 s, measured with ``PYTHONPYCACHEPREFIX`` in a
  new folder).
* **warm**: the same command again with the caches that a first (untimed) run filled.

Each command runs ``runs`` times per mode (a new cold folder each cold run); the report has
min / median / max wall seconds and the median CPU seconds (user + system: what the process
and its children cost, whatever else runs; ``reproduce`` runs two processes at once, so on an
idle machine its wall time is below its CPU time), and marks a median over its target
(issue 21: cold ≤ 2 s, ``reproduce`` cold ≤ 5 s; warm ≤ 1 s) by either clock. The peer is
``python -c "import hexapod_kin"`` in the same run (``ratio`` = median / that), so a slow
machine shows as such.

Usage: ``python tools/bench_startup.py [--quick] [--runs N] [--only CMD ...] [--mode cold|warm]``
or ``python tools/bench.py --only startup``; ``--profile CMD`` prints the numba compile seconds
of each kernel a cold ``CMD`` compiles (command-line work should compile none: the size rule).
No timing assertion anywhere.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

COLD_TARGET_S = 2.0
#: ``reproduce`` (the README's first command) from a fresh install.
REPRODUCE_COLD_TARGET_S = 5.0
WARM_TARGET_S = 1.0

#: Every subcommand with typical arguments; ``{out}`` is a scratch folder.
COMMANDS: dict[str, list[str]] = {
    "list": ["list"],
    "urdf": ["urdf", "hexabot_leg", "-o", "{out}/leg.urdf"],
    "fk": ["fk", "hexabot_leg", "--q", "0", "0.5", "-1"],
    "jacobian": ["jacobian", "hexabot_leg", "--q", "0", "0.5", "-1"],
    "ik": ["ik", "hexabot_leg", "--target", "0.25", "0.05", "-0.1"],  # out of reach: numerical
    "ik-reach": ["ik", "hexabot_leg", "--target", "0.15", "0.05", "-0.1"],
    "ik-pose": ["ik", "erd:ur5_robot", "--pose", "0.4", "0.2", "0.3", "3.1", "0.1", "0"],
    "step": ["step", "hexabot_leg", "--duration", "1", "--no-baseline"],
    "step-default": ["step", "hexabot_leg"],
    "step-twist": ["step", "erd:ur5_robot", "--twist", "0", "0", "0.01", "0", "0", "0.1"],
    "scan": ["scan", "hexabot_leg"],
    "scan-ur5": ["scan", "erd:ur5_robot"],
    "derive": ["derive", "hexabot_leg"],
    "demo": ["demo", "--out", "{out}/demo"],
    "animate": ["animate", "hexabot_leg", "--html", "{out}/anim.html"],
    "gait": ["gait", "--duration", "2"],
    "pendulum": ["pendulum", "--duration", "2"],
    "torques": ["torques", "hexabot_leg", "--q", "0", "0.5", "-1"],
    "stand": ["stand"],
    "xacro": ["xacro", "hexapod", "-o", "{out}/hexapod.xacro"],
    "mjcf": ["mjcf", "hexabot_leg", "-o", "{out}/leg.xml"],
    "export-package": ["export-package", "hexabot_leg", "-o", "{out}/pkg", "-f"],
    "sweep": [
        "sweep",
        "--height",
        "0.1",
        "--l2",
        "0.08:0.12:2",
        "--mc-samples",
        "2000",
        "--out",
        "{out}/sweep.csv",
    ],
    "timeline": ["timeline", "gait", "--duration", "2", "-o", "{out}/walk.csv"],
    "simulate": ["simulate", "hexapod", "--duration", "2", "--no-stand"],
    "reproduce": ["reproduce", "--quick", "--no-animations", "--out", "{out}/report"],
    # the README's first command: the whole report (animations included)
    "reproduce-full": ["reproduce", "--out", "{out}/report_full"],
}
#: Not timed: ``view`` and ``drive`` serve a page until interrupted (no start-to-exit time);
#: ``precompile`` exists to pay every compile at once.
UNTIMED = ("view", "drive", "control", "precompile")  # precompile compiles every kernel on purpose
#: The commands of ``--quick`` (a smoke test of the section: one of each kind of cost).
QUICK = ("list", "fk", "scan")


def _cli() -> list[str]:
    return [sys.executable, "-m", "hexapod_kin"]


def _env(cache: Path | None) -> dict[str, str]:
    env = dict(os.environ)
    # as on a user's machine: Python writes the bytecode of the package on its first import
    # (an editable install compiles none; a sandbox may set PYTHONDONTWRITEBYTECODE, and then
    # every process would compile the recently edited modules from source again)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    if cache is not None:
        env["NUMBA_CACHE_DIR"] = str(cache / "numba")
        env["HEXAPOD_KIN_CACHE_DIR"] = str(cache / "hexapod_kin")
    env.pop("HEXAPOD_KIN_DEBUG", None)
    return env


def _cpu_children() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _time(
    argv: list[str], env: dict[str, str], timeout: float, cwd: Path | None = None
) -> tuple[float, int, str, float]:
    """Wall seconds, exit status, last stderr line and CPU seconds of one whole process.

    The CPU time (user + system, the child's threads included) is what the process itself
    cost: unlike the wall time it hardly depends on what else runs on the machine.
    """
    t0, c0 = time.perf_counter(), _cpu_children()
    try:
        res = subprocess.run(
            argv, env=env, cwd=cwd, capture_output=True, text=True, timeout=timeout, check=False
        )
    except subprocess.TimeoutExpired:
        return time.perf_counter() - t0, -1, f"timed out after {timeout:g} s", float("nan")
    last = (res.stderr.strip().splitlines() or [""])[-1]
    return time.perf_counter() - t0, res.returncode, last, _cpu_children() - c0


def _stats(times: list[float]) -> dict[str, float]:
    return {
        "min_s": round(min(times), 3),
        "median_s": round(statistics.median(times), 3),
        "max_s": round(max(times), 3),
    }


def measure(
    names: list[str], runs: int, modes: tuple[str, ...], timeout: float = 300.0
) -> list[dict[str, Any]]:
    """Rows of the report: one per command and mode.

    Args:
        names: Keys of :data:`COMMANDS`.
        runs: Processes per command and mode (≥ 1).
        modes: ``"cold"`` and/or ``"warm"``.
        timeout: Bound of one process in [s].

    Returns:
        Dicts with the command, mode, min/median/max [s], the peer ratio, the target and
        ``over`` (True when the median exceeds the target) and the exit status.

    """
    out_dir = Path(tempfile.mkdtemp(prefix="hk_startup_"))
    peer_argv = [sys.executable, "-c", "import hexapod_kin"]
    rows: list[dict[str, Any]] = []
    try:
        warm_cache = out_dir / "warm_cache"
        peer = statistics.median(
            _time(peer_argv, _env(warm_cache), timeout)[0] for _ in range(max(runs, 3))
        )
        for name in names:
            argv = _cli() + [a.format(out=out_dir) for a in COMMANDS[name]]
            for mode in modes:
                times: list[float] = []
                cpus: list[float] = []
                status, last = 0, ""
                for i in range(runs):
                    if mode == "cold":
                        cache = out_dir / f"cold_{name}_{i}"
                        dt, status, last, cpu = _time(argv, _env(cache), timeout, out_dir)
                        shutil.rmtree(cache, ignore_errors=True)
                    else:
                        if i == 0:  # fill the caches first (not counted)
                            _time(argv, _env(warm_cache), timeout, out_dir)
                        dt, status, last, cpu = _time(argv, _env(warm_cache), timeout, out_dir)
                    times.append(dt)
                    cpus.append(cpu)
                target = WARM_TARGET_S
                if mode == "cold":
                    repro = name.startswith("reproduce")
                    target = REPRODUCE_COLD_TARGET_S if repro else COLD_TARGET_S
                stats = _stats(times)
                rows.append(
                    {
                        "command": name,
                        "mode": mode,
                        **stats,
                        "cpu_median_s": round(statistics.median(cpus), 3),
                        "ratio": round(stats["median_s"] / peer, 1),
                        "peer_import_s": round(peer, 3),
                        "target_s": target,
                        "over": stats["median_s"] > target,
                        "over_cpu": statistics.median(cpus) > target,
                        "exit": status,
                        **({"stderr": last[:120]} if status != 0 else {}),
                    }
                )
    finally:
        shutil.rmtree(out_dir, ignore_errors=True)
    return rows


_PROFILE = """
import sys, time
from numba.core import event
recorder_cm = event.install_recorder("numba:compile")
recorder = recorder_cm.__enter__()
from hexapod_kin.cli import main
main(sys.argv[1:])
starts, rows = {}, []
for ts, ev in recorder.buffer:
    disp = ev.data["dispatcher"]
    key = (id(disp), str(ev.data["args"]))
    if ev.is_start:
        starts[key] = ts
    else:
        name = disp.py_func.__module__ + "." + disp.py_func.__qualname__
        rows.append((ts - starts.pop(key, ts), name))
for dt, name in sorted(rows, reverse=True):
    print(f"@@{dt:8.2f} s  {name}", file=sys.stderr)
"""


def compile_profile(name: str, timeout: float = 300.0) -> str:
    """Seconds of numba compilation per kernel of one cold command (nested times included).

    Runs the command in a child with fresh caches and numba's ``numba:compile`` events; a
    kernel's time includes the kernels it calls that compile with it.
    """
    cache = Path(tempfile.mkdtemp(prefix="hk_profile_"))
    try:
        argv = [sys.executable, "-c", _PROFILE] + [a.format(out=cache) for a in COMMANDS[name]]
        res = subprocess.run(
            argv,
            env=_env(cache),
            cwd=cache,
            capture_output=True,
            text=True,
            timeout=timeout,
            check=False,
        )
        rows = [ln[2:] for ln in res.stderr.splitlines() if ln.startswith("@@")]
        return "\n".join(rows) or f"no compile events (exit {res.returncode})"
    finally:
        shutil.rmtree(cache, ignore_errors=True)


def run(quick: bool = False) -> list[dict[str, Any]]:
    """tools/bench.py's ``startup`` section (``quick``: three commands, one run each)."""
    if quick:
        return measure(list(QUICK), 1, ("warm",)) + measure(["fk"], 1, ("cold",))
    return measure(list(COMMANDS), 3, ("cold", "warm"))


def _table(rows: list[dict[str, Any]]) -> str:
    lines = [f"{'command':16} {'mode':5} {'min':>7} {'median':>7} {'max':>7} {'cpu':>7}  target"]
    for r in rows:
        flag = ("  OVER" if r["over"] else "") + ("  OVER (cpu)" if r["over_cpu"] else "")
        bad = f"  exit {r['exit']}: {r.get('stderr', '')}" if r["exit"] != 0 else ""
        lines.append(
            f"{r['command']:16} {r['mode']:5} {r['min_s']:7.2f} {r['median_s']:7.2f} "
            f"{r['max_s']:7.2f} {r['cpu_median_s']:7.2f}  <= {r['target_s']:g} s{flag}{bad}"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Print the start-time table (seconds, wall clock, whole processes)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="the bench.py smoke test")
    parser.add_argument("--runs", type=int, default=3, help="processes per command and mode")
    parser.add_argument("--only", nargs="+", choices=sorted(COMMANDS), help="these commands")
    parser.add_argument("--mode", choices=("cold", "warm", "both"), default="both")
    parser.add_argument(
        "--profile", choices=sorted(COMMANDS), help="compile seconds per kernel of one cold command"
    )
    args = parser.parse_args(argv)
    if args.profile:
        print(compile_profile(args.profile))
        return 0
    if args.quick:
        rows = run(quick=True)
    else:
        modes = ("cold", "warm") if args.mode == "both" else (args.mode,)
        rows = measure(args.only or list(COMMANDS), max(1, args.runs), modes)
    print(_table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
