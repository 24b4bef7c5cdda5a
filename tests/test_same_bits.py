"""The same calls give the same bytes: fresh process, warm one, after ``precompile``, 8 threads.

Each call's result is reduced to the sha256 of its arrays' bytes (dataclass fields walked;
timing fields skipped). The subprocesses run with their own numba and hexapod_kin caches:
(a) fresh caches (every kernel compiled on first use), (b) the same caches again (warm),
(c) other fresh caches filled by ``python -m hexapod_kin precompile`` before the calls (the
machine code precompile wrote), (d) 8 threads of one process on those caches.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

#: Minutes of compiling in fresh caches (four runs): the slow step of ``.ci/run``.
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parent.parent


def _digest(obj: Any, h: Any) -> None:
    if isinstance(obj, np.ndarray):
        h.update(f"{obj.dtype}{obj.shape}".encode())
        if obj.dtype == object:
            for x in obj.ravel():
                _digest(x, h)
        else:
            h.update(np.ascontiguousarray(obj).tobytes())
    elif dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        for f in dataclasses.fields(obj):
            if not any(w in f.name for w in ("second", "elapsed", "timing", "wall")):
                h.update(f.name.encode())
                _digest(getattr(obj, f.name), h)
    elif isinstance(obj, (list, tuple)):
        for x in obj:
            _digest(x, h)
    elif isinstance(obj, dict):
        for k in sorted(obj, key=str):
            h.update(str(k).encode())
            _digest(obj[k], h)
    elif isinstance(obj, (bool, int, float, str, np.generic, type(None))):
        h.update(repr(obj).encode())
    else:  # a model or another opaque handle: its type only
        h.update(type(obj).__name__.encode())


def _calls() -> dict[str, Any]:
    """name -> zero-argument callable; small inputs, some angles beyond the polynomial range."""
    import hexapod_kin as hk

    leg = hk.load("hexabot_leg")
    arm = hk.load("erd:ur5_robot")
    scara = hk.load("scara")
    q_leg = leg.random_q(300, seed=1)
    q_leg[7] = [2.5e5, -3.0e5, 1.0e6]
    q_arm = arm.random_q(300, seed=2)
    q_scara = scara.random_q(300, seed=4)
    targets = np.array([leg.fk(q)[:3, 3] for q in leg.random_q(5, seed=3)])
    return {
        "fk_batch": lambda: leg.fk_batch(q_leg),
        "jacobian_batch": lambda: arm.jacobian_batch(q_arm, "local"),
        "measures_batch": lambda: (
            hk.singularity.measures_batch(leg, q_leg),
            hk.singularity.measures_batch(scara, q_scara),
        ),
        "scan": lambda: hk.singularity.scan(leg, grid=15),
        "ik.solve": lambda: hk.ik.solve(leg, targets[0]),
        "solve_many": lambda: hk.ik.solve_many(leg, targets),
        "resolved_rate": lambda: hk.motion.resolved_rate(
            leg, [0.02, 0.0, 0.0], [0.0, 0.3, 1.2], 1e-3, 0.05
        ),
        "gait.walk": lambda: hk.gait.walk(duration=0.2, rate=50.0),
    }


def digests() -> dict[str, str]:
    """sha256 of every call's result, in this process."""
    out = {}
    for name, call in _calls().items():
        h = hashlib.sha256()
        _digest(call(), h)
        out[name] = h.hexdigest()
    return out


#: The precompile areas run before (c).
_AREAS = ("batch", "singularity", "ik")
_CHILD = "import json, test_same_bits as t; print(json.dumps(t.digests()))"
#: The same calls from 8 threads of one process, started together.
_THREADS = """
import json, threading, test_same_bits as t
out, barrier = {}, threading.Barrier(8)
def run(i):
    barrier.wait()
    out[str(i)] = t.digests()
threads = [threading.Thread(target=run, args=(i,)) for i in range(8)]
for th in threads:
    th.start()
for th in threads:
    th.join()
print(json.dumps(out))
"""


def _env(cache: Path) -> dict[str, str]:
    env = dict(os.environ)
    env["NUMBA_CACHE_DIR"] = str(cache / "numba")
    env["HEXAPOD_KIN_CACHE_DIR"] = str(cache / "hk")
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), str(ROOT / "tests")])
    return env


_NOTICES: list[str] = []


def _child(cache: Path, code: str = _CHILD) -> Any:
    out = subprocess.run(
        [sys.executable, "-c", code], env=_env(cache), capture_output=True, text=True
    )
    assert out.returncode == 0, out.stderr[-3000:]
    _NOTICES.append(out.stderr)
    return json.loads(out.stdout.splitlines()[-1])


def test_same_bytes_fresh_warm_after_precompile_and_threads(tmp_path: Path) -> None:
    # (c)'s precompile runs beside (a) (two processes, two cores): both compile from nothing
    pre = subprocess.Popen(
        [sys.executable, "-m", "hexapod_kin", "precompile", "--only", *_AREAS],
        env=_env(tmp_path / "c"),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    fresh = _child(tmp_path / "a")
    _, err = pre.communicate()
    assert pre.returncode == 0, err[-3000:]
    warm = _child(tmp_path / "a")
    # the first-use notice: once per area on fresh caches, never again (stamp files)
    for area in _AREAS:  # every area these calls compile: one notice each
        assert _NOTICES[-2].count(f"hexapod-kin: compiling {area} kernels") == 1, area
    assert "compiling" not in _NOTICES[-1]
    after = _child(tmp_path / "c")
    assert "compiling" not in _NOTICES[-1]  # precompile filled every area these calls use
    assert warm == fresh
    assert after == fresh
    threads = _child(tmp_path / "c", _THREADS)
    assert threads == {str(i): fresh for i in range(8)}
