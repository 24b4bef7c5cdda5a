"""Benchmarks: hexapod_kin against its peers, in one run, printing ratios.

Usage: ``python tools/bench.py [--only SECTION ...] [--quick] [--json]``.
Sections live in ``tools/bench_<section>.py`` (one per concern) and expose
``run(quick: bool) -> list[dict]``; each dict is one line of the report and carries its
comparison: a ``ratio``/``speedup`` against a peer measured in the same run, or a measured
figure beside its ``target``. ``startup`` times every subcommand as a whole process, cold
(fresh numba and derivation caches) and warm.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
from pathlib import Path

SECTIONS = [
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


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--only", nargs="+", choices=SECTIONS)
    parser.add_argument("--quick", action="store_true", help="fewer repetitions (smoke test)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    # speed sections measure machine code: every kernel compiled on its first call, never the
    # interpreted tier a cold process starts with (hexapod_kin._tier); ``startup`` times whole
    # processes, which keep the default rule
    from hexapod_kin import _tier

    _tier.set_mode("always")
    results = []
    for name in args.only or SECTIONS:
        try:
            mod = importlib.import_module(f"bench_{name}")
        except ModuleNotFoundError as exc:
            print(f"[{name}] skipped: {exc}", file=sys.stderr)
            continue
        for row in mod.run(args.quick):
            row = {"section": name, **row}
            results.append(row)
            if not args.json:
                fields = (f"{k}={v}" for k, v in row.items() if k != "section")
                print(f"[{name}] " + "  ".join(fields))
    if args.json:
        print(json.dumps(results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
