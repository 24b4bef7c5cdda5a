"""The numeric half of a report build, run in a second process beside the symbolic half.

:func:`hexapod_kin.report.reproduce` derives and checks the seeds' formulas (sympy, pure
Python: one core) while a child process runs the experiments that need no sympy: the seeds'
x-only step and the pendulum, sent back as soon as they are done (the checks compare
claims with them), then their figures, the step's still frame and animation, and the
hexapod standing and walking. Each result is computed once, by the same calls as in one
process; the experiments come back pickled (numpy arrays exactly), so the report has the
same bytes either way.

The child is a fresh interpreter (``subprocess``: never a ``fork`` of a process holding
Pinocchio or threads), told its work on stdin, answering on a pipe of its own. A child that
cannot start or fails: its share is done in the calling process, one part after the other
(an error is then raised there, as in one process). A Ctrl-C reaches the child once, from
the parent (``SIGTERM``, raised in the child as a ``KeyboardInterrupt``, so that its atomic
writes clean up); nothing outlives the build.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import signal
import subprocess
import sys
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

__all__ = ["NumericHalf"]

#: The child's start: read its inputs, then serve (``python -c``; no ``__main__`` re-run).
_BOOT = (
    "import sys, pickle; sys.path[:] = pickle.load(sys.stdin.buffer); "
    "from hexapod_kin.report._worker import _serve; _serve()"
)
#: Wall seconds an interrupted child may take to clean up (then it is killed).
_CLEANUP = 10.0


def _share(
    ctx: Any, fdir: Path, out: Path, animations: bool, walk_s: float
) -> Iterator[tuple[str, Any]]:
    """The numeric half: ``("experiments", (step, pendulum))``, then ``("figures", {...})``."""
    from . import figures

    yield "experiments", (ctx.step, ctx.pendulum)
    drawn: dict[str, Any] = {"step": figures.step_figure(ctx, fdir)}
    if animations:
        drawn["step_still"] = figures.step_still(ctx, fdir)
        try:
            drawn["step_animation"] = figures.step_animation(ctx, out)
        except Exception as exc:  # the viewer extra missing: said in the report
            drawn["step_animation"] = f"not written: {exc}"
    drawn["walk"] = figures.walk_figures(fdir, walk_s, animations, html_dir=out)
    drawn["pendulum"] = figures.pendulum_figure(ctx, fdir)
    yield "figures", drawn


class NumericHalf:
    """The numeric half of a build in a child process (or here, if the child cannot do it).

    Args:
        ctx: The build's :class:`~hexapod_kin.report.checks.Context` (the child makes its
            own :class:`~.experiments.Experiments` with the same ``quick``).
        fdir: The figures' folder.
        out: The report's folder (the animations).
        animations: Whether the step and walk animations are written.
        walk_s: Duration of the hexapod's walk in [s].

    """

    def __init__(self, ctx: Any, fdir: Path, out: Path, animations: bool, walk_s: float) -> None:
        self._ctx = ctx
        self._args = (fdir, out, animations, walk_s)
        self._proc: subprocess.Popen[bytes] | None = None
        self._items: Any = None
        read, write = os.pipe()
        try:
            self._proc = subprocess.Popen(  # noqa: S603 - this interpreter, our own bootstrap
                [sys.executable, "-c", _BOOT, str(write)],
                stdin=subprocess.PIPE,
                pass_fds=(write,),
                close_fds=True,
            )
        except OSError:
            os.close(read)
            os.close(write)
            return
        os.close(write)
        self._items = os.fdopen(read, "rb")
        try:
            assert self._proc.stdin is not None
            with self._proc.stdin:
                pickle.dump(list(sys.path), self._proc.stdin)
                pickle.dump((ctx.quick, *self._args), self._proc.stdin)
        except OSError:  # the child is gone: its share is done here
            self.close()

    def _next(self, name: str) -> Any:
        """The child's item ``name`` (its warnings said here), or None if it failed."""
        if self._items is None:
            return None
        while True:
            try:
                got, value = pickle.load(self._items)
            except Exception:  # noqa: BLE001 - a child that ended: its share is done here
                self.close()
                return None
            if got == "__warning__":  # said in the child: said here, once
                warnings.warn(value[1], value[0], stacklevel=3)
            elif got == name:
                return value
            else:  # "__error__": the share is done here, the error raised here
                self.close()
                return None

    def experiments(self) -> None:
        """The step and the pendulum in the context (from the child, else computed here)."""
        got = self._next("experiments")
        if got is not None:
            self._ctx.__dict__["step"], self._ctx.__dict__["pendulum"] = got

    def figures(self) -> dict[str, Any]:
        """The numeric half's figures, animations and facts (from the child, else made here)."""
        got = self._next("figures")
        if got is None:
            shared = _share(self._ctx, *self._args)
            next(shared)  # the experiments: the context's own (computed, or from the child)
            got = next(shared)[1]
        self.close()
        return dict(got)

    def close(self) -> None:
        """End the child (told once, then killed after :data:`_CLEANUP` s); idempotent."""
        proc, self._proc = self._proc, None
        items, self._items = self._items, None
        if proc is not None and proc.poll() is None:
            with contextlib.suppress(OSError):
                proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(_CLEANUP)
            except subprocess.TimeoutExpired:
                proc.kill()
        if proc is not None:
            proc.wait()
        if items is not None:
            items.close()


def _interrupted(signum: int, frame: Any) -> None:  # pragma: no cover - in the child
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    raise KeyboardInterrupt


def _serve() -> None:  # pragma: no cover - runs in the child
    """The child: read the work, send each item as it comes; quiet on any failure."""
    from .experiments import Experiments

    out = os.fdopen(int(sys.argv[1]), "wb")
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a Ctrl-C reaches it once, from the parent:
    signal.signal(signal.SIGTERM, _interrupted)  # as a KeyboardInterrupt in the work

    def send(item: tuple[str, Any]) -> None:
        pickle.dump(item, out)
        out.flush()

    def forward(message: Any, category: Any, *rest: Any, **kw: Any) -> None:
        send(("__warning__", (category, str(message))))

    warnings.showwarning = forward
    try:
        quick, fdir, folder, animations, walk_s = pickle.load(sys.stdin.buffer)
        for item in _share(Experiments(quick), fdir, folder, animations, walk_s):
            send(item)
    except BaseException as exc:  # noqa: BLE001 - the parent does the share itself
        with contextlib.suppress(BaseException):
            send(("__error__", f"{type(exc).__name__}: {exc}"))
        os._exit(1)
    with contextlib.suppress(BaseException):
        out.close()
