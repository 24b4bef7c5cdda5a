"""The options and the result of the numerical IK (:mod:`hexapod_kin.ik.solver`).

:class:`IKOptions` (checked on construction) and :class:`IKResult` (read-only arrays, SI
units), built from one output row of the loop (:func:`~hexapod_kin.ik.step.lm_loop`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any, Literal, get_args

import numpy as np

from ..exceptions import ParameterError
from .prepare import N_STARTS
from .task import Task, _task

__all__ = ["MAX_ITER", "STATUSES", "IKOptions", "IKResult"]

#: Cap on ``max_iter`` (the residual history holds max_iter + 1 values per target).
MAX_ITER = 100_000

Status = Literal["converged", "unreachable", "joint_limits", "singular", "not_converged"]
STATUSES: tuple[str, ...] = get_args(Status)


# ============================================================================ options
def _bad(name: str, value: Any, allowed: str) -> ParameterError:
    return ParameterError(
        f"{name}={value!r} is not allowed; {allowed} is needed",
        parameter=name,
        value=value,
        allowed=allowed,
    )


@dataclass(frozen=True)
class IKOptions:
    """The options of :func:`~hexapod_kin.ik.solve` and its batch, checked on construction.

    A value out of its range raises ParameterError.

    Attributes:
        mask: Optional 6 booleans for rows x y z wx wy wz (e.g. ``[1, 1, 1, 0, 0, 1]``).
        weights: Optional 6 weights >= 0 for those rows (instead of ``mask``).
        tol: Convergence threshold on the position error in [m].
        rot_tol: Convergence threshold on the orientation error in [rad].
        max_iter: Accepted steps per attempt (1 to :data:`MAX_ITER`).
        restarts: Extra attempts from seeded random configurations if the first fails (≤ 32).
        within_limits: Clamp limited joints to their bounds (continuous joints always wrap).
        posture: Secondary task of redundant chains: ``"middle"``, a configuration, or None.
        posture_gain: Fraction of the distance to ``posture`` tried per step (0 < g ≤ 1).

    """

    mask: Any = None
    weights: Any = None
    tol: float = 1e-10
    rot_tol: float = 1e-10
    max_iter: int = 100
    restarts: int = 16
    within_limits: bool = True
    posture: Any = "middle"
    posture_gain: float = 0.1

    def __post_init__(self) -> None:
        for name in ("tol", "rot_tol", "posture_gain"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 < v < math.inf:
                raise _bad(name, v, "a finite number > 0")
        if self.posture_gain > 1:
            raise _bad("posture_gain", self.posture_gain, "0 < gain <= 1")
        for name, least in (("max_iter", 1), ("restarts", 0)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < least:
                raise _bad(name, v, f"an int >= {least}")
        if self.max_iter > MAX_ITER:
            raise _bad("max_iter", self.max_iter, f"an int from 1 to {MAX_ITER}")
        if self.restarts > N_STARTS:
            raise _bad("restarts", self.restarts, f"at most {N_STARTS}")
        if isinstance(self.posture, str) and self.posture != "middle":
            raise _bad("posture", self.posture, "'middle', None or a (nq,) array")

    @classmethod
    def of(cls, options: dict[str, Any]) -> IKOptions:
        """Options from keywords (unknown names raise :class:`ParameterError`)."""
        names = [f.name for f in fields(cls)]
        unknown = sorted(set(options) - set(names))
        if unknown:
            raise ParameterError(
                f"unknown IK option(s) {unknown}; valid: {names}",
                parameter=unknown[0],
                value=options[unknown[0]],
                allowed=names,
            )
        return cls(**options)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary."""
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        for k in ("mask", "weights", "posture"):
            if out[k] is not None and not isinstance(out[k], str):
                out[k] = np.asarray(out[k], dtype=float).tolist()
        return out


#: The options of a call that gives none.
_DEFAULT = IKOptions()


