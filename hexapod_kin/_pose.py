"""Poses: one rigid-transform notation, one RPY convention (:mod:`hexapod_kin.params`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .exceptions import ParameterError

__all__ = ["Pose", "matrix_to_rpy", "rodrigues", "rotation_angle", "rpy_to_matrix"]


def rotation_angle(r_a: Any, r_b: Any) -> np.ndarray:
    """Angles ‖log(R_a R_bᵀ)‖ in [0, π] [rad] of stacks of rotations (…, 3, 3).

    ``atan2(‖vee(M − Mᵀ)‖ / 2, (tr M − 1) / 2)``, ``M = R_a R_bᵀ``: full precision for tiny
    angles (where ``arccos`` of the trace loses half the digits) and near π.
    """
    m = np.asarray(r_a, dtype=float) @ np.swapaxes(np.asarray(r_b, dtype=float), -1, -2)
    skew = np.stack(
        [m[..., 2, 1] - m[..., 1, 2], m[..., 0, 2] - m[..., 2, 0], m[..., 1, 0] - m[..., 0, 1]],
        axis=-1,
    )
    sin_t = 0.5 * np.linalg.norm(skew, axis=-1)
    cos_t = 0.5 * (np.trace(m, axis1=-2, axis2=-1) - 1.0)
    return np.arctan2(sin_t, cos_t)


def rodrigues(k: np.ndarray, sin: float, cos: float) -> np.ndarray:
    """Rotation about the unit axis ``k`` by the angle of ``(sin, cos)`` (Rodrigues)."""
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + sin * kx + (1.0 - cos) * (kx @ kx)


def rpy_to_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Rotation matrix ``Rz(yaw)·Ry(pitch)·Rx(roll)`` (URDF fixed-axis X-Y-Z), angles in [rad]."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def matrix_to_rpy(rot: np.ndarray) -> tuple[float, float, float]:
    """URDF ``(roll, pitch, yaw)`` [rad] of a 3×3 rotation ``R = Rz(yaw)·Ry(pitch)·Rx(roll)``.

    At gimbal lock (``|pitch| = π/2``) yaw is 0.
    """
    r = np.asarray(rot, float)
    pitch = math.atan2(-r[2, 0], math.hypot(r[0, 0], r[1, 0]))
    if math.hypot(r[0, 0], r[1, 0]) < 1e-12:
        return (math.atan2(-r[1, 2], r[1, 1]), pitch, 0.0)
    return (math.atan2(r[2, 1], r[2, 2]), pitch, math.atan2(r[1, 0], r[0, 0]))


@dataclass(frozen=True)
class Pose:
    """A rigid transform ``T_a_b``: ``xyz`` [m] and ``rotation`` ``R_a_b`` (row tuples).

    :meth:`of` builds one from a matrix, ``(xyz, rpy)`` or another pose.
    """

    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotation: tuple[tuple[float, ...], ...] = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))

    def __post_init__(self) -> None:
        try:
            xyz = tuple(float(v) for v in self.xyz)
            rot = np.array(self.rotation, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError(
                f"Pose: xyz={self.xyz!r}, rotation={self.rotation!r}; three numbers and a 3x3 "
                "rotation are required"
            ) from None
        if len(xyz) != 3 or rot.shape != (3, 3) or not np.all(np.isfinite(rot + sum(xyz))):
            raise ParameterError(
                f"Pose: xyz={self.xyz!r}, rotation={self.rotation!r}; three numbers and a finite "
                "3x3 rotation are required"
            )
        err = float(np.abs(rot @ rot.T - np.eye(3)).max())
        if err > 1e-9 or np.linalg.det(rot) < 0:
            raise ParameterError(
                f"Pose.rotation={rot.tolist()} is not a rotation (|R Rt - I| = {err:.1e}, "
                f"det = {np.linalg.det(rot):.3f}); an orthonormal matrix with det +1 is required"
            )
        object.__setattr__(self, "xyz", xyz)
        object.__setattr__(self, "rotation", tuple(tuple(float(x) for x in r) for r in rot))

    @classmethod
    def of(cls, value: Any, where: str = "pose") -> Pose:
        """Return ``value`` as a :class:`Pose` (the package's one reader of poses).

        Args:
            value: A :class:`Pose`; a 4×4 homogeneous matrix (orthonormal, det +1 to 1e-9, last
                row ``0 0 0 1``) or anything with ``.homogeneous`` (``pin.SE3``); ``(xyz, rpy)``,
                a 6-vector ``xyz + rpy`` or a mapping of ``xyz`` and/or ``rpy`` ([m], [rad]).
            where: The parameter named in errors (``error.parameter``).

        Raises:
            ParameterError: Anything else, non-finite numbers or a matrix that is not rigid.

        """
        if isinstance(value, Pose):
            return value
        allowed = "a 4x4 homogeneous matrix, (xyz, rpy), a 6-vector xyz+rpy or {'xyz':…, 'rpy':…}"

        def bad(why: str) -> ParameterError:
            message = f"{where}={value!r}: {why}; give {allowed}"
            return ParameterError(message, parameter=where, value=value, allowed=allowed)

        if isinstance(value, dict):
            if set(value) - {"xyz", "rpy"}:
                raise bad(f"unknown keys {sorted(set(value) - {'xyz', 'rpy'})}")
            value = (value.get("xyz", (0.0, 0.0, 0.0)), value.get("rpy", (0.0, 0.0, 0.0)))
        value = getattr(value, "homogeneous", value)
        try:
            if isinstance(value, (str, bytes)):
                raise TypeError
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError, OverflowError):
            raise bad("not numbers") from None
        if arr.shape == (2, 3):  # (xyz, rpy)
            arr = arr.reshape(6)
        if not np.all(np.isfinite(arr)):
            raise bad("non-finite values")
        if arr.shape == (6,):
            return cls(xyz=tuple(arr[:3]), rotation=tuple(map(tuple, rpy_to_matrix(*arr[3:]))))
        if arr.shape != (4, 4):
            raise bad(f"shape {arr.shape}")
        if not np.allclose(arr[3], (0.0, 0.0, 0.0, 1.0), rtol=0, atol=1e-12):
            raise bad("not a rigid transform (last row must be 0 0 0 1)")
        try:
            return cls(xyz=tuple(arr[:3, 3]), rotation=tuple(map(tuple, arr[:3, :3])))
        except ParameterError as exc:
            raise bad(f"not a rigid transform ({exc})") from None

    @classmethod
    def identity(cls) -> Pose:
        """The identity transform."""
        return cls()

    @property
    def matrix(self) -> np.ndarray:
        """The 4×4 homogeneous matrix (a fresh array)."""
        t = np.eye(4)
        t[:3, :3] = self.rotation
        t[:3, 3] = self.xyz
        return t

    @property
    def rpy(self) -> tuple[float, float, float]:
        """``(roll, pitch, yaw)`` in [rad], URDF convention."""
        return matrix_to_rpy(np.array(self.rotation))

    @property
    def is_identity(self) -> bool:
        """True when the pose is exactly the identity."""
        return self == Pose()

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready ``{"xyz": [m], "rpy": [rad], "matrix": 4x4}``."""
        return {"xyz": list(self.xyz), "rpy": list(self.rpy), "matrix": self.matrix.tolist()}
