"""The cold path of the resolved-rate loop (``motion/_cold.py``) against the compiled kernel.

Two implementations of one control law: the numba kernel (our chain arrays, our FK) and the
cold path (Pinocchio's FK and Jacobian, the law on Python floats). Every output of a run —
q, q̇, tip pose, tip twist, σ bounds, damping, the limited flags — must agree to rounding on
legs, a prismatic joint, a 4-joint leg from a table file, joint limits hit on the way, a
start at a singularity, 6-D twists in the base and tip frames (UR5, Panda) and a leg on the
hexapod's body (a sub-chain whose base is not Pinocchio's root).
"""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import hexapod_kin as hk
from hexapod_kin import _tier, robots
from hexapod_kin.motion import _kernel

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
FIELDS = ("q", "qdot", "foot", "rotation", "foot_velocity", "angular_velocity", "sigma_min",
          "sigma_max", "damping")  # fmt: skip


def _run(mode: str, fn):
    before = _tier.set_mode(mode)
    try:
        return fn()
    finally:
        _tier.set_mode(before)


def _spy(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    calls: list[int] = []
    real = _kernel.rr_cold

    def spy(*args, **kw):
        calls.append(1)
        return real(*args, **kw)

    monkeypatch.setattr(_kernel, "rr_cold", spy)
    return calls


def _same(a, b, tol: float) -> None:
    for name in FIELDS:
        x, y = np.asarray(getattr(a, name)), np.asarray(getattr(b, name))
        assert x.shape == y.shape, name
        assert np.array_equal(np.isnan(x), np.isnan(y)), name
        fin = ~np.isnan(x)
        err = float(np.max(np.abs(x[fin] - y[fin]))) if fin.any() else 0.0
        assert err <= tol * max(1.0, float(np.max(np.abs(y[fin]), initial=0.0))), (name, err)
    assert np.array_equal(a.limited, b.limited)


UR5_Q0 = [0.3, -0.8, 1.1, -0.4, 0.6, 0.2]
_LEG = robots.get("hexabot_leg")
#: the leg with narrow joint limits: the run ends up pressing a joint against its limit
NARROW = dataclasses.replace(
    _LEG, limits=tuple(dataclasses.replace(lim, lower=-0.2, upper=1.3) for lim in _LEG.limits)
)
CASES = [
    # (source, load kwargs, velocity, q0, dt, duration, resolved_rate kwargs)
    ("hexabot_leg", {}, [0.02, 0.0, 0.0], [0, 0.3, 1.2], 2e-3, 0.6, {}),
    ("hexabot_leg", {}, [0.02, -0.01, 0.01], [0, 0.3, 1.2], 2e-3, 0.4, {"method": "euler"}),
    # pushed out of reach: damping near the boundary, then the joint limits
    ("hexabot_leg", {}, [0.3, 0.0, 0.0], [0, 0.3, 1.2], 2e-3, 1.0, {}),
    (NARROW, {}, [-0.05, 0.0, 0.0], [0, 0.3, 1.2], 2e-3, 1.0, {}),  # joint limits hit
    (NARROW, {}, [0.0, 0.0, 0.05], [0, 0.3, 1.2], 2e-3, 1.0, {"method": "euler"}),
    # a singular start (straight leg): damped, never a division by zero
    ("hexabot_leg", {}, [0.0, 0.0, 0.02], [0, 0, 0], 2e-3, 0.3, {}),
    ("scara", {}, [0.01, 0.02, -0.02], None, 2e-3, 0.5, {}),  # prismatic joint
    (str(EXAMPLES / "leg4.toml"), {}, [0.02, 0.0, 0.01], None, 2e-3, 0.4, {}),  # m < n
    ("hexapod", {"tip": "leg3_foot"}, [0.01, 0.01, 0.0], None, 2e-3, 0.4, {}),
    ("erd:ur5_robot", {}, [0.0, 0.01, 0.02, 0.1, 0.0, 0.05], UR5_Q0, 5e-3, 0.5, {"frame": "tip"}),
    ("erd:ur5_robot", {}, [0.02, 0.0, -0.01, 0.0, 0.2, 0.0], UR5_Q0, 5e-3, 0.5, {"gain": 5.0}),
    ("erd:panda", {}, [0.02, 0.0, 0.01, 0.1, 0.0, 0.1], None, 5e-3, 0.5, {}),  # 6 rows, 7 joints
]


def _id(case: tuple) -> str:
    name = case[0] if isinstance(case[0], str) else "narrow_leg"
    return Path(name).stem + str(case[2]) + str(case[6] or "")


@pytest.mark.parametrize("case", CASES, ids=_id)
def test_cold_path_equals_the_kernel(case, monkeypatch):
    source, load_kw, vel, q0, dt, duration, kw = case
    model = hk.load(source, **load_kw)
    calls = _spy(monkeypatch)

    def run():
        return hk.motion.resolved_rate(model, vel, q0, dt, duration, **kw)

    compiled = _run("always", run)
    assert not calls  # the kernel ran
    cold = _run("never", run)
    assert calls == [1]  # the cold path ran
    _same(cold, compiled, 1e-11)
    if source is NARROW:
        assert cold.limited.any()  # the limit rule ran


def test_cold_path_is_the_law_not_a_copy_of_the_kernel_output():
    """Independent of both: the run follows the commanded velocity (J q̇ = v on a regular path)."""
    model = hk.load("hexabot_leg")
    v = np.array([0.02, -0.01, 0.01])
    tr = _run("never", lambda: hk.motion.resolved_rate(model, v, [0, 0.3, 1.2], 1e-3, 0.5))
    # Pinocchio's own Jacobian at every sample times the recorded q̇ gives back the command
    jv = np.array([model.jacobian(q)[:3] @ qd for q, qd in zip(tr.q, tr.qdot)])
    assert np.abs(jv - v).max() < 1e-9
    # the foot moved by v t (closed loop on the integrated reference)
    assert np.abs(tr.foot[-1] - tr.foot[0] - v * 0.5).max() < 1e-9


_PROBE = r"""
import json, sys
import numpy as np
import hexapod_kin as hk
from hexapod_kin.motion import _kernel as k
calls = []
real = k.rr_cold
k.rr_cold = lambda *a, **kw: (calls.append(1), real(*a, **kw))[1]
leg = hk.motion.resolved_rate(hk.load("hexabot_leg"), [0.01, 0, 0], [0, 0.3, 1.2], 1e-3, 10.0)
ur5 = hk.load("erd:ur5_robot")
q0 = np.array([0.3, -0.8, 1.1, -0.4, 0.6, 0.2])
tw = hk.motion.resolved_rate(ur5, [0, 0, 0.01, 0, 0, 0.1], q0, 1e-3, 2.0, frame="tip")
print(json.dumps({"cold_calls": len(calls), "compiled": [bool(k._rr3.dispatcher.signatures),
                  bool(k._rr6.dispatcher.signatures)], "spent": k._rr3._spent}))
"""


def test_a_fresh_install_runs_the_cold_path_and_compiles_nothing(tmp_path):
    """Empty caches, default rule: a 10-s leg run and a 2-s UR5 twist never compile."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"), HEXAPOD_KIN_JIT="auto")
    env["HEXAPOD_KIN_CACHE_DIR"] = str(tmp_path / "hk")
    res = subprocess.run(
        [sys.executable, "-c", _PROBE], env=env, capture_output=True, text=True, timeout=300
    )
    assert res.returncode == 0, res.stderr[-2000:]
    out = json.loads(res.stdout.strip().splitlines()[-1])
    assert out["cold_calls"] == 2 and out["compiled"] == [False, False]
    assert out["spent"] > 0.0  # charged to the kernel's budget (the ski-rental rule)
