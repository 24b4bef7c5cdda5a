"""Resolved-rate motion, joint-space schedules and foot steps.

* :func:`resolved_rate` integrates ``q̇ = J⁺_λ (v(t) + K (p_ref(t) − p(q)))`` — the seeds' main
  experiment (drive the foot with ``q̇ = J⁻¹v``) done properly: damped least squares whose
  damping grows as ``σ_min`` falls below a threshold (Nakamura/Chiaverini:
  ``λ² = λ²_max (1 − (σ_min/ε)²)`` for ``σ_min < ε``, else 0), explicit Euler or classic RK4,
  an optional closed-loop term toward the reference path ``p_ref = p0 + ∫v dt`` (gain ``K`` in
  [1/s]), joint position limits (a joint at a limit moving outward is frozen) and joint
  velocity limits (q̇ scaled uniformly, its direction kept). The loop is compiled (numba);
  velocity and reference are sampled beforehand at the RK4 half steps.
* :func:`seed_experiment` is the seeds' run: the 3-DOF leg, ``v = [A sin(2πt/T), 0, 0]``, with
  the drift figures, and the plain Euler + ``np.linalg.solve`` baseline the seeds used.
* :class:`JointSchedule` replays piecewise-linear joint tables such as seed 002's Table I
  (:func:`seed002_schedule`); :func:`track` turns foot positions back into joint trajectories
  by IK (closed form with branch continuity when the chain has one, else damped least squares
  warm-started from the previous sample).
* :func:`foot_path` / :func:`foot_step`: one step cycle — stance (a straight line on the
  ground, front to back) and swing (a lifted half ellipse or cycloid, back to front) — with
  step length, height, duration and duty factor. ``foot_path`` is a pure function of the
  phase so that gait tables can call it per leg with their phase offsets.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from . import ik as _ik
from ._kernels import fk_jac_into, njit
from .exceptions import ConfigurationError, IKError, ParameterError

__all__ = [
    "FootStep",
    "JointSchedule",
    "SeedRun",
    "Trajectory",
    "default_stance",
    "euler_baseline",
    "foot_path",
    "foot_step",
    "resolved_rate",
    "seed002_schedule",
    "seed_experiment",
    "track",
]

Method = Literal["euler", "rk4"]


def _pos(name: str, value: Any, allow_zero: bool = False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name}={value!r} is not a number") from None
    if not math.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        need = ">= 0" if allow_zero else "> 0"
        raise ParameterError(f"{name}={value!r} is not allowed; a finite value {need} is needed")
    return v


def _ro(*arrays: np.ndarray) -> None:
    for a in arrays:
        a.setflags(write=False)


# ============================================================================ trajectory
@dataclass(frozen=True)
class Trajectory:
    """A resolved-rate run, sampled at ``t`` (all arrays read-only, SI units).

    Attributes:
        t: (N,) times in [s].
        q: (N, n) joint values in [rad]/[m].
        qdot: (N, n) joint rates in [rad/s]/[m/s] (the control law at each sample).
        foot: (N, 3) tip position in [m] in the base frame.
        foot_velocity: (N, 3) actual tip velocity ``J q̇`` in [m/s].
        command: (N, 3) commanded tip velocity ``v(t)`` in [m/s].
        reference: (N, 3) reference path ``p0 + ∫v`` in [m].
        sigma_min: (N,) smallest singular value of the position Jacobian [m/rad].
        sigma_max: (N,) largest singular value [m/rad].
        damping: (N,) DLS damping λ² [m²] used at each sample.
        limited: (N,) True where a joint limit froze a joint or q̇ was scaled to the speed limits.
        method: ``"euler"`` or ``"rk4"``.
        dt: Step in [s].
        gain: Closed-loop gain K in [1/s] (0: open loop).

    """

    t: np.ndarray
    q: np.ndarray
    qdot: np.ndarray
    foot: np.ndarray
    foot_velocity: np.ndarray
    command: np.ndarray
    reference: np.ndarray
    sigma_min: np.ndarray
    sigma_max: np.ndarray
    damping: np.ndarray
    limited: np.ndarray
    method: str
    dt: float
    gain: float

    @property
    def condition(self) -> np.ndarray:
        """(N,) condition number σ_max/σ_min (inf at a singularity)."""
        with np.errstate(divide="ignore"):
            return np.where(self.sigma_min > 0, self.sigma_max / self.sigma_min, np.inf)

    @property
    def closest_approach(self) -> dict[str, Any]:
        """Closest approach to a singularity: ``{"t", "sigma_min", "condition", "q", "index"}``."""
        i = int(np.argmin(self.sigma_min))
        return {
            "index": i,
            "t": float(self.t[i]),
            "sigma_min": float(self.sigma_min[i]),
            "condition": float(self.condition[i]),
            "q": [float(v) for v in self.q[i]],
        }

    @property
    def tracking_error(self) -> np.ndarray:
        """(N,) ‖foot − reference‖ in [m]."""
        return np.asarray(np.linalg.norm(self.foot - self.reference, axis=1))


# ============================================================================ compiled loop
@njit(cache=True, nogil=True)
def _rate(
    rot: np.ndarray, trans: np.ndarray, axis: np.ndarray, kind: np.ndarray, col: np.ndarray,
    q: np.ndarray, v: np.ndarray, ref: np.ndarray, gain: float, eps: float, lam2max: float,
    lower: np.ndarray, upper: np.ndarray, use_limits: bool, vmax: np.ndarray,
    out_qd: np.ndarray, p: np.ndarray, jac: np.ndarray, scratch: np.ndarray, free: np.ndarray,
    work: np.ndarray, rhs: np.ndarray, sol: np.ndarray, xd: np.ndarray,
) -> tuple[float, float, float, bool]:  # pragma: no cover - compiled
    """The control law q̇(q, t); returns (σ_min, σ_max, λ², limited)."""
    n = q.shape[0]
    fk_jac_into(rot, trans, axis, kind, col, q, p, jac, scratch, True)
    for r in range(3):
        xd[r] = v[r] + gain * (ref[r] - p[r])
    smin, smax = _ik.sigma_bounds(jac)
    lam2 = 0.0
    if smin < eps:
        ratio = smin / eps
        lam2 = lam2max * (1.0 - ratio * ratio)
    floor = 1e-14 * (smax * smax + 1e-300)
    limited = False
    for i in range(n):
        free[i] = True
    for _pass in range(2):
        ok = _ik._dls_into(jac, xd, max(lam2, floor), free, out_qd, work, rhs, sol)
        if not ok:
            for i in range(n):
                out_qd[i] = 0.0
        again = False
        if use_limits:
            for i in range(n):
                if free[i] and (
                    (q[i] <= lower[i] and out_qd[i] < 0.0) or (q[i] >= upper[i] and out_qd[i] > 0.0)
                ):
                    free[i] = False
                    again = True
        if not again:
            break
        limited = True
    scale = 1.0
    for i in range(n):
        a = abs(out_qd[i])
        if a * scale > vmax[i]:
            scale = vmax[i] / a
    if scale < 1.0:
        limited = True
        for i in range(n):
            out_qd[i] *= scale
    return smin, smax, lam2, limited


@njit(cache=True, nogil=True)
def _rr_kernel(
    rot: np.ndarray, trans: np.ndarray, axis: np.ndarray, kind: np.ndarray, col: np.ndarray,
    q0: np.ndarray, vel: np.ndarray, ref: np.ndarray, dt: float, rk4: bool, gain: float,
    eps: float, lam2max: float, lower: np.ndarray, upper: np.ndarray, use_limits: bool,
    vmax: np.ndarray, out_q: np.ndarray, out_qd: np.ndarray, out_p: np.ndarray,
    out_pd: np.ndarray, out_s: np.ndarray, out_lam: np.ndarray, out_lim: np.ndarray,
) -> None:  # pragma: no cover - compiled
    """Integrate; ``vel``/``ref`` are sampled at half steps (index 2k = t_k, 2k+1 = t_k + dt/2)."""
    n = q0.shape[0]
    steps = out_q.shape[0] - 1
    scratch = np.empty((6, max(rot.shape[0], 1)))
    p = np.empty(3)
    jac = np.empty((3, n))
    free = np.empty(n, dtype=np.bool_)
    m = max(n, 3)
    work = np.empty((m, m))
    rhs = np.empty(m)
    sol = np.empty(m)
    xd = np.empty(3)
    q = q0.copy()
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    qs = np.empty(n)
    for k in range(steps + 1):
        h = 2 * k
        smin, smax, lam2, lim = _rate(
            rot, trans, axis, kind, col, q, vel[h], ref[h], gain, eps, lam2max, lower, upper,
            use_limits, vmax, k1, p, jac, scratch, free, work, rhs, sol, xd,
        )
        for i in range(n):
            out_q[k, i] = q[i]
            out_qd[k, i] = k1[i]
        for r in range(3):
            out_p[k, r] = p[r]
            s = 0.0
            for i in range(n):
                s += jac[r, i] * k1[i]
            out_pd[k, r] = s
        out_s[k, 0] = smin
        out_s[k, 1] = smax
        out_lam[k] = lam2
        out_lim[k] = lim
        if k == steps:
            break
        if rk4:
            for i in range(n):
                qs[i] = q[i] + 0.5 * dt * k1[i]
            _rate(rot, trans, axis, kind, col, qs, vel[h + 1], ref[h + 1], gain, eps, lam2max,
                  lower, upper, use_limits, vmax, k2, p, jac, scratch, free, work, rhs, sol, xd)
            for i in range(n):
                qs[i] = q[i] + 0.5 * dt * k2[i]
            _rate(rot, trans, axis, kind, col, qs, vel[h + 1], ref[h + 1], gain, eps, lam2max,
                  lower, upper, use_limits, vmax, k3, p, jac, scratch, free, work, rhs, sol, xd)
            for i in range(n):
                qs[i] = q[i] + dt * k3[i]
            _rate(rot, trans, axis, kind, col, qs, vel[h + 2], ref[h + 2], gain, eps, lam2max,
                  lower, upper, use_limits, vmax, k4, p, jac, scratch, free, work, rhs, sol, xd)
            for i in range(n):
                q[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        else:
            for i in range(n):
                q[i] += dt * k1[i]
        if use_limits:
            for i in range(n):
                if q[i] < lower[i]:
                    q[i] = lower[i]
                elif q[i] > upper[i]:
                    q[i] = upper[i]


def _sample_velocity(velocity: Any, times: np.ndarray) -> np.ndarray:
    """Evaluate a constant (3,) or callable ``v(t)`` at ``times``; (M, 3) finite values."""
    if callable(velocity):
        try:
            out = np.asarray(velocity(times), dtype=float)
            if out.shape == (3, times.size):
                out = out.T
            if out.shape != (times.size, 3):
                raise ValueError
        except (ValueError, TypeError, IndexError):
            out = np.array([np.asarray(velocity(float(t)), dtype=float) for t in times])
            if out.shape != (times.size, 3):
                raise ConfigurationError(
                    f"velocity(t) returned shape {out.shape[1:]}; a (3,) velocity in [m/s] "
                    "(or (M, 3) for an array of times) is needed"
                ) from None
    else:
        try:
            v = np.asarray(velocity, dtype=float)
        except (TypeError, ValueError):
            raise ConfigurationError(
                f"velocity={velocity!r} is not numbers or a callable"
            ) from None
        if v.shape != (3,):
            raise ConfigurationError(
                f"velocity has shape {v.shape}; a constant (3,) in [m/s] or a callable v(t)"
            )
        out = np.broadcast_to(v, (times.size, 3)).copy()
    if not np.all(np.isfinite(out)):
        raise ConfigurationError("velocity contains non-finite values")
    return np.ascontiguousarray(out)


def _integrate_reference(p0: np.ndarray, vel: np.ndarray, dt: float) -> np.ndarray:
    """p_ref at half steps by Simpson's rule on (v_k, v_k+½, v_k+1) (exact for quadratics)."""
    v0, vh, v1 = vel[0:-1:2], vel[1::2], vel[2::2]
    full = dt / 6.0 * (v0 + 4.0 * vh + v1)
    half = dt / 24.0 * (5.0 * v0 + 8.0 * vh - v1)
    ref = np.empty_like(vel)
    ref[0] = p0
    ref[2::2] = p0 + np.cumsum(full, axis=0)
    ref[1::2] = ref[0:-1:2] + half
    return ref


