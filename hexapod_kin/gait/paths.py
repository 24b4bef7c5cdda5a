"""One leg's step cycle: stance on the ground, swing through the air.

:func:`foot_path` is a pure function of the gait phase (stance: a straight line on the ground,
front to back; swing: a lifted half ellipse or cycloid, back to front) with step length,
height and duty factor, so that gait tables call it per leg with their phase offsets;
:func:`foot_step` turns one cycle into joint angles by IK.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any, Literal

import numpy as np

from .._tree import poses_of
from ..exceptions import ParameterError, positive
from ..motion import default_stance, read_only, track
from .robot import BodyIK

__all__ = [
    "FootStep",
    "foot_path",
    "foot_step",
    "last_stance_value",
    "rolling_ik",
    "rolling_offsets",
    "rotation_increments",
    "se2_pose",
    "stance_start_index",
    "terrain_normals",
]


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
    length = positive("length", length, allow_zero=True)
    height = positive("height", height, allow_zero=True)
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

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (arrays as nested lists, SI units)."""
        return {
            f.name: (v.tolist() if isinstance(v, np.ndarray) else v)
            for f in fields(self)
            for v in (getattr(self, f.name),)
        }

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
    dt: float = 0.005,
    duration: float = 1.0,
    duty_factor: float = 0.5,
    direction: Any = (1.0, 0.0),
    shape: Literal["ellipse", "cycloid"] = "ellipse",
    cycles: int = 1,
    phase_offset: float = 0.0,
    q0: Any = None,
) -> FootStep:
    """Plan a foot step (stance + swing) and its joint trajectory by IK.

    Args:
        model: A loaded leg model.
        center: Middle of the stance line (3,) in [m]; default the foot at
            :func:`default_stance`.
        length: Step length [m].
        height: Swing height [m].
        dt: Sample time [s].
        duration: Cycle time [s].
        duty_factor: Stance fraction in (0, 1).
        direction: Horizontal travel direction (2,).
        shape: Swing shape ``"ellipse"`` or ``"cycloid"``.
        cycles: Number of cycles (>= 1).
        phase_offset: Phase at t = 0 in cycles (gait tables set one per leg).
        q0: Joints near the first sample (IK branch / warm start).

    Returns:
        A :class:`FootStep`.

    Raises:
        ParameterError: Bad step parameters.

    """
    duration = positive("duration", duration)
    dt = positive("dt", dt)
    if not (isinstance(cycles, int) and cycles >= 1):
        raise ParameterError(f"cycles={cycles!r} is not allowed; an int >= 1 is needed")
    q_home = default_stance(model) if q0 is None else model.check_q(q0, "q0")
    c = model.position(q_home) if center is None else np.asarray(center, dtype=float)
    m = int(round(cycles * duration / dt))
    t = np.arange(m + 1) * (cycles * duration / m)
    phase = t / duration + float(phase_offset)
    foot = foot_path(
        phase,
        center=c,
        length=length,
        height=height,
        duty_factor=duty_factor,
        direction=direction,
        shape=shape,
    )
    tracked = track(model, foot, q_home)
    q, reached = tracked.q, tracked.reached
    qdot = np.gradient(q, t, axis=0)
    actual = np.array([model.position(qi) for qi in q])
    within = bool(np.all(q >= model.lower - 1e-12) and np.all(q <= model.upper + 1e-12))
    step = float(np.max(np.abs(np.diff(q, axis=0)))) if len(q) > 1 else 0.0
    stance = np.remainder(phase, 1.0) < duty_factor
    read_only(t, phase, stance, foot, qdot, actual)
    return FootStep(t, phase, stance, foot, q, qdot, reached, actual, within, step)


