"""The replay: a plan's joint angles driven open-loop in MuJoCo, and the figures of merit."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from .._fields import fields_dict
from ..exceptions import ConfigurationError, ParameterError, UrdfError, one_of
from .collision import scene_robot
from .scene import (
    POINT_FOOT,
    SCENE_TERRAINS,
    SimScene,
    _Engine,
    _joints,
    _mujoco,
    _robot,
    check_steps,
    scene_foot_radius,
    scene_mjcf,
)
from .standing import STAND_SETTLE, StandForces, stand_forces

__all__ = ["LIMITS", "STRIKE_CLEARANCE", "SimRun", "Travel", "simulate"]

#: The check's limits: travel (relative), heading [rad], roll and pitch [rad], slip in one
#: contact [m], body height error [m].
LIMITS: dict[str, float] = {
    "travel": 0.01,
    "heading": math.radians(0.5),
    "tilt": math.radians(1.0),
    "slip": 0.005,
    "height": 0.01,
}

#: A swing foot touching the ground where the plan has its sphere at least this far from it
#: [m] (along the normal, less the body's sinking while settling; plus twice the bumps) is a
#: strike.
STRIKE_CLEARANCE = 0.002


class Travel:
    """A walk's travel against its plan, in figures and words (a replay's, a controlled walk's).

    From the ``distance``, ``distance_planned``, ``direction_error``, ``turn`` and
    ``turn_planned`` of the class using it.
    """

    if TYPE_CHECKING:  # given by the class using it (fields or properties)

        @property
        def distance(self) -> float: ...  # noqa: D102
        @property
        def distance_planned(self) -> float: ...  # noqa: D102
        @property
        def direction_error(self) -> float: ...  # noqa: D102
        @property
        def turn(self) -> float: ...  # noqa: D102
        @property
        def turn_planned(self) -> float: ...  # noqa: D102
        def checks(self) -> dict[str, dict[str, Any]]: ...  # noqa: D102

    @staticmethod
    def judged(rows: dict[str, tuple[float, float]]) -> dict[str, dict[str, Any]]:
        """``{check: (value, limit)}`` as checks: ``{check: {value, limit, ok}}`` (ok: ≤)."""
        return {k: {"value": v, "limit": li, "ok": bool(v <= li)} for k, (v, li) in rows.items()}

    @property
    def distance_along(self) -> float:
        """The simulated displacement along the planned one [m] (< 0: went backwards)."""
        return self.distance * math.cos(self.direction_error)

    @property
    def direction(self) -> str:
        """Where the body went relative to the plan's direction, in words."""
        if self.distance_planned < 1e-6 or self.distance < 1e-9:
            return "-"
        deg = math.degrees(self.direction_error)
        if deg <= 10.0:
            return f"as planned ({deg:.2f} deg off)"
        return f"{deg:.1f} deg off the planned direction" + (" (backwards)" if deg > 90 else "")

    @property
    def distance_error(self) -> float | None:
        """(:attr:`distance_along` − planned) / planned (None: no translation)."""
        if self.distance_planned < 1e-6:
            return None
        return (self.distance_along - self.distance_planned) / self.distance_planned

    @property
    def turn_error(self) -> float | None:
        """(turn − planned) / planned (None when the plan does not turn)."""
        if abs(self.turn_planned) < 1e-6:
            return None
        return (self.turn - self.turn_planned) / self.turn_planned

    @property
    def ok(self) -> bool:
        """Every check passes."""
        return all(row["ok"] for row in self.checks().values())