def resolved_rate(
    model: Any,
    velocity: Any,
    q0: Any,
    dt: float,
    duration: float,
    *,
    method: Method = "rk4",
    gain: float = 0.0,
    reference: Callable[[np.ndarray], Any] | None = None,
    sigma_threshold: float | None = None,
    max_damping: float | None = None,
    respect_limits: bool = True,
    velocity_limits: bool = True,
) -> Trajectory:
    """Drive the tip with a Cartesian velocity by resolved-rate control.

    Args:
        model: A loaded model (:func:`hexapod_kin.load`).
        velocity: Tip velocity in [m/s] in the base frame: a constant (3,) or a callable
            ``v(t)`` (t in [s]; called with an array of times if it accepts one, returning
            (M, 3), else once per time).
        q0: Start configuration (nq,).
        dt: Step in [s] (> 0).
        duration: Length of the run in [s] (> 0); ``round(duration/dt)`` steps.
        method: ``"rk4"`` (classic Runge–Kutta) or ``"euler"``.
        gain: Closed-loop gain K in [1/s] pulling the tip toward the reference path
            (0 = open loop). Keep ``K·dt`` well below 1.
        reference: Optional callable ``p_ref(t)`` → (M, 3) or (3,) in [m]; default
            ``FK(q0) + ∫v dt`` (Simpson's rule on the same samples).
        sigma_threshold: ε in [m/rad]: damping starts when σ_min < ε. Default 1 % of the
            largest σ at q0.
        max_damping: λ²_max in [m²] reached at σ_min = 0. Default ε².
        respect_limits: Freeze joints at their position limits (and clamp).
        velocity_limits: Scale q̇ to the joint velocity limits of the model.

    Returns:
        A :class:`Trajectory` with ``round(duration/dt) + 1`` samples.

    Raises:
        ParameterError: Bad ``dt``, ``duration``, ``method``, ``gain`` or thresholds.
        ConfigurationError: Bad ``q0`` or velocity.

    """
    dt = _pos("dt", dt)
    duration = _pos("duration", duration)
    gain = _pos("gain", gain, allow_zero=True)
    if method not in ("rk4", "euler"):
        raise ParameterError(f"method={method!r} is not allowed; use 'rk4' or 'euler'")
    steps = int(round(duration / dt))
    if steps < 1 or steps > 50_000_000:
        raise ParameterError(
            f"duration/dt = {duration / dt:g} steps; between 1 and 5e7 steps are allowed"
        )
    q_start = model.check_q(q0, "q0").copy()
    packed, lower, upper, cont, _, _, _, _ = _ik._prepared(model)
    times_half = np.arange(2 * steps + 1) * (0.5 * dt)
    vel = _sample_velocity(velocity, times_half)
    p0 = model.position(q_start)
    if reference is None:
        ref = _integrate_reference(p0, vel, dt)
    else:
        ref = _sample_velocity(reference, times_half)
    smax0 = _ik.sigma_bounds(model.position_jacobian(q_start))[1]
    eps = 0.01 * smax0 if sigma_threshold is None else _pos("sigma_threshold", sigma_threshold)
    lam2max = eps * eps if max_damping is None else _pos("max_damping", max_damping, True)
    vmax = np.where(
        velocity_limits & (np.asarray(model.velocity_limit) > 0),
        np.asarray(model.velocity_limit, dtype=float),
        np.inf,
    )
    lo = np.where(cont, -np.inf, lower) if respect_limits else lower
    hi = np.where(cont, np.inf, upper) if respect_limits else upper
    if respect_limits and (np.any(q_start < lo) or np.any(q_start > hi)):
        raise ConfigurationError(
            f"q0={q_start.tolist()} is outside the joint limits {lower.tolist()} .. "
            f"{upper.tolist()}"
        )
    n = model.nq
    out_q = np.empty((steps + 1, n))
    out_qd = np.empty((steps + 1, n))
    out_p = np.empty((steps + 1, 3))
    out_pd = np.empty((steps + 1, 3))
    out_s = np.empty((steps + 1, 2))
    out_lam = np.empty(steps + 1)
    out_lim = np.empty(steps + 1, dtype=np.bool_)
    _rr_kernel(
        *packed, q_start, vel, ref, dt, method == "rk4", gain, eps, lam2max,
        np.ascontiguousarray(lo, dtype=float), np.ascontiguousarray(hi, dtype=float),
        respect_limits, vmax, out_q, out_qd, out_p, out_pd, out_s, out_lam, out_lim,
    )
    t = np.arange(steps + 1) * dt
    command = np.ascontiguousarray(vel[::2])
    reference_s = np.ascontiguousarray(ref[::2])
    smin = np.ascontiguousarray(out_s[:, 0])
    smx = np.ascontiguousarray(out_s[:, 1])
    _ro(t, out_q, out_qd, out_p, out_pd, command, reference_s, smin, smx, out_lam, out_lim)
    return Trajectory(
        t=t, q=out_q, qdot=out_qd, foot=out_p, foot_velocity=out_pd, command=command,
        reference=reference_s, sigma_min=smin, sigma_max=smx, damping=out_lam,
        limited=out_lim, method=method, dt=dt, gain=gain,
    )


