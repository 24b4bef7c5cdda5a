"""The resolved-rate loop for a cold start: Pinocchio's C++ for the kinematics, Python for the law.

:mod:`._kernel` compiles the loop with numba, which costs seconds the first time a process
meets it without machine code in numba's disk cache (about 5 s for the 3-row loop, 6 s for
the twist). The kernel's own source run by Python (its interpreted tier) costs about 60 µs
per RK4 stage of a 3-joint leg and 360 µs for a 6-joint arm, most of it scalar indexing of
numpy arrays in the forward kinematics. This module runs the same control law with the tip
pose and Jacobian from Pinocchio (``KinematicModel.fk_jacobian``, one C++ call) and the
small linear algebra on Python floats: about 15 µs (leg) and 30 µs (UR5) per stage.
:func:`hexapod_kin.motion.rate.resolved_rate` chooses it through the tier rule
(:meth:`hexapod_kin._tier.Kernel.prefer_interpreted`): while the kernel is not compiled and
this path's seconds stay within the kernel's compile time.

It is a second implementation of :mod:`._kernel`'s law (``_rate3``/``_rate6``,
``_solve_law``, ``dls_into``): the same formulas in the same order — damping from σ_min,
the free-joint passes at the limits, the speed scaling, the twist's damping held over the
step's RK4 stages — so both give the same trajectory to rounding (``tests/test_motion_cold.py``
compares them on legs, a prismatic joint, limits, singular starts and 6-D twists). σ of a
3-row task is the kernel's own closed form (``sigma_bounds`` run by Python); the log of the
orientation error is the kernel's ``log3_into`` run by Python.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .. import _tier
from .._numerics import eig3_sym, sigma_bounds
from ..ik.step import log3_into

__all__ = ["rr_cold"]


def _chol_solve(a: list[list[float]], b: list[float]) -> list[float] | None:
    """Cholesky solve of a small SPD system on Python floats (``a`` overwritten); None if not SPD.

    The operations of ``_numerics.solve_spd`` in the same order.
    """
    n = len(b)
    for j in range(n):
        row_j = a[j]
        s = row_j[j]
        for k in range(j):
            s -= row_j[k] * row_j[k]
        if not s > 0.0:
            return None
        d = math.sqrt(s)
        row_j[j] = d
        for i in range(j + 1, n):
            row_i = a[i]
            t = row_i[j]
            for k in range(j):
                t -= row_i[k] * row_j[k]
            row_i[j] = t / d
    out = [0.0] * n
    for i in range(n):
        row_i = a[i]
        t = b[i]
        for k in range(i):
            t -= row_i[k] * out[k]
        out[i] = t / row_i[i]
    for i in range(n - 1, -1, -1):
        t = out[i]
        for k in range(i + 1, n):
            t -= a[k][i] * out[k]
        out[i] = t / a[i][i]
    return out


def _dot(x: list[float], y: list[float]) -> float:
    """Σ x_i y_i from i = 0 up, as the kernels sum (never ``sum``: Python ≥ 3.12 compensates)."""
    s = 0.0
    for a, b in zip(x, y):
        s += a * b
    return s


def _dls(jac: np.ndarray, e: list[float], lam2: float, free: list[bool]) -> list[float] | None:
    """``_numerics.dls_into`` on Python floats: Δq, or None when the system is not SPD.

    The same sums in the same order as the kernel (a frozen joint's column is zeroed, which
    adds exact zeros where the kernel skips it), so both round alike.
    """
    m, n = jac.shape
    if not all(free):
        jac = jac * np.array(free, dtype=float)
    if n <= m:
        cols = jac.T.tolist()
        rhs = []
        work = [[0.0] * n for _ in range(n)]
        for i in range(n):
            ci = cols[i]
            g = 0.0
            for x, y in zip(ci, e):
                g += x * y
            rhs.append(g)
            wi = work[i]
            for k in range(i, n):
                s = 0.0
                for x, y in zip(ci, cols[k]):
                    s += x * y
                wi[k] = work[k][i] = s
            wi[i] += lam2
        sol = _chol_solve(work, rhs)
        if sol is None:
            return None
        return [sol[i] if free[i] else 0.0 for i in range(n)]
    rows = jac.tolist()
    work = [[0.0] * m for _ in range(m)]
    for a in range(m):
        ra = rows[a]
        for b in range(a, m):
            work[a][b] = work[b][a] = _dot(ra, rows[b])
        work[a][a] += lam2
    sol = _chol_solve(work, list(e))
    if sol is None:
        return None
    cols = jac.T.tolist()
    return [_dot(cols[k], sol) if free[k] else 0.0 for k in range(n)]


def _solve_law(
    jac: np.ndarray,
    xd: list[float],
    lam_use: float,
    q: list[float],
    lower: list[float],
    upper: list[float],
    vmax: list[float],
    use_limits: bool,
) -> tuple[list[float], bool]:
    """``_kernel._solve_law``: damped least squares with joint and speed limits → (q̇, limited)."""
    n = len(q)
    free = [True] * n
    limited = False
    qd = [0.0] * n
    for _pass in range(2):
        sol = _dls(jac, xd, lam_use, free)
        qd = [0.0] * n if sol is None else sol
        again = False
        if use_limits:
            for i in range(n):
                if free[i] and (
                    (q[i] <= lower[i] and qd[i] < 0.0) or (q[i] >= upper[i] and qd[i] > 0.0)
                ):
                    free[i] = False
                    again = True
        if not again:
            break
        limited = True
    qd, slowed = _speed(qd, vmax)
    return qd, limited or slowed


def _at_limit(q: list[float], qd: list[float], lower: list[float], upper: list[float]) -> bool:
    """True when a joint sits at a limit and ``qd`` pushes it further (the law then freezes it)."""
    for i in range(len(q)):
        if (q[i] <= lower[i] and qd[i] < 0.0) or (q[i] >= upper[i] and qd[i] > 0.0):
            return True
    return False


def _speed(qd: list[float], vmax: list[float]) -> tuple[list[float], bool]:
    """The law's speed limit: ``qd`` scaled down uniformly so no joint passes ``vmax``.

    Returns the (possibly scaled) rates and whether they were scaled.
    """
    scale = 1.0
    for i in range(len(qd)):
        a = abs(qd[i])
        if a * scale > vmax[i]:
            scale = vmax[i] / a
    if scale < 1.0:
        return [x * scale for x in qd], True
    return qd, False


def _damping(smin: float, smax: float, eps: float, lam2max: float) -> tuple[float, float]:
    """(λ², λ² used): the kernels' damping rule."""
    lam2 = 0.0
    if smin < eps:
        ratio = smin / eps
        lam2 = lam2max * (1.0 - ratio * ratio)
    return lam2, max(lam2, 1e-14 * (smax * smax + 1e-300))


