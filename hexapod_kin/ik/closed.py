"""Closed-form inverse kinematics of the leg families, recognised from the Khalil table.

Closed forms (:func:`analytic`, :func:`analytic_batch`) are chosen from the *structure* of the
Khalil table (the pattern of σ, α, d, r), never from a preset name:
``"coxa_tibia"`` (2 DOF, seed 002)
    ``R(α=0, d=0, r=r1) · R(α=±π/2, d=l1, r=0) · F(d=l2, r=0)``; foot
    ``Rz(φ1)·[l1 + l2 cos φ2, 0, ±l2 sin φ2] + [0, 0, r1]``. A 2-DOF leg reaches a *surface*
    (a target farther than ``tol`` from it has no solution); the tibia angle is ``atan2`` of
    both coordinates (its sign kept). Up to 2 solutions (hip ± π).
``"leg3"`` (3 DOF hip/knee/ankle, seeds 000/001/003)
    ``R(0, 0, r1) · R(±π/2, l1, 0) · R(0, l2, 0) · F(d=l3, r=0)``. Up to 4 solutions: hip
    ``atan2(y, x)`` or that ``+ π`` (the leg reaching back over the hip axis), each with both
    knee branches (ankle ``±acos``).
``"scara"`` (seed 003)
    ``R(0, 0, r1) · R(0, d2, r2) · R(0, d3, r3) · P(α ∈ {0, π}, d=0) · F(d=0, r=0)``. Target
    ``(x, y, z)`` or ``(x, y, z, yaw)`` (``yaw`` [rad]: the tool x axis in the base xy-plane;
    without it ``θ3 = 0``). Up to 2 solutions (both elbow branches).

Legs are also recognised (:func:`detect_family`, :class:`LegFamily`) on a mount (base pose,
``α1``, ``d1``), with offsets along the knee axis, a foot point after the last joint, an ankle
anti-parallel to the knee and twists within ``angle_tol`` of the pattern. Revolute results are
wrapped to ``(−π, π]``. The legs' closed form is written once, vectorised
(:func:`leg_solutions`); the numerical solver for any chain is :mod:`hexapod_kin.ik.solver`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from .._fields import fields_dict, read_only
from .._numerics import wrap_angles
from ..exceptions import IKError
from ..model import Model
from ..params import Chain, Hexapod, Pose, khalil_transform
from ._table_finish import finish_on_table
from ._table_finish import fit_angles as _fit

__all__ = ["FAMILIES", "FAMILY_TOL", "AnalyticBatch", "LegFamily", "analytic",
           "analytic_batch", "detect_family", "leg_reachable", "leg_solutions"]  # fmt: skip

FAMILIES: tuple[str, ...] = ("coxa_tibia", "leg3", "scara")

_HALF_PI = 0.5 * math.pi
_TWO_PI = 2.0 * math.pi
_ANG_TOL = 1e-12

#: Default tolerance [rad] of :func:`detect_family` on a leg's twists: covers unsnapped URDF
#: constants (``1.5704`` for π/2); such solutions are finished on the exact table.
FAMILY_TOL = 1e-3


def _is(value: float, target: float, tol: float = _ANG_TOL) -> bool:
    return abs(value - target) <= tol


def _twist_off(alpha: float, target: float) -> float:
    """|alpha − target| modulo 2π [rad]."""
    return abs(math.remainder(alpha - target, _TWO_PI))


def _angle_is(value: float, target: float) -> bool:
    return _twist_off(value, target) <= _ANG_TOL


# ============================================================================ family detection
@dataclass(frozen=True)
class LegFamily:
    """A chain recognised as one of the closed-form families (see the module docstring).

    Attributes:
        family: ``"coxa_tibia"``, ``"leg3"`` or ``"scara"`` (of ``chain``).
        lengths: The family's lengths in [m]: ``(l1, l2)``, ``(l1, l2, l3)`` or ``(d2, d3)``
            (a leg's last one to its foot point, ``√(p_x² + p_y²)``).
        height: Height of the first horizontal plane ``r1`` (SCARA: ``r1 + r2 + r3``) in [m].
        sign: ``sin α2`` (±1) of the legs; ``cos α4`` (±1) of the SCARA's prismatic row.
        offsets: The joints' θ (revolute) or r (prismatic) constants, one per joint.
        yaw_offset: SCARA only: tool yaw added by the constant rows, in [rad].
        lateral: Legs: the foot's offset ``e`` along the knee axis [m] (``r2 + κ(r3 + p_z)``).
        joint_signs: Legs: ``+1`` per joint, ``−1`` for an ankle anti-parallel to the knee.
        mount: Legs: ``base_pose · Rx(α1) · Tx(d1)`` when not identity, else None.
        deviation: Legs: how far [rad] the twists are from the exact pattern (0: exact; else
            the solutions are finished on the table, see :func:`analytic_batch`).

    """

    family: str
    chain: Chain
    lengths: tuple[float, ...]
    height: float
    sign: float
    offsets: tuple[float, ...]
    yaw_offset: float = 0.0
    lateral: float = 0.0
    joint_signs: tuple[float, ...] = ()
    mount: Pose | None = None
    deviation: float = 0.0

    @property
    def nq(self) -> int:
        """Number of joints."""
        return self.chain.nq

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (the chain by name; lengths in [m], angles in [rad])."""
        names = ("lengths", "height", "sign", "offsets", "yaw_offset", "lateral", "joint_signs")
        out = {"family": self.family, "chain": self.chain.name} | fields_dict(self, *names)
        return out | {"deviation": self.deviation}

    @property
    def target_size(self) -> tuple[int, ...]:
        """Accepted target lengths: (3,) for legs, (3, 4) for the SCARA (with yaw)."""
        return (3, 4) if self.family == "scara" else (3,)

    def reach_excess(self, targets: Any) -> np.ndarray:
        """Distance (N,) [m] by which targets lie outside the leg's reach (0 inside).

        Targets (N, 3) in the chain's base frame; the exact pattern's workspace, joint limits
        ignored (planar reach ``‖(u, w)‖`` against ``[|l2 − l3|, l2 + l3]``, both hip branches).
        Raises IKError: the family is ``scara`` (no such distance) or bad targets.
        """
        if self.family == "scara":
            raise IKError("reach_excess: legs only (coxa_tibia, leg3)", parameter="family")
        x, _ = _targets(self, targets)
        h = np.hypot(x[:, 0], x[:, 1])
        w = (x[:, 2] - self.height) * self.sign
        side = np.maximum(abs(self.lateral) - h, 0.0)
        m = np.sqrt(np.maximum(h * h - self.lateral**2, 0.0))
        if self.family == "leg3":
            l1, l2, l3 = self.lengths
            rmin, rmax = abs(abs(l2) - abs(l3)), abs(l2) + abs(l3)
        else:
            l1, l2 = self.lengths
            rmin = rmax = abs(l2)
        best = np.full(len(x), np.inf)
        for hs in (1.0, -1.0):
            r = np.hypot(hs * m - l1, w)
            best = np.minimum(best, np.maximum.reduce([r - rmax, rmin - r, np.zeros_like(r)]))
        return np.asarray(np.maximum(best, side))

    @property
    def scale(self) -> float:
        """A length scale of the chain in [m] (sum of |d|, |r| and the tool offset)."""
        s = sum(abs(r.d) + abs(r.r) for r in self.chain.rows)
        s += float(np.linalg.norm(self.chain.tool_matrix[:3, 3]))
        return s if s > 0 else 1.0


def _chain_of(chain: Chain | Model | str) -> Chain:
    if isinstance(chain, Chain):
        return chain
    if not isinstance(chain, Model):  # any other source: what hexapod_kin.load takes
        from ..kinematics import load

        chain = load(chain)
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
    if isinstance(params, Hexapod):  # one leg of the robot: its table on its mount
        base, tip = chain.base, chain.tip
        for mount, foot in zip(params.legs, params.foot_frames):
            if tip == foot and base == params.body:
                return replace(mount.chain, base_pose=Pose.of(mount.transform()))
        msg = (
            f"chain: the hexapod's sub-chain {base!r} -> {tip!r} is not one leg from the body "
            f"{params.body!r}; closed forms take base={params.body!r} and a foot as tip"
        )
        raise IKError(msg, parameter="tip", value=tip, allowed=list(params.foot_frames))
    raise IKError(
        f"chain={chain!r}: closed-form IK needs a Khalil table (a Chain, or a model loaded from "
        "one); this source has none (URDF) — use hexapod_kin.ik.solve(model, target)",
        parameter="chain",
        value=getattr(chain, "name", repr(chain)),
        allowed="a Chain, a preset, a table file, or a model loaded from one",
    )


def detect_family(chain: Chain | Model | str, *, angle_tol: float = FAMILY_TOL) -> LegFamily:
    """Recognise the closed-form family of a chain from its table pattern.

    ``chain``: a :class:`~hexapod_kin.params.Chain`, a model loaded from one, or any source
    :func:`hexapod_kin.load` takes; ``angle_tol`` [rad]: how far a leg's twists may be from the
    exact pattern. Raises IKError: the table matches no family, or the model has no table.

    """
    ch = _chain_of(chain)
    rows = ch.rows
    sig = tuple(str(r.sigma)[0].upper() for r in rows)
    offsets = tuple(
        rows[i].theta if rows[i].sigma == "revolute" else rows[i].r for i in ch.joint_rows
    )
    r1 = rows[0]
    base_ok = _is(r1.alpha, 0.0) and _is(r1.d, 0.0)
    joints = "".join(s for s in sig if s != "F")
    n_joint_rows = len(ch.joint_rows)
    legs_ok = joints in ("RR", "RRR") and sig[:n_joint_rows] == tuple(joints)
    if legs_ok:
        leg = _leg_family(ch, float(angle_tol))
        if leg is not None:
            return leg
    tool_xyz = ch.tool_matrix[:3, 3]
    if not np.allclose(tool_xyz, 0.0, atol=1e-15) and not legs_ok:
        msg = (
            f"chain {ch.name!r} has a tool offset {tool_xyz.tolist()} m: the SCARA closed form "
            "places the table's last frame; use hexapod_kin.ik.solve(model, target)"
        )
        raise IKError(msg, parameter="tool", value=tool_xyz.tolist(), allowed="no tool translation")
    if sig == ("R", "R", "R", "P", "F") and base_ok:
        b, c, p, f = rows[1:]
        flip, f_flip = _angle_is(p.alpha, math.pi), _angle_is(f.alpha, math.pi)
        zeros = all(_is(v, 0.0) for v in (b.alpha, c.alpha, p.d, f.d, f.r))
        twists = (flip or _angle_is(p.alpha, 0.0)) and (f_flip or _angle_is(f.alpha, 0.0))
        if zeros and twists and abs(b.d) > 0 and abs(c.d) > 0:
            c4, c5 = (-1.0 if flip else 1.0), (-1.0 if f_flip else 1.0)
            height, yaw = r1.r + b.r + c.r, c4 * (p.theta + c5 * f.theta)
            return LegFamily("scara", ch, (b.d, c.d), height, c4, offsets, yaw_offset=yaw)
    pattern = " ".join(f"{s}(α={r.alpha:.4g}, d={r.d:.4g}, r={r.r:.4g})" for s, r in zip(sig, rows))
    raise IKError(
        f"chain {ch.name!r} has no closed-form IK: its table {pattern} matches none of the "
        f"families {list(FAMILIES)} (coxa_tibia: R R(±π/2, l1) + a foot off the last axis; "
        "leg3: R R(±π/2, l1) R(0 or π, l2) + a foot off the last axis, twists within "
        f"angle_tol={float(angle_tol):.3g} rad; scara: R(0,0,r1) R(0,d2) R(0,d3) "
        "P(α∈{0,π},d=0) F(d=0,r=0)); use hexapod_kin.ik.solve(model, target)"
    )


def _leg_family(ch: Chain, angle_tol: float) -> LegFamily | None:
    """The leg families through mounts, tool offsets and near-exact twists (None: no leg)."""
    rows, jr = ch.rows, ch.joint_rows
    nq = len(jr)
    r1, a = rows[0], rows[1]
    # α2 = σ·π/2
    sigma = 1.0 if math.sin(a.alpha) > 0 else -1.0
    dev = _twist_off(a.alpha, sigma * _HALF_PI)
    kappa = 1.0
    if nq == 3:
        b = rows[2]
        kappa = 1.0 if math.cos(b.alpha) > 0 else -1.0
        dev = max(dev, _twist_off(b.alpha, 0.0 if kappa > 0 else math.pi))
    if dev > angle_tol:
        return None
    # the foot: a fixed point in the last joint's frame (fixed rows, then the tool)
    t = np.eye(4)
    for row in rows[nq:]:
        t = t @ row.transform()
    px, py, pz = (t @ ch.tool_matrix)[:3, 3]
    if py == 0.0:  # the catalogue's legs: the length as the table writes it (sign kept)
        last, delta = float(px), 0.0
    else:
        last, delta = math.hypot(px, py), math.atan2(py, px)
    if last == 0.0 or (nq == 3 and rows[2].d == 0.0):
        return None  # a foot on the last axis, or no thigh: not these closed forms
    lengths: tuple[float, ...]
    offs: tuple[float, ...]
    if nq == 2:
        lengths, lateral, offs = (a.d, last), a.r + pz, (r1.theta, a.theta + delta)
    else:
        b = rows[2]
        lengths, lateral = (a.d, b.d, last), a.r + kappa * (b.r + pz)
        offs = (r1.theta, a.theta, b.theta + delta)
    if abs(lateral) < 1e-15 * (abs(a.d) + abs(last)):
        lateral = 0.0
    mount = ch.base_pose  # α1 = d1 = 0: the base pose as it is (same bits as before)
    if not (r1.alpha == 0.0 and r1.d == 0.0):
        mount = Pose.of(ch.base_matrix @ khalil_transform(r1.alpha, r1.d, 0.0, 0.0))
    name, signs = ("coxa_tibia" if nq == 2 else "leg3"), (1.0, 1.0, kappa)[:nq]
    offs, dev = tuple(float(v) for v in offs), (0.0 if dev <= _ANG_TOL else dev)
    return LegFamily(name, ch, lengths, r1.r, sigma, offs, 0.0, float(lateral), signs, mount, dev)


# ============================================================================ closed forms
@dataclass(frozen=True)
class AnalyticBatch:
    """Closed-form solutions of many targets, in fixed-shape arrays (read-only).

    Attributes:
        q: (N, K, n) joint values, NaN where not ``valid``; K is 2 (coxa_tibia, scara) or 4
            (leg3), slots of fixed branch meaning (see :func:`analytic_batch`).
        valid: (N, K) True where the slot holds a solution (``family``: the detected one).

    """

    q: np.ndarray
    valid: np.ndarray
    family: str

    @property
    def reachable(self) -> np.ndarray:
        """(N,) True where a target has at least one solution."""
        return np.asarray(self.valid.any(axis=1))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (NaN slots as None)."""
        q = [
            [s if ok else None for s, ok in zip(qi, vi)]
            for qi, vi in zip(self.q.tolist(), self.valid.tolist())
        ]
        return {"family": self.family, "q": q, "valid": self.valid.tolist()}


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
    pose = fam.chain.base_pose if fam.family == "scara" else fam.mount
    if pose is not None:  # targets in the base link -> Khalil frame 0 (legs: after α1, d1)
        T = pose.matrix
        R, t = T[:3, :3], T[:3, 3]
        arr = arr.copy()
        arr[:, :3] = (arr[:, :3] - t) @ R
        if arr.shape[1] == 4:
            if not math.isclose(R[2, 2], 1.0, abs_tol=1e-12):
                raise IKError(
                    "a yaw target needs a base pose that only turns about z; this chain's "
                    "base_pose tilts it: use hexapod_kin.ik.solve(model, target)"
                )
            arr[:, 3] -= math.atan2(R[1, 0], R[0, 0])
        if fam.family == "scara" and fam.chain.tool is not None:
            raise IKError("SCARA closed form: a tool pose turns the yaw; use ik.solve")
    return np.ascontiguousarray(arr), single


def analytic_batch(
    chain: Chain | Model | str, targets: Any, *, tol: float = 1e-9, within_limits: bool = False
) -> AnalyticBatch:
    """All closed-form solutions of N targets as fixed-shape arrays plus a validity mask.

    Slots: coxa_tibia ``[hip toward the target, hip reversed (φ1 + π)]``; leg3
    ``[toward/ankle +, toward/ankle −, reversed/ankle +, reversed/ankle −]``; scara
    ``[elbow +, elbow −]``; coincident branches both stay valid. A leg off the pattern is
    finished on the table (:mod:`hexapod_kin.ik._table_finish`): a slot stays valid when its
    foot lands within ``tol`` × the length scale of the target. ``chain`` as
    :func:`detect_family`; ``targets`` (N, 3) foot positions [m] in the base frame (SCARA: or
    (N, 4) with yaw [rad]; a (3,) target is N = 1); ``tol`` relative (× the chain's length
    scale) for the reachability tests; ``within_limits``: invalidate solutions outside the joint
    limits (after ±2π). Raises IKError: no closed form for this chain; bad or non-finite targets.

    """
    fam = detect_family(chain)
    x, _ = _targets(fam, targets)
    tol_abs, limits = float(tol) * fam.scale, None
    if within_limits:
        limits = (np.asarray(fam.chain.lower(), float), np.asarray(fam.chain.upper(), float))
    if fam.family == "scara":
        with np.errstate(invalid="ignore", divide="ignore"):
            q, valid = _ik_scara(fam, x)
        q = q - np.asarray(fam.offsets)
        q[..., :3] = wrap_angles(q[..., :3])
        if limits is not None:
            lo, hi = limits[0] - 1e-12, limits[1] + 1e-12
            for j in range(4):  # θ1 θ2 θ3 revolute, then the prismatic joint
                v, ok = _fit(q[..., j], lo[j], hi[j]) if j < 3 else (q[..., j], True)
                q[..., j] = v
                valid &= ok & (v >= lo[j]) & (v <= hi[j])
        q[~valid] = np.nan
    else:  # twists near the pattern: solve the exact pattern, finish on the table itself
        exact = fam.deviation == 0.0
        q, valid = leg_solutions(
            x,
            fam.lengths,
            height=fam.height,
            sign=fam.sign,
            offsets=fam.offsets,
            tol=tol_abs if exact else tol_abs + 4.0 * fam.deviation * fam.scale,
            limits=limits if exact else None,
            lateral=fam.lateral,
            joint_signs=fam.joint_signs,
        )
        if not exact:
            q, valid = finish_on_table(fam.chain, x, q, valid, tol_abs, fam.scale, limits)
    read_only(q, valid)
    return AnalyticBatch(q=q, valid=valid, family=fam.family)


def _ik_scara(fam: LegFamily, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    d2, d3 = fam.lengths
    n, rr = x.shape[0], x[:, 0] ** 2 + x[:, 1] ** 2
    c2 = (rr - d2 * d2 - d3 * d3) / (2.0 * d2 * d3)
    eps = 1e-9 * (abs(d2) + abs(d3)) ** 2 / abs(d2 * d3)
    ok, c2 = np.abs(c2) <= 1.0 + eps, np.clip(c2, -1.0, 1.0)
    s2, base = np.sqrt(1.0 - c2 * c2), np.arctan2(x[:, 1], x[:, 0])
    q, valid = np.empty((n, 2, 4)), np.empty((n, 2), dtype=bool)
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


def _leg_slots(
    targets: Any, lengths: tuple[Any, ...], *, height: float = 0.0, sign: float = -1.0,
    offsets: Any = None, tol: float = 0.0, limits: tuple[Any, Any] | None = None,
    lateral: Any = 0.0, joint_signs: Any = None,
) -> tuple[np.ndarray | None, list[np.ndarray], list[np.ndarray]]:  # fmt: skip
    """The leg closed form as columns on the targets a branch reaches.

    Returns ``(sub, cols, oks)``: the indices of those targets (None: all), their joint values
    slot by slot and joint by joint, and each slot's validity.
    """
    x = np.asarray(targets, dtype=np.float64).reshape(-1, 3)
    nq = len(lengths)
    off = np.zeros(nq) if offsets is None else np.asarray(offsets, dtype=np.float64)
    if not off.any():
        off = [0] * nq  # type: ignore[assignment]  # a - 0 is a: no work
    lo = hi = None
    if limits is not None:
        lo, hi = (np.asarray(v, dtype=np.float64) for v in limits)
        # joint j's bounds lo[j], hi[j]: scalars or contiguous (N,)
        lo, hi = np.ascontiguousarray(lo.T - 1e-12), np.ascontiguousarray(hi.T + 1e-12)
    flip = [] if joint_signs is None else [j for j, s in enumerate(joint_signs) if s < 0]
    n, h = len(x), np.hypot(x[:, 0], x[:, 1])
    w = (x[:, 2] - height) * sign
    l1, l2 = lengths[0], lengths[1]
    l3 = lengths[2] if nq == 3 else 0.0
    e = lateral
    side = np.ndim(e) > 0 or e != 0.0  # a foot off the leg plane: h² = (l1 + ρ)² + e²
    if side:
        m2 = h * h - np.square(e)
        lat_ok = m2 >= -(2.0 * np.abs(e) * tol + tol * tol)
        h = np.sqrt(np.maximum(m2, 0.0))
    with np.errstate(invalid="ignore", divide="ignore"):
        us = [h - l1, -h - l1]  # the hip toward the target, then reversed
        if nq == 2:
            reach = [np.abs(np.hypot(u, w) - np.abs(l2)) <= tol for u in us]
        else:
            eps = tol * (np.abs(l2) + np.abs(l3)) / np.abs(l2 * l3)
            c3s = [(u * u + w * w - l2 * l2 - l3 * l3) / (2.0 * l2 * l3) for u in us]
            reach = [np.abs(c3) <= 1.0 + eps for c3 in c3s]
        if side:
            reach = [r & lat_ok for r in reach]
    # the angles only where a branch reaches (the trigonometry is most of the work)
    sub = np.flatnonzero(reach[0] | reach[1])
    full = len(sub) == n

    def take(a: Any) -> Any:
        return a if full or np.ndim(a) == 0 else a[..., sub]

    x, h, w = (x if full else x[sub]), take(h), take(w)
    us, reach = [take(u) for u in us], [take(r) for r in reach]
    l1, l2, l3 = take(np.asarray(l1)), take(np.asarray(l2)), take(np.asarray(l3))
    if side:
        e = take(np.asarray(e, dtype=np.float64))
    if lo is not None and hi is not None and lo.ndim == 2:  # per target: (nq, N)
        lo, hi = take(lo), take(hi)
    phi = np.arctan2(x[:, 1], x[:, 0])
    cols: list[np.ndarray] = []  # slot by slot, joint by joint
    oks: list[np.ndarray] = []

    def slot(ok: np.ndarray, *angles: np.ndarray) -> None:
        angles = tuple(-a if j in flip else a for j, a in enumerate(angles))
        vals = [wrap_angles(a - off[j] if off[j] else a) for j, a in enumerate(angles)]
        if lo is not None and hi is not None:
            for j, v in enumerate(vals):
                vals[j], inside = _fit(v, lo[j], hi[j])
                ok = ok & inside
        oks.append(ok)
        cols.extend(vals)

    with np.errstate(invalid="ignore", divide="ignore"):
        for k, u in enumerate(us):
            # e = 0: the foot's plane holds the hip axis, φ1 = atan2(y, x) (+ π reversed)
            hip = phi - np.arctan2(-sign * e, u + l1) if side else phi + k * np.pi
            if nq == 2:
                slot(reach[k], hip, np.arctan2(w / l2, u / l2))
                continue
            c3 = np.clip(take(c3s[k]), -1.0, 1.0)
            s3, base = np.sqrt(1.0 - c3 * c3), np.arctan2(w, u)
            a2 = np.arctan2(l3 * s3, l2 + l3 * c3)
            a3 = np.arctan2(s3, c3)
            slot(reach[k], hip, base - a2, a3)
            slot(reach[k], hip, base + a2, -a3)
    return (None if full else sub), cols, oks


def leg_solutions(
    targets: np.ndarray,
    lengths: tuple[Any, ...],
    *,
    height: float = 0.0,
    sign: float = -1.0,
    offsets: Any = None,
    tol: float = 0.0,
    limits: tuple[Any, Any] | None = None,
    lateral: Any = 0.0,
    joint_signs: Any = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The one closed form of the coxa_tibia (2 lengths) and leg3 (3 lengths) legs, vectorised.

    Foot ``Rz(φ1)·[l1 + ρ', 0, σ·w] + [0, 0, h]`` with ``ρ' = l2 c2`` (2 DOF) or
    ``l2 c2 + l3 c23`` and ``w = l2 s2 (+ l3 s23)``; σ = ``sign`` (sin α2). For each hip
    branch (``φ1 = atan2(y, x)`` or ``+ π``, ``u = ±√(x² + y²) − l1``): 2 DOF, valid when
    ``|‖(u, w)‖ − |l2|| ≤ tol``, ``φ2 = atan2(w/l2, u/l2)``; 3 DOF,
    ``c3 = (u² + w² − l2² − l3²)/(2 l2 l3)`` valid when ``|c3| ≤ 1 + ε`` (ε: ``tol`` as a
    cosine), ``φ3 = ±acos c3``, ``φ2 = atan2(w, u) − atan2(l3 s3, l2 + l3 c3)``.

    ``targets`` (N, 3) [m] in the leg's frame 0; ``lengths`` [m], each a number or (N,);
    ``height`` ``r1`` [m]; ``offsets`` θ [rad] removed from the result; ``tol`` absolute [m];
    ``limits`` (lower, upper), each (n,) or (N, n): solutions outside (after ±2π) are invalid;
    ``lateral`` the foot's offset ``e`` [m] along the knee axis (number or (N,)): then
    ``u = ±√(x² + y² − e²) − l1``, ``φ1 = atan2(y, x) − atan2(−σe, u + l1)``; ``joint_signs``
    ±1 per joint (−1: enters the planar leg negated). Returns ``(q, valid)``: (N, K, n) joint
    values (NaN where invalid) and (N, K) validity, the slots of :func:`analytic_batch`.

    """
    n = len(np.asarray(targets).reshape(-1, 3))
    sub, cols, oks = _leg_slots(targets, lengths, height=height, sign=sign, offsets=offsets,
                                tol=tol, limits=limits, lateral=lateral,
                                joint_signs=joint_signs)  # fmt: skip
    nq, k = len(lengths), 2 * len(lengths) - 2  # 2 slots (2 DOF) or 4 (3 DOF)
    q = np.full((k * nq, n), np.nan)  # slot-major rows, one column per target
    valid = np.zeros((k, n), dtype=bool)
    at = slice(None) if sub is None else sub
    for i, ok in enumerate(oks):
        valid[i, at] = ok
        for j in range(nq):
            q[i * nq + j, at] = np.where(ok, cols[i * nq + j], np.nan)
    return q.T.reshape(n, k, nq), valid.T


def leg_reachable(targets: Any, lengths: tuple[Any, ...], **options: Any) -> np.ndarray:
    """(N,) True where :func:`leg_solutions` has a valid slot (its arguments and keywords)."""
    sub, _, oks = _leg_slots(targets, lengths, **options)
    if sub is None:
        return np.logical_or.reduce(oks)
    out = np.zeros(len(np.asarray(targets).reshape(-1, 3)), dtype=bool)
    out[sub] = np.logical_or.reduce(oks)
    return out


def analytic(
    chain: Chain | Model | str, target: Any, *, tol: float = 1e-9, within_limits: bool = False
) -> list[np.ndarray]:
    """All closed-form solutions, as a list with one (k, n) array per target (k ≥ 0).

    A single target (3,) gives a list of one array; coincident solutions are returned once; an
    unreachable target gives a (0, n) array. Arguments and errors: :func:`analytic_batch`'s.

    Example:
        >>> from hexapod_kin import robots, ik
        >>> import math
        >>> p = [10 + 5 * math.cos(math.radians(30)), 0.0, -2.5]  # seed 002, P1
        >>> ik.analytic(robots.coxa_tibia_leg(), p)[0].round(4)
        array([[ 0.    , -0.5236],
               [ 3.1416, -2.618 ]])

    """
    batch = analytic_batch(chain, target, tol=tol, within_limits=within_limits)
    out: list[np.ndarray] = []
    for qi, vi in zip(batch.q, batch.valid):
        sols = qi[vi]
        keep: list[np.ndarray] = []
        for s in sols:
            if not any(np.max(np.abs(wrap_angles(s - k))) <= 1e-12 for k in keep):
                keep.append(s)
        out.append(np.array(keep, dtype=float).reshape(len(keep), qi.shape[-1]))
    return out