# ---------------------------------------------------------------------- round feet
def terrain_normals(ground: Any, x: Any, y: Any, step: float = 1e-6) -> np.ndarray:
    """Unit normals (..., 3) of the ground ``z = h(x, y)`` at ``x``, ``y`` [m].

    ``n ∝ (−∂h/∂x, −∂h/∂y, 1)`` with each slope the smaller (in size) of the forward and the
    backward difference over ``step`` [m] (min-mod: exact on a plane up to rounding, and the
    flat side at a step's edge); ``ẑ`` where the ground is undefined.
    """
    xa, ya = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
    h0 = ground(xa, ya)

    def slope(dx: float, dy: float) -> np.ndarray:
        fwd = (ground(xa + dx, ya + dy) - h0) / step
        bwd = (h0 - ground(xa - dx, ya - dy)) / step
        g = np.where(np.abs(fwd) <= np.abs(bwd), fwd, bwd)
        return np.where(np.isfinite(g), g, 0.0)

    out = np.empty(xa.shape + (3,))
    out[..., 0] = -slope(step, 0.0)
    out[..., 1] = -slope(0.0, step)
    out[..., 2] = 1.0
    out /= np.linalg.norm(out, axis=-1, keepdims=True)
    return out


def rotation_increments(rot: np.ndarray) -> np.ndarray:
    """Rotation vectors (N − 1, ...) ``θ_k = log(R_{k+1} R_kᵀ)`` of world rotations (N, ..., 3, 3).

    ``θ_k`` is the world-frame rotation from sample k to k + 1 (``ω dt`` for a constant angular
    velocity ω): axis-angle from the trace and the skew part (angles below π).
    """
    # R_{k+1} R_kᵀ = Σ_j b_j a_jᵀ (columns a_j of R_k, b_j of R_{k+1}): trace Σ a_j·b_j,
    # skew part (vee) Σ a_j × b_j
    R0, R1 = rot[:-1], rot[1:]
    tr = np.einsum("...ij,...ij->...", R0, R1)
    cos = np.clip((tr - 1.0) / 2.0, -1.0, 1.0)
    ang = np.arccos(cos)
    sin = np.sqrt(np.maximum(1.0 - cos * cos, 0.0))
    small = ang < 1e-6
    scale = np.where(small, 0.5 + ang * ang / 12.0, ang / (2.0 * np.where(small, 1.0, sin)))
    a, b = np.swapaxes(R0, -1, -2), np.swapaxes(R1, -1, -2)  # rows: the columns
    vee = _cross(a[..., 0, :], b[..., 0, :])
    vee += _cross(a[..., 1, :], b[..., 1, :])
    vee += _cross(a[..., 2, :], b[..., 2, :])
    vee *= scale[..., None]
    return vee


def rolling_offsets(rot: Any, support: Any, normals: Any, radius: float) -> np.ndarray:
    """How far each stance foot's centre has rolled since its first stance sample, (N, L, 3) [m].

    A sphere of radius r rolling without slip on a plane of unit normal n has centre velocity
    ``v = ω × (r n)`` (the material point in contact, ``c − r n``, is at rest). Discretely,
    ``D_i = Σ_{k = s}^{i − 1} θ_k × (r n)`` from the stance's first sample s, ``θ_k`` the foot
    frame's rotation increment (:func:`rotation_increments`) and n the stance's contact
    normal; 0 in swing. The contact point then slips by ``c_i − c_s − D_i`` (zero when rolling).

    Args:
        rot: (N, L, 3, 3) world rotations of the foot frames.
        support: (N, L) True in stance.
        normals: (N, L, 3) the ground's unit normal at each stance contact.
        radius: Foot radius r [m].

    """
    R = np.asarray(rot, dtype=float)
    sup = np.asarray(support, dtype=bool)
    n = np.asarray(normals, dtype=float)
    out = np.zeros(sup.shape + (3,))
    if radius == 0.0 or len(sup) < 2:
        return out
    inc = _cross(rotation_increments(R), radius * n[:-1] * (sup[:-1] & sup[1:])[..., None])
    cum = np.zeros_like(out)
    np.cumsum(inc, axis=0, out=cum[1:])
    cum -= cum[stance_start_index(sup), np.arange(sup.shape[1])[None, :]]
    cum *= sup[..., None]
    return cum


