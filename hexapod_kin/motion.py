"""Resolved-rate motion and joint-space schedules.

* :func:`resolved_rate` integrates ``q̇ = J⁺_λ (v(t) + K (p_ref(t) − p(q)))`` — the seeds' main
  experiment (drive the foot with ``q̇ = J⁻¹v``) done properly: damped least squares whose
  damping grows as ``σ_min`` falls below a threshold (Nakamura/Chiaverini:
  ``λ² = λ²_max (1 − (σ_min/ε)²)`` for ``σ_min < ε``, else 0), explicit Euler or classic RK4,
  an optional closed-loop term toward the reference path ``p_ref = p0 + ∫v dt`` (gain ``K`` in
  [1/s]), joint position limits (a joint at a limit moving outward is frozen) and joint
  velocity limits (q̇ scaled uniformly, its direction kept). The loop is compiled (numba);
  velocity and reference are sampled beforehand at the RK4 half steps.
* :class:`JointSchedule` replays piecewise-linear joint tables; :func:`track` turns foot
  positions back into joint trajectories by IK (closed form with branch continuity when the
  chain has one, else damped least squares warm-started from the previous sample).

The seeds' own experiments live in :mod:`hexapod_kin.seeds`; foot steps and gaits in
:mod:`hexapod_kin.gait`.
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
    "JointSchedule",
    "SEED_Q0",
    "Trajectory",
    "default_stance",
    "positive",
    "read_only",
    "resolved_rate",
    "track",
]

Method = Literal["euler", "rk4"]


def positive(name: str, value: Any, allow_zero: bool = False) -> float:
    """``value`` as a finite float > 0 (≥ 0 with ``allow_zero``).

    Raises:
        ParameterError: Not a number, not finite, or out of range; the message names ``name``.

    """
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name}={value!r} is not a number") from None
    if not math.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        need = ">= 0" if allow_zero else "> 0"
        raise ParameterError(f"{name}={value!r} is not allowed; a finite value {need} is needed")
    return v


def read_only(*arrays: np.ndarray) -> None:
    """Mark arrays read-only (results handed to users are protected)."""
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
    rot: np.ndarray,
    trans: np.ndarray,
    axis: np.ndarray,
    kind: np.ndarray,
    col: np.ndarray,
    q: np.ndarray,
    v: np.ndarray,
    ref: np.ndarray,
    gain: float,
    eps: float,
    lam2max: float,
    lower: np.ndarray,
    upper: np.ndarray,
    use_limits: bool,
    vmax: np.ndarray,
    out_qd: np.ndarray,
    p: np.ndarray,
    jac: np.ndarray,
    scratch: np.ndarray,
    free: np.ndarray,
    work: np.ndarray,
    rhs: np.ndarray,
    sol: np.ndarray,
    xd: np.ndarray,
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
    rot: np.ndarray,
    trans: np.ndarray,
    axis: np.ndarray,
    kind: np.ndarray,
    col: np.ndarray,
    q0: np.ndarray,
    vel: np.ndarray,
    ref: np.ndarray,
    dt: float,
    rk4: bool,
    gain: float,
    eps: float,
    lam2max: float,
    lower: np.ndarray,
    upper: np.ndarray,
    use_limits: bool,
    vmax: np.ndarray,
    out_q: np.ndarray,
    out_qd: np.ndarray,
    out_p: np.ndarray,
    out_pd: np.ndarray,
    out_s: np.ndarray,
    out_lam: np.ndarray,
    out_lim: np.ndarray,
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
            rot,
            trans,
            axis,
            kind,
            col,
            q,
            vel[h],
            ref[h],
            gain,
            eps,
            lam2max,
            lower,
            upper,
            use_limits,
            vmax,
            k1,
            p,
            jac,
            scratch,
            free,
            work,
            rhs,
            sol,
            xd,
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
            _rate(
                rot,
                trans,
                axis,
                kind,
                col,
                qs,
                vel[h + 1],
                ref[h + 1],
                gain,
                eps,
                lam2max,
                lower,
                upper,
                use_limits,
                vmax,
                k2,
                p,
                jac,
                scratch,
                free,
                work,
                rhs,
                sol,
                xd,
            )
            for i in range(n):
                qs[i] = q[i] + 0.5 * dt * k2[i]
            _rate(
                rot,
                trans,
                axis,
                kind,
                col,
                qs,
                vel[h + 1],
                ref[h + 1],
                gain,
                eps,
                lam2max,
                lower,
                upper,
                use_limits,
                vmax,
                k3,
                p,
                jac,
                scratch,
                free,
                work,
                rhs,
                sol,
                xd,
            )
            for i in range(n):
                qs[i] = q[i] + dt * k3[i]
            _rate(
                rot,
                trans,
                axis,
                kind,
                col,
                qs,
                vel[h + 2],
                ref[h + 2],
                gain,
                eps,
                lam2max,
                lower,
                upper,
                use_limits,
                vmax,
                k4,
                p,
                jac,
                scratch,
                free,
                work,
                rhs,
                sol,
                xd,
            )
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
    dt = positive("dt", dt)
    duration = positive("duration", duration)
    gain = positive("gain", gain, allow_zero=True)
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
    eps = 0.01 * smax0 if sigma_threshold is None else positive("sigma_threshold", sigma_threshold)
    lam2max = eps * eps if max_damping is None else positive("max_damping", max_damping, True)
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
        *packed,
        q_start,
        vel,
        ref,
        dt,
        method == "rk4",
        gain,
        eps,
        lam2max,
        np.ascontiguousarray(lo, dtype=float),
        np.ascontiguousarray(hi, dtype=float),
        respect_limits,
        vmax,
        out_q,
        out_qd,
        out_p,
        out_pd,
        out_s,
        out_lam,
        out_lim,
    )
    t = np.arange(steps + 1) * dt
    command = np.ascontiguousarray(vel[::2])
    reference_s = np.ascontiguousarray(ref[::2])
    smin = np.ascontiguousarray(out_s[:, 0])
    smx = np.ascontiguousarray(out_s[:, 1])
    read_only(t, out_q, out_qd, out_p, out_pd, command, reference_s, smin, smx, out_lam, out_lim)
    return Trajectory(
        t=t,
        q=out_q,
        qdot=out_qd,
        foot=out_p,
        foot_velocity=out_pd,
        command=command,
        reference=reference_s,
        sigma_min=smin,
        sigma_max=smx,
        damping=out_lam,
        limited=out_lim,
        method=method,
        dt=dt,
        gain=gain,
    )


# ============================================================================ start pose
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


# ====================================================================== schedules and tracking
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
        read_only(t, v)
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "values", v)

    def sample(self, t: Any) -> np.ndarray:
        """Joint values at times ``t`` ((M,) → (M, n); a scalar → (n,))."""
        tt = np.asarray(t, dtype=float)
        out = np.stack(
            [np.interp(tt, self.times, self.values[:, j]) for j in range(self.values.shape[1])],
            axis=-1,
        )
        return out


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
    read_only(out, ok)
    return out, ok
