"""Numerical IK for any loaded chain: position, position + yaw, or a full 6-D pose.

:func:`solve` builds the task (:func:`~hexapod_kin.ik.task.build_task`), runs the compiled
Levenberg–Marquardt loop (:func:`~hexapod_kin.ik.step.lm_loop`: damping ``λ² = μ(‖We‖² + w̄)``
adapted step by step, a step kept only if it lowers the error — the residual history decreases
strictly —, a step cap, joint limits: continuous joints (range ≥ 2π) wrap, the others are
clamped and a joint blocked at a limit is frozen; stall detection; seeded restarts) and reports
the result with Pinocchio's FK. Orientation errors are ``log(R* Rᵀ)`` on SO(3), never Euler
angles. On a redundant chain (more joints than task rows, e.g. Panda 7-DOF with a 6-D pose)
a secondary task moves toward a preferred posture (default: the middle of the joint ranges)
in the null space of the task, while it does not slow the task down.

Per-model data (:mod:`hexapod_kin.ik.prepare`) is built once and kept in the model's cache;
every call allocates its own buffers, so one model can be solved from many threads.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from .._kernels import fk_jac_into
from .._numerics import sigma_bounds
from ..exceptions import ConfigurationError, IKError, ParameterError
from ..kinematics import KinematicModel
from .prepare import N_STARTS, ModelLike, Prepared, as_model, prepared
from .step import (
    I_LIMITS,
    I_MAX_ITER,
    P_ROT_TOL,
    P_TOL,
    P_YAW,
    lm_loop,
    pose_errors,
    task_cost,
    task_into,
    tip_rotation_into,
)
from .task import Task, build_task

__all__ = ["STATUSES", "IKResult", "solve", "solve_many"]

Status = Literal["converged", "unreachable", "joint_limits", "singular", "not_converged"]
STATUSES: tuple[str, ...] = (
    "converged",
    "unreachable",
    "joint_limits",
    "singular",
    "not_converged",
)

_MU0 = 0.1  # initial LM factor: λ² = μ (‖e‖² + w̄)


# ============================================================================ result
@dataclass(frozen=True)
class IKResult:
    """Result of :func:`solve` (arrays are read-only; SI units).

    Attributes:
        q: Joint values (nq,) in [rad]/[m] — the solution, or the best configuration found.
        status: ``"converged"``, ``"unreachable"``, ``"joint_limits"``, ``"singular"`` or
            ``"not_converged"``.
        error: Position error ‖p* − p(q)‖ in [m] over the weighted position rows, recomputed
            with Pinocchio.
        rotation_error: Orientation error in [rad] (pose: ‖log(R* Rᵀ)‖ over the weighted rows;
            position + yaw: |ψ* − ψ|; position: 0), recomputed with Pinocchio.
        iterations: Accepted steps of the returned attempt.
        history: Weighted residual ‖W e‖ after each accepted step of the returned attempt
            (starts with the initial residual; strictly decreasing).
        position: p(q) in [m] (Pinocchio).
        rotation: R(q) (3, 3), the tip's rotation in the base frame (Pinocchio).
        target: The target position in [m].
        task: The task solved (mode, target pose, yaw, weights).
        attempts: How many starts were tried (1 + restarts used).
        reason: One sentence explaining the status.
        distance: For ``"unreachable"`` / ``"joint_limits"``: the position error in [m] of the
            best configuration found; else 0.
        nearest: For ``"unreachable"`` / ``"joint_limits"``: that point (3,); else the target.
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
        return {
            "status": self.status,
            "q": [float(v) for v in self.q],
            "error": float(self.error),
            "rotation_error": float(self.rotation_error),
            "iterations": int(self.iterations),
            "attempts": int(self.attempts),
            "position": [float(v) for v in self.position],
            "rotation": self.rotation.tolist(),
            "target": [float(v) for v in self.target],
            "task": self.task.to_dict(),
            "distance": float(self.distance),
            "nearest": [float(v) for v in self.nearest],
            "sigma_min": float(self.sigma_min),
            "reason": self.reason,
            "history": [float(v) for v in self.history],
        }