# ============================================================================ seed experiment
#: Default start of the seed run on the 3-DOF leg [rad]: foot at (0.1526, 0, −0.1293) m,
#: well away from the singularities (q3 = 0, π; foot over the hip axis).
SEED_Q0 = (0.0, 0.3, 1.2)


def default_stance(model: Any) -> np.ndarray:
    """A well-conditioned start configuration.

    ``SEED_Q0`` for 3-joint chains when it is inside the limits (the seeds' leg); otherwise the
    most dexterous of the IK home and 256 seeded samples within the limits (each range clipped
    to ±π): the one with the largest smallest singular value of the position Jacobian, so that
    a run starts far from the singular manifolds.
    """
    if model.nq == 3:
        q = np.array(SEED_Q0)
        if np.all(q >= model.lower) and np.all(q <= model.upper):
            return q
    lo = np.maximum(model.lower, -np.pi)
    hi = np.minimum(model.upper, np.pi)
    rng = np.random.default_rng(0)
    candidates = [np.array(_ik._prepared(model)[7], dtype=float)]
    candidates += list(rng.uniform(lo, hi, size=(256, model.nq)))
    best, best_sigma = candidates[0], -1.0
    for q in candidates:
        sigma = float(np.linalg.svd(model.position_jacobian(q), compute_uv=False)[-1])
        if sigma > best_sigma:
            best, best_sigma = q, sigma
    return np.array(best)


