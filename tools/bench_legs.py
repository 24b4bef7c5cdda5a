"""Benchmark: any legged robot walks (issue 22, build items 1-2).

Targets (issue 22): planning 10 s of tripod at 100 Hz (1,001 samples) with every check in
<= 0.05 s with closed-form legs (the built-in hexapod) and <= 0.3 s with numerical leg IK
(the PhantomX URDF, whose legs no closed form solves exactly; its wave and ripple exceed the
URDF's 5.655 rad/s thigh speed limit at the default period, so they run with
``strict=False``: every check computed, none raised). Also measured: the
numerical body-pose IK alone, the same IK forced onto the built-in legs, and building the
robot from its URDF (legs from the tree, closed-form checks, standing seed).

Times are the best of ``--repeat`` runs (wall clock; ``--cpu``: the process's CPU time, for
a shared machine). The numerical-IK target is also measured on the built-in legs forced
numerical (closed forms switched off) with their 12 mm rolling feet, the default walk.

Usage: ``python tools/bench_legs.py [--repeat N] [--cpu]``.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

from hexapod_kin.gait import as_whole_body, walk, whole_body

PHX = Path(__file__).resolve().parents[1] / "tests" / "data" / "phantomx" / "phantomx.urdf"
FEET = " ".join(f"tibia_{s}:0,0.16,0.029" for s in ("lf", "lm", "lr", "rf", "rm", "rr"))


CLOCK: Callable[[], float] = time.perf_counter


def best_of(fn: Callable[[], Any], repeat: int, clock: Callable[[], float]) -> float:
    """The shortest of ``repeat`` runs of ``fn`` [s], timed by ``clock``."""
    times = []
    for _ in range(repeat):
        t0 = clock()
        fn()
        times.append(clock() - t0)
    return min(times)


def _best(fn: Callable[[], Any], repeat: int) -> float:
    return best_of(fn, repeat, CLOCK)


def _uncached_build() -> Any:
    from hexapod_kin.gait import robot

    robot._SOURCES.clear()  # the per-source cache: measure a fresh build
    return as_whole_body(str(PHX), feet=FEET)


def rows(repeat: int = 5) -> list[tuple[str, float, str]]:
    """(label, seconds, target text) per case."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the PhantomX meshes are not shipped
        builtin = whole_body()
        phx = as_whole_body(str(PHX), feet=FEET)
        t_build = _best(_uncached_build, max(1, repeat // 2))
        phx = as_whole_body(str(PHX), feet=FEET)
        phx_round = as_whole_body(str(PHX), feet=FEET, foot_radius=0.012)
    forced = replace(builtin, _closed=(None,) * builtin.n_legs)
    run = walk(phx, duration=10.0, rate=100.0)  # warm up
    walk(forced, duration=1.0)
    ref = walk(builtin, duration=10.0, rate=100.0)
    out = [
        (
            "built-in hexapod: tripod 10 s @ 100 Hz, all checks (closed-form legs)",
            _best(lambda: walk(builtin, pattern="tripod"), repeat),
            "<= 0.05 s",
        )
    ]
    out.append(
        (
            "built-in legs forced numerical: tripod 10 s @ 100 Hz, 12 mm rolling feet, all checks",
            _best(lambda: walk(forced, pattern="tripod"), repeat),
            "<= 0.3 s",
        )
    )
    out.append(
        (
            "PhantomX URDF, 12 mm rolling feet: tripod 10 s @ 100 Hz, all checks (numerical)",
            _best(lambda: walk(phx_round, pattern="tripod"), repeat),
            "(informative)",
        )
    )
    for pattern in ("tripod", "wave", "ripple"):
        out.append(
            (
                f"PhantomX URDF: {pattern} 10 s @ 100 Hz, all checks (numerical leg IK)",
                _best(lambda p=pattern: walk(phx, pattern=p, strict=p == "tripod"), repeat),
                "<= 0.3 s" if pattern == "tripod" else "(informative)",
            )
        )
    out += [
        (
            "PhantomX: body_ik alone, 1001 samples x 6 legs (numerical)",
            _best(lambda: phx.body_ik(run.base_poses, run.feet_planned), repeat),
            "(informative)",
        ),
        (
            "built-in legs forced numerical: body_ik, 1001 samples x 6 legs",
            _best(lambda: forced.body_ik(ref.base_poses, ref.feet_planned), repeat),
            "(informative)",
        ),
        (
            "built-in legs closed form: body_ik, 1001 samples x 6 legs",
            _best(lambda: builtin.body_ik(ref.base_poses, ref.feet_planned), repeat),
            "(informative)",
        ),
        ("PhantomX: as_whole_body from the URDF file (uncached)", t_build, "(informative)"),
    ]
    return out


def main(argv: list[str] | None = None) -> int:
    """Print one line per case."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=5, help="timed runs per case (best)")
    parser.add_argument(
        "--cpu", action="store_true", help="process CPU time instead of wall clock (shared hosts)"
    )
    args = parser.parse_args(argv)
    global CLOCK
    if args.cpu:
        CLOCK = time.process_time
    for label, sec, target in rows(args.repeat):
        print(f"{sec:9.4f} s  {target:<14} {label}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
