"""The compiled resolved-rate loop: the control law ``q̇(q, t)`` and its Euler / RK4 integration.

Tasks: ``rows6 = False`` — the tip's linear velocity (3 rows, base axes); ``rows6 = True`` — a
6-D twist ``[v; ω]`` given in the base axes (``tip_frame = False``: the tip's linear velocity and
angular velocity in base axes, LOCAL_WORLD_ALIGNED) or in the tip frame (``tip_frame = True``:
the body twist, LOCAL), rotated here into base axes — damped least squares is invariant under
that rotation, so both use the one LWA Jacobian. The feedback term is ``K [p_ref − p;
log(R_ref Rᵀ)]`` (the pose error on SO(3), never Euler angles).

Damping: ``σ_min`` of a 3-row task comes from closed forms at every evaluation; for a twist it
takes a small Jacobi eigen-solve, done at the start of each step and held (zero-order) over
that step's RK4 stages. All buffers are allocated per call (thread-safe, ``nogil``).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from .._kernels import fk_jac_into
from .._numerics import dls_into, jacobi_eig, njit, sigma_bounds
from ..ik.step import log3_into, tip_rotation_into
from ._cold import rr_cold

__all__ = ["rr_kernel"]


@njit(cache=True, nogil=True)
def _sigma6(jac: np.ndarray, g: np.ndarray, ev: np.ndarray) -> tuple[float, float]:
    """(σ_min, σ_max) of a (6, n) Jacobian: eigenvalues of the smaller Gram matrix."""
    n = jac.shape[1]
    k = min(n, 6)
    if n >= 6:
        for a in range(6):
            for b in range(6):
                s = 0.0
                for i in range(n):
                    s += jac[a, i] * jac[b, i]
                g[a, b] = s
    else:
        for a in range(n):
            for b in range(n):
                s = 0.0
                for r in range(6):
                    s += jac[r, a] * jac[r, b]
                g[a, b] = s
    jacobi_eig(g[:k, :k], ev[:k])
    return math.sqrt(max(ev[k - 1], 0.0)), math.sqrt(max(ev[0], 0.0))


@njit(cache=True, nogil=True)
def _solve_law(
    jac: np.ndarray,
    xd: np.ndarray,
    lam_use: float,
    q: np.ndarray,
    lim: np.ndarray,
    use_limits: bool,
    out_qd: np.ndarray,
    free: np.ndarray,
    work: np.ndarray,
    rhs: np.ndarray,
    sol: np.ndarray,
) -> bool:  # pragma: no cover - compiled
    """Damped least squares ``J q̇ = ẋ`` with joint and speed limits; returns ``limited``."""
    n = q.shape[0]
    lower = lim[0]
    upper = lim[1]
    vmax = lim[2]
    limited = False
    for i in range(n):
        free[i] = True
    for _pass in range(2):
        ok = dls_into(jac, xd, lam_use, free, out_qd, work, rhs, sol)
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
    return limited


@njit(cache=True, nogil=True)
def _rate3(
    rot: np.ndarray,
    trans: np.ndarray,
    axis: np.ndarray,
    kind: np.ndarray,
    col: np.ndarray,
    q: np.ndarray,
    v: np.ndarray,
    ref_p: np.ndarray,
    gain: float,
    eps: float,
    lam2max: float,
    lim: np.ndarray,
    use_limits: bool,
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
    """The 3-row control law q̇(q, t) into ``out_qd``; returns (σ_min, σ_max, λ², limited)."""
    n = q.shape[0]
    fk_jac_into(rot, trans, axis, kind, col, q, p, jac, scratch, n >= 0)
    for a in range(3):
        xd[a] = v[a]
    smin, smax = sigma_bounds(jac)
    for a in range(3):
        xd[a] += gain * (ref_p[a] - p[a])
    lam2 = 0.0
    if smin < eps:
        ratio = smin / eps
        lam2 = lam2max * (1.0 - ratio * ratio)
    lam_use = max(lam2, 1e-14 * (smax * smax + 1e-300))
    limited = _solve_law(jac, xd, lam_use, q, lim, use_limits, out_qd, free, work, rhs, sol)
    return smin, smax, lam2, limited


@njit(cache=True, nogil=True)
def _rate6(
    rot: np.ndarray,
    trans: np.ndarray,
    axis: np.ndarray,
    kind: np.ndarray,
    col: np.ndarray,
    tip_rot: np.ndarray,
    q: np.ndarray,
    v: np.ndarray,
    ref_p: np.ndarray,
    ref_r: np.ndarray,
    tip_frame: bool,
    gain: float,
    eps: float,
    lam2max: float,
    hold: float,
    lim: np.ndarray,
    use_limits: bool,
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
    """The twist control law q̇(q, t) into ``out_qd``; returns (σ_min, σ_max, λ², limited)."""
    n = q.shape[0]
    fk_jac_into(rot, trans, axis, kind, col, q, p, jac, scratch, n >= 0)
    r = np.empty((3, 3))
    w3 = np.empty((3, 3))
    ew = np.empty(3)
    ev = np.empty(max(n, 6))
    tip_rotation_into(rot, axis, kind, col, tip_rot, q, r)
    if tip_frame:
        for a in range(3):
            xd[a] = r[a, 0] * v[0] + r[a, 1] * v[1] + r[a, 2] * v[2]
            xd[3 + a] = r[a, 0] * v[3] + r[a, 1] * v[4] + r[a, 2] * v[5]
    else:
        for a in range(6):
            xd[a] = v[a]
    if gain != 0.0:
        for a in range(3):
            for b in range(3):
                w3[a, b] = ref_r[a, 0] * r[b, 0] + ref_r[a, 1] * r[b, 1] + ref_r[a, 2] * r[b, 2]
        log3_into(w3, ew)
        for a in range(3):
            xd[3 + a] += gain * ew[a]
    if hold < 0.0:
        smin, smax = _sigma6(jac, work, ev)
    else:  # an RK4 stage of a twist: the damping of the step's start is held
        smin, smax = math.nan, math.nan
    for a in range(3):
        xd[a] += gain * (ref_p[a] - p[a])
    lam2 = 0.0
    if hold >= 0.0:
        lam2 = hold
        lam_use = hold
    else:
        if smin < eps:
            ratio = smin / eps
            lam2 = lam2max * (1.0 - ratio * ratio)
        lam_use = max(lam2, 1e-14 * (smax * smax + 1e-300))
    limited = _solve_law(jac, xd, lam_use, q, lim, use_limits, out_qd, free, work, rhs, sol)
    return smin, smax, lam2, limited


@njit(cache=True, nogil=True)
def _record(
    k: int,
    q: np.ndarray,
    qd: np.ndarray,
    p: np.ndarray,
    r: np.ndarray,
    jac: np.ndarray,
    out_q: np.ndarray,
    out_qd: np.ndarray,
    out_pose: np.ndarray,
    out_twist: np.ndarray,
) -> None:  # pragma: no cover - compiled
    """Sample ``k``: q, q̇, the tip pose and the rows of ``J q̇`` that ``jac`` has."""
    n = q.shape[0]
    for i in range(n):
        out_q[k, i] = q[i]
        out_qd[k, i] = qd[i]
    for a in range(3):
        for b in range(3):
            out_pose[k, a, b] = r[a, b]
        out_pose[k, a, 3] = p[a]
        out_pose[k, 3, a] = 0.0
    out_pose[k, 3, 3] = 1.0
    for a in range(jac.shape[0]):
        s = 0.0
        for i in range(n):
            s += jac[a, i] * qd[i]
        out_twist[k, a] = s


@njit(cache=True, nogil=True)
def _advance(
    q: np.ndarray,
    k1: np.ndarray,
    k2: np.ndarray,
    k3: np.ndarray,
    k4: np.ndarray,
    dt: float,
    rk4: bool,
    lower: np.ndarray,
    upper: np.ndarray,
    use_limits: bool,
) -> None:  # pragma: no cover - compiled
    """One Euler or RK4 update of ``q`` in place, clamped to the limits."""
    n = q.shape[0]
    if rk4:
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


@njit(
    cache=True,
    nogil=True,
    # interpreted: about 7 µs per RK4 stage and squared joint count; compiles in about 5 s
    work=lambda *a: a[16].shape[0] * (4 if a[10] else 1) * a[6].shape[0] ** 2,
    per_unit_s=7e-6,
    compile_s=5.0,
)
def _rr3(
    rot: np.ndarray,
    trans: np.ndarray,
    axis: np.ndarray,
    kind: np.ndarray,
    col: np.ndarray,
    tip_rot: np.ndarray,
    q0: np.ndarray,
    vel: np.ndarray,
    ref_p: np.ndarray,
    dt: float,
    rk4: bool,
    gain: float,
    eps: float,
    lam2max: float,
    lims: np.ndarray,
    use_limits: bool,
    out_q: np.ndarray,
    out_qd: np.ndarray,
    out_pose: np.ndarray,
    out_twist: np.ndarray,
    out_s: np.ndarray,
    out_lam: np.ndarray,
    out_lim: np.ndarray,
) -> None:  # pragma: no cover - compiled
    """The 3-row task (the tip's linear velocity): no twist code is compiled."""
    n = q0.shape[0]
    steps = out_q.shape[0] - 1
    scratch = np.empty((6, max(rot.shape[0], 1)))
    p = np.empty(3)
    r = np.empty((3, 3))
    jac3 = np.empty((3, n))
    free = np.empty(n, dtype=np.bool_)
    mm = max(n, 6)
    work = np.empty((mm, mm))
    rhs = np.empty(mm)
    sol = np.empty(mm)
    xd = np.empty(3)
    q = q0.copy()
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    qs = np.empty(n)
    sc = (free, work, rhs, sol, xd)
    for k in range(steps + 1):
        h = 2 * k
        smin, smax, lam2, lim = _rate3(
            rot,
            trans,
            axis,
            kind,
            col,
            q,
            vel[h],
            ref_p[h],
            gain,
            eps,
            lam2max,
            lims,
            use_limits,
            k1,
            p,
            jac3,
            scratch,
            *sc,
        )
        tip_rotation_into(rot, axis, kind, col, tip_rot, q, r)
        _record(k, q, k1, p, r, jac3, out_q, out_qd, out_pose, out_twist)
        # ω = Σ axis_j q̇_j over the revolute joints (the axes fk_jac_into left in scratch)
        for a in range(3):
            s = 0.0
            for j in range(kind.shape[0]):
                if kind[j] == 0:
                    s += scratch[3 + a, j] * k1[col[j]]
            out_twist[k, 3 + a] = s
        out_s[k, 0] = smin
        out_s[k, 1] = smax
        out_lam[k] = lam2
        out_lim[k] = lim
        if k == steps:
            break
        if rk4:
            for i in range(n):
                qs[i] = q[i] + 0.5 * dt * k1[i]
            _rate3(
                rot,
                trans,
                axis,
                kind,
                col,
                qs,
                vel[h + 1],
                ref_p[h + 1],
                gain,
                eps,
                lam2max,
                lims,
                use_limits,
                k2,
                p,
                jac3,
                scratch,
                *sc,
            )
            for i in range(n):
                qs[i] = q[i] + 0.5 * dt * k2[i]
            _rate3(
                rot,
                trans,
                axis,
                kind,
                col,
                qs,
                vel[h + 1],
                ref_p[h + 1],
                gain,
                eps,
                lam2max,
                lims,
                use_limits,
                k3,
                p,
                jac3,
                scratch,
                *sc,
            )
            for i in range(n):
                qs[i] = q[i] + dt * k3[i]
            _rate3(
                rot,
                trans,
                axis,
                kind,
                col,
                qs,
                vel[h + 2],
                ref_p[h + 2],
                gain,
                eps,
                lam2max,
                lims,
                use_limits,
                k4,
                p,
                jac3,
                scratch,
                *sc,
            )
        _advance(q, k1, k2, k3, k4, dt, rk4, lims[0], lims[1], use_limits)


@njit(
    cache=True,
    nogil=True,
    work=lambda *a: a[18].shape[0] * (4 if a[11] else 1) * a[6].shape[0] ** 2,
    per_unit_s=1e-5,
    compile_s=5.0,
)
def _rr6(
    rot: np.ndarray,
    trans: np.ndarray,
    axis: np.ndarray,
    kind: np.ndarray,
    col: np.ndarray,
    tip_rot: np.ndarray,
    q0: np.ndarray,
    vel: np.ndarray,
    ref_p: np.ndarray,
    ref_r: np.ndarray,
    dt: float,
    rk4: bool,
    tip_frame: bool,
    gain: float,
    eps: float,
    lam2max: float,
    lims: np.ndarray,
    use_limits: bool,
    out_q: np.ndarray,
    out_qd: np.ndarray,
    out_pose: np.ndarray,
    out_twist: np.ndarray,
    out_s: np.ndarray,
    out_lam: np.ndarray,
    out_lim: np.ndarray,
) -> None:  # pragma: no cover - compiled
    """The 6-D twist task; the damping of each step's start is held over its RK4 stages."""
    n = q0.shape[0]
    steps = out_q.shape[0] - 1
    scratch = np.empty((6, max(rot.shape[0], 1)))
    p = np.empty(3)
    r = np.empty((3, 3))
    jac = np.empty((6, n))
    free = np.empty(n, dtype=np.bool_)
    mm = max(n, 6)
    work = np.empty((mm, mm))
    rhs = np.empty(mm)
    sol = np.empty(mm)
    xd = np.empty(6)
    q = q0.copy()
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    qs = np.empty(n)
    sc = (free, work, rhs, sol, xd)
    for k in range(steps + 1):
        h = 2 * k
        smin, smax, lam2, lim = _rate6(
            rot,
            trans,
            axis,
            kind,
            col,
            tip_rot,
            q,
            vel[h],
            ref_p[h],
            ref_r[h],
            tip_frame,
            gain,
            eps,
            lam2max,
            -1.0,
            lims,
            use_limits,
            k1,
            p,
            jac,
            scratch,
            *sc,
        )
        hold = max(lam2, 1e-14 * (smax * smax + 1e-300))
        tip_rotation_into(rot, axis, kind, col, tip_rot, q, r)
        _record(k, q, k1, p, r, jac, out_q, out_qd, out_pose, out_twist)
        out_s[k, 0] = smin
        out_s[k, 1] = smax
        out_lam[k] = lam2
        out_lim[k] = lim
        if k == steps:
            break
        if rk4:
            for i in range(n):
                qs[i] = q[i] + 0.5 * dt * k1[i]
            _rate6(
                rot,
                trans,
                axis,
                kind,
                col,
                tip_rot,
                qs,
                vel[h + 1],
                ref_p[h + 1],
                ref_r[h + 1],
                tip_frame,
                gain,
                eps,
                lam2max,
                hold,
                lims,
                use_limits,
                k2,
                p,
                jac,
                scratch,
                *sc,
            )
            for i in range(n):
                qs[i] = q[i] + 0.5 * dt * k2[i]
            _rate6(
                rot,
                trans,
                axis,
                kind,
                col,
                tip_rot,
                qs,
                vel[h + 1],
                ref_p[h + 1],
                ref_r[h + 1],
                tip_frame,
                gain,
                eps,
                lam2max,
                hold,
                lims,
                use_limits,
                k3,
                p,
                jac,
                scratch,
                *sc,
            )
            for i in range(n):
                qs[i] = q[i] + dt * k3[i]
            _rate6(
                rot,
                trans,
                axis,
                kind,
                col,
                tip_rot,
                qs,
                vel[h + 2],
                ref_p[h + 2],
                ref_r[h + 2],
                tip_frame,
                gain,
                eps,
                lam2max,
                hold,
                lims,
                use_limits,
                k4,
                p,
                jac,
                scratch,
                *sc,
            )
        _advance(q, k1, k2, k3, k4, dt, rk4, lims[0], lims[1], use_limits)


#: Predicted seconds of :func:`._cold.rr_cold` per unit: one stage of the unrolled 3×3
#: position task ("square3"), one stage × (4 + n) otherwise; refined by every run here.
_COLD = {"square3": 1.6e-5, "general": 5e-6}


def rr_kernel(
    packed: tuple[np.ndarray, ...],
    tip_rot: np.ndarray,
    q0: np.ndarray,
    vel: np.ndarray,
    ref_p: np.ndarray,
    ref_r: np.ndarray,
    dt: float,
    rk4: bool,
    rows6: bool,
    tip_frame: bool,
    gain: float,
    eps: float,
    lam2max: float,
    lower: np.ndarray,
    upper: np.ndarray,
    use_limits: bool,
    vmax: np.ndarray,
    out_q: np.ndarray,
    out_qd: np.ndarray,
    out_pose: np.ndarray,
    out_twist: np.ndarray,
    out_s: np.ndarray,
    out_lam: np.ndarray,
    out_lim: np.ndarray,
    model: Any = None,
) -> None:
    """Integrate the control law from ``q0`` (Euler or RK4) into the ``out_*`` arrays.

    ``vel`` (2K+1, 3 or 6), ``ref_p`` (2K+1, 3) and ``ref_r`` (2K+1, 3, 3) — (1, 3, 3), unused,
    for a 3-row task — are sampled at half steps (index 2k = t_k, 2k+1 = t_k + dt/2).
    Outputs per sample: q, q̇, tip pose (4, 4), tip velocity ``J q̇`` (6, LWA),
    (σ_min, σ_max), λ², limited. Chosen here, in Python: a 3-row task runs (and compiles) only
    the position kernel, a twist only the 6-D one. ``packed``: the chain's
    ``(rot, trans, axis, kind, col)`` arrays. With ``model`` (the loaded model of that chain)
    the loop runs as :func:`._cold.rr_cold` (Pinocchio + Python) while the tier rule prefers
    it to compiling the kernel (``Kernel.prefer_interpreted``, charged with its seconds).
    """
    outs = (out_q, out_qd, out_pose, out_twist, out_s, out_lam, out_lim)
    kernel = _rr6 if rows6 else _rr3
    if model is not None:  # the cold path while the kernel is not compiled (see ._cold)
        path = "square3" if not rows6 and q0.shape[0] == 3 else "general"
        per_stage = 1 if path == "square3" else 4 + q0.shape[0]
        units = (out_q.shape[0] - 1) * (4 if rk4 else 1) * per_stage
        if kernel.prefer_interpreted(_COLD[path] * units):
            t0 = time.perf_counter()
            rr_cold(
                model, q0, vel, ref_p, ref_r, dt, rk4, rows6, tip_frame, gain, eps, lam2max,
                lower, upper, use_limits, vmax, *outs,
            )  # fmt: skip
            spent = time.perf_counter() - t0
            kernel.charge(spent)
            _COLD[path] = 0.5 * (_COLD[path] + spent / max(units, 1))
            return
    rot, trans, axis, kind, col = packed
    lims = np.empty((3, q0.shape[0]))  # lower, upper, speed limits: one argument of the law
    lims[0], lims[1], lims[2] = lower, upper, vmax
    if rows6:
        _rr6(
            rot,
            trans,
            axis,
            kind,
            col,
            tip_rot,
            q0,
            vel,
            ref_p,
            ref_r,
            dt,
            rk4,
            tip_frame,
            gain,
            eps,
            lam2max,
            lims,
            use_limits,
            *outs,
        )
    else:
        _rr3(
            rot,
            trans,
            axis,
            kind,
            col,
            tip_rot,
            q0,
            vel,
            ref_p,
            dt,
            rk4,
            gain,
            eps,
            lam2max,
            lims,
            use_limits,
            *outs,
        )
