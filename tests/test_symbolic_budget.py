"""Symbolic budgets: unfinished derivations kept, redundant chains' rank deficiency, printing.

The 5-DOF leg of ``examples/leg5.yaml`` (hip yaw, roll and pitch axes meeting at one point,
knee, foot roll about the shank): its position Jacobian (3×5) loses rank where the knee
stretches the shank in line with the femur. Every claim is checked against Pinocchio's
Jacobian by SVD. One test holds two commands on the 12-joint chain of ``tests/data`` to their
budgets in CPU time (figures: ``tools/bench_symbolic_budget.py``).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from hexapod_kin import load
from hexapod_kin.symbolic import derive

pytestmark = pytest.mark.usefixtures("own_cache_dir")

LEG5 = str(Path(__file__).resolve().parent.parent / "examples" / "leg5.yaml")


def _ratio(jac: np.ndarray) -> float:
    s = np.linalg.svd(jac, compute_uv=False)
    return float(s[-1] / s[0])


@pytest.fixture(scope="module")
def leg5():
    return load(LEG5), derive(LEG5, budget=None)


def _coxa_leg(coxa: float = 0.03):
    """The same leg with a coxa [m] between the yaw axis and the roll/pitch axes.

    (The cache is keyed by the table: each test that must derive takes its own length.)
    """
    from dataclasses import replace

    from hexapod_kin.sources import resolve_source

    chain = resolve_source(LEG5).params
    rows = list(chain.rows)
    rows[1] = replace(rows[1], r=coxa)
    return chain.replace(rows=tuple(rows), name="leg5_coxa")


def test_leg5_rank_deficiency_families_against_sigma_min(leg5):
    model, d = leg5
    assert d.complete and d.det is None and d.rows == ("x", "y", "z")
    assert "common factors of all" in d.method
    q4 = sp.Symbol("q4", real=True)
    assert [f.factor for f in d.families] == [sp.cos(q4)] * 2
    assert sorted(f.value for f in d.families) == pytest.approx([-math.pi / 2, math.pi / 2])
    rng = np.random.default_rng(5)
    lo, hi = model.lower, model.upper
    for fam in d.families:
        assert fam.verified
        on = rng.uniform(lo, hi, (20, 5))
        on[:, fam.joint] = fam.value
        # on the family: rank 2 (every 3x3 minor of Pinocchio's position Jacobian vanishes)
        assert max(_ratio(model.jacobian(q)[:3]) for q in on) < 1e-12
    off = rng.uniform(lo, hi, (200, 5))
    ratios = [_ratio(model.jacobian(q)[:3]) for q in off]
    near = np.abs(np.cos(off[:, 3]))  # distance-like to the families
    # off them: full rank, sigma_min growing with |cos q4| (no other codimension-1 family)
    assert min(r / c for r, c in zip(ratios, near)) > 1e-3


def test_leg5_gram_and_jacobians_equal_pinocchio(leg5):
    model, d = leg5
    qs = model.random_q(40, seed=11)
    gram = d.function(d.gram)(qs)
    jac = d.function(d.J_direct)(qs)
    for i, q in enumerate(qs):
        jp = model.jacobian(q)
        np.testing.assert_allclose(jac[i], jp, atol=1e-12)
        assert abs(gram[i] - np.linalg.det(jp[:3] @ jp[:3].T)) < 1e-14
    assert d.methods_agree and d.agree is True


def test_redundant_leg_without_common_factor_has_no_family():
    chain = _coxa_leg()
    d = derive(chain, budget=None)
    model = load(chain)
    assert d.complete and d.families == () and "share no factor" in d.method
    # cos(q5) divides some minors (foot roll at 90 deg) but not all: J keeps rank 3 there
    rng = np.random.default_rng(6)
    qs = rng.uniform(model.lower, model.upper, (30, 5))
    qs[:, 4] = math.pi / 2
    assert min(_ratio(model.jacobian(q)[:3]) for q in qs) > 1e-4
    qs = model.random_q(20, seed=12)
    gram = d.function(d.gram)(qs)
    for i, q in enumerate(qs):
        jp = model.jacobian(q)[:3]
        assert abs(gram[i] - np.linalg.det(jp @ jp.T)) < 1e-14


@pytest.mark.slow  # the whole derivation at the end: ~15-25 s of sympy's CPU
def test_unfinished_derivation_is_kept_and_a_larger_budget_carries_on():
    from hexapod_kin.symbolic import clear_memory

    chain = _coxa_leg(0.032)
    # a budget short enough that even an idle machine stops early (the child is killed)
    first = derive(chain, budget=0.03)
    assert first.incomplete and not first.cached
    clear_memory()  # a new process: from the disk (read within the budget, not derived)
    again = derive(chain, budget=0.03)
    assert again.cached  # not spent again
    assert [w.split(" (")[0] for w in again.incomplete] == [
        w.split(" (")[0] for w in first.incomplete
    ]
    smaller = derive(chain, budget=0.01)
    assert smaller.cached
    done = derive(chain, budget=None)  # larger: carries on from what was reached
    assert not done.cached and done.complete
    assert derive(chain, budget=0.03).complete


@pytest.mark.slow  # the whole derivation at the end: ~15-25 s of sympy's CPU
def test_scan_keeps_an_unfinished_family_derivation(monkeypatch):
    from hexapod_kin import symbolic
    from hexapod_kin.singularity import scan

    model = load(_coxa_leg(0.034))
    calls = []
    real = symbolic.derive

    def counting(*args, **kwargs):
        calls.append(kwargs.get("budget"))
        return real(*args, **kwargs)

    monkeypatch.setattr(symbolic, "derive", counting)
    first = scan(model, grid=5, family_budget=0.2)
    assert "incomplete" in first.family_reason and len(calls) == 1
    second = scan(model, grid=5, family_budget=0.2)
    assert "kept" in second.family_reason and len(calls) == 1  # not derived again
    third = scan(model, grid=5, family_budget=600.0)  # larger: tries again, finishes
    assert len(calls) == 2 and third.families == ()
    assert third.family_reason.startswith("no factor of det J")


def test_printed_derivation_is_tidy_and_within_100_columns(leg5):
    from hexapod_kin.symbolic import core

    _, d = leg5
    text = d.text()
    assert max(len(line) for line in text.splitlines()) <= 100
    assert "lengths: d4 = 0.11 m, r5 = 0.13 m, r6 = 0.02 m" in text
    assert "sin²(q1)" not in text and "cos²(q1)" not in text
    assert "(r5 + r6)" in text  # terms grouped, lengths factored
    q1, q2 = sp.symbols("q1 q2", real=True)
    d3 = sp.Symbol("d3", positive=True)
    messy = -d3 * sp.sin(q1) ** 2 * sp.cos(q2) - d3 * sp.cos(q1) ** 2 * sp.cos(q2)
    assert core.tidy(messy, (q1, q2), ("revolute", "revolute")) == -d3 * sp.cos(q2)
    q = np.array([0.3, -0.2, 0.5, 0.7, -0.4])  # the tidied forms are the same functions
    ref = core.numeric_jacobian(d.chain, q, range(6))
    np.testing.assert_allclose(d.function(d.J_direct)(q), ref, atol=1e-14)
    np.testing.assert_allclose(d.function(d.J_indirect)(q), ref[:3], atol=1e-14)


def test_cli_derive_of_the_leg_table_file(capsys):
    from hexapod_kin.cli import main

    assert main(["derive", LEG5, "--budget", "600"]) == 0
    out = capsys.readouterr().out
    assert "q4 = pi/2 (mod 2*pi)" in out and "q4 = -pi/2 (mod 2*pi)" in out
    assert "check vs Pinocchio" in out and "NOT DONE" not in out
    assert max(len(line) for line in out.splitlines()) <= 100


def test_families_only_stops_after_the_families_and_a_full_call_carries_on(monkeypatch):
    from dataclasses import replace

    from hexapod_kin import _budget, robots
    from hexapod_kin.symbolic import clear_memory

    leg = robots.hexabot_leg()
    rows = list(leg.rows)
    rows[-1] = replace(rows[-1], d=0.107)  # a table of its own (the cache is keyed by it)
    chain = leg.replace(rows=tuple(rows), name="leg_107")
    stages: list[list[str]] = []
    real = _budget.run

    def recording(job, args, budget):
        done, reason = real(job, args, budget)
        computed = [k for k in done if k != "__found__"]  # the disk cache's entry, read first
        if computed:
            stages.append(computed)
        return done, reason

    monkeypatch.setattr(_budget, "run", recording)
    part = derive(chain, budget=None, families_only=True)
    assert stages == [["kinematics", "rows", "determinant", "families", "checks"]]
    assert part.families_done and part.agree is None and len(part.families) == 3
    assert [w.split(" (")[0] for w in part.incomplete] == ["direct = indirect Jacobian, exactly"]
    clear_memory()  # a new process: from the disk, not derived again
    again = derive(chain, budget=None, families_only=True)
    assert again.cached and len(stages) == 1 and again.families == part.families
    full = derive(chain, budget=None)  # carries on: only what families_only left out
    assert stages[1] == ["agree", "tidy", "seconds"]
    assert full.complete and full.agree is True and full.families == part.families
    clear_memory()
    assert derive(chain, budget=None).cached and len(stages) == 2


@pytest.mark.slow
def test_an_entry_in_progress_answers_no_call_and_the_next_carries_on(monkeypatch):
    """A derivation running beside this one (its entry on disk after each stage) is not a stop.

    Four ``scan`` commands started together on one empty cache once read each other's
    part-written entries as budget stops and answered "incomplete" (CI, session 7).
    """
    from dataclasses import replace

    from hexapod_kin import _budget, robots
    from hexapod_kin.symbolic import cache as scache
    from hexapod_kin.symbolic import clear_memory
    from hexapod_kin.symbolic.derivation import ATTEMPT, IN_PROGRESS, _cache_key

    leg = robots.hexabot_leg()
    rows = list(leg.rows)
    rows[-1] = replace(rows[-1], d=0.109)  # a table of its own (the cache is keyed by it)
    chain = leg.replace(rows=tuple(rows), name="leg_109")
    marks: list[object] = []
    add = scache.Writer.add

    def marking(self, name, value, attempt, key):
        marks.append(attempt)
        return add(self, name, value, attempt, key)

    monkeypatch.setattr(scache.Writer, "add", marking)
    with _budget.cpu_limit(600.0):  # inside a budget: the worker runs here, its writes seen
        full = derive(chain, budget=10.0)
    assert full.complete and len(marks) == 8
    assert marks[:-1] == [(IN_PROGRESS, None)] * 7 and marks[-1] is None
    digest = _cache_key(chain, None, None)
    kept = scache.load(digest)
    assert kept is not None and ATTEMPT not in kept
    # what the worker's file holds after its first stage, while it runs on
    scache.store(digest, {"kinematics": kept["kinematics"], ATTEMPT: (IN_PROGRESS, None)})
    clear_memory()
    stages: list[list[str]] = []
    real = _budget.run

    def recording(job, args, budget):
        done, reason = real(job, args, budget)
        stages.append([k for k in done if k != "__found__"])
        return done, reason

    monkeypatch.setattr(_budget, "run", recording)
    again = derive(chain, budget=10.0)  # a budget: the part-run's entry must not answer it
    assert not again.cached and again.complete and again.families == full.families
    assert stages == [["rows", "determinant", "families", "checks", "agree", "tidy", "seconds"]]
    assert ATTEMPT not in scache.load(digest)  # the finished entry replaced it
    # a budget stop is marked by the caller once the worker has stopped
    rows[-1] = replace(rows[-1], d=0.111)
    chain = leg.replace(rows=tuple(rows), name="leg_111")
    part = derive(chain, budget=0.03)
    stored = scache.load(_cache_key(chain, None, None))
    if part.incomplete:
        assert stored[ATTEMPT] == ("budget of 0.03 s reached", 0.03)


CHAIN12 = str(Path(__file__).resolve().parent / "data" / "chain12.yaml")


def _timed_cli(argv: list[str], cache: Path) -> tuple[float, int, str]:
    """CPU time [s] (the command and its child), exit status and stdout of ``hexapod_kin ARGV``."""
    import os
    import resource
    import subprocess
    import sys

    root = Path(__file__).resolve().parent.parent
    env = {**os.environ, "HEXAPOD_KIN_CACHE_DIR": str(cache), "PYTHONPATH": str(root)}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    run = subprocess.run(
        [sys.executable, "-m", "hexapod_kin", *argv],
        env=env, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    assert "Traceback" not in run.stderr, run.stderr
    return cpu, run.returncode, run.stdout


#: CPU seconds of the start-up the budget does not count: the command's (Python, Pinocchio,
#: the model) and its one budgeted child's (Python, sympy).
STARTUP = 3.0


@pytest.mark.slow
def test_budgets_bound_the_whole_command_on_a_12_joint_chain(tmp_path):
    """``derive --budget B`` and ``scan --family-budget B`` on a chain sympy cannot finish.

    Budgets count CPU time of the work (never wall-clock time: a busy machine changes
    nothing): the derive command takes at most B of CPU time beside its start-up; the
    scan's families (reading the cache, deriving) at most B more than the same scan without
    families, plus the child's start-up. Both say what is not done and exit with 1.
    """
    budget = 2.0
    cpu, code, out = _timed_cli(["derive", CHAIN12, "--budget", f"{budget:g}"], tmp_path / "a")
    assert code == 1 and cpu <= budget + STARTUP, (cpu, code, out[-2000:])
    assert "NOT DONE: det J factored and singular families (budget of 2 s reached)" in out
    argv = ["scan", CHAIN12, "--grid", "5"]
    base, code0, _ = _timed_cli([*argv, "--families", "off"], tmp_path / "b")
    cpu, code, out = _timed_cli([*argv, "--family-budget", f"{budget:g}"], tmp_path / "b")
    assert code0 == 0 and code == 1 and cpu <= base + budget + 1.5, (base, cpu, out)
    assert "no families: derivation incomplete:" in out and "budget of 2 s reached" in out


def test_derive_command_starts_one_child(monkeypatch, capsys, tmp_path):
    """A budgeted ``derive`` runs the derivation, its printing and its check in one child
    process, a fresh interpreter (never a fork of this process)."""
    import os
    import subprocess

    from hexapod_kin.cli import main

    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(tmp_path))
    started: list[list[str]] = []
    real = subprocess.Popen

    def counting(argv, *a, **kw):
        started.append(list(argv))
        return real(argv, *a, **kw)

    def no_fork() -> int:
        raise AssertionError("a bare fork")

    monkeypatch.setattr(subprocess, "Popen", counting)
    monkeypatch.setattr(os, "fork", no_fork)
    assert main(["derive", "hexabot_leg", "--budget", "60"]) == 0
    assert len(started) == 1, started
    out = capsys.readouterr().out
    assert "det J[x,y,z] = l2·l3·(l1 + l2·cos(q2) + l3·cos(q2 + q3))·sin(q3)" in out


def test_a_prestarted_child_takes_the_next_job_or_is_ended(monkeypatch):
    """``_budget.prestart`` starts the next budgeted child ahead (its imports beside the
    caller's work): the next ``run`` sends it the job (one process in all, the job's items
    back); one that no job takes is ended by ``drop``."""
    import subprocess

    from hexapod_kin import _budget

    started: list[list[str]] = []
    real = subprocess.Popen

    def counting(argv, *a, **kw):
        started.append(list(argv))
        return real(argv, *a, **kw)

    monkeypatch.setattr(subprocess, "Popen", counting)
    _budget.prestart(("json",))
    assert _budget.run(zip, (("a", "b"), (1, 2)), 30.0) == ({"a": 1, "b": 2}, None)
    assert [argv[4:] for argv in started] == [["json"]] and not _budget._SPARE
    _budget.prestart(("json",))
    (spare,) = _budget._SPARE
    _budget.drop()
    assert spare._proc is None and not _budget._SPARE and len(started) == 2


_FIRST_SCAN = """
import json, subprocess, sys
started, real = [], subprocess.Popen
def counting(argv, *a, **kw):
    started.append(list(argv))
    return real(argv, *a, **kw)
