"""Closed-loop walking in MuJoCo: the controller in the loop, disturbances, terrain, figures.

:func:`run` builds the scene of :func:`hexapod_kin.simulate.scene_mjcf` (the robot, foot
spheres, Coulomb friction, elliptic cones), then for the ``torque`` kind replaces each
position servo with a torque motor limited to the joint's effort (the scene's height-field
bumps: heights uniform in ``±bumps`` on a 50 mm grid, from ``seed``, flat within
:data:`FLAT_START` of the start) and runs the
:class:`~.controller.Controller` at its rate, the physics at the scene's time step.
The controller is fed what the robot senses (IMU attitude and body rates, joint positions
and velocities, foot contacts) and the base position and velocity: the simulator's, or
with ``estimate=True`` those of :class:`~.estimator.StateEstimator` (a contact-aided
Kalman filter on the accelerometer, the attitude and the legs' kinematics).

Pushes ``(force [N], start [s], duration [s])`` act at the body's centre of mass along the
path's left normal (a negative force pushes right), from the end of settling.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from .._fields import fields_dict
from .._pose import matrix_to_rpy
from ..exceptions import ParameterError, positive
from .commands import Command, Timeline
from .controller import Controller, Measurement
from .estimator import StateEstimator

__all__ = ["ControlRun", "Payload", "Push", "hardware_loop", "run", "scene_xml"]

#: Half-width [m] of the flat square around the start amid the bumps (the robot set down there).
FLAT_START = 0.3


@dataclass(frozen=True)
class Push:
    """A push: ``force`` [N] along the path's left normal from ``start`` for ``duration`` [s]."""

    force: float
    start: float
    duration: float

    @classmethod
    def parse(cls, text: str) -> Push:
        """``FORCE@START,DURATION`` (e.g. ``20@2,0.2``)."""
        try:
            f, rest = text.split("@")
            s, d = rest.split(",")
            out = cls(float(f), float(s), float(d))
        except ValueError:
            raise ParameterError(
                f"push {text!r}: FORCE@START,DURATION in N, s, s (e.g. 20@2,0.2)",
                parameter="push",
                value=text,
                allowed="FORCE@START,DURATION",
            ) from None
        for name, v in (("force", out.force), ("start", out.start), ("duration", out.duration)):
            if not math.isfinite(v) or (name != "force" and v < 0):
                raise ParameterError(
                    f"push {text!r}: {name} must be finite (times >= 0)",
                    parameter="push",
                    value=text,
                )
        return out


@dataclass(frozen=True)
class Payload:
    """A load fixed to the body: ``mass`` [kg] at ``at`` (x, y, z) [m] in the base frame.

    MuJoCo carries it as a welded body (a solid 0.1 m cube's inertia about its centre); the
    controller is not told of it: its weight, and its moments when ``at`` is off the centre,
    are a disturbance the feedback must hold.
    """

    mass: float
    at: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @classmethod
    def parse(cls, text: str) -> Payload:
        """``MASS`` or ``MASS@X,Y,Z`` (kg; m in the base frame; e.g. ``1.5@0.05,0,0.03``)."""
        try:
            m, _, rest = text.partition("@")
            at = tuple(float(v) for v in rest.split(",")) if rest else (0.0, 0.0, 0.0)
            if len(at) != 3:
                raise ValueError
            out = cls(float(m), (at[0], at[1], at[2]))
        except ValueError:
            raise ParameterError(
                f"payload {text!r}: MASS or MASS@X,Y,Z in kg and m (e.g. 1.5@0.05,0,0.03)",
                parameter="payload",
                value=text,
                allowed="MASS[@X,Y,Z]",
            ) from None
        out.check()
        return out

    def check(self) -> None:
        """Raise :class:`ParameterError` unless mass >= 0 is finite and ``at`` within 1 m."""
        at = tuple(self.at)
        if not (math.isfinite(self.mass) and self.mass >= 0):
            raise ParameterError(
                f"payload mass={self.mass!r}: a finite mass >= 0 kg",
                parameter="payload",
                value=self.mass,
            )
        if len(at) != 3 or not all(math.isfinite(v) and abs(v) <= 1.0 for v in at):
            raise ParameterError(
                f"payload at={self.at!r}: three finite coordinates within 1 m of the base",
                parameter="payload",
                value=self.at,
            )

    def add_to(self, xml: str) -> str:
        """``xml`` (a scene's MJCF) with the payload welded to its floating base body."""
        if self.mass == 0:
            return xml
        from lxml import etree

        root = etree.fromstring(xml.encode("utf-8"))
        base = next(b for b in root.iter("body") if b.find("freejoint") is not None)
        body = etree.SubElement(
            base, "body", name="payload", pos=" ".join(repr(float(v)) for v in self.at)
        )
        inertia = self.mass * 0.1**2 / 6  # a solid 0.1 m cube about its centre
        etree.SubElement(
            body,
            "inertial",
            pos="0 0 0",
            mass=repr(float(self.mass)),
            diaginertia=f"{inertia!r} {inertia!r} {inertia!r}",
        )
        return etree.tostring(root, encoding="unicode")


