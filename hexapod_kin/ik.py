"""Inverse kinematics: closed forms for the leg families, damped least squares for any chain.

Closed forms (:func:`analytic`, :func:`analytic_batch`) are chosen from the *structure* of the
Khalil table (the pattern of σ, α, d, r), never from a preset name:

``"coxa_tibia"`` (2 DOF, seed 002)
    ``R(α=0, d=0, r=r1) · R(α=±π/2, d=l1, r=0) · F(d=l2, r=0)``; foot
    ``Rz(φ1)·[l1 + l2 cos φ2, 0, ±l2 sin φ2] + [0, 0, r1]``. A 2-DOF leg reaches a *surface*:
    a target off it (farther than ``tol`` from it) has no solution. The tibia angle comes from
    ``atan2`` of both coordinates, so its sign is right (the seed's ``θ2 = 180° − β`` loses it:
    ``(0°, −30°)`` and ``(0°, +30°)`` give the same ``β``). Up to 2 solutions (hip ± π).
``"leg3"`` (3 DOF hip/knee/ankle, seeds 000/001/003)
    ``R(0, 0, r1) · R(±π/2, l1, 0) · R(0, l2, 0) · F(d=l3, r=0)``. Up to 4 solutions: hip
    ``atan2(y, x)`` or that ``+ π`` (the leg reaching back over the hip axis), each with both
    knee branches (ankle ``±acos``).
``"scara"`` (seed 003)
    ``R(0, 0, r1) · R(0, d2, r2) · R(0, d3, r3) · P(α ∈ {0, π}, d=0) · F(d=0, r=0)``. Target
    ``(x, y, z)`` or ``(x, y, z, yaw)``: ``yaw`` [rad] is the angle of the tool frame's x axis
    in the base xy-plane. A position alone leaves θ3 free (it only turns the tool); then the
    solutions use ``θ3 = 0`` (joint value). Up to 2 solutions (both elbow branches); the
    prismatic value follows from z.

Joint angle offsets (``θ`` of revolute rows) and the base height ``r1`` are allowed. Revolute
results are wrapped to ``(−π, π]``; they are returned whether or not they are inside the joint
limits unless ``within_limits=True`` (then each is shifted by 2π if that helps, else dropped).

The numerical solver :func:`solve` works on any loaded model (Pinocchio). It is a
Levenberg–Marquardt damped-least-squares loop (damping ``λ² = μ(‖e‖² + w̄)``, adapted step by
step; a step is kept only if it lowers the error, so the residual history decreases strictly),
with a step cap, joint limits (continuous joints — range ≥ 2π — wrap, the others are clamped and
a joint blocked at a limit is frozen), stall detection, restarts, and a status with a reason.
The loop runs compiled (numba, on :mod:`hexapod_kin._kernels`); the final residual is
recomputed with Pinocchio.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from .exceptions import ConfigurationError, IKError, ParameterError
from .params import Chain

__all__ = [
    "FAMILIES",
    "STATUSES",
    "AnalyticBatch",
    "IKResult",
    "LegFamily",
    "analytic",
    "analytic_batch",
    "detect_family",
    "dls_step",
    "sigma_bounds",
    "solve",
    "solve_many",
]

Status = Literal["converged", "unreachable", "joint_limits", "singular", "not_converged"]
STATUSES: tuple[str, ...] = (
    "converged", "unreachable", "joint_limits", "singular", "not_converged"
)
FAMILIES: tuple[str, ...] = ("coxa_tibia", "leg3", "scara")

_HALF_PI = 0.5 * math.pi
_ANG_TOL = 1e-12


def _is(value: float, target: float, tol: float = _ANG_TOL) -> bool:
    return abs(value - target) <= tol


def _angle_is(value: float, target: float) -> bool:
    return abs(math.remainder(value - target, 2 * math.pi)) <= _ANG_TOL


# ============================================================================ family detection
@dataclass(frozen=True)
class LegFamily:
    """A chain recognised as one of the closed-form families (see the module docstring).

    Attributes:
        family: ``"coxa_tibia"``, ``"leg3"`` or ``"scara"``.
        chain: The chain.
        lengths: The family's lengths in [m]: ``(l1, l2)``, ``(l1, l2, l3)`` or ``(d2, d3)``.
        height: Height of the first horizontal plane ``r1`` (SCARA: ``r1 + r2 + r3``) in [m].
        sign: ``sin α2`` (±1) of the legs; ``cos α4`` (±1) of the SCARA's prismatic row.
        offsets: The joints' θ (revolute) or r (prismatic) constants, one per joint.
        yaw_offset: SCARA only: tool yaw added by the constant rows, in [rad].
        yaw_sign: SCARA only: ±1 factor of those constant rows' contribution.

    """

    family: str
    chain: Chain
    lengths: tuple[float, ...]
    height: float
    sign: float
    offsets: tuple[float, ...]
    yaw_offset: float = 0.0

    @property
    def nq(self) -> int:
        """Number of joints."""
        return self.chain.nq

    @property
    def max_solutions(self) -> int:
        """Number of solution slots of :func:`analytic_batch` (2, 4 or 2)."""
        return {"coxa_tibia": 2, "leg3": 4, "scara": 2}[self.family]

    @property
    def target_size(self) -> tuple[int, ...]:
        """Accepted target lengths: (3,) for legs, (3, 4) for the SCARA (with yaw)."""
        return (3, 4) if self.family == "scara" else (3,)

    @property
    def scale(self) -> float:
        """A length scale of the chain in [m] (sum of |d| and |r|), for tolerances."""
        s = sum(abs(r.d) + abs(r.r) for r in self.chain.rows)
        return s if s > 0 else 1.0


def _chain_of(chain: Any) -> Chain:
    if isinstance(chain, Chain):
        return chain
    params = getattr(chain, "params", None)
    if isinstance(params, Chain):
        base, tip = getattr(chain, "base", params.base), getattr(chain, "tip", params.tip)
        if base != params.base or tip != params.tip:
            raise IKError(
                f"chain: the model's sub-chain {base!r} -> {tip!r} is not the table's "
                f"{params.base!r} -> {params.tip!r}; closed forms need the whole table "
                "(use ik.solve for sub-chains)"
            )
        return params
    raise IKError(
        f"chain={chain!r}: closed-form IK needs a Khalil table (a Chain, or a model loaded from "
        "one); this source has none (URDF) — use hexapod_kin.ik.solve(model, target)"
    )


def detect_family(chain: Any) -> LegFamily:
    """Recognise the closed-form family of a chain from its table pattern.

    Args:
        chain: A :class:`~hexapod_kin.params.Chain` or a model loaded from one.

    Returns:
        The :class:`LegFamily`.

    Raises:
        IKError: If the table matches no family (the message shows the pattern and the
            families), or the model has no table.

    """
    ch = _chain_of(chain)
    rows = ch.rows
    sig = tuple(str(r.sigma)[0].upper() for r in rows)
    offsets = tuple(
        rows[i].theta if rows[i].sigma == "revolute" else rows[i].r for i in ch.joint_rows
    )
    r1 = rows[0]
    base_ok = _is(r1.alpha, 0.0) and _is(r1.d, 0.0)
    if sig == ("R", "R", "F") and base_ok:
        a, f = rows[1], rows[2]
        if (
            _is(abs(a.alpha), _HALF_PI) and _is(a.r, 0.0) and _is(f.r, 0.0)
            and abs(f.d) > 0
        ):
            return LegFamily(
                "coxa_tibia", ch, (a.d, f.d), r1.r, math.copysign(1.0, a.alpha), offsets
            )
    if sig == ("R", "R", "R", "F") and base_ok:
        a, b, f = rows[1], rows[2], rows[3]
        if (
            _is(abs(a.alpha), _HALF_PI) and _is(a.r, 0.0) and _is(b.alpha, 0.0) and _is(b.r, 0.0)
            and _is(f.r, 0.0) and abs(b.d) > 0 and abs(f.d) > 0
        ):
            return LegFamily(
                "leg3", ch, (a.d, b.d, f.d), r1.r, math.copysign(1.0, a.alpha), offsets
            )
    if sig == ("R", "R", "R", "P", "F") and base_ok:
        b, c, p, f = rows[1], rows[2], rows[3], rows[4]
        flip = _angle_is(p.alpha, math.pi)
        f_flip = _angle_is(f.alpha, math.pi)
        if (
            _is(b.alpha, 0.0) and _is(c.alpha, 0.0) and (flip or _angle_is(p.alpha, 0.0))
            and _is(p.d, 0.0) and _is(f.d, 0.0) and _is(f.r, 0.0)
            and (f_flip or _angle_is(f.alpha, 0.0)) and abs(b.d) > 0 and abs(c.d) > 0
        ):
            c4 = -1.0 if flip else 1.0
            c5 = -1.0 if f_flip else 1.0
            return LegFamily(
                "scara",
                ch,
                (b.d, c.d),
                r1.r + b.r + c.r,
                c4,
                offsets,
                yaw_offset=c4 * (p.theta + c5 * f.theta),
            )
    pattern = " ".join(
        f"{s}(α={r.alpha:.4g}, d={r.d:.4g}, r={r.r:.4g})" for s, r in zip(sig, rows)
    )
    raise IKError(
        f"chain {ch.name!r} has no closed-form IK: its table {pattern} matches none of the "
        f"families {list(FAMILIES)} (coxa_tibia: R(0,0,r1) R(±π/2,l1,0) F(l2,r=0); leg3: "
        "R(0,0,r1) R(±π/2,l1,0) R(0,l2,0) F(l3,r=0); scara: R(0,0,r1) R(0,d2) R(0,d3) "
        "P(α∈{0,π},d=0) F(d=0,r=0)); use hexapod_kin.ik.solve(model, target)"
    )


# ============================================================================ closed forms
@dataclass(frozen=True)
class AnalyticBatch:
    """Closed-form solutions of many targets, in fixed-shape arrays (read-only).

    Attributes:
        q: (N, K, n) joint values; slot ``k`` of target ``i`` is meaningful where
            ``valid[i, k]`` (elsewhere NaN). K is 2 (coxa_tibia, scara) or 4 (leg3); slots
            keep a fixed branch meaning (see :func:`analytic_batch`).
        valid: (N, K) True where the slot holds a solution.
        family: The detected family name.

    """

    q: np.ndarray
    valid: np.ndarray
    family: str

    @property
    def reachable(self) -> np.ndarray:
        """(N,) True where a target has at least one solution."""
        return np.asarray(self.valid.any(axis=1))


def _wrap(a: np.ndarray) -> np.ndarray:
    """Wrap angles to (−π, π]."""
    out = np.remainder(a + np.pi, 2 * np.pi) - np.pi
    out[out == -np.pi] = np.pi
    return out


def _targets(fam: LegFamily, target: Any) -> tuple[np.ndarray, bool]:
    try:
        arr = np.asarray(target, dtype=np.float64)
    except (TypeError, ValueError):
        raise IKError(f"target={target!r} is not an array of numbers") from None
    single = arr.ndim == 1
    if single:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] not in fam.target_size:
        allowed = " or ".join(f"({k},)/(N, {k})" for k in fam.target_size)
        raise IKError(
            f"target has shape {np.shape(target)}; family {fam.family!r} takes {allowed}"
            + (" — (x, y, z[, yaw]) in [m], [rad]" if fam.family == "scara" else " in [m]")
        )
    if not np.all(np.isfinite(arr)):
        raise IKError(f"target={np.asarray(target).tolist()!r} contains non-finite values")
    return np.ascontiguousarray(arr), single


def analytic_batch(
    chain: Any, targets: Any, *, tol: float = 1e-9, within_limits: bool = False
) -> AnalyticBatch:
    """All closed-form solutions of N targets as fixed-shape arrays plus a validity mask.

    Slot meanings: coxa_tibia ``[hip toward the target, hip reversed (φ1 + π)]``; leg3
    ``[toward/ankle +, toward/ankle −, reversed/ankle +, reversed/ankle −]``; scara
    ``[elbow +, elbow −]``. Coincident branches (at a boundary) both stay valid.

    Args:
        chain: A :class:`~hexapod_kin.params.Chain` or a model loaded from one.
        targets: (N, 3) foot positions in [m] in the base frame (SCARA: (N, 3) or (N, 4) with
            yaw [rad]); a single (3,) target is accepted as N = 1.
        tol: Relative tolerance (× the chain's length scale) of the reachability tests; a
            target this close outside the workspace is solved on its boundary.
        within_limits: If True, invalidate solutions outside the joint limits (revolute
            values are first shifted by ±2π when that brings them inside).

    Returns:
        An :class:`AnalyticBatch`.

    Raises:
        IKError: No closed form for this chain; bad or non-finite targets.

    """
    fam = detect_family(chain)
    x, _ = _targets(fam, targets)
    tol_abs = float(tol) * fam.scale
    if _HAVE_NUMBA and not within_limits and fam.family in ("coxa_tibia", "leg3"):
        leg3 = fam.family == "leg3"
        qk = np.empty((x.shape[0], fam.max_solutions, fam.nq))
        vk = np.empty((x.shape[0], fam.max_solutions), dtype=np.bool_)
        ls = fam.lengths + (1.0,) * (3 - len(fam.lengths))
        _legs_kernel(
            x, leg3, ls[0], ls[1], ls[2], fam.height, fam.sign, tol_abs,
            np.asarray(fam.offsets, dtype=float), qk, vk,
        )
        qk.setflags(write=False)
        vk.setflags(write=False)
        return AnalyticBatch(q=qk, valid=vk, family=fam.family)
    with np.errstate(invalid="ignore", divide="ignore"):
        if fam.family == "coxa_tibia":
            q, valid = _ik_coxa_tibia(fam, x, tol_abs)
        elif fam.family == "leg3":
            q, valid = _ik_leg3(fam, x, tol_abs)
        else:
            q, valid = _ik_scara(fam, x)
    off = np.asarray(fam.offsets)
    revolute = np.array([s == "revolute" for s in fam.chain.sigmas])
    q = q - off
    q[..., revolute] = _wrap(q[..., revolute])
    if within_limits:
        lo, hi = fam.chain.lower(), fam.chain.upper()
        for j in np.flatnonzero(revolute):
            for shift in (2 * np.pi, -2 * np.pi):
                moved = q[..., j] + shift
                fix = ((q[..., j] < lo[j]) | (q[..., j] > hi[j])) & (moved >= lo[j]) & (
                    moved <= hi[j]
                )
                q[..., j] = np.where(fix, moved, q[..., j])
        valid &= np.all((q >= lo - 1e-12) & (q <= hi + 1e-12), axis=-1)
    q[~valid] = np.nan
    q.setflags(write=False)
    valid.setflags(write=False)
    return AnalyticBatch(q=q, valid=valid, family=fam.family)


def _ik_coxa_tibia(fam: LegFamily, x: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    l1, l2 = fam.lengths
    n = x.shape[0]
    h = np.hypot(x[:, 0], x[:, 1])
    phi = np.arctan2(x[:, 1], x[:, 0])
    w = (x[:, 2] - fam.height) * fam.sign  # = l2 sin φ2
    q = np.empty((n, 2, 2))
    valid = np.empty((n, 2), dtype=bool)
    for k, hs in enumerate((1.0, -1.0)):
        u = hs * h - l1  # = l2 cos φ2
        dist = np.hypot(u, w)
        valid[:, k] = np.abs(dist - abs(l2)) <= tol
        q[:, k, 0] = phi if hs > 0 else phi + np.pi
        q[:, k, 1] = np.arctan2(w / l2, u / l2)
    return q, valid


def _ik_leg3(fam: LegFamily, x: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    l1, l2, l3 = fam.lengths
    n = x.shape[0]
    h = np.hypot(x[:, 0], x[:, 1])
    phi = np.arctan2(x[:, 1], x[:, 0])
    w = (x[:, 2] - fam.height) * fam.sign  # = l2 s2 + l3 s23
    q = np.empty((n, 4, 3))
    valid = np.empty((n, 4), dtype=bool)
    eps = tol * (abs(l2) + abs(l3)) / abs(l2 * l3)
    for k, hs in enumerate((1.0, -1.0)):
        u = hs * h - l1  # = l2 c2 + l3 c23
        c3 = (u * u + w * w - l2 * l2 - l3 * l3) / (2.0 * l2 * l3)
        ok = np.abs(c3) <= 1.0 + eps
        c3 = np.clip(c3, -1.0, 1.0)
        s3 = np.sqrt(1.0 - c3 * c3)
        base = np.arctan2(w, u)
        for b, sgn in enumerate((1.0, -1.0)):
            slot = 2 * k + b
            s = sgn * s3
            q[:, slot, 0] = phi if hs > 0 else phi + np.pi
            q[:, slot, 2] = np.arctan2(s, c3)
            q[:, slot, 1] = base - np.arctan2(l3 * s, l2 + l3 * c3)
            valid[:, slot] = ok
    return q, valid


def _ik_scara(fam: LegFamily, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    d2, d3 = fam.lengths
    n = x.shape[0]
    rr = x[:, 0] ** 2 + x[:, 1] ** 2
    c2 = (rr - d2 * d2 - d3 * d3) / (2.0 * d2 * d3)
    eps = 1e-9 * (abs(d2) + abs(d3)) ** 2 / abs(d2 * d3)
    ok = np.abs(c2) <= 1.0 + eps
    c2 = np.clip(c2, -1.0, 1.0)
    s2 = np.sqrt(1.0 - c2 * c2)
    base = np.arctan2(x[:, 1], x[:, 0])
    q = np.empty((n, 2, 4))
    valid = np.empty((n, 2), dtype=bool)
    c4 = fam.sign
    prism = (x[:, 2] - fam.height) * c4  # = r4 + q4 along ±z
    for b, sgn in enumerate((1.0, -1.0)):
        s = sgn * s2
        t2 = np.arctan2(s, c2)
        t1 = base - np.arctan2(d3 * s, d2 + d3 * c2)
        q[:, b, 0] = t1
        q[:, b, 1] = t2
        if x.shape[1] == 4:
            # yaw = φ1 + φ2 + φ3 + yaw_offset → φ3 (offset θ3 is removed later with the others)
            q[:, b, 2] = x[:, 3] - fam.yaw_offset - t1 - t2
        else:
            q[:, b, 2] = fam.offsets[2]  # joint value θ3 = 0 after the offset is removed
        q[:, b, 3] = prism
        valid[:, b] = ok
    return q, valid



# -------------------------------------------------------------------- compiled closed forms
from ._kernels import HAVE_NUMBA as _HAVE_NUMBA  # noqa: E402
from ._kernels import njit as _njit  # noqa: E402
from ._kernels import prange as _prange  # noqa: E402


@_njit(cache=True, nogil=True, inline="always")
def _wrap1(a: float) -> float:  # pragma: no cover - compiled
    """Wrap to (−π, π] by adding/subtracting 2π (inputs are within a few turns)."""
    while a > math.pi:
        a -= 2.0 * math.pi
    while a <= -math.pi:
        a += 2.0 * math.pi
    return a


@_njit(cache=True, parallel=True, nogil=True)
def _legs_kernel(
    x: np.ndarray, fam3: bool, l1: float, l2: float, l3: float, height: float, sign: float,
    tol: float, off: np.ndarray, q: np.ndarray, valid: np.ndarray,
) -> None:  # pragma: no cover - compiled
    """coxa_tibia (fam3 False) and leg3 (fam3 True) closed forms, offsets removed, wrapped."""
    n = x.shape[0]
    eps = tol * (abs(l2) + abs(l3)) / abs(l2 * l3) if fam3 else 0.0
    nan = np.nan
    for i in _prange(n):
        h = math.sqrt(x[i, 0] * x[i, 0] + x[i, 1] * x[i, 1])
        phi = math.atan2(x[i, 1], x[i, 0])
        w = (x[i, 2] - height) * sign
        for k in range(2):
            u = (h if k == 0 else -h) - l1
            p1 = _wrap1((phi if k == 0 else phi + math.pi) - off[0])
            if not fam3:
                ok = abs(math.sqrt(u * u + w * w) - abs(l2)) <= tol
                valid[i, k] = ok
                if ok:
                    q[i, k, 0] = p1
                    q[i, k, 1] = _wrap1(math.atan2(w / l2, u / l2) - off[1])
                else:
                    q[i, k, 0] = nan
                    q[i, k, 1] = nan
                continue
            c3 = (u * u + w * w - l2 * l2 - l3 * l3) / (2.0 * l2 * l3)
            ok = abs(c3) <= 1.0 + eps
            valid[i, 2 * k] = ok
            valid[i, 2 * k + 1] = ok
            if not ok:
                for b in range(2):
                    for j in range(3):
                        q[i, 2 * k + b, j] = nan
                continue
            c3 = min(max(c3, -1.0), 1.0)
            s3 = math.sqrt(1.0 - c3 * c3)
            base = math.atan2(w, u)
            a3 = math.atan2(s3, c3)
            a2 = math.atan2(l3 * s3, l2 + l3 * c3)
            q[i, 2 * k, 0] = p1
            q[i, 2 * k, 1] = _wrap1(base - a2 - off[1])
            q[i, 2 * k, 2] = _wrap1(a3 - off[2])
            q[i, 2 * k + 1, 0] = p1
            q[i, 2 * k + 1, 1] = _wrap1(base + a2 - off[1])
            q[i, 2 * k + 1, 2] = _wrap1(-a3 - off[2])


def analytic(
    chain: Any, target: Any, *, tol: float = 1e-9, within_limits: bool = False
) -> Any:
    """All closed-form solutions for one target (k×n array, k ≥ 0) or a list for N targets.

    Coincident solutions (e.g. the two knee branches of a stretched leg) are returned once.

    Args:
        chain: A :class:`~hexapod_kin.params.Chain` or a model loaded from one (the family is
            recognised from the table; see the module docstring).
        target: Foot position (3,) in [m] in the base frame, or (N, 3); SCARA: (3,) or
            (4,) = (x, y, z, yaw [rad]).
        tol: Relative reachability tolerance (see :func:`analytic_batch`).
        within_limits: Keep only solutions inside the joint limits.

    Returns:
        A (k, n) array for one target (k = 0 when unreachable); a list of those for (N, ·).

    Raises:
        IKError: No closed form for this chain; bad or non-finite target.

    Example:
        >>> from hexapod_kin import robots, ik
        >>> import math
        >>> p = [10 + 5 * math.cos(math.radians(30)), 0.0, -2.5]  # seed 002, P1
        >>> ik.analytic(robots.coxa_tibia_leg(), p).round(4)
        array([[ 0.    , -0.5236],
               [ 3.1416, -2.618 ]])

    """
    batch = analytic_batch(chain, target, tol=tol, within_limits=within_limits)
    single = np.asarray(target).ndim == 1
    out = []
    for qi, vi in zip(batch.q, batch.valid):
        sols = qi[vi]
        keep: list[np.ndarray] = []
        for s in sols:
            if not any(np.max(np.abs(_wrap_diff(s, k))) <= 1e-12 for k in keep):
                keep.append(s)
        arr = np.array(keep, dtype=float).reshape(len(keep), qi.shape[-1])
        out.append(arr)
    return out[0] if single else out


def _wrap_diff(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.remainder(a - b + np.pi, 2 * np.pi) - np.pi


# ============================================================================ numerical IK
@dataclass(frozen=True)
class IKResult:
    """Result of :func:`solve` (arrays are read-only).

    Attributes:
        q: Joint values (nq,) in [rad]/[m] — the solution, or the best configuration found.
        status: ``"converged"``, ``"unreachable"``, ``"joint_limits"``, ``"singular"`` or
            ``"not_converged"``.
        error: ‖target − FK(q)‖ in [m], recomputed with Pinocchio.
        iterations: Accepted steps of the returned attempt.
        history: Residual ‖e‖ [m] after each accepted step of the returned attempt (starts
            with the initial residual; strictly decreasing).
        position: FK(q) in [m] (Pinocchio).
        target: The target in [m].
        attempts: How many starts were tried (1 + restarts used).
        reason: One sentence explaining the status.
        distance: For ``"unreachable"`` / ``"joint_limits"``: distance in [m] from the target to
            the nearest reachable point found (= ``error``); else 0.
        nearest: For ``"unreachable"`` / ``"joint_limits"``: that point (3,); else the target.
        sigma_min: Smallest singular value of the position Jacobian at ``q`` [m/rad].

    """

    q: np.ndarray
    status: Status
    error: float
    iterations: int
    history: np.ndarray
    position: np.ndarray
    target: np.ndarray
    attempts: int
    reason: str
    distance: float = 0.0
    nearest: np.ndarray = field(default_factory=lambda: np.zeros(3))
    sigma_min: float = float("nan")

    @property
    def converged(self) -> bool:
        """True when ``status == "converged"``."""
        return self.status == "converged"

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary."""
        return {
            "status": self.status,
            "q": [float(v) for v in self.q],
            "error": float(self.error),
            "iterations": int(self.iterations),
            "attempts": int(self.attempts),
            "position": [float(v) for v in self.position],
            "target": [float(v) for v in self.target],
            "distance": float(self.distance),
            "nearest": [float(v) for v in self.nearest],
            "sigma_min": float(self.sigma_min),
            "reason": self.reason,
            "history": [float(v) for v in self.history],
        }


def dls_step(jac: Any, error: Any, damping: float) -> np.ndarray:
    """One damped-least-squares step ``Δq = Jᵀ(JJᵀ + λ²I)⁻¹ e`` (pure function).

    Args:
        jac: Position Jacobian (3, n) in [m/rad].
        error: Task error ``target − p`` (3,) in [m].
        damping: ``λ² ≥ 0`` in [m²].

    Returns:
        Δq (n,) in [rad]/[m].

    """
    j = np.asarray(jac, dtype=float)
    e = np.asarray(error, dtype=float)
    n = j.shape[1]
    if n <= j.shape[0]:
        return np.asarray(np.linalg.solve(j.T @ j + damping * np.eye(n), j.T @ e))
    return np.asarray(j.T @ np.linalg.solve(j @ j.T + damping * np.eye(j.shape[0]), e))


# -------------------------------------------------------------------- compiled loop
from ._kernels import HAVE_NUMBA, ChainArrays, fk_jac_into, njit  # noqa: E402


@njit(cache=True, nogil=True)
def _solve_spd(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> bool:  # pragma: no cover
    """Cholesky solve of a small SPD system in place of ``a``; False if not SPD."""
    n = a.shape[0]
    for j in range(n):
        s = a[j, j]
        for k in range(j):
            s -= a[j, k] * a[j, k]
        if not s > 0.0:
            return False
        d = math.sqrt(s)
        a[j, j] = d
        for i in range(j + 1, n):
            t = a[i, j]
            for k in range(j):
                t -= a[i, k] * a[j, k]
            a[i, j] = t / d
    for i in range(n):
        t = b[i]
        for k in range(i):
            t -= a[i, k] * out[k]
        out[i] = t / a[i, i]
    for i in range(n - 1, -1, -1):
        t = out[i]
        for k in range(i + 1, n):
            t -= a[k, i] * out[k]
        out[i] = t / a[i, i]
    return True


@njit(cache=True, nogil=True)
def _dls_into(
    jac: np.ndarray, e: np.ndarray, lam2: float, free: np.ndarray, dq: np.ndarray,
    work: np.ndarray, rhs: np.ndarray, sol: np.ndarray,
) -> bool:  # pragma: no cover - compiled
    """Δq = Jfᵀ(JfJfᵀ + λ²I)⁻¹e (n > 3) or (JfᵀJf + λ²I)⁻¹Jfᵀe (n ≤ 3); frozen joints get 0."""
    n = jac.shape[1]
    if n <= 3:
        for i in range(n):
            g = 0.0
            if free[i]:
                for r in range(3):
                    g += jac[r, i] * e[r]
            rhs[i] = g
            for k in range(n):
                s = 0.0
                if free[i] and free[k]:
                    for r in range(3):
                        s += jac[r, i] * jac[r, k]
                work[i, k] = s
            work[i, i] += lam2
        ok = _solve_spd(work[:n, :n], rhs[:n], sol[:n])
        for i in range(n):
            dq[i] = sol[i] if free[i] else 0.0
        return ok
    for a in range(3):
        rhs[a] = e[a]
        for b in range(3):
            s = 0.0
            for k in range(n):
                if free[k]:
                    s += jac[a, k] * jac[b, k]
            work[a, b] = s
        work[a, a] += lam2
    ok = _solve_spd(work[:3, :3], rhs[:3], sol[:3])
    for k in range(n):
        if free[k]:
            dq[k] = jac[0, k] * sol[0] + jac[1, k] * sol[1] + jac[2, k] * sol[2]
        else:
            dq[k] = 0.0
    return ok


@njit(cache=True, nogil=True)
def _limit_into(
    q: np.ndarray, lower: np.ndarray, upper: np.ndarray, cont: np.ndarray, use_limits: bool
) -> None:  # pragma: no cover - compiled
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
def _lm_kernel(
    rot: np.ndarray, trans: np.ndarray, axis: np.ndarray, kind: np.ndarray, col: np.ndarray,
    target: np.ndarray, q: np.ndarray, lower: np.ndarray, upper: np.ndarray, cont: np.ndarray,
    use_limits: bool, tol: float, max_iter: int, step_cap: np.ndarray, wbar: float,
    hist: np.ndarray, free: np.ndarray, mu0: float,
) -> tuple[int, int]:  # pragma: no cover - compiled
    """Levenberg–Marquardt DLS loop; q updated in place.

    Returns (accepted steps, code): code 0 converged, 1 stalled, 2 iteration cap.
    """
    n = q.shape[0]
    scratch = np.empty((6, max(rot.shape[0], 1)))
    p = np.empty(3)
    jac = np.empty((3, n))
    jac_t = np.empty((3, n))
    e = np.empty(3)
    dq = np.empty(n)
    qn = np.empty(n)
    work = np.empty((max(n, 3), max(n, 3)))
    rhs = np.empty(max(n, 3))
    sol = np.empty(max(n, 3))
    fk_jac_into(rot, trans, axis, kind, col, q, p, jac, scratch, True)
    for r in range(3):
        e[r] = target[r] - p[r]
    err2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2]
    hist[0] = math.sqrt(err2)
    mu = mu0
    accepted = 0
    tries = 0
    slow = 0
    tol2 = tol * tol
    while True:
        if err2 <= tol2:
            return accepted, 0
        if accepted >= max_iter:
            return accepted, 2
        # freeze joints blocked at a limit with the gradient pointing outward
        for i in range(n):
            free[i] = True
            if use_limits and not cont[i]:
                g = jac[0, i] * e[0] + jac[1, i] * e[1] + jac[2, i] * e[2]
                if (q[i] <= lower[i] and g < 0.0) or (q[i] >= upper[i] and g > 0.0):
                    free[i] = False
        lam2 = mu * (err2 + wbar)
        ok = _dls_into(jac, e, lam2, free, dq, work, rhs, sol)
        if not ok:
            mu *= 10.0
            tries += 1
            if tries > 40:
                return accepted, 1
            continue
        scale = 1.0
        for i in range(n):
            a = abs(dq[i])
            if a * scale > step_cap[i]:
                scale = step_cap[i] / a
        for i in range(n):
            qn[i] = q[i] + scale * dq[i]
        _limit_into(qn, lower, upper, cont, use_limits)
        fk_jac_into(rot, trans, axis, kind, col, qn, p, jac_t, scratch, True)
        en2 = 0.0
        for r in range(3):
            d = target[r] - p[r]
            en2 += d * d
        if en2 < err2:
            if en2 > err2 * (1.0 - 1e-10):
                slow += 1
            else:
                slow = 0
            for i in range(n):
                q[i] = qn[i]
                for r in range(3):
                    jac[r, i] = jac_t[r, i]
            for r in range(3):
                e[r] = target[r] - p[r]
            err2 = en2
            accepted += 1
            hist[accepted] = math.sqrt(err2)
            mu = max(mu * 0.25, 1e-12)
            tries = 0
            if slow >= 8:
                return accepted, 1
        else:
            mu *= 8.0
            tries += 1
            if tries > 40:
                return accepted, 1


# -------------------------------------------------------------------- the Python side
_MU0 = 0.1  # initial LM factor: λ² = μ (‖e‖² + w̄)
_ARRAYS: weakref.WeakKeyDictionary[Any, tuple[Any, ...]] = weakref.WeakKeyDictionary()


def _prepared(model: Any) -> tuple[Any, ...]:
    """Cached (packed arrays, lower, upper, continuous mask, step caps, scale) of a model."""
    hit = _ARRAYS.get(model)
    if hit is not None:
        return hit
    arrays = ChainArrays.from_model(model)
    lower = np.ascontiguousarray(model.lower, dtype=float)
    upper = np.ascontiguousarray(model.upper, dtype=float)
    prism = np.asarray(model.is_prismatic, dtype=bool)
    cont = (~prism) & (upper - lower >= 2 * np.pi - 1e-9)
    scale = float(np.sum(np.linalg.norm(arrays.trans, axis=1)))
    scale = scale if scale > 0 else 1.0
    cap = np.where(prism, 0.25 * scale, 0.5)
    home = _home(lower, upper, cont)
    home.setflags(write=False)
    prep = (arrays.packed, lower, upper, cont, cap, scale, arrays, home)
    _ARRAYS[model] = prep
    return prep


def _check_target(target: Any) -> np.ndarray:
    if type(target) is np.ndarray and target.dtype == np.float64 and target.shape == (3,):
        if math.isfinite(target[0]) and math.isfinite(target[1]) and math.isfinite(target[2]):
            return target.copy()
    try:
        t = np.asarray(target, dtype=np.float64)
    except (TypeError, ValueError):
        raise IKError(f"target={target!r} is not 3 numbers (x, y, z) in [m]") from None
    if t.shape != (3,):
        raise IKError(f"target has shape {t.shape}; a position (3,) = (x, y, z) in [m] is needed")
    if not np.all(np.isfinite(t)):
        raise IKError(f"target={t.tolist()} contains non-finite values; finite metres required")
    return np.ascontiguousarray(t)


def _home(lower: np.ndarray, upper: np.ndarray, cont: np.ndarray) -> np.ndarray:
    """A default start: 0.3 rad off zero on revolute joints (zero is often singular)."""
    q = np.where(cont, 0.3, 0.5 * (lower + upper) + 0.15 * (upper - lower))
    return np.clip(q, lower, upper)


def _starts(
    q0: np.ndarray, lower: np.ndarray, upper: np.ndarray, cont: np.ndarray, restarts: int
) -> Iterator[np.ndarray]:
    """``q0``, then ``restarts`` seeded random configurations (generated only when needed)."""
    yield q0
    if restarts:
        rng = np.random.default_rng(12345)
        lo = np.where(cont, -np.pi, lower)
        hi = np.where(cont, np.pi, upper)
        for _ in range(restarts):
            yield rng.uniform(lo, hi)


@njit(cache=True, nogil=True)
def sigma_bounds(jac: np.ndarray) -> tuple[float, float]:  # pragma: no cover - compiled
    """Smallest and largest singular values of a (3, n) position Jacobian, closed form.

    The smallest counts the task directions: for n >= 3 it is the 3rd singular value (0 at a
    singularity), for n < 3 the n-th. Uses the eigenvalues of ``JJᵀ`` (3×3) or ``JᵀJ`` (n×n);
    for n == 3 the smallest is ``|det J| / (σ1 σ2)`` (accurate near singularities).
    """
    n = jac.shape[1]
    if n == 0:
        return 0.0, 0.0
    if n == 1:
        v = math.sqrt(jac[0, 0] ** 2 + jac[1, 0] ** 2 + jac[2, 0] ** 2)
        return v, v
    if n == 2:
        a = jac[0, 0] ** 2 + jac[1, 0] ** 2 + jac[2, 0] ** 2
        d = jac[0, 1] ** 2 + jac[1, 1] ** 2 + jac[2, 1] ** 2
        b = jac[0, 0] * jac[0, 1] + jac[1, 0] * jac[1, 1] + jac[2, 0] * jac[2, 1]
        # |c1 x c2|^2 = ad - b^2 without cancellation
        cx = jac[1, 0] * jac[2, 1] - jac[2, 0] * jac[1, 1]
        cy = jac[2, 0] * jac[0, 1] - jac[0, 0] * jac[2, 1]
        cz = jac[0, 0] * jac[1, 1] - jac[1, 0] * jac[0, 1]
        det = cx * cx + cy * cy + cz * cz
        tr = a + d
        lmax = 0.5 * (tr + math.sqrt(max((a - d) ** 2 + 4.0 * b * b, 0.0)))
        lmin = det / lmax if lmax > 0.0 else 0.0
        return math.sqrt(max(lmin, 0.0)), math.sqrt(lmax)
    m00 = m01 = m02 = m11 = m12 = m22 = 0.0
    for k in range(n):
        x, y, z = jac[0, k], jac[1, k], jac[2, k]
        m00 += x * x
        m01 += x * y
        m02 += x * z
        m11 += y * y
        m12 += y * z
        m22 += z * z
    q = (m00 + m11 + m22) / 3.0
    p1 = m01 * m01 + m02 * m02 + m12 * m12
    p2 = (m00 - q) ** 2 + (m11 - q) ** 2 + (m22 - q) ** 2 + 2.0 * p1
    if p2 <= 0.0:
        v = math.sqrt(max(q, 0.0))
        return v, v
    p = math.sqrt(p2 / 6.0)
    b00, b11, b22 = (m00 - q) / p, (m11 - q) / p, (m22 - q) / p
    b01, b02, b12 = m01 / p, m02 / p, m12 / p
    r = 0.5 * (
        b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02)
        + b02 * (b01 * b12 - b11 * b02)
    )
    r = min(max(r, -1.0), 1.0)
    phi = math.acos(r) / 3.0
    e1 = q + 2.0 * p * math.cos(phi)
    e3 = q + 2.0 * p * math.cos(phi + 2.0 * math.pi / 3.0)
    e2 = 3.0 * q - e1 - e3
    smax = math.sqrt(max(e1, 0.0))
    if n == 3:
        det = (
            jac[0, 0] * (jac[1, 1] * jac[2, 2] - jac[1, 2] * jac[2, 1])
            - jac[0, 1] * (jac[1, 0] * jac[2, 2] - jac[1, 2] * jac[2, 0])
            + jac[0, 2] * (jac[1, 0] * jac[2, 1] - jac[1, 1] * jac[2, 0])
        )
        s12 = smax * math.sqrt(max(e2, 0.0))
        return (abs(det) / s12 if s12 > 0.0 else 0.0), smax
    return math.sqrt(max(e3, 0.0)), smax


