"""The ``hexapod-kin`` command line: ``main(argv=None) -> int``.

One module per area, each with a ``register(sub)`` that adds its subcommands and binds their
runners (``set_defaults(func=...)``); heavy imports stay inside the runners. ``--json`` is one
JSON object on stdout; messages go to stderr. Exit statuses: :func:`main`.
"""

from __future__ import annotations

import argparse
import contextlib
import gc
import importlib
import os
import signal
import sys
import threading
import warnings
from collections.abc import Sequence
from typing import Any

from ..exceptions import HexapodKinError, ParameterError
from .common import OneLineParser

__all__ = ["build_parser", "main", "run"]

#: Modules of this package whose ``register(sub)`` adds subcommands, in help order.
MODULES: tuple[str, ...] = tuple(
    "core view drive motion dynamics export sweep gait simulate control report timeline "
    "precompile".split()
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
        for v in value if isinstance(value, (list, tuple)) else [value]:
            if isinstance(v, float) and not math.isfinite(v):
                option = "--" + dest.replace("_", "-")
                msg = f"{option} {v}: not a finite number; give a finite value"
                raise ParameterError(msg, parameter=option, value=v, allowed="a finite number")


def _one_line(text: object) -> str:
    return " ".join(str(text).split())


def _one_line_warning(original: Any) -> Any:
    """``warnings.showwarning`` printing each distinct package warning ``hexapod-kin: warning``."""
    from ..exceptions import HexapodKinWarning

    said: set[str] = set()

    def show(message: Any, category: Any, filename: Any, lineno: Any, *rest: Any) -> None:
        if issubclass(category, HexapodKinWarning):
            if str(message) in said:
                return
            said.add(str(message))
            for text in str(message).splitlines():
                print(f"hexapod-kin: warning: {text}", file=sys.stderr)
        else:
            original(message, category, filename, lineno, *rest)

    return show


#: Set by :func:`run`: a Ctrl-C once the command is done is ignored (the status stands).
_ENTRY = [False]


def run() -> None:
    """The ``hexapod-kin`` and ``python -m hexapod_kin`` entry point: :func:`main`, then exit."""
    _ENTRY[0] = True
    # The program owns its process (the library never writes os.environ): MuJoCo, never used
    # to render here, is imported without its OpenGL backends, whose glfw probe would start a
    # child process that a Ctrl-C to the process group interrupts with a fatal error.
    os.environ.setdefault("MUJOCO_GL", "disable")
    status = main()
    if status == 130:
        _exit_interrupted()
    # The command's clean-up has run; the interpreter's teardown would still traverse every
    # object numba's typing registries and Pinocchio built (0.15-0.3 s of CPU for a command
    # that loaded a kernel). Frozen objects are left to the process's exit.
    gc.freeze()
    sys.exit(status)


def _exit_interrupted() -> None:
    """End an interrupted command by its own SIGINT (the shell sees 130), with no teardown.

    The command's clean-up has run; the teardown would finalize what the interrupt left
    half-built (a numba compile cut short).
    """
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):  # a closed pipe: nothing more to say
            stream.flush()
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.raise_signal(signal.SIGINT)
    sys.exit(130)  # pragma: no cover - only where SIGINT's default action does not end us


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status.

    **0** achieved; **1** answered but not achieved (a limit reached, a check of the plan
    failed, a negative static or ZMP margin, infeasible forces, a budget ran out, a claim
    not computed), one line ``hexapod-kin: not achieved: ...``; **2** bad input or any
    failure, one line on stderr (``HEXAPOD_KIN_DEBUG=1`` shows an unexpected traceback);
    **130** interrupted. A closed stdout ends quietly.

    Ctrl-C is recorded as well as raised, so a library that swallows the
    ``KeyboardInterrupt`` cannot turn it into a success (a swallowed one is delivered again).
    A command started with Ctrl-C ignored (``nohup``, a script's ``cmd &``) keeps ignoring it.
    """
    interrupted: list[int] = []
    active = [True]  # False once the command is done: a late signal is only recorded
    lock = threading.Lock()

    def on_sigint(signum: int, frame: object) -> None:
        interrupted.append(signum)
        if active[0]:
            raise KeyboardInterrupt

    def deliver_again() -> None:
        with lock:
            if active[0]:
                os.kill(os.getpid(), signal.SIGINT)

    def unraisable(info: Any) -> None:  # an exception raised where Python cannot raise it
        try:
            if not isinstance(info.exc_value, KeyboardInterrupt):
                hook(info)
                return
            interrupted.append(signal.SIGINT)
        except KeyboardInterrupt:  # a Ctrl-C inside this hook (recorded by on_sigint)
            pass
        if previous is not None:
            # The interrupt was swallowed (a ctypes callback, a finalizer): deliver it again
            # once this hook has returned (a signal raised here would be handled here), so
            # that it stops the work where it can propagate. (numba's compile callback would
            # otherwise leave the compile to fail later, and the failure would be retried.)
            timer = threading.Timer(0.01, deliver_again)
            timer.daemon = True
            timer.start()

    try:  # started with Ctrl-C ignored (nohup, a script's `cmd &`): it stays ignored
        ignored = signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        previous = None if ignored else signal.signal(signal.SIGINT, on_sigint)
    except ValueError:  # not the main thread: leave signals alone
        previous = None
    hook, sys.unraisablehook = sys.unraisablehook, unraisable
    try:
        status = _main(argv, interrupted)
    except KeyboardInterrupt:  # between the handler and _main's own handler
        status = 130
        print("hexapod-kin: interrupted", file=sys.stderr)
    finally:
        with lock:
            active[0] = False
        sys.unraisablehook = hook
        if (budget := sys.modules.get("hexapod_kin._budget")) is not None:
            budget.drop()  # a child started ahead of a job that never came
        if previous is not None:
            signal.signal(signal.SIGINT, signal.SIG_IGN if _ENTRY[0] else previous)
    if interrupted and status != 130:
        print("hexapod-kin: interrupted", file=sys.stderr)
        return 130
    return status


def _not_achieved(exc: BaseException) -> bool:
    """A ``LimitError`` or the gait's ``GaitError`` (if the gait was imported): status 1."""
    from ..exceptions import LimitError

    gait = sys.modules.get("hexapod_kin.gait.robot")
    kinds: tuple[type, ...] = (LimitError,)
    if gait is not None and isinstance(getattr(gait, "GaitError", None), type):
        kinds += (gait.GaitError,)
    return isinstance(exc, kinds)


def _main(argv: Sequence[str] | None, interrupted: Sequence[int] = ()) -> int:
    """Run the command; return its status (after a Ctrl-C an error prints nothing)."""

    def error(text: str) -> int:
        if not interrupted:
            print(f"hexapod-kin: error: {text}", file=sys.stderr)
        return 2

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
        if _not_achieved(exc):  # good input; the plan reached a limit or failed a check
            if not interrupted:
                print(f"hexapod-kin: not achieved: {_one_line(exc)}", file=sys.stderr)
            return 1
        return error(_one_line(exc))
    except KeyboardInterrupt:
        print("hexapod-kin: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # stdout closed early (| head): silence the flush at exit and stop quietly
        with contextlib.suppress(OSError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as exc:
        where = f" {exc.filename!r}" if exc.filename else ""
        return error(f"{exc.strerror or exc}{where}")
    except MemoryError:
        return error("not enough memory for this request; ask for fewer samples")
    except Exception as exc:  # the last line of defence: one line, never a traceback
        if os.environ.get("HEXAPOD_KIN_DEBUG") and not interrupted:
            raise
        return error(
            f"unexpected {type(exc).__name__}: {_one_line(exc)} "
            "(a bug: please report it; HEXAPOD_KIN_DEBUG=1 shows the traceback)"
        )