@dataclass(frozen=True)
class ControlRun:
    """A closed-loop walk and its figures (SI units; times from the end of settling).

    Attributes:
        t: (N,) control tick times [s].
        position: (N, 3) the tracked point (CoM for torque control, base for servos) [m].
        path: (N, 3) the reference path: x, y [m], yaw [rad].
        rpy: (N, 3) body roll, pitch, yaw [rad].
        end: (2,) where the tracked point ends [m]: the path's end plus its mean offset from
            the path over the last gait cycle (the steps' surge and sway left out).
        travel: Horizontal distance walked [m]: from the start to the end of the path plus
            the tracked point's mean offset from the path over the last gait cycle (the
            steps' surge and sway within a cycle left out); along the path when it turns.
        travel_planned: Length of the commanded path [m].
        heading_error: Max |yaw − path yaw| [rad].
        max_roll: Max |roll| [rad].
        max_pitch: Max |pitch| [rad].
        max_path_error: Max cross-track distance to the path [m].
        fell: The body fell (the tracked point below 40 % of its standing height above the
            feet, or tilted past 60°).
        non_foot_contacts: ``(geom, geom, first time)`` of each pair in contact that is not
            a foot on the ground.
        swing_strikes: ``(leg, time)`` of each swing foot touching in the first half of its
            swing.
        recovery_time: Per push, the time after it ends until the cross-track error stays
            under ``recovery_tolerance`` [s] (None: never).
        recovery_tolerance: [m].
        velocity_error: Per command segment, the mean velocity error relative to the
            command (None for a zero command).
        kind: ``torque`` or ``servo``.
        pattern: The final gait pattern.
        tick_cpu: Median CPU time of a controller tick [s].
        qp_cpu: Mean CPU time of the force QP per tick [s].
        cpu_time: CPU time of the whole run [s].
        simulated: Simulated time [s].
        settings: The run's arguments.
        estimate_error: With ``estimate``: the state estimate's errors against the
            simulator's state, from the end of settling: ``horizontal_final`` and
            ``horizontal_max`` [m] (the drift of the unobservable x, y), ``height_max`` [m],
            ``velocity_rms`` and ``velocity_max`` [m/s]; else None.

    """

    t: np.ndarray
    position: np.ndarray
    path: np.ndarray
    rpy: np.ndarray
    end: np.ndarray
    travel: float
    travel_planned: float
    heading_error: float
    max_roll: float
    max_pitch: float
    max_path_error: float
    fell: bool
    non_foot_contacts: tuple[tuple[str, str, float], ...]
    swing_strikes: tuple[tuple[str, float], ...]
    recovery_time: tuple[float | None, ...]
    recovery_tolerance: float
    velocity_error: tuple[float | None, ...]
    kind: str
    pattern: str
    tick_cpu: float
    qp_cpu: float
    cpu_time: float
    simulated: float
    settings: dict[str, Any] = field(default_factory=dict)
    estimate_error: dict[str, float] | None = None

    @property
    def travel_error(self) -> float | None:
        """(travel − planned) / planned (None when the path does not translate)."""
        if self.travel_planned < 1e-6:
            return None
        return (self.travel - self.travel_planned) / self.travel_planned

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (no time series)."""
        names = (
            "travel",
            "travel_planned",
            "travel_error",
            "heading_error",
            "max_roll",
            "max_pitch",
            "max_path_error",
            "fell",
            "non_foot_contacts",
            "swing_strikes",
            "recovery_time",
            "recovery_tolerance",
            "velocity_error",
            "kind",
            "pattern",
            "tick_cpu",
            "qp_cpu",
            "cpu_time",
            "simulated",
            "settings",
            "estimate_error",
        )
        return fields_dict(self, *names)


def scene_xml(scene: Any, kind: str) -> str:
    """The MJCF of ``scene`` (:func:`~hexapod_kin.simulate.scene.scene_mjcf`) for ``kind``.

    The torque kind replaces each position servo with a torque motor limited to the joint's
    effort; the servo kind keeps the scene as it is.
    """
    from lxml import etree

    root = etree.fromstring(scene.xml.encode("utf-8"))
    if kind == "torque":
        act = root.find("actuator")
        for el in list(act):
            attrs = {"name": el.get("name"), "joint": el.get("joint")}
            if el.get("forcerange"):
                attrs.update(ctrlrange=el.get("forcerange"), ctrllimited="true")
            act.replace(el, etree.Element("motor", **attrs))
    return etree.tostring(root, encoding="unicode")


def _timeline(command: Any) -> Timeline:
    if isinstance(command, Timeline):
        return command
    if isinstance(command, Command):
        return Timeline.constant(command)
    if command is None:
        return Timeline.constant(Command())
    try:
        vx, vy, wz = (float(v) for v in command)
    except (TypeError, ValueError):
        raise ParameterError(
            f"command={command!r}: a Command, a Timeline or (vx, vy, wz)",
            parameter="command",
            value=repr(command),
        ) from None
    return Timeline.constant(Command(vx, vy, wz))


def default_kind(wb: Any) -> str:
    """:func:`run`'s default kind for the whole-body robot ``wb``.

    ``servo`` for a Hexapod preset (it has a table; the point tracked: the base's origin),
    ``torque`` else (the CoM).
    """
    return "servo" if wb.params is not None else "torque"


def run(
    robot: Any = None,
    *,
    pattern: str | None = None,
    command: Any = (0.2, 0.0, 0.0),
    duration: float = 10.0,
    kind: str | None = None,
    pushes: Sequence[Push] = (),
    bumps: float = 0.0,
    friction: float = 1.0,
    seed: int = 0,
    payload: Payload | None = None,
    settle: float = 0.5,
    rate: float | None = None,
    period: float | None = None,
    recovery_tolerance: float = 0.03,
    estimate: bool = False,
    lying: bool = False,
) -> ControlRun:
    """Walk ``robot`` under the controller in MuJoCo for ``duration`` [s] after ``settle``.

    Args:
        robot: The robot (None: the built-in hexapod).
        pattern: Starting gait (default ``tripod`` on six legs, ``trot`` on four, else
            ``wave``).
        command: A :class:`Command`, a :class:`Timeline` or ``(vx, vy, wz)`` [m/s, rad/s].
        duration: Walking time [s].
        kind: ``servo`` or ``torque`` (default: servo for a Hexapod preset, torque else).
        pushes: :class:`Push` disturbances.
        bumps: Height-field bump amplitude [m] (heights uniform in ``±bumps``; 0: flat).
        friction: Ground friction coefficient.
        seed: The bumps' random seed.
        payload: A :class:`Payload` fixed to the body (not told to the controller).
        settle: Standing time before the walk [s].
        rate: Control rate [Hz] (default the controller's).
        period: Gait cycle [s] (default the controller's).
        recovery_tolerance: Cross-track distance counted as back on the path [m].
        estimate: Feed the controller the base position and velocity of a
            :class:`~.estimator.StateEstimator` (IMU accelerometer and attitude, joints,
            foot contacts) instead of the simulator's; its errors go to
            :attr:`ControlRun.estimate_error`.
        lying: Start lying: the body resting on the ground (its lowest collision point
            1 mm above it), the feet on the ground under their neutral places; the
            controller raises the body to its standing height (its contacts with the ground
            while it rises are counted among ``non_foot_contacts``; a fall by height is
            counted once it has risen to 90 % of it).

    Returns:
        A :class:`ControlRun`.

    Raises:
        ParameterError: A bad value.

    """
    from ..gait import as_whole_body
    from ..simulate.scene import check_steps, scene_mjcf

    wb = as_whole_body(robot)
    if kind is None:
        kind = default_kind(wb)
    if pattern is None:
        pattern = {6: "tripod", 4: "trot"}.get(wb.n_legs, "wave")
    if not (math.isfinite(bumps) and 0 <= bumps <= 0.05):
        raise ParameterError(
            f"bumps={bumps!r}: an amplitude from 0 to 0.05 m", parameter="bumps", value=bumps
        )
    duration = positive("duration", duration)
    dt_phys = check_steps(1e-3, {"settle": settle, "duration": duration})
    timeline = _timeline(command)
    scene = scene_mjcf(
        robot, friction=friction, timestep=dt_phys, bumps=bumps, seed=seed, flat_start=FLAT_START
    )
    ctl = Controller(
        robot, kind=kind, pattern=pattern, rate=rate, period=period, armature=scene.armature
    )
    import mujoco as mj  # scene_mjcf has said how to install it when it is missing

    if payload is not None:
        payload.check()
    xml = scene_xml(scene, kind)
    model = mj.MjModel.from_xml_string(xml if payload is None else payload.add_to(xml))
    data = mj.MjData(model)
    joints = [mj.mj_name2id(model, mj.mjtObj.mjOBJ_JOINT, n) for n in scene.joint_names]
    jq = np.array([int(model.jnt_qposadr[j]) for j in joints])
    jv = np.array([int(model.jnt_dofadr[j]) for j in joints])
    act = np.array([mj.mj_name2id(model, mj.mjtObj.mjOBJ_ACTUATOR, a) for a in scene.actuators])
    foot_geom = np.array([mj.mj_name2id(model, mj.mjtObj.mjOBJ_GEOM, g) for g in scene.foot_geoms])
    leg_of = np.full(model.ngeom, -1)
    leg_of[foot_geom] = np.arange(len(foot_geom))
    ground = np.zeros(model.ngeom, dtype=bool)
    for name in ("ground", "bumps"):
        g = mj.mj_name2id(model, mj.mjtObj.mjOBJ_GEOM, name)
        if g >= 0:
            ground[g] = True
    base = int(model.jnt_bodyid[0])
    # start: neutral pose, feet on the ground
    q0 = np.asarray(wb.neutral_q(), dtype=float)
    feet0 = wb.feet(q0[None], np.eye(4)[None])[0]
    data.qpos[2] = -float(feet0[:, 2].min()) + scene.foot_radius + 1e-4
    data.qpos[3] = 1.0
    data.qpos[jq] = q0
    mj.mj_forward(model, data)
    stand_height = None
    if lying:
        q0 = _lie_down(mj, model, data, wb, jq, base, scene.foot_radius)
        # the height the controller holds: its tracked point's above the foot centres
        stand_height = ctl.height0 + (float(ctl.com_body[2]) if kind == "torque" else 0.0)
    if kind == "servo":
        data.ctrl[act] = q0
    mj.mj_forward(model, data)
    sub = max(1, int(round(1.0 / (ctl.rate * model.opt.timestep))))
    n_settle = int(round(settle * ctl.rate))
    n_walk = int(round(duration * ctl.rate))
    ctl.set_command(Command(mode="stand"))
    risen = not lying

    est = StateEstimator(ctl) if estimate else None
    est_err: list[tuple[float, float, float]] = []
    v_prev: np.ndarray | None = None

    def measure(t: float) -> Measurement:
        contacts = np.zeros(len(foot_geom), dtype=bool)
        for c in data.contact[: data.ncon]:
            g1, g2 = int(c.geom1), int(c.geom2)
            if leg_of[g1] >= 0 and ground[g2]:
                contacts[leg_of[g1]] = True
            elif leg_of[g2] >= 0 and ground[g1]:
                contacts[leg_of[g2]] = True
        return Measurement(
            t=t,
            quat=np.array(data.qpos[3:7]),
            gyro=np.array(data.qvel[3:6]),
            q=np.array(data.qpos[jq]),
            qd=np.array(data.qvel[jv]),
            contacts=contacts,
            position=np.array(data.qpos[:3]),
            velocity=np.array(data.qvel[:3]),
        )

    def label(g: int) -> str:
        name = mj.mj_id2name(model, mj.mjtObj.mjOBJ_GEOM, g)
        if name:
            return str(name)
        b = int(model.geom_bodyid[g])
        return f"{mj.mj_id2name(model, mj.mjtObj.mjOBJ_BODY, b)}/{g - int(model.body_geomadr[b])}"

    ts, pos, path, rpys, ticks = [], [], [], [], []
    others: dict[tuple[str, str], float] = {}
    strikes: dict[str, float] = {}
    fell = False
    was_down = np.ones(len(foot_geom), dtype=bool)
    cpu0 = time.process_time()
    for k in range(n_settle + n_walk):
        t = (k - n_settle) / ctl.rate
        if k >= n_settle:
            cmd = timeline.at(t)
            if cmd != ctl.command:
                ctl.set_command(cmd)
        m = measure(t)
        if not ctl.ready:
            ctl.reset(m, stand_height=stand_height)
        if est is not None:  # the controller sees the estimate, not the simulator's state
            if not est.ready:
                est.reset(m.position, m.velocity, m)
            # the accelerometer's specific force, averaged over the control period (as an
            # IMU's delta-velocity output is)
            R_b = np.array(data.xmat[base]).reshape(3, 3)
            acc = (m.velocity - (m.velocity if v_prev is None else v_prev)) * ctl.rate
            f_spec = R_b.T @ (acc + np.array([0.0, 0.0, 9.81]))
            v_prev = m.velocity
            p_est, v_est = est.update(m, f_spec)
            if k >= n_settle:
                est_err.append(
                    (
                        float(np.linalg.norm(p_est[:2] - m.position[:2])),
                        abs(float(p_est[2] - m.position[2])),
                        float(np.linalg.norm(v_est - m.velocity)),
                    )
                )
            m = replace(m, position=p_est, velocity=v_est)
        c0 = time.process_time()
        u = ctl.tick(m)
        ticks.append(time.process_time() - c0)
        data.ctrl[act] = u
        R = np.array(data.xmat[base]).reshape(3, 3)
        data.xfrc_applied[base] = 0.0
        for p in pushes:
            if p.start <= t < p.start + p.duration:
                n = _rz_col(ctl.path_yaw)
                data.xfrc_applied[base, :3] += p.force * n
        for _ in range(sub):
            mj.mj_step(model, data)
        if k < n_settle:
            continue
        st_point = np.array(data.subtree_com[base]) if kind == "torque" else np.array(data.qpos[:3])
        ts.append(t)
        pos.append(st_point)
        path.append([*ctl.path_xy, ctl.path_yaw])
        roll, pitch, yaw = matrix_to_rpy(R)
        rpys.append((roll, pitch, yaw))
        # the tracked point's height, as the controller's standing height is (a base frame at
        # ground level, as Kraby's, is not a fallen body)
        height = float(st_point[2]) - ctl.ground_z
        risen = risen or height > 0.9 * ctl.stand_height
        if (risen and height < 0.4 * ctl.stand_height) or abs(roll) > 1.05 or abs(pitch) > 1.05:
            fell = True
        down = np.zeros(len(foot_geom), dtype=bool)
        for c in data.contact[: data.ncon]:
            g1, g2 = int(c.geom1), int(c.geom2)
            if (leg_of[g1] >= 0 and ground[g2]) or (leg_of[g2] >= 0 and ground[g1]):
                down[int(max(leg_of[g1], leg_of[g2]))] = True
                continue
            a, b = sorted((label(g1), label(g2)))
            others.setdefault((a, b), t)
        # a strike: a foot that was off the ground touching in the first half of its swing
        for leg in np.flatnonzero(down & ~was_down & ctl.in_swing & (ctl.swing_s < 0.5)):
            strikes.setdefault(wb.leg_names[leg], t)
        was_down = down
    cpu = time.process_time() - cpu0
    T = np.array(ts)
    P = np.array(pos)
    PA = np.array(path)
    RPY = np.array(rpys)
    yaws = np.unwrap(RPY[:, 2])
    d = P[:, :2] - PA[:, :2]
    normal = np.stack([-np.sin(PA[:, 2]), np.cos(PA[:, 2])], axis=1)
    cross = np.abs((d * normal).sum(axis=1))
    start = P[0, :2]
    end_xy = _end_point(P, PA, int(round(ctl.period * ctl.rate)))
    travel = float(np.linalg.norm(end_xy - start))
    seg = np.diff(PA[:, :2], axis=0)
    planned = float(np.linalg.norm(PA[-1, :2] - PA[0, :2]))
    if abs(PA[-1, 2] - PA[0, 2]) > 1e-6:  # a turning path: its length
        planned = float(np.linalg.norm(seg, axis=1).sum())
        travel = float(np.linalg.norm(np.diff(P[:, :2], axis=0), axis=1).sum())
    recovery: list[float | None] = []
    for p in pushes:
        end = p.start + p.duration
        after = T >= end
        bad = np.flatnonzero(after & (cross > recovery_tolerance))
        if not after.any():
            recovery.append(None)
        elif len(bad) == 0:
            recovery.append(0.0)
        elif bad[-1] == len(T) - 1:
            recovery.append(None)
        else:
            recovery.append(float(T[bad[-1] + 1] - end))
    vel_err = _velocity_errors(timeline, T, P, yaws, PA, ctl.period, duration)
    tick = np.array(ticks)
    errs = np.array(est_err).reshape(-1, 3)
    return ControlRun(
        t=T,
        position=P,
        path=PA,
        rpy=RPY,
        end=end_xy,
        travel=travel,
        travel_planned=planned,
        heading_error=float(np.abs(yaws - yaws[0] - (PA[:, 2] - PA[0, 2])).max()),
        max_roll=float(np.abs(RPY[:, 0]).max()),
        max_pitch=float(np.abs(RPY[:, 1]).max()),
        max_path_error=float(cross.max()),
        fell=fell,
        non_foot_contacts=tuple((a, b, t) for (a, b), t in others.items()),
        swing_strikes=tuple(strikes.items()),
        recovery_time=tuple(recovery),
        recovery_tolerance=recovery_tolerance,
        velocity_error=tuple(vel_err),
        kind=kind,
        pattern=ctl.pattern,
        tick_cpu=float(np.median(tick)),
        qp_cpu=ctl.qp_time / max(1, len(tick)),
        cpu_time=cpu,
        simulated=settle + duration,
        settings={
            "robot": str(wb.source),
            "rate": ctl.rate,
            "period": ctl.period,
            "bumps": bumps,
            "seed": seed,
            "friction": friction,
            "payload": None if payload is None else fields_dict(payload, "mass", "at"),
            "pushes": [fields_dict(p, "force", "start", "duration") for p in pushes],
            "estimate": estimate,
            **timeline.to_dict(),
        },
        estimate_error=None
        if est is None
        else {
            "horizontal_final": float(errs[-1, 0]),
            "horizontal_max": float(errs[:, 0].max()),
            "height_max": float(errs[:, 1].max()),
            "velocity_rms": float(np.sqrt((errs[:, 2] ** 2).mean())),
            "velocity_max": float(errs[:, 2].max()),
        },
    )


def _lie_down(
    mj: Any, model: Any, data: Any, wb: Any, jq: np.ndarray, base: int, foot_radius: float
) -> np.ndarray:
    """Put the robot lying; its joints [rad].

    The body's lowest point 1 mm above z = 0, the feet on the ground under their neutral
    places (the legs by the whole body's ``body_ik``).
    """
    q0 = np.asarray(wb.neutral_q(), dtype=float)
    lowest = np.inf
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    for g in range(model.ngeom):
        if int(model.geom_bodyid[g]) != base:
            continue
        c, h = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
        R = np.array(data.geom_xmat[g]).reshape(3, 3)
        corners = data.geom_xpos[g] + (c + h * signs) @ R.T
        lowest = min(lowest, float(corners[:, 2].min()))
    z = float(data.qpos[2]) - lowest + 1e-3
    B = np.eye(4)
    B[2, 3] = z
    feet = wb.feet(q0[None], np.eye(4)[None])[0]
    feet[:, 2] = foot_radius + 1e-4
    ik = wb.body_ik(B, feet, q_prev=q0, strict=False)
    q = np.asarray(ik.q[0], dtype=float)
    data.qpos[2] = z
    data.qpos[jq] = q
    return q


def _end_point(position: np.ndarray, path: np.ndarray, cycle: int) -> np.ndarray:
    """Where the tracked point ends (2,) [m], its steps' surge and sway left out.

    The path's end plus the point's offset from the path averaged over the last ``cycle``
    samples (one gait cycle). A step's surge and sway within a cycle (up to a centimetre
    either way) is not distance walked; sampled at the last tick it would be, by the phase
    at which the walk stops.
    """
    last = slice(max(0, len(position) - max(1, cycle)), len(position))
    return np.asarray(path[-1, :2] + (position[last, :2] - path[last, :2]).mean(axis=0))


def _rz_col(yaw: float) -> np.ndarray:
    return np.array([-math.sin(yaw), math.cos(yaw), 0.0])


def _velocity_errors(
    timeline: Timeline,
    T: np.ndarray,
    P: np.ndarray,
    yaw: np.ndarray,
    path: np.ndarray,
    period: float,
    duration: float,
) -> list[float | None]:
    """Per command segment (its first cycle left out): |mean twist − command| / |command|.

    The twist is (vx, vy) in the heading frame and wz; a turn's size counts ``wz`` times the
    robot's ... radius-free: the error and the command are compared as (vx, vy, wz) vectors.
    """
    out: list[float | None] = []
    times = [t for t, _ in timeline.entries] + [duration]
    for (t0, cmd), t1 in zip(timeline.entries, times[1:]):
        a, b = t0 + period, t1
        sel = np.flatnonzero((T >= a) & (T <= b))
        ref = np.array([cmd.vx, cmd.vy, cmd.wz]) if cmd.mode == "walk" else np.zeros(3)
        if len(sel) < 2 or not np.linalg.norm(ref) > 0:
            out.append(None)
            continue
        i, j = sel[0], sel[-1]
        h = T[j] - T[i]
        dyaw = (yaw[j] - yaw[i]) / h
        mid = 0.5 * (path[i, 2] + path[j, 2])
        c, s = math.cos(mid), math.sin(mid)
        dx, dy = (P[j, :2] - P[i, :2]) / h
        meas = np.array([c * dx + s * dy, -s * dx + c * dy, dyaw])
        out.append(float(np.linalg.norm(meas - ref) / np.linalg.norm(ref)))
    return out


def hardware_loop(
    controller: Controller,
    sense: Callable[[], Measurement],
    act: Callable[[np.ndarray], None],
    ticks: int,
    timeline: Timeline | None = None,
    wait: Callable[[float], None] | None = None,
) -> int:
    """Run ``controller`` on hardware: ``ticks`` times sense → tick → act.

    ``sense()`` returns the robot's :class:`Measurement`, ``act(u)`` sends the torques or
    servo targets; ``wait(dt)`` (e.g. a rate keeper) is called after each tick with the
    control period [s]. The commands follow ``timeline`` by the measurement's time.
    Returns the number of ticks run.
    """
    for _ in range(int(ticks)):
        m = sense()
        if timeline is not None:
            cmd = timeline.at(m.t)
            if cmd != controller.command:
                controller.set_command(cmd)
        act(controller.tick(m))
        if wait is not None:
            wait(controller.dt)
    return int(ticks)
