"""Body sway of a statically stable walk on few legs: the zero-moment point to each support.

A crawl lifts one leg at a time and the body must sway over the three stance feet. A
swaying body accelerates, so the ground holds it at the zero-moment point (ZMP), not under
the CoM: on flat ground ``z = c − (h / g) c̈`` (h the CoM height; the legs' own momentum
neglected), centimetres apart at a 1 s cycle.

The sway is a periodic cubic spline (C², period T) in the body frame with one knot per
swing group at mid-swing. The knot values put the ZMP at ``gain`` × the safest point of that
swing's support (:func:`support_centre`), by one linear solve (spline, its second derivative
and the ZMP at the knots are linear in them), then two correction passes with the whole
robot's ZMP (:func:`.zmp.zmp_points`). The stance feet's mean replaces the incentre when the
legs cannot follow its larger sway (a foot out of reach, a joint past a position or speed
limit). The incentre has the largest static margin and leans towards the stance foot
diagonal to the swinging one, which halves the swinging corner's drop on compliant ground
(``s_a + s_b − s_d``: ``∝ 1 − 2/3`` at the centroid, ``3 − 2√2 ≈ 0.17`` at the incentre).

Friction: the sway asks ``|c − z| / h`` of the weight as horizontal force, at most
:data:`SWAY_FRICTION` at the knots; beyond it each target is the point farthest inside its
support within a common (bisected) distance of the body's centre. If that sway's ZMP leaves
the support, the incentres are kept: a body that tips is worse than one that slides.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .paths import se2_pose
from .stability import periodic_spline, support_margin
from .zmp import GRAVITY, rates, zmp_points

__all__ = ["SWAY_FRICTION", "support_centre", "sway_poses", "zmp_margin"]

#: The sway's friction budget: its horizontal acceleration at the knots, ``|s − z| g / h``
#: (``s`` the sway, ``z`` its ZMP target, ``h`` the body's height), at most this many ``g``:
#: half the lowest floor friction of ``simulate --robust`` (0.6).
SWAY_FRICTION = 0.3


def _zmp_matrix(knots: np.ndarray, T: float, height: float) -> np.ndarray:
    """(K, K) map from knot values to the ZMP offsets at the knots: ``s − (h/g) s̈``.

    ``s̈`` at the knots: the periodic cubic spline's (:func:`.stability.periodic_spline`, the
    same spline as :class:`scipy.interpolate.CubicSpline` with ``bc_type="periodic"``) of
    each unit knot vector. ``knots`` sorted, in [0, 1) cycles.
    """
    k = len(knots)
    if k == 1:  # a constant sway
        return np.eye(1)
    unit = np.eye(k)
    from scipy.interpolate import CubicSpline  # 0.3 s of import: only when a sway is fitted

    spline = CubicSpline(np.append(knots, knots[0] + 1.0) * T, np.vstack([unit, unit[:1]]),
                         bc_type="periodic")  # fmt: skip
    return np.asarray(unit - height / GRAVITY * spline(knots * T, 2))


def support_centre(points: np.ndarray, reach: float = math.inf) -> np.ndarray:
    """The point (2,) of a support the farthest inside it [m]: where a sway puts the ZMP.

    Three feet: the triangle's incentre ``(a·A + b·B + c·C) / (a + b + c)`` (each foot
    weighted by the length of the side opposite it), the centre of the largest circle inside
    the triangle, so the largest static stability margin; when it is farther than ``reach``
    from the origin, the point of the disc ``|P| ≤ reach`` farthest inside the triangle
    (the margin ``min_i d_i(P)`` is concave: its largest value on the disc's circle, at the
    peak of one edge's distance or where two are equal). Other supports (and a triangle
    whose feet coincide): the feet's mean; none: the origin.

    Args:
        points: (K, 2) stance feet [m].
        reach: The largest distance of the point from the origin [m] (≥ 0; default none).

    """
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    if not len(p):
        return np.zeros(2)
    side = np.linalg.norm(np.roll(p, -1, axis=0) - np.roll(p, 1, axis=0), axis=1)
    if len(p) != 3 or not side.sum() > 0.0:
        return np.asarray(p.mean(axis=0))
    centre = np.asarray(side @ p / side.sum())
    if not np.hypot(*centre) > reach:
        return centre
    edge = np.roll(p, -1, axis=0) - p  # edge i: p_i -> p_i+1
    if not np.all(np.hypot(*edge.T) > 0.0):
        return centre
    n = np.stack([-edge[:, 1], edge[:, 0]], axis=1) / np.hypot(*edge.T)[:, None]
    n *= np.sign(np.einsum("ij,ij->i", n, np.roll(p, -2, axis=0) - p))[:, None]  # inwards
    c = -np.einsum("ij,ij->i", n, p)  # d_i(P) = n_i · P + c_i

    cands = [reach * n[i] for i in range(3)]
    for i in range(3):
        for j in range(i + 1, 3):
            w, k = n[i] - n[j], c[j] - c[i]
            ww = float(w @ w)
            if not ww > 0.0 or k * k > reach * reach * ww:
                continue
            foot = (k / ww) * w
            off = math.sqrt(reach * reach - k * k / ww) / math.sqrt(ww)
            cands += [foot + off * np.array([-w[1], w[0]]), foot - off * np.array([-w[1], w[0]])]
    return np.asarray(max(cands, key=lambda q: float(np.min(n @ q + c))))


def _within_friction(
    supports: list[np.ndarray], zmp_of: np.ndarray, height: float, gain: float
) -> tuple[np.ndarray, np.ndarray]:
    """The ZMP targets (K, 2) at the knots within the friction budget, and the incentres.

    Each support's :func:`support_centre` within a common ``reach`` of the origin, the largest
    (bisected) whose sway ``s = M⁻¹ (gain · z)`` accelerates at most :data:`SWAY_FRICTION` g
    at the knots, ``|s − gain · z| g / h``.
    """

    def targets(reach: float) -> np.ndarray:
        return np.array([support_centre(f, reach) for f in supports]).reshape(-1, 2)

    def accel(z: np.ndarray) -> float:  # in g
        s = np.linalg.solve(zmp_of, gain * z)
        return float(np.hypot(*(s - gain * z).T).max()) / height

    full = targets(math.inf)
    if not (height > 0.0 and gain > 0.0) or accel(full) <= SWAY_FRICTION:
        return full, full
    lo, hi = 0.0, float(np.hypot(*full.T).max())
    for _ in range(40):  # 1e-12 of the incentres' distance
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if accel(targets(mid)) <= SWAY_FRICTION else (lo, mid)
    return targets(lo), full


def zmp_margin(
    wb: Any, q: np.ndarray, base: np.ndarray, feet: np.ndarray, support: Any, t: Any, ground: Any
) -> np.ndarray:
    """(N,) margins [m] of the ZMP (on the heights ``ground`` (N,)) in the support polygons."""
    return np.asarray(support_margin(feet, support, zmp_points(wb, q, base, t, ground)))


def sway_poses(
    wb: Any,
    table: Any,
    T: float,
    vel: tuple[float, float, float],
    nb: np.ndarray,
    gain: float,
    base: np.ndarray,
    plan: np.ndarray,
    t: np.ndarray,
    q0: Any,
) -> np.ndarray:
    """The body poses (N, 4, 4) with the periodic sway added (see the module docstring).

    Args:
        wb: The robot (:class:`~.robot.WholeBody`).
        table: The phase table.
        T: Cycle time [s].
        vel: Body twist ``(vx, vy, wz)``.
        nb: (L, 2) neutral feet in the body frame [m].
        gain: Sway gain in [0, 1].
        base: (N, 4, 4) nominal body poses.
        plan: (N, L, 3) planned foot points in the world [m].
        t: (N,) sample times [s].
        q0: Joints the first sample's IK branch is nearest to.

    """
    offs = np.asarray(table.offsets)
    beta = table.duty_factor
    mid = np.remainder(beta - offs + 0.5 * (1.0 - beta), 1.0)  # mid-swing, in cycles
    knots = np.unique(np.round(mid, 12))
    nominal = base
    rot2 = nominal[:, :2, :2]
    ground = float(np.mean(plan[0, :, 2]))
    height = max(float(np.mean(nominal[:, 2, 3])) - ground, 0.0)
    supports: list[np.ndarray] = []
    centroid = np.zeros((len(knots), 2))
    for k, tau in enumerate(knots):
        phi = np.remainder(tau + offs, 1.0)
        stance = phi < beta
        rel = se2_pose((0.5 * beta - phi) * T, vel)  # the stance's mid-pose, body frame
        c, sn = np.cos(rel[:, 2]), np.sin(rel[:, 2])
        px = rel[:, 0] + c * nb[:, 0] - sn * nb[:, 1]
        py = rel[:, 1] + sn * nb[:, 0] + c * nb[:, 1]
        supports.append(np.stack([px[stance], py[stance]], axis=1))
        if stance.any():
            centroid[k] = [px[stance].mean(), py[stance].mean()]
    zmp_of = _zmp_matrix(knots, T, height)
    safest, incentres = _within_friction(supports, zmp_of, height, gain)
    phase_t = np.remainder(t, T)
    dt = float(t[1] - t[0]) if len(t) > 1 else T
    near = [
        np.abs(np.remainder(phase_t - tau * T + 0.5 * T, T) - 0.5 * T) <= 0.5 * dt + 1e-12
        for tau in knots
    ]

    def fit(targets: np.ndarray) -> np.ndarray:
        values = np.linalg.solve(zmp_of, targets)
        out = nominal
        for it in range(3):
            off = periodic_spline(knots * T, values, T, t)  # (N, 2) body frame
            out = nominal.copy()
            out[:, :2, 3] += np.einsum("nij,nj->ni", rot2, off)
            if it == 2 or not any(m.any() for m in near) or len(t) < 5:
                break
            q = np.array(wb.body_ik(out, plan, q_prev=q0, times=t, strict=False).q)
            zmp = zmp_points(wb, q, out, t, np.full(len(t), ground))
            zmp_b = np.einsum("nji,nj->ni", rot2, zmp[:, :2] - nominal[:, :2, 3])
            err = np.zeros_like(targets)
            for k, m in enumerate(near):
                if m.any():
                    err[k] = targets[k] - zmp_b[m].mean(axis=0)
            step = np.linalg.solve(zmp_of, err)
            if not np.abs(values + step).max() <= wb.leg_span:  # a ZMP no sway of the body can
                break  # follow (absurd inertias): the centre of mass's sway is kept
            values += step
        return out

    out = fit(safest * gain)
    if not np.array_equal(safest, incentres):
        q = np.array(wb.body_ik(out, plan, q_prev=q0, times=t, strict=False).q)
        stance = np.remainder(np.asarray(t)[:, None] / T + offs[None, :], 1.0) < beta
        if zmp_margin(wb, q, out, plan, stance, t, np.full(len(t), ground)).min() < 0.0:
            safest = incentres  # a body that tips is worse than one that asks more friction
            out = fit(safest * gain)
    if np.array_equal(safest, centroid):
        return out
    # the largest margin where the legs follow it (reached, within their position and speed
    # limits), else the centroid's smaller sway
    ik = wb.body_ik(out, plan, q_prev=q0, times=t, strict=False)
    speed = np.abs(rates(np.asarray(ik.q), t)[0])
    vlim = np.broadcast_to(np.asarray(wb.velocity_limit, dtype=float).reshape(-1), speed.shape)
    if np.asarray(ik.ok).all() and not np.any(speed > np.where(vlim > 0, vlim, np.inf)):
        return out
    return fit(centroid * gain)