def _sigma_min(jac: np.ndarray) -> float:
    return float(sigma_bounds(jac if jac.flags.c_contiguous else np.ascontiguousarray(jac))[0])


def solve(
    model: Any,
    target: Any,
    q0: Any = None,
    *,
    tol: float = 1e-10,
    max_iter: int = 100,
    restarts: int = 8,
    respect_limits: bool = True,
) -> IKResult:
    """Numerical IK of the tip position by damped least squares, for any loaded chain.

    Args:
        model: A loaded model (:func:`hexapod_kin.load`).
        target: Tip position (3,) in [m] in the base frame.
        q0: Start configuration (nq,); default: 0.3 rad on continuous revolute joints, a point
            inside the limits on the others.
        tol: Convergence threshold on ‖e‖ in [m].
        max_iter: Accepted steps per attempt.
        restarts: Extra attempts from seeded random configurations if the first one fails.
        respect_limits: Clamp limited joints to their bounds (continuous joints always wrap).

    Returns:
        An :class:`IKResult`. ``"unreachable"`` means every attempt ended at a local minimum of
        the distance (no direction lowers it), also without limits; ``nearest`` / ``distance``
        give the closest reachable point found. ``"joint_limits"``: reachable only outside the
        limits. ``"singular"``: stuck at a singular configuration that is not a minimum (only
        when restarts are exhausted). ``"not_converged"``: iteration cap.

    Raises:
        IKError: Non-finite or wrongly shaped target.
        ConfigurationError: Bad ``q0``.
        ParameterError: Bad ``tol``, ``max_iter`` or ``restarts``.

    """
    t = _check_target(target)
    if not (type(tol) is float and 0 < tol < math.inf):
        if not (isinstance(tol, (int, float)) and math.isfinite(tol) and tol > 0):
            raise ParameterError(f"tol={tol!r} is not allowed; a finite tolerance > 0 m is needed")
    if not (isinstance(max_iter, int) and max_iter >= 1):
        raise ParameterError(f"max_iter={max_iter!r} is not allowed; an int >= 1 is needed")
    if not (isinstance(restarts, int) and restarts >= 0):
        raise ParameterError(f"restarts={restarts!r} is not allowed; an int >= 0 is needed")
    packed, lower, upper, cont, cap, scale, _, home = _prepared(model)
    if q0 is None:
        qs = home
    else:
        qs = model.check_q(q0, "q0").copy()
        _limit_into(qs, lower, upper, cont, respect_limits)
    wbar = 1e-8 * scale * scale
    free = np.ones(model.nq, dtype=bool)
    best: tuple[float, np.ndarray, np.ndarray, int, int] | None = None
    starts = _starts(qs, lower, upper, cont, restarts)
    attempts = 0
    for start in starts:
        attempts += 1
        q = np.array(start, dtype=float)
        hist = np.empty(max_iter + 1)
        it, code = _lm_kernel(
            *packed, t, q, lower, upper, cont, respect_limits, tol, max_iter, cap, wbar, hist,
            free, _MU0,
        )
        err = float(hist[it])
        if best is None or err < best[0]:
            best = (err, q, hist[: it + 1].copy(), it, code)
        if code == 0:
            break
    assert best is not None
    _, q, hist, it, code = best
    # Pinocchio: the residual that is reported
    pose, jac6 = model.fk_jacobian(q)
    pos = np.array(pose[:3, 3])
    jac = np.array(jac6[:3])
    e = t - pos
    err = math.sqrt(float(e @ e))
    smin = _sigma_min(jac)
    q.setflags(write=False)
    hist.setflags(write=False)
    pos.setflags(write=False)
    t.setflags(write=False)

    def result(status: Status, reason: str, far: bool = False) -> IKResult:
        near = pos if far else t
        return IKResult(
            q=q, status=status, error=err, iterations=it, history=hist, position=pos, target=t,
            attempts=attempts, reason=reason, distance=err if far else 0.0, nearest=near,
            sigma_min=smin,
        )

    if code == 0 or err <= tol:
        return result("converged", f"‖e‖ = {err:.3g} m <= tol = {tol:g} m")
    if code == 2:
        return result(
            "not_converged", f"{max_iter} steps taken, ‖e‖ = {err:.3g} m still decreasing"
        )
    blocked = _blocked(q, jac, e, lower, upper, cont) if respect_limits else np.zeros(0, int)
    if blocked.size:
        free_run = _unconstrained_reaches(model, packed, t, q, lower, upper, cont, tol, cap, wbar)
        if free_run:
            names = [model.joint_names[i] for i in blocked]
            return result(
                "joint_limits",
                f"reachable only beyond the limits of {names}; nearest point within the limits "
                f"is {err:.3g} m away",
                far=True,
            )
    if _is_local_min(model, t, q, err, lower, upper, cont, respect_limits, scale):
        return result(
            "unreachable",
            f"outside the workspace: every start ends at a local minimum of the distance, "
            f"{err:.6g} m from the target",
            far=True,
        )
    if smin <= 1e-6 * scale:
        return result(
            "singular",
            f"stalled at a singular configuration (σ_min = {smin:.3g}) that is not a minimum "
            "of the distance; try another q0 or more restarts",
        )
    return result("not_converged", f"stalled at ‖e‖ = {err:.3g} m (no step lowers the error)")


