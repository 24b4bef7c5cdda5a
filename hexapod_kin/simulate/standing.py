"""The robot standing in MuJoCo: per-foot contact forces against :func:`dynamics.stand`."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .._fields import fields_dict, read_only
from ..exceptions import ParameterError, positive
from .scene import SimScene, _Engine, _robot, check_steps, scene_mjcf, servo_defaults

__all__ = ["STAND_SETTLE", "StandForces", "stand_forces"]

#: The simulated time [s] of :func:`stand_forces` (its ``settle``'s default).
STAND_SETTLE = 2.0


@dataclass(frozen=True)
class StandForces:
    """Per-foot contact forces of the robot standing in MuJoCo vs :func:`dynamics.stand`.

    ``forces`` (L, 3): MuJoCo's on each stance foot (``legs``), world frame [N], mean over the
    last 0.2 s; ``expected``: ``stand()``'s [N]; ``weight`` ``m g`` [N]; ``height`` of the
    stance's body [m] (foot points at the ground).
    """

    legs: tuple[str, ...]
    forces: np.ndarray
    expected: np.ndarray
    weight: float
    height: float

    @property
    def max_error(self) -> float:
        """Largest per-foot difference, the norm of the force vectors' difference [N]."""
        return float(np.linalg.norm(self.forces - self.expected, axis=-1).max())

    @property
    def max_normal_error(self) -> float:
        """Largest per-foot difference of the vertical components [N]."""
        return float(np.abs(self.forces[:, 2] - self.expected[:, 2]).max())

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (SI units)."""
        names = ("legs", "forces", "expected", "max_error", "max_normal_error", "weight")
        return fields_dict(self, *names, "height")


def stand_forces(
    robot: Any = None,
    *,
    scene: SimScene | None = None,
    settle: float = STAND_SETTLE,
    **scene_options: Any,
) -> StandForces:
    """The robot standing in MuJoCo at :func:`hexapod_kin.dynamics.stand`'s pose, flat ground.

    The base level at the stance's height with the stance spheres on the ground, the joints
    held at the stance's angles; after ``settle`` seconds each foot's contact force (mean over
    the last 0.2 s) is compared with the stance's. The servos hold at a tenth of the robot's
    gains (:func:`~.scene.servo_defaults`) for the first half of ``settle``, so that the load
    spreads as the stance shares it (stiff servos keep the internal forces friction locks in
    at touch-down), then ramp to them over a quarter; no armature unless asked.

    ``robot`` and ``**scene_options`` as :func:`scene_mjcf` (``armature`` defaults to 0 here),
    or a flat :class:`SimScene` ``scene``; ``settle`` > 0.2 [s] (at most
    ``dynamics.MAX_STEPS`` timesteps).

    Raises:
        ParameterError: Bad values, a scene that is not flat, too many physics steps.
        OptionalDependencyError: MuJoCo is not installed.

    """
    from ..dynamics import stand
    from ..kinematics import load
    from ..params import Hexapod

    dur = positive("settle", settle)
    check_steps(
        scene_options.get("timestep") or 1e-3 if scene is None else scene.timestep, {"settle": dur}
    )
    wb = _robot(robot, scene_options.get("feet"))
    scene_options.setdefault("armature", 0.0)
    kp, kv, _ = servo_defaults(wb)
    scene_options.setdefault("kp", kp)
    scene_options.setdefault("kv", kv)
    sc = scene_mjcf(wb, **scene_options) if scene is None else scene
    if sc.terrain != "flat":
        raise ParameterError(
            f"stand_forces needs a flat scene, not {sc.terrain!r}", parameter="scene"
        )
    st = stand(load(wb.params) if isinstance(wb.params, Hexapod) else wb)
    eng = _Engine(sc)
    q = np.asarray(st.q, dtype=float)[[list(st.joint_names).index(j) for j in sc.joint_names]]
    pose = np.eye(4)
    pose[2, 3] = st.height
    eng.place(pose, q)
    stance = [list(sc.leg_names).index(n) for n in st.stance_legs]
    centres = eng.data.geom_xpos[eng.feet[stance], 2]
    pose[2, 3] += sc.foot_radius - float(centres.mean())  # the stance spheres on the ground
    eng.place(pose, q)
    steps = int(round(dur / sc.timestep))
    tail = max(1, int(round(0.2 / sc.timestep)))
    acc = np.zeros((len(sc.leg_names), 3))
    m = eng.model
    gain0, bias0 = m.actuator_gainprm[:, 0].copy(), m.actuator_biasprm[:, 1:3].copy()
    for k in range(steps):
        scale = min(1.0, 0.1 + 0.9 * max(0.0, (k / steps - 0.5) / 0.25))
        m.actuator_gainprm[:, 0] = scale * gain0
        m.actuator_biasprm[:, 1:3] = scale * bias0
        eng.mj.mj_step(m, eng.data)
        if k >= steps - tail:
            acc += eng.contact_forces()
    mine, expected = (acc / tail)[stance], np.asarray(st.forces, dtype=float).copy()
    read_only(mine, expected)
    return StandForces(tuple(st.stance_legs), mine, expected, float(st.weight), float(st.height))
