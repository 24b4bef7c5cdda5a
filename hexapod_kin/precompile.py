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
    from ._kernels import fk_batch, position_jacobian_batch
    from .kinematics import load

    for source in ("hexabot_leg", "scara"):
        model = load(source)
        qs = model.random_q(8, seed=0)
        model.fk_batch(qs)
        for ref in ("local_world_aligned", "world", "local"):
            model.jacobian_batch(qs, ref)
        model.fk_jacobian_batch(qs)
        fk_batch(model.arrays, qs)
        position_jacobian_batch(model.arrays, qs)


def _ik() -> None:
    from .ik import analytic_batch, solve, solve_many
    from .kinematics import load

    leg = load("hexabot_leg")
    targets = np.array([leg.fk(q)[:3, 3] for q in leg.random_q(4, seed=1)])
    solve(leg, targets[0])
    solve_many(leg, targets)
    analytic_batch(leg, targets)
    arm = load("erd:ur5_robot")
    pose = arm.fk(arm.random_q(1, seed=2)[0])
    solve(arm, pose)
    solve_many(arm, np.array([pose, pose]))


def _motion() -> None:
    from .kinematics import load
    from .motion import resolved_rate

    leg = load("hexabot_leg")
    resolved_rate(leg, [0.01, 0.0, 0.0], [0.0, 0.3, 1.2], 1e-3, 0.01)
    resolved_rate(leg, [0.01, 0.0, 0.0], [0.0, 0.3, 1.2], 1e-3, 0.01, method="euler")
    arm = load("erd:ur5_robot")
    q0 = np.array([0.3, -0.8, 1.1, -0.4, 0.6, 0.2])
    for frame in ("base", "tip"):
        resolved_rate(arm, [0.0, 0.0, 0.01, 0.0, 0.0, 0.1], q0, 1e-3, 0.01, frame=frame)


def _singularity() -> None:
    from .kinematics import load
    from .singularity import measures_batch

    for source in ("hexabot_leg", "scara", "erd:ur5_robot"):
        model = load(source)
        measures_batch(model, model.random_q(8, seed=3))


def _gait() -> None:
    from .gait import walk

    walk(duration=0.2)


def _sweep() -> None:
    from .sweep import score_designs
    from .sweep.designs import DEFAULTS, PARAMETERS

    row = np.array([[DEFAULTS[name] for name in PARAMETERS]], dtype=float)
    score_designs(row, mc_samples=16, line_points=4, stride_points=2)


#: Area name → the calls that compile its kernels.
AREAS: dict[str, Callable[[], None]] = {
    "batch": _batch,
    "ik": _ik,
    "motion": _motion,
    "singularity": _singularity,
    "gait": _gait,
    "sweep": _sweep,
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