def _blocked(
    q: np.ndarray, jac: np.ndarray, e: np.ndarray, lower: np.ndarray, upper: np.ndarray,
    cont: np.ndarray,
) -> np.ndarray:
    g = jac.T @ e
    at_lo = (~cont) & (q <= lower + 1e-12) & (g < 0)
    at_hi = (~cont) & (q >= upper - 1e-12) & (g > 0)
    return np.flatnonzero(at_lo | at_hi)


def _unconstrained_reaches(
    model: Any, packed: Any, t: np.ndarray, q: np.ndarray, lower: np.ndarray,
    upper: np.ndarray, cont: np.ndarray, tol: float, cap: np.ndarray, wbar: float,
) -> bool:
    free = np.ones(model.nq, dtype=bool)
    for start in _starts(np.array(q), lower, upper, cont, 8):
        qq = np.array(start)
        hist = np.empty(201)
        it, code = _lm_kernel(
            *packed, t, qq, lower, upper, cont, False, tol, 200, cap, wbar, hist, free, _MU0
        )
        if code == 0:
            return True
    return False


def _is_local_min(
    model: Any, t: np.ndarray, q: np.ndarray, err: float, lower: np.ndarray, upper: np.ndarray,
    cont: np.ndarray, respect_limits: bool, scale: float,
) -> bool:
    """True if no small perturbation of q (±1e-3 rad) lowers the distance by > 1e-9 scale."""
    arrays = _prepared(model)[6]
    rng = np.random.default_rng(7)
    jac = model.position_jacobian(q)
    _, sv, vt = np.linalg.svd(jac)
    sv_full = np.zeros(model.nq)
    sv_full[: sv.size] = sv
    null = vt[sv_full <= 1e-6 * max(scale, float(sv_full.max()))]
    base = np.vstack([np.eye(model.nq), rng.normal(size=(16, model.nq)), null])
    dirs = np.vstack([base, -base])
    trial = np.vstack([q[None, :] + h * dirs for h in (1e-3, 3e-2)])
    if respect_limits:
        trial = np.where(cont, trial, np.clip(trial, lower, upper))
    from ._kernels import fk_batch

    t_err = np.linalg.norm(fk_batch(arrays, trial) - t, axis=1)
    return bool(np.all(t_err >= err - 1e-9 * scale))


def solve_many(
    model: Any, targets: Any, q0: Any = None, **kwargs: Any
) -> list[IKResult]:
    """:func:`solve` for each row of ``targets`` (N, 3); ``q0`` (nq,) or (N, nq) or None."""
    t = np.asarray(targets, dtype=float)
    if t.ndim != 2 or t.shape[1] != 3:
        raise IKError(f"targets has shape {t.shape}; (N, 3) positions in [m] are needed")
    if q0 is None or np.ndim(q0) == 1:
        starts: Sequence[Any] = [q0] * len(t)
    else:
        starts = model.check_q_batch(q0, "q0")
        if len(starts) != len(t):
            raise ConfigurationError(f"q0 has {len(starts)} rows; targets has {len(t)}")
    return [solve(model, ti, si, **kwargs) for ti, si in zip(t, starts)]


del HAVE_NUMBA
