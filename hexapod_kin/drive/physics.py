"""Physics mode: the robot in MuJoCo under the closed-loop controller, stepped live.

The scene is :func:`hexapod_kin.simulate.scene.scene_mjcf` (flat ground, foot spheres) in the
controller's kind (:func:`hexapod_kin.control.sim.scene_xml`), the controller
:class:`hexapod_kin.control.Controller` of the kind :func:`hexapod_kin.control.run` chooses
(``servo``, joint targets to position servos, for the built-in hexapod; ``torque``, joint
torques to motors limited to the joints' efforts, for any other legged robot, e.g.
``erd:solo12``), run through its public API as :func:`~hexapod_kin.control.run` runs it: the
robot starts in its neutral pose with the feet on the ground, each control tick senses
(:class:`~hexapod_kin.control.Measurement`: attitude, joints, foot contacts, base position and
velocity), ticks the controller and steps MuJoCo for one control period. A push is a
horizontal force on the base for :data:`PUSH_TIME` seconds. The ZMP drawn is the centre of
pressure of the ground's reaction on the robot (:meth:`Physics.zmp`, from MuJoCo's contact
forces).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..exceptions import ParameterError

__all__ = ["PUSH_TIME", "PUSH_WEIGHTS", "Physics", "default_pattern", "kind_of"]

#: Duration of a push [s].
PUSH_TIME = 0.1
#: The page's push, in the robot's weights, per controller kind: the hexapod's feet's friction
#: holds about one weight (two make it slide); the torque kind's quadrupeds (erd:solo12,
#: erd:anymal) recover from one, and two thrown at them while walking make them fall.
PUSH_WEIGHTS = {"servo": 2.0, "torque": 1.0}
#: MuJoCo's time step [s].
TIMESTEP = 1e-3


def _quat_matrix(w: float, x: float, y: float, z: float) -> np.ndarray:
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def kind_of(body: Any) -> str:
    """The controller's kind for ``body`` as :func:`~hexapod_kin.control.run` chooses it.

    ``servo`` for the built-in hexapod (a whole body with hexapod parameters), ``torque``
    for any other legged robot.
    """
    return "servo" if getattr(body, "params", None) is not None else "torque"


def default_pattern(body: Any) -> str:
    """The gait ``hexapod-kin control`` starts ``body`` with: tripod on six legs, trot on four.

    (:func:`hexapod_kin.control.run`'s default; else the first of the legs' patterns.)
    """
    from ..gait.tables import pattern_names

    names = pattern_names(body.n_legs, np.asarray(body.mounts)[:, :2, 3])
    best = {6: "tripod", 4: "trot"}.get(body.n_legs, "wave")
    return best if best in names else names[0]


class Physics:
    """One legged robot in MuJoCo under the closed-loop controller (see the module doc).

    Args:
        body: The :class:`~hexapod_kin.gait.robot.WholeBody` (with masses).
        pattern: The controller's starting gait pattern.

    Raises:
        OptionalDependencyError: MuJoCo or proxsuite is missing.
        ConfigurationError: A robot the controller cannot drive.

    """

    def __init__(self, body: Any, pattern: str) -> None:
        import mujoco as mj

        from ..control import Command, Controller
        from ..control.sim import scene_xml
        from ..simulate.scene import scene_mjcf

        self.mj, self.body = mj, body
        self.Command = Command
        #: The controller's kind, as :func:`~hexapod_kin.control.run` chooses it.
        self.kind = kind_of(body)
        self.ctl = Controller(body, kind=self.kind, pattern=pattern)
        scene = scene_mjcf(body, timestep=TIMESTEP)
        self.model = mj.MjModel.from_xml_string(scene_xml(scene, self.kind))
        self.data = mj.MjData(self.model)
        m, name2id, obj = self.model, mj.mj_name2id, mj.mjtObj
        joints = [name2id(m, obj.mjOBJ_JOINT, n) for n in scene.joint_names]
        self.jq = np.array([int(m.jnt_qposadr[j]) for j in joints])
        self.jv = np.array([int(m.jnt_dofadr[j]) for j in joints])
        self.act = np.array([name2id(m, obj.mjOBJ_ACTUATOR, a) for a in scene.actuators])
        feet = np.array([name2id(m, obj.mjOBJ_GEOM, g) for g in scene.foot_geoms])
        self.leg_of = np.full(m.ngeom, -1)
        self.leg_of[feet] = np.arange(len(feet))
        self.ground = np.zeros(m.ngeom, dtype=bool)
        self.ground[name2id(m, obj.mjOBJ_GEOM, "ground")] = True
        #: The ground plane's height [m] (the scene's plane geom).
        self.ground_z = float(m.geom_pos[name2id(m, obj.mjOBJ_GEOM, "ground"), 2])
        self._cop = np.zeros(3)  # over the last control period: Σ x·Fz − (z−h)·Fx, Σ y…, Σ Fz
        self._f6 = np.zeros(6)
        self.base_body = int(m.jnt_bodyid[0])
        #: The scene's foot sphere radius [m] (the robot's, or its foot links' shapes').
        self.foot_radius = float(scene.foot_radius)
        self.sub = max(1, int(round(1.0 / (self.ctl.rate * TIMESTEP))))
        q0 = np.asarray(body.neutral_q(), dtype=float)
        feet0 = body.feet(q0[None], np.eye(4)[None])[0]
        d = self.data
        d.qpos[2] = -float(feet0[:, 2].min()) + scene.foot_radius + 1e-4
        d.qpos[3] = 1.0
        d.qpos[self.jq] = q0
        if self.kind == "servo":
            d.ctrl[self.act] = q0
        mj.mj_forward(self.model, d)
        self.ctl.set_command(Command(mode="stand"))
        self.time = 0.0
        self._due = 0.0
        self._push = np.zeros(3)
        #: The end of the last push, in simulated time [s].
        self.push_until = -1.0
        #: The base velocity (3,) [m/s] when the last push began and when it ended (simulated
        #: time: what a loaded machine's clock does not change); None until then.
        self.push_velocities: tuple[np.ndarray, np.ndarray | None] | None = None

    @property
    def mass(self) -> float:
        """The robot's mass in the simulation [kg]."""
        return float(self.model.body_subtreemass[self.base_body])

    @property
    def push_force(self) -> float:
        """The page's push [N]: :data:`PUSH_WEIGHTS` of its kind × the robot's weight."""
        return PUSH_WEIGHTS[self.kind] * self.mass * float(-self.model.opt.gravity[2])

    def set_command(self, twist: tuple[float, float, float], pattern: str) -> None:
        """Walk at ``twist`` (vx, vy [m/s], wz [rad/s]; all zero: stand) with ``pattern``."""
        mode = "walk" if any(twist) else "stand"
        vx, vy, wz = (float(v) for v in twist)
        cmd = self.Command(vx=vx, vy=vy, wz=wz, pattern=pattern, mode=mode)
        if cmd != self.ctl.command:
            self.ctl.set_command(cmd)

    def push(self, force: Any) -> None:
        """Push the base with the horizontal ``force`` (fx, fy) [N] for :data:`PUSH_TIME`.

        Raises:
            ParameterError: Not two finite numbers.

        """
        f = np.asarray(force, dtype=float).reshape(-1)
        if f.shape != (2,) or not np.all(np.isfinite(f)):
            raise ParameterError(
                f"force={force!r} is not allowed; give (fx, fy) [N], two finite numbers",
                parameter="force",
                value=repr(force)[:80],
            )
        self._push = np.array([f[0], f[1], 0.0])
        self.push_until = self.time + PUSH_TIME
        self.push_velocities = (np.array(self.data.qvel[:3]), None)

    def contacts(self) -> np.ndarray:
        """(n_legs,) bool: the feet touching the ground in the simulation."""
        d = self.data
        contacts = np.zeros(len(self.body.leg_names), dtype=bool)
        for c in d.contact[: d.ncon]:
            g1, g2 = int(c.geom1), int(c.geom2)
            if self.leg_of[g1] >= 0 and self.ground[g2]:
                contacts[self.leg_of[g1]] = True
            elif self.leg_of[g2] >= 0 and self.ground[g1]:
                contacts[self.leg_of[g2]] = True
        return contacts

    def ground_reaction(self) -> tuple[np.ndarray, np.ndarray]:
        """The ground's contact forces on the robot now: points (K, 3) and forces (K, 3) [m, N].

        MuJoCo's contacts with the ground geom (``mj_contactForce``, the contact frame's rows
        in the world), each force turned to act on the robot (the geom that is not the ground).
        """
        mj, m, d = self.mj, self.model, self.data
        pts, forces = [], []
        for i in range(d.ncon):
            c = d.contact[i]
            g1, g2 = int(c.geom1), int(c.geom2)
            if not (self.ground[g1] or self.ground[g2]):
                continue
            mj.mj_contactForce(m, d, i, self._f6)
            f = np.asarray(c.frame).reshape(3, 3).T @ self._f6[:3]  # on geom2, from geom1
            forces.append(f if self.ground[g1] else -f)
            pts.append(np.array(c.pos))
        if not pts:
            return np.zeros((0, 3)), np.zeros((0, 3))
        return np.array(pts), np.array(forces)

    def zmp(self) -> np.ndarray | None:
        """The centre of pressure of the ground reaction over the last control period [m].

        On the ground plane ``z = h`` (:attr:`ground_z`), from the contact points ``p_i`` and
        forces ``F_i`` of every MuJoCo step of the period (:meth:`ground_reaction`):
        ``x = Σ(x_i F_zi − (z_i − h) F_xi) / Σ F_zi`` and the same for ``y`` — the point
        about which the reaction's moment has no horizontal part, i.e. the ZMP on flat ground.
        None while nothing pushes on the ground (before the first step, or airborne).
        """
        sx, sy, fz = self._cop
        if not fz > 1e-9:
            return None
        return np.array([sx / fz, sy / fz, self.ground_z])

    def _measure(self) -> Any:
        from ..control import Measurement

        d = self.data
        contacts = self.contacts()
        return Measurement(
            t=self.time,
            quat=np.array(d.qpos[3:7]),
            gyro=np.array(d.qvel[3:6]),
            q=np.array(d.qpos[self.jq]),
            qd=np.array(d.qvel[self.jv]),
            contacts=contacts,
            position=np.array(d.qpos[:3]),
            velocity=np.array(d.qvel[:3]),
        )

    def advance(self, dt: float) -> None:
        """Run the closed loop for ``dt`` [s] (whole control periods; the rest carried over)."""
        self._due += dt
        period = 1.0 / self.ctl.rate
        while self._due >= period - 1e-12:
            self._due -= period
            u = self.ctl.tick(self._measure())
            self.data.ctrl[self.act] = u
            self.data.xfrc_applied[self.base_body] = 0.0
            if self.time < self.push_until:
                self.data.xfrc_applied[self.base_body, :3] = self._push
            cop = np.zeros(3)
            for _ in range(self.sub):
                self.mj.mj_step(self.model, self.data)
                # the step's contact forces (its state before the integration)
                p, f = self.ground_reaction()
                if len(p):
                    h = p[:, 2] - self.ground_z
                    cop += (
                        float(np.sum(p[:, 0] * f[:, 2] - h * f[:, 0])),
                        float(np.sum(p[:, 1] * f[:, 2] - h * f[:, 1])),
                        float(np.sum(f[:, 2])),
                    )
            self._cop = cop
            self.time += period
            pv = self.push_velocities
            if pv is not None and pv[1] is None and self.time >= self.push_until - 1e-12:
                self.push_velocities = (pv[0], np.array(self.data.qvel[:3]))

    def state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q (nq,) the legs' joints [rad], worldMbody (4, 4), base velocity (3,) [m/s])."""
        d = self.data
        base = np.eye(4)
        base[:3, :3] = _quat_matrix(*(float(v) for v in d.qpos[3:7]))
        base[:3, 3] = d.qpos[:3]
        return np.array(d.qpos[self.jq]), base, np.array(d.qvel[:3])
