"""An ensemble member walked under the closed-loop controller, judged against the plan.

An open-loop replay cannot react to ground it was not told about: on ±3 mm bumps a stiff
quadruped's planned touch-downs land early or late, the weight moves between legs and the
stance feet slide, whatever the plan (issue 31's measurements: every bump replay of the
eight example-robot-data quadrupeds slid 5.5–25.5 mm in one stance). A walking robot meets
unknown bumps with feedback, so the bumpy members of :data:`~hexapod_kin.robust.ENSEMBLE`
walk the plan's pattern for the plan's duration under :func:`hexapod_kin.control.run` (the
path of ``simulate --control --bumps A --seed K``), commanded the plan's mean twist
(:func:`plan_command`): the controller's path ends where the plan's tracked point does, which
the plan's nominal twist held for its duration need not (a crawl's surge and sway, a duration
that is not a whole number of cycles). :func:`controlled_run` judges that walk by the
replay's kind of checks (:meth:`ControlledRun.checks`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._pose import rpy_to_matrix
from ..simulate.replay import Travel

__all__ = [
    "CONTROL_LIMITS",
    "RAMP_STEP",
    "ControlledRun",
    "controlled_run",
    "finite",
    "mean_twist",
    "plan_command",
    "plan_motion",
    "ramped_motion",
]

#: The closed loop's limits: travel along the plan within 1 % of the plan's distance (the
#: replay's :data:`~hexapod_kin.simulate.replay.LIMITS` ``travel``); the largest yaw error
#: against the controller's path within 3° (the controller's own must-show over bumps,
#: ``tests/test_control.py``: a closed loop steers back, so its heading wanders where a replay's
#: is the plan's). A fall or a non-foot contact fails. The controller measures no stance slip.
CONTROL_LIMITS: dict[str, float] = {"travel": 0.01, "heading": math.radians(3.0)}


@dataclass(frozen=True)
class ControlledRun(Travel):
    """A closed-loop walk of a plan's twist, with the figures a replay reports.

    Attributes:
        control: The walk (:class:`hexapod_kin.control.ControlRun`).
        distance_planned: The plan's horizontal displacement [m] of the point the
            controller tracks (:func:`controlled_run`).
        direction_planned: Its direction [rad] in the plan's start frame.
        turn_planned: The plan's yaw change [rad].

    """

    control: Any
    distance_planned: float
    direction_planned: float
    turn_planned: float

    mode = "controlled"

    @property
    def _moved(self) -> np.ndarray:
        return np.asarray(self.control.end) - np.asarray(self.control.position)[0, :2]

    @property
    def distance(self) -> float:
        """The walked horizontal displacement [m] (the controller's tracked point).

        To :attr:`~hexapod_kin.control.ControlRun.end`: the steps' surge and sway left out.
        """
        return float(np.hypot(*self._moved))

    @property
    def direction_error(self) -> float:
        """Angle between the walked and the planned displacements [rad]."""
        if self.distance < 1e-9:
            return 0.0
        yaw0 = float(np.asarray(self.control.rpy)[0, 2])  # the start frame's heading
        d = math.atan2(self._moved[1], self._moved[0]) - yaw0 - self.direction_planned
        return abs(math.atan2(math.sin(d), math.cos(d)))

    @property
    def turn(self) -> float:
        """The walked yaw change [rad]."""
        yaw = np.unwrap(np.asarray(self.control.rpy)[:, 2])
        return float(yaw[-1] - yaw[0])

    def checks(self) -> dict[str, dict[str, Any]]:
        """Each check: value, limit, pass (:data:`CONTROL_LIMITS`).

        ``travel``: the larger of |distance_error| and |turn_error|; ``heading``: the
        controller's largest yaw error; ``fell``: 1 when it fell; ``contacts``: the number of
        non-foot contact pairs (both must be 0).
        """
        c = self.control
        rel = [abs(e) for e in (self.distance_error, self.turn_error) if e is not None]
        rows = {
            "travel": (max(rel) if rel else 0.0, CONTROL_LIMITS["travel"]),
            "heading": (float(c.heading_error), CONTROL_LIMITS["heading"]),
            "fell": (float(bool(c.fell)), 0.0),
            "contacts": (float(len(c.non_foot_contacts)), 0.0),
        }
        return Travel.judged(rows)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the figures, the checks and the closed loop's own summary."""
        return {
            "mode": self.mode,
            "distance_planned": self.distance_planned,
            "distance": self.distance,
            "distance_along": self.distance_along,
            "distance_error": self.distance_error,
            "direction": self.direction,
            "turn_planned": self.turn_planned,
            "turn": self.turn,
            "turn_error": self.turn_error,
            "checks": self.checks(),
            "ok": self.ok,
            "control": self.control.to_dict(),
        }


def finite(obj: Any) -> Any:
    """``obj`` (dicts, lists, tuples of numbers) with NaN and infinities as None (JSON null).

    A walk that blew up (a robot that fell through the ground) has non-finite figures.
    """
    if isinstance(obj, dict):
        return {k: finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [finite(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def plan_motion(planned: Any, turn: float, point: Any = None) -> np.ndarray:
    """The plan's body motion ``(x, y, yaw)`` [m, m, rad]: its end in its start frame.

    Args:
        planned: (N, 4, 4) the plan's body poses (a replay's ``planned``).
        turn: The plan's yaw change [rad], unwrapped (a replay's ``turn_planned``).
        point: (N, 2 or 3) the planned positions of the point that moves [m] (the
            controller's tracked point: the plan's ``com`` for torque control), or None (the
            poses' origins).

    Returns:
        (3,) the point's horizontal displacement from the first sample to the last, in the
        frame of the first pose's heading, and ``turn``.

    """
    poses = np.asarray(planned, dtype=float)
    xy = poses[:, :2, 3] if point is None else np.asarray(point, dtype=float)[:, :2]
    d = xy[-1] - xy[0]
    yaw0 = math.atan2(poses[0, 1, 0], poses[0, 0, 0])
    c, s = math.cos(yaw0), math.sin(yaw0)
    return np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1], float(turn)])


def mean_twist(motion: Any, duration: float) -> np.ndarray:
    """The constant body twist ``(vx, vy, wz)`` [m/s, rad/s] that makes ``motion`` in ``duration``.

    The logarithm of SE(2) over the time: a body moving at the body-frame twist ``(v, w)``
    for ``T`` turns by ``th = w T`` and moves by ``V(th) v T`` in its start frame, with
    ``V(th) = [[sin th, cos th - 1], [1 - cos th, sin th]] / th`` (the identity at
    ``th = 0``), so ``v = V^-1 d / T`` (least squares where ``V`` is singular: whole turns).

    Args:
        motion: ``(x, y, yaw)`` [m, m, rad] in the start frame (:func:`plan_motion`).
        duration: [s].

    Returns:
        (3,) the twist.

    """
    x, y, th = (float(v) for v in motion)
    if abs(th) < 1e-12:
        return np.array([x, y, 0.0]) / duration
    s, c = math.sin(th), math.cos(th)
    V = np.array([[s, c - 1.0], [1.0 - c, s]]) / th
    v = np.linalg.lstsq(V, np.array([x, y]), rcond=None)[0]
    return np.array([v[0], v[1], th]) / duration


#: Time step [s] of :func:`ramped_motion`'s integration of the controller's path.
RAMP_STEP = 1e-3


def ramped_motion(command: Any, duration: float, accel: tuple[float, float]) -> np.ndarray:
    """The controller's path ``(x, y, yaw)`` after ``duration`` of the held ``command``.

    The controller's reference twist ramps from rest to the command at ``accel`` (linear
    [m/s²], yaw [rad/s²]; :data:`hexapod_kin.control.controller.ACCEL`), each component
    clipped on its own, and the path integrates it in the path's heading frame (the
    controller's ``_advance``), here at :data:`RAMP_STEP` (the controller's own rate changes
    the ramp's shortfall by about ``|v| dt / 2``).
    """
    cmd = np.asarray(command, dtype=float)
    n = max(1, int(round(duration / RAMP_STEP)))
    k = np.arange(1, n + 1, dtype=float)[:, None]
    step = np.array([accel[0], accel[0], accel[1]]) * RAMP_STEP
    tw = np.sign(cmd) * np.minimum(k * step, np.abs(cmd))
    yaw = np.concatenate([[0.0], np.cumsum(tw[:, 2]) * RAMP_STEP])
    rot = np.array([rpy_to_matrix(0.0, 0.0, a)[:2, :2] for a in yaw[:-1]])
    x, y = np.einsum("kij,kj->i", rot, tw[:, :2]) * RAMP_STEP
    return np.array([float(x), float(y), float(yaw[-1])])


def plan_command(motion: Any, duration: float) -> tuple[float, float, float]:
    """The command ``(vx, vy, wz)`` whose controller path makes ``motion`` in ``duration``.

    The plan's mean twist (:func:`mean_twist`), raised by the shortfall of the controller's
    start from rest (:func:`ramped_motion`): ``c ← c + mean_twist(motion) −
    mean_twist(ramped_motion(c))`` from ``c = mean_twist(motion)`` (a contraction by about
    ``|v| / (a T)``), so the path ends where the plan does. A plan need not move at its
    nominal twist for its whole duration (a crawl's surge and sway, a duration that is not
    a whole number of cycles): the path and the replay are asked the same displacement.
    """
    from ..control.controller import ACCEL

    goal = mean_twist(motion, duration)
    cmd = goal.copy()
    for _ in range(50):
        miss = goal - mean_twist(ramped_motion(cmd, duration, ACCEL), duration)
        cmd = cmd + miss
        if float(np.abs(miss).max()) < 1e-15:
            break
    return float(cmd[0]), float(cmd[1]), float(cmd[2])


def controlled_run(replay: Any, robot: Any, member: Any, feet: Any, foot_radius: Any) -> Any:
    """Walk ``replay``'s plan under the controller on ``member``'s ground.

    The controller is commanded :func:`plan_command` of the plan's motion of the point it
    tracks (the CoM for torque control, the base's origin for servos): its path ends where
    that point of the plan does (not the plan's nominal twist held for the duration), and
    the walk is judged against that motion.

    Args:
        replay: A :class:`~hexapod_kin.simulate.SimRun` of the plan (its pattern, duration,
            planned body poses and turn).
        robot: The robot as the plan was given it (a source, a model; a run's ``robot``).
        member: The :class:`~hexapod_kin.robust.Member` (friction, bumps, seed).
        feet: Feet of a URDF robot without foot links (as ``simulate`` takes them), or None.
        foot_radius: Foot sphere radius [m], or None (the robot's: as the replay's scene,
            feet that are round ends of the legs' meshes are those spheres,
            :func:`~hexapod_kin.simulate.collision.scene_robot`).

    Returns:
        A :class:`ControlledRun`.

    """
    from ..control import run
    from ..control.sim import default_kind
    from ..gait import as_whole_body
    from ..simulate.collision import scene_robot

    if feet is not None or foot_radius is not None:  # as ``control`` on the command line
        robot = as_whole_body(robot, feet=feet, foot_radius=foot_radius)
    if foot_radius is None:  # the feet the replay's scene has (its meshes' round ends)
        moved = scene_robot(robot)
        robot = moved if moved is not as_whole_body(robot) else robot
    kind = default_kind(as_whole_body(robot))  # tracks the base's origin (servo), the CoM
    plan = replay.plan
    duration = float(plan["duration"])
    com = np.asarray(replay.run.com) if kind == "torque" else None
    motion = plan_motion(replay.planned, replay.turn_planned, com)
    walked = run(
        robot,
        pattern=str(plan["pattern"]["name"]),
        command=plan_command(motion, duration),
        duration=duration,
        kind=kind,
        friction=member.friction,
        bumps=member.bumps,
        seed=member.seed,
    )
    moved = float(np.hypot(motion[0], motion[1]))
    return ControlledRun(
        control=walked,
        distance_planned=moved,
        direction_planned=math.atan2(motion[1], motion[0]) if moved > 1e-9 else 0.0,
        turn_planned=float(replay.turn_planned),
    )
