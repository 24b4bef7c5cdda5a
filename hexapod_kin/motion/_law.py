"""The resolved-rate law ``q̇(q, t)`` and its Euler / RK4 integration, on Pinocchio and numpy.

One evaluation at ``q`` and half-step index ``h`` (``t = h dt/2``):

1. Pinocchio: the tip pose and its LOCAL_WORLD_ALIGNED Jacobian ``J`` (rows ``[v; ω]``).
2. The task velocity ``ẋ = ξ(t) + K e``, ``e = [p_ref − p; log(R_ref Rᵀ)]`` (a twist in the tip
   frame rotated into base axes).
3. Damped least squares ``q̇ = Jᵀ (J Jᵀ + λ² I)⁻¹ ẋ``, ``λ² = λ²_max (1 − (σ_min/ε)²)`` for
   ``σ_min < ε``, else 0 (Nakamura; Chiaverini), floored at ``1e-14 σ_max²``; σ and λ² held
   over a step's RK4 stages.
4. A joint at a limit that ``q̇`` pushes outward is frozen and the system solved again, once;
   then ``q̇`` is scaled uniformly to the speed limits.

A 3×3 task runs on Python floats (:func:`~hexapod_kin._numerics.dls_step3`), larger ones on
:func:`~hexapod_kin._numerics.dls_step`.
"""

from __future__ import annotations

import math
from operator import ge, le, truediv
from typing import Any

import numpy as np
import pinocchio as pin

from .._numerics import dls_step, dls_step3

__all__ = ["integrate"]

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
dot = np.dot


def _sigma3(j: list[list[float]]) -> tuple[float, float]:
    """(σ_min, σ_max) of a 3×3 matrix (rows ``j``), closed form.

    σ_max² = ``e1`` the largest eigenvalue of ``J Jᵀ`` (trigonometric cubic solution); ``e2``
    from ``tr`` and ``det``; ``σ_min = |det J| / sqrt(e1 e2)`` stays accurate when singular.
    """
    (a, b, c), (d, e, f), (g, h, i) = j
    m00, m11, m22 = a * a + b * b + c * c, d * d + e * e + f * f, g * g + h * h + i * i
    m01, m02, m12 = a * d + b * e + c * f, a * g + b * h + c * i, d * g + e * h + f * i
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    tr = m00 + m11 + m22
    mean = tr / 3.0
    off = m01 * m01 + m02 * m02 + m12 * m12
    b00, b11, b22 = m00 - mean, m11 - mean, m22 - mean
    p2 = b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * off
    if p2 > 0.0:
        p = math.sqrt(p2 / 6.0)
        detb = (
            b00 * (b11 * b22 - m12 * m12)
            - m01 * (m01 * b22 - m12 * m02)
            + m02 * (m01 * m12 - b11 * m02)
        )
        r = max(-1.0, min(1.0, detb / (2.0 * p * p * p)))
        e1 = mean + 2.0 * p * math.cos(math.acos(r) / 3.0)
    else:
        e1 = mean
    if not e1 > 0.0:
        return 0.0, 0.0
    s = tr - e1
    e2 = 0.5 * (s + math.sqrt(max(s * s - 4.0 * det * det / e1, 0.0)))
    s12 = math.sqrt(e1 * e2)
    return (abs(det) / s12 if s12 > 0.0 else 0.0), math.sqrt(e1)


def _sigma(rows: np.ndarray) -> tuple[float, float]:
    """(σ_min, σ_max) of a task J: its min(m, n)-th and first singular values (Eigen's Jacobi)."""
    import eigenpy

    m, n = rows.shape
    if n == 0:
        return 0.0, 0.0
    svd = eigenpy.NoPrecondJacobiSVD if m == n else eigenpy.ColPivHhJacobiSVD  # QR first if not
    s = svd(rows, 0).singularValues().tolist()
    return s[-1], s[0]


