"""Kinematic walking driven live: the planner's walk, one cycle at a time.

The cockpit walks by playing :func:`hexapod_kin.gait.walk` runs of one gait cycle each, planned
for the commanded body twist and pattern (cached per command), chained end to start: each
cycle's body poses are moved so that it starts where the last one ended. A new command (keys)
from standstill starts at once; while walking, it takes effect at the next cycle (a walk's
feet are planned per cycle). Every check of the planner holds on every cycle played (a cycle
that fails a check is refused with its reason and the robot stops).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..exceptions import HexapodKinError
from ..gait.robot import body_pose
from ..gait.walk import walk
from ..gait.zmp import zmp_points

__all__ = ["Cycle", "Walker", "run_zmp"]

#: Sample rate of the planned cycles [Hz].
RATE = 100.0


@dataclass(frozen=True)
class Cycle:
    """One planned gait cycle and where it was placed in the world.

    Attributes:
        run: The planner's :class:`~hexapod_kin.gait.walk.GaitRun` (one period).
        anchor: ``worldMrun`` (4, 4): the run's frame placed in the world.
        command: The body twist (vx [m/s], vy [m/s], wz [rad/s]).
        pattern: The phase pattern's name.
        zmp: (N, 3) the run's ZMP per sample, in the run's frame [m] (:func:`run_zmp`).

    """

    run: Any
    anchor: np.ndarray
    command: tuple[float, float, float]
    pattern: str
    zmp: np.ndarray


def run_zmp(body: Any, run: Any) -> np.ndarray:
    """(N, 3) ZMP of each sample of ``run`` [m] (flat ground: the stance feet's contact height).

    :func:`hexapod_kin.gait.zmp.zmp_points` of the run's joint poses, on the plane of the
    supporting contacts (the foot points ``foot_radius`` below the foot frames), as the planner
    checks it for :attr:`~hexapod_kin.gait.walk.GaitRun.zmp_margin`. Without a mass or with
    fewer than 4 samples: the CoM's ground projection.
    """
    q, base, t = np.asarray(run.q), np.asarray(run.base_poses), np.asarray(run.t)
    T = body.joint_poses(q, base)
    contacts = body.feet_of(T)
    sup = np.asarray(run.support)[..., None]
    h = ((contacts[..., 2:3] - body.foot_radius) * sup).sum(axis=1) / np.maximum(sup.sum(axis=1), 1)
    if len(t) < 4 or not body.mass > 0:
        com = np.asarray(body.com(q, base))
        return np.column_stack([com[:, :2], h[:, 0]])
    return np.asarray(zmp_points(body, q, base, t, np.ascontiguousarray(h[:, 0])))


class Walker:
    """Plans and plays the cycles of a kinematic walk of one legged robot.

    Args:
        body: The :class:`~hexapod_kin.gait.robot.WholeBody`.
        period: Gait cycle [s].

    """

    def __init__(self, body: Any, period: float = 1.0) -> None:
        self.body = body
        self.period = float(period)
        self._runs: dict[tuple[str, tuple[float, float, float]], tuple[Any, np.ndarray]] = {}
        self.cycle: Cycle | None = None
        self.time = 0.0  # in the current cycle [s]

    def plan(self, pattern: str, command: tuple[float, float, float]) -> Any:
        """The one-cycle run of ``pattern`` at ``command`` (cached).

        Raises:
            HexapodKinError: The planner refuses it (its reason: reach, joint limit, margin).

        """
        return self._plan(pattern, command)[0]

    def _plan(self, pattern: str, command: tuple[float, float, float]) -> tuple[Any, np.ndarray]:
        vx, vy, wz = (round(float(c), 6) for c in command)
        key = (pattern, (vx, vy, wz))
        if key not in self._runs:
            if len(self._runs) > 64:
                self._runs.pop(next(iter(self._runs)))
            run = walk(
                self.body,
                pattern=pattern,
                velocity=key[1],
                period=self.period,
                duration=self.period,
                rate=RATE,
            )
            self._runs[key] = (run, run_zmp(self.body, run))
        return self._runs[key]

    def start(self, pattern: str, command: tuple[float, float, float], base: np.ndarray) -> Cycle:
        """Plan a cycle and place its start at the body pose ``base`` (heading kept, z of the run).

        Raises:
            HexapodKinError: The planner refuses the cycle.

        """
        run, zmp = self._plan(pattern, command)
        start = np.asarray(run.base_poses[0])
        yaw = float(np.arctan2(base[1, 0], base[0, 0]))
        place = body_pose((0.0, 0.0, 0.0), (0.0, 0.0, yaw))  # the run turned to the heading
        place[:2, 3] = base[:2, 3] - place[:2, :2] @ start[:2, 3]
        self.cycle = Cycle(run, place, tuple(command), pattern, zmp)  # type: ignore[arg-type]
        self.time = 0.0
        return self.cycle

    def sample(self) -> tuple[np.ndarray, np.ndarray, int]:
        """(q (nq,), worldMbody (4, 4), sample index) of the current cycle at :attr:`time`."""
        assert self.cycle is not None
        run = self.cycle.run
        k = min(int(round(self.time * RATE)), len(run.t) - 1)
        return np.asarray(run.q[k]), self.cycle.anchor @ np.asarray(run.base_poses[k]), k

    def advance(self, dt: float, pattern: str, command: tuple[float, float, float]) -> str:
        """Move on by ``dt`` [s]; at a cycle's end chain the next one for the current command.

        Returns:
            ``""`` while walking, ``"stopped"`` when a cycle ended with a zero command, or the
            planner's reason when it refused the next cycle (the robot stops).

        """
        if self.cycle is None:
            return "stopped"
        self.time += dt
        end = float(self.cycle.run.t[-1])
        while self.time >= end:
            left = self.time - end
            self.time = end
            _, base, _ = self.sample()
            if not any(command):
                self.cycle = None
                return "stopped"
            try:
                self.start(pattern, command, base)
            except HexapodKinError as exc:
                self.cycle = None
                return str(exc)
            self.time = left
            end = float(self.cycle.run.t[-1])
        return ""
