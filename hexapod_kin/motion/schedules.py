"""Joint schedules, pose paths in SE(3), and tracking of tip paths by IK.

* :class:`JointSchedule` replays piecewise-linear joint tables.
* :class:`PosePath` interpolates poses on SE(3) (``T_i exp(s log(T_i⁻¹ T_{i+1}))``: a constant
  body twist per segment) and :func:`follow_pose_path` tracks it by resolved rate, closed loop
  on the pose error (log map).
* :func:`track` turns tip positions (or poses) back into joint trajectories by IK.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from .._fields import fields_dict
from ..exceptions import IKError, ParameterError, positive
from ..kinematics import as_model
from .rate import Method, Trajectory, read_only, resolved_rate

if TYPE_CHECKING:
    from ..ik.prepare import ModelLike

__all__ = ["JointSchedule", "PosePath", "Tracked", "follow_pose_path", "track"]


# ============================================================================ joint schedule
@dataclass(frozen=True)
class JointSchedule:
    """Piecewise-linear joint trajectory through knots (held constant after the last one).

    ``times`` (K,) in [s], non-decreasing; ``values`` (K, n) in [rad]/[m]; ``description``
    free text (source).
    """

    times: np.ndarray
    values: np.ndarray
    description: str = ""

    def __post_init__(self) -> None:
        t = np.asarray(self.times, dtype=float).reshape(-1)
        v = np.asarray(self.values, dtype=float)
        if v.ndim == 1:
            v = v[:, None]
        if t.size < 1 or v.shape[0] != t.size:
            msg = f"JointSchedule: {t.size} times and {v.shape[0]} value rows; one row per knot"
            raise ParameterError(msg, parameter="values", value=v.shape, allowed=f"({t.size}, n)")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
            raise ParameterError("JointSchedule: times and values must be finite")
        if np.any(np.diff(t) < 0):
            raise ParameterError(f"JointSchedule.times={t.tolist()} must be non-decreasing")
        read_only(t, v)
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "values", v)

    def sample(self, t: Any) -> np.ndarray:
        """Joint values at times ``t`` ((M,) → (M, n); a scalar → (n,))."""
        tt = np.asarray(t, dtype=float)
        cols = [np.interp(tt, self.times, self.values[:, j]) for j in range(self.values.shape[1])]
        return np.stack(cols, axis=-1)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary ([s], [rad]/[m])."""
        return fields_dict(self, "times", "values", "description")


# ============================================================================ pose path
@dataclass(frozen=True)
class PosePath:
    """Poses at knot times, interpolated on SE(3) (arrays read-only).

    Between knots ``i`` and ``i+1``: ``T_i exp(s ξ_i)``, ``ξ_i = log(T_i⁻¹ T_{i+1})``, ``s``
    linear in time (a screw motion); held at the last pose afterwards. ``times`` (K,) in [s]
    start at 0 and increase strictly; ``poses`` (K, 4, 4) are ``baseMtarget``.
    """

    times: np.ndarray
    poses: np.ndarray

    def __post_init__(self) -> None:
        t = np.asarray(self.times, dtype=float).reshape(-1)
        p = np.asarray(self.poses, dtype=float)
        if p.shape != (t.size, 4, 4) or t.size < 2:
            msg = (
                f"PosePath: {t.size} times and poses of shape {p.shape}; K >= 2 times and "
                "(K, 4, 4) poses are needed"
            )
            raise ParameterError(msg, parameter="poses", value=p.shape, allowed=f"({t.size}, 4, 4)")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(p))):
            raise ParameterError("PosePath: times and poses must be finite")
        if t[0] != 0.0 or np.any(np.diff(t) <= 0):
            raise ParameterError(
                f"PosePath.times={t.tolist()} must start at 0 and increase strictly",
                parameter="times",
                value=t.tolist(),
                allowed="0 = t0 < t1 < ...",
            )
        for k, m in enumerate(p):
            r = m[:3, :3]
            if np.max(np.abs(r.T @ r - np.eye(3))) > 1e-9 or np.linalg.det(r) < 0:
                raise ParameterError(
                    f"PosePath.poses[{k}] is not a rigid transform",
                    parameter="poses",
                    value=k,
                    allowed="rotation orthonormal with det +1",
                )
        xi = np.array(
            [pin.log6(pin.SE3(p[k]).actInv(pin.SE3(p[k + 1]))).vector for k in range(t.size - 1)]
        )
        read_only(t, p, xi)
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "poses", p)
        object.__setattr__(self, "_xi", xi)

    @property
    def duration(self) -> float:
        """Time of the last knot in [s]."""
        return float(self.times[-1])

    def _segment(self, t: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(t, t as 1-D, segment index k, fraction s in it)``."""
        tt = np.asarray(t, dtype=float)
        flat = np.atleast_1d(tt)
        k = np.clip(np.searchsorted(self.times, flat, side="right") - 1, 0, self.times.size - 2)
        dt = self.times[k + 1] - self.times[k]
        s = np.clip((flat - self.times[k]) / dt, 0.0, 1.0)
        return tt, flat, k, s

    def sample(self, t: Any) -> np.ndarray:
        """Poses at times ``t``: (M, 4, 4) for (M,) times, (4, 4) for a scalar."""
        tt, _, k, s = self._segment(t)
        xi: np.ndarray = self._xi  # type: ignore[attr-defined]
        se3, exp6, motion = pin.SE3, pin.exp6, pin.Motion
        out = np.array([(se3(self.poses[ki]) * exp6(motion(si * xi[ki]))).homogeneous
                        for ki, si in zip(k, s)])  # fmt: skip
        return out[0] if tt.ndim == 0 else out

    def twist(self, t: Any) -> np.ndarray:
        """Body twist ``[v; ω]`` of the path (tip frame) at times ``t``: (M, 6) or (6,).

        Segment i's twist on ``[t_i, t_{i+1}]`` (the last segment's at the end), 0 after.
        """
        tt, flat, k, _ = self._segment(t)
        xi: np.ndarray = self._xi  # type: ignore[attr-defined]
        out = xi[k] / (self.times[k + 1] - self.times[k])[:, None]
        out[flat > self.times[-1]] = 0.0
        return out[0] if tt.ndim == 0 else out

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary ([s], poses as nested lists)."""
        return fields_dict(self, "times", "poses")


