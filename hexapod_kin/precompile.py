"""Compile every kernel ahead of use: ``hexapod_kin.precompile()`` / ``hexapod-kin precompile``.

Each area calls its batch APIs once with tiny inputs (numba's disk cache then holds them) and
stamps itself (:func:`hexapod_kin._kernels.mark_compiled`: no first-use notice).
"""

from __future__ import annotations

import contextlib
import json
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Sequence

from .exceptions import ParameterError, one_of

__all__ = ["AREAS", "precompile"]


def _batch() -> None:
    from .kinematics import load

    for source in ("hexabot_leg", "scara"):
        model = load(source)
        qs = model.random_q(8, seed=0)
        model.fk_batch(qs)
        for ref in ("local_world_aligned", "world", "local"):
            model.jacobian_batch(qs, ref)
        model.fk_jacobian_batch(qs)


def _ik() -> None:
    import numpy as np  # here: the command line's parser reads AREAS without numpy

    from .ik import solve_many
    from .kinematics import load

    leg = load("hexabot_leg")
    targets = [leg.fk(q)[:3, 3] for q in leg.random_q(4, seed=1)] + [[1.0, 0.0, 0.0]]
    solve_many(leg, np.array(targets))  # the last one unreachable: the report's checks too
    arm = load("erd:ur5_robot")
    pose = arm.fk(arm.random_q(1, seed=2)[0])
    solve_many(arm, np.array([pose, pose]))


def _singularity() -> None:
    from .kinematics import load
    from .singularity import measures_batch

    for source in ("hexabot_leg", "scara", "erd:ur5_robot"):
        model = load(source)
        measures_batch(model, model.random_q(8, seed=3))


#: Area name → the calls that compile its kernels.
AREAS: dict[str, Callable[[], None]] = {"batch": _batch, "ik": _ik, "singularity": _singularity}


#: What a child process of :func:`precompile` runs: its areas one by one, a JSON line each.
_CHILD = (
    "import json, sys\n"
    "from hexapod_kin.precompile import precompile\n"
    "for name in sys.argv[1:]:\n"
    "    print(json.dumps(precompile([name])), flush=True)\n"
)


def precompile(
    areas: Sequence[str] | None = None,
    *,
    processes: int = 1,
    done: Callable[[str, float], object] | None = None,
) -> dict[str, float]:
    """Compile (or load from numba's disk cache) the kernels of ``areas``.

    ``areas``: names of :data:`AREAS` (default all); ``processes``: areas compiled at once
    (numba holds the GIL), here and in ``processes - 1`` children (a failed child's areas
    compiled here); ``done(name, seconds)`` as each finishes. Returns seconds per area.

    Raises:
        ParameterError: An unknown area name or ``processes`` < 1.

    """
    from ._kernels import COMPILE_SECONDS, mark_compiled, silence_notice

    names = list(AREAS) if areas is None else list(areas)
    for name in names:
        one_of("areas", name, AREAS)
    if isinstance(processes, bool) or not isinstance(processes, int) or processes < 1:
        raise ParameterError(
            f"processes={processes!r} is not allowed; an int >= 1 is needed",
            parameter="processes",
            value=processes,
            allowed="an int >= 1",
        )
    silence_notice()
    shares = _shares(names, processes, COMPILE_SECONDS)
    seconds: dict[str, float] = {}
    lock = threading.Lock()

    def finished(name: str, dt: float) -> None:
        with lock:
            seconds[name] = dt
            mark_compiled(name)
            if done is not None:
                done(name, dt)

    def compile_here(name: str) -> None:
        t0 = time.perf_counter()
        AREAS[name]()
        finished(name, time.perf_counter() - t0)

    children = [_start(share, finished) for share in shares[1:]]
    here = False
    try:
        for name in shares[0]:
            compile_here(name)
        here = True
    finally:  # the children's areas reported, or compiled here below; none left running
        for proc, thread in children:
            if not here:  # interrupted, or an area failed here
                proc.kill()
            proc.wait()
            thread.join()
    for name in names:  # a failed child's areas: here (an error is raised)
        if name not in seconds:
            compile_here(name)
    return {name: seconds[name] for name in names}


#: Seconds a child process takes to start (Python, the package, Pinocchio, numba).
_CHILD_START = 1.0


def _shares(names: list[str], processes: int, cost: dict[str, float]) -> list[list[str]]:
    """The areas of each worker (this process first), the costliest first to the least busy."""
    loads = [0.0] + [_CHILD_START] * (min(processes, len(names)) - 1)
    shares: list[list[str]] = [[] for _ in loads]
    for name in sorted(names, key=lambda n: -cost[n]):
        w = loads.index(min(loads))
        shares[w].append(name)
        loads[w] += cost[name]
    return shares


def _start(
    names: list[str], finished: Callable[[str, float], None]
) -> tuple[subprocess.Popen[str], threading.Thread]:
    """A child process compiling ``names``; a thread reports each area as the child ends it."""
    proc = subprocess.Popen(
        [sys.executable, "-c", _CHILD, *names], stdout=subprocess.PIPE, text=True
    )

    def read() -> None:
        for line in proc.stdout or ():
            with contextlib.suppress(ValueError, TypeError, AttributeError):
                [(name, dt)] = json.loads(line).items()
                finished(str(name), float(dt))

    thread = threading.Thread(target=read, daemon=True)
    thread.start()
    return proc, thread
