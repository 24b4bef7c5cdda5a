"""Budgets in CPU time: work that sympy cannot interrupt, run in one child and cut at its budget.

:func:`run` runs a job (a module-level generator function yielding ``(name, value)`` pairs)
within a budget of **CPU time of the work**, never wall-clock time, in a fresh interpreter
(job, arguments, ``sys.path`` down its stdin, items back on a pipe); its ``ITIMER_PROF``
raises :class:`BudgetReached` in the job (:func:`cpu_limit` nests): the items sent so far are
the answer; ``RLIMIT_CPU`` ends a child stuck in C code. Inside a budgeted child, or where no
child can start, the job runs inline; :func:`prestart` starts the next child early. A Ctrl-C
reaches the child once (``SIGTERM``: a ``KeyboardInterrupt`` in the job); its warnings are said
in the parent.
"""

from __future__ import annotations

import contextlib
import math
import os
import pickle
import signal
import subprocess
import sys
import time
import warnings
from collections.abc import Callable, Iterator
from typing import Any

__all__ = ["BudgetReached", "Child", "cpu_limit", "drop", "prestart", "run", "start"]

Job = Callable[..., Iterator[tuple[str, Any]]]

#: Ends (``time.process_time()``) of the CPU limits open in this process, innermost last.
_ENDS: list[float] = []
#: Seconds of CPU time after the budget at which ``RLIMIT_CPU`` ends a stuck child.
_HARD_SLACK = 3.0
#: Wall seconds a child interrupted by a Ctrl-C may take to clean up (then it is killed).
_CLEANUP = 10.0
#: A child started ahead of its job (:func:`prestart`): the next :func:`run` takes it.
_SPARE: list[Child] = []
#: The child's start: read its inputs, then serve (``python -c``; no ``__main__`` re-run).
_BOOT = (
    "import sys, pickle; sys.path[:] = pickle.load(sys.stdin.buffer); "
    "from hexapod_kin._budget import _serve; _serve()"
)


class BudgetReached(BaseException):  # noqa: N818 - a control-flow signal, like KeyboardInterrupt
    """The CPU time of a :func:`cpu_limit` block is spent.

    A ``BaseException``: no ``except Exception`` in the work swallows it.
    """


def _expired(signum: int, frame: Any) -> None:
    raise BudgetReached


def _arm(end: float) -> None:
    left = end - time.process_time()
    if left <= 0:
        raise BudgetReached
    signal.setitimer(signal.ITIMER_PROF, left)


@contextlib.contextmanager
def cpu_limit(seconds: float) -> Iterator[None]:
    """Raise :class:`BudgetReached` in the block after ``seconds`` of this process's CPU time.

    Nested: the tightest end applies; leaving an inner block re-arms the outer one. Main
    thread only (signals); elsewhere the block runs unbounded.
    """
    import threading

    if (
        not hasattr(signal, "setitimer")
        or threading.current_thread() is not threading.main_thread()
    ):
        yield
        return
    end = time.process_time() + max(0.0, seconds)
    if _ENDS:
        end = min(end, _ENDS[-1])
    _ENDS.append(end)
    old = signal.signal(signal.SIGPROF, _expired)
    try:
        _arm(end)
        yield
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
        _ENDS.pop()
        signal.signal(signal.SIGPROF, old)
        if _ENDS:
            _arm(_ENDS[-1])


def _inline(job: Job, args: tuple[Any, ...], budget: float) -> tuple[dict[str, Any], str | None]:
    done: dict[str, Any] = {}
    end = time.process_time() + budget
    try:
        with cpu_limit(budget):
            for name, value in job(*args):
                done[name] = value
                if time.process_time() > end:  # no CPU timer (another platform, thread)
                    raise BudgetReached
    except BudgetReached:
        if _ENDS and time.process_time() >= _ENDS[-1]:
            raise  # the enclosing budget is spent too: its caller answers
        return done, f"budget of {budget:g} s reached"
    return done, None


def prestart(modules: tuple[str, ...]) -> None:
    """Start the next child now (it imports ``modules`` meanwhile); unused, :func:`drop` ends it."""
    if not (_SPARE or _ENDS or not hasattr(signal, "setitimer")):
        with contextlib.suppress(OSError):
            _SPARE.append(Child(None, modules, None))


def start(job: Job, args: tuple[Any, ...], budget: float | None) -> Child:
    """A :class:`Child` of ``job(*args)``: the prestarted one if it takes the job, else new."""
    spare = _SPARE.pop() if _SPARE else None
    return spare if spare and spare.send(job, args, budget) else Child(job, args, budget)


def drop() -> None:
    """End the child of :func:`prestart` if no job took it."""
    while _SPARE:
        _SPARE.pop().close(wait=0.0)


def run(job: Job, args: tuple[Any, ...], budget: float | None) -> tuple[dict[str, Any], str | None]:
    """Run ``job(*args)`` within ``budget`` seconds of CPU time (see the module docstring).

    ``job``: a module-level generator function yielding picklable ``(name, value)`` pairs;
    ``args``: picklable; ``budget``: CPU seconds, or ``None``: no limit, run here.

    Returns:
        ``(items by name, None)``, or the items yielded before it stopped and why
        (``"budget of 5 s reached"``, or the job's error).

    """
    if budget is None:
        return dict(job(*args)), None
    if budget <= 0:
        return {}, f"budget of {budget:g} s reached"
    if _ENDS or not hasattr(signal, "setitimer"):
        return _inline(job, args, budget)
    try:
        child = start(job, args, budget)
    except OSError:
        return _inline(job, args, budget)
    try:
        done = dict(child.items())
    except KeyboardInterrupt:  # the child ignores Ctrl-C: told once, it cleans up as after one
        child.close()
        raise
    finally:
        child.close(wait=0.0)
    return done, child.reason


