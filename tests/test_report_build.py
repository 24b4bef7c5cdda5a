"""The build's three processes: what a child computes equals what the parent computes alone.

``reproduce`` forks a symbolic child and a dynamics child (``report/build.py``); when a child
cannot fork, raises or dies, the parent computes the same part itself. Both ways must give
the same verdicts (status, text, computed value) and the same facts.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from hexapod_kin.report import build, replay


def _build(out: Path, monkeypatch: pytest.MonkeyPatch) -> dict:
    monkeypatch.setattr(replay, "lookup", lambda key: None)  # computed, never replayed
    rep = build.reproduce(out, quick=True, animations=False, cache=False)
    return json.loads((out / "verdicts.json").read_text()) | {"_report": rep}


def _same(a: dict, b: dict) -> None:
    keep = ("claim", "status", "verdict", "computed", "claimed")
    va = [{k: v[k] for k in keep} for v in a["verdicts"]]
    vb = [{k: v[k] for k in keep} for v in b["verdicts"]]
    assert va == vb
    _close(a["facts"], b["facts"], "facts")


def _close(x: object, y: object, where: str) -> None:
    """Equal, floats to 1e-12 relative (a kernel may run compiled in one process and
    interpreted in the other: same source, rounding may differ in the last bits)."""
    if isinstance(x, dict) and isinstance(y, dict):
        assert x.keys() == y.keys(), where
        for k in x:
            _close(x[k], y[k], f"{where}.{k}")
    elif isinstance(x, list) and isinstance(y, list):
        assert len(x) == len(y), where
        for i, (u, v) in enumerate(zip(x, y)):
            _close(u, v, f"{where}[{i}]")
    elif isinstance(x, float) and isinstance(y, float):
        assert x == pytest.approx(y, rel=1e-12, abs=1e-15), where
    else:
        assert x == y, where


@pytest.fixture(scope="module")
def forked(tmp_path_factory: pytest.TempPathFactory) -> dict:
    with pytest.MonkeyPatch.context() as mp:
        calls: list[str] = []
        real = build.Forked.__init__

        def spy(self, fn, budget=300.0):
            calls.append(fn.__name__)
            real(self, fn, budget)

        mp.setattr(build.Forked, "__init__", spy)
        data = _build(tmp_path_factory.mktemp("forked"), mp)
    assert len(calls) == 2 and "dynamics_side" in calls  # the sympy side and the dynamics
    return data


def test_no_fork_gives_the_same_report(forked, tmp_path, monkeypatch):
    monkeypatch.setattr(build.Forked, "result", lambda self: None)  # as if fork failed
    _same(_build(tmp_path, monkeypatch), forked)


def test_a_failing_child_is_redone_here(forked, tmp_path, monkeypatch):
    real = build.Forked.__init__

    def boom(self, fn, budget=300.0):
        def fail():
            raise RuntimeError("child fails")

        real(self, fail, budget)

    monkeypatch.setattr(build.Forked, "__init__", boom)
    _same(_build(tmp_path, monkeypatch), forked)
