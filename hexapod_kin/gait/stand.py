"""Standing poses and the hexapod's body sway (feet kept on the ground).

:func:`standing_pose` stands any legged robot (any source :func:`~.robot.as_whole_body`
takes) level on flat ground: the body at ``height`` (default the robot's
:attr:`~.robot.WholeBody.body_height`), every foot's contact sphere on the ground under its
neutral point (:meth:`~.robot.WholeBody.neutral_feet`), legs by body-pose IK.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..exceptions import ParameterError, positive
from ..params import Hexapod
from .knee import knee_seed
from .legs import check_size
from .robot import WholeBody, as_whole_body, body_pose, leg_home

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model

__all__ = [
    "StandingPose",
    "default_configuration",
    "demo_trajectory",
    "frame_poses",
    "hexapod_sway",
    "standing_base",
    "standing_pose",
]


@dataclass(frozen=True)
class StandingPose:
    """A legged robot standing level on flat ground (z = 0, z up; SI units; arrays read-only).

    ``height`` of the body origin [m]; ``base`` (4, 4) ``worldMbody``; ``feet`` (L, 3) the
    contact spheres' centres (``foot_radius`` above the ground) and ``contacts`` (L, 3) the
    points on the ground [m].
    """

    robot: WholeBody
    height: float
    q: np.ndarray
    base: np.ndarray
    feet: np.ndarray
    contacts: np.ndarray


def standing_pose(
    robot: Any = None,
    *,
    height: float | None = None,
    reach: float | None = None,
    shift: Any = (0.0, 0.0),
    feet: Any = None,
    foot_radius: Any = None,
    knee: str | None = None,
) -> StandingPose:
    """Stand any legged robot level on flat ground (see the module doc for the rule).

    ``robot``: any :func:`~.robot.as_whole_body` takes (default the built-in hexapod).
    Lengths in [m]: ``height`` of the body origin (default the robot's ``body_height``;
    negative for a base frame below the ground, e.g. Kraby's belly; every leg's mount must be
    above the ground), ``reach`` mount to foot, horizontal (default the robot's own), ``shift``
    (dx, dy), ``foot_radius``. ``feet``: for a URDF without foot links (:func:`~.legs.parse_feet`);
    ``knee``: :data:`~.knee.KNEES` (default: the branch inside the joint limits nearest the
    robot's neutral q).

    Raises:
        ParameterError: Bad numbers; ``height``, ``reach`` or a ``shift`` component larger
            than :data:`~.legs.OFFSET_FACTOR` × the robot's size.
        GaitError: A foot out of reach or a joint beyond its limit (names the leg).

    """
    wb = as_whole_body(robot, feet=feet, foot_radius=foot_radius)
    h = wb.body_height if height is None else float(height)
    low = -float(np.min(wb.mounts[:, 2, 3]))  # the body frame may sit below its legs' mounts
    if not (math.isfinite(h) and h > low):
        raise ParameterError(
            f"height={h!r} m puts a leg's mount at or below the ground; give a height > "
            f"{low:.4g} m (the body frame's origin above the ground: the lowest mount is "
            f"{-low:.4g} m above it)",
            parameter="height",
            value=h,
            allowed=f"> {low:.4g}",
        )
    try:
        sh = np.asarray(shift, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        sh = np.full(1, np.nan)
    if sh.shape != (2,) or not np.all(np.isfinite(sh)):
        raise ParameterError(
            f"shift={shift!r}: two finite numbers dx, dy [m]", parameter="shift", value=shift
        )
    r = None if reach is None else positive("reach", reach, allow_zero=True)
    for name, v in (("height", h), ("reach", r), ("shift", float(np.abs(sh).max()))):
        if v is not None:  # refused before any IK (no overflow)
            check_size(v, wb.model, name)
    base = body_pose([0.0, 0.0, h])
    pts = wb.neutral_feet(r)
    pts[:, :2] -= sh
    pts[:, 2] = wb.foot_radius
    q_prev = None if knee is None else knee_seed(wb, knee, base, pts)
    q = np.array(wb.body_ik(base, pts, q_prev=q_prev, strict=True).q[0])
    contacts = pts.copy()
    contacts[:, 2] = 0.0
    for a in (q, base, pts, contacts):
        a.setflags(write=False)
    return StandingPose(wb, h, q, base, pts, contacts)


def frame_poses(
    model: Model, data: Any, qs: np.ndarray, base_poses: np.ndarray | None, frames: Sequence[str]
) -> np.ndarray:
    """World poses (K, F, 4, 4) of ``frames`` at configurations ``qs`` (K, nq).

    ``base_poses`` (K, 4, 4), when given, places the model's base in the world at each sample.
    ``data`` is a Pinocchio Data of ``model.model`` owned by the caller.
    """
    import pinocchio as pin

    ids = [model.frame_id(f) for f in frames]
    m = model.model
    out = np.empty((len(qs), len(ids), 4, 4))
    for i, q in enumerate(qs):
        pin.forwardKinematics(m, data, model.pinocchio_q(q))  # continuous: (cos, sin)
        for j, fid in enumerate(ids):
            out[i, j] = pin.updateFramePlacement(m, data, fid).homogeneous
    if base_poses is not None:
        out = np.einsum("kab,kfbc->kfac", base_poses, out)
    return out


def default_configuration(model: Model) -> np.ndarray:
    """The package's home pose (:func:`hexapod_kin.ik.home`), for display and demos.

    A hexapod's legs at :data:`hexapod_kin.ik.LEG_HOME` (clipped to the limits).
    """
    from .. import ik

    if not isinstance(model.params, Hexapod):
        home_of: Any = ik.home  # takes any loaded model
        return np.asarray(home_of(model), dtype=float)
    return leg_home(model.joint_names, model.lower, model.upper)


def standing_base(model: Model, q: np.ndarray) -> np.ndarray:
    """Body pose lifting a hexapod so that its lowest foot touches z = 0."""
    params = model.params
    if not isinstance(params, Hexapod):
        return np.eye(4)
    data = model.model.createData()
    feet = frame_poses(model, data, q[None, :], None, params.foot_frames)[0, :, :3, 3]
    return body_pose([0.0, 0.0, -float(feet[:, 2].min()) + 0.01])


#: Most samples of a demo motion (bounded work: a page of 1e5 frames is already some MB).
MAX_DEMO_SAMPLES = 100_000


def demo_trajectory(
    model: Model, duration: float = 4.0, samples: int = 121
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """A demo motion of any model: ``(times, qs, base_poses)``.

    A hexapod stands and sways its body (heave, roll, pitch) with its feet kept on the ground
    (closed-form leg IK when :mod:`hexapod_kin.ik` is available, else legs held still); any
    other model sweeps each joint sinusoidally within its limits (amplitude ≤ 0.6 rad or a
    quarter of the range, phases staggered).

    ``duration`` > 0 in [s]; ``samples`` from 2 to :data:`MAX_DEMO_SAMPLES`.

    Raises:
        ParameterError: Bad ``duration`` or ``samples``.

    """
    duration = positive("duration", duration)  # [s]
    if not isinstance(samples, int) or not 2 <= samples <= MAX_DEMO_SAMPLES:
        raise ParameterError(
            f"samples={samples!r} is not allowed; give an integer from 2 to {MAX_DEMO_SAMPLES}",
            parameter="samples",
            value=samples,
            allowed=(2, MAX_DEMO_SAMPLES),
        )

    times = np.linspace(0.0, float(duration), samples)
    phase = 2 * np.pi * times / duration
    q0 = default_configuration(model)
    if isinstance(model.params, Hexapod):
        return hexapod_sway(model, times, phase, q0)
    lo, hi = np.asarray(model.lower), np.asarray(model.upper)
    span = np.where(np.isfinite(hi - lo), hi - lo, 2 * np.pi)
    amp = np.minimum(0.6, span / 4)
    amp = np.where(model.is_prismatic, np.minimum(span / 4, 0.05 + 0 * span), amp)
    offsets = np.arange(model.nq) * np.pi / max(model.nq, 1)
    qs = q0[None, :] + amp[None, :] * np.sin(phase[:, None] + offsets[None, :])
    return times, np.clip(qs, lo, hi), None


def hexapod_sway(
    model: Model, times: np.ndarray, phase: np.ndarray, q0: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The hexapod sways its body (heave, roll, pitch, yaw) with its feet fixed in the world.

    Returns ``(times, qs, base_poses)``; the legs by :meth:`~.robot.WholeBody.body_ik`.
    """
    import pinocchio as pin

    stand = standing_base(model, q0)
    h = float(stand[2, 3])
    base = np.empty((len(times), 4, 4))
    for i, ph in enumerate(phase):
        T = body_pose([0.012 * math.sin(ph), 0.012 * math.cos(ph), h + 0.012 * math.sin(2 * ph)])
        R = pin.rpy.rpyToMatrix(0.08 * math.sin(ph), 0.08 * math.cos(ph), 0.1 * math.sin(ph))
        T[:3, :3] = R
        base[i] = T
    wb = as_whole_body(model)  # the legs of the same robot
    cols = [wb.joint_names.index(name) for name in model.joint_names]
    q_wb = np.empty(wb.nq)
    q_wb[cols] = q0
    feet = wb.feet(q_wb[None], stand[None])[0]  # fixed in the world where the stance puts them
    qs = np.asarray(wb.body_ik(base, feet, q_prev=q_wb, strict=False).q)[:, cols]
    return times, np.clip(qs, model.lower, model.upper), base