def integrate(
    model: Any, q0: np.ndarray, vel: np.ndarray, ref_p: np.ndarray, ref_r: np.ndarray | None,
    dt: float, rk4: bool, tip_frame: bool, gain: float, eps: float, lam2max: float,
    lower: np.ndarray, upper: np.ndarray, use_limits: bool, vmax: np.ndarray,
) -> dict[str, np.ndarray]:  # fmt: skip
    """Integrate the law from ``q0`` (Euler or RK4); ``(len(vel) − 1) / 2`` steps.

    ``vel``, ``ref_p``, ``ref_r`` (None for a 3-row task) are sampled at half steps (index 2k =
    t_k); limits ±inf where none.

    Returns:
        Per sample: ``q``, ``qdot``, ``pose`` (4×4), ``twist`` ``J q̇`` (6, base axes),
        ``sigma`` (σ_min, σ_max), ``damping`` λ², ``limited``.

    """
    pm, data, fid = model.model, model.data, model.tip_id
    base = model.baseMo
    rot_base = np.asarray(base.rotation)
    moved = not np.array_equal(base.homogeneous, np.eye(4))
    convert = model.pinocchio_q if pm.nq != model.nq else None
    n, rows6 = int(q0.shape[0]), vel.shape[1] == 6
    fast = not rows6 and n == 3
    vel_l, refp_l = vel.tolist(), ref_p.tolist()
    lo, hi, vm = lower.tolist(), upper.tolist(), vmax.tolist()
    speed = any(math.isfinite(v) for v in vm)
    # no finite position limit (continuous joints): nothing to freeze or clamp
    bounded = use_limits and any(math.isfinite(v) for v in lo + hi)
    ref_l = None if ref_r is None else list(ref_r)  # the 3×3 references, one view per sample
    frame_jacobian, frame_placement = pin.computeFrameJacobian, pin.updateFramePlacement
    log3, array = pin.log3, np.array

    def law(q: list[float], h: int, held: Any) -> tuple[Any, ...]:
        """q̇ at (q, t_h) → (q̇, pose, J, σ_min, σ_max, λ², held, limited) (``held``: a step's λ²)."""
        jac = frame_jacobian(pm, data, array(q) if convert is None else convert(q), fid, _LWA)
        omf = frame_placement(pm, data, fid)
        if jac.ndim == 1:  # one joint: Eigen's 6×1 comes back 1-D
            jac = jac.reshape(6, 1)
        if moved:
            omf = base * omf
            jac = np.vstack((rot_base @ jac[:3], rot_base @ jac[3:]))
        pose = omf.homogeneous
        (r00, r01, r02, p0), (r10, r11, r12, p1), (r20, r21, r22, p2), _ = pose.tolist()
        v, rp = vel_l[h], refp_l[h]
        if rows6 and tip_frame:  # the body twist in base axes: [R v; R ω]
            a, b, c, d, e, f = v
            v = [r00 * a + r01 * b + r02 * c, r10 * a + r11 * b + r12 * c,
                 r20 * a + r21 * b + r22 * c, r00 * d + r01 * e + r02 * f,
                 r10 * d + r11 * e + r12 * f, r20 * d + r21 * e + r22 * f]  # fmt: skip
        xd = [v[0] + gain * (rp[0] - p0), v[1] + gain * (rp[1] - p1), v[2] + gain * (rp[2] - p2)]
        if rows6:
            wx, wy, wz = v[3], v[4], v[5]
            if gain != 0.0:
                ex, ey, ez = log3(dot(ref_l[h], pose[:3, :3].T)).tolist()  # type: ignore[index]
                wx, wy, wz = wx + gain * ex, wy + gain * ey, wz + gain * ez
            xd += [wx, wy, wz]
            rows = jac
        else:
            rows = jac[:3]
        j3 = rows.tolist() if fast else None
        smin = smax = lam2 = math.nan
        if held is None:
            smin, smax = _sigma3(j3) if j3 is not None else _sigma(rows)
            lam2 = 0.0
            if smin < eps:
                ratio = smin / eps
                lam2 = lam2max * (1.0 - ratio * ratio)
            held = max(lam2, 1e-14 * (smax * smax + 1e-300))
        lam_use = held
        if j3 is not None:
            qd = dls_step3(j3, xd, lam_use) or [0.0, 0.0, 0.0]
        else:
            qd = dls_step(rows, xd, lam_use).tolist()
        limited = False
        if bounded and (any(map(le, q, lo)) or any(map(ge, q, hi))):  # a joint at a limit
            free = [not ((x <= a and v < 0.0) or (x >= b and v > 0.0))
                    for x, v, a, b in zip(q, qd, lo, hi)]  # fmt: skip
            if not all(free):  # freeze the joints pushed outward, solve for the others
                qd = dls_step(rows, xd, lam_use, free).tolist()
                qd = [x if ok else 0.0 for x, ok in zip(qd, free)]
                limited = True
        if speed:
            ratio = max(map(truediv, map(abs, qd), vm))  # largest |q̇_i| / q̇max_i
            if ratio > 1.0:
                qd, limited = [x / ratio for x in qd], True
        return qd, pose, jac, smin, smax, lam2, held, limited

    steps = (vel.shape[0] - 1) // 2
    rows: tuple[list[Any], ...] = ([], [], [], [], [], [], [])
    qs, qds, poses, jacs, sig, lams, lims = rows
    q = q0.tolist()
    half, sixth = 0.5 * dt, dt / 6.0
    for k in range(steps + 1):
        h = 2 * k
        k1, pose, jac, smin, smax, lam2, held, lim = law(q, h, None)
        for col, value in zip(rows, (q, k1, pose, jac, (smin, smax), lam2, lim)):
            col.append(value)
        if k == steps:
            break
        if rk4:
            k2 = law([a + half * b for a, b in zip(q, k1)], h + 1, held)[0]
            k3 = law([a + half * b for a, b in zip(q, k2)], h + 1, held)[0]
            k4 = law([a + dt * b for a, b in zip(q, k3)], h + 2, held)[0]
            ks = zip(q, k1, k2, k3, k4)
            q = [a + sixth * (b + 2.0 * c + 2.0 * d + e) for a, b, c, d, e in ks]
        else:
            q = [a + dt * b for a, b in zip(q, k1)]
        if bounded:
            q = [lo[i] if x < lo[i] else hi[i] if x > hi[i] else x for i, x in enumerate(q)]
    qdot = np.array(qds)
    twist = np.einsum("kij,kj->ki", np.array(jacs), qdot)
    out = {"q": np.array(qs), "qdot": qdot, "pose": np.array(poses), "twist": twist}
    out["sigma"], out["damping"] = np.array(sig), np.array(lams)
    return out | {"limited": np.array(lims, dtype=bool)}
