"""What the controller is fed (:class:`Measurement`) and its small rotation helpers."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._pose import rpy_to_matrix

__all__ = ["Measurement"]


@dataclass(frozen=True)
class Measurement:
    """What the robot senses at one tick (SI units, world z up).

    Attributes:
        t: Time [s].
        quat: (4,) body attitude ``w, x, y, z`` (IMU).
        gyro: (3,) body angular velocity in the body frame [rad/s] (IMU).
        q: (nq,) leg joint positions [rad] (the model's joint order).
        qd: (nq,) joint velocities [rad/s].
        contacts: (L,) True where a foot touches (foot switches / force sensing).
        position: (3,) base position estimate in the world [m].
        velocity: (3,) base linear velocity estimate in the world [m/s].

    """

    t: float
    quat: np.ndarray
    gyro: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    contacts: np.ndarray
    position: np.ndarray
    velocity: np.ndarray


def _quat_mat(q: np.ndarray) -> np.ndarray:
    """The rotation of the unit quaternion ``q = (w, x, y, z)``."""
    import pinocchio as pin

    w, x, y, z = (float(v) for v in q)
    return np.array(pin.Quaternion(w, x, y, z).normalized().toRotationMatrix())


def _rz(a: float) -> np.ndarray:
    return rpy_to_matrix(0.0, 0.0, a)


def _log3(R: np.ndarray) -> np.ndarray:
    """The rotation vector of ``R`` [rad] (Pinocchio's ``log3``)."""
    import pinocchio as pin

    return np.array(pin.log3(R))


def _yaw(R: np.ndarray) -> float:
    return math.atan2(R[1, 0], R[0, 0])


def _rot(w: np.ndarray) -> np.ndarray:
    """The rotation of rotation vector ``w`` [rad] (Pinocchio's ``exp3``)."""
    import pinocchio as pin

    return np.array(pin.exp3(np.asarray(w, dtype=float)))