@dataclass(frozen=True)
class SimRun(Travel):
    """A plan replayed in MuJoCo, and how far the physics departs from it (SI units).

    ``t``: the plan's sample times [s]; ``base_poses``, ``q``: the simulated body poses and
    joint angles [rad]; ``planned``: the plan's body poses raised by ``lift`` [m] (the foot
    spheres on the ground); ``foot_forces`` (N, L): normal force on each foot [N];
    ``distance``, ``turn``: horizontal displacement of the body [m] and yaw change [rad]
    (``distance_planned``, ``turn_planned``: the plan's).

    Attributes:
        heading_error: Max over time of the yaw error (both from their start) [rad].
        direction_error: Angle between the simulated and planned displacements [rad]
            (0 when the plan does not move).
        max_roll: Max |roll| [rad].
        max_pitch: Max |pitch| [rad].
        height_error: Max |z − z_planned| of the body [m].
        max_slip: Largest tangential slide of a stance foot's contact point during one
            planned stance [m], added up across contact breaks (its lowest point's slide
            meanwhile counts).
        max_slip_speed: Largest tangential speed of a stance foot's contact point [m/s].
        swing_strikes: ``(leg, first time [s])`` of every swing foot that came down on the
            ground where the plan has it :data:`STRIKE_CLEARANCE` clear (not a late lift-off).
        non_foot_contacts: ``(geom, geom, first time [s])`` of every pair in contact that is
            not a foot on the ground.
        stand: The standing forces check (None when skipped).
        scene: The scene simulated.
        wall_time: Wall time of the replay (settling included) [s].
        plan: The plan's own summary (:meth:`GaitRun.to_dict`).
        run: The plan replayed.
        feedforward: The servos carried the plan's joint torques (False: a bare PD law).

    """

    t: np.ndarray
    base_poses: np.ndarray
    planned: np.ndarray
    q: np.ndarray
    foot_forces: np.ndarray
    lift: float
    distance_planned: float
    distance: float
    turn_planned: float
    turn: float
    heading_error: float
    direction_error: float
    max_roll: float
    max_pitch: float
    height_error: float
    max_slip: float
    max_slip_speed: float
    swing_strikes: tuple[tuple[str, float], ...]
    non_foot_contacts: tuple[tuple[str, str, float], ...]
    stand: StandForces | None
    scene: SimScene
    wall_time: float
    plan: dict[str, Any] = field(default_factory=dict)
    run: Any = field(default=None, repr=False, compare=False)
    feedforward: bool = False

    def checks(self, limits: dict[str, float] | None = None) -> dict[str, dict[str, Any]]:
        """Each check: its value, its limit and whether it passes (limits: :data:`LIMITS`).

        ``travel``: the larger of |distance_error| and |turn_error| (those that exist);
        ``heading``: the yaw error; ``roll``/``pitch``; ``slip``: ``max_slip``; ``height``:
        ``height_error``; ``contacts``: the number of non-foot contact pairs; ``strikes``:
        the number of legs whose swing foot struck the ground (both must be 0).
        """
        lim = {**LIMITS, **(limits or {})}
        rel = [abs(e) for e in (self.distance_error, self.turn_error) if e is not None]
        rows = {
            "travel": (max(rel) if rel else 0.0, lim["travel"]),
            "heading": (self.heading_error, lim["heading"]),
            "roll": (self.max_roll, lim["tilt"]),
            "pitch": (self.max_pitch, lim["tilt"]),
            "slip": (self.max_slip, lim["slip"]),
            "height": (self.height_error, lim["height"]),
            "contacts": (float(len(self.non_foot_contacts)), 0.0),
            "strikes": (float(len(self.swing_strikes)), 0.0),
        }
        return Travel.judged(rows)

    @property
    def stumbled(self) -> bool:
        """A stumble: a non-foot contact, a swing strike, roll, pitch or slip over its limit."""
        c = self.checks()
        return not all(c[k]["ok"] for k in ("contacts", "strikes", "roll", "pitch", "slip"))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary: the figures, the checks, the scene and the plan's summary."""
        out = fields_dict(self, *"distance_planned distance distance_error distance_along".split())
        out |= fields_dict(self, "direction", "turn_planned", "turn", "turn_error")
        for name in ("heading_error", "direction_error", "max_roll", "max_pitch"):
            out[f"{name}_deg"] = math.degrees(getattr(self, name))
        out |= fields_dict(self, "height_error", "max_slip", "max_slip_speed")
        out["swing_strikes"] = [list(c) for c in self.swing_strikes]
        out |= {"lift": self.lift, "non_foot_contacts": [list(c) for c in self.non_foot_contacts]}
        out["stand"] = None if self.stand is None else self.stand.to_dict()
        out |= {"checks": self.checks()} | fields_dict(self, "stumbled", "ok", "wall_time")
        out |= {"feedforward": self.feedforward, "scene": self.scene.to_dict()}
        return out | {"plan": self.plan}


def _linear(v: np.ndarray, sub: int) -> np.ndarray:
    """Linear interpolation (N−1, sub, ...) of samples ``v`` (N, ...) at ``s = k / sub``."""
    s = (np.arange(sub) / sub).reshape((1, sub) + (1,) * (v.ndim - 1))
    return np.asarray(v[:-1, None] * (1.0 - s) + v[1:, None] * s)