subprocess.Popen = counting
from hexapod_kin.cli import main
status = main(["scan", "hexabot_leg", "--grid", "7"])
print(json.dumps([status, [argv[4:] for argv in started], "sympy" in sys.modules]))
"""


@pytest.mark.slow  # two fresh processes, one derivation (~5 s of CPU)
def test_a_first_scan_starts_the_family_child_as_it_starts(tmp_path):
    """A scan with no family derived yet starts the derivation's child (sympy imported there)
    as the command starts; the derivation runs in it: one child, no sympy here, the leg's
    three families. With the families on disk: no child, the same families."""
    import json
    import os
    import subprocess
    import sys

    env = dict(os.environ, HEXAPOD_KIN_CACHE_DIR=str(tmp_path))
    runs = [
        subprocess.run(
            [sys.executable, "-c", _FIRST_SCAN],
            env=env,
            capture_output=True,
            text=True,
            timeout=600,
            check=False,
        )
        for _ in range(2)  # fmt: skip
    ]
    (first, *_), (second, *_) = (r.stdout.splitlines()[::-1] for r in runs)
    ahead = ["hexapod_kin.singularity.families", "hexapod_kin.symbolic.derivation"]
    status, children, sympy_here = json.loads(first)
    assert (status, len(children), children[0][:2], sympy_here) == (0, 1, ahead, False), runs[0]
    assert json.loads(second) == [0, [], False], runs[1]
    for run in runs:
        assert "family l1 + l2*cos(q2) + l3*cos(q2 + q3) = 0" in run.stdout
        assert "family q3 = 0 (mod 2*pi)" in run.stdout and "family q3 = pi" in run.stdout


@pytest.mark.slow
def test_derive_gives_the_same_bytes_beside_eight_busy_processes(tmp_path):
    """Budgets count CPU time: ``derive`` and ``scan`` (its families derived within their
    budget) of the seeds' leg give the same output idle and with 8 busy-loop processes on the
    machine's cores (each run with fresh caches)."""
    import os
    import subprocess
    import sys

    def derive_cli(cache: Path) -> bytes:
        env = {**os.environ, "HEXAPOD_KIN_CACHE_DIR": str(cache)}
        out = b""
        for argv in (["derive", "hexabot_leg"], ["scan", "hexabot_leg", "--json"]):
            res = subprocess.run(
                [sys.executable, "-m", "hexapod_kin", *argv],
                env=env, capture_output=True, timeout=900, check=False,
            )  # fmt: skip
            assert res.returncode == 0, res.stderr.decode()[-2000:]
            out += res.stdout
        return out

    idle = derive_cli(tmp_path / "idle")
    hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(8)]
    try:
        busy = derive_cli(tmp_path / "busy")
    finally:
        for hog in hogs:
            hog.kill()
            hog.wait()
    assert busy == idle
