"""Resolved-rate motion: drive the tip with a linear velocity or a 6-D twist.

:func:`resolved_rate` integrates ``q̇ = J⁺_λ (ξ(t) + K e(t))`` (Euler or RK4): damped least
squares with variable damping, an optional closed-loop term toward the reference path (gain
``K`` in [1/s]), joint position and velocity limits (the law and the loop: :mod:`._law`).
Velocities: a linear velocity (3,) [m/s] of the tip in base axes, or a twist (6,) ``[v; ω]``
([m/s], [rad/s]) in base axes (``frame="base"``: ``p = p0 + v t``, ``R = exp(ω t) R0``) or in
the tip frame (``frame="tip"``: ``T = T0 exp(t ξ)``, a screw motion).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import pinocchio as pin

from .._fields import fields_dict, read_only
from ..exceptions import ConfigurationError, ParameterError, one_of, positive
from ..ik.task import check_within
from ..kinematics import as_model
from ._law import integrate

if TYPE_CHECKING:
    from ..ik.prepare import ModelLike

__all__ = ["FRAMES", "ClosestApproach", "Trajectory", "constant_twist_pose",
           "default_stance", "read_only", "resolved_rate"]  # fmt: skip

Method = Literal["euler", "rk4"]
Frame = Literal["base", "tip"]
FRAMES: tuple[str, ...] = ("base", "tip")


def default_stance(model: ModelLike) -> np.ndarray:
    """The default start of a run: :func:`hexapod_kin.ik.home` (imported on use)."""
    from ..ik.prepare import home

    return home(model)


# ============================================================================ results
@dataclass(frozen=True)
class ClosestApproach:
    """The sample of a run nearest to a singularity (smallest σ_min of the task Jacobian).

    ``t`` in [s]; ``condition`` σ_max/σ_min (inf at a singularity); ``q`` in [rad]/[m].
    """

    index: int
    t: float
    sigma_min: float
    condition: float
    q: tuple[float, ...]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (a non-finite condition becomes None)."""
        out = fields_dict(self, "index", "t", "sigma_min", "condition", "q")
        if not math.isfinite(self.condition):
            out["condition"] = None
        return out


