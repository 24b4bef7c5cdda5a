"""The compiled numerical IK: the task error, the damped least-squares step, the loop.

:func:`task_into` builds the weighted task rows (the problem), :func:`step_into` one step from
them (a pure function), :func:`lm_loop` the small loop around them.

Task modes (``ipar[0]``):

* ``0`` position: rows ``[x, y, z]`` of ``e = p* − p`` (base frame, [m]);
* ``1`` position + yaw: plus ``wrap(ψ* − ψ)``, ψ = ``atan2(x_y, x_x)`` the angle of the tool's
  x axis in the base xy-plane, with its exact row ``∂ψ/∂q = [−x_z x_x/h², −x_z x_y/h², 1]·J_ω``;
* ``2`` pose: plus the orientation error on SO(3), ``e_ω = log(R* Rᵀ)`` (base axes, [rad]) —
  never Euler angles — with the rotation rows of the LOCAL_WORLD_ALIGNED Jacobian.

Each row is multiplied by its weight (0 drops the row); buffers are per call (``nogil``).
"""

from __future__ import annotations

import math

import numpy as np

from .._kernels import dls_into, fk_jac_into, njit, wrap_angle

__all__ = ["lm_loop", "log3", "nearest", "sigma_min3", "step_into", "task_into"]  # fmt: skip

# indices into the float parameters ``par`` and the int parameters ``ipar`` of the loop
P_TOL, P_ROT_TOL, P_WBAR, P_MU0, P_POST_GAIN, P_YAW, P_POST_FLOOR = range(7)
I_MODE, I_MAX_ITER, I_LIMITS, I_POSTURE, I_NEAR = range(5)
# the rest of :func:`lm_loop`'s int plan: links m, joints n, then kind, col, continuous
I_LINKS, I_JOINTS, I_CHAIN = 5, 6, 7
# one row of :func:`lm_loop`'s output: these scalars, then q, p, R and the residual history
O_ATTEMPTS, O_STEPS, O_CODE, O_ERROR, O_ROT_ERROR, O_SIGMA_MIN, O_Q = range(7)


@njit(cache=True, nogil=True)
def log3(m: np.ndarray) -> tuple[float, float, float, float]:  # pragma: no cover - compiled
    """``log(M)`` (rotation vector, [rad]) of a rotation matrix and its angle: ``(x, y, z, θ)``.

    ``θ = atan2(‖v‖, (tr M − 1)/2)`` with ``v = vee(M − Mᵀ)/2 = sin θ·a`` (accurate at small
    angles); near π the axis comes from the symmetric part ``(M + Mᵀ)/2 = cos θ I + (1 − cos θ)
    a aᵀ`` with the sign of ``v``.
    """
    vx = 0.5 * (m[2, 1] - m[1, 2])
    vy = 0.5 * (m[0, 2] - m[2, 0])
    vz = 0.5 * (m[1, 0] - m[0, 1])
    s = math.sqrt(vx * vx + vy * vy + vz * vz)
    c = 0.5 * (m[0, 0] + m[1, 1] + m[2, 2] - 1.0)
    theta = math.atan2(s, c)
    if c > -0.5 or s > 0.5:
        f = theta / s if s > 1e-300 else 1.0
        return f * vx, f * vy, f * vz, theta
    d = 1.0 - c
    a0 = max((m[0, 0] - c) / d, 0.0)
    a1 = max((m[1, 1] - c) / d, 0.0)
    a2 = max((m[2, 2] - c) / d, 0.0)
    if a0 >= a1 and a0 >= a2:
        x = math.sqrt(a0)
        y = 0.5 * (m[0, 1] + m[1, 0]) / (d * x)
        z = 0.5 * (m[0, 2] + m[2, 0]) / (d * x)
    elif a1 >= a2:
        y = math.sqrt(a1)
        x = 0.5 * (m[0, 1] + m[1, 0]) / (d * y)
        z = 0.5 * (m[1, 2] + m[2, 1]) / (d * y)
    else:
        z = math.sqrt(a2)
        x = 0.5 * (m[0, 2] + m[2, 0]) / (d * z)
        y = 0.5 * (m[1, 2] + m[2, 1]) / (d * z)
    norm = math.sqrt(x * x + y * y + z * z)
    sign = -1.0 if x * vx + y * vy + z * vz < 0.0 else 1.0
    f = sign * theta / norm
    return f * x, f * y, f * z, theta