@dataclass(frozen=True)
class SeedRun:
    """The seeds' experiment and its drift figures (metres).

    Attributes:
        trajectory: The resolved-rate run.
        amplitude: A in [m/s].
        period: T in [s].
        drift_y: max |y(t) − y(0)| in [m] (tip from Pinocchio FK of the joint trajectory).
        drift_z: max |z(t) − z(0)| in [m].
        error_x: max |x(t) − x(0) − ∫v_x| in [m] against the exact integral
            ``A T/(2π) (1 − cos 2πt/T)``.
        baseline: Same three figures for the plain Euler + ``np.linalg.solve`` open loop.
        baseline_deviation: (N, 3) |foot − reference| of that baseline in [m], or None.

    """

    trajectory: Trajectory
    amplitude: float
    period: float
    drift_y: float
    drift_z: float
    error_x: float
    baseline: dict[str, float]
    baseline_deviation: np.ndarray | None = None

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready summary."""
        tr = self.trajectory
        return {
            "method": tr.method,
            "gain": tr.gain,
            "dt": tr.dt,
            "duration": float(tr.t[-1]),
            "amplitude": self.amplitude,
            "period": self.period,
            "q0": [float(v) for v in tr.q[0]],
            "drift_y": self.drift_y,
            "drift_z": self.drift_z,
            "error_x": self.error_x,
            "baseline_euler_solve": self.baseline,
            "closest_approach": tr.closest_approach,
            "max_joint_speed": float(np.max(np.abs(tr.qdot))),
        }


def _drift(
    model: Any, q: np.ndarray, t: np.ndarray, amplitude: float, period: float
) -> tuple[dict[str, float], np.ndarray]:
    """Drift figures from Pinocchio FK of ``q`` and the (N, 3) |foot − exact reference|."""
    foot = np.array([model.position(qi) for qi in q])
    ref = np.broadcast_to(foot[0], foot.shape).copy()
    ref[:, 0] += amplitude * period / (2 * np.pi) * (1 - np.cos(2 * np.pi * t / period))
    dev = np.abs(foot - ref)
    figs = {
        "drift_y": float(np.max(dev[:, 1])),
        "drift_z": float(np.max(dev[:, 2])),
        "error_x": float(np.max(dev[:, 0])),
    }
    return figs, dev


def euler_baseline(
    model: Any, velocity: Callable[[float], Any], q0: Any, dt: float, duration: float
) -> np.ndarray:
    """The seeds' integration: ``q += dt · np.linalg.solve(J(q), v(t))`` (open loop, Pinocchio).

    Returns:
        (N, n) joint trajectory.

    """
    q = model.check_q(q0, "q0").copy()
    steps = int(round(duration / dt))
    out = np.empty((steps + 1, model.nq))
    out[0] = q
    for k in range(steps):
        jac = model.position_jacobian(q)
        q = q + dt * np.linalg.solve(jac, np.asarray(velocity(k * dt), dtype=float))
        out[k + 1] = q
    return out


def seed_experiment(
    model: Any = None,
    *,
    amplitude: float = 0.05,
    period: float = 2.0,
    duration: float = 10.0,
    dt: float = 1e-3,
    q0: Any = None,
    method: Method = "rk4",
    gain: float = 10.0,
    baseline: bool = True,
) -> SeedRun:
    """The seeds' experiment: foot velocity ``[A sin(2πt/T), 0, 0]`` on the 3-DOF leg.

    The seeds give no amplitude or period; the defaults (A = 0.05 m/s, T = 2 s) move the foot
    0 → 3.2 cm → 0 along x every period from ``SEED_Q0``.

    Args:
        model: A loaded 3-joint model (default: ``hexabot_leg``).
        amplitude: A in [m/s].
        period: T in [s].
        duration: In [s].
        dt: Step in [s].
        q0: Start (default :func:`default_stance`).
        method: Integration method.
        gain: Closed-loop gain [1/s] toward the exact reference ``x0 + A T/(2π)(1 − cos 2πt/T)``.
        baseline: Also run the plain Euler + ``np.linalg.solve`` loop (needs a square J).

    Returns:
        A :class:`SeedRun`.

    """
    from .kinematics import load

    mdl = load("hexabot_leg") if model is None else model
    a = float(amplitude)
    per = _pos("period", period)
    if not math.isfinite(a):
        raise ParameterError(f"amplitude={amplitude!r} is not finite")
    q_start = default_stance(mdl) if q0 is None else mdl.check_q(q0, "q0")
    w = 2 * np.pi / per

    def vel(t: Any) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        out = np.zeros(t.shape + (3,))
        out[..., 0] = a * np.sin(w * t)
        return out

    p0 = mdl.position(q_start)

    def ref(t: Any) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        out = np.broadcast_to(p0, t.shape + (3,)).copy()
        out[..., 0] += a / w * (1.0 - np.cos(w * t))
        return out

    traj = resolved_rate(mdl, vel, q_start, dt, duration, method=method, gain=gain, reference=ref)
    figs, _ = _drift(mdl, traj.q, traj.t, a, per)
    base: dict[str, float] = {}
    base_dev = None
    if baseline and mdl.nq == 3:
        qb = euler_baseline(mdl, vel, q_start, dt, duration)
        base, base_dev = _drift(mdl, qb, traj.t, a, per)
        base_dev.setflags(write=False)
    return SeedRun(
        traj, a, per, figs["drift_y"], figs["drift_z"], figs["error_x"], base, base_dev
    )


# ============================================================================ schedules and IK
@dataclass(frozen=True)
class JointSchedule:
    """Piecewise-linear joint trajectory through knots (held constant after the last one).

    Attributes:
        times: (K,) knot times in [s], non-decreasing.
        values: (K, n) joint values at the knots in [rad]/[m].
        description: Free text (source).

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
            raise ParameterError(
                f"JointSchedule: {t.size} times and {v.shape[0]} value rows; one row per knot"
            )
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
            raise ParameterError("JointSchedule: times and values must be finite")
        if np.any(np.diff(t) < 0):
            raise ParameterError(f"JointSchedule.times={t.tolist()} must be non-decreasing")
        _ro(t, v)
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "values", v)

    def sample(self, t: Any) -> np.ndarray:
        """Joint values at times ``t`` ((M,) → (M, n); a scalar → (n,))."""
        tt = np.asarray(t, dtype=float)
        out = np.stack([np.interp(tt, self.times, self.values[:, j])
                        for j in range(self.values.shape[1])], axis=-1)
        return out


