"""Run a function in a forked process and get its return value back (or None).

Used where a command has independent parts that can use a second core: ``reproduce``'s
sympy and dynamics sides, the ``step`` command's Euler baseline. The caller always has the
same computation at hand and runs it itself when :meth:`Forked.result` is None (no ``fork``
on this platform, the child raised, died or ran out of time), so results never depend on
whether the fork happened.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

__all__ = ["Forked"]


class Forked:
    """``fn()`` in a forked process; :meth:`result` is its return value (pickled back) or None.

    None when this platform cannot fork, the child raised or died, or it outlived ``budget``
    seconds (then it is killed): the caller computes the same thing itself. The child's
    output is read before it is joined (a large result would otherwise block its pipe).
    """

    def __init__(self, fn: Callable[[], Any], budget: float = 300.0) -> None:
        import multiprocessing as mp

        self.budget = budget
        self.proc: Any = None
        self.recv: Any = None
        try:
            ctx = mp.get_context("fork")
            self.recv, send = ctx.Pipe(duplex=False)
            self.proc = ctx.Process(target=self._run, args=(fn, send))
            self.proc.start()
            send.close()
        except Exception:  # noqa: BLE001 - no fork here: result() is None
            self.proc = None

    @staticmethod
    def _run(fn: Callable[[], Any], send: Any) -> None:  # pragma: no cover - in the child
        try:
            out = ("ok", fn())
        except BaseException as exc:  # noqa: BLE001 - reported as a failure, recomputed
            out = ("error", repr(exc))
        try:
            send.send(out)
        finally:
            send.close()

    def result(self) -> Any:
        """The child's return value, or None (see the class docstring)."""
        if self.proc is None:
            return None
        value = None
        try:
            if self.recv.poll(self.budget):
                status, payload = self.recv.recv()
                value = payload if status == "ok" else None
        except (EOFError, OSError):  # the child died before sending
            value = None
        self.stop(wait=value is not None)
        return value

    def stop(self, wait: bool = False) -> None:
        """End the child (kill it unless ``wait`` and it is about to exit)."""
        if self.proc is None:
            return
        self.proc.join(5.0 if wait else 0.0)
        if self.proc.is_alive():
            self.proc.kill()
            self.proc.join(5.0)
        self.recv.close()
        self.proc = None
