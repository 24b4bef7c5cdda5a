"""``hexapod-kin reproduce``: redo the four lab reports and write the checked report."""

from __future__ import annotations

import argparse
import json
from typing import Any

__all__ = ["register"]


def _reproduce(args: argparse.Namespace) -> int:
    from ..report import reproduce

    rep = reproduce(
        args.out, quick=args.quick, animations=not args.no_animations, cache=not args.no_cache
    )
    if args.json:
        print(json.dumps(rep.to_dict(), default=str))
    else:
        print(f"report: {rep.html} (also {rep.markdown}, verdicts.json)")
        when = f"{rep.seconds:.1f} s"
        if rep.replayed_from:
            when = f"{rep.seconds:.2f} s" + (
                ", replayed: same code, data and libraries as the build of "
                f"{rep.replayed_from[:16]}Z ({rep.build_seconds or 0.0:.1f} s); "
                "--no-cache recomputes"
            )
        print(f"verdicts: {rep.summary()} [{when}]")
        for v in rep.verdicts:
            if v.status != "agrees":
                text = v.text if len(v.text) <= 150 else v.text[:147] + "..."
                print(f"  {v.claim} (seed {v.seed}, {v.where}): {text}")
    return 1 if rep.counts["error"] else 0


def register(sub: Any) -> None:
    """Add ``reproduce``."""
    p = sub.add_parser(
        "reproduce",
        help="redo every result of the four lab reports; write the checked report (MD + HTML)",
    )
    p.add_argument("--out", default="report", help="report folder (created)")
    p.add_argument(
        "--quick", action="store_true", help="reduced sizes (shorter runs, coarser scans)"
    )
    p.add_argument("--no-animations", action="store_true",
                   help="skip the step and walk animations (no viewer extra needed)")  # fmt: skip
    p.add_argument(
        "--no-cache",
        action="store_true",
        help="recompute everything instead of replaying an earlier build with the same code, "
        "data and libraries (the cache is only written)",
    )
    p.add_argument("--json", action="store_true", help="print the verdicts as one JSON object")
    p.set_defaults(func=_reproduce)