def stance_start_index(support: np.ndarray) -> np.ndarray:
    """(N, L) index of the first sample of the current stance (or of the last one, in swing)."""
    n = len(support)
    start = support.copy()
    start[1:] &= ~support[:-1]
    idx = np.where(start, np.arange(n)[:, None], 0)
    return np.asarray(np.maximum.accumulate(idx, axis=0))


def last_stance_value(values: np.ndarray, support: np.ndarray) -> np.ndarray:
    """(N, L, ...) ``values`` at each leg's latest stance sample (0 before the first one)."""
    n = len(support)
    idx = np.where(support, np.arange(n)[:, None], -1)
    idx = np.maximum.accumulate(idx, axis=0)
    out = values[np.maximum(idx, 0), np.arange(support.shape[1])[None, :]]
    return np.asarray(np.where((idx >= 0)[..., None], out, 0.0))


@dataclass(frozen=True)
class _LegStructure:
    """Which joints move each foot, each joint's axis in its own frame, each foot's link."""

    joints: np.ndarray  # (L, M) joint columns of each leg (padded with -1)
    axes: np.ndarray  # (nq, 3) joint axis in the joint's frame
    revolute: np.ndarray  # (nq,) True: revolute, False: prismatic
    link: np.ndarray  # (L,) the joint whose frame carries the foot (the deepest of the leg)
    foot: np.ndarray  # (L, 3) the foot in that joint's frame


_STRUCTURES: dict[int, tuple[Any, _LegStructure]] = {}

#: Fixed-point sweeps of the Newton step's coupling between samples (:func:`rolling_ik`).
_SWEEPS = 2


def _leg_structure(wb: Any, q: np.ndarray, base: np.ndarray) -> _LegStructure:
    """Found once per robot by moving each joint by ε at one configuration (exact axes)."""
    hit = _STRUCTURES.get(id(wb))
    if hit is not None and hit[0] is wb:
        return hit[1]
    nq, eps = wb.nq, 1e-4
    Q = np.repeat(q[None], nq + 1, axis=0)
    Q[1:] += eps * np.eye(nq)
    B = np.repeat(base[None], nq + 1, axis=0)
    T = wb.joint_poses(Q, B)
    feet = wb.points_of(T)[:, :, -1]  # (nq+1, L, 3)
    moved = np.linalg.norm(feet[1:] - feet[0][None], axis=-1) > 1e-12  # (nq, L)
    axes = np.zeros((nq, 3))
    revolute = np.ones(nq, dtype=bool)
    for j in range(nq):
        R0, R1 = T[0, j, :3, :3], T[j + 1, j, :3, :3]
        w = rotation_increments(np.stack([np.eye(3), R0.T @ R1]))[0] / eps
        if np.linalg.norm(w) > 0.5:
            axes[j] = w / np.linalg.norm(w)
        else:
            revolute[j] = False
            d = R0.T @ (T[j + 1, j, :3, 3] - T[0, j, :3, 3]) / eps
            axes[j] = d / max(np.linalg.norm(d), 1e-300)
    cols = [np.flatnonzero(moved[:, k]) for k in range(moved.shape[1])]
    width = max(1, max(len(c) for c in cols))
    joints = np.full((len(cols), width), -1)
    for k, c in enumerate(cols):
        joints[k, : len(c)] = c
    link = np.array([c.max() if len(c) else 0 for c in cols])
    Tl = T[0, link]
    foot = np.einsum("lji,lj->li", Tl[:, :3, :3], feet[0] - Tl[:, :3, 3])
    out = _LegStructure(joints, axes, revolute, link, foot)
    _STRUCTURES.clear()
    _STRUCTURES[id(wb)] = (wb, out)
    return out


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``u × v`` over the last axis (3), written out (faster than np.cross on small arrays)."""
    out = np.empty(np.broadcast_shapes(u.shape, v.shape))
    out[..., 0] = u[..., 1] * v[..., 2] - u[..., 2] * v[..., 1]
    out[..., 1] = u[..., 2] * v[..., 0] - u[..., 0] * v[..., 2]
    out[..., 2] = u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]
    return out


def _x(u: Any, v: Any) -> np.ndarray:
    """``u × v`` of component-first vectors (3, ...)."""
    out = np.empty((3,) + np.broadcast_shapes(np.shape(u[0]), np.shape(v[0])))
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        np.multiply(u[j], v[k], out=out[i])
        out[i] -= u[k] * v[j]
    return out


def _increments(R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`rotation_increments` components first: (3, L, N − 1) from (3, 3, L, N); and θ."""
    a, b = R[..., :-1], R[..., 1:]
    cos = np.clip((np.einsum("ij...,ij...->...", a, b) - 1.0) / 2.0, -1.0, 1.0)
    ang = np.arccos(cos)
    sin = np.sqrt(np.maximum(1.0 - cos * cos, 0.0))
    small = ang < 1e-6
    scale = np.where(small, 0.5 + ang * ang / 12.0, ang / (2.0 * np.where(small, 1.0, sin)))
    vee = _x(a[:, 0], b[:, 0]) + _x(a[:, 1], b[:, 1]) + _x(a[:, 2], b[:, 2])
    vee *= scale
    return vee, ang