# ============================================================================ solve
def _positive(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(
            f"{name}={value!r} is not allowed; a finite number > 0 is needed",
            parameter=name,
            value=value,
            allowed="finite > 0",
        )
    if not (math.isfinite(value) and value > 0):
        raise ParameterError(
            f"{name}={value!r} is not allowed; a finite number > 0 is needed",
            parameter=name,
            value=value,
            allowed="finite > 0",
        )
    return float(value)


def _count(name: str, value: Any, least: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
        raise ParameterError(
            f"{name}={value!r} is not allowed; an int >= {least} is needed",
            parameter=name,
            value=value,
            allowed=f"int >= {least}",
        )
    return int(value)


def _posture(model: KinematicModel, prep: Prepared, posture: Any) -> tuple[np.ndarray, bool]:
    if posture is None or posture is False:
        return prep.middle, False
    if isinstance(posture, str):
        if posture != "middle":
            raise ParameterError(
                f"posture={posture!r} is not allowed; use 'middle', None or a (nq,) array",
                parameter="posture",
                value=posture,
                allowed="'middle', None, (nq,) array",
            )
        return prep.middle, True
    return np.ascontiguousarray(model.check_q(posture, "posture"), dtype=float), True


def solve(
    model: ModelLike,
    target: Any,
    q0: Any = None,
    *,
    mask: Any = None,
    weights: Any = None,
    tol: float = 1e-10,
    rot_tol: float = 1e-10,
    max_iter: int = 100,
    restarts: int = 16,
    within_limits: bool = True,
    posture: Any = "middle",
    posture_gain: float = 0.1,
) -> IKResult:
    """Numerical IK of the tip: position, position + yaw, or a 6-D pose, for any chain.

    Args:
        model: A loaded model (:func:`hexapod_kin.load`) or anything ``load`` takes.
        target: Tip position (3,) [m]; position + yaw (4,) (ψ [rad]: angle of the tool's x
            axis in the base xy-plane); or a pose ``baseMtarget`` (4, 4).
        q0: Start configuration (nq,); default :func:`~hexapod_kin.ik.home`.
        mask: Optional 6 booleans for rows x y z wx wy wz (e.g. ``[1, 1, 1, 0, 0, 1]``).
        weights: Optional 6 weights >= 0 for those rows (instead of ``mask``).
        tol: Convergence threshold on the position error in [m].
        rot_tol: Convergence threshold on the orientation error in [rad].
        max_iter: Accepted steps per attempt.
        restarts: Extra attempts from seeded random configurations if the first fails (≤ 32).
        within_limits: Clamp limited joints to their bounds (continuous joints always wrap).
        posture: Secondary task of redundant chains: ``"middle"`` (middle of the joint
            ranges), a preferred configuration (nq,), or None (off).
        posture_gain: Fraction of the distance to ``posture`` tried per step (0 < g ≤ 1).

    Returns:
        An :class:`IKResult`. ``"unreachable"``: every attempt ended at a local minimum of the
        task error (no direction lowers it), also without limits; ``nearest`` / ``distance``
        give the best point found. ``"joint_limits"``: reachable only outside the limits.
        ``"singular"``: stuck at a singular configuration that is not a minimum.
        ``"not_converged"``: iteration cap.

    Raises:
        IKError: Non-finite or wrongly shaped target, or bad mask/weights.
        ConfigurationError: Bad ``q0`` or ``posture``.
        ParameterError: Bad ``tol``, ``rot_tol``, ``max_iter``, ``restarts`` or posture.

    """
    mdl = model if model.__class__ is KinematicModel else as_model(model)
    task = build_task(target, mask=mask, weights=weights)
    # options and default starts, checked once per model and set of options (never written)
    key = None
    if posture is None or posture.__class__ is str:
        key = (tol, rot_tol, max_iter, restarts, within_limits, posture, posture_gain, task.code)
    known: dict[Any, Any] = mdl.cached("ik.options", dict)
    hit = known.get(key) if key is not None else None
    if hit is None:
        opts = _options(
            mdl, tol, rot_tol, max_iter, restarts, within_limits, posture, posture_gain, task.code
        )
        prep, par, ipar, target_posture, n_restarts = opts
        home_starts = np.empty((1 + n_restarts, mdl.nq))
        home_starts[0] = prep.home
        home_starts[1:] = prep.starts[:n_restarts]
        hit = (prep, par, ipar, target_posture, home_starts)
        if key is not None and len(known) < 64:
            known[key] = hit
    prep, par, ipar, target_posture, starts = hit
    if task.yaw != 0.0:
        par = par.copy()
        par[P_YAW] = task.yaw
    if q0 is not None:
        starts = starts.copy()
        starts[0] = mdl.check_q(q0, "q0")
    q = np.empty(mdl.nq)
    hist = np.empty(int(ipar[I_MAX_ITER]) + 1)
    jac = np.empty((6, mdl.nq))
    attempts, it, code = lm_loop(
        *prep.packed,
        prep.tip_rot,
        task.pose,
        task.weights,
        par,
        ipar,
        starts,
        prep.lim,
        prep.cont,
        target_posture,
        q,
        hist,
        jac,
    )
    return _report(mdl, prep, task, q, hist[: it + 1], jac, attempts, it, code, par, ipar)


def _options(
    mdl: KinematicModel,
    tol: Any,
    rot_tol: Any,
    max_iter: Any,
    restarts: Any,
    within_limits: bool,
    posture: Any,
    posture_gain: Any,
    mode: int,
) -> tuple[Prepared, np.ndarray, np.ndarray, np.ndarray, int]:
    """Checked options as the loop's parameters: (prepared, par, ipar, posture, restarts)."""
    if not (tol.__class__ is float and 0.0 < tol < math.inf):
        tol = _positive("tol", tol)
    if not (rot_tol.__class__ is float and 0.0 < rot_tol < math.inf):
        rot_tol = _positive("rot_tol", rot_tol)
    if not (max_iter.__class__ is int and max_iter >= 1):
        max_iter = _count("max_iter", max_iter, 1)
    if not (restarts.__class__ is int and restarts >= 0):
        restarts = _count("restarts", restarts, 0)
    if restarts > N_STARTS:
        raise ParameterError(
            f"restarts={restarts} is not allowed; at most {N_STARTS}",
            parameter="restarts",
            value=restarts,
            allowed=f"0..{N_STARTS}",
        )
    gain = posture_gain
    if not (gain.__class__ is float and 0.0 < gain <= 1.0):
        gain = _positive("posture_gain", posture_gain)
        if gain > 1.0:
            raise ParameterError(
                f"posture_gain={posture_gain!r} is not allowed; 0 < gain <= 1",
                parameter="posture_gain",
                value=posture_gain,
                allowed="(0, 1]",
            )
    prep = prepared(mdl)
    target_posture, use_posture = _posture(mdl, prep, posture)
    # the loop's parameters, in the order of step.P_* and step.I_* (P_YAW set per target)
    par = np.array([tol, rot_tol, 1e-8 * prep.scale**2, _MU0, gain, 0.0, 1e-6 * prep.scale])
    ipar = np.array([mode, max_iter, int(bool(within_limits)), int(use_posture)], dtype=np.int64)
    return prep, par, ipar, target_posture, int(restarts)


def _report(
    mdl: KinematicModel,
    prep: Prepared,
    task: Task,
    q: np.ndarray,
    hist: np.ndarray,
    jac: np.ndarray,
    attempts: int,
    it: int,
    code: int,
    par: np.ndarray,
    ipar: np.ndarray,
) -> IKResult:
    pose = mdl.fk(q)  # the reported residual: Pinocchio's FK (a fresh C-ordered array)
    err, rot = pose_errors(task.code, task.pose, task.weights, task.yaw, pose)
    smin = float(sigma_bounds(jac[:3])[0])
    # read-only views, no copies: ``pose`` and ``hist``'s base are this call's own arrays and
    # ``task.pose`` is read-only already
    pose.setflags(write=False)
    tgt = task.pose[:3, 3]
    pos = pose[:3, 3]
    rmat = pose[:3, :3]
    q.setflags(write=False)
    hist.setflags(write=False)
    tol, rot_tol = float(par[P_TOL]), float(par[P_ROT_TOL])

    def result(status: Status, reason: str, far: bool = False) -> IKResult:
        # a frozen dataclass's __init__ sets each of its 15 fields through
        # object.__setattr__; filling __dict__ at once is the same object, 2 µs sooner
        out = object.__new__(IKResult)
        out.__dict__.update(
            q=q,
            status=status,
            error=err,
            rotation_error=rot,
            iterations=it,
            history=hist,
            position=pos,
            rotation=rmat,
            target=tgt,
            task=task,
            attempts=attempts,
            reason=reason,
            distance=err if far else 0.0,
            nearest=pos if far else tgt,
            sigma_min=smin,
        )
        return out

    if code == 0 or (err <= tol and rot <= rot_tol):
        return result("converged", f"‖e‖ = {err:.3g} m, {rot:.3g} rad <= tol {tol:g}, {rot_tol:g}")
    if code == 2:
        return result(
            "not_converged",
            f"{int(ipar[I_MAX_ITER])} steps taken, ‖e‖ = {err:.3g} m, "
            f"{rot:.3g} rad, still decreasing",
        )
    use_limits = bool(ipar[I_LIMITS])
    if use_limits and _blocked(q, jac, task, prep).size:
        free = ipar.copy()
        free[I_LIMITS] = 0
        free[I_MAX_ITER] = 200
        qq, hh, jj = np.empty(mdl.nq), np.empty(201), np.empty((6, mdl.nq))
        starts = np.vstack([q, prep.starts[:8]])
        _, _, c2 = lm_loop(
            *prep.packed,
            prep.tip_rot,
            task.pose,
            task.weights,
            par,
            free,
            starts,
            prep.lim,
            prep.cont,
            prep.middle,
            qq,
            hh,
            jj,
        )
        if c2 == 0:
            names = [mdl.joint_names[i] for i in _blocked(q, jac, task, prep)]
            return result(
                "joint_limits",
                f"reachable only beyond the limits of {names}; the nearest point within the "
                f"limits is {err:.3g} m, {rot:.3g} rad away",
                far=True,
            )
    if _is_local_min(mdl, prep, task, q, hist[-1], par, ipar):
        return result(
            "unreachable",
            f"outside the workspace: every start ends at a local minimum of the error, "
            f"{err:.6g} m, {rot:.6g} rad from the target",
            far=True,
        )
    if smin <= 1e-6 * prep.scale:
        return result(
            "singular",
            f"stalled at a singular configuration (σ_min = {smin:.3g}) that is not a minimum "
            "of the error; try another q0 or more restarts",
        )
    return result("not_converged", f"stalled at ‖e‖ = {err:.3g} m (no step lowers the error)")


def _blocked(q: np.ndarray, jac: np.ndarray, task: Task, prep: Prepared) -> np.ndarray:
    """Joints at a limit whose task-error gradient points outward."""
    rot, trans, axis, kind, col = prep.packed
    q = np.array(q, dtype=float)  # writable, like the kernels' q: one compiled fk_jac_into
    p = np.empty(3)
    fk_jac_into(rot, trans, axis, kind, col, q, p, np.empty((3, q.size)), _scratch(prep), False)
    r = np.empty((3, 3))
    tip_rotation_into(rot, axis, kind, col, prep.tip_rot, q, r)
    et, jt = np.empty(6), np.empty((6, q.size))
    m, _, _ = task_into(
        task.code, task.pose, task.weights, task.yaw, p, r, jac, np.empty((3, 3)), et, jt
    )
    g = jt[:m].T @ et[:m]
    lower, upper, cont = prep.lim[0], prep.lim[1], prep.cont
    at_lo = (~cont) & (q <= lower + 1e-12) & (g < 0)
    at_hi = (~cont) & (q >= upper - 1e-12) & (g > 0)
    return np.flatnonzero(at_lo | at_hi)


def _scratch(prep: Prepared) -> np.ndarray:
    return np.empty((6, max(prep.packed[0].shape[0], 1)))


def _is_local_min(
    mdl: KinematicModel,
    prep: Prepared,
    task: Task,
    q: np.ndarray,
    cost_root: float,
    par: np.ndarray,
    ipar: np.ndarray,
) -> bool:
    """True if no small perturbation of q (±1e-3, ±3e-2 rad) lowers the task error."""
    rng = np.random.default_rng(7)
    jac = mdl.jacobian(q)
    rows = task.weights != 0
    jt = jac[rows] * task.weights[rows, None]
    _, sv, vt = np.linalg.svd(jt)
    sv_full = np.zeros(mdl.nq)
    sv_full[: sv.size] = sv
    null = vt[sv_full <= 1e-6 * max(prep.scale, float(sv_full.max()))]
    base = np.vstack([np.eye(mdl.nq), rng.normal(size=(16, mdl.nq)), null])
    dirs = np.vstack([base, -base])
    trial = np.vstack([q[None, :] + h * dirs for h in (1e-3, 3e-2)])
    if ipar[I_LIMITS]:
        trial = np.where(prep.cont, trial, np.clip(trial, prep.lim[0], prep.lim[1]))
    cost = np.empty(trial.shape[0])
    task_cost(
        *prep.packed,
        prep.tip_rot,
        task.pose,
        task.weights,
        par,
        ipar,
        np.ascontiguousarray(trial),
        cost,
    )
    return bool(np.all(np.sqrt(cost) >= cost_root - 1e-9 * prep.scale))


def solve_many(
    model: ModelLike,
    targets: Any,
    q0: Any = None,
    *,
    mask: Any = None,
    weights: Any = None,
    tol: float = 1e-10,
    rot_tol: float = 1e-10,
    max_iter: int = 100,
    restarts: int = 16,
    within_limits: bool = True,
    posture: Any = "middle",
    posture_gain: float = 0.1,
) -> list[IKResult]:
    """:func:`solve` for N targets of one kind, the loops in one compiled call.

    Args:
        model: A loaded model or anything :func:`hexapod_kin.load` takes.
        targets: (N, 3) positions, (N, 4) positions + yaw, or (N, 4, 4) poses.
        q0: None (:func:`~hexapod_kin.ik.home` for all), one start (nq,) for all, or (N, nq)
            starts.
        mask: As in :func:`solve` (one for all targets).
        weights: As in :func:`solve`.
        tol: As in :func:`solve`.
        rot_tol: As in :func:`solve`.
        max_iter: As in :func:`solve`.
        restarts: As in :func:`solve`.
        within_limits: As in :func:`solve`.
        posture: As in :func:`solve`.
        posture_gain: As in :func:`solve`.

    Returns:
        One :class:`IKResult` per target, equal to :func:`solve`'s.

    Raises:
        IKError: Bad targets. ConfigurationError: ``q0`` rows do not match.
        ParameterError: Bad options.

    """
    from .step import lm_batch

    mdl = as_model(model)
    t = np.asarray(targets, dtype=float)
    if (
        t.ndim not in (2, 3)
        or (t.ndim == 2 and t.shape[1] not in (3, 4))
        or (t.ndim == 3 and t.shape[1:] != (4, 4))
    ):
        raise IKError(
            f"targets has shape {t.shape}; (N, 3), (N, 4) or (N, 4, 4) is needed",
            parameter="targets",
            value=t.shape,
            allowed="(N, 3), (N, 4), (N, 4, 4)",
        )
    tasks = [build_task(ti, mask=mask, weights=weights) for ti in t]
    n_t = len(tasks)
    code = tasks[0].code if tasks else 0
    prep, par, ipar, target_posture, restarts = _options(
        mdl, tol, rot_tol, max_iter, restarts, within_limits, posture, posture_gain, code
    )
    starts = np.empty((n_t, 1 + restarts, mdl.nq))
    if q0 is None:
        starts[:, 0] = prep.home
    elif np.ndim(q0) == 1:
        starts[:, 0] = mdl.check_q(q0, "q0")
    else:
        rows = mdl.check_q_batch(q0, "q0")
        if len(rows) != n_t:
            raise ConfigurationError(
                f"q0 has {len(rows)} rows; targets has {n_t}",
                parameter="q0",
                value=len(rows),
                allowed=f"{n_t} rows",
            )
        starts[:, 0] = rows
    starts[:, 1:] = prep.starts[:restarts]
    pars = np.tile(par, (n_t, 1))
    pars[:, P_YAW] = [task.yaw for task in tasks]
    tgts = np.array([task.pose for task in tasks]).reshape(n_t, 4, 4)
    m = int(ipar[I_MAX_ITER])
    q = np.empty((n_t, mdl.nq))
    hist = np.empty((n_t, m + 1))
    jac = np.empty((n_t, 6, mdl.nq))
    res = np.empty((n_t, 3), dtype=np.int64)
    if n_t:
        weights6 = np.ascontiguousarray(tasks[0].weights)
        lm_batch(
            *prep.packed,
            prep.tip_rot,
            tgts,
            weights6,
            pars,
            ipar,
            starts,
            prep.lim,
            prep.cont,
            target_posture,
            q,
            hist,
            jac,
            res,
        )
    out = []
    for i, task in enumerate(tasks):
        a, it, c = (int(v) for v in res[i])
        out.append(
            _report(
                mdl,
                prep,
                task,
                q[i].copy(),
                hist[i, : it + 1].copy(),
                jac[i].copy(),
                a,
                it,
                c,
                pars[i],
                ipar,
            )
        )
    return out
