"""The zero-moment point of a planned walk, from the whole robot's centroidal dynamics.

On flat ground at height ``h`` (the stance contacts' mean), with gravity ``g`` along −z:

    x_z = c_x − (c_z − h) c̈_x / (g + c̈_z) − L̇_y / (m (g + c̈_z))
    y_z = c_y − (c_z − h) c̈_y / (g + c̈_z) + L̇_x / (m (g + c̈_z))

``c`` the centre of mass, ``L`` the angular momentum about it, ``m`` the mass. ``L`` sums over
the body and every link, ``m_j (x_j − c) × ẋ_j + R_j I_j R_jᵀ ω_j``, from the links' poses by
forward kinematics (vectorised over the samples); velocities and ``L̇``, ``c̈`` by finite
differences on the uniform samples. A swinging leg's momentum shifts a Solo12's ZMP by up to
2 cm; ``tests/test_gait_physics.py`` checks the whole against Pinocchio's
``computeCentroidalMomentumTimeVariation``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["GRAVITY", "angular_momentum", "second_difference", "zmp_points"]

#: Gravity [m/s²].
GRAVITY = 9.81


def second_difference(x: np.ndarray, t: np.ndarray) -> np.ndarray:
    """d²x/dt² (N, ...) on uniform samples (N ≥ 4).

    ``(x_{i+1} − 2x_i + x_{i−1}) / dt²`` inside, the second-order one-sided
    ``(2x₀ − 5x₁ + 4x₂ − x₃) / dt²`` at the ends.
    """
    dt = float(t[1] - t[0])
    out = np.empty_like(x)
    out[1:-1] = x[2:] - 2.0 * x[1:-1] + x[:-2]
    out[0] = 2.0 * x[0] - 5.0 * x[1] + 4.0 * x[2] - x[3]
    out[-1] = 2.0 * x[-1] - 5.0 * x[-2] + 4.0 * x[-3] - x[-4]
    return np.asarray(out / (dt * dt))


def angular_momentum(
    masses: np.ndarray,
    rot_inertia: np.ndarray,
    R: np.ndarray,
    x: np.ndarray,
    c: np.ndarray,
    xd: np.ndarray,
    w: np.ndarray,
) -> np.ndarray:
    """Angular momentum about the centre of mass (N, 3) [kg·m²/s], world axes.

    ``L = Σ_j m_j (x_j − c) × ẋ_j + R_j I_j R_jᵀ ω_j`` (Pinocchio's centroidal momentum
    ``h_G``, angular part).

    Args:
        masses: (K,) link masses [kg].
        rot_inertia: (K, 3, 3) rotational inertias about each link's CoM, link axes [kg·m²].
        R: (N, K, 3, 3) link rotations in the world.
        x: (N, K, 3) link CoMs in the world [m].
        c: (N, 3) the centre of mass [m].
        xd: (N, K, 3) link CoM velocities [m/s].
        w: (N, K, 3) link angular velocities, world axes [rad/s].

    """
    local = np.swapaxes(R, -1, -2) @ w[..., None]  # ω in each link's frame
    spin = (R @ (rot_inertia[None] @ local))[..., 0]  # R I Rᵀ ω
    return np.asarray(masses @ np.cross(x - c[:, None], xd) + spin.sum(axis=1))


def zmp_points(
    wb: Any, joint_poses: np.ndarray, base: np.ndarray, t: np.ndarray, ground: np.ndarray
) -> np.ndarray:
    """ZMP (N, 3) on the ground plane of each sample (z = ``ground``) [m] (N ≥ 4 samples).

    Args:
        wb: The robot (:class:`~.robot.WholeBody`).
        joint_poses: (N, nq, 4, 4) every joint's pose in the world (``wb.joint_poses``).
        base: (N, 4, 4) body poses.
        t: (N,) uniform sample times [s].
        ground: (N,) ground height under the robot [m].

    """
    masses, levers, rot_i = wb.link_inertias()
    R = np.concatenate([base[:, None, :3, :3], joint_poses[:, :, :3, :3]], axis=1)
    p = np.concatenate([base[:, None, :3, 3], joint_poses[:, :, :3, 3]], axis=1)
    x = (R @ levers[None, :, :, None])[..., 0] + p  # (N, K, 3) link CoMs
    mass = float(masses.sum())
    c = (masses @ x) / mass
    dt = float(t[1] - t[0])
    xd = np.gradient(x, dt, axis=0, edge_order=2)
    Rd = np.gradient(R, dt, axis=0, edge_order=2)
    W = Rd @ np.swapaxes(R, -1, -2)  # Ṙ Rᵀ = [ω]×
    w = 0.5 * np.stack([W[..., 2, 1] - W[..., 1, 2], W[..., 0, 2] - W[..., 2, 0],
                        W[..., 1, 0] - W[..., 0, 1]], axis=-1)  # fmt: skip
    L = angular_momentum(masses, rot_i, R, x, c, xd, w)
    Ld = np.gradient(L, dt, axis=0, edge_order=2)
    cdd = second_difference(c, t)
    den = GRAVITY + cdd[:, 2]
    out = np.empty_like(c)
    lever = (c[:, 2] - ground) / den
    out[:, 0] = c[:, 0] - lever * cdd[:, 0] - Ld[:, 1] / (mass * den)
    out[:, 1] = c[:, 1] - lever * cdd[:, 1] + Ld[:, 0] / (mass * den)
    out[:, 2] = ground
    return out
