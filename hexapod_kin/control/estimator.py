r"""Base state estimation from the IMU and the legs: a contact-aided linear Kalman filter.

The filter of MIT's Cheetah-Software (``LinearKFPositionVelocityEstimator``; Bledt et al.,
IROS 2018) for any number of feet. The state is the base position and velocity and the feet
positions, all in the world frame,

.. math::

    x = (p, v, p_1, \dots, p_L) \in \mathbb{R}^{6 + 3L},

propagated by the accelerometer (its specific force rotated to the world by the IMU's
attitude, gravity added back): ``p ← p + v dt``, ``v ← v + a dt``, feet constant. Each tick
measures, per foot *i*, its position relative to the base ``p_i − p = R r_i(q)`` and the
base velocity it implies when the foot's contact point stands still,
``v = −(ω × R r_i + R J_i(q) q̇ + ω_i × (−ρ ẑ))`` (``ρ`` the foot sphere's radius, ``ω_i``
its angular velocity: the sphere rolls; all from the joint encoders and Pinocchio's
kinematics), and its height ``p_i,z = z_ground + r_foot`` (flat ground assumed). A foot in
swing (not touching, or not in the controller's stance) is not trusted: its process and
measurement noises are multiplied by ``SUSPECT``, so the filter follows the standing feet.
The horizontal position is not observable (it drifts as odometry does); height and velocity
are.

The leg-odometry velocity is trusted per actuator kind (:data:`VEL_NOISE`): a torque-controlled
leg lets its foot sphere roll as the model says, but position servos hold the foot sphere's
centre where the controller put it, so its contact point slides instead of rolling, and a
light robot's feet bounce: that velocity is biased, and the feet's positions, which carry
the same information, are trusted instead.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["StateEstimator"]

#: The noise multiplier of a foot in swing (its measurements are not trusted).
SUSPECT = 100.0

#: The default measurement noise [m/s] of the leg-odometry velocity per controller kind
#: (see the module docstring).
VEL_NOISE = {"torque": 0.1, "servo": 1.0}


class StateEstimator:
    """The base position and velocity from IMU, joints and contacts (see the module).

    Args:
        controller: The :class:`~.controller.Controller` whose robot model gives the feet's
            kinematics.
        ground: The ground height the standing feet are assumed at [m].
        accel_noise: Process noise density of the base velocity [m/s²] (per √tick).
        foot_noise: Process noise of a standing foot's position [m] (per tick).
        kin_noise: Measurement noise of a foot's relative position [m].
        vel_noise: Measurement noise of the leg-odometry velocity [m/s] (default:
            :data:`VEL_NOISE` of the controller's kind).
        height_noise: Measurement noise of a standing foot's height [m].

    """

    def __init__(
        self,
        controller: Any,
        *,
        ground: float = 0.0,
        accel_noise: float = 0.2,
        foot_noise: float = 0.002,
        kin_noise: float = 0.002,
        vel_noise: float | None = None,
        height_noise: float = 0.005,
    ) -> None:
        self.ctl = controller
        self.L = controller.n_legs
        self.dt = controller.dt
        self.radius = float(controller.wb.foot_radius)
        self.foot_z = float(ground) + self.radius
        if vel_noise is None:
            vel_noise = VEL_NOISE[controller.kind]
        self.noise = (accel_noise, foot_noise, kin_noise, vel_noise, height_noise)
        n = 6 + 3 * self.L
        self.x = np.zeros(n)
        self.P = np.eye(n) * 1e-4
        self.ready = False

    def _feet(self, R: np.ndarray, gyro: np.ndarray, q: np.ndarray, qd: np.ndarray) -> Any:
        """Feet relative to the base (world axes) and their velocities with the base fixed."""
        pin, model, data = self.ctl.pin, self.ctl.model, self.ctl.data
        B = np.eye(4)
        B[:3, :3] = R
        qp = self.ctl.wb.pinocchio_q(q[None], B[None])[0]
        v = np.concatenate([np.zeros(3), gyro, qd])
        pin.forwardKinematics(model, data, qp, v)
        pin.updateFramePlacements(model, data)
        rel = np.array([data.oMf[f].translation for f in self.ctl.feet_ids])
        frame = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        # the contact point's velocity: a foot sphere rolls (its centre moves ω × r ẑ)
        down = np.array([0.0, 0.0, -self.radius])
        vel = []
        for f in self.ctl.feet_ids:
            tw = pin.getFrameVelocity(model, data, f, frame)
            vel.append(np.array(tw.linear) + np.cross(np.array(tw.angular), down))
        return rel, np.array(vel)

    def reset(self, position: np.ndarray, velocity: np.ndarray, m: Any) -> None:
        """Start from a known base position and velocity [m, m/s] and measurement ``m``."""
        from .controller import _quat_mat

        R = _quat_mat(np.asarray(m.quat, dtype=float))
        rel, _ = self._feet(R, np.asarray(m.gyro, float), np.asarray(m.q, float), m.qd)
        self.x[:3], self.x[3:6] = position, velocity
        self.x[6:] = (np.asarray(position, float) + rel).reshape(-1)
        self.P = np.eye(len(self.x)) * 1e-4
        self.ready = True

    def update(self, m: Any, accel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One tick of the filter: the base position [m] and velocity [m/s] (world).

        Args:
            m: The tick's :class:`~.controller.Measurement` (its ``position`` and
                ``velocity`` ignored).
            accel: (3,) the accelerometer's specific force in the body frame [m/s²].

        Returns:
            The estimated base position and velocity.

        """
        from .controller import _quat_mat

        L, dt = self.L, self.dt
        qa, qf, rk, rv, rh = self.noise
        R = _quat_mat(np.asarray(m.quat, dtype=float))
        a = R @ np.asarray(accel, dtype=float) + np.array([0.0, 0.0, -9.81])
        n = 6 + 3 * L
        A = np.eye(n)
        A[:3, 3:6] = dt * np.eye(3)
        x = A @ self.x
        x[3:6] += a * dt
        # standing: touching and in the controller's stance (a light robot's feet bounce)
        touch = np.asarray(m.contacts, dtype=bool) & ~self.ctl.in_swing
        trust = np.where(touch, 1.0, SUSPECT)
        Q = np.zeros(n)
        Q[:3] = (qa * dt * dt) ** 2
        Q[3:6] = (qa * dt) ** 2
        Q[6:] = np.repeat((qf * trust) ** 2, 3)
        P = A @ self.P @ A.T + np.diag(Q)
        rel, vel = self._feet(R, np.asarray(m.gyro, float), np.asarray(m.q, float), m.qd)
        # measurements: p_i − p = rel_i, v = −vel_i, p_i,z = foot_z
        y = np.concatenate([rel.reshape(-1), -vel.reshape(-1), np.full(L, self.foot_z)])
        C = np.zeros((7 * L, n))
        for i in range(L):
            C[3 * i : 3 * i + 3, :3] = -np.eye(3)
            C[3 * i : 3 * i + 3, 6 + 3 * i : 9 + 3 * i] = np.eye(3)
            C[3 * L + 3 * i : 3 * L + 3 * i + 3, 3:6] = np.eye(3)
            C[6 * L + i, 8 + 3 * i] = 1.0
        Rn = np.concatenate(
            [np.repeat((rk * trust) ** 2, 3), np.repeat((rv * trust) ** 2, 3), (rh * trust) ** 2]
        )
        S = C @ P @ C.T + np.diag(Rn)
        K = np.linalg.solve(S, C @ P).T
        self.x = x + K @ (y - C @ x)
        self.P = (np.eye(n) - K @ C) @ P
        self.P = 0.5 * (self.P + self.P.T)
        return self.x[:3].copy(), self.x[3:6].copy()
