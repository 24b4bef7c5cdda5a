"""Recover a Khalil–Kleinfinger table from a serial URDF chain (:func:`chain_from_urdf`).

The loaded model's joint axes at ``q = 0`` are lines (base frame) carrying the Khalil frames:

* ``z_j`` is joint ``j``'s axis, with the URDF's direction (``q`` keeps its sign);
* ``x_j`` is the common normal from line ``j`` to line ``j + 1``, frame ``j``'s origin its foot
  on line ``j``. Intersecting axes: ``x_j = z_j × z_{j+1}`` at the intersection. Parallel
  axes: the origin where ``x_{j-1}`` meets line ``j`` (``r_j = 0``), ``x_j`` towards line
  ``j + 1`` (coincident: ``x_j = x_{j-1}``). The last joint keeps ``x_n = x_{n-1}``;
* frame 0 is the base link's frame when Khalil's rule for row 1 holds there (``z_1 ⟂ x_0``,
  joint 1's axis meeting the ``x_0`` line: every URDF hexapod_kin writes), else frame 1 at
  ``q = 0``, the offset going to ``Chain.base_pose``; what remains to the tip is ``Chain.tool``.

Rows ``(α_j, d_j, θ_j, r_j)`` are read off consecutive frames (fixed joints need none).

**Snapping.** Rounded rotations (``3.14159``) leave parallel axes a few µrad off (their common
normal kilometres away): an axis within ``angle_tol`` (:data:`SNAP_TOL`) of parallel or
perpendicular to the previous one is made exact by turning the rest of the chain about that
joint (each :class:`Snap` reported; twists then multiples of π/2); a snap of ``ε`` rad moves
the tip by at most ``ε ×`` the path length to it (:attr:`TableRecovery.fk_bound`).

**Checks.** No recovered length may exceed twice the path length
(:attr:`TableRecovery.size`; else a :class:`~hexapod_kin.exceptions.ConfigurationError` names
the joints and the ``angle_tol`` that would snap them); the table's FK equals Pinocchio's to
1e-9 relative without snaps, else within ``fk_bound``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ._fields import fields_dict
from ._pose import rodrigues
from ._table_kin import table_fk
from .exceptions import ConfigurationError, ParameterError, SourceError
from .params import Chain, JointLimits, KhalilRow, Pose

__all__ = ["SNAP_TOL", "Snap", "TableRecovery", "chain_from_urdf", "recover_chain"]

#: Default angle tolerance [rad] within which consecutive joint axes are snapped to exactly
#: parallel, anti-parallel or perpendicular (:func:`recover_chain`).
SNAP_TOL = 1e-4

_EPS = 1e-10


def _clean(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]", "_", str(name)) or "x"


def _angle(a: np.ndarray, b: np.ndarray, about: np.ndarray) -> float:
    """Signed angle from unit ``a`` to unit ``b`` about unit ``about`` (both ⟂ ``about``)."""
    return math.atan2(float(np.dot(np.cross(a, b), about)), float(np.dot(a, b)))


def _perp(v: np.ndarray, z: np.ndarray) -> np.ndarray | None:
    w = v - np.dot(v, z) * z
    n = float(np.linalg.norm(w))
    return None if n < 1e-9 else w / n


def _meet(o: np.ndarray, x: np.ndarray, p: np.ndarray, u: np.ndarray, scale: float) -> Any:
    """Point where line (o, x) meets line (p, u), or None when they do not meet."""
    n = np.cross(x, u)
    nn = float(np.dot(n, n))
    if nn < 1e-18:
        return None
    point = o + float(np.dot(np.cross(p - o, u), n)) / nn * x
    off = point - p
    miss = off - np.dot(off, u) * u
    return None if float(np.linalg.norm(miss)) > _EPS * scale else point


def _row(
    prev: tuple[np.ndarray, np.ndarray, np.ndarray],
    cur: tuple[np.ndarray, ...],
    sigma: str,
    where: str,
    scale: float,
) -> KhalilRow:
    o0, x0, z0 = prev
    o1, x1, z1 = cur
    if abs(float(np.dot(x0, z1))) > 1e-9:
        raise ConfigurationError(f"{where}: axis not perpendicular to the previous x axis")
    alpha = _angle(z0, z1, x0)
    delta = o1 - o0
    d = float(np.dot(delta, x0))
    r = float(np.dot(delta, z1))
    if float(np.linalg.norm(delta - d * x0 - r * z1)) > 1e-9 * scale:
        raise ConfigurationError(f"{where}: the axis does not meet the previous common normal")
    theta = _angle(x0, x1, z1)
    tiny = 1e-14 * scale
    alpha, d, theta, r = (0.0 if abs(v) < tiny else v for v in (alpha, d, theta, r))
    return KhalilRow(sigma, alpha, d, theta, r)


def _frame(o: np.ndarray, x: np.ndarray, z: np.ndarray) -> np.ndarray:
    t = np.eye(4)
    t[:3, 0], t[:3, 1], t[:3, 2], t[:3, 3] = x, np.cross(z, x), z, o
    return t


@dataclass(frozen=True)
class Snap:
    """One snap: a joint axis turned exactly parallel or perpendicular to the previous one.

    ``joints``: the previous and the snapped joint (URDF names); ``kind``: ``"parallel"``,
    ``"anti-parallel"`` or ``"perpendicular"``; ``angle`` [rad]: the rotation of the snapped
    joint and all after it; ``reach`` [m]: the path length from it to the tip (the tip moves by
    at most ``angle × reach``).
    """

    joints: tuple[str, str]
    kind: str
    angle: float
    reach: float

    def __str__(self) -> str:
        return f"{self.joints[0]}/{self.joints[1]} {self.kind} by {self.angle:.3g} rad"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (angle in [rad], reach in [m])."""
        return fields_dict(self, "joints", "kind", "angle", "reach")