@njit(cache=True, nogil=True)
def task_into(
    mode: int, tgt: np.ndarray, w6: np.ndarray, yaw: float, p: np.ndarray, r: np.ndarray,
    jac: np.ndarray, work3: np.ndarray, e_out: np.ndarray, j_out: np.ndarray,
) -> tuple[int, float, float]:  # pragma: no cover - compiled  # fmt: skip
    """Weighted task rows at one configuration (the problem, built from FK and J).

    ``mode`` (module doc), target pose ``tgt`` (4, 4; rotation used in mode 2) and ``yaw``
    [rad] (mode 1), row weights ``w6`` (x y z wx wy wz; mode 1: ``w6[5]`` weights the yaw row),
    tip ``p`` (3,) [m] and ``r`` (3, 3), LOCAL_WORLD_ALIGNED ``jac`` (6, n), ``work3`` (3, 3)
    scratch. Writes the first ``m`` weighted errors into ``e_out`` (6,) and rows into ``j_out``
    (6, n); returns ``(m, ‖e_position‖², ‖e_rotation‖²)`` (unweighted, kept rows).
    """
    n = jac.shape[1]
    m = 0
    pos2 = 0.0
    rot2 = 0.0
    for k in range(3):
        if w6[k] != 0.0:
            e = tgt[k, 3] - p[k]
            pos2 += e * e
            e_out[m] = w6[k] * e
            for i in range(n):
                j_out[m, i] = w6[k] * jac[k, i]
            m += 1
    if mode == 1 and w6[5] != 0.0:
        x0, x1, x2 = r[0, 0], r[1, 0], r[2, 0]
        h2 = x0 * x0 + x1 * x1
        e = wrap_angle(yaw - math.atan2(x1, x0))
        rot2 += e * e
        a = -x2 * x0 / h2 if h2 > 1e-24 else 0.0
        b = -x2 * x1 / h2 if h2 > 1e-24 else 0.0
        e_out[m] = w6[5] * e
        for i in range(n):
            j_out[m, i] = w6[5] * (a * jac[3, i] + b * jac[4, i] + jac[5, i])
        m += 1
    elif mode == 2:
        # R* Rᵀ: the rotation still to apply, in base axes
        for a in range(3):
            for b in range(3):
                work3[a, b] = tgt[a, 0] * r[b, 0] + tgt[a, 1] * r[b, 1] + tgt[a, 2] * r[b, 2]
        e0, e1, e2, _ = log3(work3)
        # e(q + dq) = log(E exp(−J_ω dq)) ≈ e − Jr⁻¹(e) J_ω dq: the rows are Jr⁻¹(e) J_ω, exact
        # also when masked rows leave a large rotation error (Jr: right Jacobian of SO(3))
        th2 = e0 * e0 + e1 * e1 + e2 * e2
        th = math.sqrt(th2)
        if th < 1e-4:
            c = 1.0 / 12.0 + th2 / 720.0
        else:
            c = 1.0 / th2 - 0.5 / (th * math.tan(0.5 * th))
        # M = I + [e]/2 + c [e]²  ([e]² = e eᵀ − θ² I)
        ev = (e0, e1, e2)
        for k in range(3):
            if w6[3 + k] == 0.0:
                continue
            rot2 += ev[k] * ev[k]
            m0 = c * ev[k] * e0
            m1 = c * ev[k] * e1
            m2 = c * ev[k] * e2
            if k == 0:
                m0 += 1.0 - c * th2
                m1 -= 0.5 * e2
                m2 += 0.5 * e1
            elif k == 1:
                m0 += 0.5 * e2
                m1 += 1.0 - c * th2
                m2 -= 0.5 * e0
            else:
                m0 -= 0.5 * e1
                m1 += 0.5 * e0
                m2 += 1.0 - c * th2
            wk = w6[3 + k]
            e_out[m] = wk * ev[k]
            for i in range(n):
                j_out[m, i] = wk * (m0 * jac[3, i] + m1 * jac[4, i] + m2 * jac[5, i])
            m += 1
    return m, pos2, rot2