def _sigma3x3(j: list[list[float]], eig3: Any) -> tuple[float, float]:
    """``_numerics.sigma_bounds`` of a 3×3 Jacobian on Python floats (the same operations)."""
    (a, b, c), (d, e, f), (g, h, i) = j
    m00 = a * a + b * b + c * c
    m01 = a * d + b * e + c * f
    m02 = a * g + b * h + c * i
    m11 = d * d + e * e + f * f
    m12 = d * g + e * h + f * i
    m22 = g * g + h * h + i * i
    e1, e2, _ = eig3(m00, m11, m22, m01, m02, m12)
    smax = math.sqrt(max(e1, 0.0))
    s12 = smax * math.sqrt(max(e2, 0.0))
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    return (abs(det) / s12 if s12 > 0.0 else 0.0), smax


def _dls3x3(j: list[list[float]], x: list[float], lam2: float) -> list[float] | None:
    """``_numerics.dls_into`` (every joint free) for a 3×3 Jacobian, unrolled, same order."""
    (a, b, c), (d, e, f), (g, h, i) = j
    x0, x1, x2 = x
    r0 = a * x0 + d * x1 + g * x2
    r1 = b * x0 + e * x1 + h * x2
    r2 = c * x0 + f * x1 + i * x2
    w00 = a * a + d * d + g * g + lam2
    w10 = b * a + e * d + h * g
    w20 = c * a + f * d + i * g
    w11 = b * b + e * e + h * h + lam2
    w21 = c * b + f * e + i * h
    w22 = c * c + f * f + i * i + lam2
    if not w00 > 0.0:
        return None
    l00 = math.sqrt(w00)
    l10 = w10 / l00
    l20 = w20 / l00
    s = w11 - l10 * l10
    if not s > 0.0:
        return None
    l11 = math.sqrt(s)
    l21 = (w21 - l20 * l10) / l11
    s = w22 - l20 * l20 - l21 * l21
    if not s > 0.0:
        return None
    l22 = math.sqrt(s)
    y0 = r0 / l00
    y1 = (r1 - l10 * y0) / l11
    y2 = (r2 - l20 * y0 - l21 * y1) / l22
    z2 = y2 / l22
    z1 = (y1 - l21 * z2) / l11
    return [(y0 - l10 * z1 - l20 * z2) / l00, z1, z2]


