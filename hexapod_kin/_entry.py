"""The ``hexapod-kin`` console entry point: Ctrl-C is the program's from its first statement.

:func:`run` installs a SIGINT handler before the command line's imports load (then one line,
``hexapod-kin: interrupted``, status 130, never a traceback). Importing :mod:`hexapod_kin`
leaves SIGINT as it is; this module imports only what the interpreter has loaded already.
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
