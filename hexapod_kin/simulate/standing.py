"""The robot standing in MuJoCo: per-foot normal forces against :func:`dynamics.stand`."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .._fields import fields_dict, read_only
from ..exceptions import ParameterError, positive
from .scene import SimScene, _Engine, _robot, check_steps, scene_mjcf

__all__ = ["STAND_SETTLE", "StandForces", "stand_forces"]

#: The simulated time [s] of :func:`stand_forces` (its ``settle``'s default).
STAND_SETTLE = 2.0


@dataclass(frozen=True)
class StandForces:
    """Per-foot normal forces of the robot standing in MuJoCo vs :func:`dynamics.stand`.

    Attributes:
        legs: The stance legs.
        forces: (L,) MuJoCo's normal force per foot [N] (mean over the last 0.2 s).
        expected: (L,) ``stand()``'s vertical force per foot [N].
        weight: ``m g`` [N].
        height: Body height of the stance [m] (foot points at the ground).

    """

    legs: tuple[str, ...]
    forces: np.ndarray
    expected: np.ndarray
    weight: float
    height: float

    @property
    def max_error(self) -> float:
        """Largest per-foot difference [N]."""
        return float(np.abs(self.forces - self.expected).max())

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (SI units)."""
        return fields_dict(self, "legs", "forces", "expected", "max_error", "weight", "height")


def _stance(wb: Any) -> Any:
    from ..dynamics import stand
    from ..params import Hexapod

    params = getattr(wb, "params", None)
    if isinstance(params, Hexapod):
        from ..kinematics import load

        return stand(load(params))
    return stand(wb)


def stand_forces(
    robot: Any = None,
    *,
    scene: SimScene | None = None,
    settle: float = STAND_SETTLE,
    **scene_options: Any,
) -> StandForces:
    """The robot standing in MuJoCo at :func:`hexapod_kin.dynamics.stand`'s pose, flat ground.

    The base is placed level at the stance's height, raised so that the stance feet's
    spheres touch the ground, the joints held at the stance's angles by the actuators;
    after ``settle`` seconds the normal force of each foot (mean over the last 0.2 s) is
    compared with the stance's vertical contact force.

    The servos have no armature here unless asked: with more feet than needed, MuJoCo's
    soft contacts share the load in proportion to each constraint's regularisation, which
    scales with the joint-space inertia; a rotor inertia of 0.002 kg·m² moves the built-in
    hexapod's shares by about 0.004 N (without it they are equal to 2e-4 N). The servos
    are soft here too (kp 300 N·m/rad, kv 3 N·m·s/rad unless asked, whatever the robot's
    walking gains): such a stance is statically indeterminate, and stiff servos keep the
    internal forces friction locks in at touch-down (erd:anymal at its walking kp of 12,800:
    85 N apart on a diagonal), soft ones let them relax to the shares ``stand()`` computes.

    Args:
        robot: As :func:`scene_mjcf`.
        scene: A flat :class:`SimScene` of the robot (default built from ``scene_options``).
        settle: Simulated time [s] (> 0.2; at most ``dynamics.MAX_STEPS`` timesteps).
        **scene_options: Passed to :func:`scene_mjcf` (``foot_radius``, ``kp``...;
            ``armature`` defaults to 0 here).

    Raises:
        ParameterError: Bad values, a scene that is not flat, too many physics steps.
        OptionalDependencyError: MuJoCo is not installed.

    """
    dur = positive("settle", settle)
    check_steps(
        scene_options.get("timestep", 1e-3) if scene is None else scene.timestep, {"settle": dur}
    )
    wb = _robot(robot, scene_options.get("feet"))
    scene_options.setdefault("armature", 0.0)
    scene_options.setdefault("kp", 300.0)
    scene_options.setdefault("kv", 3.0)
    sc = scene_mjcf(wb, **scene_options) if scene is None else scene
    if sc.terrain != "flat":
        raise ParameterError(
            f"stand_forces needs a flat scene, not {sc.terrain!r}", parameter="scene"
        )
    st = _stance(wb)
    eng = _Engine(sc)
    q = np.zeros(len(sc.joint_names))
    cols = [list(st.joint_names).index(j) for j in sc.joint_names]
    q[:] = np.asarray(st.q)[cols]
    pose = np.eye(4)
    pose[2, 3] = st.height
    eng.place(pose, q)
    stance = [list(sc.leg_names).index(n) for n in st.stance_legs]
    centres = eng.data.geom_xpos[eng.feet[stance], 2]
    pose[2, 3] += sc.foot_radius - float(centres.mean())  # the stance spheres on the ground
    eng.place(pose, q)
    steps = int(round(dur / sc.timestep))
    tail = max(1, int(round(0.2 / sc.timestep)))
    acc = np.zeros(len(sc.leg_names))
    for k in range(steps):
        eng.mj.mj_step(eng.model, eng.data)
        if k >= steps - tail:
            acc += eng.normal_forces()
    forces = acc / tail
    idx = [list(sc.leg_names).index(n) for n in st.stance_legs]
    mine, expected = forces[idx], np.asarray(st.forces)[:, 2].copy()
    read_only(mine, expected)
    return StandForces(
        legs=tuple(st.stance_legs),
        forces=mine,
        expected=expected,
        weight=float(st.weight),
        height=float(st.height),
    )
