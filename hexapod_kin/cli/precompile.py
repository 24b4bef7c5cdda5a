"""``hexapod-kin precompile``: compile the kernels ahead of use (:mod:`hexapod_kin.precompile`)."""

from __future__ import annotations

import argparse
from typing import Any

from .common import emit_json

__all__ = ["register"]


def register(sub: Any) -> None:
    """Add the ``precompile`` subcommand."""
    from ..precompile import AREAS

    p = sub.add_parser(
        "precompile",
        help="compile the numba kernels now, so that later commands start from machine code",
        description=(
            "A new process runs small calls interpreted and compiles a kernel only when its "
            "work pays for it; this compiles the kernels of the chosen areas at once and "
            "numba's disk cache keeps them for every later process."
        ),
    )
    p.add_argument(
        "--only", nargs="+", choices=list(AREAS), metavar="AREA", help="areas (default: all)"
    )
    p.add_argument("--json", action="store_true")
    p.add_argument("--background", action="store_true", help=argparse.SUPPRESS)
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    import os

    from .. import _tier
    from ..precompile import precompile

    if args.background:  # started by a command at its exit (_tier): low priority, then unlock
        try:
            os.nice(10)
        except OSError:
            pass
        try:
            precompile(args.only)
        finally:
            _tier.background_done(os.getpid())
        return 0
    seconds = precompile(args.only)
    if args.json:
        emit_json({"seconds": {k: round(v, 3) for k, v in seconds.items()}})
        return 0
    for name, dt in seconds.items():
        print(f"{name:<12} {dt:7.2f} s")
    print(f"{'total':<12} {sum(seconds.values()):7.2f} s (machine code now in numba's disk cache)")
    return 0
