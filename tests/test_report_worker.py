"""The report's numeric half (:mod:`hexapod_kin.report._worker`): a child process or, when the
child fails, the calling process; the same experiments and the same figure bytes either way."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from hexapod_kin import _budget
from hexapod_kin.report import _worker
from hexapod_kin.report.experiments import Experiments


def _half(tmp: Path) -> tuple[Experiments, dict, Path, bool]:
    ctx = Experiments(quick=True)
    fdir = tmp / "figures"
    fdir.mkdir(parents=True)
    half = _worker.NumericHalf(ctx, fdir, tmp, False, 0.5)
    try:
        half.experiments()
        sent = "step" in vars(ctx) and "pendulum" in vars(ctx)  # from the child
        drawn = half.figures()
    finally:
        half.close()
    return ctx, drawn, fdir, sent


@pytest.mark.slow
def test_child_and_calling_process_give_the_same_experiments_and_figures(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    child_ctx, child_drawn, child_dir, sent = _half(tmp_path / "child")
    assert sent
    with monkeypatch.context() as mp:  # a child that fails at once: all of it done here
        mp.setattr(_budget, "_BOOT", "import sys; sys.exit(3)")
        here_ctx, here_drawn, here_dir, sent = _half(tmp_path / "here")
    assert not sent
    a, b = child_ctx.step.trajectory, here_ctx.step.trajectory
    assert np.array_equal(a.q, b.q) and np.array_equal(a.t, b.t)
    assert child_ctx.step.to_dict() == here_ctx.step.to_dict()
    assert child_ctx.pendulum.to_dict() == here_ctx.pendulum.to_dict()
    names = sorted(p.name for p in child_dir.iterdir())
    assert names == sorted(p.name for p in here_dir.iterdir())
    assert {"step.png", "pendulum.png", "walk.png"} <= set(names)
    for name in names:
        assert (child_dir / name).read_bytes() == (here_dir / name).read_bytes(), name
    assert child_drawn["walk"][1] == here_drawn["walk"][1]  # the walk's facts
    assert child_drawn["step"].name == "step.png" and here_drawn["step"].parent == here_dir