def rr_cold(
    model: Any,
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
) -> None:
    """``_kernel.rr_kernel``'s loop with ``model``'s Pinocchio kinematics (same arguments/outputs).

    ``model`` is the loaded model whose chain ``rr_kernel`` would get packed.
    """
    fkj = model.fk_jacobian
    sig3 = _tier.interpreted(sigma_bounds)
    eig3 = _tier.interpreted(eig3_sym)
    square3 = not rows6 and q0.shape[0] == 3
    log3 = _tier.interpreted(log3_into)
    lo, hi, vm = lower.tolist(), upper.tolist(), vmax.tolist()
    w3 = np.empty((3, 3))
    ew = np.empty(3)
    vel_l = vel.tolist()
    refp_l = ref_p.tolist()
    steps = out_q.shape[0] - 1

    def rate(q: np.ndarray, h: int, hold: float) -> tuple[Any, ...]:
        """q̇ at (q, t_h/2) → (q̇, pose, J, σ_min, σ_max, λ², limited); ``hold`` ≥ 0: twist λ²."""
        pose, jac = fkj(q)
        v = vel_l[h]
        if rows6:
            r = pose[:3, :3]
            xd = (r @ v[:3]).tolist() + (r @ v[3:]).tolist() if tip_frame else list(v)
            if gain != 0.0:
                np.matmul(ref_r[h], r.T, out=w3)
                log3(w3, ew)
                xd[3] += gain * float(ew[0])
                xd[4] += gain * float(ew[1])
                xd[5] += gain * float(ew[2])
            rows = jac
            if hold < 0.0:
                sv = np.linalg.svd(jac, compute_uv=False)
                smin, smax = float(sv[-1]), float(sv[0])
            else:  # an RK4 stage of a twist: the damping of the step's start is held
                smin = smax = math.nan
        elif square3:
            rows = jac[:3]
            j3 = rows.tolist()
            smin, smax = _sigma3x3(j3, eig3)
            xd = list(v)
        else:
            rows = jac[:3]
            # an object array: the same source, indexing gives Python floats (faster math)
            smin, smax = sig3(rows.astype(object))
            xd = list(v)
        rp = refp_l[h]
        pl = pose[:3, 3].tolist()
        for a in range(3):
            xd[a] += gain * (rp[a] - pl[a])
        if hold >= 0.0:
            lam2 = lam_use = hold
        else:
            lam2, lam_use = _damping(smin, smax, eps, lam2max)
        ql = q.tolist()
        if square3:  # the kernel's first pass; its limit and speed rules when they apply
            qd = _dls3x3(j3, xd, lam_use) or [0.0, 0.0, 0.0]
            if not (use_limits and _at_limit(ql, qd, lo, hi)):
                qd, slowed = _speed(qd, vm)
                return np.array(qd), pose, jac, smin, smax, lam2, slowed
        qd, limited = _solve_law(rows, xd, lam_use, ql, lo, hi, vm, use_limits)
        return np.array(qd), pose, jac, smin, smax, lam2, limited

    q = np.array(q0, dtype=float)
    for k in range(steps + 1):
        h = 2 * k
        k1, pose, jac, smin, smax, lam2, lim = rate(q, h, -1.0)
        out_q[k] = q
        out_qd[k] = k1
        out_pose[k] = pose
        out_twist[k] = jac @ k1
        out_s[k, 0] = smin
        out_s[k, 1] = smax
        out_lam[k] = lam2
        out_lim[k] = lim
        if k == steps:
            break
        if rk4:
            hold = max(lam2, 1e-14 * (smax * smax + 1e-300)) if rows6 else -1.0
            k2 = rate(q + 0.5 * dt * k1, h + 1, hold)[0]
            k3 = rate(q + 0.5 * dt * k2, h + 1, hold)[0]
            k4 = rate(q + dt * k3, h + 2, hold)[0]
            q = q + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        else:
            q = q + dt * k1
        if use_limits:
            np.clip(q, lower, upper, out=q)