def seed002_schedule() -> JointSchedule:
    """Seed 002 Table I (movement planning of the 2-DOF leg), in radians.

    Knots (t [s]: θ1, θ2 [deg]): 0: (0, −90); 2: (0, −90) — no movement; 7: (0, −50) — tibia
    +40°; 11: (20, −50) — coxa +20°; 15: (20, −50) — no movement; 20: (0, −90) — both back;
    idle afterwards. Linear ramps (the paper's Signal Builder).
    """
    deg = np.array([(0, -90), (0, -90), (0, -50), (20, -50), (20, -50), (0, -90)], float)
    return JointSchedule(
        times=np.array([0, 2, 7, 11, 15, 20], float),
        values=np.radians(deg),
        description="seed 002 Table I (movement planning)",
    )


def track(
    model: Any, positions: Any, q_start: Any = None, *, tol: float = 1e-10
) -> tuple[np.ndarray, np.ndarray]:
    """Joint trajectory reaching a sequence of tip positions, continuously.

    Uses the closed form when the model comes from a chain with one (each sample takes the
    solution nearest to the previous sample's joints, so no branch jumps), else :func:`ik.solve`
    warm-started from the previous sample.

    Args:
        model: A loaded model.
        positions: (M, 3) tip positions in [m].
        q_start: Joints near the first sample (branch choice / warm start); default
            :func:`default_stance`.
        tol: Position tolerance [m] of the numerical fallback.

    Returns:
        ``(q, ok)``: (M, n) joints and (M,) True where the position was reached.

    Raises:
        IKError: Bad positions.

    """
    pts = np.asarray(positions, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3 or not np.all(np.isfinite(pts)):
        raise IKError(f"positions has shape {pts.shape}; finite (M, 3) in [m] is needed")
    prev = default_stance(model) if q_start is None else model.check_q(q_start, "q_start")
    out = np.empty((pts.shape[0], model.nq))
    ok = np.zeros(pts.shape[0], dtype=bool)
    try:
        batch = _ik.analytic_batch(model, pts, within_limits=True)
    except IKError:
        batch = None
    for i, p in enumerate(pts):
        if batch is not None and batch.valid[i].any():
            cands = batch.q[i][batch.valid[i]]
            d = cands - prev
            rev = ~np.asarray(model.is_prismatic)
            d[:, rev] = np.remainder(d[:, rev] + np.pi, 2 * np.pi) - np.pi
            idx = int(np.argmin(np.sum(d * d, axis=1)))
            best = cands[idx]
            # keep revolute joints continuous (no 2π jumps) when that stays inside the limits
            unwrapped = prev + d[idx]
            if np.all(unwrapped >= model.lower) and np.all(unwrapped <= model.upper):
                best = unwrapped
            out[i] = best
            ok[i] = True
        else:
            res = _ik.solve(model, p, prev, tol=tol, restarts=2)
            out[i] = res.q
            ok[i] = res.converged
        prev = out[i]
    _ro(out, ok)
    return out, ok


# ============================================================================ foot steps
def foot_path(
    phase: Any,
    *,
    center: Any,
    length: float,
    height: float,
    duty_factor: float = 0.5,
    direction: Any = (1.0, 0.0),
    shape: Literal["ellipse", "cycloid"] = "ellipse",
) -> np.ndarray:
    """Foot position over one step cycle, as a pure function of the phase.

    Phase 0 is touchdown at the front: during stance (``phase < duty_factor``) the foot
    moves on the ground in a straight line from ``center + L/2·u`` to ``center − L/2·u`` at
    constant speed (``u`` the horizontal unit ``direction`` of travel of the body); during
    swing it returns through the air: a half ellipse (``shape="ellipse"``, semi-axes L/2 and
    ``height``) or a cycloid (``shape="cycloid"``, zero velocity at lift-off and touchdown).

    Args:
        phase: Phase(s) in cycles (any real; taken modulo 1).
        center: Middle of the stance line (3,) in [m] (its z is the ground).
        length: Step length L in [m] (>= 0).
        height: Swing height in [m] (>= 0).
        duty_factor: Fraction of the cycle in stance, in (0, 1).
        direction: Horizontal direction of travel (2,), normalised here.
        shape: ``"ellipse"`` or ``"cycloid"``.

    Returns:
        (..., 3) positions in [m], the shape of ``phase`` plus 3.

    Raises:
        ParameterError: Bad lengths, duty factor, direction or shape.

    """
    c = np.asarray(center, dtype=float)
    if c.shape != (3,) or not np.all(np.isfinite(c)):
        raise ParameterError(f"center={center!r}: a finite (3,) position in [m] is needed")
    length = _pos("length", length, allow_zero=True)
    height = _pos("height", height, allow_zero=True)
    beta = float(duty_factor)
    if not (0.0 < beta < 1.0):
        raise ParameterError(f"duty_factor={duty_factor!r} is not allowed; 0 < duty_factor < 1")
    u = np.asarray(direction, dtype=float).reshape(-1)
    if u.shape != (2,) or not np.all(np.isfinite(u)) or np.hypot(*u) == 0:
        raise ParameterError(f"direction={direction!r}: a non-zero horizontal (2,) vector")
    u = u / np.hypot(*u)
    if shape not in ("ellipse", "cycloid"):
        raise ParameterError(f"shape={shape!r} is not allowed; use 'ellipse' or 'cycloid'")
    ph = np.remainder(np.asarray(phase, dtype=float), 1.0)
    stance = ph < beta
    s = np.where(stance, ph / beta, (ph - beta) / (1.0 - beta))
    along = np.where(stance, 0.5 - s, 0.0)
    up = np.zeros_like(s)
    sw = ~stance
    if shape == "ellipse":
        along = np.where(sw, -0.5 * np.cos(np.pi * s), along)
        up = np.where(sw, np.sin(np.pi * s), up)
    else:
        along = np.where(sw, s - np.sin(2 * np.pi * s) / (2 * np.pi) - 0.5, along)
        up = np.where(sw, 0.5 * (1.0 - np.cos(2 * np.pi * s)), up)
    out = np.empty(ph.shape + (3,))
    out[..., 0] = c[0] + length * along * u[0]
    out[..., 1] = c[1] + length * along * u[1]
    out[..., 2] = c[2] + height * up
    return out


@dataclass(frozen=True)
class FootStep:
    """One or more step cycles of a leg (arrays read-only, SI units).

    Attributes:
        t: (M,) times in [s].
        phase: (M,) phase in cycles (0 = touchdown).
        stance: (M,) True during stance.
        foot: (M, 3) planned foot positions in [m].
        q: (M, n) joint trajectory by IK.
        qdot: (M, n) joint rates by finite differences [rad/s].
        reached: (M,) True where IK reached the planned position.
        foot_actual: (M, 3) FK(q) (Pinocchio) in [m].
        within_limits: True if every sample is inside the joint position limits.
        max_joint_step: Largest |Δq| between consecutive samples [rad]/[m] (continuity).

    """

    t: np.ndarray
    phase: np.ndarray
    stance: np.ndarray
    foot: np.ndarray
    q: np.ndarray
    qdot: np.ndarray
    reached: np.ndarray
    foot_actual: np.ndarray
    within_limits: bool
    max_joint_step: float

    @property
    def max_error(self) -> float:
        """Max ‖FK(q) − planned‖ in [m]."""
        return float(np.max(np.linalg.norm(self.foot_actual - self.foot, axis=1)))


def foot_step(
    model: Any,
    *,
    center: Any = None,
    length: float = 0.04,
    height: float = 0.03,
    duration: float = 1.0,
    duty_factor: float = 0.5,
    dt: float = 0.005,
    direction: Any = (1.0, 0.0),
    shape: Literal["ellipse", "cycloid"] = "ellipse",
    cycles: int = 1,
    phase_offset: float = 0.0,
    q_start: Any = None,
) -> FootStep:
    """Plan a foot step (stance + swing) and its joint trajectory by IK.

    Args:
        model: A loaded leg model.
        center: Middle of the stance line (3,) in [m]; default the foot at
            :func:`default_stance`.
        length: Step length [m].
        height: Swing height [m].
        duration: Cycle time [s].
        duty_factor: Stance fraction in (0, 1).
        dt: Sample time [s].
        direction: Horizontal travel direction (2,).
        shape: Swing shape ``"ellipse"`` or ``"cycloid"``.
        cycles: Number of cycles (>= 1).
        phase_offset: Phase at t = 0 in cycles (gait tables set one per leg).
        q_start: Joints near the first sample (IK branch / warm start).

    Returns:
        A :class:`FootStep`.

    Raises:
        ParameterError: Bad step parameters.

    """
    duration = _pos("duration", duration)
    dt = _pos("dt", dt)
    if not (isinstance(cycles, int) and cycles >= 1):
        raise ParameterError(f"cycles={cycles!r} is not allowed; an int >= 1 is needed")
    q_home = default_stance(model) if q_start is None else model.check_q(q_start, "q_start")
    c = model.position(q_home) if center is None else np.asarray(center, dtype=float)
    m = int(round(cycles * duration / dt))
    t = np.arange(m + 1) * (cycles * duration / m)
    phase = t / duration + float(phase_offset)
    foot = foot_path(
        phase, center=c, length=length, height=height, duty_factor=duty_factor,
        direction=direction, shape=shape,
    )
    q, reached = track(model, foot, q_home)
    qdot = np.gradient(q, t, axis=0)
    actual = np.array([model.position(qi) for qi in q])
    within = bool(np.all(q >= model.lower - 1e-12) and np.all(q <= model.upper + 1e-12))
    step = float(np.max(np.abs(np.diff(q, axis=0)))) if len(q) > 1 else 0.0
    stance = np.remainder(phase, 1.0) < duty_factor
    _ro(t, phase, stance, foot, qdot, actual)
    return FootStep(t, phase, stance, foot, q, qdot, reached, actual, within, step)