# ============================================================================ result
@dataclass(frozen=True)
class IKResult:
    """Result of :func:`~hexapod_kin.ik.solve` (arrays are read-only; SI units).

    Attributes:
        q: Joint values (nq,) in [rad]/[m] — the solution, or the best configuration found.
        status: ``"converged"``, ``"unreachable"``, ``"joint_limits"``, ``"singular"`` or
            ``"not_converged"``.
        error: Position error ‖p* − p(q)‖ in [m] over the weighted position rows.
        rotation_error: Orientation error in [rad] (pose: ‖log(R* Rᵀ)‖; position + yaw:
            ``|ψ* − ψ|``; position: 0).
        iterations: Accepted steps of the returned attempt.
        history: Weighted residual ‖W e‖ from the start, after each accepted step.
        position: p(q) in [m].
        rotation: R(q) (3, 3), the tip's rotation in the base frame.
        target: The target position in [m].
        task: The task solved (mode, target pose, yaw, weights).
        attempts: How many starts were tried.
        reason: One sentence explaining the status.
        distance: ``"unreachable"`` / ``"joint_limits"``: the best position error [m]; else 0.
        nearest: ``"unreachable"`` / ``"joint_limits"``: that point (3,); else the target.
        sigma_min: Smallest singular value of the position Jacobian at ``q`` [m/rad].

    """

    q: np.ndarray
    status: Status
    error: float
    rotation_error: float
    iterations: int
    history: np.ndarray
    position: np.ndarray
    rotation: np.ndarray
    target: np.ndarray
    task: Task
    attempts: int
    reason: str
    distance: float
    nearest: np.ndarray
    sigma_min: float

    if not TYPE_CHECKING:  # (hidden from mypy: the fields keep their types)

        def __getattr__(self, name: str) -> Any:
            """A field of a converged per-call result, filled on first use."""
            d = object.__getattribute__(self, "__dict__")
            lazy = d.get("_lazy")
            if lazy is not None:
                d.update(_converged_fields(*lazy))
                d.pop("_lazy", None)
            if name in d and name[0] != "_":
                return d[name]
            raise AttributeError(f"'IKResult' object has no attribute {name!r}")

    def __getstate__(self) -> dict[str, Any]:
        """The fields (a lazy result filled first)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @property
    def converged(self) -> bool:
        """True when ``status == "converged"``."""
        return self.status == "converged"

    @property
    def pose(self) -> np.ndarray:
        """The reached pose ``baseMtip`` (4, 4)."""
        out = np.eye(4)
        out[:3, :3] = self.rotation
        out[:3, 3] = self.position
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary ([rad]/[m])."""
        out: dict[str, Any] = {"status": self.status, "q": [float(v) for v in self.q]}
        out |= {k: float(getattr(self, k)) for k in ("error", "rotation_error")}
        out |= {"iterations": int(self.iterations), "attempts": int(self.attempts)}
        out |= {"position": [float(v) for v in self.position], "rotation": self.rotation.tolist()}
        out |= {"target": [float(v) for v in self.target], "task": self.task.to_dict()}
        out |= {"distance": float(self.distance), "nearest": [float(v) for v in self.nearest]}
        out |= {"sigma_min": float(self.sigma_min), "reason": self.reason}
        return out | {"history": [float(v) for v in self.history]}


#: Where a result's values sit in a row of the loop's output (see ``step.lm_loop``).
_O_Q = 6


def _converged_fields(row: np.ndarray, s: Any, task: Any) -> dict[str, Any]:
    """The fields of a result from its read-only output row (width,) or (1, width), converged.

    ``task``: the :class:`Task`, or ``(mode, pose (1, 4, 4), weights)``.
    """
    if row.ndim == 2:
        row = row[0]
    if not isinstance(task, Task):
        task = _task(task[0], task[1][0], 0.0, task[2])
    attempts, it, _, err, rot, smin = row[:_O_Q].tolist()
    n, it = _O_Q + s.n, int(it)
    target = task.pose[:3, 3]
    rotation = row[n + 3 : n + 12].reshape(3, 3)
    return {"q": row[_O_Q:n], "status": "converged", "error": err, "rotation_error": rot,
            "iterations": it, "history": row[n + 12 : n + 13 + it], "position": row[n : n + 3],
            "rotation": rotation, "target": target, "task": task, "attempts": int(attempts),
            "reason": s.why % (err, rot), "distance": 0.0, "nearest": target,
            "sigma_min": smin}  # fmt: skip


def _result(fields: dict[str, Any], status: Status, reason: str, far: bool) -> IKResult:
    """``IKResult(**fields)`` without ``__init__``.

    ``far``: ``distance`` and ``nearest`` are the error and the reached point (else 0, target).
    """
    fields["status"], fields["reason"] = status, reason
    fields["distance"] = fields["error"] if far else 0.0
    fields["nearest"] = fields["position"] if far else fields["target"]
    out = object.__new__(IKResult)
    object.__setattr__(out, "__dict__", fields)
    return out
