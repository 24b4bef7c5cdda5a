"""The ``hexapod-kin`` command line: ``main(argv=None) -> int``.

Subcommands live in the modules of this package, one module per area; each module has a
``register(sub)`` that declares its subcommands (``sub.add_parser``) and binds each one's
runner with ``set_defaults(func=...)``. Heavy imports stay inside the runners.
``--json`` output is one JSON object on stdout; progress and messages go to stderr.
Errors of the :class:`~hexapod_kin.exceptions.HexapodKinError` family print one line
``hexapod-kin: error: ...`` and exit with status 2; a plan that reaches a limit or fails a
check exits with 1 (the rule: :func:`main`).
"""

from __future__ import annotations

import argparse
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
    line), each distinct text once (the same warning said again by a child process, e.g. a
    cache folder that is a file, is not repeated); other warnings are shown as Python shows
    them.
    """
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


#: Set by :func:`run`: the process ends after :func:`main`, so a Ctrl-C that arrives once the
#: command is done is ignored (the status stands) instead of killing the exiting interpreter.
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
    """End an interrupted command now, by SIGINT, without the interpreter's teardown.

    When :func:`main` returns, the command's own clean-up has run (``finally`` blocks and
    context managers: temporary files, the viewer's server, the symbolic worker). The
    teardown would then finalize what the interrupt left half-built — a numba/LLVM compile
    cut short has crashed it (SIGSEGV after the line). The process ends the way POSIX asks
    an interrupted program to end, by its own SIGINT with the default action, so that the
    shell sees status 130 (``$?``; ``subprocess`` reports ``-2``) and a calling script
    stops too (CPython itself ends so after an unhandled ``KeyboardInterrupt``).
    """
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except Exception:  # noqa: BLE001 - a closed pipe: nothing more to say
            pass
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.raise_signal(signal.SIGINT)
    sys.exit(130)  # pragma: no cover - only where SIGINT's default action does not end us


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status.

    One rule for every command: **0** achieved (the answer achieves what was asked); **1**
    answered but not achieved — a check of the plan fails, infeasible, a limit reached
    (``ik``: the target is unreachable or only beyond the joint limits, the nearest point is
    printed; ``step`` and ``timeline``: a joint, speed or servo limit; ``gait``,
    ``simulate``, ``timeline gait``: a check of the plan fails, or the walk's static or ZMP
    margin is negative; ``simulate``: a physics check fails; ``stand``: the contact forces
    are not feasible; ``derive``: ``--budget`` ran out before all was derived, checked and
    printed; ``scan``: the families were not all derived within ``--family-budget``;
    ``reproduce``: a claim's computation failed) — one line ``hexapod-kin: not achieved:
    ...`` says why; **2** bad input or any failure (one line on stderr, never a traceback;
    ``HEXAPOD_KIN_DEBUG=1`` shows the traceback of an unexpected error); **130**
    interrupted. A closed stdout (``hexapod-kin fk ... | head``) ends quietly.

    Ctrl-C (SIGINT) is recorded as well as raised, so that a library that swallows the
    ``KeyboardInterrupt`` (e.g. inside an import, or where Python can only report it as
    "Exception ignored": then it is delivered again, to stop the work where it can
    propagate) cannot turn it into a success: an interrupted command ends with one line and
    status 130 (:func:`run`, the entry point, then ends the process by its own SIGINT after
    the command's clean-up, as POSIX asks of an interrupted program: the shell's ``$?`` is
    130; see :func:`_exit_interrupted`).
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

    try:
        previous = signal.signal(signal.SIGINT, on_sigint)
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
        if previous is not None:
            signal.signal(signal.SIGINT, signal.SIG_IGN if _ENTRY[0] else previous)
    if interrupted and status != 130:
        print("hexapod-kin: interrupted", file=sys.stderr)
        return 130
    return status


def _not_achieved(exc: BaseException) -> bool:
    """An error that answers "not achieved" (status 1): a limit reached, a gait check failed.

    :class:`~hexapod_kin.exceptions.LimitError`, and the gait's ``GaitError`` (looked up
    only when the gait was imported: raising one imports it).
    """
    from ..exceptions import LimitError

    gait = sys.modules.get("hexapod_kin.gait.robot")
    kinds: tuple[type, ...] = (LimitError,)
    if gait is not None and isinstance(getattr(gait, "GaitError", None), type):
        kinds += (gait.GaitError,)
    return isinstance(exc, kinds)


def _main(argv: Sequence[str] | None, interrupted: Sequence[int] = ()) -> int:
    """Run the command; return its status.

    An error that follows a Ctrl-C (``interrupted`` not empty: a library turned the
    interrupt into an error, e.g. pybind11's ``ImportError`` "initialization failed") prints
    nothing: :func:`main` prints the one line of the interrupt.
    """

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
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
        except OSError:
            pass
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