@njit(cache=True, nogil=True)
def step_into(
    jt: np.ndarray, et: np.ndarray, m: int, lam2: float, free: np.ndarray, z: np.ndarray,
    use_z: bool, dq: np.ndarray, e2: np.ndarray, work: np.ndarray, rhs: np.ndarray,
    sol: np.ndarray,
) -> bool:  # pragma: no cover - compiled  # fmt: skip
    """One damped step (pure: writes only ``dq`` and the scratch arrays).

    ``Δq = z + J⁺_λ (e − J z)``, ``J⁺_λ = Jᵀ(JJᵀ + λ²I)⁻¹`` on the free joints (``z``: a secondary
    motion, only with ``use_z``). False if the damped system is not positive definite.
    """
    n = jt.shape[1]
    for r in range(m):
        s = et[r]
        if use_z:
            for i in range(n):
                if free[i]:
                    s -= jt[r, i] * z[i]
        e2[r] = s
    ok = dls_into(jt, e2, m, lam2, free, dq, work, rhs, sol)
    if use_z:
        for i in range(n):
            if free[i]:
                dq[i] += z[i]
    return ok


@njit(cache=True, nogil=True)
def _limit_into(
    q: np.ndarray, lower: np.ndarray, upper: np.ndarray, cont: np.ndarray, use_limits: bool
) -> None:  # pragma: no cover - compiled
    """Wrap continuous joints into their range; clamp the others (when ``use_limits``)."""
    for i in range(q.shape[0]):
        if cont[i]:
            span = upper[i] - lower[i]
            if q[i] < lower[i] or q[i] > upper[i]:
                q[i] = lower[i] + ((q[i] - lower[i]) % span)
        elif use_limits:
            if q[i] < lower[i]:
                q[i] = lower[i]
            elif q[i] > upper[i]:
                q[i] = upper[i]


@njit(cache=True, nogil=True)
def sigma_min3(jac: np.ndarray) -> float:  # pragma: no cover - compiled
    """Smallest singular value of the position rows ``J[:3]`` (3, n); 0 for n < 3.

    One-sided Jacobi (Hestenes): the rows made orthogonal, their norms are the singular values,
    with high relative accuracy also at a singularity (Demmel & Veselić 1992).
    """
    n = jac.shape[1]
    if n < 3:
        return 0.0
    a = np.empty((3, n))
    for r in range(3):
        for k in range(n):
            a[r, k] = jac[r, k]
    for _sweep in range(40):
        rotated = False
        for i in range(2):
            for j in range(i + 1, 3):
                alpha = 0.0
                beta = 0.0
                gamma = 0.0
                for k in range(n):
                    alpha += a[i, k] * a[i, k]
                    beta += a[j, k] * a[j, k]
                    gamma += a[i, k] * a[j, k]
                if gamma == 0.0 or abs(gamma) <= 1e-15 * math.sqrt(alpha * beta):
                    continue
                rotated = True
                zeta = (beta - alpha) / (2.0 * gamma)
                t = (1.0 if zeta >= 0.0 else -1.0) / (abs(zeta) + math.sqrt(1.0 + zeta * zeta))
                c = 1.0 / math.sqrt(1.0 + t * t)
                s = c * t
                for k in range(n):
                    x, y = a[i, k], a[j, k]
                    a[i, k] = c * x - s * y
                    a[j, k] = s * x + c * y
        if not rotated:
            break
    out = np.inf
    for r in range(3):
        norm2 = 0.0
        for k in range(n):
            norm2 += a[r, k] * a[r, k]
        out = min(out, math.sqrt(norm2))
    return out


@njit(cache=True, nogil=True)
def nearest(
    mode: int, tgt: np.ndarray, w6: np.ndarray, poses: np.ndarray
) -> int:  # pragma: no cover - compiled
    """The index of the pose nearest to the target among ``poses`` (K, 12): p (3), R (9).

    Distance: ``Σ w²(p* − p)²`` over the position rows, plus in mode 2 (pose)
    ``Σ_k w²_{3+k} ‖R*_{:,k} − R_{:,k}‖²`` over the rotation rows; index 0 wins ties.
    """
    best = 0
    best_d = np.inf
    for k in range(poses.shape[0]):
        d = 0.0
        for a in range(3):
            e = w6[a] * (tgt[a, 3] - poses[k, a])
            d += e * e
        if mode == 2:
            for c in range(3):
                wc = w6[3 + c] * w6[3 + c]
                if wc != 0.0:
                    for a in range(3):
                        e = tgt[a, c] - poses[k, 3 + 3 * a + c]
                        d += wc * e * e
        if d < best_d:
            best_d = d
            best = k
    return best