def follow_pose_path(
    model: ModelLike,
    path: PosePath,
    q0: Any = None,
    *,
    dt: float = 1e-3,
    gain: float = 20.0,
    method: Method = "rk4",
    within_limits: bool = True,
) -> Trajectory:
    """Track a :class:`PosePath` by resolved rate: feed-forward body twist + pose feedback.

    ``q0`` defaults to the 6-D IK of the first pose; ``dt`` in [s]; ``gain`` in [1/s] on the
    pose error ``[p_ref − p; log(R_ref Rᵀ)]``. Returns the :class:`Trajectory` (``frame="tip"``;
    its reference is the path).

    Raises:
        IKError: The first pose cannot be reached (when ``q0`` is None).

    """
    mdl = as_model(model)
    if q0 is None:
        from .. import ik

        res = ik.solve(mdl, path.poses[0], within_limits=within_limits)
        if not res.converged:
            raise IKError(
                f"follow_pose_path: the first pose is not reachable ({res.reason})",
                parameter="path",
                value="poses[0]",
                allowed="a reachable pose (or give q0)",
            )
        q0 = res.q
    return resolved_rate(mdl, path.twist, q0, dt, path.duration, frame="tip", method=method,
                         gain=gain, path=path.sample, within_limits=within_limits)  # fmt: skip


# ============================================================================ tracking by IK
@dataclass(frozen=True)
class Tracked:
    """Joint trajectory reaching a sequence of tip targets (arrays read-only).

    ``q`` (M, n) in [rad]/[m]; ``reached`` (M,) True where the target was reached.
    """

    q: np.ndarray
    reached: np.ndarray

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary."""
        return fields_dict(self, "q", "reached")


def track(model: ModelLike, positions: Any, q0: Any = None, *, tol: float = 1e-10) -> Tracked:
    """Joint trajectory reaching a sequence of tip positions (or poses), continuously.

    The closed form when the chain has one (the solution nearest the previous sample), else
    :func:`hexapod_kin.ik.solve` warm-started from the previous sample.

    ``positions``: (M, 3) tip positions in [m], or (M, 4, 4) poses; ``q0``: joints near the
    first sample (branch choice, warm start; default :func:`hexapod_kin.ik.home`); ``tol``:
    position tolerance [m] of the numerical fallback.

    Raises:
        IKError: Bad positions.

    """
    from .. import ik

    mdl = as_model(model)
    pts = np.asarray(positions, dtype=float)
    poses = pts.ndim == 3
    if not ((pts.ndim == 2 and pts.shape[1] == 3) or (poses and pts.shape[1:] == (4, 4))):
        msg = f"positions has shape {pts.shape}; (M, 3) in [m] or (M, 4, 4) poses are needed"
        raise IKError(msg, parameter="positions", value=pts.shape, allowed="(M, 3) or (M, 4, 4)")
    if not np.all(np.isfinite(pts)):
        raise IKError("positions contains non-finite values", parameter="positions")
    ik.check_within(mdl, pts[:, :3, 3] if poses else pts, "positions")
    tol = positive("tol", tol)
    prev = ik.home(mdl) if q0 is None else mdl.check_q(q0, "q0")
    out = np.empty((pts.shape[0], mdl.nq))
    ok = np.zeros(pts.shape[0], dtype=bool)
    batch = None
    if not poses:
        try:
            batch = ik.analytic_batch(mdl, pts, within_limits=True)
        except IKError:
            pass
    rev = ~np.asarray(mdl.is_prismatic)
    for i, p in enumerate(pts):
        if batch is not None and batch.valid[i].any():
            cands = batch.q[i][batch.valid[i]]
            d = cands - prev
            d[:, rev] = np.remainder(d[:, rev] + np.pi, 2 * np.pi) - np.pi
            idx = int(np.argmin(np.sum(d * d, axis=1)))
            # keep revolute joints continuous (no 2π jumps) when that stays inside the limits
            best = prev + d[idx]
            if not (np.all(best >= mdl.lower) and np.all(best <= mdl.upper)):
                best = cands[idx]
            out[i], ok[i] = best, True
        else:
            res = ik.solve(mdl, p, prev, tol=tol, restarts=2)
            out[i], ok[i] = res.q, res.converged
        prev = out[i]
    read_only(out, ok)
    return Tracked(q=out, reached=ok)