def _rolled(inc: np.ndarray, sup: np.ndarray, start: np.ndarray) -> np.ndarray:
    """``Σ_{k=s}^{i−1} inc_k`` over each stance (0 in swing), (3, L, N) from (3, L, N − 1)."""
    cum = np.zeros(inc.shape[:-1] + (inc.shape[-1] + 1,))
    np.cumsum(inc, axis=-1, out=cum[..., 1:])
    cum -= cum[:, np.arange(len(start))[:, None], start]
    cum *= sup
    return cum


def _inv_sym3(A: np.ndarray) -> np.ndarray:
    """Inverses of symmetric positive-definite 3×3 matrices, components first (3, 3, ...)."""
    a, b, c, d, e, f = A[0, 0], A[0, 1], A[0, 2], A[1, 1], A[1, 2], A[2, 2]
    out = np.empty(A.shape)
    out[0, 0] = d * f - e * e
    out[0, 1] = out[1, 0] = c * e - b * f
    out[0, 2] = out[2, 0] = b * e - c * d
    out[1, 1] = a * f - c * c
    out[1, 2] = out[2, 1] = b * c - a * e
    out[2, 2] = a * d - b * b
    out /= a * out[0, 0] + b * out[0, 1] + c * out[0, 2]
    return out


def rolling_ik(
    wb: Any,
    base: np.ndarray,
    plan: np.ndarray,
    support: np.ndarray,
    swing: np.ndarray,
    blend: np.ndarray,
    normals: np.ndarray,
    rad: float,
    t: np.ndarray,
    q0: Any,
    tol: float,
    max_passes: int,
) -> tuple[np.ndarray, np.ndarray, Any, int, float, np.ndarray | None, np.ndarray]:
    """IK of the planned feet with the stance feet rolling, iterated to a fixed point.

    Pass 1: ``wb.body_ik`` of the plan (branches chosen there). Then, with the joint poses of
    q: the rolling ``D(q)`` (:func:`rolling_offsets` of the rotations of each foot's link,
    whose increments are the foot frame's), the targets ``plan + D`` (stance) or
    ``plan + D_lift-off·(1 − blend)`` (swing), the error ``e = targets − centres(q)``, and a
    Newton step — until ``max|e| ≤ tol`` [m] or ``max_passes``. ``e`` is the planned contact
    points' slip (up to rounding). Returns (feet, q, ik, passes, residual [m], joint poses of
    q or None, D: the rolling of q's own foot rotations, by FK).

    The Newton step is the exact linearisation of the whole stance: a foot rotation
    ``δφ_k = J_ω δq_k`` (world frame) changes the increment ``θ_k = log(R_{k+1} R_kᵀ)`` by
    ``δθ_k = J_l⁻¹(θ_k) δφ_{k+1} − J_r⁻¹(θ_k) δφ_k``, i.e.
    ``δφ_{k+1} − δφ_k − ½ θ_k × (δφ_{k+1} + δφ_k) + β θ_k × (θ_k × (δφ_{k+1} − δφ_k))``,
    ``β = 1/θ² − (1 + cos θ)/(2θ sin θ)`` (SO(3)'s left/right Jacobians), so that
    ``δD_i = Σ_{k=s}^{i−1} δθ_k × (r n)``. Sample i's own term ``δφ_i × (r n) = −K_i δq_i``
    (``K = r [n]ₓ J_ω``) goes into the per-sample matrix ``J = J_p + K``; the rest (earlier
    samples, through the sum) is small (the increments are ~ω dt) and is solved for by
    fixed-point sweeps ``J δq = e + δD(δq) + K δq`` (each sweep gains a factor ~θ, a few
    hundred here; :data:`_SWEEPS`), so the Newton iteration converges quadratically. Swing
    targets follow the lift-off rolling ``D_ℓ + δD_ℓ``. Arrays are components first with the
    samples last (long vector operations).
    """
    ik = wb.body_ik(base, plan, q_prev=q0, times=t, strict=False)
    q = np.array(ik.q)
    if rad == 0.0:
        return plan, q, ik, 1, 0.0, None, np.zeros(plan.shape)
    st = _leg_structure(wb, q[0], base[0])
    n, nl = support.shape
    sup = np.ascontiguousarray(np.asarray(support, dtype=bool).T)  # (L, N)
    sw = np.ascontiguousarray(np.asarray(swing, dtype=bool).T)
    start = stance_start_index(np.asarray(support, dtype=bool)).T  # (L, N)
    both = sup[:, :-1] & sup[:, 1:]
    rn = rad * np.ascontiguousarray(np.asarray(normals, dtype=float).transpose(2, 1, 0))
    rn_inc = rn[..., :-1] * both  # the increments' lever r n, 0 outside a stance
    planT = np.ascontiguousarray(np.asarray(plan, dtype=float).transpose(2, 1, 0))  # (3, L, N)
    keep = np.where(sw, 1.0 - np.asarray(blend, dtype=float).T, 0.0)  # swing: lift-off share
    last = np.maximum.accumulate(np.where(sup, np.arange(n), -1), axis=1)
    last_at = (np.arange(nl)[:, None], np.maximum(last, 0))
    seen = last >= 0
    jj = np.maximum(st.joints, 0)  # (L, M)
    valid = st.joints >= 0
    rev = (st.revolute[jj] & valid)[..., None]  # (L, M, 1)
    lin_ok = valid[..., None]
    ax_j = st.axes.T[..., None]  # (3, nq, 1)
    foot = st.foot.T[..., None]  # (3, L, 1): the foot in its link's frame
    qt = np.ascontiguousarray(q.T)  # (nq, N)
    passes, residual = 1, math.inf
    while True:
        R, p = wb.joint_frames(qt.T, base)
        Rl = R[:, :, st.link]
        centres = Rl[:, 0] * foot[0] + Rl[:, 1] * foot[1] + Rl[:, 2] * foot[2] + p[:, st.link]
        if n > 1:
            theta, ang = _increments(Rl)
            D = _rolled(_x(theta, rn_inc), sup, start)
        else:
            D = np.zeros(centres.shape)
        lo = D[:, last_at[0], last_at[1]] * seen
        feet = planT + np.where(sw, lo * keep, D)
        err = feet - centres
        residual = float(np.abs(err).max())
        if residual <= tol or passes >= max_passes or n < 2:
            break
        # Jacobians (3, L, M, N): world axes a, J_p = a × (c − o) (prismatic: a), J_ω = a
        a = (R[:, 0] * ax_j[0] + R[:, 1] * ax_j[1] + R[:, 2] * ax_j[2])[:, jj]
        Jw = a * rev
        J = np.where(rev, _x(a, centres[:, :, None] - p[:, jj]), a * lin_ok)
        J += _x(rn[:, :, None], Jw) * sup[:, None]  # + K = r [n]ₓ J_ω in stance
        A = np.einsum("ilmn,klmn->ikln", J, J)
        A[0, 0] += 1e-14
        A[1, 1] += 1e-14
        A[2, 2] += 1e-14
        A_inv = _inv_sym3(A)  # J⁺ = Jᵀ (J Jᵀ + λ I)⁻¹
        small = ang < 1e-3
        a_ = np.where(small, 1.0, ang)
        exact = 1.0 / a_**2 - (1.0 + np.cos(a_)) / (2.0 * a_ * np.sin(a_))
        beta = np.where(small, 1.0 / 12.0 + ang * ang / 720.0, exact)
        rhs = err
        sweeps = 1 if passes == 1 else _SWEEPS  # the first step is far from quadratic anyway
        for sweep in range(sweeps + 1):
            y = A_inv[:, 0] * rhs[0] + A_inv[:, 1] * rhs[1] + A_inv[:, 2] * rhs[2]
            dq = J[0] * y[0, :, None] + J[1] * y[1, :, None] + J[2] * y[2, :, None]  # (L, M, N)
            if sweep == sweeps:
                break
            phi = np.einsum("ilmn,lmn->iln", Jw, dq) * sup  # foot-link rotations δφ (stance)
            dif = phi[..., 1:] - phi[..., :-1]
            d_theta = dif - 0.5 * _x(theta, phi[..., 1:] + phi[..., :-1])
            d_theta += beta * _x(theta, _x(theta, dif))
            dD = _rolled(_x(d_theta, rn_inc), sup, start)
            lo = (D + dD)[:, last_at[0], last_at[1]] * seen
            rhs = np.where(sw, planT + lo * keep - centres, err + dD - _x(phi, rn))
        for m in range(jj.shape[1]):
            ok = valid[:, m]
            qt[jj[ok, m]] += dq[ok, m]
        passes += 1
    q = np.ascontiguousarray(qt.T)
    margin = np.minimum(q - wb.lower, wb.upper - q)
    for arr in (q, margin):
        arr.setflags(write=False)
    ik = BodyIK(q, ik.reached, ik.excess, margin, ik.leg_names)
    back = (2, 1, 0)
    T = poses_of(R, p)
    feet_out, d_out = (np.ascontiguousarray(x.transpose(back)) for x in (feet, D))
    return feet_out, q, ik, passes, residual, T, d_out


def se2_pose(t: Any, velocity: Any) -> np.ndarray:
    """Exact SE(2) integration of a constant body twist from the origin.

    Args:
        t: Times (...) in [s].
        velocity: ``(vx, vy, wz)``: body-frame velocity [m/s] and yaw rate [rad/s].

    Returns:
        (..., 3) ``x, y`` [m] and yaw ``ψ`` [rad]:
        ``x = (vx sin ψ − vy (1 − cos ψ)) / ωz``, ``y = (vx (1 − cos ψ) + vy sin ψ) / ωz``,
        ``ψ = ωz t`` (the limits ``vx t, vy t`` for ωz = 0).

    """
    vx, vy, w = (float(v) for v in velocity)
    tt = np.asarray(t, dtype=float)
    psi = w * tt
    half = psi / 2.0
    sinc = np.sinc(half / np.pi)  # sin(ψ/2)/(ψ/2)
    s = tt * sinc * np.cos(half)  # sin(ψ)/ω
    c = tt * sinc * np.sin(half)  # (1 − cos ψ)/ω
    out = np.empty(tt.shape + (3,))
    out[..., 0] = vx * s - vy * c
    out[..., 1] = vx * c + vy * s
    out[..., 2] = psi
    return out
