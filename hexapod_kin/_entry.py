"""The ``hexapod-kin`` console entry point: Ctrl-C is the program's from its first statement.

The console script (``[project.scripts]``) calls :func:`run`. Its first statement installs a
SIGINT handler, before the command line and its imports (argparse, numpy, Pinocchio: a few
hundred milliseconds) are loaded: a Ctrl-C in that time prints ``hexapod-kin: interrupted``
and ends the process by its own SIGINT (the shell sees 130), never Python's traceback. The
command line's :func:`hexapod_kin.cli.main` then replaces the handler with its own.

Only the program does this: importing :mod:`hexapod_kin` (a library user) leaves SIGINT as
it is. This module imports nothing but ``os``, ``signal`` and ``sys`` (loaded by the
interpreter already), so that the handler comes as early as a package module can: what
remains before it is the interpreter's own start-up and the package's ``__init__`` (its
version and exceptions).
"""

from __future__ import annotations

import os
import signal

__all__ = ["run"]


def _interrupted(signum: int, frame: object) -> None:
    """Ctrl-C while the command line loads: one line, then end by SIGINT (status 130)."""
    try:
        os.write(2, b"hexapod-kin: interrupted\n")
    except OSError:  # stderr closed: nothing more to say
        pass
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    os.kill(os.getpid(), signal.SIGINT)


def run() -> None:
    """The ``hexapod-kin`` command: :func:`hexapod_kin.cli.run` with Ctrl-C handled at once.

    A command started with Ctrl-C ignored (``nohup``, a script's ``cmd &``) keeps ignoring it.
    """
    if signal.getsignal(signal.SIGINT) is not signal.SIG_IGN:
        signal.signal(signal.SIGINT, _interrupted)
    from .cli import run as cli_run

    cli_run()
