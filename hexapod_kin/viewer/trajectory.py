"""Trajectories for the viewer: validation, resampling and the keyframe clips of a pose track.

A trajectory is sample times [s], joint configurations and optional root poses ``worldMroot``
(4, 4) per sample; :func:`resample` brings long ones to a frame rate (linear in q, SE(3)
geodesic for the root); :func:`clip` is the three.js animation clip (position and
quaternion tracks, times in seconds) of one object's poses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..exceptions import ConfigurationError, positive
from .objects import f32

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model


#: Above this many samples (and with ``fps=None``) an animation is resampled at 60 frames/s.
MAX_SAMPLES = 3000


@dataclass(frozen=True)
class Motion:
    """A checked trajectory: times (N,) [s], q (N, nq), root poses (N, 4, 4) or None."""

    times: np.ndarray
    qs: np.ndarray
    base_poses: np.ndarray | None


def check_base_poses(poses: Any, n: int) -> np.ndarray | None:
    """Root poses as (n, 4, 4) rigid transforms (one (4, 4) is repeated), or None."""
    if poses is None:
        return None
    try:
        arr = np.asarray(poses, dtype=float)
    except (TypeError, ValueError):
        raise ConfigurationError("base_poses is not an array of numbers") from None
    if arr.shape == (4, 4):
        arr = np.broadcast_to(arr, (n, 4, 4)).copy()
    if arr.shape != (n, 4, 4):
        msg = f"base_poses has shape {arr.shape}; expected ({n}, 4, 4) (one pose per sample)"
        raise ConfigurationError(msg + " or (4, 4)")
    if not np.all(np.isfinite(arr)):
        raise ConfigurationError("base_poses contains non-finite values")
    rot = arr[:, :3, :3]
    err = np.abs(np.einsum("nji,njk->nik", rot, rot) - np.eye(3)).max()
    bottom = np.abs(arr[:, 3, :] - [0.0, 0.0, 0.0, 1.0]).max()
    if err > 1e-6 or bottom > 1e-9 or np.any(np.linalg.det(rot) < 0):
        msg = f"base_poses are not rigid transforms (|RᵀR − I| = {err:.2e}, last row off by "
        msg += f"{bottom:.2e}); expected rotations with det +1 and a last row [0, 0, 0, 1]"
        raise ConfigurationError(msg)
    return arr


def check_motion(model: Model, times: Any, qs: Any, base_poses: Any) -> Motion:
    """Check times (strictly increasing), q and root poses of a trajectory."""
    q = model.check_q_batch(qs, "qs")
    try:
        t = np.asarray(times, dtype=float)
    except (TypeError, ValueError):
        raise ConfigurationError("times is not an array of numbers") from None
    if t.ndim == 0:
        t = t[None]
    if t.ndim != 1 or len(t) != len(q):
        msg = f"times has shape {t.shape}; expected ({len(q)},), one time per row of qs"
        raise ConfigurationError(msg)
    if not np.all(np.isfinite(t)):
        raise ConfigurationError("times contains non-finite values")
    if len(t) > 1 and np.any(np.diff(t) <= 0):
        bad = int(np.argmax(np.diff(t) <= 0))
        msg = f"times must increase strictly; times[{bad}]={t[bad]} >= times[{bad + 1}]="
        raise ConfigurationError(f"{msg}{t[bad + 1]}")
    return Motion(t, q, check_base_poses(base_poses, len(q)))


def resample(motion: Motion, fps: float | None) -> Motion:
    """Resample at ``fps`` [frames/s] (linear in q; SE(3) geodesic for the base)."""
    n = len(motion.times)
    if fps is None:
        if n <= MAX_SAMPLES:
            return motion
        fps = 60.0
    fps = positive("fps", fps, at_most=1000.0)  # frames/s
    t0, t1 = float(motion.times[0]), float(motion.times[-1])
    if n < 2 or t1 <= t0:
        return motion
    count = max(2, int(math.floor((t1 - t0) * fps + 1e-9)) + 1)
    times = t0 + np.arange(count) / fps
    times[-1] = min(times[-1], t1)
    if times[-1] < t1 - 1e-12:
        times = np.append(times, t1)
    qs = np.column_stack([np.interp(times, motion.times, col) for col in motion.qs.T])
    poses = None
    if motion.base_poses is not None:
        import pinocchio as pin

        idx = np.clip(np.searchsorted(motion.times, times, side="right") - 1, 0, n - 2)
        poses = np.empty((len(times), 4, 4))
        for k, (i, t) in enumerate(zip(idx, times)):
            a, b = motion.times[i], motion.times[i + 1]
            alpha = min(max((t - a) / (b - a), 0.0), 1.0)
            A, B = pin.SE3(motion.base_poses[i]), pin.SE3(motion.base_poses[i + 1])
            poses[k] = (A * pin.exp6(alpha * pin.log6(A.inverse() * B))).homogeneous
    return Motion(times, qs, poses)


def quaternions(T: np.ndarray) -> np.ndarray:
    """(N, 4) quaternions x, y, z, w of (N, 4, 4) poses, sign-continuous along N."""
    import pinocchio as pin

    out = np.array([pin.Quaternion(np.ascontiguousarray(m[:3, :3])).coeffs() for m in T])
    for i in range(1, len(out)):
        if np.dot(out[i], out[i - 1]) < 0:
            out[i] = -out[i]
    return out


def check_mask(mask: Any, n: int) -> np.ndarray | None:
    """The singular mask as (n,) booleans, or None."""
    if mask is None:
        return None
    arr = np.asarray(mask)
    if arr.shape != (n,) or arr.dtype.kind not in "bi":
        msg = f"singular_mask has shape {arr.shape} and dtype {arr.dtype}"
        raise ConfigurationError(f"{msg}; expected ({n},) booleans")
    return arr.astype(bool)


def track(prop: str, kind: str, times: np.ndarray, values: Any) -> dict[str, Any]:
    """One keyframe track of property ``prop`` (``"vector3"`` or ``"quaternion"``), times [s]."""
    return {"name": f".{prop}", "type": kind, "times": f32(times), "values": f32(values)}


def clip(path: str, times: np.ndarray, T: np.ndarray) -> dict[str, Any]:
    """The animation clip (position and quaternion tracks, times [s]) of poses ``T`` (N, 4, 4)."""
    tracks = [track("position", "vector3", times, T[:, :3, 3])]
    tracks.append(track("quaternion", "quaternion", times, quaternions(T)))
    return {"path": path, "clip": {"fps": 1.0, "name": "default", "tracks": tracks}}
