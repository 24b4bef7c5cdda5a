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
import os
import signal
import sys
import warnings
from collections.abc import Sequence
from typing import Any

from ..exceptions import HexapodKinError, ParameterError
from .common import OneLineParser

__all__ = ["build_parser", "main", "run"]

#: Modules of this package whose ``register(sub)`` adds subcommands, in help order.
MODULES: tuple[str, ...] = (
    "core",
    "view",
    "motion",
    "dynamics",
    "export",
    "sweep",
    "gait",
    "simulate",
    "report",
    "timeline",
    "precompile",
)


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser with every subcommand."""
    from .. import __version__

    parser = OneLineParser(
        prog="hexapod-kin",
        description="Robot legs: Khalil/DH tables -> URDF -> Pinocchio kinematics.",
    )
    parser.add_argument("--version", action="version", version=f"hexapod-kin {__version__}")
    sub = parser.add_subparsers(
        dest="command", required=True, metavar="COMMAND", parser_class=OneLineParser
    )
    for name in MODULES:
        importlib.import_module(f"{__name__}.{name}").register(sub)
    return parser


def _refuse_non_finite(args: argparse.Namespace) -> None:
    """No option value may be NaN or infinite (``--q nan``, ``--dt inf``): one clear error."""
    import math

    for dest, value in vars(args).items():
        values = value if isinstance(value, (list, tuple)) else [value]
        for v in values:
            if isinstance(v, float) and not math.isfinite(v):
                option = "--" + dest.replace("_", "-")
                raise ParameterError(
                    f"{option} {v}: not a finite number; give a finite value",
                    parameter=option,
                    value=v,
                    allowed="a finite number",
                )


def _one_line(text: object) -> str:
    return " ".join(str(text).split())


def _one_line_warning(original: Any) -> Any:
    """``warnings.showwarning`` printing the package's own warnings as plain lines.

    ``hexapod-kin: warning: ...`` (one per line of the message, no file:line and no source
    line); other warnings are shown as Python shows them.
    """
    from ..exceptions import HexapodKinWarning

    def show(message: Any, category: Any, filename: Any, lineno: Any, *rest: Any) -> None:
        if issubclass(category, HexapodKinWarning):
            for text in str(message).splitlines():
                print(f"hexapod-kin: warning: {text}", file=sys.stderr)
        else:
            original(message, category, filename, lineno, *rest)

    return show


#: Set by :func:`run`: the process ends after :func:`main`, so a Ctrl-C that arrives once the
#: command is done is ignored (the status stands) instead of killing the exiting interpreter.
_ENTRY = [False]


def run() -> None:
    """The ``hexapod-kin`` and ``python -m hexapod_kin`` entry point: :func:`main`, then exit."""
    _ENTRY[0] = True
    sys.exit(main())


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status.

    One rule for every command: **0** done (the answer achieves what was asked); **1**
    answered but not achieved (``ik``: the target is unreachable or only beyond the joint
    limits — the nearest point is printed; ``step``: joint or speed limits cut the motion;
    ``gait``: a check of the plan fails; ``simulate``: a physics check fails; ``derive``:
    ``--budget`` ran out before all was derived, checked and printed; ``scan``: the families
    were not all derived within ``--family-budget`` — ``NOT DONE`` lines say what is
    missing); **2** bad input or any failure (one line on stderr, never a traceback;
    ``HEXAPOD_KIN_DEBUG=1`` shows the traceback of an unexpected error); **130**
    interrupted. A closed stdout (``hexapod-kin fk ... | head``) ends quietly.

    Ctrl-C (SIGINT) is recorded as well as raised, so that a library that swallows the
    ``KeyboardInterrupt`` (e.g. inside an import, or where Python can only report it as
    "Exception ignored") cannot turn it into a success: an interrupted command ends with one
    line and status 130. (When the interrupt lands inside Python code that an extension
    module runs at import, CPython ends the process by SIGINT itself after this status is
    returned; a shell reports that as 130 too.)
    """
    interrupted: list[int] = []

    def on_sigint(signum: int, frame: object) -> None:
        interrupted.append(signum)
        raise KeyboardInterrupt

    def unraisable(info: Any) -> None:  # an interrupt raised where Python cannot raise it
        if isinstance(info.exc_value, KeyboardInterrupt):
            interrupted.append(signal.SIGINT)
        else:
            hook(info)

    try:
        previous = signal.signal(signal.SIGINT, on_sigint)
    except ValueError:  # not the main thread: leave signals alone
        previous = None
    hook, sys.unraisablehook = sys.unraisablehook, unraisable
    try:
        status = _main(argv)
    except KeyboardInterrupt:  # between the handler and _main's own handler
        status = 130
        print("hexapod-kin: interrupted", file=sys.stderr)
    finally:
        sys.unraisablehook = hook
        if previous is not None:
            signal.signal(signal.SIGINT, signal.SIG_IGN if _ENTRY[0] else previous)
    if interrupted and status != 130:
        print("hexapod-kin: interrupted", file=sys.stderr)
        return 130
    return status


def _main(argv: Sequence[str] | None) -> int:
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        _refuse_non_finite(args)
        with warnings.catch_warnings():
            warnings.showwarning = _one_line_warning(warnings.showwarning)
            return int(args.func(args))
    except SystemExit as exc:  # argparse: --help (0) or a usage error (2, already printed)
        return int(exc.code) if isinstance(exc.code, int) else 2
    except HexapodKinError as exc:
        print(f"hexapod-kin: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("hexapod-kin: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # stdout closed early (| head): silence the flush at exit and stop quietly
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
        except OSError:
            pass
        return 0
    except OSError as exc:
        where = f" {exc.filename!r}" if exc.filename else ""
        print(f"hexapod-kin: error: {exc.strerror or exc}{where}", file=sys.stderr)
        return 2
    except MemoryError:
        print(
            "hexapod-kin: error: not enough memory for this request; ask for fewer samples",
            file=sys.stderr,
        )
        return 2
    except Exception as exc:  # the last line of defence: one line, never a traceback
        if os.environ.get("HEXAPOD_KIN_DEBUG"):
            raise
        print(
            f"hexapod-kin: error: unexpected {type(exc).__name__}: {_one_line(exc)} "
            "(a bug: please report it; HEXAPOD_KIN_DEBUG=1 shows the traceback)",
            file=sys.stderr,
        )
        return 2
