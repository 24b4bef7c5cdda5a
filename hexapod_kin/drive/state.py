"""The cockpit's state and its laws, apart from any page: :class:`Cockpit`.

One robot (the one loaded model; a legged robot is also viewed as its
:class:`~hexapod_kin.gait.robot.WholeBody`), one configuration ``q`` (the model's joint order)
and one body pose, changed by four kinds of command, each in the robot's terms:

* **joints** — :meth:`Cockpit.set_joint` (within the joint's limits);
* **target** — :meth:`Cockpit.set_target`: the selected foot or tool follows by resolved-rate
  steps (:mod:`.reach`) on every :meth:`Cockpit.advance`, and stops with a reason;
* **body** — :meth:`Cockpit.set_body`: 6-DOF body pose with every foot held (body-pose IK);
* **walk** — :meth:`Cockpit.set_drive` / :meth:`Cockpit.set_pattern`: the planner's walk,
  cycle by cycle (:mod:`.walking`).

:meth:`Cockpit.readout` is what the page prints: FK (``model.fk``), σ_min and manipulability of
the foot/tool Jacobian, the distance to the nearest singular family (a chain whose families are
known), the support polygon, CoM and static margin, commanded and actual velocity. The server
advances it in real time; tests advance it by fixed steps.
"""

from __future__ import annotations

import math
import threading
from typing import Any

import numpy as np

from ..exceptions import ConfigurationError, FrameNotFoundError, ParameterError, choices
from ..gait.robot import as_whole_body, body_pose
from ..gait.stability import support_margin
from ..gait.tables import pattern_names, phase_table
from .reach import Limb
from .walking import Walker

__all__ = ["MODES", "Cockpit"]

#: The page's modes.
MODES = ("joints", "target", "body", "walk", "physics")
#: Body-pose slider ranges: translation as a fraction of the leg span, angles [rad].
BODY_SHIFT, BODY_ANGLE = 0.3, 0.4
#: Time over which the joints blend into a new cycle (from standstill, a new pattern) [s].
BLEND = 0.3
#: Distance to a singular family [rad or m] below which the page draws the chain on it.
FAMILY_NEAR = 0.25
#: Recorded samples kept (a session of about 30 min at 50 Hz).
MAX_RECORD = 90_000


def _finite(name: str, value: Any, size: int) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        arr = np.array([math.nan])
    if arr.shape != (size,) or not np.all(np.isfinite(arr)):
        raise ParameterError(
            f"{name}={value!r} is not allowed; give {size} finite number(s)",
            parameter=name,
            value=repr(value)[:80],
            allowed=f"{size} finite numbers",
        )
    return arr


def _leg_view(model: Any, body: Any, leg: int) -> Any:
    """Leg ``leg``'s chain as a model: the root → the last frame carried by its last joint."""
    cols = [j for j in range(body.nq) if body.leg_of_joint(j) == body.leg_names[leg]]
    joint = model.model.getJointId(body.joint_names[cols[-1]])
    tip = [f.name for f in model.model.frames if f.parentJoint == joint][-1]
    return model.view(None, tip)


