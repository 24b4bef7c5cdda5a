"""Compile every kernel ahead of use: ``hexapod_kin.precompile()`` / ``hexapod-kin precompile``.

Each area calls its batch APIs once with tiny inputs, so numba compiles every kernel of the
package and writes the machine code to its disk cache (``cache=True``; ``NUMBA_CACHE_DIR``,
else ``__pycache__`` beside the sources); every later process loads it. The area's stamp
(:func:`hexapod_kin._kernels.mark_compiled`) then silences the first-use notice.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

import numpy as np

from .exceptions import one_of

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
AREAS: dict[str, Callable[[], None]] = {
    "batch": _batch,
    "ik": _ik,
    "singularity": _singularity,
}


def precompile(areas: Sequence[str] | None = None) -> dict[str, float]:
    """Compile (or load from numba's disk cache) the kernels of ``areas``.

    Args:
        areas: Names from :data:`AREAS` (default: all of them).

    Returns:
        Seconds per area, in order (a second call, or a later process, takes milliseconds:
        the machine code comes from the disk cache).

    Raises:
        ParameterError: An unknown area name.

    """
    from ._kernels import mark_compiled, silence_notice

    names = list(AREAS) if areas is None else list(areas)
    for name in names:
        one_of("areas", name, AREAS)
    silence_notice()
    seconds: dict[str, float] = {}
    for name in names:
        t0 = time.perf_counter()
        AREAS[name]()
        seconds[name] = time.perf_counter() - t0
        mark_compiled(name)
    return seconds
