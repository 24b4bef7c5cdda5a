"""The result of a walk: :class:`GaitRun`, the samples and every check's figures.

:func:`~.walk.walk` plans it; the viewer, the plots, the simulator and the timelines read it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..exceptions import ConfigurationError
from .robot import WholeBody
from .tables import PhaseTable
from .zmp import rates

__all__ = ["GaitRun"]


@dataclass(frozen=True)
class GaitRun:
    """A walk of the whole robot sampled in time (arrays read-only, SI units).

    Attributes:
        t: (N,) times [s].
        base_poses: (N, 4, 4) body poses ``worldMbody`` (the free-flyer's placement).
        feet: (N, L, 3) foot-sphere centres in the world by forward kinematics of ``q`` [m].
        feet_planned: (N, L, 3) planned feet [m].
        q: (N, nq) joint angles [rad] (in ``joint_names`` order).
        qdot: (N, nq) joint rates [rad/s] (second-order finite differences).
        support: (N, L) True for the stance feet (the support set).
        phase: (N, L) gait phase in cycles [0, 1) (stance below the duty factor).
        com: (N, 3) whole-body centre of mass in the world [m].
        slip: (N, L) slide of each stance foot's contact point since the stance's first
            sample [m] (0 in swing): ``‖c − c_s − D‖``, c the sphere's centre by FK, D its
            rolling (:func:`.paths.rolling_offsets`).
        margin: (N,) static stability margin [m] (negative: CoM outside the support polygon).
        limit_margin: (N, nq) distance of each joint to its nearest limit [rad].
        ik_ok: (N, L) True where the leg's IK reached its foot inside the joint limits.
        reach_excess: (N, L) distance a foot is out of its leg's reach [m] (0 if reached).
        clearance: (N, P) surface gap between the links of each neighbouring pair [m].
        pairs: The neighbouring pairs, by leg index.
        leg_names: The legs.
        joint_names: The joints.
        table: The phase table used.
        settings: The walk's parameters (stride [m], step_height [m], period [s],
            duty_factor, velocity (vx [m/s], vy [m/s], wz [rad/s]), body_height [m],
            foot_reach [m], terrain, duration [s], rate [Hz], foot_radius [m], sway,
            rolling_passes, rolling_residual [m], margin_tol [m]).
        mass: Total mass [kg].
        qddot: (N, nq) joint accelerations [rad/s²] (second differences).
        velocity_limit: (nq,) the joints' velocity limits [rad/s] (inf: none).
        accel_limit: (nq,) the acceleration limits checked [rad/s²] (inf: none given).
        robot: The whole-robot model that walked (for viewers and simulators).
        normals: (N, L, 3) the ground's unit normal at each foot's current or next contact
            (the contact point: ``feet − foot_radius · normals``).
        foot_gap: (N, L) how far each foot sphere clears the terrain [m] (sampled,
            :func:`.stability.terrain_clearance`; 0 in stance, negative: into it).
        leg_gap: (N, L) how far each leg's links clear the terrain above its foot's ground
            [m] (:func:`.stability.leg_terrain_clearance`).
        zmp_margin: (N,) the zero-moment point's (:func:`.zmp.zmp_points`) signed distance to
            the support polygon's edge [m]. Reported, not a check.

    """

    t: np.ndarray
    base_poses: np.ndarray
    feet: np.ndarray
    feet_planned: np.ndarray
    q: np.ndarray
    qdot: np.ndarray
    support: np.ndarray
    phase: np.ndarray
    com: np.ndarray
    slip: np.ndarray
    margin: np.ndarray
    limit_margin: np.ndarray
    ik_ok: np.ndarray
    reach_excess: np.ndarray
    clearance: np.ndarray
    pairs: tuple[tuple[int, int], ...]
    leg_names: tuple[str, ...]
    joint_names: tuple[str, ...]
    table: PhaseTable
    settings: dict[str, Any] = field(default_factory=dict)
    mass: float = 0.0
    qddot: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    velocity_limit: np.ndarray = field(default_factory=lambda: np.zeros(0))
    accel_limit: np.ndarray = field(default_factory=lambda: np.zeros(0))
    robot: WholeBody | None = field(default=None, repr=False)
    normals: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 3)))
    foot_gap: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    leg_gap: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    zmp_margin: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def min_zmp_margin(self) -> float:
        """Smallest dynamic (zero-moment point) stability margin over the run [m] (nan: none)."""
        return float(self.zmp_margin.min()) if self.zmp_margin.size else math.nan

    @property
    def min_margin(self) -> float:
        """Smallest stability margin over the run [m]."""
        return float(self.margin.min())

    @property
    def max_slip(self) -> float:
        """Largest stance-foot slip over the run [m]."""
        return float(self.slip.max())

    @property
    def min_limit_margin(self) -> float:
        """Smallest joint-limit margin over the run [rad]."""
        return float(self.limit_margin.min())

    @property
    def min_clearance(self) -> float:
        """Smallest gap between the links of neighbouring legs over the run [m]."""
        return float(self.clearance.min()) if self.clearance.size else math.inf

    @property
    def max_foot_error(self) -> float:
        """Largest distance between the feet by FK and the planned feet [m]."""
        return float(np.linalg.norm(self.feet - self.feet_planned, axis=-1).max())

    @property
    def statically_stable(self) -> bool:
        """False for patterns that are not statically stable (trot, pace): margin not checked."""
        return self.table.statically_stable

    @property
    def margin_ok(self) -> bool:
        """The margin check: ``min_margin > −margin_tol`` (always True if not statically stable)."""
        tol = float(self.settings.get("margin_tol", 0.0))
        return (not self.statically_stable) or self.min_margin > -tol

    @property
    def max_joint_speed(self) -> np.ndarray:
        """(nq,) largest |q̇| of each joint over the run [rad/s]."""
        return np.abs(self.qdot).max(axis=0) if self.qdot.size else np.zeros(self.q.shape[1])

    @property
    def max_joint_accel(self) -> np.ndarray:
        """(nq,) largest |q̈| of each joint over the run [rad/s²]."""
        return np.abs(self.qddot).max(axis=0) if self.qddot.size else np.zeros(self.q.shape[1])

    @property
    def speed_ok(self) -> bool:
        """Every joint within its velocity limit (and acceleration limit, if given)."""
        lim = self.velocity_limit if self.velocity_limit.size else np.inf
        acc = self.accel_limit if self.accel_limit.size else np.inf
        return bool(
            np.all(self.max_joint_speed <= lim * (1 + 1e-9))
            and np.all(self.max_joint_accel <= acc * (1 + 1e-9))
        )

    @property
    def ok(self) -> bool:
        """True when every check passes at every sample (margin only if statically stable)."""
        return bool(
            self.ik_ok.all()
            and self.margin_ok
            and self.min_limit_margin >= 0
            and self.min_clearance > 0
            and self.max_slip <= 1e-9
            and self.speed_ok
            and (not self.foot_gap.size or self.foot_gap.min() >= -1e-9)
            and (not self.leg_gap.size or self.leg_gap.min() >= -1e-9)
        )

    def pinocchio_q(self) -> np.ndarray:
        """Pinocchio free-flyer configurations (N, nq): xyz, quaternion (x, y, z, w), joints.

        Raises:
            ConfigurationError: A run without its robot (``robot=None``).

        """
        if self.robot is None:
            raise ConfigurationError(
                "this run carries no robot (robot=None): its Pinocchio configurations are "
                "the robot's (WholeBody.pinocchio_q)",
                parameter="robot",
            )
        return self.robot.pinocchio_q(self.q, self.base_poses)

    def _base_rates(self) -> tuple[np.ndarray, np.ndarray]:
        p = self.base_poses[:, :3, 3]
        yaw = np.unwrap(np.arctan2(self.base_poses[:, 1, 0], self.base_poses[:, 0, 0]))
        return rates(np.concatenate([p, yaw[:, None]], axis=1), self.t)

    def base_velocity(self) -> np.ndarray:
        """Body twist (N, 6) in the body frame, Pinocchio's ``v[:6] = (Rᵀ ṗ, ω)`` [m/s, rad/s].

        By second-order finite differences of :attr:`base_poses` (a level body: ω = (0, 0, ψ̇)).
        """
        rate, _ = self._base_rates()
        out = np.zeros((len(self.t), 6))
        out[:, :3] = np.einsum("nji,nj->ni", self.base_poses[:, :3, :3], rate[:, :3])
        out[:, 5] = rate[:, 3]
        return out

    def base_acceleration(self) -> np.ndarray:
        """The free-flyer's acceleration (N, 6), Pinocchio's ``a[:6] = d/dt v[:6]``.

        ``(Rᵀ p̈ − ω × Rᵀ ṗ, ω̇)`` with p̈ and ψ̈ by second differences (the classical
        acceleration of the body origin is ``p̈``).
        """
        rate, acc = self._base_rates()
        v = self.base_velocity()
        out = np.zeros((len(self.t), 6))
        out[:, :3] = np.einsum("nji,nj->ni", self.base_poses[:, :3, :3], acc[:, :3])
        out[:, :3] -= np.cross(v[:, 3:], v[:, :3])
        out[:, 5] = acc[:, 3]
        return out

    def pinocchio_v(self) -> np.ndarray:
        """Pinocchio free-flyer velocities (N, 6 + nq): :meth:`base_velocity` then ``qdot``."""
        return np.concatenate([self.base_velocity(), self.qdot], axis=1)

    def pinocchio_a(self) -> np.ndarray:
        """Pinocchio free-flyer accelerations (N, 6 + nq): :meth:`base_acceleration`, ``qddot``."""
        return np.concatenate([self.base_acceleration(), self.qddot], axis=1)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary of the checks and the settings.

        Keys: min_margin [m], statically_stable, max_slip [m], min_limit_margin [rad],
        min_clearance [m], max_foot_error [m], max_joint_rate [rad/s], max_joint_speed and
        max_joint_accel per joint [rad/s], [rad/s²], velocity_limit [rad/s] (None: no
        limit), speed_ok, samples, ok, pattern (the table), mass [kg], and the settings.
        """

        def finite(a: np.ndarray) -> list[float | None]:
            return [float(x) if math.isfinite(x) else None for x in a]

        return {
            "min_margin": self.min_margin,
            "min_zmp_margin": self.min_zmp_margin,
            "statically_stable": self.statically_stable,
            "max_slip": self.max_slip,
            "min_limit_margin": self.min_limit_margin,
            "min_clearance": self.min_clearance,
            "max_foot_error": self.max_foot_error,
            "max_joint_rate": float(np.abs(self.qdot).max()) if self.qdot.size else 0.0,
            "max_joint_speed": dict(zip(self.joint_names, finite(self.max_joint_speed))),
            "max_joint_accel": dict(zip(self.joint_names, finite(self.max_joint_accel))),
            "velocity_limit": dict(zip(self.joint_names, finite(self.velocity_limit))),
            "speed_ok": self.speed_ok,
            "samples": int(len(self.t)),
            "ok": self.ok,
            "pattern": self.table.to_dict(),
            "mass": self.mass,
            **{k: (list(v) if isinstance(v, tuple) else v) for k, v in self.settings.items()},
        }
