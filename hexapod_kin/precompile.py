"""Compile every kernel ahead of use: ``hexapod_kin.precompile()`` / ``hexapod-kin precompile``.

Each area calls its batch APIs once with tiny inputs, so numba compiles every kernel of the
package and writes the machine code to its disk cache (``cache=True``; ``NUMBA_CACHE_DIR``,
else ``__pycache__`` beside the sources); every later process loads it. The area's stamp
(:func:`hexapod_kin._kernels.mark_compiled`) then silences the first-use notice.

numba compiles holding the GIL, one function at a time: areas compile in parallel only in
separate processes (``processes > 1``, what ``hexapod-kin precompile`` does), each writing
its kernels to the shared disk cache; the calling process then loads them from there on
first use.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from collections.abc import Callable, Sequence

import numpy as np

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


#: What a child process of :func:`precompile` runs: one area, its seconds as JSON on stdout.
_CHILD = (
    "import json, sys\n"
    "from hexapod_kin.precompile import precompile\n"
    "print(json.dumps(precompile(sys.argv[1:])))\n"
)


def precompile(areas: Sequence[str] | None = None, *, processes: int = 1) -> dict[str, float]:
    """Compile (or load from numba's disk cache) the kernels of ``areas``.

    Args:
        areas: Names from :data:`AREAS` (default: all of them).
        processes: Areas compiled at once, each in its own child process (numba compiles
            holding the GIL); 1: in this process, one after the other (the kernels are then
            also loaded here). An area whose child fails is compiled here (its error raised).

    Returns:
        Seconds per area, in order (a second call, or a later process, takes milliseconds:
        the machine code comes from the disk cache).

    Raises:
        ParameterError: An unknown area name or ``processes`` < 1.

    """
    from ._kernels import mark_compiled, silence_notice

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
    seconds: dict[str, float] = {}
    if processes > 1 and len(names) > 1:
        seconds = _in_children(names, processes)
    for name in names:
        if name in seconds:
            mark_compiled(name)
            continue
        t0 = time.perf_counter()
        AREAS[name]()
        seconds[name] = time.perf_counter() - t0
        mark_compiled(name)
    return {name: seconds[name] for name in names}


def _in_children(names: list[str], processes: int) -> dict[str, float]:
    """Each area in a child process, ``processes`` at a time, the costliest first.

    Returns the seconds of the areas whose child succeeded (measured in the child). The
    children are ended if this process is interrupted.
    """
    todo = sorted(names, key=lambda n: -_COST[n])
    running: list[tuple[str, subprocess.Popen[str]]] = []
    done: dict[str, float] = {}
    try:
        while todo or running:
            while todo and len(running) < processes:
                name = todo.pop(0)
                cmd = [sys.executable, "-c", _CHILD, name]
                running.append((name, subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)))
            name, proc = running.pop(0)
            out, _ = proc.communicate()
            if proc.returncode == 0:
                try:
                    done.update({name: float(json.loads(out.splitlines()[-1])[name])})
                except (ValueError, KeyError, IndexError):
                    pass
    finally:
        for _, proc in running:
            proc.kill()
            proc.wait()
    return done


#: Relative compile cost of each area (the order children start in).
_COST: dict[str, int] = {"singularity": 4, "ik": 3, "batch": 1}
