"""The numeric half of a report build, run in a second process beside the symbolic half.

While :func:`hexapod_kin.report.reproduce` derives and checks the formulas (sympy, one
core), a child (:class:`hexapod_kin._budget.Child`: a fresh interpreter, no budget) runs the
step and the pendulum (sent back pickled as soon as done: the same bytes as in one process),
then the figures, the animations and the hexapod standing and walking. A child that cannot
start or fails: its share is done in the calling process. A Ctrl-C reaches the child once;
nothing outlives the build.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

from .._budget import Child, start

__all__ = ["NumericHalf"]


def _share(
    ctx: Any, fdir: Path, out: Path, animations: bool, walk_s: float
) -> Iterator[tuple[str, Any]]:
    """The numeric half: ``("experiments", (step, pendulum))``, then ``("figures", {...})``."""
    from ..plots import plot_motion
    from . import figures

    yield "experiments", (ctx.step, ctx.pendulum)
    title = "x-only step: v = [A sin(2πt/T), 0, 0] (seeds 000, 001, 003)"
    drawn: dict[str, Any] = {"step": plot_motion(ctx.step, fdir / "step.png", title=title)}
    if animations:
        drawn["step_still"] = figures.step_still(ctx, fdir)
        try:  # the step, animated (self-contained HTML)
            from ..viewer import export_html

            tr, title = ctx.step.trajectory, "hexabot_leg: the seeds' x-only step"
            html = export_html(ctx.model("leg"), tr.t, tr.q, out / "step.html", fps=30, title=title)
            drawn["step_animation"] = html
        except Exception as exc:  # the viewer extra missing: said in the report
            drawn["step_animation"] = f"not written: {exc}"
    drawn["walk"] = figures.walk_figures(fdir, walk_s, animations, html_dir=out)
    drawn["pendulum"] = figures.plot_pendulum(ctx.pendulum, fdir / "pendulum.png")
    yield "figures", drawn


def _job(
    quick: bool, fdir: Path, out: Path, animations: bool, walk_s: float
) -> Iterator[tuple[str, Any]]:  # pragma: no cover - runs in the child
    """The child's job (:class:`hexapod_kin._budget.Child`): the share on its own experiments."""
    from .experiments import Experiments

    yield from _share(Experiments(quick), fdir, out, animations, walk_s)


class NumericHalf:
    """The numeric half of a build in a child process (or here, if the child cannot do it).

    ``ctx``: the build's :class:`~hexapod_kin.report.checks.Context` (the child makes its own
    :class:`~.experiments.Experiments`); figures into ``fdir``, animations into ``out``;
    ``walk_s``: the hexapod's walk [s].
    """

    def __init__(self, ctx: Any, fdir: Path, out: Path, animations: bool, walk_s: float) -> None:
        self._ctx = ctx
        self._args = (fdir, out, animations, walk_s)
        self._child: Child | None = None
        self._items: Iterator[tuple[str, Any]] = iter(())
        try:
            self._child = start(_job, (ctx.quick, *self._args), None)  # prestarted, if one is
            self._items = self._child.items()
        except OSError:  # no child: its share is done here
            pass

    def _next(self, name: str) -> Any:
        """The child's item ``name``, or None if it failed (then its share is done here)."""
        for got, value in self._items:
            if got == name:
                return value
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
        """End the child (told once, then killed); idempotent."""
        child, self._child = self._child, None
        self._items = iter(())
        if child is not None:
            child.close()
