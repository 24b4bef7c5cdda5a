"""The walking controller: measured state in, joint torques or servo targets out.

One :class:`Controller` for any legged robot of the model (a view of the one Pinocchio
model: :func:`hexapod_kin.gait.as_whole_body`), at a fixed rate. Each :meth:`Controller.tick`
takes a :class:`Measurement` (what the robot can sense: IMU attitude and rates, joint
positions and velocities, foot contacts, and a base position/velocity estimate) and returns
one value per leg joint.

* **Schedule**: a phase table (:func:`hexapod_kin.gait.tables.phase_table`): leg *i* is in
  stance while ``(φ + offset_i) mod 1 < β``; a pattern change waits for the cycle boundary.
  A swing foot that touches down after 60 % of its swing joins the stance early (torque
  kind: and stays in it until its scheduled stance, however it bounces).
* **Reference**: the commanded twist integrated from the start (the *path*: position and
  yaw); the body height the standing height measured at :meth:`Controller.reset` (lowered
  in ``sit``).
* **Swing** (both kinds): the foothold re-targeted every tick, Raibert's rule with the
  capture-point correction: ``p = hip(t_td) + v_ref T_st / 2 + k_v (v − v_ref)`` (Raibert
  1986; Pratt et al. 2006) with ``k_v = sqrt(h / g)``; the foot moves from its lift-off
  point along a smooth step (``3u² − 2u³``, ``u = min(1, s / a)``; ``a = 1`` for torque,
  ``ARRIVE`` for servos, whose lag would otherwise land the foot short of its foothold)
  with a ``sin(π s)`` lift of ``swing_height``, and keeps descending past ``s = 1`` until it
  touches. Torque kind: the lift (under the MPC rising as ``sin(π s)``, coming down as
  ``sin²(π s)``) plus ``v T_sw (1 − s) s⁴``: at ``s = 1`` the foot is at its lift-off height
  coming down at the landing speed ``v`` (:data:`LAND`), and goes on down at ``v`` until it
  touches.
* **Torque kind** (quadrupeds' motors): the body wrench from PD laws on the CoM path and
  height (with a bounded integral of the error along the path, which removes the steady
  lag of slow gaits) and on the attitude, ``F = m (K_p e_p + K_I ∫e_p + K_d e_v + g)``,
  ``M = I (K_R log(R_d Rᵀ) + K_ω (ω_d − ω))``, shared among the stance feet by
  :class:`~.qp.ForceQP` (friction pyramids, normal force bounds, joint torque limits),
  then ``τ = h − Jᵀ f`` per stance leg (``h`` Pinocchio's non-linear effects) and
  ``τ = Jᵀ Λ (a + ω² e + 2 ζ ω ė) + h`` per swing leg (``Λ = (J M⁻¹ Jᵀ)⁻¹`` the foot's
  operational-space inertia, ``M`` the leg's joint-space inertia plus its rotors'
  ``armature``; ``a`` the path's acceleration; ``ω = 2π`` :data:`SWING_HZ`, ``ζ = 0.7``).
  The MPC keeps each standing leg's forces within its joint torque limits.
  Under the MPC, a push puts the controller in its catching mode (:class:`~.mpc.Catch`).
* **Servo kind** (position servos, hobby hexapods): the body pose is the feedback
  (OpenSHC's posing): the commanded body is the reference pose (level, on the path, at its
  height above the stance feet) plus an integral of its error; the stance feet are held
  where they are measured, the swing feet on their paths; leg IK (the whole body's,
  closed form per leg where it has one, the branch nearest the last command) turns them into
  targets. A body pushed off its path is not dragged back
  by the posing (its stance feet would leave their reach): the reference stays within
  ``0.08`` leg span of the body and returns to the path at :data:`RETURN_SPEED`, while the
  swing feet step towards the path (standing, it stays where the push left the body). A
  standing foot that slid (a push beyond the feet's friction) is held within :data:`SLIP`
  of where it is measured: the reference is relative to the measured body, so a foot held
  ``δ`` from where it stands would move the body on by ``δ`` each tick.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._pose import matrix_to_rpy
from ..exceptions import one_of
from .commands import Command
from .measurement import Measurement, _log3, _quat_mat, _rot, _rz, _yaw
from .mpc import CATCH_RETURN, Catch, ConvexMPC, schedule
from .qp import ForceQP

__all__ = ["BALANCES", "KINDS", "Controller", "Measurement"]

#: Actuator kinds: joint torques, or joint position targets for servos.
KINDS = ("torque", "servo")

#: Torque kind's stance-force methods: model-predictive, or one wrench's QP.
BALANCES = ("mpc", "qp")

#: MPC: the horizon's steps, the steps per gait cycle, and control ticks between two solves.
MPC_STEPS = 10
MPC_DIV = 20
MPC_EVERY = 5

#: MPC: the integral gain [1/s] moving the reference by the integral of the height error and of
#: the lag along the path, and the integral's bound [m·s].
MPC_KI = 0.5
MPC_INT = 0.05

#: MPC's footholds: the least lateral offset from the body's centre line, as a fraction of the
#: foot's neutral one, and the least distance from a standing foot, as a fraction of the span.
SIDE = 0.3
CLEAR = 0.2

#: MPC's largest normal force of a foot, as a multiple of the robot's weight.
MPC_FMAX = 1.5

_G = 9.81

#: The commanded twist's largest rate of change: linear [m/s²], yaw [rad/s²].
ACCEL = (1.0, 2.0)

#: Torque kind: the swing feet's position loop's natural frequency [Hz] (damping ratio 0.7).
SWING_HZ = 8.0

#: Torque kind: a swing foot's landing speed [m/s] as ``LAND · swing_height / T_sw`` (it comes
#: down to its lift-off height at that speed, and on down until it touches).
LAND = 1.0

#: Servo kind: the fraction of the swing by which the foot reaches its foothold's x, y (the
#: servos lag their targets; arriving early lands the foot where it was placed).
ARRIVE = 0.8

#: Servo kind: the speed [leg spans/s] at which the body's goal returns to the path.
RETURN_SPEED = 0.7

#: Servo kind: the farthest [leg spans] a standing foot is held from where it is measured (a
#: foot that slipped further is held nearer).
SLIP = 0.06

#: Torque kind: the CoM's along-path integral gain as ``KI_FRAC · ω_p³`` (ω_p the position
#: loop's natural frequency) and the most acceleration it may add [m/s²].
KI_FRAC = 0.3
ACC_I = 1.5


class Controller:
    """A walking controller for one robot (see the module docstring).

    Args:
        robot: The robot (what :func:`hexapod_kin.gait.as_whole_body` takes; None: the
            built-in hexapod).
        kind: ``torque`` (outputs joint torques [N·m]) or ``servo`` (joint targets [rad]).
        pattern: The starting gait pattern (a name of :func:`~hexapod_kin.gait.tables.
            pattern_names` for the robot's legs).
        rate: Control rate [Hz] (default 500 for torque, 100 for servo).
        period: Gait cycle [s] (default: 0.5 s for trot/pace, 1 s otherwise, scaled by
            ``sqrt(leg span / 0.5 m)``).
        swing_height: Foot lift [m] (default 12 % of the standing height, plus the foot
            radius for torque control).
        mu: Friction coefficient the force distribution assumes.
        balance: Torque kind: how the stance forces are found, one of :data:`BALANCES`:
            ``mpc`` (:class:`~.mpc.ConvexMPC` over one gait cycle) or ``qp`` (the body
            wrench of the PD laws shared by :class:`~.qp.ForceQP`).
        armature: Rotor inertia of each leg joint [kg·m²] (the motors' reflected inertia,
            as MuJoCo's ``armature``): the torque kind's swing legs move with it.

    Raises:
        ParameterError: A bad kind, pattern or value.

    """

    def __init__(
        self,
        robot: Any = None,
        *,
        kind: str = "torque",
        pattern: str = "trot",
        rate: float | None = None,
        period: float | None = None,
        swing_height: float | None = None,
        mu: float = 0.6,
        balance: str = "mpc",
        armature: float = 0.0,
    ) -> None:
        import pinocchio as pin

        from ..exceptions import positive
        from ..gait import as_whole_body

        one_of("kind", kind, list(KINDS))
        self.kind = kind
        self.wb = wb = as_whole_body(robot)
        wb.require_mass()
        self.pin = pin
        self.model = pin.Model(wb.model)
        self.data = self.model.createData()
        self.n_legs, self.nq = wb.n_legs, wb.nq
        self.rate = positive(
            "rate", rate if rate is not None else (500.0 if kind == "torque" else 100.0)
        )
        self.dt = 1.0 / self.rate
        self.mu = positive("mu", mu)
        self.armature = 0.0 if armature == 0 else positive("armature", armature)
        self.feet_ids = [self.model.getFrameId(f"{leg}_contact") for leg in wb.leg_names]
        self.mass = float(wb.mass)
        # the legs' columns of v[6:] (the joints moving each foot), from the Jacobian at rest
        q0 = wb.neutral_q()
        self.q_neutral = q0
        qp = wb.pinocchio_q(q0[None], np.eye(4)[None])[0]
        pin.computeJointJacobians(self.model, self.data, qp)
        pin.framesForwardKinematics(self.model, self.data, qp)
        self.cols: list[np.ndarray] = []
        feet0 = []
        for fid in self.feet_ids:
            J = pin.getFrameJacobian(
                self.model, self.data, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
            )
            self.cols.append(np.flatnonzero(np.abs(J[:3, 6:]).sum(axis=0) > 1e-12))
            feet0.append(self.data.oMf[fid].translation.copy())
        self.leg_of_col = np.zeros(self.nq, dtype=int)
        for i, c in enumerate(self.cols):
            self.leg_of_col[c] = i
        #: (L, 3) the feet at rest in the body frame [m]
        self.feet_body = np.array(feet0)
        pin.ccrba(self.model, self.data, qp, np.zeros(self.model.nv))
        self.inertia_body = np.array(self.data.Ig.inertia)
        self.com_body = np.array(self.data.com[0])
        self.height0 = float(-self.feet_body[:, 2].mean())
        self.span = float(wb.leg_span)
        self.effort = np.asarray(wb.effort_limit, dtype=float)
        positions = self.feet_body[:, :2]
        self.positions = positions
        self._pattern = ""
        self._table: Any = None
        self.set_pattern(pattern)
        self.period_given = period
        scale = math.sqrt(max(self.span, 1e-3) / 0.5)
        self._scale = scale
        self.period = positive("period", period) if period is not None else self._period(pattern)
        self.swing_height = (
            positive("swing_height", swing_height)
            if swing_height is not None
            else 0.12 * self.height0 + (float(wb.foot_radius) if kind == "torque" else 0.0)
        )
        self.force_qp = ForceQP(
            mu=self.mu,
            f_min=0.02 * self.mass * _G / self.n_legs,
            f_max=3.0 * self.mass * _G,
            weights=np.array([1.0, 1.0, 1.0, 10.0, 10.0, 10.0]),
        )
        one_of("balance", balance, list(BALANCES))
        self.balance = balance
        self.mpc = ConvexMPC(
            mass=self.mass,
            inertia=self.inertia_body,
            mu=self.mu,
            f_min=0.02 * self.mass * _G / self.n_legs,
            f_max=MPC_FMAX * self.mass * _G,
            horizon=MPC_STEPS,
        )
        self.command = Command()
        self._pending: str | None = None
        self.qp_time = 0.0
        self.reset_state()

    # ------------------------------------------------------------------ configuration
    def _period(self, pattern: str) -> float:
        base = 0.5 if pattern in ("trot", "pace") else 1.0
        return float(base * self._scale)

    def set_pattern(self, pattern: str) -> None:
        """Switch the gait pattern now (see :meth:`set_command` for the switch at a boundary)."""
        from ..gait.tables import phase_table

        self._table = phase_table(pattern, self.n_legs, self.positions)
        self._pattern = pattern

    @property
    def pattern(self) -> str:
        """The gait pattern in use."""
        return self._pattern

    def set_command(self, command: Command) -> None:
        """Take a new command; a pattern change waits for the next cycle boundary."""
        if command.pattern is not None and command.pattern != self._pattern:
            from ..gait.tables import phase_table

            phase_table(command.pattern, self.n_legs, self.positions)  # refuse it now
            self._pending = command.pattern
        self.command = command

    # ------------------------------------------------------------------ state
    def reset_state(self) -> None:
        """Forget the path and the schedule (call :meth:`reset` with a measurement)."""
        L = self.n_legs
        self.phase = 0.0
        self.walking = False
        self.in_swing = np.zeros(L, dtype=bool)
        self.touched = np.ones(L, dtype=bool)
        self.footholds = np.zeros((L, 3))
        self.stand_at = np.zeros((L, 3))
        self.v_filt = np.zeros(3)
        self.lift_off = np.zeros((L, 3))
        self.swing_s = np.zeros(L)
        self.path_xy = np.zeros(2)
        self.path_yaw = 0.0
        self.twist = np.zeros(3)
        self.late = np.zeros(L, dtype=bool)
        self.landed = np.zeros(L, dtype=bool)
        self.late_time = np.zeros(L)
        self.height_ref = self.height0
        self.ground_z = 0.0
        self.q_cmd = np.array(self.q_neutral)
        self.integral = np.zeros(6)
        self.return_offset = np.zeros(2)
        self.ready = False
        self._mpc_f = np.zeros((L, 3))
        self._mpc_age = MPC_EVERY
        self._mpc_stance = np.zeros(L, dtype=bool)
        self._mpc_int = np.zeros(2)
        self._mpc_age_ticks = 0
        width = float(np.abs(self.feet_body[:, 1]).mean())
        self.catch = Catch(self.mass, self.dt, width, CATCH_RETURN * self.span)

    def reset(self, m: Measurement, stand_height: float | None = None) -> None:
        """Start from measurement ``m``: the path starts where the robot is.

        Args:
            m: The first measurement.
            stand_height: The height [m] of the tracked point (CoM for torque, base for
                servos) above the feet's centres that ``stand`` and ``walk`` hold (default:
                the measured one). A robot lying down rises to it at a quarter of it per
                second.

        """
        self.reset_state()
        st = self._state(m)
        self.path_xy = st["ref_point"][:2].copy()
        self.path_yaw = _yaw(st["R"])
        self.ground_z = float(st["feet"][:, 2].mean())
        self.stand_at = np.array(st["feet"])
        self.height_ref = float(st["ref_point"][2] - self.ground_z)
        self.stand_height = self.height_ref if stand_height is None else stand_height
        self.q_cmd = np.array(m.q, dtype=float)
        self.ready = True

    def _state(self, m: Measurement) -> dict[str, Any]:
        """Kinematics of the measured state with Pinocchio (feet, Jacobians, CoM, bias)."""
        pin, model, data = self.pin, self.model, self.data
        R = _quat_mat(np.asarray(m.quat, dtype=float))
        B = np.eye(4)
        B[:3, :3], B[:3, 3] = R, m.position
        qp = self.wb.pinocchio_q(np.asarray(m.q, dtype=float)[None], B[None])[0]
        v = np.concatenate([R.T @ np.asarray(m.velocity, float), m.gyro, m.qd])
        pin.forwardKinematics(model, data, qp, v)
        pin.computeJointJacobians(model, data, qp)
        pin.updateFramePlacements(model, data)
        feet = np.array([data.oMf[f].translation for f in self.feet_ids])
        jac = [
            pin.getFrameJacobian(model, data, f, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)[:3]
            for f in self.feet_ids
        ]
        out: dict[str, Any] = {"R": R, "B": B, "qp": qp, "v": v, "feet": feet, "jac": jac}
        if self.kind == "torque":
            out["com"] = np.array(pin.centerOfMass(model, data, qp, v))
            out["vcom"] = np.array(data.vcom[0])
            out["bias"] = np.array(pin.nonLinearEffects(model, data, qp, v))[6:]
            M = np.array(pin.crba(model, data, qp))
            out["M"] = np.triu(M) + np.triu(M, 1).T  # crba fills the upper triangle
            out["ref_point"] = out["com"]
            out["ref_vel"] = out["vcom"]
        else:
            out["ref_point"] = np.array(m.position, dtype=float)
            out["ref_vel"] = np.array(m.velocity, dtype=float)
        return out

    # ------------------------------------------------------------------ schedule
    def _advance(self, m: Measurement) -> np.ndarray:
        """Advance the path and the gait clock by one tick; the scheduled stance (L,)."""
        cmd, dt = self.command, self.dt
        walk = cmd.mode == "walk"
        # the twist ramps to the command at ACCEL (m/s², rad/s²): no step in the reference
        goal = np.array([cmd.vx, cmd.vy, cmd.wz]) if walk else np.zeros(3)
        step = np.array([ACCEL[0], ACCEL[0], ACCEL[1]]) * dt
        self.twist = self.twist + np.clip(goal - self.twist, -step, step)
        Rz = _rz(self.path_yaw)[:2, :2]
        self.path_xy = self.path_xy + Rz @ self.twist[:2] * dt
        self.path_yaw += float(self.twist[2]) * dt
        target = self.stand_height * (cmd.height if cmd.mode == "sit" else 1.0)
        rate = 0.25 * self.stand_height * dt  # a quarter of the height per second
        self.height_ref += float(np.clip(target - self.height_ref, -rate, rate))
        if not walk and not self.in_swing.any():
            self.walking = False
            self.phase = 0.0
        if walk:
            self.walking = True
        if self.walking:
            # the clock holds while a foot due down has not touched (no lift-off before it)
            # (a quarter of a swing at most)
            limit = 0.25 * (1.0 - self._table.duty_factor) * self.period
            hold = bool(np.any(self.late & (self.late_time < limit)))
            new = self.phase + (0.0 if hold else dt / self.period)
            if new >= 1.0:
                new -= 1.0
                if self._pending is not None:
                    self.set_pattern(self._pending)
                    self._pending = None
                    if self.period_given is None:
                        self.period = self._period(self._pattern)
                if not walk:
                    self.walking = False
                    new = 0.0
            self.phase = new
        if not self.walking:
            return np.ones(self.n_legs, dtype=bool)
        tab = self._table
        beta = tab.duty_factor
        ph = (self.phase + np.asarray(tab.offsets)) % 1.0
        self.swing_s = np.clip((ph - beta) / (1.0 - beta), 0.0, 1.0)
        return ph < beta

    def _swing_targets(
        self, st: dict[str, Any], legs: np.ndarray, progress: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """World targets, velocities and accelerations (L, 3) of the swing feet ``legs``.

        ``progress`` (L,) is each leg's swing fraction (1: due down, not touching yet).
        """
        tab, T = self._table, self.period
        beta = tab.duty_factor
        t_st, t_sw = beta * T, (1.0 - beta) * T
        Rz = _rz(self.path_yaw)
        v_ref = Rz @ np.array([*self.twist[:2], 0.0])
        v = np.array(self.v_filt)
        k_v = math.sqrt(self.height_ref / _G)
        p_out = np.zeros((self.n_legs, 3))
        v_out = np.zeros((self.n_legs, 3))
        a_out = np.zeros((self.n_legs, 3))
        if self.kind == "torque":  # Raibert: about the measured hips, the path as a speed
            ref = np.array([*st["B"][:2, 3], 0.0])
            err = np.array([*(self.path_xy + self.catch.ret - st["ref_point"][:2]), 0.0])
            v_ref = v_ref + np.clip(1.0 * err, -0.3, 0.3)
        else:  # servo posing: about the hips of the body on its path
            ref = np.array([*self.path_xy, 0.0])
        if self.kind == "torque" and self.balance == "mpc":
            # up as sin(π s), down as sin²(π s) (the same height and rate at s = 1/2): the
            # foot leaves the ground at once and comes down at rest (no impact kicking the body)
            sp = np.asarray(progress)
            up = sp < 0.5
            lift = np.where(up, np.sin(np.pi * sp), np.sin(np.pi * sp) ** 2)
            lift_rate = np.where(up, np.cos(np.pi * sp), np.sin(2 * np.pi * sp))
            lift_acc = np.where(up, -np.sin(np.pi * sp), 2 * np.cos(2 * np.pi * sp))
        else:  # sin(π s) and its rates
            lift = np.sin(np.pi * np.asarray(progress))
            lift_rate = np.cos(np.pi * np.asarray(progress))
            lift_acc = -lift
        for i in np.flatnonzero(legs):
            s = float(progress[i])
            if s > 0.7:  # the foothold frozen for the last 30 % of the swing
                target = self.footholds[i]
            else:
                target = None
            t_left = (1.0 - s) * t_sw
            # the hip where the body will be at touch-down (on the path, yawed by then)
            yaw_td = self.path_yaw + float(self.twist[2]) * (t_left + t_st / 2)
            hip = ref + v_ref * t_left + _rz(yaw_td) @ np.array([*self.feet_body[i, :2], 0.0])
            if target is None:
                target = hip + v_ref * t_st / 2 + k_v * (v - v_ref)
                # within reach: at most 0.35 span from the neutral foot under the body now
                home = st["B"][:3, 3] + st["R"] @ self.feet_body[i]
                off = target[:2] - home[:2]
                n = float(np.linalg.norm(off))
                if n > 0.35 * self.span:
                    target[:2] = home[:2] + off * (0.35 * self.span / n)
                if self.kind == "torque" and self.balance == "mpc":
                    target = self._clear_of_stance(st, legs, int(i), target)
                self.footholds[i] = target
            step = target - self.lift_off[i]
            lim = 1.0 * self.span
            n = float(np.linalg.norm(step[:2]))
            if n > lim:
                step[:2] *= lim / n
            z0 = self.lift_off[i, 2]
            h = self.swing_height
            # servos lag their targets: the foot is above its foothold at s = ARRIVE
            a = ARRIVE if self.kind == "servo" else 1.0
            u = min(1.0, s / a)
            sh = 3 * u * u - 2 * u**3
            dsh = (6 * u - 6 * u * u) / (a * t_sw) if u < 1.0 else 0.0
            ddsh = (6 - 12 * u) / (a * t_sw) ** 2 if u < 1.0 else 0.0
            p = self.lift_off[i] + np.array([step[0] * sh, step[1] * sh, 0.0])
            if self.kind == "torque":
                # at s = 1 at the lift-off height, coming down at the landing speed v:
                # z0 + h lift + v T_sw (1 − s) s⁴
                v_land = LAND * h / t_sw
                p[2] = z0 + h * lift[i] + v_land * t_sw * (1 - s) * s**4
                vz = h * math.pi / t_sw * lift_rate[i] + v_land * (4 * s**3 - 5 * s**4)
                az = (
                    h * (math.pi / t_sw) ** 2 * lift_acc[i]
                    + v_land * (12 * s * s - 20 * s**3) / t_sw
                )
                acc = np.array([step[0] * ddsh, step[1] * ddsh, az])
                if s >= 1.0:  # scheduled down but not touching: on down at the landing speed
                    p = np.array([*self.footholds[i, :2], st["feet"][i, 2]])
                    vz, acc = -v_land, np.zeros(3)
            else:
                sm = 3 * s * s - 2 * s**3
                dsm = (6 * s - 6 * s * s) / t_sw
                dz = 0.25 * h  # aim below the lift-off height: the touch stops the foot
                p[2] = z0 - dz * sm + h * lift[i]
                vz = -dz * dsm + h * math.pi / t_sw * lift_rate[i]
                acc = np.zeros(3)
                if s >= 1.0:  # scheduled down but not touching: keep going down
                    p = np.array([*self.footholds[i, :2], st["feet"][i, 2] - dz])
                    vz = -h / t_sw
            vel = np.array([step[0] * dsh, step[1] * dsh, vz])
            if s >= 1.0:
                vel[:2] = 0.0
            p_out[i], v_out[i], a_out[i] = p, vel, acc
        return p_out, v_out, a_out

    def _clear_of_stance(
        self, st: dict[str, Any], swing: np.ndarray, i: int, target: np.ndarray
    ) -> np.ndarray:
        """Foothold ``target`` of swing leg ``i``, kept clear of the other legs.

        On its own side of the body (at least :data:`SIDE` of its neutral lateral offset from
        the body's centre line) and at least :data:`CLEAR` of the leg span from every
        standing foot (pushed away from it, or outwards when on it).
        """
        out = np.array(target, dtype=float)
        base = st["B"][:3, 3]
        Rz = _rz(self.path_yaw)
        local = Rz.T @ (out - base)
        side = math.copysign(1.0, float(self.feet_body[i, 1]))
        y_min = SIDE * abs(float(self.feet_body[i, 1]))
        if side * local[1] < y_min:
            local[1] = side * y_min
            out[:2] = (base + Rz @ local)[:2]
        d_min = CLEAR * self.span
        for j in np.flatnonzero(~swing):
            d = out[:2] - st["feet"][j, :2]
            n = float(np.linalg.norm(d))
            if n < d_min:
                u = d / n if n > 1e-9 else side * Rz[:2, 1]
                out[:2] = st["feet"][j, :2] + u * d_min
        return out

    def _contacts(self, sched: np.ndarray, m: Measurement) -> np.ndarray:
        """Stance legs: scheduled, or touched down after 60 % of their swing.

        Torque kind: an early touch-down holds the leg in stance until its scheduled stance
        begins (a foot bouncing off the ground is not swung again).
        """
        touch = np.asarray(m.contacts, dtype=bool)
        early = touch & (self.swing_s > 0.6) & self.in_swing
        if self.kind == "servo":  # an early touch counts while it lasts
            return sched | early
        self.landed = (self.landed | early) & ~sched & self.walking
        return sched | self.landed

    # ------------------------------------------------------------------ the tick
    def tick(self, m: Measurement) -> np.ndarray:
        """One control step: joint torques [N·m] (torque kind) or joint targets [rad]."""
        if not self.ready:
            self.reset(m)
        st = self._state(m)
        # the velocity low-passed over 1/20 cycle (torque) or 1/4 cycle (servos: the body
        # rocks on its compliant servos)
        a = min(1.0, self.dt / ((0.05 if self.kind == "torque" else 0.25) * self.period))
        self.v_filt = (1 - a) * self.v_filt + a * np.array([*st["ref_vel"][:2], 0.0])
        if self.kind == "torque" and self.balance == "mpc":  # a push: the MPC's catching mode
            v_ref = _rz(self.path_yaw) @ np.array([*self.twist[:2], 0.0])
            error = float(np.linalg.norm(self.v_filt[:2] - v_ref[:2]))
            self.catch.mode(math.sqrt(self.height_ref / _G) * error, self.walking)
        sched = self._advance(m)
        stance = self._contacts(sched, m)
        # lift-off bookkeeping
        for i in range(self.n_legs):
            if not stance[i] and not self.in_swing[i]:
                self.in_swing[i] = True
                self.lift_off[i] = st["feet"][i]
            elif stance[i] and self.in_swing[i] and sched[i]:
                self.in_swing[i] = False
            elif stance[i] and self.in_swing[i]:
                self.in_swing[i] = False  # early touch-down
        touch = np.asarray(m.contacts, dtype=bool)
        new = touch & stance & ~self.touched
        self.touched = (self.touched | touch) & stance
        if not self.walking:
            self.touched[:] = True
        for i in np.flatnonzero(new).tolist():  # touch-down: where the foot stands, the ground
            self.stand_at[i] = st["feet"][i]
            self.ground_z = 0.8 * self.ground_z + 0.2 * float(st["feet"][i, 2])
        stance = stance & self.touched  # a foot still coming down is swung down
        self.late = sched & ~stance
        self.late_time = np.where(self.late, self.late_time + self.dt, 0.0)
        swing = ~stance
        s_eff = np.where(sched, 1.0, self.swing_s)
        p_sw, v_sw, a_sw = self._swing_targets(st, swing, s_eff)
        if self.kind == "torque":
            return self._torques(st, stance, swing, p_sw, v_sw, a_sw)
        return self._servo(st, stance, swing, p_sw, m)

    def _desired_rotation(self) -> np.ndarray:
        return _rz(self.path_yaw)

    def _torques(
        self,
        st: dict[str, Any],
        stance: np.ndarray,
        swing: np.ndarray,
        p_sw: np.ndarray,
        v_sw: np.ndarray,
        a_sw: np.ndarray,
    ) -> np.ndarray:
        import time

        R = st["R"]
        tau = np.zeros(self.nq)
        v = st["v"]
        bias = st["bias"]
        # swing legs: the foot's PD and its path's acceleration through the leg's
        # operational-space inertia (its joints' mass matrix, rotors included), plus the bias
        w_sw = 2.0 * math.pi * SWING_HZ
        M = st["M"]
        for i in np.flatnonzero(swing):
            c = self.cols[i]
            J = st["jac"][i]
            Jc = J[:, 6 + c]
            M_leg = M[np.ix_(6 + c, 6 + c)] + self.armature * np.eye(len(c))
            lam = np.linalg.pinv(Jc @ np.linalg.solve(M_leg, Jc.T), rcond=1e-6)
            e, ed = p_sw[i] - st["feet"][i], v_sw[i] - J @ v
            f = lam @ (w_sw**2 * e + 2.0 * 0.7 * w_sw * ed + a_sw[i])
            tau[c] = Jc.T @ f + bias[c]
        legs = np.flatnonzero(stance)
        if len(legs):
            com, vcom = st["com"], st["vcom"]
            Rz = _rz(self.path_yaw)
            v_ref = Rz @ np.array([*self.twist[:2], 0.0])
            p_ref = np.array([*self.path_xy, self.ground_z + self.height_ref])
            wp, wz_, wr = 2 * math.pi * 1.2, 2 * math.pi * 2.0, 2 * math.pi * 3.0
            kp = np.array([wp**2, wp**2, wz_**2])
            kd = np.array([2 * 0.9 * wp, 2 * 0.9 * wp, 2 * 0.9 * wz_])
            e_p = p_ref - com
            # an integral of the CoM's lag (a steady lag: swing reactions, slips),
            # along the path's heading only (a lateral integral makes a trot sway)
            ki = wp**3 * KI_FRAC
            cap = ACC_I / max(ki, 1e-9)
            ahead = Rz[:2, 0]
            e_along = float(ahead @ e_p[:2])
            self.integral[0] = float(np.clip(self.integral[0] + e_along * self.dt, -cap, cap))
            acc = kp * e_p + kd * (v_ref - vcom) + np.array([0.0, 0.0, _G])
            acc[:2] += ki * self.integral[0] * ahead
            F = self.mass * acc
            Rd = self._desired_rotation()
            omega = R @ st["v"][3:6]
            omega_ref = np.array([0.0, 0.0, float(self.twist[2])])
            Iw = R @ self.inertia_body @ R.T
            M = Iw @ (wr**2 * _log3(Rd @ R.T) + 2 * 0.9 * wr * (omega_ref - omega))
            r = st["feet"][legs] - com
            jac = [st["jac"][i][:, 6 + self.cols[i]] for i in legs]
            biases = [bias[self.cols[i]] for i in legs]
            lims = [self.effort[self.cols[i]] for i in legs]
            t0 = time.process_time()
            if self.balance == "mpc":
                torque = {int(i): (jac[k], biases[k], lims[k]) for k, i in enumerate(legs)}
                f = self._mpc_forces(st, stance, v_ref, p_ref, torque)[legs]
            else:
                f = self.force_qp.solve(np.concatenate([F, M]), r, jac, biases, lims)
            self.qp_time += time.process_time() - t0
            for k, i in enumerate(legs):
                c = self.cols[i]
                tau[c] = bias[c] - jac[k].T @ f[k]
        return np.clip(tau, -self.effort, self.effort)

    def _mpc_forces(
        self,
        st: dict[str, Any],
        stance: np.ndarray,
        v_ref: np.ndarray,
        p_ref: np.ndarray,
        torque: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]],
    ) -> np.ndarray:
        """The stance forces (L, 3) [N] of :class:`~.mpc.ConvexMPC`.

        Solved every :data:`MPC_EVERY` ticks and whenever the stance set changes (held in
        between), from the trunk's state, the path ahead, the gait's contact schedule and
        the feet's footholds; the standing legs' forces within their joint torque limits
        (``torque``: leg → its foot Jacobian over its joints, bias torques, limits).
        """
        R = st["R"]
        omega = R @ st["v"][3:6]
        arm = R @ self.com_body
        vcom = R @ st["v"][:3] + np.cross(omega, arm)
        off = st["com"][:2] - self.path_xy
        self.catch.observe(vcom, self._mpc_f[stance].sum(axis=0), off)
        self._mpc_age += 1
        if self._mpc_age < MPC_EVERY and np.array_equal(stance, self._mpc_stance):
            return self._mpc_f
        self._mpc_age_ticks = self._mpc_age
        self._mpc_age, self._mpc_stance = 0, stance.copy()
        N = MPC_STEPS
        tab, T = self._table, self.period
        dt = T / MPC_DIV
        # the rigid body's state: the robot's CoM, moving with the trunk (the swing legs'
        # motion is not the body's)
        com = st["com"]
        # an integral of the height error and of the lag along the path (the swing legs'
        # reactions and touch-downs are not in the model) moves the reference
        # (while walking only: standing, sitting and rising track their heights without it)
        ahead = _rz(self.path_yaw)[:, 0]
        p_ref = p_ref + np.array([*self.catch.ret, 0.0])
        e = p_ref - com
        step = self.dt * self._mpc_age_ticks * float(self.walking)
        self._mpc_int[0] = np.clip(self._mpc_int[0] + float(ahead @ e) * step, -MPC_INT, MPC_INT)
        self._mpc_int[1] = np.clip(self._mpc_int[1] + float(e[2]) * step, -MPC_INT, MPC_INT)
        p_ref = p_ref + MPC_KI * (self._mpc_int[0] * ahead + np.array([0, 0, self._mpc_int[1]]))
        th = np.array(matrix_to_rpy(R))
        th[2] = self.path_yaw + math.remainder(th[2] - self.path_yaw, 2 * math.pi)
        x0 = np.concatenate([th, com, omega, vcom])
        t = dt * np.arange(1, N + 1)
        wz = float(self.twist[2])
        ref = np.zeros((N, 12))
        ref[:, 2] = self.path_yaw + wz * t
        ref[:, 3:6] = p_ref + t[:, None] * v_ref
        ref[:, 8] = wz
        ref[:, 9:12] = v_ref
        if self.walking:
            contact = schedule(self.phase, tab.offsets, tab.duty_factor, dt / T, N)
        else:
            contact = np.ones((N, self.n_legs), dtype=bool)
        contact[0] = stance
        # where each foot stands during the horizon: the standing ones where they are, the
        # others at their footholds (a nominal one when the swing has not planned it yet)
        t_st = tab.duty_factor * T
        feet = np.array(st["feet"])
        for i in np.flatnonzero(~stance):
            feet[i] = self.footholds[i]
        levers = np.zeros((N, self.n_legs, 3))
        for k in range(N):
            if k > 0:  # a foot landing again in the horizon: under its hip, Raibert's rule
                for i in np.flatnonzero(contact[k] & ~contact[k - 1] & stance):
                    hip = com + t[k] * v_ref + _rz(ref[k, 2]) @ self.feet_body[i]
                    feet[i] = [*(hip[:2] + v_ref[:2] * t_st / 2), self.ground_z]
            levers[k] = feet - (com + t[k] * v_ref)
        w = self.catch.weights(self.mpc.weights)
        self._mpc_f = self.mpc.solve(
            x0, ref, contact, levers, dt, self.catch.accel(), w, torque=torque
        )
        return self._mpc_f

    def _servo(
        self,
        st: dict[str, Any],
        stance: np.ndarray,
        swing: np.ndarray,
        p_sw: np.ndarray,
        m: Measurement,
    ) -> np.ndarray:
        R, pos = st["R"], np.asarray(m.position, dtype=float)
        # the body's reference pose and its error (position, rotation vector)
        Rd = self._desired_rotation()
        lim = 0.08 * self.span
        # the body's goal: the path, returned to at RETURN_SPEED when the body is off it (a
        # push), never more than ``lim`` from the body (the steps carry it back; standing,
        # with no steps, it stays where the push left the body: the feet would be dragged)
        off = pos[:2] - self.path_xy
        d = self.return_offset
        n = float(np.linalg.norm(d))
        speed = RETURN_SPEED * self.span * float(self.walking)
        d = d * max(0.0, 1.0 - speed * self.dt / n) if n > 0 else d
        self.return_offset = d = np.clip(d, off - lim, off + lim)
        p_ref = np.array([*(self.path_xy + d), self.ground_z + self.height_ref])
        e = np.concatenate([p_ref - pos, _log3(Rd @ R.T)])
        e[:3] = np.clip(e[:3], -lim, lim)
        self.integral = np.clip(self.integral + 2.0 * self.dt * e, -lim, lim)
        corr = e + self.integral
        Bc = np.eye(4)
        Bc[:3, 3] = pos + corr[:3]
        Bc[:3, :3] = _rot(corr[3:6]) @ R
        # a standing foot that slipped (a push) is held where it is, within ``slip`` of it: held
        # where it was, the legs would carry the body on in the push's direction
        slip = SLIP * self.span
        gap = self.stand_at[:, :2] - st["feet"][:, :2]
        dist = np.linalg.norm(gap, axis=1)
        far = stance & np.asarray(m.contacts, dtype=bool) & (dist > slip)
        if far.any():
            self.stand_at[far, :2] = st["feet"][far, :2] + gap[far] * (slip / dist[far])[:, None]
        targets = np.where(stance[:, None], self.stand_at, p_sw)
        q = self._leg_ik(Bc, targets)
        self.q_cmd = q
        return np.array(q)

    def _leg_ik(self, B: np.ndarray, targets: np.ndarray) -> np.ndarray:
        """Joints [rad] that put the feet at ``targets`` (L, 3) under body pose ``B``.

        The whole body's :meth:`~hexapod_kin.gait.robot.WholeBody.body_ik` (each leg's closed
        form where it has one, else the package's one IK loop; the branch nearest the last
        command); a leg out of reach keeps its last command. Measured against two steps of the
        IK loop per tick: the same pushes recovered (9 of 10), but over ±10 mm bumps the
        heading stays within 1.4° where the steps let it turn 2.5–5.3°.
        """
        ik = self.wb.body_ik(B, targets, q_prev=self.q_cmd, strict=False)
        q = np.where(ik.reached[0][self.leg_of_col], ik.q[0], self.q_cmd)
        return np.clip(q, self.wb.lower, self.wb.upper)
