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

import numpy as np

from .._kernels import fk_jac_into
from .._numerics import dls_into, jacobi_eig, njit, sigma_bounds
from ..ik.step import log3_into, tip_rotation_into

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
def _rate(
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
    rows6: bool,
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
    """The control law q̇(q, t) into ``out_qd``; returns (σ_min, σ_max, λ², limited)."""
    n = q.shape[0]
    lower = lim[0]
    upper = lim[1]
    vmax = lim[2]
    fk_jac_into(rot, trans, axis, kind, col, q, p, jac, scratch, n >= 0)
    if rows6:
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
    else:
        for a in range(3):
            xd[a] = v[a]
        smin, smax = sigma_bounds(jac)
    for a in range(3):
        xd[a] += gain * (ref_p[a] - p[a])
    lam2 = 0.0
    if hold >= 0.0 and rows6:
        lam2 = hold
        lam_use = hold
    else:
        if smin < eps:
            ratio = smin / eps
            lam2 = lam2max * (1.0 - ratio * ratio)
        lam_use = max(lam2, 1e-14 * (smax * smax + 1e-300))
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
    return smin, smax, lam2, limited


@njit(cache=True, nogil=True)
def rr_kernel(
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
) -> None:  # pragma: no cover - compiled
    """Integrate the control law from ``q0`` (Euler or RK4).

    ``vel`` (2K+1, 3 or 6), ``ref_p`` (2K+1, 3) and ``ref_r`` (2K+1, 3, 3) — (1, 3, 3), unused,
    for a 3-row task — are sampled at half steps (index 2k = t_k, 2k+1 = t_k + dt/2).
    Outputs per sample: q, q̇, tip pose (4, 4), tip velocity ``J q̇`` (6, LWA),
    (σ_min, σ_max), λ², limited.
    """
    n = q0.shape[0]
    steps = out_q.shape[0] - 1
    scratch = np.empty((6, max(rot.shape[0], 1)))
    p = np.empty(3)
    r = np.empty((3, 3))
    jac = np.empty((6, n))
    jac3 = np.empty((3, n))  # a 3-row task needs no angular rows
    jst = jac if rows6 else jac3
    free = np.empty(n, dtype=np.bool_)
    mm = max(n, 6)
    work = np.empty((mm, mm))
    rhs = np.empty(mm)
    sol = np.empty(mm)
    xd = np.empty(6 if rows6 else 3)  # one row per task row; jac (jst) has as many
    lims = np.empty((3, n))  # lower, upper, speed limits: one argument of the control law
    for i in range(n):
        lims[0, i] = lower[i]
        lims[1, i] = upper[i]
        lims[2, i] = vmax[i]
    q = q0.copy()
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    qs = np.empty(n)
    for k in range(steps + 1):
        h = 2 * k
        hr0 = h if rows6 else 0  # a 3-row task passes one unused rotation
        hr1 = h + 1 if rows6 else 0
        hr2 = h + 2 if rows6 else 0
        smin, smax, lam2, lim = _rate(
            rot,
            trans,
            axis,
            kind,
            col,
            tip_rot,
            q,
            vel[h],
            ref_p[h],
            ref_r[hr0],
            rows6,
            tip_frame,
            gain,
            eps,
            lam2max,
            -1.0,
            lims,
            use_limits,
            k1,
            p,
            jst,
            scratch,
            free,
            work,
            rhs,
            sol,
            xd,
        )
        hold = max(lam2, 1e-14 * (smax * smax + 1e-300)) if rows6 else -1.0
        tip_rotation_into(rot, axis, kind, col, tip_rot, q, r)
        for i in range(n):
            out_q[k, i] = q[i]
            out_qd[k, i] = k1[i]
        for a in range(3):
            for b in range(3):
                out_pose[k, a, b] = r[a, b]
            out_pose[k, a, 3] = p[a]
            out_pose[k, 3, a] = 0.0
        out_pose[k, 3, 3] = 1.0
        for a in range(3):
            s = 0.0
            for i in range(n):
                s += jst[a, i] * k1[i]
            out_twist[k, a] = s
        if rows6:
            for a in range(3, 6):
                s = 0.0
                for i in range(n):
                    s += jac[a, i] * k1[i]
                out_twist[k, a] = s
        else:  # ω = Σ axis_j q̇_j over the revolute joints (the axes fk_jac_into left in scratch)
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
            _rate(
                rot,
                trans,
                axis,
                kind,
                col,
                tip_rot,
                qs,
                vel[h + 1],
                ref_p[h + 1],
                ref_r[hr1],
                rows6,
                tip_frame,
                gain,
                eps,
                lam2max,
                hold,
                lims,
                use_limits,
                k2,
                p,
                jst,
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
                tip_rot,
                qs,
                vel[h + 1],
                ref_p[h + 1],
                ref_r[hr1],
                rows6,
                tip_frame,
                gain,
                eps,
                lam2max,
                hold,
                lims,
                use_limits,
                k3,
                p,
                jst,
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
                tip_rot,
                qs,
                vel[h + 2],
                ref_p[h + 2],
                ref_r[hr2],
                rows6,
                tip_frame,
                gain,
                eps,
                lam2max,
                hold,
                lims,
                use_limits,
                k4,
                p,
                jst,
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
