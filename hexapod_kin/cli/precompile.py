"""``hexapod-kin precompile``: compile the kernels ahead of use (:mod:`hexapod_kin.precompile`)."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from .common import emit_json

__all__ = ["register"]


def register(sub: Any) -> None:
    """Add the ``precompile`` subcommand."""
    from ..precompile import AREAS

    p = sub.add_parser(
        "precompile",
        help="compile the numba kernels now, so that later batch calls start from machine code",
        description=(
            "Compiles every batch kernel of the chosen areas once; numba's disk cache keeps "
            "the machine code for every later process."
        ),
    )
    p.add_argument(
        "--only", nargs="+", choices=list(AREAS), metavar="AREA", help="areas (default: all)"
    )
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    import os

    from .._kernels import COMPILE_SECONDS
    from ..precompile import AREAS, precompile

    areas = args.only or list(AREAS)
    jobs = max(1, min(len(areas), os.cpu_count() or 1))
    total = sum(COMPILE_SECONDS[a] for a in areas)
    about = max(total / jobs, max(COMPILE_SECONDS[a] for a in areas)) + (jobs > 1)  # + start

    def done(name: str, dt: float) -> None:
        print(f"  {name} done ({dt:.1f} s)", file=sys.stderr, flush=True)

    if not args.json:
        print(
            f"compiling {', '.join(areas)} in {jobs} process(es): about {about:.0f} s "
            "(less if numba's cache holds some)",
            file=sys.stderr,
            flush=True,
        )
    seconds = precompile(areas, processes=jobs, done=None if args.json else done)
    if args.json:
        emit_json({"seconds": {k: round(v, 3) for k, v in seconds.items()}})
        return 0
    for name, dt in seconds.items():
        print(f"{name:<12} {dt:7.2f} s")
    print(
        f"{'sum':<12} {sum(seconds.values()):7.2f} s (in numba's disk cache, unless warned above)"
    )
    return 0
