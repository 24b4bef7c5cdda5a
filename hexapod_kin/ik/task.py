"""Build an IK task from a target: position, position + yaw, or a full pose with weights.

The task is the *problem*: rows ``x y z wx wy wz`` (position error ``p* − p`` [m], orientation
error ``log(R* Rᵀ)`` [rad], base axes) and their weights; :mod:`hexapod_kin.ik.step` solves it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from .._fields import read_only
from ..exceptions import HexapodKinError, IKError

__all__ = ["AXES", "TARGET_FACTOR", "Task", "build_task", "build_tasks", "check_within"]

#: Names of the six task rows (position [m], orientation [rad]; base axes).
AXES: tuple[str, ...] = ("x", "y", "z", "wx", "wy", "wz")

#: A target farther than this many robot sizes from the base is refused (not "unreachable").
TARGET_FACTOR = 100.0

Mode = Literal["position", "position_yaw", "pose"]
MODES: tuple[str, ...] = ("position", "position_yaw", "pose")


@dataclass(frozen=True)
class Task:
    """A target and the weight of each task row (arrays read-only).

    Attributes:
        mode: ``"position"``, ``"position_yaw"`` (x y z and the tool's yaw ψ) or ``"pose"``.
        pose: Target pose ``baseMtarget`` (4, 4); rotation = identity unless ``mode="pose"``.
        yaw: Target yaw [rad] (``"position_yaw"``), else 0.
        weights: (6,) weights of rows x y z wx wy wz (the yaw row's in ``wz``).

    """

    mode: Mode
    pose: np.ndarray
    yaw: float
    weights: np.ndarray

    @property
    def position(self) -> np.ndarray:
        """Target position (3,) in [m]."""
        return np.array(self.pose[:3, 3])

    @property
    def code(self) -> int:
        """The compiled loop's mode number (0, 1, 2)."""
        return MODES.index(self.mode)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (pose as nested lists, [m] and [rad])."""
        out = {"mode": self.mode, "pose": self.pose.tolist(), "yaw": float(self.yaw)}
        return out | {"weights": self.weights.tolist()}


def _task(mode: Mode, pose: np.ndarray, yaw: float, weights: np.ndarray) -> Task:
    """``Task(mode, pose, yaw, weights)`` of checked values, without the dataclass ``__init__``."""
    out = _NEW(Task)
    _SET(out, "__dict__", {"mode": mode, "pose": pose, "yaw": yaw, "weights": weights})
    return out


_NEW, _SET = object.__new__, object.__setattr__


def _weights(mask: Any, weights: Any, allowed: tuple[int, ...]) -> np.ndarray:
    """(6,) row weights from ``mask`` or ``weights``; rows not in ``allowed`` must be 0."""
    if mask is not None and weights is not None:
        raise IKError(
            "give either mask= or weights=, not both",
            parameter="mask",
            value=mask,
            allowed="mask (6 booleans) or weights (6 numbers >= 0)",
        )
    w = np.zeros(6)
    w[list(allowed)] = 1.0
    given = mask if mask is not None else weights
    if given is None:
        return w
    name = "mask" if mask is not None else "weights"
    try:
        arr = np.array(given, dtype=np.float64)  # a private C-contiguous copy
    except (TypeError, ValueError):
        raise IKError(
            f"{name}={given!r} is not 6 numbers",
            parameter=name,
            value=given,
            allowed="6 values for rows x y z wx wy wz",
        ) from None
    if arr.shape != (6,) or not np.all(np.isfinite(arr)) or np.any(arr < 0) or not arr.any():
        msg = (
            f"{name}={np.asarray(given).tolist()!r} is not allowed; 6 finite values >= 0 (rows "
            "x y z wx wy wz [m], [rad]), at least one > 0"
        )
        raise IKError(msg, parameter=name, value=given, allowed="6 finite values >= 0, not all 0")
    if mask is not None:
        arr = (arr != 0).astype(np.float64)
    unused = [AXES[k] for k in range(6) if k not in allowed and arr[k] != 0]
    if unused:
        raise IKError(
            f"{name} weights rows {unused} that this target does not define (a position "
            "target has rows x y z; position + yaw adds wz; give a 4×4 pose for the others)",
            parameter=name,
            value=given,
            allowed=f"non-zero only on {[AXES[k] for k in allowed]}",
        )
    return arr


_POSE_WEIGHTS, _POSITION_WEIGHTS = np.ones(6), np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0])
read_only(_POSE_WEIGHTS, _POSITION_WEIGHTS)
_EYE1, _F64 = np.eye(4)[None], np.dtype(np.float64)


def _fast(t: np.ndarray) -> tuple[Mode, np.ndarray, np.ndarray, float] | None:
    """``(mode, pose (1, 4, 4) read-only, weights, |x| + |y| + |z|)`` of a float64 target.

    None for anything else (e.g. a pose not rigid to 1e-9): the general path checks it.
    """
    if t.dtype is not _F64:  # float64's one dtype object (any other: the general path)
        return None
    mode: Mode
    if t.shape == (3,):
        x, y, z = t.tolist()
        mode, w = "position", _POSITION_WEIGHTS
        pose = _EYE1.copy()
        pose[0, 0, 3], pose[0, 1, 3], pose[0, 2, 3] = x, y, z
    elif t.shape == (4, 4):
        (a, b, c, x), (d, e, f, y), (g, h, i, z), last = t.tolist()
        # columns orthonormal and det +1 (third column = first × second), to 1e-9
        tol = 1e-9
        if not (
            last == [0.0, 0.0, 0.0, 1.0]
            and -tol <= a * a + d * d + g * g - 1.0 <= tol
            and -tol <= b * b + e * e + h * h - 1.0 <= tol
            and -tol <= a * b + d * e + g * h <= tol
            and -tol <= d * h - g * e - c <= tol
            and -tol <= g * b - a * h - f <= tol
            and -tol <= a * e - d * b - i <= tol
        ):
            return None
        mode, w = "pose", _POSE_WEIGHTS
        pose = t[None].copy()
    else:
        return None
    pose.setflags(write=False)
    return mode, pose, w, abs(x) + abs(y) + abs(z)


def build_task(target: Any, *, mask: Any = None, weights: Any = None) -> Task:
    """Parse a target into a :class:`Task` with read-only arrays (pure function).

    ``target``: a position (3,) [m]; position + yaw (4,) = (x, y, z, ψ [rad]); or a pose
    ``baseMtarget`` (4, 4), a homogeneous transform with a proper rotation. ``mask`` (6
    booleans) or ``weights`` (6 values >= 0) select the rows x y z wx wy wz.

    Raises:
        IKError: Wrong shape, non-finite values, a matrix that is not a rigid transform, or
            weights on rows the target does not define.

    """
    if target.__class__ is np.ndarray and mask is None and weights is None:
        fast = _fast(target)
        if fast is not None and math.isfinite(fast[3]):
            return _task(fast[0], fast[1][0], 0.0, fast[2])
    try:
        t = np.array(target, dtype=np.float64)
    except (TypeError, ValueError):
        raise IKError(
            f"target={target!r} is not numbers",
            parameter="target",
            value=target,
            allowed="(3,) position [m], (4,) position + yaw [rad], or a (4, 4) pose",
        ) from None
    if not np.all(np.isfinite(t)):
        msg = f"target={t.tolist()} contains non-finite values; finite [m]/[rad] required"
        raise IKError(msg, parameter="target", value=t.tolist(), allowed="finite numbers")
    pose, yaw = np.eye(4), 0.0
    mode: Mode
    if t.shape == (3,):
        mode, pose[:3, 3] = "position", t
        w = _weights(mask, weights, (0, 1, 2))
    elif t.shape == (4,):
        mode, pose[:3, 3], yaw = "position_yaw", t[:3], float(t[3])
        w = _weights(mask, weights, (0, 1, 2, 5))
    elif t.shape == (4, 4):
        rot = t[:3, :3]
        if (
            np.max(np.abs(t[3] - [0.0, 0.0, 0.0, 1.0])) > 1e-12
            or np.max(np.abs(rot.T @ rot - np.eye(3))) > 1e-9
            or np.linalg.det(rot) < 0
        ):
            raise IKError(
                "target (4, 4) is not a rigid transform (rotation orthonormal to 1e-9 with "
                "det +1, last row [0, 0, 0, 1])",
                parameter="target",
                value=t.tolist(),
                allowed="a homogeneous transform baseMtarget",
            )
        mode, pose = "pose", t
        w = _weights(mask, weights, (0, 1, 2, 3, 4, 5))
    else:
        msg = (
            f"target has shape {t.shape}; a position (3,) [m], position + yaw (4,) or a pose "
            "(4, 4) is needed"
        )
        raise IKError(msg, parameter="target", value=t.shape, allowed="(3,), (4,) or (4, 4)")
    pose = np.ascontiguousarray(pose)
    pose.setflags(write=False)
    w.setflags(write=False)
    return Task(mode=mode, pose=pose, yaw=yaw, weights=w)


def build_tasks(targets: Any, *, mask: Any = None, weights: Any = None) -> list[Task]:
    """:func:`build_task` of each row of ``targets`` ((N, 3) positions or (N, 4, 4) poses).

    Without ``mask`` or ``weights`` the rows are checked at once; any other case, or a row that
    fails, goes through :func:`build_task` one by one. Raises IKError: as :func:`build_task`.
    """
    t = np.asarray(targets)
    if mask is None and weights is None and t.dtype == np.float64 and len(t):
        if t.ndim == 2 and t.shape[1] == 3 and np.all(np.isfinite(t)):
            poses = np.broadcast_to(np.eye(4), (len(t), 4, 4)).copy()
            poses[:, :3, 3] = t
            poses.setflags(write=False)
            return [_task("position", p, 0.0, _POSITION_WEIGHTS) for p in poses]
        if t.ndim == 3 and t.shape[1:] == (4, 4) and np.all(np.isfinite(t)):
            rot = t[:, :3, :3]
            gram = np.einsum("nji,njk->nik", rot, rot) - np.eye(3)
            rigid = (
                np.all(t[:, 3] == [0.0, 0.0, 0.0, 1.0])
                and np.max(np.abs(gram)) <= 1e-9
                and np.all(np.linalg.det(rot) > 0)
            )
            if rigid:
                poses = np.array(t)
                poses.setflags(write=False)
                return [_task("pose", p, 0.0, _POSE_WEIGHTS) for p in poses]
    return [build_task(ti, mask=mask, weights=weights) for ti in t]


def _robot_size(model: Any) -> float:
    from .._tree import robot_size

    return float(robot_size(model))


def _limit(model: Any) -> float:
    """:data:`TARGET_FACTOR` × the robot's size [m] (the size cached in the model)."""
    return TARGET_FACTOR * model.cached("robot_size", lambda: _robot_size(model.model))


def check_within(
    model: Any, positions: Any, parameter: str = "target", kind: type[HexapodKinError] = IKError
) -> None:
    """Refuse (3,) or (N, 3) ``positions`` [m] beyond :data:`TARGET_FACTOR` × the robot's size.

    ``model``: a loaded :class:`hexapod_kin.model.Model`; the error names ``parameter`` and is
    of class ``kind`` (one of the package's).
    Raises IKError: (or ``kind``) A position with ``|x|``, ``|y|`` or ``|z|`` over the limit.
    """
    if isinstance(positions, np.ndarray) and positions.shape == (3,):  # per call: ~1 µs
        total = sum(map(abs, positions.tolist()))  # ≥ the largest; NaN stays NaN
        if total <= 1e-3 * TARGET_FACTOR or total <= _limit(model):
            return
    xyz = np.asarray(positions, dtype=float).reshape(-1, 3)
    far = float(np.max(np.abs(xyz))) if xyz.size else 0.0
    if far <= 1e-3 * TARGET_FACTOR:  # within the smallest robot's limit: no size needed
        return
    limit = _limit(model)
    if far <= limit:  # NaN is not: refused below
        return
    k = int(np.argmax(np.max(np.abs(xyz), axis=1)))
    row, where = xyz[k], ("" if len(xyz) == 1 else f" (row {k})")
    msg = (
        f"{parameter}{where} {', '.join(f'{v:.6g}' for v in row)} m is larger than the robot; "
        f"allowed |x|, |y|, |z| <= {limit:.4g} m ({TARGET_FACTOR:g} x the robot's size)"
    )
    raise kind(msg, parameter=parameter, value=row.tolist(), allowed=[-limit, limit])
