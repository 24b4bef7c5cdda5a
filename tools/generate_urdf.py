"""Write the URDF of every catalogue preset to ``urdf/`` (``--check``: report drift, exit 1).

Usage::

    python tools/generate_urdf.py            # (re)write urdf/*.urdf
    python tools/generate_urdf.py --check    # exit 1 if any file differs from the generator

Each file's header says which preset and command made it. Files are written atomically.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from hexapod_kin import robots
from hexapod_kin._io import atomic_write
from hexapod_kin.params import Hexapod
from hexapod_kin.urdf import to_urdf

ROOT = Path(__file__).resolve().parent.parent
COMMAND = "python tools/generate_urdf.py"


def targets() -> dict[str, str]:
    """File name → URDF text for every preset (and each hexapod leg with its mount)."""
    out: dict[str, str] = {}
    for name in robots.names():
        built = robots.get(name)
        header = f"preset: robots.{name}() with its defaults; made by: {COMMAND}"
        out[f"{name}.urdf"] = to_urdf(built, header=header)
        if isinstance(built, Hexapod):
            for leg in built.legs:
                header = (
                    f"preset: robots.{name}(), leg {leg.name!r} with its mount on the body; "
                    f"made by: {COMMAND}"
                )
                out[f"{name}_{leg.name}.urdf"] = to_urdf(built, leg=leg.name, header=header)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="report drift, write nothing")
    parser.add_argument("--dir", default=str(ROOT / "urdf"), help="output directory")
    args = parser.parse_args(argv)
    outdir = Path(args.dir)
    wanted = targets()
    if args.check:
        drift = []
        for name, text in wanted.items():
            path = outdir / name
            if not path.exists():
                drift.append(f"missing: {path}")
            elif path.read_text(encoding="utf-8") != text:
                drift.append(f"differs: {path}")
        stale = sorted(p.name for p in outdir.glob("*.urdf") if p.name not in wanted)
        drift += [f"not generated (stale): {outdir / n}" for n in stale]
        for line in drift:
            print(line)
        if drift:
            print(f"{len(drift)} URDF file(s) drifted; run: {COMMAND}", file=sys.stderr)
            return 1
        print(f"{len(wanted)} URDF files up to date in {outdir}")
        return 0
    outdir.mkdir(parents=True, exist_ok=True)
    for name, text in wanted.items():
        atomic_write(outdir / name, text)
        print(f"wrote {outdir / name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
