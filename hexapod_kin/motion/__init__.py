"""Motion of the tip: resolved rate (linear velocity or 6-D twist), pose paths, schedules.

* :mod:`.rate` — :func:`resolved_rate`, :class:`Trajectory`, :class:`ClosestApproach`,
  :func:`constant_twist_pose`; :mod:`._law` — the control law and its integration;
* :mod:`.schedules` — :class:`JointSchedule`, :class:`PosePath` + :func:`follow_pose_path`,
  :func:`track` (IK along a path).

The default start is :func:`hexapod_kin.ik.home` (:func:`default_stance`).
"""

from __future__ import annotations

from .rate import (
    FRAMES,
    ClosestApproach,
    Method,
    Trajectory,
    constant_twist_pose,
    default_stance,
    read_only,
    resolved_rate,
)
from .schedules import JointSchedule, PosePath, Tracked, follow_pose_path, track

#: The seeds' start on the 3-DOF leg [rad] (the value of :data:`hexapod_kin.ik.LEG_HOME`,
#: written here so that a run from it does not import the IK package).
SEED_Q0 = (0.0, 0.3, 1.2)

__all__ = ["FRAMES", "SEED_Q0", "ClosestApproach", "JointSchedule", "Method",
           "PosePath", "Tracked", "Trajectory", "constant_twist_pose",
           "default_stance", "follow_pose_path", "read_only", "resolved_rate", "track"]  # fmt: skip