@dataclass(frozen=True)
class Trajectory:
    """A resolved-rate run, sampled at ``t`` (all arrays read-only, SI units, base axes).

    Per sample (N rows): ``t`` [s]; ``q``, ``qdot`` joint values and rates (the law at each
    sample); ``foot`` [m], ``foot_velocity`` (``J q̇``) [m/s], ``rotation`` (3, 3) and
    ``angular_velocity`` [rad/s] of the tip; ``command``: linear velocity (3,) or twist (6,)
    ``[v; ω]`` in ``frame``; ``reference`` [m] and ``reference_rotation`` (None for a linear
    velocity); ``sigma_min``, ``sigma_max`` of the task Jacobian (3×n or 6×n); ``damping`` λ²;
    ``limited``: a joint frozen at a limit or q̇ scaled to the speed limits. ``gain``: K in
    [1/s] (0: open loop); ``frame``: ``"base"`` or ``"tip"``, the axes of ``command``.
    """

    t: np.ndarray
    q: np.ndarray
    qdot: np.ndarray
    foot: np.ndarray
    foot_velocity: np.ndarray
    rotation: np.ndarray
    angular_velocity: np.ndarray
    command: np.ndarray
    reference: np.ndarray
    reference_rotation: np.ndarray | None
    sigma_min: np.ndarray
    sigma_max: np.ndarray
    damping: np.ndarray
    limited: np.ndarray
    method: str
    dt: float
    gain: float
    frame: str = "base"

    @property
    def poses(self) -> np.ndarray:
        """(N, 4, 4) tip poses ``baseMtip``."""
        return _poses(self.rotation, self.foot)

    @property
    def condition(self) -> np.ndarray:
        """(N,) condition number σ_max/σ_min (inf at a singularity)."""
        with np.errstate(divide="ignore"):
            return np.where(self.sigma_min > 0, self.sigma_max / self.sigma_min, np.inf)

    @property
    def closest_approach(self) -> ClosestApproach:
        """The sample with the smallest σ_min."""
        i = int(np.argmin(self.sigma_min))
        smin, cond, q = float(self.sigma_min[i]), float(self.condition[i]), self.q[i]
        return ClosestApproach(i, float(self.t[i]), smin, cond, tuple(float(v) for v in q))

    @property
    def tracking_error(self) -> np.ndarray:
        """(N,) ‖foot − reference‖ in [m]."""
        return np.asarray(np.linalg.norm(self.foot - self.reference, axis=1))

    @property
    def rotation_error(self) -> np.ndarray:
        """(N,) ‖log(R_ref Rᵀ)‖ in [rad] (zeros for a linear-velocity run)."""
        if self.reference_rotation is None:
            return np.zeros(self.t.size)
        rel = self.reference_rotation @ np.transpose(self.rotation, (0, 2, 1))
        return np.array([float(np.linalg.norm(pin.log3(m))) for m in rel])

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary of every field (arrays as nested lists)."""
        out: dict[str, Any] = {}
        for name in self.__dataclass_fields__:
            v = getattr(self, name)
            out[name] = v.tolist() if isinstance(v, np.ndarray) else v
        out["closest_approach"] = self.closest_approach.to_dict()
        return out


def _poses(rot: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """(M, 4, 4) homogeneous transforms of rotations (M, 3, 3) and positions (M, 3)."""
    out = np.zeros((len(pos), 4, 4))
    out[:, :3, :3], out[:, :3, 3], out[:, 3, 3] = rot, pos, 1.0
    return out


# ============================================================================ sampling
def _call(fn: Any, times: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """``fn(times)`` if it returns (M, *shape) (or a (width, M) transpose), else ``fn`` per time."""
    try:
        out = np.asarray(fn(times), dtype=float)
        if len(shape) == 1 and out.shape == (shape[0], times.size):
            out = out.T
        if out.shape == (times.size, *shape):
            return out
    except (ValueError, TypeError, IndexError):
        pass
    return np.array([np.asarray(fn(float(t)), dtype=float) for t in times])


def _sample(fn: Any, times: np.ndarray, width: int, name: str, what: str) -> np.ndarray:
    """Evaluate a constant or callable ``fn(t)`` at ``times`` → (M, width) finite values."""
    if callable(fn):
        out = _call(fn, times, (width,))
        if out.shape != (times.size, width):
            raise ConfigurationError(
                f"{name}(t) returned shape {out.shape[1:]}; {what} (or (M, {width}) for an "
                "array of times) is needed",
                parameter=name,
                value=out.shape[1:],
                allowed=f"({width},)",
            )
    else:
        try:
            v = np.asarray(fn, dtype=float)
        except (TypeError, ValueError):
            msg = f"{name}={fn!r} is not numbers or a callable"
            raise ConfigurationError(msg, parameter=name, value=fn, allowed=what) from None
        if v.shape != (width,):
            msg = f"{name} has shape {v.shape}; {what} or a callable"
            raise ConfigurationError(msg, parameter=name, value=v.shape, allowed=what)
        out = np.broadcast_to(v, (times.size, width)).copy()
    if not np.all(np.isfinite(out)):
        msg = f"{name} contains non-finite values"
        raise ConfigurationError(msg, parameter=name, value="non-finite", allowed="finite numbers")
    return np.ascontiguousarray(out)


def _simpson(vel: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Increments over full and half steps by Simpson's rule on (v_k, v_k+½, v_k+1)."""
    v0, vh, v1 = vel[0:-1:2], vel[1::2], vel[2::2]
    return dt / 6.0 * (v0 + 4.0 * vh + v1), dt / 24.0 * (5.0 * v0 + 8.0 * vh - v1)


def constant_twist_pose(pose0: Any, twist: Any, t: Any, frame: Frame = "base") -> np.ndarray:
    """Exact poses reached by following a constant twist from ``pose0`` for times ``t``.

    ``pose0`` (4, 4), ``twist`` ``[v; ω]`` (6,) in [m/s], [rad/s], times ``t`` (M,) in [s]
    → (M, 4, 4) poses.
    """
    t0, xi = np.asarray(pose0, dtype=float), np.asarray(twist, dtype=float)
    times = np.atleast_1d(np.asarray(t, dtype=float))
    inc = times[:, None] * xi  # the increments t ξ, one row per time
    exp3, exp6, motion = pin.exp3, pin.exp6, pin.Motion  # Pinocchio's exp of SO(3) / SE(3)
    if frame == "tip":
        steps = np.array([exp6(motion(v, w)).homogeneous for v, w in zip(inc[:, :3], inc[:, 3:])])
        return np.asarray(t0 @ steps)  # one 4×4 product per time, T0 exp(t ξ)
    return _poses(np.array([exp3(w) for w in inc[:, 3:]]) @ t0[:3, :3], t0[:3, 3] + inc[:, :3])


