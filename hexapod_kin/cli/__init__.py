"""The ``hexapod-kin`` command line: ``main(argv=None) -> int``.

Subcommands live in the modules of this package, one module per area; each module has a
``register(sub)`` that declares its subcommands (``sub.add_parser``) and binds each one's
runner with ``set_defaults(func=...)``. Heavy imports stay inside the runners.
``--json`` output is one JSON object on stdout; progress and messages go to stderr.
Errors of the :class:`~hexapod_kin.exceptions.HexapodKinError` family print one line
``hexapod-kin: error: ...`` and exit with status 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from ..exceptions import HexapodKinError

__all__ = ["build_parser", "main"]

#: Modules of this package whose ``register(sub)`` adds subcommands, in help order.
MODULES: tuple[str, ...] = ("core",)


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser with every subcommand."""
    from .. import __version__

    parser = argparse.ArgumentParser(
        prog="hexapod-kin",
        description="Robot legs: Khalil/DH tables -> URDF -> Pinocchio kinematics.",
    )
    parser.add_argument("--version", action="version", version=f"hexapod-kin {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in MODULES:
        importlib.import_module(f"{__name__}.{name}").register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status (0 ok, 2 usage or input error)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except HexapodKinError as exc:
        print(f"hexapod-kin: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("hexapod-kin: interrupted", file=sys.stderr)
        return 130