@dataclass(frozen=True)
class TableRecovery:
    """A recovered Khalil table with what was done to get it (:func:`recover_chain`).

    Attributes:
        chain: The recovered :class:`~hexapod_kin.params.Chain`.
        snaps: The snaps applied, in chain order; ``angle_tol``: their tolerance [rad].
        size: The bound on every recovered length [m] (see the module docstring).
        fk_bound: ``Σ angle × reach`` over the snaps (and the zeroed lengths) [m]: the most the
            table's tip can differ from the URDF's in any configuration.
        fk_error: The largest tip position difference table vs URDF at ``q = 0`` and 8
            random configurations [m].
        zeroed: Lengths (``d<j>``, ``r<j>``, ``tool_<x|y|z>``) below 1e-9 × max(1 m, size)
            set to exactly 0, with their values [m] (only when snapping).

    """

    chain: Chain
    snaps: tuple[Snap, ...]
    angle_tol: float
    size: float
    fk_bound: float
    fk_error: float
    zeroed: tuple[tuple[str, float], ...] = ()

    def summary(self) -> str:
        """One line: the snaps with their sizes and the FK difference (or "no snaps")."""
        zeroed = "".join(f"; zeroed {k} = {v:.2g} m" for k, v in self.zeroed)
        if not self.snaps:
            return (
                f"no axis snapped (angle_tol {self.angle_tol:.3g} rad){zeroed}; FK equals the "
                f"URDF's to {self.fk_error:.2g} m"
            )
        return (
            f"snapped {len(self.snaps)} axis pair(s) (angle_tol {self.angle_tol:.3g} rad): "
            + ", ".join(str(s) for s in self.snaps)
            + zeroed
            + f"; FK within {self.fk_error:.2g} m of the URDF (bound {self.fk_bound:.2g} m)"
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (the chain by name; lengths in [m], angles in [rad])."""
        out = {"chain": self.chain.name, "snaps": [s.to_dict() for s in self.snaps]}
        out |= fields_dict(self, "angle_tol", "size", "fk_bound", "fk_error")
        return out | {"zeroed": dict(self.zeroed)}


def _rotation(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation taking unit ``a`` to unit ``b`` (Rodrigues)."""
    axis = np.cross(a, b)
    s = float(np.linalg.norm(axis))
    c = float(np.dot(a, b))
    if s == 0.0:
        return np.eye(3)
    return rodrigues(axis / s, s, c)


def _snap(
    points: list[np.ndarray], axes: list[np.ndarray], tip: np.ndarray, names: list[str], tol: float
) -> list[Snap]:
    """Turn near-parallel / near-perpendicular axes exact, in place (``tip``: 4×4 pose)."""
    snaps: list[Snap] = []
    n = len(axes)
    for k in range(n - 1):
        z0, z1 = axes[k], axes[k + 1]
        c = float(np.dot(z0, z1))
        s = float(np.linalg.norm(np.cross(z0, z1)))
        off_par = math.atan2(s, abs(c))  # angle to the nearest of ±z0
        off_perp = math.atan2(abs(c), s)  # angle to the plane ⟂ z0
        if off_par <= _ROUNDING or off_perp <= _ROUNDING:
            continue  # exact up to rounding: the frame placement handles it as it is
        if off_par <= tol:
            target = z0 if c > 0 else -z0
            kind, angle = ("parallel" if c > 0 else "anti-parallel"), off_par
        elif off_perp <= tol:
            w = z1 - c * z0
            target = w / np.linalg.norm(w)
            kind, angle = "perpendicular", off_perp
        else:
            continue
        rot = _rotation(z1, target)
        pivot = points[k + 1].copy()
        for j in range(k + 1, n):
            points[j] = pivot + rot @ (points[j] - pivot)
            axes[j] = rot @ axes[j]
        axes[k + 1] = target.copy()
        tip[:3, 3] = pivot + rot @ (tip[:3, 3] - pivot)
        tip[:3, :3] = rot @ tip[:3, :3]
        path = [points[j] for j in range(k + 1, n)] + [tip[:3, 3]]
        reach = sum(float(np.linalg.norm(b - a)) for a, b in zip(path[:-1], path[1:]))
        snaps.append(Snap((names[k], names[k + 1]), kind, angle, reach))
    return snaps


_HALF_PI = 0.5 * math.pi
_LEN_TOL = 1e-9
_ROUNDING = 1e-13  # [rad]: axis relations this close are exact already (never snapped)


def chain_from_urdf(
    source: Any,
    base: str | None = None,
    tip: str | None = None,
    *,
    angle_tol: float = SNAP_TOL,
    **load_kwargs: Any,
) -> Chain:
    """The Khalil table (base/tool poses included) of a serial URDF chain.

    ``recover_chain(...).chain``: the same arguments and errors as :func:`recover_chain`.
    """
    return recover_chain(source, base, tip, angle_tol=angle_tol, **load_kwargs).chain


def recover_chain(
    source: Any,
    base: str | None = None,
    tip: str | None = None,
    *,
    angle_tol: float = SNAP_TOL,
    **load_kwargs: Any,
) -> TableRecovery:
    """Recover the Khalil table of a serial URDF chain (see the module docstring).

    Args:
        source: Anything :func:`hexapod_kin.load` takes (URDF path or text, ``erd:NAME``,
            preset, or an already loaded model).
        base: Base frame name (default: the source's default base).
        tip: Tip frame name (default: the source's default tip).
        angle_tol: Axes within this angle [rad] of parallel or perpendicular to the previous
            joint's axis are snapped (default :data:`SNAP_TOL`; 0 = never snap).
        **load_kwargs: Passed to :func:`hexapod_kin.load` (e.g. preset parameters).

    Raises:
        ConfigurationError: A joint the table cannot express (named), a branch between
            ``base`` and ``tip`` (not serial), a recovered length larger than the chain
            (near-parallel axes beyond ``angle_tol``), or a failed check.
        ParameterError: ``angle_tol`` not a finite angle in [0, 0.1] rad.
        HexapodKinError: Whatever :func:`hexapod_kin.load` raises for the source.

    """
    from .frames import joint_kind  # the one place joint kinds (and their axes) are told apart
    from .kinematics import KinematicModel, load

    try:
        tol = float(angle_tol)
    except (TypeError, ValueError):
        tol = float("nan")
    if not (0.0 <= tol <= 0.1):
        raise ParameterError(
            f"angle_tol={angle_tol!r} is not allowed; a snapping tolerance in [0, 0.1] rad",
            parameter="angle_tol",
            value=angle_tol,
            allowed="[0, 0.1] rad",
        )
    if isinstance(source, KinematicModel) and base is None and tip is None and not load_kwargs:
        km = source
    else:
        try:
            km = load(source, base=base, tip=tip, **load_kwargs)
        except SourceError as exc:
            if "joints of kind" not in str(exc):
                raise
            raise ConfigurationError(
                f"chain_from_urdf: {exc}; a Khalil table expresses revolute, continuous, "
                "prismatic and fixed joints only"
            ) from None
    m = km.model
    names = [str(m.names[i]) for i in range(m.njoints)]
    # (kind, axis) of every joint: the loader admitted one-variable joints only
    kinds = {i: joint_kind(m.joints[i]) for i in range(1, m.njoints)}
    frame = m.frames[km.tip_id]
    path = [int(j) for j in m.supports[frame.parentJoint]][1:]  # root → tip, universe left out
    if sorted(path) != list(range(1, m.njoints)):
        extra = sorted(set(range(1, m.njoints)) - set(path))
        raise ConfigurationError(
            f"joints {[names[i] for i in extra]} are not on the path to tip={km.tip!r}: the model "
            "is not a serial chain; pick the chain with base=/tip="
        )
    if not path:
        raise ConfigurationError(f"no moving joint between base={km.base!r} and tip={km.tip!r}")
    # placements at q = 0, in the universe, then in the base frame
    o_m_i = [np.eye(4)] * m.njoints
    for i in range(1, m.njoints):
        o_m_i[i] = o_m_i[int(m.parents[i])] @ m.jointPlacements[i].homogeneous
    base_frame = m.frames[km.base_id]
    o_m_base = o_m_i[int(base_frame.parentJoint)] @ base_frame.placement.homogeneous
    inv_base = np.linalg.inv(o_m_base)
    t_base_tip = inv_base @ o_m_i[int(frame.parentJoint)] @ frame.placement.homogeneous
    points, axes, sigmas = [], [], []
    for i in path:
        t = inv_base @ o_m_i[i]
        points.append(t[:3, 3])
        jkind, axis = kinds[i]  # type: ignore[misc]
        axes.append(t[:3, :3] @ (axis / np.linalg.norm(axis)))
        sigmas.append("prismatic" if jkind == "prismatic" else "revolute")
    path_names = [names[i] for i in path]
    snaps = _snap(points, axes, t_base_tip, path_names, tol)
    snapped_rows = {path_names.index(s.joints[1]) for s in snaps}
    scale = max(1.0, float(np.abs(points).max()), float(np.abs(t_base_tip[:3, 3]).max()))
    n = len(path)
    # frame 0: the base frame when row 1 can start from it
    o_b, x_b, z_b = np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 0, 1.0])
    perpendicular = abs(float(np.dot(axes[0], x_b))) < 1e-12
    base_ok = perpendicular and _meet(o_b, x_b, points[0], axes[0], scale) is not None
    prev = (o_b, x_b, z_b) if base_ok else None
    frames: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    for k in range(n):
        z, p = axes[k], points[k]
        where = f"joint {names[path[k]]!r}"
        nxt = (points[k + 1], axes[k + 1]) if k + 1 < n else None
        # the point where the previous x axis meets this axis (r_k = 0 choice)
        if prev is not None:
            hit = _meet(prev[0], prev[1], p, z, scale)
            if hit is None:  # prev x is a common normal: it must meet this axis
                raise ConfigurationError(f"{where}: internal error, common normal misses the axis")
            x_prev = _perp(prev[1], z)
        else:
            hit = p - np.dot(p, z) * z  # the foot of the base origin on the axis
            x_prev = _perp(x_b, z) if _perp(x_b, z) is not None else _perp(np.array([0, 1.0, 0]), z)
        assert x_prev is not None
        if nxt is None:
            o, x = hit, x_prev
        else:
            p2, u2 = nxt
            cr = np.cross(z, u2)
            ncr = float(np.linalg.norm(cr))
            if ncr < 1e-12:  # parallel
                w = (p2 - hit) - np.dot(p2 - hit, z) * z
                dist = float(np.linalg.norm(w))
                o = hit
                x = w / dist if dist > _EPS * scale else x_prev
            else:
                nh = cr / ncr
                dist = float(np.dot(p2 - p, nh))
                t1 = float(np.dot(np.cross(p2 - p, u2), cr)) / ncr**2
                o = p + t1 * z
                x = nh if abs(dist) <= _EPS * scale else (nh if dist > 0 else -nh)
        frames.append((o, x, z))
        prev = frames[-1]
    base_pose = None if base_ok else _frame(*frames[0])
    if base_pose is not None:  # frame 1 at q = 0 is frame 0: the offset is the base pose
        inv0 = np.linalg.inv(base_pose)
        frames = [
            (inv0[:3, :3] @ o + inv0[:3, 3], inv0[:3, :3] @ x, inv0[:3, :3] @ z)
            for o, x, z in frames
        ]
    prevs = [(o_b, x_b, z_b) if base_ok else frames[0], *frames]
    rows = [
        _row(prevs[k], fr, sigmas[k], f"joint {names[path[k]]!r}", scale)
        for k, fr in enumerate(frames)
    ]
    for k in snapped_rows:  # snapped twists: exact multiples of π/2 (within rounding of one)
        turns = round(rows[k].alpha / _HALF_PI)
        if abs(rows[k].alpha - turns * _HALF_PI) < 1e-9:
            rows[k] = replace(rows[k], alpha=0.0 if turns == 0 else turns * _HALF_PI)
    last = _frame(*frames[-1])
    tool = np.linalg.inv(last)
    tool = tool @ t_base_tip if base_pose is None else tool @ inv0 @ t_base_tip
    tool[3] = (0.0, 0.0, 0.0, 1.0)
    u, _, vt = np.linalg.svd(tool[:3, :3])
    tool[:3, :3] = u @ vt
    joints = [np.zeros(3), *points, t_base_tip[:3, 3]]  # size: twice the path's length [m]
    size = 2.0 * sum(float(np.linalg.norm(b - a)) for a, b in zip(joints[:-1], joints[1:])) + 1e-9
    values = [(f"d{k + 1}", r.d, k) for k, r in enumerate(rows)]
    values += [(f"r{k + 1}", r.r, k) for k, r in enumerate(rows)]
    values += [("the tool offset", float(np.linalg.norm(tool[:3, 3])), len(rows) - 1)]
    for label, value, k in values:
        if abs(value) <= size:
            continue
        # the usual cause: axes k-1, k or k, k+1 nearly (not quite) parallel
        worst = ""
        for a in range(max(0, k - 1), min(len(axes) - 1, k + 1)):
            s = float(np.linalg.norm(np.cross(axes[a], axes[a + 1])))
            off = math.atan2(s, abs(float(np.dot(axes[a], axes[a + 1]))))
            if 0.0 < off < 0.1:
                worst = (
                    f"; the axes of {path_names[a]!r} and {path_names[a + 1]!r} are {off:.3g} "
                    f"rad from parallel (angle_tol={tol:.3g} rad): snap them with angle_tol >= "
                    f"{off * 1.01:.3g} or correct the URDF"
                )
                break
        raise ConfigurationError(
            f"chain_from_urdf: {km.name!r} ({km.base} -> {km.tip}): recovered {label} = "
            f"{value:.6g} m is larger than the chain itself (size bound {size:.4g} m){worst}",
            parameter="angle_tol",
            value=tol,
            allowed=f"recovered lengths <= {size:.4g} m",
        )
    zeroed: list[tuple[str, float]] = []
    if tol > 0:  # |d|, |r| and tool offsets within rounding of the URDF's constants: clean zeros
        tiny = _LEN_TOL * max(1.0, size)  # (each moves the tip by its size)
        for k, row in enumerate(rows):
            for key in ("d", "r"):
                v = getattr(row, key)
                if v != 0.0 and abs(v) < tiny:
                    zeroed.append((f"{key}{k + 1}", v))
                    row = rows[k] = replace(row, d=0.0) if key == "d" else replace(row, r=0.0)
        for i, axis in enumerate("xyz"):
            v = float(tool[i, 3])
            if v != 0.0 and abs(v) < tiny:
                if abs(v) > 1e-14:  # beyond rounding: say so
                    zeroed.append((f"tool_{axis}", v))
                tool[i, 3] = 0.0
    limits = []
    for k in range(n):
        lo, hi = float(km.lower[k]), float(km.upper[k])
        if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi and max(-lo, hi) <= 1e6):
            lo, hi = (-math.pi, math.pi) if sigmas[k] == "revolute" else (-0.1, 0.1)
        vel = float(km.velocity_limit[k]) if math.isfinite(km.velocity_limit[k]) else 10.0
        eff = float(km.effort_limit[k]) if math.isfinite(km.effort_limit[k]) else 10.0
        limits.append(JointLimits(lo, hi, max(vel, 0.0), max(eff, 0.0)))
    jnames = tuple(_clean(names[i]) for i in path)
    base_name, tip_name = _clean(km.base), _clean(km.tip)
    links = tuple(
        f"{base_name}_kk{j}" if f"{base_name}_kk{j}" != tip_name else f"kk{j}"
        for j in range(1, n + 1)
    )
    fk_bound = sum(s.angle * s.reach for s in snaps) + sum(abs(v) for _, v in zeroed)
    description = f"Khalil table recovered from {km.name!r} ({km.base} -> {km.tip})"
    if snaps:
        description += f"; snapped (angle_tol {tol:.3g} rad): " + ", ".join(str(s) for s in snaps)
    if zeroed:
        description += "; zeroed " + ", ".join(f"{k} = {v:.2g} m" for k, v in zeroed)
    chain = Chain(
        rows=tuple(rows),
        joint_names=jnames,
        limits=tuple(limits),
        name=_clean(getattr(m, "name", "") or "chain"),
        base=base_name,
        tip=tip_name,
        link_names=links,
        base_pose=None if base_pose is None else Pose.of(base_pose),
        tool=Pose.of(tool),
        description=description,
    )
    fk_error = _check(chain, km, fk_bound, sum(s.angle for s in snaps))
    return TableRecovery(chain, tuple(snaps), tol, size, fk_bound, fk_error, tuple(zeroed))