def _plan_torques(run: Any, joint_names: Any) -> np.ndarray | None:
    """(N, nq) the plan's joint torques [N·m], columns ``joint_names``, for the servos.

    :func:`hexapod_kin.dynamics.gait_torques` (full inverse dynamics when the run carries its
    robot, else quasi-static). None when the stance cannot hold the robot at some sample
    (not statically stable) or its inertials are implausible: replayed without them.
    """
    from ..dynamics.gait_loads import gait_torques

    try:
        loads = gait_torques(run)
    except (ConfigurationError, UrdfError):
        return None
    names = list(loads.joint_names)
    tau = loads.torque_full if loads.torque_full.size else loads.torque
    return np.asarray(tau)[:, [names.index(j) for j in joint_names]]


def _start_moving(eng: _Engine, run: Any, qd: np.ndarray) -> None:
    """Give the settled robot the plan's first velocities: the body's twist, the joints' rates.

    MuJoCo's free joint takes the linear velocity in the world and the angular one in the
    body (``qvel[3:6]``, Pinocchio's ``v[3:6]``).
    """
    mj, m, d = eng.mj, eng.model, eng.data
    twist = np.asarray(run.base_velocity(), dtype=float)[0]
    d.qvel[:3] = eng.base_pose()[:3, :3] @ twist[:3]
    d.qvel[3:6] = twist[3:]
    d.qvel[m.jnt_dofadr[_joints(mj, m, eng.scene.joint_names)]] = qd


def _lift(run: Any, scene: SimScene) -> float:
    """Vertical shift putting the first sample's stance spheres on the scene's ground."""
    feet = np.asarray(run.feet[0])[np.asarray(run.support[0])]
    if not len(feet):
        feet = np.asarray(run.feet[0])
    gap = (feet[:, 2] - scene.height(feet[:, 0], feet[:, 1])) * scene.normal_z
    if np.ptp(gap) > 1e-6:
        raise ConfigurationError(
            f"the plan's stance feet are {np.ptp(gap):.3g} m apart in height above the scene's "
            f"{scene.terrain!r} ground; the plan's terrain is not the scene's",
            parameter="terrain",
            value=scene.terrain,
        )
    return float((scene.foot_radius - gap.mean()) / scene.normal_z)