class Cockpit:
    """A robot driven live: state, commands and readouts (thread-safe).

    Args:
        model: The loaded robot (:func:`hexapod_kin.load`).
        feet: Feet of a legged URDF without foot links (see
            :func:`~hexapod_kin.gait.robot.as_whole_body`).
        families: The chain's singular families (:class:`~hexapod_kin.singularity.Families`)
            or ``None``; a legged robot's: one per leg (:attr:`leg_views`' order, ``None``
            for a leg without); may be given later (:attr:`families`).
        calibration: The servos of the downloaded timeline (a
            :class:`~hexapod_kin.export.timeline.Calibration` or a calibration file; None:
            every joint in rad, unlimited).

    Raises:
        ParameterError, ConfigurationError: Bad ``feet``; a bad calibration file.
        SourceError: The calibration file cannot be read.

    """

    def __init__(
        self, model: Any, *, feet: Any = None, families: Any = None, calibration: Any = None
    ) -> None:
        self.model = model
        self.families = families
        if calibration is not None and not hasattr(calibration, "servo"):
            from ..export.servos import read_calibration

            calibration = read_calibration(calibration)
        self.calibration = calibration
        self.lock = threading.RLock()
        self.body: Any = None
        self.not_legged = ""
        try:
            self.body = as_whole_body(model, feet=feet)
        except (ParameterError, ConfigurationError) as exc:
            if feet is not None:
                raise
            self.not_legged = str(exc)
        if self.body is not None and not pattern_names(self.body.n_legs):
            self.not_legged = f"{self.body.n_legs} limb(s) and no gait for them: one chain"
            self.body = None  # an arm or a single leg found as limbs of a tree
        self.target: np.ndarray | None = None
        self.time = 0.0
        self.record: list[tuple[float, list[float], list[float]]] = []
        self.events: list[dict[str, Any]] = []
        self.min_margin = math.inf
        self.margins: list[float] = []
        self._actual = np.zeros(3)
        self._blend: tuple[Any, Any, float] = (None, None, 0.0)
        if self.body is None:
            self.limbs = [Limb(model)]
            self.patterns: tuple[str, ...] = ()
            self.physics_patterns: tuple[str, ...] = ()
            self.leg_views: tuple[Any, ...] = ()
            self.pattern = ""
        else:
            wb = self.body
            try:
                self._cols = np.array([model.joint_names.index(n) for n in wb.joint_names])
            except ValueError:
                raise ConfigurationError(
                    f"the legged robot's joints {list(wb.joint_names)} are not the model's",
                    parameter="model",
                ) from None
            self.limbs = [Limb(None, wb, i) for i in range(wb.n_legs)]
            # kinematic mode walks the open-loop planner: its statically stable patterns only
            xy = wb.mounts[:, :2, 3]
            self.patterns = tuple(
                p
                for p in pattern_names(wb.n_legs, xy)
                if phase_table(p, wb.n_legs, xy).statically_stable
            )
            self.pattern = "tripod" if "tripod" in self.patterns else self.patterns[0]
            #: Physics mode's patterns: every one the closed-loop controller walks.
            self.physics_patterns = tuple(pattern_names(wb.n_legs, xy))
            self.walker = Walker(wb)
            #: Each leg's chain, body → foot, as a model of its own (``Model.view``).
            self.leg_views = tuple(_leg_view(model, wb, i) for i in range(wb.n_legs))
        self.physics: Any = None
        self.limb = 0
        self.speed = (0.05, 0.05, 0.3) if self.body is not None else (0.0, 0.0, 0.0)
        self.reset()

    def reset(self) -> None:
        """Back to the home pose (a chain) or standing on flat ground at z = 0 (legs)."""
        with self.lock:
            self.mode, self.status, self.message, self.target = "joints", "idle", "", None
            self.body_xyz = np.zeros(3)
            self.body_rpy = np.zeros(3)
            self.drive = (0.0, 0.0, 0.0)
            self.min_margin, self.margins = math.inf, []
            if self.body is None:
                self.q = np.asarray(self.model.check_q(self._home()), dtype=float)
                self.base = np.eye(4)
            else:
                wb = self.body
                self.walker.cycle = None
                self.base = body_pose([0.0, 0.0, wb.body_height])
                feet = (self.base[:3, :3] @ wb.neutral_feet().T + self.base[:3, 3:4]).T
                ik = wb.body_ik(self.base, feet, strict=False)
                self.qb = np.asarray(ik.q[0] if np.all(ik.ok) else wb.neutral_q(), dtype=float)
                self.q = np.asarray(self.model.neutral(), dtype=float)
                self.q[self._cols] = self.qb
                self.feet = np.asarray(wb.feet(self.qb[None], self.base[None])[0])
                self.stand = self.base.copy()
            self._event("reset")
            self._record()

    def _home(self) -> np.ndarray:
        from ..gait.stand import default_configuration

        return np.asarray(default_configuration(self.model), dtype=float)

    # ------------------------------------------------------------------ helpers
    @property
    def legged(self) -> bool:
        """Whether the robot has legs (body and walk modes)."""
        return self.body is not None

    def _limb_q(self) -> np.ndarray:
        return self.q if self.body is None else self.qb

    def _set_limb_q(self, qv: np.ndarray) -> None:
        if self.body is None:
            self.q = qv
        else:
            self.qb = qv
            self.q = self.q.copy()
            self.q[self._cols] = qv

    def _event(self, kind: str, **data: Any) -> None:
        self.events.append({"t": round(self.time, 6), "type": kind, **data})
        del self.events[:-1000]

    def _record(self) -> None:
        self.record.append((self.time, self.q.tolist(), self.base.reshape(-1).tolist()))
        if len(self.record) > MAX_RECORD:
            del self.record[: len(self.record) - MAX_RECORD]

    # ------------------------------------------------------------------ commands
    def set_mode(self, mode: str) -> None:
        """Switch the page's mode (one of :data:`MODES`; body, walk and physics need legs).

        ``physics`` starts a new simulation (:class:`~.physics.Physics`) from the neutral
        pose at the origin, in the pattern ``hexapod-kin control`` starts with
        (:func:`~.physics.default_pattern`); leaving it resets the robot (standing at the
        origin, in a pattern of the kinematic walk).

        Raises:
            ParameterError: Unknown mode, or a legged mode for a robot without legs.
            HexapodKinError: The controller cannot drive the robot (physics mode).
            OptionalDependencyError: MuJoCo or proxsuite is missing (physics mode).

        """
        allowed = MODES if self.legged else MODES[:2]
        if mode not in allowed:
            raise ParameterError(
                f"mode={mode!r} is not allowed for {self.model.name}; use one of "
                f"{choices(allowed)}",
                parameter="mode",
                value=mode,
                allowed=allowed,
            )
        with self.lock:
            if self.mode == "physics" and mode != "physics":
                self.reset()
                if self.pattern not in self.patterns:
                    self.pattern = "tripod" if "tripod" in self.patterns else self.patterns[0]
            if mode == "physics":
                from .physics import Physics, default_pattern

                self.pattern = default_pattern(self.body)
                self.physics = Physics(self.body, self.pattern)
                self.walker.cycle, self.drive = None, (0.0, 0.0, 0.0)
                self.status, self.message = "physics", ""
            if self.legged and mode not in ("walk", "physics"):
                self.drive = (0.0, 0.0, 0.0)
            if self.legged and mode == "body" and self.mode != "body":
                self._hold_feet()
            self.mode = mode
            self.target = None if mode != "target" else self.target
            self._event("mode", mode=mode)

    def _hold_feet(self) -> None:
        """The feet where they are now are held; the body sliders move from here."""
        self.feet = np.asarray(self.body.feet(self.qb[None], self.base[None])[0])
        yaw = math.atan2(self.base[1, 0], self.base[0, 0])
        self.stand = body_pose(self.base[:3, 3], (0.0, 0.0, yaw))
        self.body_xyz[:] = 0.0
        self.body_rpy[:] = 0.0

    def set_joint(self, name: str | int, value: float) -> None:
        """Set one joint [rad] / [m] (the joints mode).

        Raises:
            FrameNotFoundError: Unknown joint.
            ParameterError: A value outside the joint's limits.

        """
        names = list(self.model.joint_names)
        j = name if isinstance(name, int) and 0 <= name < len(names) else None
        if j is None:
            if name not in names:
                raise FrameNotFoundError(
                    f"joint {name!r} is not in {self.model.name}; use one of {choices(names)}"
                )
            j = names.index(name)
        v = float(_finite("value", value, 1)[0])
        lo, hi = float(self.model.lower[j]), float(self.model.upper[j])
        if not lo - 1e-12 <= v <= hi + 1e-12:
            raise ParameterError(
                f"value={v!r} of joint {names[j]!r} is not allowed; its limits are "
                f"[{lo:.6g}, {hi:.6g}]",
                parameter=names[j],
                value=v,
                allowed=f"[{lo:.6g}, {hi:.6g}]",
            )
        with self.lock:
            self.q = self.q.copy()
            self.q[j] = v
            if self.body is not None:
                self.qb = self.q[self._cols].copy()
                col = np.flatnonzero(self._cols == j)
                if col.size:  # the readout follows the leg being moved
                    leg = self.body.leg_of_joint(int(col[0]))
                    self.limb = list(self.body.leg_names).index(leg)
            self.status, self.message = "idle", ""
            self._record()

    def set_q(self, q: Any) -> None:
        """Set every joint at once (``q`` (nq,) in the model's order, inside the limits).

        Raises:
            ConfigurationError: Bad ``q``.
            ParameterError: A joint beyond its limits.

        """
        qv = np.asarray(self.model.check_q(q), dtype=float)
        bad = np.flatnonzero((qv < self.model.lower - 1e-12) | (qv > self.model.upper + 1e-12))
        if bad.size:
            j = int(bad[0])
            raise ParameterError(
                f"q[{j}]={qv[j]!r} ({self.model.joint_names[j]}) is beyond its limits "
                f"[{self.model.lower[j]:.6g}, {self.model.upper[j]:.6g}]",
                parameter="q",
                value=float(qv[j]),
            )
        with self.lock:
            self.q = qv
            if self.body is not None:
                self.qb = qv[self._cols].copy()
            self._record()

    def select(self, limb: int | str) -> None:
        """Select the driven foot (legged: a leg name or index; a chain has one tip).

        Raises:
            ParameterError: Unknown leg.

        """
        names = list(self.body.leg_names) if self.body is not None else [str(self.model.tip)]
        i = limb if isinstance(limb, int) and 0 <= limb < len(names) else None
        if i is None and limb in names:
            i = names.index(limb)
        if i is None:
            raise ParameterError(
                f"foot={limb!r} is not allowed; use one of {choices(names)}",
                parameter="foot",
                value=repr(limb),
                allowed=names,
            )
        with self.lock:
            self.limb = i
            self.target = None

    def set_target(self, xyz: Any) -> None:
        """Set the selected foot's or tool's target point [m] (world; a chain: its base frame).

        The point is followed on each :meth:`advance` (target mode).

        Raises:
            ParameterError: Not three finite numbers.

        """
        t = _finite("target", xyz, 3)
        with self.lock:
            if self.legged and self.mode == "walk":
                self.drive = (0.0, 0.0, 0.0)
            self.mode = "target"
            self.target = t
            self.status, self.message = "moving", ""
            self._event("target", xyz=t.tolist())

    def set_body(self, xyz: Any = (0.0, 0.0, 0.0), rpy: Any = (0.0, 0.0, 0.0)) -> None:
        """Body pose relative to the standing pose, every foot held: ``xyz`` [m], ``rpy`` [rad].

        A pose the legs cannot take (a foot out of reach, a joint beyond its limit) is refused
        with the reason (:attr:`message`) and the body stays where it was.

        Raises:
            ParameterError: Not a legged robot, or not finite numbers.

        """
        if not self.legged:
            raise ParameterError(
                f"{self.model.name} has no legs to hold: {self.not_legged}", parameter="body"
            )
        p, a = _finite("xyz", xyz, 3), _finite("rpy", rpy, 3)
        with self.lock:
            if self.mode != "body":
                self.set_mode("body")
            base = self.stand @ body_pose(p, a)
            ik = self.body.body_ik(base, self.feet, q_prev=self.qb, strict=False)
            ok = np.asarray(ik.ok)[0]
            if not np.all(ok):
                leg = int(np.flatnonzero(~ok)[0])
                name = self.body.leg_names[leg]
                excess = float(ik.excess[0, leg])
                if excess > 0:
                    why = f"{name}: its foot is {excess * 1e3:.1f} mm out of reach"
                else:
                    per = np.asarray(ik.limit_margin[0])
                    bad = [j for j in self.limbs[leg].columns if per[j] < 0]
                    j = bad[0] if bad else self.limbs[leg].columns[0]
                    why = (
                        f"{name}: joint {self.body.joint_names[j]} would pass its limit by "
                        f"{-per[j]:.4f}"
                    )
                self.status, self.message = "refused", f"body pose refused: {why}"
                return
            self.body_xyz, self.body_rpy = p, a
            self.base = base
            self._set_limb_q(np.asarray(ik.q[0], dtype=float))
            self.status, self.message = "held", ""
            self._record()

    def set_stance(self, scale: float) -> None:
        """Stance width: every foot back on the ground at ``scale`` × the robot's reach.

        The reach is the robot's mean mount-to-foot distance
        (:meth:`~hexapod_kin.gait.WholeBody.neutral_feet`), ``scale`` in [0.6, 1.4]; the body
        stays where it stands (its height is the body's z slider).

        Raises:
            ParameterError: Not a legged robot, or ``scale`` outside [0.6, 1.4].

        """
        if not self.legged:
            raise ParameterError(f"{self.model.name} has no legs", parameter="stance")
        k = float(_finite("stance", scale, 1)[0])
        if not 0.6 <= k <= 1.4:
            raise ParameterError(
                f"stance={k!r} is not allowed; give a factor of the reach in [0.6, 1.4]",
                parameter="stance",
                value=k,
                allowed="[0.6, 1.4]",
            )
        wb = self.body
        with self.lock:
            if self.mode != "body":
                self.set_mode("body")
            local = wb.neutral_feet(k * wb.foot_reach)
            local[:, 2] = 0.0
            feet = (self.stand[:3, :3] @ local.T + self.stand[:3, 3:4]).T
            feet[:, 2] = wb.foot_radius  # on the ground z = 0
            ik = wb.body_ik(self.base, feet, q_prev=self.qb, strict=False)
            ok = np.asarray(ik.ok)[0]
            if not np.all(ok):
                leg = wb.leg_names[int(np.flatnonzero(~ok)[0])]
                self.status, self.message = "refused", f"stance refused: {leg} cannot reach it"
                return
            self.feet = feet
            self._set_limb_q(np.asarray(ik.q[0], dtype=float))
            self.status, self.message = "held", ""
            self._event("stance", scale=k)
            self._record()

    def set_drive(self, axes: Any) -> None:
        """Walk: ``axes`` (forward, left, turn), each in [-1, 1] of :attr:`speed` (W/S, A/D, Q/E).

        Raises:
            ParameterError: Not a legged robot, or not three numbers in [-1, 1].

        """
        if not self.legged:
            raise ParameterError(f"{self.model.name} has no legs to walk with", parameter="drive")
        a = _finite("drive", axes, 3)
        if np.any(np.abs(a) > 1):
            raise ParameterError(
                f"drive={axes!r} is not allowed; give three numbers in [-1, 1]",
                parameter="drive",
                value=repr(axes),
            )
        cmd = tuple(float(x * s) for x, s in zip(a, self.speed))
        with self.lock:
            if self.mode not in ("walk", "physics"):
                self.mode = "walk"
                self.target = None
            self.drive = cmd  # type: ignore[assignment]
            self._event("drive", command=list(cmd))
            if self.mode == "physics":
                return
            if any(cmd) and self.walker.cycle is None:
                self._start_cycle()

    def set_pattern(self, name: str) -> None:
        """The walk's phase pattern, from the next cycle on.

        One of :attr:`patterns` (the kinematic walk), or in physics mode one of
        :attr:`physics_patterns` (the controller switches at its next cycle boundary).

        Raises:
            ParameterError: Unknown pattern (for the current mode).

        """
        allowed = self.physics_patterns if self.mode == "physics" else self.patterns
        if name not in allowed:
            raise ParameterError(
                f"pattern={name!r} is not allowed in {self.mode} mode; use one of "
                f"{choices(allowed)}",
                parameter="pattern",
                value=name,
                allowed=allowed,
            )
        with self.lock:
            self.pattern = name
            self._event("pattern", pattern=name)

    def push(self, force: Any) -> None:
        """Push the simulated robot's base with a horizontal force (fx, fy) [N] (physics mode).

        Raises:
            ParameterError: Not in physics mode, or not two finite numbers.

        """
        with self.lock:
            if self.mode != "physics":
                raise ParameterError(
                    f"push: mode={self.mode!r}; a push needs the physics mode",
                    parameter="mode",
                    value=self.mode,
                    allowed="physics",
                )
            self.physics.push(force)
            self._event("push", force=[float(f) for f in np.reshape(force, -1)])

    def _start_cycle(self) -> None:
        from ..exceptions import HexapodKinError

        try:
            self.walker.start(self.pattern, self.drive, self.base)
        except HexapodKinError as exc:
            self.drive = (0.0, 0.0, 0.0)
            self.status, self.message = "refused", f"walk refused: {exc}"
            return
        self.status, self.message = "walking", ""
        self._apply_walk_sample()

    def _apply_walk_sample(self) -> None:
        q, base, k = self.walker.sample()
        q = np.asarray(q, dtype=float)
        cycle = self.walker.cycle
        if cycle is not self._blend[0]:  # a new cycle: blend the joints from where they are
            self._blend = (cycle, self.qb - q, self.walker.time)
        s = min(max((self.walker.time - self._blend[2]) / BLEND, 0.0), 1.0)
        self._set_limb_q(q + (1.0 - s * s * (3.0 - 2.0 * s)) * self._blend[1])
        self.base = base
        run = self.walker.cycle.run  # type: ignore[union-attr]
        self.margins.append(float(run.margin[k]))
        del self.margins[:-5000]
        self.min_margin = min(self.min_margin, float(run.margin[k]))

    # ------------------------------------------------------------------ time
    def advance(self, dt: float) -> None:
        """Move the robot on by ``dt`` [s] (a follow's steps, a walk's samples) and record it."""
        dt = float(min(max(dt, 0.0), 0.1))
        with self.lock:
            self.time += dt
            before = self.base[:3, 3].copy(), math.atan2(self.base[1, 0], self.base[0, 0])
            if self.mode == "target" and self.target is not None and self.status == "moving":
                limb = self.limbs[self.limb]
                res = limb.follow(self._limb_q(), self.base, self.target, dt=dt / 10, steps=10)
                self._set_limb_q(res.q)
                if res.status != "moving":
                    self.status, self.message = res.status, res.reason
                    self._event("target stop", status=res.status, reason=res.reason)
            elif self.mode == "physics":
                self.physics.set_command(self.drive, self.pattern)
                self.physics.advance(dt)
                q, self.base, _ = self.physics.state()
                self._set_limb_q(q)
            elif self.legged and self.mode == "walk" and self.walker.cycle is not None:
                why = self.walker.advance(dt, self.pattern, self.drive)
                if self.walker.cycle is not None:
                    self._apply_walk_sample()
                else:
                    self.status = "standing" if why == "stopped" else "refused"
                    self.message = "" if why == "stopped" else f"walk stopped: {why}"
                    self.drive = (0.0, 0.0, 0.0) if why != "stopped" else self.drive
            if dt > 0:
                yaw = math.atan2(self.base[1, 0], self.base[0, 0])
                d = self.base[:3, 3] - before[0]
                c, s = math.cos(yaw), math.sin(yaw)
                inst = np.array(
                    [
                        (c * d[0] + s * d[1]) / dt,
                        (-s * d[0] + c * d[1]) / dt,
                        (yaw - before[1]) / dt,
                    ]
                )
                self._actual = 0.9 * self._actual + 0.1 * inst
            self._record()

    # ------------------------------------------------------------------ readouts
    def support(self) -> dict[str, Any]:
        """Support polygon (stance feet, world [m]), CoM, ZMP, static and ZMP margins [m] (legs).

        While walking, the ZMP is the planner's of the sample (:func:`.walking.run_zmp`, placed
        in the world) and ``zmp_margin`` its margin in the support polygon
        (:attr:`~hexapod_kin.gait.walk.GaitRun.zmp_margin`); in physics mode it is the centre
        of pressure of MuJoCo's ground reaction over the last control period
        (:meth:`~.physics.Physics.zmp`) and its margin in the polygon of the feet in contact;
        standing still, the ZMP is the CoM's projection on the ground and its margin the
        static one.
        """
        wb = self.body
        feet = np.asarray(wb.feet(self.qb[None], self.base[None])[0])
        physics = self.physics if self.mode == "physics" else None
        radius = wb.foot_radius if physics is None else physics.foot_radius
        if physics is None:
            stance = np.abs(feet[:, 2] - radius) < 2e-3  # on the ground z = 0
        else:  # the feet MuJoCo has on the ground
            stance = physics.contacts()
        com = np.asarray(wb.com(self.qb[None], self.base[None])[0])
        zmp = zmp_margin = None
        cycle = self.walker.cycle if self.mode == "walk" else None
        if cycle is not None:
            run = cycle.run
            k = self.walker.sample()[2]
            stance = np.asarray(run.support[k])
            zmp = cycle.anchor[:3, :3] @ cycle.zmp[k] + cycle.anchor[:3, 3]
            if len(run.zmp_margin) > k:
                zmp_margin = float(run.zmp_margin[k])
        margin = float(support_margin(feet, stance, com))
        cop = physics.zmp() if physics is not None else None
        if cop is not None:
            zmp, zmp_margin = cop, float(support_margin(feet, stance, cop))
        if zmp is None:
            ground = float(np.mean(feet[stance, 2])) - radius if stance.any() else 0.0
            zmp, zmp_margin = np.array([com[0], com[1], ground]), margin
        return {
            "feet": feet.tolist(),
            "stance": stance.tolist(),
            "com": com.tolist(),
            "margin": margin,
            "zmp": np.asarray(zmp).tolist(),
            "zmp_margin": zmp_margin,
        }

    def readout(self) -> dict[str, Any]:
        """What the page prints, JSON-ready (SI units)."""
        with self.lock:
            limb = self.limbs[self.limb]
            qv = self._limb_q()
            smin, manip = limb.measures(qv, self.base)
            out: dict[str, Any] = {
                "time": self.time,
                "mode": self.mode,
                "q": self.q.tolist(),
                "base": self.base.tolist(),
                "fk": np.asarray(self.model.fk(self.q)).tolist(),
                "foot": limb.label,
                "point": limb.point(qv, self.base).tolist(),
                "sigma_min": smin,
                "manipulability": manip,
                "family": self._family(),
                "status": self.status,
                "message": self.message,
                "target": None if self.target is None else self.target.tolist(),
            }
            if self.legged:
                out["support"] = self.support()
                out["body"] = {"xyz": self.body_xyz.tolist(), "rpy": self.body_rpy.tolist()}
                out["command"] = list(self.drive)
                out["actual"] = self._actual.tolist()
                out["pattern"] = self.pattern
                out["min_margin"] = None if math.isinf(self.min_margin) else self.min_margin
            return out

    def _family(self) -> dict[str, Any] | None:
        """The nearest singular family: name, distance, and the chain on it (the ghost).

        ``q`` is a configuration of the family near the current one: the closest one for a
        family ``q_k = v`` (``q_k`` moved by the distance), a Gauss–Newton projection onto the
        family for an implicit one (None when it does not converge); ``ghost`` the origins of
        the chain's frames (``model.frame_placements``, base frame [m]) at ``q``; ``near``
        whether the distance is below :data:`FAMILY_NEAR` (the page draws the ghost then).
        A legged robot, in joints mode: the chain of the leg being moved (:attr:`leg_views`,
        ``q`` its joints), the ghost in the world.
        """
        fams, model, q_now, to_world = self.families, self.model, self.q, np.eye(4)
        if self.body is not None:  # the leg being moved: its chain's families
            if fams is None or self.limb >= len(fams) or self.mode != "joints":
                return None
            fams, model = fams[self.limb], self.leg_views[self.limb]
            q_now = self.q[[self.model.joint_names.index(n) for n in model.joint_names]]
            to_world = self.base
        if fams is None or not fams.families:
            return None
        idx, dist, _, _ = fams.nearest(q_now[None])
        if idx[0] < 0:
            return None
        fam = fams.families[int(idx[0])]
        q = fam.project(q_now)
        ghost = None
        if q is not None:
            ghost = [(to_world @ t)[:3, 3].tolist() for t in model.frame_placements(q)]
        return {
            "name": str(getattr(fam, "name", idx[0])),
            "distance": float(dist[0]),
            "near": bool(dist[0] < FAMILY_NEAR),
            "q": None if q is None else q.tolist(),
            "ghost": ghost,
        }

    def session(self) -> dict[str, Any]:
        """The recorded session: times [s], q (model order), body poses, events (JSON-ready)."""
        with self.lock:
            rec = list(self.record)
            return {
                "robot": self.model.name,
                "joint_names": list(self.model.joint_names),
                "t": [r[0] for r in rec],
                "q": [r[1] for r in rec],
                "base_poses": [r[2] for r in rec],
                "events": list(self.events),
            }

    def timeline(self, rate: float = 50.0) -> Any:
        """The session's joints as a calibrated servo timeline (``hexapod-kin timeline``'s checks).

        The recorded samples (commands at one time keep the last) are resampled at ``rate``
        [Hz] and mapped through :attr:`calibration` (None: every joint in rad, unlimited) by
        :func:`hexapod_kin.export.timeline.timeline`, checked against the joints' limits and
        speed limits and the servos' limits.

        Returns:
            The :class:`~hexapod_kin.export.timeline.Timeline` (``to_csv()``, ``to_dict()``).

        Raises:
            LimitError: A sample beyond a servo's or a joint's limits or its speed limit (e.g.
                a slider moved faster than the servo turns), naming the joint and the time.
            ConfigurationError: Fewer than two recorded times.

        """
        from ..export.timeline import timeline

        with self.lock:
            rec = list(self.record)
        t: list[float] = []
        q: list[list[float]] = []
        for ti, qi, _ in rec:
            if t and ti <= t[-1]:  # a plan's times increase strictly: keep the last command
                q[-1] = qi
                continue
            t.append(ti)
            q.append(qi)
        m = self.model
        return timeline(
            (np.asarray(t), np.asarray(q)),
            rate=rate,
            calibration=self.calibration,
            joint_names=list(m.joint_names),
            velocity_limit=np.asarray(m.velocity_limit, dtype=float),
            position_limit=(np.asarray(m.lower, dtype=float), np.asarray(m.upper, dtype=float)),
        )
