"""Inverse kinematics: closed forms for the leg families, damped least squares for any chain.

* :mod:`.closed` — closed forms chosen from the Khalil table's pattern (:func:`detect_family`,
  :func:`analytic`, :func:`analytic_batch`); the legs' one closed form, vectorised
  (:func:`leg_solutions`, :func:`leg_reachable`); legs with a tool offset or twists within
  :data:`FAMILY_TOL` of the pattern (finished on the table by :mod:`._table_finish`).
* :mod:`.task` — the problem: a position, position + yaw, or a 6-D pose target with per-row
  weights (:func:`build_task`).
* :mod:`.prepare` — what the solver keeps per model (:class:`Prepared`, in the model's cache)
  and the package's one home pose :func:`home` (IK's first candidate start, resolved-rate start).
* :mod:`.solver` — the one numerical loop (compiled, :mod:`.step`, imported on first use)
  for one target (:func:`solve`), many (:func:`solve_many`) or a chain view such as a leg
  (:func:`solve_chain`).
* :mod:`.result` — its options and result (:class:`IKOptions`, :class:`IKResult`).
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