def simulate(
    run_or_robot: Any = None,
    *,
    pattern: Any = None,
    velocity: Any = None,
    terrain: Any = None,
    duration: float = 10.0,
    feet: Any = None,
    foot_radius: float | None = None,
    friction: float = 1.0,
    kp: float | None = None,
    kv: float | None = None,
    armature: float | None = None,
    contact_time: float = 0.005,
    timestep: float | None = None,
    settle: float = 0.5,
    stand: bool = True,
    bumps: float = 0.0,
    seed: int = 0,
    feedforward: bool = True,
    **walk_options: Any,
) -> SimRun:
    """Replay a walk open-loop in MuJoCo and measure how far the physics departs from it.

    Args:
        run_or_robot: A :class:`~hexapod_kin.gait.walk.GaitRun` (its robot: ``run.robot``, or
            the built-in hexapod), or a robot (what :func:`~hexapod_kin.gait.walk.walk`
            takes; None: the built-in hexapod) to plan with the keywords below.
        pattern: The walk's pattern (when planning; default the robot's
            :func:`~hexapod_kin.gait.tables.default_pattern`: tripod for six legs, crawl for four).
        velocity: The walk's body twist ``(vx, vy, wz)`` (when planning).
        terrain: ``flat`` (default), ``slope`` or ``step``, planned and simulated on; with a
            run, its own unless given (its first stance feet must then stand on both).
        duration: The walk's length [s] (when planning).
        feet: The feet of a URDF robot without foot links (``"frame:x,y,z ..."``, as
            :func:`~hexapod_kin.gait.robot.as_whole_body` takes them; when planning).
        foot_radius: Foot sphere radius [m] (default: the plan's, else the robot's); when
            planning, the plan's feet too; without it, feet at the round ends of the legs'
            meshes are planned and simulated as those spheres (:func:`~.collision.scene_robot`).
        friction: Sliding friction coefficient.
        kp: Servo position gain [N·m/rad] (default: scaled to the robot,
            :func:`~.scene.servo_defaults`; 300 for the built-in hexapod).
        kv: Servo velocity gain [N·m·s/rad] (default ``0.01 s × kp``).
        armature: Servo rotor inertia per leg joint [kg·m²] (see :func:`scene_mjcf`).
        contact_time: Contact stiffness time constant [s] (see :func:`scene_mjcf`).
        timestep: Physics step [s]; must divide the plan's sample interval (default: 1 ms
            or less for the servos' stability, see :func:`scene_mjcf`).
        settle: Time [s] the robot stands at the first pose before the replay (≥ 0); all
            the steps at most ``dynamics.MAX_STEPS`` (:func:`~.scene.check_steps`).
        stand: Also run :func:`stand_forces` (flat ground).
        bumps: Random bumps of this amplitude [m] on flat ground (see :func:`scene_mjcf`);
            the plan stays the flat one.
        seed: The bumps' seed.
        feedforward: The servos carry the plan's quasi-static joint torques
            (``τ_ref``, see the module's docstring); False: a bare PD law on the angles.
        **walk_options: More keywords of :func:`~hexapod_kin.gait.walk.walk` (when planning).

    Returns:
        A :class:`SimRun`.

    Raises:
        ParameterError: Bad values; a terrain the scene cannot build; too many physics
            steps (names the option).
        GaitError: The plan fails (as :func:`~hexapod_kin.gait.walk.walk`; pass
            ``strict=False`` to replay a failing plan).
        OptionalDependencyError: MuJoCo is not installed.

    """
    import time

    from ..gait.walk import GaitRun, walk

    _mujoco()
    try:
        wait = float(settle)
    except (TypeError, ValueError):
        raise ParameterError(f"settle={settle!r}: a time >= 0 s", parameter="settle") from None
    if isinstance(run_or_robot, GaitRun):
        t_run = np.asarray(run_or_robot.t, dtype=float)
        walked = float(t_run[-1] - t_run[0]) if len(t_run) else 0.0
    else:
        try:
            walked = float(duration)
        except (TypeError, ValueError):
            walked = 0.0  # the walk refuses it
    spans = {"settle": wait, "duration": walked, "stand": STAND_SETTLE if stand else 0.0}
    check_steps(1e-3 if timestep is None else timestep, spans)  # bounded work, before planning
    if isinstance(run_or_robot, GaitRun):
        run = run_or_robot
        wb = _robot(getattr(run, "robot", None))
        if tuple(wb.joint_names) != tuple(run.joint_names):
            raise ParameterError(
                f"the run's joints {list(run.joint_names)[:3]}... are not its robot's "
                f"{list(wb.joint_names)[:3]}...: a run from a gait without `run.robot`; "
                "simulate the robot (its source) with the walk's keywords instead",
                parameter="run",
            )
        ground = str(run.settings.get("terrain", "flat")) if terrain is None else terrain
    else:
        if terrain is not None and not isinstance(terrain, str):
            raise ParameterError(
                f"terrain={terrain!r}: the simulation builds {list(SCENE_TERRAINS)} only",
                parameter="terrain",
                value=repr(terrain),
                allowed=list(SCENE_TERRAINS),
            )
        ground = "flat" if terrain is None else terrain
        one_of("terrain", ground, list(SCENE_TERRAINS))
        wb = _robot(run_or_robot, feet)
        if foot_radius is None:  # the robot's feet, from its collision shapes if need be
            wb = scene_robot(wb)  # a mesh's round end: the foot's centre moves there
            foot_radius = scene_foot_radius(wb)
        walk_options["foot_radius"] = foot_radius  # the plan rolls the same feet
        run = walk(
            wb,
            pattern=pattern,
            velocity=velocity,
            terrain=ground,
            duration=duration,
            **walk_options,
        )
    planned_radius = run.settings.get("foot_radius")
    if foot_radius is None and planned_radius is not None:  # the feet the plan rolled
        foot_radius = float(planned_radius) if planned_radius > 0 else POINT_FOOT
    one_of("terrain", ground, list(SCENE_TERRAINS))
    by_name = isinstance(run_or_robot, (str, os.PathLike))
    sc = scene_mjcf(
        wb,
        source=run_or_robot if by_name else getattr(run_or_robot, "urdf", None),
        terrain=ground,
        foot_radius=foot_radius,
        friction=friction,
        kp=kp,
        kv=kv,
        armature=armature,
        contact_time=contact_time,
        timestep=timestep,
        bumps=bumps,
        seed=seed,
    )
    check_steps(sc.timestep, spans)  # the automatic timestep too
    t = np.asarray(run.t, dtype=float)
    if len(t) < 2:
        raise ParameterError("the run has fewer than 2 samples", parameter="run")
    h = float(t[1] - t[0])
    sub = int(round(h / sc.timestep))
    if sub < 1 or abs(sub * sc.timestep - h) > 1e-9 * h:
        raise ParameterError(
            f"timestep={sc.timestep!r} s does not divide the plan's sample interval {h!r} s",
            parameter="timestep",
            value=sc.timestep,
            allowed=f"{h:g} / k",
        )
    cols = [list(run.joint_names).index(j) for j in sc.joint_names]
    q_plan = np.asarray(run.q)[:, cols]
    qd_plan = np.asarray(run.qdot)[:, cols]
    lift = _lift(run, sc)
    planned = np.array(run.base_poses, dtype=float)
    planned[:, 2, 3] += lift
    chunk = max(1, 65536 // sub)  # intervals of servo targets computed at a time
    eng = _Engine(sc)
    mj, m, d = eng.mj, eng.model, eng.data
    support = np.asarray(run.support)
    n, nl = len(t), len(sc.leg_names)
    base = np.empty((n, 4, 4))
    qs = np.empty((n, len(cols)))
    forces = np.zeros((n, nl))
    max_slip = max_speed = 0.0
    seen: dict[tuple[str, str], float] = {}
    start = time.perf_counter()
    tau = _plan_torques(run, sc.joint_names) if feedforward else None
    fed = tau is not None
    tau = np.zeros(q_plan.shape) if tau is None else tau
    eng.place(planned[0], q_plan[0])
    d.ctrl[eng.act] = q_plan[0] + tau[0] / sc.kp  # the first sample's load, held
    for _ in range(int(round(wait / sc.timestep))):
        mj.mj_step(m, d)
    _start_moving(eng, run, qd_plan[0])

    def record(i: int) -> None:
        base[i] = eng.base_pose()
        qs[i] = d.qpos[eng.jq]
        forces[i] = eng.normal_forces()

    record(0)
    dt = sc.timestep
    slides = [0.0] * nl
    strikes: dict[str, float] = {}
    leg_names = sc.leg_names
    centre = np.asarray(run.feet)
    above = centre[..., 2] + lift - sc.height(centre[..., 0], centre[..., 1])
    # soft contacts sink the settled body (~4 mm) and the swing feet with it
    sink = max(0.0, float(planned[0, 2, 3] - base[0, 2, 3]))
    gap = (above - sink) * sc.normal_z - sc.foot_radius
    # on bumps the ground under swing and stance feet is each up to ±bumps off the plan's
    held = (gap >= STRIKE_CLEARANCE + 2.0 * sc.bumps) & ~support
    clear = (held[:-1] & held[1:]).tolist()  # clear over the whole interval
    in_order = bool(np.array_equal(eng.act, np.arange(m.nu)))
    was_down = [True] * nl
    landed = [False] * nl  # the stance foot has touched down in this stance
    pending = [0.0] * nl  # its lowest point's slide while off the ground since
    sn = math.sqrt(max(0.0, 1.0 - sc.normal_z**2))
    normal = (-sn, 0.0, sc.normal_z)  # the ground's (slope: rising along +x)
    for i in range(n - 1):
        if i % chunk == 0:
            ref, rate = _hermite(q_plan[i : i + chunk + 1], qd_plan[i : i + chunk + 1], h, sub)
            ctrl = ref + (sc.kv / sc.kp) * rate + _linear(tau[i : i + chunk + 1], sub) / sc.kp
        stance = support[i].tolist()
        for k in range(sub):
            if in_order:
                d.ctrl[:] = ctrl[i % chunk, k]
            else:
                d.ctrl[eng.act] = ctrl[i % chunk, k]
            mj.mj_step(m, d)
            others, feet = eng.scan()
            for g0, g1 in others:
                pair = sorted((eng.label(g0), eng.label(g1)))
                seen.setdefault((pair[0], pair[1]), float(t[i] + (k + 1) * dt))
            touching = [False] * nl
            down = [False] * nl
            for leg, v, _ in feet:
                down[leg] = True
                if not stance[leg]:
                    # a new contact of a swing foot the plan holds clear (not a lift-off lag)
                    if clear[i][leg] and not was_down[leg] and leg_names[leg] not in strikes:
                        strikes[leg_names[leg]] = float(t[i] + (k + 1) * dt)
                    continue
                if not touching[leg]:
                    touching[leg] = True
                    landed[leg] = True
                    slides[leg] += v * dt + pending[leg]  # a break within the stance counts
                    pending[leg] = 0.0
                    max_speed = max(max_speed, v)
            for leg in range(nl):
                if not stance[leg]:  # the slide adds up over the whole stance, not per contact
                    slides[leg], landed[leg], pending[leg] = 0.0, False, 0.0
                elif landed[leg] and not down[leg]:  # a break: the sphere's lowest point slides
                    pending[leg] += eng.bottom_speed(leg, normal) * dt  # (an early lift-off not)
            max_slip = max(max_slip, *slides)
            was_down = down
        record(i + 1)
    wall = time.perf_counter() - start
    stance = None
    if stand:
        stance = stand_forces(
            wb,
            source=run_or_robot if by_name else None,
            foot_radius=sc.foot_radius,
            friction=sc.friction,
            contact_time=sc.contact_time,
            timestep=timestep,  # None: its own stable step (its servos have no armature)
            settle=STAND_SETTLE,
        )
    dp = planned[-1, :2, 3] - planned[0, :2, 3]
    ds = base[-1, :2, 3] - base[0, :2, 3]
    yaw_p, yaw_s = (np.unwrap(np.arctan2(T[:, 1, 0], T[:, 0, 0])) for T in (planned, base))
    yaw_p, yaw_s = yaw_p - yaw_p[0], yaw_s - yaw_s[0]
    roll = np.arctan2(base[:, 2, 1], base[:, 2, 2])  # of R = Rz(ψ) Ry(θ) Rx(φ)
    pitch = np.arcsin(np.clip(-base[:, 2, 0], -1.0, 1.0))
    lp, ls = float(np.linalg.norm(dp)), float(np.linalg.norm(ds))
    direction = 0.0
    if lp > 1e-6 and ls > 0:
        direction = math.atan2(abs(float(dp[0] * ds[1] - dp[1] * ds[0])), float(dp @ ds))
    for a in (t, base, planned, qs, forces):
        a.setflags(write=False)
    contacts = tuple(sorted(((a, b, w) for (a, b), w in seen.items()), key=lambda x: x[2]))
    return SimRun(
        t=t,
        base_poses=base,
        planned=planned,
        q=qs,
        foot_forces=forces,
        lift=lift,
        distance_planned=lp,
        distance=ls,
        turn_planned=float(yaw_p[-1]),
        turn=float(yaw_s[-1]),
        heading_error=float(np.abs(yaw_s - yaw_p).max()),
        direction_error=direction,
        max_roll=float(np.abs(roll).max()),
        max_pitch=float(np.abs(pitch).max()),
        height_error=float(np.abs(base[:, 2, 3] - planned[:, 2, 3]).max()),
        max_slip=max_slip,
        max_slip_speed=max_speed,
        swing_strikes=tuple(sorted(strikes.items(), key=lambda x: x[1])),
        non_foot_contacts=contacts,
        stand=stance,
        scene=sc,
        wall_time=wall,
        plan=run.to_dict(),
        run=run,
        feedforward=fed,
    )


def _hermite(q: np.ndarray, qd: np.ndarray, h: float, sub: int) -> tuple[np.ndarray, np.ndarray]:
    """Cubic Hermite values and rates (N−1, sub, nq) at ``s = k / sub`` of every interval."""
    s = (np.arange(sub) / sub)[None, :, None]
    s2, s3 = s * s, s * s * s
    q0, q1, d0, d1 = q[:-1, None], q[1:, None], h * qd[:-1, None], h * qd[1:, None]
    val = (2 * s3 - 3 * s2 + 1) * q0 + (s3 - 2 * s2 + s) * d0 + (-2 * s3 + 3 * s2) * q1
    val = val + (s3 - s2) * d1
    rate = (6 * s2 - 6 * s) * q0 + (3 * s2 - 4 * s + 1) * d0 + (-6 * s2 + 6 * s) * q1
    rate = (rate + (3 * s2 - 2 * s) * d1) / h
    return val, rate