def _check(chain: Chain, km: Any, bound: float = 0.0, turn: float = 0.0) -> float:
    """Table FK vs Pinocchio's; returns the largest position difference [m]."""
    rng = np.random.default_rng(0)
    lo = np.where(np.isfinite(km.lower), km.lower, -math.pi)
    hi = np.where(np.isfinite(km.upper), km.upper, math.pi)
    qs = [np.zeros(km.nq)] + [rng.uniform(lo, hi) for _ in range(8)]
    worst = worst_pos = worst_rot = 0.0
    for q in qs:
        a, b = table_fk(chain, q), km.fk(q)
        worst = max(worst, float(np.abs(a - b).max()))
        worst_pos = max(worst_pos, float(np.linalg.norm(a[:3, 3] - b[:3, 3])))
        worst_rot = max(worst_rot, float(np.abs(a[:3, :3] - b[:3, :3]).max()))
    scale = max(1.0, float(np.abs(km.fk(qs[0])[:3, 3]).max()))
    slack = 1e-9 * scale
    if bound == 0.0 and turn == 0.0:
        ok = worst <= slack
    else:
        ok = worst_pos <= bound * (1 + 1e-6) + slack and worst_rot <= 2.0 * turn + slack
    if not ok:
        raise ConfigurationError(
            f"chain_from_urdf: the recovered table of {km.name!r} misses the URDF's forward "
            f"kinematics by {worst:.2e} (base={km.base!r}, tip={km.tip!r}"
            + (f"; snap bound {bound:.2e} m" if bound else "")
            + "); not supported"
        )
    return worst_pos
