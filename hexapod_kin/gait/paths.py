"""One leg's step cycle: stance on the ground, swing through the air.

:func:`foot_path` is a pure function of the gait phase (stance: a straight line on the ground,
front to back; swing: a lifted half ellipse or cycloid, back to front) with step length,
height and duty factor, so that gait tables call it per leg with their phase offsets;
:func:`foot_step` turns one cycle into joint angles by IK.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any, Literal

import numpy as np

from .._fields import fields_dict
from ..exceptions import ParameterError, positive
from ..motion import default_stance, read_only, track

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

    Phase 0 is touchdown at the front: in stance (``phase < duty_factor``) the foot moves at
    constant speed from ``center + L/2·u`` to ``center − L/2·u`` (``u`` the unit horizontal
    ``direction`` of travel); in swing it returns through a half ellipse (semi-axes L/2 and
    ``height``) or a cycloid (zero velocity at lift-off and touchdown).

    ``phase`` in cycles (any real, taken modulo 1); ``center`` (3,) [m] (its z is the
    ground); ``length`` L and ``height`` [m] (>= 0); ``duty_factor`` in (0, 1); ``direction``
    (2,) normalised here. Returns (..., 3) positions in [m], the shape of ``phase`` plus 3.

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

    Per sample: ``t`` [s], ``phase`` in cycles (0 = touchdown), ``stance``, planned ``foot``
    [m], ``q`` by IK, ``qdot`` by finite differences, ``reached`` (IK reached the plan),
    ``foot_actual`` FK(q) [m]. ``within_limits``: every sample inside the joint position
    limits; ``max_joint_step``: largest |Δq| between samples [rad]/[m] (continuity).
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
        return fields_dict(self, *(f.name for f in fields(self)))

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

    The step as in :func:`foot_path` (``center`` default: the foot at
    :func:`default_stance`); ``dt`` and ``duration`` (of one cycle) in [s]; ``cycles`` >= 1;
    ``phase_offset`` in cycles at t = 0 (gait tables set one per leg); ``q0``: joints near the
    first sample (IK branch, warm start).

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

    ``n ∝ (−∂h/∂x, −∂h/∂y, 1)``, each slope the smaller of the forward and backward difference
    over ``step`` [m] (min-mod: exact on a plane, the flat side at an edge); ``ẑ`` where the
    ground is undefined.
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

    Axis-angle from the trace and the skew part (angles below π).
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

    A sphere of radius r rolling without slip on a plane of normal n moves its centre by
    ``ω × (r n)``; discretely ``D_i = Σ_{k = s}^{i − 1} θ_k × (r n)`` from the stance's first
    sample s (``θ_k``: :func:`rotation_increments` of the foot frame), 0 in swing. The contact
    point slips by ``c_i − c_s − D_i``.

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


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``u × v`` over the last axis (3), written out (faster than np.cross on small arrays)."""
    out = np.empty(np.broadcast_shapes(u.shape, v.shape))
    out[..., 0] = u[..., 1] * v[..., 2] - u[..., 2] * v[..., 1]
    out[..., 1] = u[..., 2] * v[..., 0] - u[..., 0] * v[..., 2]
    out[..., 2] = u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]
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

    Each pass solves the targets by ``wb.body_ik`` (the first: the plan); the rolling ``D(q)``
    of the solution (:func:`rolling_offsets`) gives the next targets, ``plan + D`` in stance and
    ``plan + D_lift-off·(1 − blend)`` in swing, until ``max|targets − feet(q)| ≤ tol`` [m],
    ``max_passes``, or a foot out of reach. Anderson(1) mixing per foot and sample (2-3× fewer
    passes).

    Returns:
        ``(feet, q, ik, passes, residual [m], joint poses of q or None, D)``: the targets
        of the last pass, D the rolling of q's own foot rotations (by FK).

    """
    ik = wb.body_ik(base, plan, q_prev=q0, times=t, strict=False)
    q = np.asarray(ik.q)
    if rad == 0.0:
        return plan, q, ik, 1, 0.0, None, np.zeros(plan.shape)
    sup = np.asarray(support, dtype=bool)
    keep = np.where(swing, 1.0 - np.asarray(blend, dtype=float), 0.0)[..., None]
    x = np.asarray(plan, dtype=float)
    prev: tuple[np.ndarray, np.ndarray] | None = None
    passes = 1
    while True:
        T = wb.joint_poses(q, base)
        D = rolling_offsets(T[:, wb._foot_joint, :3, :3], sup, normals, rad)
        feet = plan + np.where(np.asarray(swing)[..., None], last_stance_value(D, sup) * keep, D)
        residual = float(np.abs(feet - wb.feet_of(T)).max())
        if residual <= tol or passes >= max_passes or len(sup) < 2 or not ik.reached.all():
            break
        f = feet - x
        nxt = feet
        if prev is not None:  # Anderson(1) per foot and sample: x ← g − γ (g − g_prev)
            df = f - prev[0]
            den = np.einsum("...i,...i->...", df, df)
            gamma = np.einsum("...i,...i->...", f, df) / np.where(den > 0.0, den, 1.0)
            nxt = feet - gamma[..., None] * (feet - prev[1])
        prev, x = (f, feet), nxt
        ik = wb.body_ik(base, x, q_prev=q0, times=t, strict=False)
        q = np.asarray(ik.q)
        passes += 1
    return np.ascontiguousarray(feet), q, ik, passes, residual, T, D


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