class Child:
    """``job(*args)`` in a fresh interpreter (:func:`run`'s child; ``budget`` None: no limit).

    ``job`` None: the child imports the modules named by ``args`` and waits for :meth:`send`.
    Raises :class:`OSError` when no child can be started.
    """

    def __init__(self, job: Job | None, args: tuple[Any, ...], budget: float | None) -> None:
        self._budget = budget
        #: Why the job stopped early (None: it finished; see :func:`run`).
        self.reason: str | None = "the budgeted process ended unexpectedly"
        read, write = os.pipe()
        # SIGINT blocked for the child's start-up (the mask survives exec) until _serve
        # ignores it: a Ctrl-C to the process group is never a traceback of the child's.
        held = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            self._proc: subprocess.Popen[bytes] | None = subprocess.Popen(  # noqa: S603
                # this interpreter, our bootstrap (and the modules to import ahead of a job)
                [sys.executable, "-c", _BOOT, str(write), *(args if job is None else ())],
                stdin=subprocess.PIPE,
                pass_fds=(write,),
                close_fds=True,
            )
        except OSError:
            os.close(read)
            os.close(write)
            raise
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, held)
        os.close(write)
        self._items: Any = os.fdopen(read, "rb")
        try:
            assert self._proc.stdin is not None
            pickle.dump(list(sys.path), self._proc.stdin)
            self._proc.stdin.flush()
            if job is not None:
                self.send(job, args, budget)
        except OSError:  # gone already: no items
            self.close(wait=0.0)

    def send(self, job: Job, args: tuple[Any, ...], budget: float | None) -> bool:
        """Give the child its job; False (then it is ended) when it cannot take it."""
        proc, self._budget = self._proc, budget
        try:
            with proc.stdin as stdin:  # type: ignore[union-attr]
                pickle.dump((job, args, budget), stdin)
        except (OSError, ValueError, AttributeError):  # gone already: no items
            self.close(wait=0.0)
            return False
        return True

    def items(self) -> Iterator[tuple[str, Any]]:
        """The job's ``(name, value)`` items until it ends (its warnings said here, once)."""
        while self._items is not None:
            try:
                name, value = pickle.load(self._items)
            except (EOFError, OSError, pickle.UnpicklingError):
                return
            if name == "__done__":
                self.reason = None
                return
            if name == "__warning__":  # said in the child: said here, once
                warnings.warn(value[1], value[0], stacklevel=3)
                continue
            if name in ("__budget__", "__error__"):
                spent = f"budget of {self._budget:g} s reached"
                self.reason = spent if name == "__budget__" else value
                return
            yield name, value

    def close(self, wait: float = _CLEANUP) -> None:
        """End the child: told once (``SIGTERM``), killed after ``wait`` s; idempotent."""
        proc, self._proc = self._proc, None
        items, self._items = self._items, None
        if proc is not None:
            if proc.poll() is None and wait > 0:
                with contextlib.suppress(OSError):
                    proc.send_signal(signal.SIGTERM)
                with contextlib.suppress(subprocess.TimeoutExpired):
                    proc.wait(wait)
            if proc.poll() is None:
                proc.kill()
            proc.wait()
            if proc.returncode == -getattr(signal, "SIGXCPU", -1):
                self.reason = f"budget of {self._budget:g} s reached"
        if items is not None:
            items.close()


def _interrupted(signum: int, frame: Any) -> None:  # pragma: no cover - in the child
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    raise KeyboardInterrupt


def _serve() -> None:  # pragma: no cover - runs in the child
    """The child: read the job, run it under its budget, send each item as it comes."""
    import resource

    out = os.fdopen(int(sys.argv[1]), "wb")
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a Ctrl-C reaches it once, from the parent:
    signal.signal(signal.SIGTERM, _interrupted)  # as a KeyboardInterrupt in the job
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})  # blocked by the parent
    prof = {signal.SIGPROF}

    def send(item: tuple[str, Any]) -> None:
        signal.pthread_sigmask(signal.SIG_BLOCK, prof)  # never cut a message in two
        try:
            pickle.dump(item, out)
            out.flush()
        finally:
            signal.pthread_sigmask(signal.SIG_UNBLOCK, prof)

    def forward(message: Any, category: Any, *rest: Any, **kw: Any) -> None:
        send(("__warning__", (category, str(message))))

    warnings.showwarning = forward
    try:
        for name in sys.argv[2:]:  # a prestarted child's imports, ahead of its job
            with contextlib.suppress(Exception):
                __import__(name)
        # unpickling imports the job's modules: told to stop meanwhile, the child ends quietly
        job, args, budget = pickle.load(sys.stdin.buffer)
        if budget is not None:
            hard = math.ceil(time.process_time() + budget + _HARD_SLACK)
            with contextlib.suppress(ValueError, OSError):
                resource.setrlimit(resource.RLIMIT_CPU, (hard, hard + 1))
        try:
            with contextlib.nullcontext() if budget is None else cpu_limit(budget):
                for item in job(*args):
                    send(item)
            send(("__done__", None))
        except BudgetReached:
            send(("__budget__", None))
        except BaseException as exc:  # noqa: BLE001 - report, never hang the parent
            send(("__error__", f"{type(exc).__name__}: {exc}"))
    except BaseException:  # noqa: BLE001, S110 - told to stop, the parent gone, a send cut
        pass
    finally:
        with contextlib.suppress(OSError):
            out.close()
