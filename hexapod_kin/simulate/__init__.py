"""A planned walk replayed open-loop in MuJoCo: does the physics do what the plan says.

:func:`simulate` takes a :class:`~hexapod_kin.gait.walk.GaitRun` (or a robot and the keywords
of :func:`~hexapod_kin.gait.walk.walk`, and plans it), builds a MuJoCo scene and replays the
plan's joint angles:

* **Scene** (:func:`scene_mjcf`): the robot's MJCF with a free base
  (:func:`hexapod_kin.export.to_mjcf`), a contact sphere per foot, the terrain of
  :mod:`hexapod_kin.gait.terrain` as geoms, Coulomb friction (no rolling friction: a round
  foot rolls), elliptic cones, integrator ``implicitfast``, and a position servo per leg
  joint: ``τ = kp (q_ref − q) + kv (q̇_ref − q̇) + τ_ref`` clamped to the effort limit, on the
  plan (cubic Hermite between samples) with the plan's quasi-static torques as feed-forward
  (:func:`hexapod_kin.dynamics.gait_torques`; a bare PD servo gives way by ``τ / kp`` and the
  body walks back by 1-2 % of its travel; ``feedforward=False`` replays without it).
* **Start**: the free base at the plan's first pose, raised by ``lift`` so that the stance
  spheres touch the ground; the joints held at the first sample for ``settle`` [s]; then the
  plan at its first velocities (a robot let go at rest is jerked to speed and slides).
* **The robot's own body** (:mod:`.collision`): foot radius from the foot links' collision
  shapes when the robot names none, mesh collisions as convex hulls, the servo armature of
  :func:`~.scene.servo_defaults`, a physics step small enough for the servos, optional bumps.
* **Report** (:class:`SimRun`), against the plan shifted by ``lift``: travel along the
  planned direction, yaw turned, heading error, roll and pitch, body height error,
  stance-foot slip (of the contact point, over each planned stance), every contact that is
  not foot-on-ground, and the standing forces at the robot's own gains
  (:func:`stand_forces`) against :func:`hexapod_kin.dynamics.stand`.

:meth:`SimRun.checks` is the verdict (limits in :data:`LIMITS`); a *stumble* is a non-foot
contact, a swing foot striking the ground where the plan has it at least
:data:`STRIKE_CLEARANCE` clear, roll or pitch over 1°, or a stance foot sliding more than
``LIMITS["slip"]`` in one stance. :mod:`hexapod_kin.robust` judges a plan over an ensemble of
simulator settings.

MuJoCo is the optional extra ``hexapod-kin[export]`` (MuJoCo 3.14 or later, or 4).
"""

from __future__ import annotations

from .page import simulation_html
from .replay import LIMITS, STRIKE_CLEARANCE, SimRun, simulate
from .scene import POINT_FOOT, SCENE_TERRAINS, SimScene, scene_mjcf
from .standing import StandForces, stand_forces

__all__ = [
    "LIMITS",
    "POINT_FOOT",
    "SCENE_TERRAINS",
    "STRIKE_CLEARANCE",
    "SimRun",
    "SimScene",
    "StandForces",
    "scene_mjcf",
    "simulate",
    "simulation_html",
    "stand_forces",
]
