"""Recover a Khalil–Kleinfinger table from a serial URDF chain (:func:`chain_from_urdf`).

The model is loaded with :func:`hexapod_kin.load` (the loader gate, then Pinocchio; a sub-chain
is picked with ``base=`` / ``tip=``); the joint placements and axes are read from the Pinocchio
model at ``q = 0``, which gives one line in space per joint (a point and the unit axis, in the
base frame). Khalil frames are then placed on those lines:

* ``z_j`` is joint ``j``'s axis, with the URDF's direction (so ``q`` keeps its sign);
* ``x_j`` is the common normal from line ``j`` to line ``j + 1`` and frame ``j``'s origin is
  its foot on line ``j``. Intersecting axes: ``x_j = z_j × z_{j+1}`` at the intersection.
  Parallel axes: the origin is where ``x_{j-1}`` meets line ``j`` (``r_j = 0``) and ``x_j``
  points to line ``j + 1``; coincident axes keep ``x_j = x_{j-1}``. The last joint keeps
  ``x_n = x_{n-1}`` (``θ_n = r_n = 0`` at ``q = 0``);
* frame 0 is the base link's frame when it satisfies Khalil's rule for row 1 (``z_1 ⟂ x_0`` and
  joint 1's axis meeting the ``x_0`` line — true for every URDF hexapod_kin writes), else it is
  frame 1 at ``q = 0`` and the offset goes to ``Chain.base_pose``;
* what remains to the tip frame is ``Chain.tool``.

Each row ``(α_j, d_j, θ_j, r_j)`` is read off consecutive frames; fixed URDF joints need no
rows (Pinocchio folds them into the placements). The result is checked: the table's forward
kinematics must equal Pinocchio's at ``q = 0`` and at random configurations, else an error.
"""

from __future__ import annotations

import math
import re
from typing import Any

import numpy as np

from ._table_kin import table_fk
from .exceptions import ConfigurationError, SourceError
from .params import Chain, JointLimits, KhalilRow, Pose

__all__ = ["chain_from_urdf"]

_REVOLUTE = (
    "JointModelRX",
    "JointModelRY",
    "JointModelRZ",
    "JointModelRevoluteUnaligned",
    "JointModelRUBX",
    "JointModelRUBY",
    "JointModelRUBZ",
    "JointModelRevoluteUnboundedUnaligned",
)
_PRISMATIC = ("JointModelPX", "JointModelPY", "JointModelPZ", "JointModelPrismaticUnaligned")
_EPS = 1e-10


def _axis(joint: Any) -> np.ndarray:
    name = joint.shortname()
    for suffix, vec in (("X", (1.0, 0, 0)), ("Y", (0, 1.0, 0)), ("Z", (0, 0, 1.0))):
        if name.endswith(suffix) and ("Unaligned" not in name):
            return np.array(vec, dtype=float)
    axis = np.asarray(joint.extract().axis, dtype=float)
    return axis / np.linalg.norm(axis)


def _clean(name: str) -> str:
    out = re.sub(r"[^A-Za-z0-9_.-]", "_", str(name))
    return out or "x"


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
    t = float(np.dot(np.cross(p - o, u), n)) / nn
    point = o + t * x
    off = point - p
    miss = off - np.dot(off, u) * u
    if float(np.linalg.norm(miss)) > _EPS * scale:
        return None
    return point


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


