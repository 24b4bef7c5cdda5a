"""Tiered kernels (hexapod_kin._tier): both tiers give the same numbers; the rule picks right."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import hexapod_kin as hk
from hexapod_kin import _tier
from hexapod_kin.exceptions import ParameterError


@_tier.njit(cache=False, compile_s=0.5)
def _inner(x: np.ndarray, i: int) -> float:  # pragma: no cover - also compiled
    return x[i] * 2.0


@_tier.njit(cache=False, work=lambda x, reps: x.size * reps, per_unit_s=1e-6, compile_s=0.5)
def _outer(x: np.ndarray, reps: int) -> float:  # pragma: no cover - also compiled
    s = 0.0
    for _ in range(reps):
        for i in range(x.shape[0]):
            s += _inner(x, i)
    return s


@_tier.njit(cache=False, compile_s=0.5)
def _lone(x: np.ndarray, i: int) -> float:  # pragma: no cover - also compiled
    return x[i] * 2.0 + 0.0


def _fresh(kernel: _tier.Kernel) -> None:
    """Forget what the rule learned (the dispatchers of these test kernels are never cached)."""
    kernel._ready = kernel._fast = False
    kernel._spent = 0.0


def test_small_call_interpreted_big_call_compiled(jit_auto):
    x = np.arange(10.0)
    for k in (_outer, _inner):
        _fresh(k)
    if _outer.dispatcher.signatures:
        pytest.skip("compiled by an earlier test in this process")
    assert _outer(x, 3) == pytest.approx(3 * 2 * x.sum(), rel=0, abs=0)
    # interpreted: the caller and its callee ran as Python, nothing compiled
    assert not _outer.dispatcher.signatures and not _inner.dispatcher.signatures
    assert 0.0 < _outer._spent < 0.5
    # predicted 1e6 units x ~1e-6 s > 0.5 s budget: compiles (callee compiled with it)
    assert _outer(x, 100_000) == pytest.approx(100_000 * 2 * x.sum(), rel=1e-12)
    assert _outer.dispatcher.signatures and _outer.ready()
    # from now on compiled: the fast path, even for a small call
    assert _outer(x, 1) == 2 * x.sum() and _outer._fast


def test_budget_spent_then_compiled(jit_auto):
    """Ski rental: interpreted calls until their seconds reach the budget, then compiled."""
    x = np.arange(50.0)
    _fresh(_lone)
    if _lone.dispatcher.signatures:
        pytest.skip("compiled by an earlier test in this process")
    _lone.compile_s = 0.02
    try:
        calls = 0
        while not _lone.dispatcher.signatures and calls < 100_000:
            assert _lone(x, calls % 50) == 2.0 * (calls % 50)
            calls += 1
        assert _lone.dispatcher.signatures, "never compiled"
        assert calls > 1 and _lone._spent <= 0.02 + 0.05  # at most one call past the budget
    finally:
        _lone.compile_s = 0.5


def test_modes_and_bad_mode():
    before = _tier.set_mode("never")
    try:
        assert _tier.mode() == "never"
        x = np.arange(4.0)
        assert _outer(x, 2) == 2 * 2 * x.sum()
        with pytest.raises(ParameterError, match="jit mode 'fast' is not allowed"):
            _tier.set_mode("fast")
        assert _tier.mode() == "never"
    finally:
        _tier.set_mode(before)
    assert _tier.interpreted(_outer) is _outer.interpreted()
    assert _tier.compiled(_outer) is _outer.dispatcher


# -- the same numbers from both tiers -----------------------------------------------------------


def _both(fn):
    out = []
    for mode in ("always", "never"):
        before = _tier.set_mode(mode)
        try:
            out.append(fn())
        finally:
            _tier.set_mode(before)
    return out


@pytest.mark.parametrize(
    ("source", "target"),
    [
        ("hexabot_leg", [0.12, 0.06, -0.12]),
        ("hexabot_leg", [0.5, 0.1, 0.0]),  # unreachable: nearest point, local-minimum check
        ("erd:ur5_robot", None),
    ],
)
def test_ik_same_in_both_tiers(source, target):
    model = hk.load(source)
    if target is None:
        target = model.fk(np.array([0.3, -0.8, 1.1, -0.4, 0.6, 0.2]))
    a, b = _both(lambda: hk.ik.solve(model, target))
    assert a.status == b.status and a.iterations == b.iterations and a.attempts == b.attempts
    assert np.abs(a.q - b.q).max() <= 1e-12
    assert abs(a.error - b.error) <= 1e-12


def test_resolved_rate_same_in_both_tiers():
    leg = hk.load("hexabot_leg")
    a, b = _both(lambda: hk.motion.resolved_rate(leg, [0.02, 0.0, 0.0], [0, 0.3, 1.2], 2e-3, 0.4))
    assert np.abs(a.q - b.q).max() <= 1e-12
    ur5 = hk.load("erd:ur5_robot")
    twist = [0.0, 0.01, 0.02, 0.1, 0.0, 0.05]
    q0 = np.array([0.3, -0.8, 1.1, -0.4, 0.6, 0.2])
    a, b = _both(lambda: hk.motion.resolved_rate(ur5, twist, q0, 5e-3, 0.2, frame="tip"))
    assert np.abs(a.q - b.q).max() <= 1e-12


def test_measures_same_in_both_tiers():
    """The compiled fused kernel against the cold path (Pinocchio Jacobians + numpy SVD)."""
    for source in ("hexabot_leg", "scara", "erd:ur5_robot"):
        model = hk.load(source)
        qs = model.random_q(300, seed=7)
        a, b = _both(lambda model=model, qs=qs: hk.singularity.measures_batch(model, qs))
        scale = float(np.abs(a.manipulability).max())
        assert np.allclose(a.sigma_min, b.sigma_min, rtol=1e-9, atol=1e-12)
        assert np.allclose(a.manipulability, b.manipulability, rtol=1e-9, atol=1e-12 * scale)
        assert np.allclose(a.det, b.det, rtol=1e-9, atol=1e-12 * scale, equal_nan=True)


def test_closed_form_batch_same_in_both_tiers():
    leg = hk.load("hexabot_leg")
    qs = leg.random_q(200, seed=3)
    targets = np.array([leg.fk(q)[:3, 3] for q in qs])
    a, b = _both(lambda: hk.ik.analytic_batch(leg, targets))
    assert np.array_equal(a.valid, b.valid) and a.valid.any()
    assert np.abs(a.q[a.valid] - b.q[b.valid]).max() <= 1e-12


# -- a fresh install: nothing compiled, small calls answer interpreted ---------------------------

_PROBE = r"""
import json, sys, numpy as np
import hexapod_kin as hk
from hexapod_kin import _numerics, _tier
from hexapod_kin.ik import step
from hexapod_kin.singularity import _kernel
what = sys.argv[1]
if what == "compile":
    _numerics.wrap_angle(7.0)
    print(json.dumps({"compiled": bool(_numerics.wrap_angle.dispatcher.signatures)}))
