"""The driven limb: one foot or tool, its position, Jacobian and resolved-rate step.

A :class:`Limb` is a view of the one loaded robot: for a chain (a leg, an arm) its tip; for a
legged robot (:class:`~hexapod_kin.gait.robot.WholeBody`) one foot, moved by its own leg's
joints with the body held. :func:`rate_step` is the resolved-rate law of the project
(:func:`hexapod_kin._numerics.dls_step`, damping raised near a singularity as in
:mod:`hexapod_kin.motion`), one pure step; :meth:`Limb.follow` is the small loop that stops
with a readable reason (reached, out of reach, a joint limit, a singularity).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .._numerics import dls_step

__all__ = ["FollowResult", "Limb", "rate_step"]

#: σ_min [m] under which the step is damped (λ² grows to ``LAM2_MAX`` at σ_min = 0).
SIGMA_EPS = 0.01
#: Largest damping λ² [m²].
LAM2_MAX = 1e-4
#: A target closer than this is reached [m].
TOLERANCE = 1e-4


def rate_step(jac: np.ndarray, error: np.ndarray, speed: float, dt: float) -> np.ndarray:
    """One resolved-rate step ``Δq = J⁺_λ v dt`` towards a point, ``v = e / τ`` capped.

    The commanded linear velocity is ``v = e / 0.1 s`` capped at ``speed`` [m/s]; the damping
    is ``λ² = (1 − (σ_min / SIGMA_EPS)²) LAM2_MAX`` below ``SIGMA_EPS``, else 0.

    Args:
        jac: Position Jacobian (3, n) [m/rad].
        error: Target minus foot (3,) [m].
        speed: Largest foot speed [m/s].
        dt: Step [s].

    Returns:
        Δq (n,).

    """
    dist = float(np.linalg.norm(error))
    vel = error / 0.1
    if dist / 0.1 > speed:
        vel = error * (speed / dist)
    smin = float(np.linalg.svd(jac, compute_uv=False)[-1]) if jac.shape[1] else 0.0
    lam2 = 0.0 if smin >= SIGMA_EPS else (1.0 - (smin / SIGMA_EPS) ** 2) * LAM2_MAX
    return np.asarray(dls_step(jac, vel * dt, lam2))


@dataclass(frozen=True)
class FollowResult:
    """Where a follow stopped.

    Attributes:
        q: The joints [rad] / [m] (the robot's order).
        status: ``"moving"``, ``"reached"``, ``"out of reach"``, ``"joint limit"`` or
            ``"singularity"``.
        reason: A sentence in the robot's terms (empty while moving).
        error: Distance left to the target [m].

    """

    q: np.ndarray
    status: str
    reason: str
    error: float


class Limb:
    """One foot or tool of a robot, moved by its own joints.

    Args:
        model: The loaded robot (a chain) or ``None`` with ``body``.
        body: A legged robot (:class:`~hexapod_kin.gait.robot.WholeBody`) or ``None``.
        leg: The leg's index with ``body``.

    """

    def __init__(self, model: Any, body: Any = None, leg: int = 0) -> None:
        self.model = model
        self.body = body
        self.leg = int(leg)
        if body is None:
            self.columns = np.arange(model.nq)
            self.names: tuple[str, ...] = tuple(model.joint_names)
            self.lower = np.asarray(model.lower, dtype=float)
            self.upper = np.asarray(model.upper, dtype=float)
            self.label = str(model.tip)
        else:
            leg_name = body.leg_names[self.leg]
            self.columns = np.array(
                [j for j in range(body.nq) if body.leg_of_joint(j) == leg_name], dtype=int
            )
            self.names = tuple(body.joint_names[j] for j in self.columns)
            self.lower = np.asarray(body.lower, dtype=float)
            self.upper = np.asarray(body.upper, dtype=float)
            self.label = f"foot of {leg_name}"
        self.center, self.max_reach = self._reach()

    # ---------------------------------------------------------------- kinematics
    def point(self, q: np.ndarray, base: np.ndarray) -> np.ndarray:
        """The foot or tool point (3,) in the world [m] (a chain: its base frame)."""
        if self.body is None:
            return np.asarray(self.model.fk(q)[:3, 3])
        return np.asarray(self.body.feet(q[None], base[None])[0, self.leg])

    def jacobian(self, q: np.ndarray, base: np.ndarray) -> np.ndarray:
        """Position Jacobian (3, k) of the point over the limb's joints (world axes)."""
        if self.body is None:
            return np.asarray(self.model.jacobian(q, "local_world_aligned")[:3])
        h = 1e-6  # central differences of the legged robot's vectorised FK
        k = len(self.columns)
        qs = np.repeat(q[None], 2 * k, axis=0)
        for i, c in enumerate(self.columns):
            qs[2 * i, c] += h
            qs[2 * i + 1, c] -= h
        feet = self.body.feet(qs, np.repeat(base[None], 2 * k, axis=0))[:, self.leg]
        return np.asarray(((feet[0::2] - feet[1::2]) / (2 * h)).T)

    def hip(self, q: np.ndarray, base: np.ndarray) -> np.ndarray:
        """The centre of the limb's reach sphere in the world [m]."""
        if self.body is None:
            return self.center
        return np.asarray(self.body.leg_points(q[None], base[None])[0, self.leg, 0])

    def _reach(self) -> tuple[np.ndarray, float]:
        """(centre, radius) of a sphere holding every reachable point (sampled, 4096 q)."""
        rng = np.random.default_rng(0)
        lo = np.where(np.isfinite(self.lower), self.lower, -np.pi)
        hi = np.where(np.isfinite(self.upper), self.upper, np.pi)
        if self.body is None:
            qs = rng.uniform(lo, hi, size=(4096, len(lo)))
            pts = np.asarray(self.model.fk_batch(qs))[:, :3, 3]
            center = np.asarray(self.model.frame_placements(qs[0])[1][:3, 3])
            return center, float(np.linalg.norm(pts - center, axis=1).max())
        qs = np.repeat(((lo + hi) / 2)[None], 4096, axis=0)
        qs[:, self.columns] = rng.uniform(
            lo[self.columns], hi[self.columns], (4096, len(self.columns))
        )
        pts = self.body.leg_points(qs, np.repeat(np.eye(4)[None], 4096, axis=0))[:, self.leg]
        return np.zeros(3), float(np.linalg.norm(pts[:, -1] - pts[:, 0], axis=1).max())

    def measures(self, q: np.ndarray, base: np.ndarray) -> tuple[float, float]:
        """(σ_min [m], manipulability) of the position Jacobian over the limb's joints."""
        jac = self.jacobian(q, base)
        s = np.linalg.svd(jac, compute_uv=False)
        return float(s[-1]), float(np.prod(s))

    # ---------------------------------------------------------------- the loop
    def check_target(self, q: np.ndarray, base: np.ndarray, target: np.ndarray) -> str:
        """Why ``target`` cannot be reached at all (empty when it may be)."""
        centre = self.hip(q, base)
        dist = float(np.linalg.norm(target - centre))
        if dist > self.max_reach + 1e-3:
            return (
                f"out of reach: the target is {dist:.3f} m from the {self.names[0]} joint; "
                f"the {self.label} reaches {self.max_reach:.3f} m at most "
                f"({dist - self.max_reach:.3f} m too far)"
            )
        return ""

    def follow(
        self,
        q: np.ndarray,
        base: np.ndarray,
        target: np.ndarray,
        *,
        dt: float,
        steps: int = 10,
        speed: float = 0.2,
    ) -> FollowResult:
        """``steps`` resolved-rate steps of ``dt`` [s] towards ``target``; stop with a reason.

        The joints are kept in their limits; a step that cannot move the point any nearer
        (a limit or a singularity holds it) stops the follow and says which.
        """
        q = np.array(q, dtype=float)
        why = self.check_target(q, base, target)
        if why:
            err = float(np.linalg.norm(target - self.point(q, base)))
            return FollowResult(q, "out of reach", why, err)
        cols = self.columns
        for _ in range(steps):
            p = self.point(q, base)
            e = target - p
            err = float(np.linalg.norm(e))
            if err < TOLERANCE:
                return FollowResult(q, "reached", f"reached within {err * 1e3:.3f} mm", err)
            jac = self.jacobian(q, base)
            dq = rate_step(jac, e, speed, dt)
            q_new = q.copy()
            q_new[cols] = np.clip(q[cols] + dq, self.lower[cols], self.upper[cols])
            err_new = float(np.linalg.norm(target - self.point(q_new, base)))
            if err - err_new < 1e-4 * dt:  # under 0.1 mm/s of progress: held
                at = np.flatnonzero(
                    (q_new[cols] <= self.lower[cols] + 1e-9)
                    | (q_new[cols] >= self.upper[cols] - 1e-9)
                )
                if at.size:
                    j = int(at[0])
                    side = "lower" if q_new[cols][j] <= self.lower[cols][j] + 1e-9 else "upper"
                    value = self.lower[cols][j] if side == "lower" else self.upper[cols][j]
                    return FollowResult(
                        q_new,
                        "joint limit",
                        f"joint limit: {self.names[j]} is at its {side} limit "
                        f"{value:.4f}; the {self.label} stops {err_new * 1e3:.1f} mm short",
                        err_new,
                    )
                smin = float(np.linalg.svd(jac, compute_uv=False)[-1])
                return FollowResult(
                    q_new,
                    "singularity",
                    f"singularity: the {self.label} cannot move towards the target "
                    f"(σ_min = {smin:.2e} m); it stops {err_new * 1e3:.1f} mm short",
                    err_new,
                )
            q = q_new
        err = float(np.linalg.norm(target - self.point(q, base)))
        return FollowResult(q, "moving", "", err)