def chain_from_urdf(
    source: Any, base: str | None = None, tip: str | None = None, **load_kwargs: Any
) -> Chain:
    """Recover the Khalil table (and base/tool poses) of a serial URDF chain.

    Args:
        source: Anything :func:`hexapod_kin.load` takes (URDF path or text, ``erd:NAME``,
            preset, or an already loaded model).
        base: Base frame name (default: the source's default base).
        tip: Tip frame name (default: the source's default tip).
        **load_kwargs: Passed to :func:`hexapod_kin.load` (e.g. preset parameters).

    Returns:
        A :class:`~hexapod_kin.params.Chain` whose :func:`~hexapod_kin.table_fk`
        equals the URDF's ``T_base_tip`` (checked to 1e-9 relative at random configurations;
        1e-12 absolute in practice).

    Raises:
        ConfigurationError: A joint the table cannot express (named), a branch between
            ``base`` and ``tip`` (not serial), or a failed check.
        HexapodKinError: Whatever :func:`hexapod_kin.load` raises for the source.

    """
    from .kinematics import KinematicModel, load

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
    for i in range(1, m.njoints):
        kind = m.joints[i].shortname()
        if kind not in _REVOLUTE + _PRISMATIC:
            raise ConfigurationError(
                f"joint {names[i]!r} is a {kind}; a Khalil table expresses revolute, continuous, "
                "prismatic and fixed joints only"
            )
    tip_id = km.tip_id
    frame = m.frames[tip_id]
    path = []
    j = int(frame.parentJoint)
    while j != 0:
        path.append(j)
        j = int(m.parents[j])
    path.reverse()
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
        axes.append(t[:3, :3] @ _axis(m.joints[i]))
        sigmas.append("prismatic" if m.joints[i].shortname() in _PRISMATIC else "revolute")
    scale = max(1.0, float(np.abs(points).max()), float(np.abs(t_base_tip[:3, 3]).max()))
    n = len(path)
    # frame 0: the base frame when row 1 can start from it
    o_b, x_b, z_b = np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 0, 1.0])
    base_ok = (
        abs(float(np.dot(axes[0], x_b))) < 1e-12
        and _meet(o_b, x_b, points[0], axes[0], scale) is not None
    )
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
    rows = []
    if base_ok:
        prev0 = (o_b, x_b, z_b)
        base_pose = None
    else:
        prev0 = frames[0]
        base_pose = _frame(*frames[0])
        inv0 = np.linalg.inv(base_pose)
        frames = [
            (inv0[:3, :3] @ o + inv0[:3, 3], inv0[:3, :3] @ x, inv0[:3, :3] @ z)
            for o, x, z in frames
        ]
        prev0 = frames[0]
    prev_f = prev0
    for k, fr in enumerate(frames):
        rows.append(_row(prev_f, fr, sigmas[k], f"joint {names[path[k]]!r}", scale))
        prev_f = fr
    last = _frame(*frames[-1])
    if base_pose is not None:
        tool = np.linalg.inv(last) @ np.linalg.inv(base_pose) @ t_base_tip
    else:
        tool = np.linalg.inv(last) @ t_base_tip
    tool[3] = (0.0, 0.0, 0.0, 1.0)
    u, _, vt = np.linalg.svd(tool[:3, :3])
    tool[:3, :3] = u @ vt
    limits = []
    for k in range(n):
        lo, hi = float(km.lower[k]), float(km.upper[k])
        if (
            not (math.isfinite(lo) and math.isfinite(hi))
            or lo > hi
            or abs(lo) > 1e6
            or abs(hi) > 1e6
        ):
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
        description=f"Khalil table recovered from {km.name!r} ({km.base} -> {km.tip})",
    )
    _check(chain, km)
    return chain


def _check(chain: Chain, km: Any) -> None:
    rng = np.random.default_rng(0)
    lo = np.where(np.isfinite(km.lower), km.lower, -math.pi)
    hi = np.where(np.isfinite(km.upper), km.upper, math.pi)
    qs = [np.zeros(km.nq)] + [rng.uniform(lo, hi) for _ in range(8)]
    worst = 0.0
    for q in qs:
        err = float(np.abs(table_fk(chain, q) - km.fk(q)).max())
        worst = max(worst, err)
    scale = max(1.0, float(np.abs(km.fk(qs[0])[:3, 3]).max()))
    if worst > 1e-9 * scale:
        raise ConfigurationError(
            f"chain_from_urdf: the recovered table of {km.name!r} misses the URDF's forward "
            f"kinematics by {worst:.2e} (base={km.base!r}, tip={km.tip!r}); not supported"
        )