elif what == "ready":
    k = _numerics.wrap_angle
    ready = k.ready()
    k(7.0)  # tiny: interpreted while numba has not started in this process, even if cached
    first = bool(k.dispatcher.signatures)
    k._spent_here = _tier.CONTEXT_S  # this process has spent numba's start-up interpreting
    k(7.0)
    hits = sum(k.dispatcher.stats.cache_hits.values())
    print(json.dumps({"ready": ready, "first_compiled": first, "cache_hits": hits}))
else:
    leg = hk.load("hexabot_leg")
    r = hk.ik.solve(leg, [0.5, 0.1, 0.0])
    m = hk.singularity.measures_batch(leg, leg.random_q(2000, seed=1))
    print(json.dumps({
        "status": r.status,
        "lm_compiled": bool(step.lm_loop.dispatcher.signatures),
        "scan_compiled": bool(_kernel.measures_kernel.dispatcher.signatures),
        "finite": bool(np.isfinite(m.sigma_min).all()),
    }))
"""


def _probe(tmp_path, what, mode):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"), HEXAPOD_KIN_JIT=mode)
    env["HEXAPOD_KIN_CACHE_DIR"] = str(tmp_path / "hk")
    res = subprocess.run(
        [sys.executable, "-c", _PROBE, what], env=env, capture_output=True, text=True, timeout=300
    )
    assert res.returncode == 0, res.stderr[-2000:]
    return json.loads(res.stdout.strip().splitlines()[-1])


def test_fresh_install_small_calls_compile_nothing(tmp_path):
    got = _probe(tmp_path, "work", "auto")
    assert got == {
        "status": "unreachable",
        "lm_compiled": False,
        "scan_compiled": False,
        "finite": True,
    }


def test_cached_machine_code_is_used(tmp_path):
    before = _probe(tmp_path, "ready", "auto")
    assert before["ready"] is False and before["cache_hits"] == 0
    assert _probe(tmp_path, "compile", "always") == {"compiled": True}
    after = _probe(tmp_path, "ready", "auto")
    assert after == {"ready": True, "first_compiled": False, "cache_hits": 1}


def test_precompile_fills_the_disk_cache(tmp_path):
    from hexapod_kin.precompile import precompile

    with pytest.raises(ParameterError, match="areas=.scans. is not allowed"):
        precompile(["scans"])
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"), HEXAPOD_KIN_JIT="auto")
    probe = (
        "import json; from hexapod_kin.motion import _kernel as k; "
        "print(json.dumps([k._rr3.ready(), k._rr6.ready()]))"
    )

    def ready():
        res = subprocess.run(
            [sys.executable, "-c", probe], env=env, capture_output=True, text=True, timeout=120
        )
        return json.loads(res.stdout)

    assert ready() == [False, False]
    cli = [sys.executable, "-m", "hexapod_kin", "precompile", "--only", "motion", "--json"]
    res = subprocess.run(cli, env=env, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr[-2000:]
    assert set(json.loads(res.stdout)["seconds"]) == {"motion"}
    assert ready() == [True, True]


@_tier.njit(cache=False)
def _domain(x: float) -> float:  # pragma: no cover - also compiled
    return math.sqrt(x) + math.acos(1.0 + x * x)


def test_interpreted_math_has_compiled_semantics():
    """Out of domain: NaN as compiled code gives (Python's math would raise)."""
    for mode in ("never", "always"):
        before = _tier.set_mode(mode)
        try:
            assert math.isnan(_domain(-1e-18)), mode
        finally:
            _tier.set_mode(before)


_LEDGER_PROBE = r"""
import json, sys
import hexapod_kin as hk
from hexapod_kin import _tier
from hexapod_kin.motion import _kernel as k
if sys.argv[1] == "spend":
    hk.motion.resolved_rate(hk.load("hexabot_leg"), [0.01, 0, 0], [0, 0.3, 1.2], 1e-3, 0.2)
    print(json.dumps({"compiled": bool(k._rr3.dispatcher.signatures)}))
else:
    before = _tier._ledger().get(_tier._ledger_key(k._rr3), 0.0)
    ask = k._rr3.compile_s - 0.5 * float(sys.argv[2])
    print(json.dumps({"before": before, "interpret": k._rr3.prefer_interpreted(ask)}))
"""


def test_interpreted_seconds_carry_over_between_processes(tmp_path):
    """A command run again and again compiles once its interpreted seconds reach the budget."""

    def run(cache, *args):
        env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"), HEXAPOD_KIN_JIT="auto")
        env["HEXAPOD_KIN_CACHE_DIR"] = str(tmp_path / cache)
        res = subprocess.run(
            [sys.executable, "-c", _LEDGER_PROBE, *args],
            env=env,
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert res.returncode == 0, res.stderr[-2000:]
        return json.loads(res.stdout.strip().splitlines()[-1])

    assert run("a", "spend") == {"compiled": False}
    got = run("a", "decide", "0")
    spent = got["before"]
    assert spent > 0.0
    # what fits the budget in a fresh cache folder does not once this folder's seconds count
    assert run("a", "decide", str(spent))["interpret"] is False
    assert run("fresh", "decide", str(spent)) == {"before": 0.0, "interpret": True}


_READY_PROBE = r"""
import json
from hexapod_kin import _tier
from hexapod_kin.motion import _kernel as k
print(json.dumps({"ready": [k._rr3.ready(), k._rr6.ready()], "bg": _tier.background_running()}))
"""


def test_a_command_leaves_a_background_compile_for_the_next(tmp_path):
    """A 10-s step on a fresh install runs interpreted, then its kernels compile behind it."""
    import time

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"), HEXAPOD_KIN_JIT="auto")
    env["HEXAPOD_KIN_CACHE_DIR"] = str(tmp_path / "hk")
    env.pop("HEXAPOD_KIN_BACKGROUND")  # as a user's shell: the command line turns it on

    def probe() -> dict:
        res = subprocess.run(
            [sys.executable, "-c", _READY_PROBE], env=env, capture_output=True, text=True
        )
        assert res.returncode == 0, res.stderr[-2000:]
        return json.loads(res.stdout.strip().splitlines()[-1])

    assert probe()["ready"] == [False, False]
    res = subprocess.run(
        [sys.executable, "-m", "hexapod_kin", "step", "hexabot_leg", "--no-baseline"],
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert res.returncode == 0, res.stderr
    lock = tmp_path / "hk" / "tier" / "background-compile.json"
    assert json.loads(lock.read_text())["areas"] == ["motion"]
    end = time.monotonic() + 280
    while lock.exists() and time.monotonic() < end:
        time.sleep(0.5)
    assert not lock.exists()  # the background compile ended and removed its lock
    assert probe() == {"ready": [True, True], "bg": False}  # machine code for both loops


def test_no_foreground_compile_while_a_background_one_runs(tmp_path, monkeypatch, jit_auto):
    import time

    def twice(x):
        return 2.0 * x

    twice.__module__ = "hexapod_kin.motion._probe"  # an area's kernel (motion)
    monkeypatch.setattr(_tier, "_all", list(_tier._all))  # keep the probes out of the list
    kernel = _tier.njit(twice, compile_s=0.5)  # a fresh kernel: never compiled, not cached
    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(tmp_path))
    monkeypatch.setitem(_tier._BACKGROUND, "on", True)
    monkeypatch.setitem(_tier._BACKGROUND, "areas", set())
    big = 2 * kernel.compile_s  # past the budget: the rule compiles now
    assert kernel.prefer_interpreted(0.01) is True  # small: interpreted, nothing asked
    assert _tier._BACKGROUND["areas"] == set()
    assert kernel.prefer_interpreted(big) is False
    assert _tier._BACKGROUND["areas"] == {"motion"}  # machine code would pay: asked for
    kernel2 = _tier.njit(twice, compile_s=0.5)
    lock = tmp_path / "tier" / "background-compile.json"
    lock.parent.mkdir(parents=True)
    lock.write_text(json.dumps({"pid": os.getpid(), "started": time.time()}))
    assert _tier.background_running()
    assert kernel2.prefer_interpreted(big) is True  # the background compile brings it
    _tier.background_done(os.getpid() + 1)  # not its lock: kept
    assert lock.exists()
    _tier.background_done(os.getpid())
    assert not lock.exists() and not _tier.background_running()
    lock.write_text(json.dumps({"pid": os.getpid(), "started": time.time() - 1e4}))
    assert not _tier.background_running()  # too old: taken for dead
