"""Inverse kinematics: closed forms for the leg families, damped least squares for any chain.

* :mod:`.closed` — closed forms chosen from the Khalil table's pattern (:func:`detect_family`,
  :func:`analytic`, :func:`analytic_batch`).
* :mod:`.task` — the problem: a position, position + yaw, or a 6-D pose target with per-row
  weights (:func:`build_task`).
* :mod:`.step` — compiled: the task rows, the damped least-squares step (a pure function),
  and the small Levenberg–Marquardt loop around it.
* :mod:`.prepare` — what the solver keeps per model (:class:`Prepared`, in the model's cache)
  and the package's one home pose :func:`home` (IK start, resolved-rate start);
* :mod:`.solver` — :func:`solve`, :func:`solve_many`, :class:`IKResult` and the statuses.

:func:`dls_step` and :func:`sigma_bounds` are the shared numerics of
:mod:`hexapod_kin._numerics`, re-exported here.
"""

from __future__ import annotations

from .._numerics import dls_step, sigma_bounds
from .closed import FAMILIES, AnalyticBatch, LegFamily, analytic, analytic_batch, detect_family
from .prepare import LEG_HOME, Prepared, home, prepared
from .solver import STATUSES, IKResult, solve, solve_many
from .task import AXES, Task, build_task

__all__ = [
    "AXES",
    "FAMILIES",
    "LEG_HOME",
    "STATUSES",
    "AnalyticBatch",
    "IKResult",
    "LegFamily",
    "Prepared",
    "Task",
    "analytic",
    "analytic_batch",
    "build_task",
    "detect_family",
    "dls_step",
    "home",
    "prepared",
    "sigma_bounds",
    "solve",
    "solve_many",
]