def _integrate_pose(pose0: np.ndarray, vel: np.ndarray, dt: float, frame: str) -> np.ndarray:
    """Reference poses at half steps from a sampled twist (exact for a constant twist)."""
    full, half = _simpson(vel, dt)
    ref, cur = np.empty((vel.shape[0], 4, 4)), pose0.copy()
    ref[0] = cur
    for k in range(full.shape[0]):
        ref[2 * k + 1] = _advance(cur, half[k], frame)
        cur = _advance(cur, full[k], frame)
        ref[2 * k + 2] = cur
    return ref


def _advance(pose: np.ndarray, inc: np.ndarray, frame: str) -> np.ndarray:
    if frame == "tip":
        return (pin.SE3(pose) * pin.exp6(pin.Motion(inc))).homogeneous
    return _poses(pin.exp3(inc[3:]) @ pose[:3, :3], (pose[:3, 3] + inc[:3])[None])[0]


# ============================================================================ resolved rate
def resolved_rate(
    model: ModelLike,
    velocity: Any,
    q0: Any,
    dt: float,
    duration: float,
    *,
    frame: Frame = "base",
    method: Method = "rk4",
    gain: float = 0.0,
    path: Callable[[np.ndarray], Any] | None = None,
    sigma_threshold: float | None = None,
    max_damping: float | None = None,
    within_limits: bool = True,
    velocity_limits: bool = True,
) -> Trajectory:
    """Drive the tip with a linear velocity or a 6-D twist by resolved-rate control.

    Args:
        model: A loaded model or anything :func:`hexapod_kin.load` takes.
        velocity: A linear velocity (3,) [m/s] in base axes, or a twist (6,) ``[v; ω]``
            ([m/s], [rad/s]) in ``frame``: constant, or a callable ``v(t)`` (t in [s]).
        q0: Start configuration (nq,); None: :func:`hexapod_kin.ik.home`.
        dt: Step in [s] (> 0).
        duration: Length of the run in [s] (> 0); ``round(duration/dt)`` steps.
        frame: Axes of a twist: ``"base"`` or ``"tip"`` (body twist).
        method: ``"rk4"`` (classic Runge–Kutta) or ``"euler"``.
        gain: Closed-loop gain K in [1/s] toward the reference path (0 = open loop).
        path: Optional reference path, a callable of time: positions (M, 3) in [m] for a
            linear velocity, poses (M, 4, 4) for a twist; default the integral of the velocity
            from FK(q0) (exact for a constant twist).
        sigma_threshold: ε: damping starts when σ_min < ε. Default 1 % of the largest σ at q0.
        max_damping: λ²_max reached at σ_min = 0. Default ε².
        within_limits: Freeze joints at their position limits (and clamp).
        velocity_limits: Scale q̇ to the joint velocity limits of the model.

    Returns:
        A :class:`Trajectory` with ``round(duration/dt) + 1`` samples.

    Raises:
        ParameterError: Bad ``dt``, ``duration``, ``method``, ``frame``, ``gain`` or thresholds;
            a motion beyond a hundred robot sizes (:func:`hexapod_kin.ik.check_within`).
        ConfigurationError: Bad ``q0``, velocity or path.

    """
    mdl, dt = as_model(model), positive("dt", dt)
    duration = positive("duration", duration)
    gain = positive("gain", gain, allow_zero=True)
    one_of("method", method, ("rk4", "euler"))
    one_of("frame", frame, FRAMES)
    steps = int(round(duration / dt))
    if steps < 1 or steps > 50_000_000:
        raise ParameterError(
            f"duration/dt = {duration / dt:g} steps; between 1 and 5e7 steps are allowed",
            parameter="duration",
            value=duration,
            allowed="1..5e7 steps of dt",
        )
    start = default_stance(mdl) if q0 is None else mdl.check_q(q0, "q0").copy()
    probe = velocity(0.0) if callable(velocity) else velocity  # 3 (linear velocity) or 6 (twist)
    try:
        width = np.asarray(probe, dtype=float).size
    except (TypeError, ValueError):
        width = -1
    if width not in (3, 6):
        msg = (
            f"velocity has {width} values; a linear velocity (3,) [m/s] or a twist (6,) "
            "[v; ω] in [m/s], [rad/s] (or a callable returning one) is needed"
        )
        raise ConfigurationError(msg, parameter="velocity", value=width, allowed="3 or 6 values")
    rows6 = width == 6
    times_half = np.arange(2 * steps + 1) * (0.5 * dt)
    what = "a linear velocity (3,) in [m/s]" if not rows6 else "a twist (6,) [m/s, rad/s]"
    vel = _sample(velocity, times_half, width, "velocity", what)
    with np.errstate(over="ignore"):  # a distance beyond a hundred robots is refused at once
        check_within(mdl, vel[:, :3] * duration, "velocity x duration", ParameterError)
    pose0, ref_r = np.array(mdl.fk(start)), None
    if rows6:
        if path is not None:
            ref = _sample_poses(path, times_half)
        elif not callable(velocity):
            ref = constant_twist_pose(pose0, vel[0], times_half, frame)
        else:
            ref = _integrate_pose(pose0, vel, dt, frame)
        ref_p = np.ascontiguousarray(ref[:, :3, 3])
        ref_r = np.ascontiguousarray(ref[:, :3, :3])
    elif path is None:  # p_ref at half steps by Simpson's rule (exact for quadratics)
        (full, half), p0 = _simpson(vel, dt), pose0[:3, 3]
        ref_p = np.empty_like(vel)
        ref_p[0], ref_p[2::2] = p0, p0 + np.cumsum(full, axis=0)
        ref_p[1::2] = ref_p[0:-1:2] + half
    else:
        ref_p = _sample(path, times_half, 3, "path", "a position (3,) in [m]")
    check_within(mdl, ref_p, "path", ParameterError)
    jac0 = mdl.jacobian(start)
    sv = np.linalg.svd(jac0 if rows6 else jac0[:3], compute_uv=False)
    eps = 0.01 * sv[0] if sigma_threshold is None else positive("sigma_threshold", sigma_threshold)
    lam2max = eps * eps
    if max_damping is not None:
        lam2max = positive("max_damping", max_damping, allow_zero=True)
    lower, upper = np.asarray(mdl.lower, dtype=float), np.asarray(mdl.upper, dtype=float)
    # continuous joints (revolute, range >= 2π) wrap: no position limit for them
    cont = ~np.asarray(mdl.is_prismatic, dtype=bool) & (upper - lower >= 2 * np.pi - 1e-9)
    lo, hi = np.where(cont, -np.inf, lower), np.where(cont, np.inf, upper)
    if within_limits and (np.any(start < lo) or np.any(start > hi)):
        raise ConfigurationError(
            f"q0={start.tolist()} is outside the joint limits {lower.tolist()} .. {upper.tolist()}",
            parameter="q0",
            value=start.tolist(),
            allowed="within the joint limits (or within_limits=False)",
        )
    vlim = np.asarray(mdl.velocity_limit, dtype=float)
    vmax = np.where(velocity_limits & (vlim > 0), vlim, np.inf)
    out = integrate(mdl, start, vel, ref_p, ref_r, dt, method == "rk4", frame == "tip", gain, eps,
                    lam2max, lo, hi, within_limits, vmax)  # fmt: skip
    c, pose, tw, sg = np.ascontiguousarray, out["pose"], out["twist"], out["sigma"]
    ref_rot = None if ref_r is None else c(ref_r[::2])
    fields = (np.arange(steps + 1) * dt, out["q"], out["qdot"], c(pose[:, :3, 3]), c(tw[:, :3]),
              c(pose[:, :3, :3]), c(tw[:, 3:]), c(vel[::2]), c(ref_p[::2]), ref_rot, c(sg[:, 0]),
              c(sg[:, 1]), out["damping"], out["limited"])  # fmt: skip
    read_only(*(a for a in fields if a is not None))
    return Trajectory(*fields, method, dt, gain, frame if rows6 else "base")


def _sample_poses(path: Any, times: np.ndarray) -> np.ndarray:
    """Evaluate a pose path at ``times`` → (M, 4, 4) rigid transforms."""
    if not callable(path):
        raise ConfigurationError(
            "path must be a callable of time returning poses (M, 4, 4)",
            parameter="path",
            value=type(path).__name__,
            allowed="callable t -> (M, 4, 4)",
        )
    out = _call(path, times, (4, 4))
    if out.shape != (times.size, 4, 4) or not np.all(np.isfinite(out)):
        raise ConfigurationError(
            f"path(t) returned shape {out.shape[1:]}; finite poses (4, 4) are needed",
            parameter="path",
            value=out.shape[1:],
            allowed="(4, 4) per time",
        )
    return out