@njit(cache=True, nogil=True)
def lm_loop(
    fplan: np.ndarray, iplan: np.ndarray, tgts: np.ndarray, w6: np.ndarray, pars: np.ndarray,
    starts: np.ndarray, out: np.ndarray,
) -> None:  # pragma: no cover - compiled  # fmt: skip
    """Levenberg–Marquardt loop for N targets, each from its starts in turn until one converges.

    The solver's module doc gives the step rules; the posture task runs while the error is
    above ``par[P_POST_FLOOR]``. Each target's numbers are its own (the same bits alone or in a
    batch).

    ``iplan`` = ``ipar`` (``I_*``), links m, joints n, the chain's ``kind`` (m), ``col`` (m),
    the continuous flags (n); ``fplan`` = ``rot`` (m, 3, 3), ``trans`` (m + 1, 3), ``axis``
    (m, 3), ``tip_rot`` (3, 3), ``lim`` (4, n: limits, step caps, posture), then ``K =
    ipar[I_NEAR]`` start configurations (K, n) and their tip poses (K, 12), flattened
    (``solver._plans``). ``tgts`` (N, 4, 4), ``pars`` (N, 7), ``starts`` (N, S, n). With ``K >
    0`` the first attempt starts from the one :func:`nearest` the target.

    ``out[i]`` at the returned q: ``O_ATTEMPTS``, ``O_STEPS``, ``O_CODE`` (0 converged, 1
    stalled, 2 iteration cap), the position [m] and rotation [rad] errors, σ_min
    (:func:`sigma_min3`), q (n), the tip position (3) and rotation (9, row-major), and the
    residual history (``max_iter + 1``, the first ``steps + 1`` written).
    """
    links = iplan[I_LINKS]
    n = iplan[I_JOINTS]
    ipar = iplan[:I_LINKS]
    kind = iplan[I_CHAIN : I_CHAIN + links]
    col = iplan[I_CHAIN + links : I_CHAIN + 2 * links]
    cont = iplan[I_CHAIN + 2 * links : I_CHAIN + 2 * links + n]
    rot = fplan[: 9 * links].reshape((links, 3, 3))
    o = 9 * links
    trans = fplan[o : o + 3 * links + 3].reshape((links + 1, 3))
    o += 3 * links + 3
    axis = fplan[o : o + 3 * links].reshape((links, 3))
    o += 3 * links
    tip_rot = fplan[o : o + 9].reshape((3, 3))
    lim = fplan[o + 9 : o + 9 + 4 * n].reshape((4, n))
    o += 9 + 4 * n
    near = ipar[I_NEAR]
    near_q = fplan[o : o + near * n].reshape((near, n))
    near_pose = fplan[o + near * n : o + near * (n + 12)].reshape((near, 12))
    mode, max_iter, use_limits = ipar[I_MODE], ipar[I_MAX_ITER], ipar[I_LIMITS] != 0
    lower, upper, cap, posture = lim[0], lim[1], lim[2], lim[3]
    scratch, p = np.empty((6, max(links, 1))), np.empty(3)
    r, w3 = np.empty((3, 3)), np.empty((3, 3))
    jac, jac_n, jac_best = np.empty((6, n)), np.empty((6, n)), np.empty((6, n))
    jt, jt_n = np.empty((6, n)), np.empty((6, n))
    et, et_n, e2 = np.empty(6), np.empty(6), np.empty(6)
    q, qn, dq, z = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    free = np.empty(n, dtype=np.bool_)
    k = max(n, 6)
    work, rhs, sol, hist = np.empty((k, k)), np.empty(k), np.empty(k), np.empty(max_iter + 1)
    o_p = O_Q + n
    o_h = o_p + 12
    for t in range(tgts.shape[0]):
        tgt, par, res = tgts[t], pars[t], out[t]
        q_out, hist_out = res[O_Q:o_p], res[o_h:]
        tol2 = par[P_TOL] * par[P_TOL]
        rtol2 = par[P_ROT_TOL] * par[P_ROT_TOL]
        yaw, wbar = par[P_YAW], par[P_WBAR]
        floor2 = par[P_POST_FLOOR] * par[P_POST_FLOOR]
        best_cost, best_steps, best_code, attempts = np.inf, 0, 1, 0
        first = -1 if near > 0 else 0
        pick = nearest(mode, tgt, w6, near_pose) if near > 0 else 0
        for s in range(first, starts.shape[1]):
            if s == 0 and pick == 0 and first < 0:  # the nearest was home, starts[t, 0]: tried
                continue
            attempts += 1
            if s < 0:
                for i in range(n):
                    q[i] = near_q[pick, i]
            else:
                for i in range(n):
                    q[i] = starts[t, s, i]
            _limit_into(q, lower, upper, cont, use_limits)
            fk_jac_into(rot, trans, axis, kind, col, q, p, jac, scratch, n >= 0, tip_rot, r)
            m, pos2, rot2 = task_into(mode, tgt, w6, yaw, p, r, jac, w3, et, jt)
            cost = 0.0
            for i in range(m):
                cost += et[i] * et[i]
            hist[0] = math.sqrt(cost)
            use_post = ipar[I_POSTURE] != 0 and n > m
            mu = par[P_MU0]
            accepted, tries, slow, code = 0, 0, 0, 1
            while True:
                if pos2 <= tol2 and rot2 <= rtol2:
                    code = 0
                    break
                if accepted >= max_iter:
                    code = 2
                    break
                for i in range(n):
                    free[i] = True
                    if use_limits and not cont[i]:
                        g = 0.0
                        for row in range(m):
                            g += jt[row, i] * et[row]
                        if (q[i] <= lower[i] and g < 0.0) or (q[i] >= upper[i] and g > 0.0):
                            free[i] = False
                lam2 = mu * (cost + wbar)
                with_z = use_post and cost > floor2
                if with_z:
                    for i in range(n):
                        d = posture[i] - q[i]
                        if cont[i]:
                            d = wrap_angle(d)
                        z[i] = par[P_POST_GAIN] * d if free[i] else 0.0
                kept = stalled = False
                for _attempt in range(2):
                    ok = step_into(jt, et, m, lam2, free, z, with_z, dq, e2, work, rhs, sol)
                    if not ok:
                        break
                    scale = 1.0
                    for i in range(n):
                        a = abs(dq[i])
                        if a * scale > cap[i]:
                            scale = cap[i] / a
                    for i in range(n):
                        qn[i] = q[i] + scale * dq[i]
                    _limit_into(qn, lower, upper, cont, use_limits)
                    fk_jac_into(
                        rot, trans, axis, kind, col, qn, p, jac_n, scratch, n >= 0, tip_rot, r
                    )
                    m_n, pos2_n, rot2_n = task_into(mode, tgt, w6, yaw, p, r, jac_n, w3, et_n, jt_n)
                    cost_n = 0.0
                    for i in range(m_n):
                        cost_n += et_n[i] * et_n[i]
                    good = cost_n < (0.25 * cost if with_z else cost)
                    if good:
                        if cost_n > cost * (1.0 - 1e-10):
                            slow += 1
                        else:
                            slow = 0
                        q, qn = qn, q  # the trial becomes the iterate (buffers swapped)
                        jac, jac_n = jac_n, jac
                        jt, jt_n = jt_n, jt
                        et, et_n = et_n, et
                        m, pos2, rot2, cost = m_n, pos2_n, rot2_n, cost_n
                        accepted += 1
                        hist[accepted] = math.sqrt(cost)
                        mu = max(mu * 0.25, 1e-12)
                        tries = 0
                        kept = True
                        if slow >= 8:
                            stalled = True
                        break
                    if not with_z:
                        break
                    with_z = False  # retry the plain step; no more posture in this attempt
                    use_post = False
                if stalled:
                    code = 1
                    break
                if not kept:
                    mu *= 8.0
                    tries += 1
                    if tries > 40:
                        code = 1
                        break
            if code == 0 or cost < best_cost or s == first:
                best_cost, best_steps, best_code = cost, accepted, code
                for i in range(n):
                    q_out[i] = q[i]
                    for row in range(6):
                        jac_best[row, i] = jac[row, i]
                for i in range(accepted + 1):
                    hist_out[i] = hist[i]
            if code == 0:
                break
        # the result, measured at the returned q: a converged attempt is the last one, whose
        # FK and errors at q are the latest computed (the same bits a new evaluation gives)
        p_out = res[o_p : o_p + 3]
        if best_code == 0:
            for u in range(3):
                p_out[u] = p[u]
        else:
            fk_jac_into(
                rot, trans, axis, kind, col, q_out, p_out, jac_best, scratch, n >= 0, tip_rot, r
            )
            _, pos2, rot2 = task_into(mode, tgt, w6, yaw, p_out, r, jac_best, w3, et, jt)
        for u in range(3):
            for v in range(3):
                res[o_p + 3 + 3 * u + v] = r[u, v]
        res[O_ATTEMPTS] = attempts
        res[O_STEPS] = best_steps
        res[O_CODE] = best_code
        res[O_ERROR] = math.sqrt(pos2)
        res[O_ROT_ERROR] = math.sqrt(rot2)
        res[O_SIGMA_MIN] = sigma_min3(jac_best)
