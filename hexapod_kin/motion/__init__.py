"""Motion of the tip: resolved rate (linear velocity or 6-D twist), pose paths, schedules.

* :mod:`.rate` — :func:`resolved_rate`, :class:`Trajectory`, :class:`ClosestApproach`,
  :func:`constant_twist_pose` (exact poses of a constant twist);
* :mod:`.schedules` — :class:`JointSchedule`, :class:`PosePath` + :func:`follow_pose_path`
  (SE(3) interpolation, closed loop on the pose error), :func:`track` (IK along a path);
* :mod:`._kernel` — the compiled control law and integrator.

The start pose is the package's one home pose, :func:`hexapod_kin.ik.home`
(``default_stance`` is the same function). The seeds' experiments live in
:mod:`hexapod_kin.seeds`; foot steps and gaits in :mod:`hexapod_kin.gait`.
"""

from __future__ import annotations

from ..ik.prepare import LEG_HOME, home
from .rate import (
    FRAMES,
    ClosestApproach,
    Method,
    Trajectory,
    constant_twist_pose,
    positive,
    read_only,
    resolved_rate,
)
from .schedules import JointSchedule, PosePath, Tracked, follow_pose_path, track

#: The seeds' start on the 3-DOF leg [rad] (= :data:`hexapod_kin.ik.LEG_HOME`).
SEED_Q0 = LEG_HOME

#: The default start of a run: the same function as :func:`hexapod_kin.ik.home`.
default_stance = home

__all__ = [
    "FRAMES",
    "SEED_Q0",
    "ClosestApproach",
    "JointSchedule",
    "Method",
    "PosePath",
    "Tracked",
    "Trajectory",
    "constant_twist_pose",
    "default_stance",
    "follow_pose_path",
    "positive",
    "read_only",
    "resolved_rate",
    "track",
]
