"""``_fork.Forked``: a part of a command on another core, its result equal to computing it here."""

from __future__ import annotations

import json

import pytest

from hexapod_kin import _fork, seeds
from hexapod_kin.cli import main


def test_result_comes_back_or_none():
    assert _fork.Forked(lambda: {"a": [1, 2.5]}).result() == {"a": [1, 2.5]}
    assert _fork.Forked(lambda: 1 / 0).result() is None  # the child raised: caller redoes it
    big = _fork.Forked(lambda: list(range(200_000)))  # more than a pipe buffer
    assert big.result() == list(range(200_000))


def _step_json(capsys, *extra: str) -> dict:
    assert main(["step", "hexabot_leg", "--duration", "2", "--json", *extra]) == 0
    return json.loads(capsys.readouterr().out)


@pytest.mark.parametrize("forks", [True, False])
def test_step_baseline_equals_the_api(forks, capsys, monkeypatch):
    """The command's Euler baseline (forked, or redone here) is the API's, number for number."""
    if not forks:
        monkeypatch.setattr(_fork.Forked, "result", lambda self: None)
    got = _step_json(capsys)
    api = seeds.seed_experiment(duration=2.0)
    assert got["baseline_euler_solve"] == api.baseline
    assert got["baseline_euler_solve"]["drift_z"] > 1e-7  # the open loop drifts (seeds' method)
    assert got["drift_z"] == api.drift_z


def test_step_singular_start_reports_the_baseline_failure(capsys):
    got = _step_json(capsys, "--q", "0", "0", "0")
    assert "singular" in got["baseline_failure"]
