"""Inverse kinematics: closed forms for the leg families, damped least squares for any chain.

* :mod:`.closed` — closed forms chosen from the Khalil table's pattern (:func:`detect_family`,
  :func:`analytic`, :func:`analytic_batch`, :func:`leg_solutions`, :func:`leg_reachable`).
* :mod:`.task` — the problem: a position, position + yaw or 6-D pose target with row weights.
* :mod:`.prepare` — what the solver keeps per model (:class:`Prepared`) and :func:`home`.
* :mod:`.solver` — the one numerical loop (compiled, :mod:`.step`): :func:`solve`,
  :func:`solve_many`, :func:`solve_chain`; :mod:`.result` — :class:`IKOptions`,
  :class:`IKResult`.
"""

from __future__ import annotations

from .closed import (
    FAMILIES,
    FAMILY_TOL,
    AnalyticBatch,
    LegFamily,
    analytic,
    analytic_batch,
    detect_family,
    leg_reachable,
    leg_solutions,
)
from .prepare import LEG_HOME, Prepared, home, prepared
from .result import STATUSES, IKOptions, IKResult
from .solver import solve, solve_chain, solve_many
from .task import AXES, TARGET_FACTOR, Task, build_task, build_tasks, check_within

__all__ = ["AXES", "FAMILIES", "FAMILY_TOL", "LEG_HOME", "STATUSES", "TARGET_FACTOR",
           "AnalyticBatch", "IKOptions", "IKResult", "LegFamily", "Prepared", "Task", "analytic",
           "analytic_batch", "build_task", "build_tasks", "check_within", "detect_family", "home",
           "leg_reachable", "leg_solutions", "prepared", "solve", "solve_chain",
           "solve_many"]  # fmt: skip
