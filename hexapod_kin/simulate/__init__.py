"""A planned walk replayed open-loop in MuJoCo: does the physics do what the plan says.

:func:`simulate` takes a :class:`~hexapod_kin.gait.walk.GaitRun` (or a robot and the keywords
of :func:`~hexapod_kin.gait.walk.walk`, and plans it), builds a MuJoCo scene and replays the
plan's joint angles:

* **Scene** (:func:`scene_mjcf`): the robot's MJCF (:func:`hexapod_kin.export.to_mjcf` with a
  free base), each foot a contact sphere of the robot's ``foot_radius`` centred on the foot
  point, the terrain as MuJoCo geoms (``flat``: the plane z = 0; ``slope``: the plane through
  the origin rising 8° along +x; ``step``: the plane z = 0 and a 0.02 m box beyond
  x = 0.25 m — the geometry of :mod:`hexapod_kin.gait.terrain`), Coulomb friction ``friction``
  on every geom (no rolling or torsional friction: a round foot rolls), and a position
  actuator per leg joint: ``τ = kp (u − q) − kv q̇`` clamped to the joint's effort limit.
  The control is ``u = q_ref + (kv / kp) q̇_ref + τ_ref / kp``, so the actuator is the PD
  law with a feed-forward torque ``kp (q_ref − q) + kv (q̇_ref − q̇) + τ_ref`` on the plan
  (cubic Hermite between its samples; ``τ_ref`` linear): ``τ_ref`` the plan's quasi-static
  joint torques (:func:`hexapod_kin.dynamics.gait_torques`: the weight shared by the
  stance feet), so that the servos hold the planned angles under the planned load — a bare
  PD servo gives way by ``τ / kp``, and the load passing from leg to leg then walks the
  body back by 1-2 % of its travel (``feedforward=False`` replays without it).
  Integrator ``implicitfast`` (the damping implicit), time step ``timestep``; elliptic
  friction cones with ``impratio = 10`` (MuJoCo's soft friction otherwise lets a loaded
  foot creep: 1.9 % lost up the 8° slope with pyramidal cones), joint ``armature`` for the
  servos' rotor inertia, contact ``solref`` time constant ``contact_time``.
* **Start**: the free base at the plan's first pose, raised so that the stance feet's
  spheres touch the ground (the vertical shift ``lift`` [m], 0 when the plan already
  puts the sphere centres one radius above the ground); the joints held at the first
  sample (and its torques) for ``settle`` [s]; then the plan, from its first sample and
  at its first velocities (the body's twist, the joints' rates: the plan walks from t = 0,
  its stance feet at rest; a robot let go at rest is jerked to speed and slides).
* **The robot's own body** (:mod:`.collision`): feet of the radius the foot links'
  collision shapes give when the robot names none (planned and simulated alike), mesh
  collisions of body and legs as convex hulls; the servo armature of
  :func:`~.scene.servo_defaults` (a URDF has none); a physics step small enough for the
  servos' stability (:func:`scene_mjcf`); optional random bumps on flat ground.
* **Report** (:class:`SimRun`), over the replay, against the plan shifted by ``lift``:
  distance travelled along the planned direction (the body's horizontal displacement
  projected on the plan's) vs planned, and the direction; the yaw turned vs planned; the
  heading (yaw) error, max over time; max roll and pitch; body height error; stance-foot
  slip (the velocity of the foot's material point at its contact point, tangential part,
  integrated over each planned stance, across contact breaks: a rolling foot does not
  slip); every contact that is not foot-on-ground (geom labels ``body/index``); and the
  per-foot contact forces of the robot standing at its own gains (:func:`stand_forces`)
  against :func:`hexapod_kin.dynamics.stand`.

:meth:`SimRun.checks` is the verdict (limits in :data:`LIMITS`); a *stumble* is a non-foot
contact, a swing foot striking the ground (coming down on it where the plan has the sphere
at least :data:`STRIKE_CLEARANCE` = 2 mm clear), roll or pitch over 1°, or a stance foot
sliding more than ``LIMITS["slip"]`` = 5 mm in one stance. :mod:`hexapod_kin.robust`
judges a plan over an ensemble of simulator settings.

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
