"""Legs of any floating-base robot: found in the kinematic tree, their kinematics and IK.

* **Legs from the tree**: every chain of actuated joints from the floating body (the root
  link) to a foot. A foot is either the deepest frame of a branch (a leaf link such as
  solo12's ``FL_FOOT``) or a point given by the user on a frame (``frame:x,y,z``, the offset
  in that frame, in [m]) when the URDF has no foot link (:func:`parse_feet`).
* **Vectorised kinematics** of the tree (any revolute axis, RX/RY/RZ or unaligned, and
  prismatic joints): joint ``j``'s frame is ``parent · P_j · M_j(q_j)`` with ``P_j`` its
  placement at q = 0 (Pinocchio's ``jointPlacements``) and ``M_j`` the rotation
  ``R(a, q) = cos q I + sin q [a]× + (1 − cos q) a aᵀ`` (Rodrigues) or the translation ``a q``
  along its unit axis ``a``. Raw Pinocchio FK is the reference in the tests.
* **Numerical leg IK** (:func:`solve_legs`), used where no closed form recognises the leg:
  damped least squares on the leg's own joints, vectorised over samples and legs, with the
  analytic position Jacobian ``J_k = w_k × (p − o_k)`` (revolute; ``w_k`` for prismatic)::

      Δq = (JᵀJ + λ²I)⁻¹ Jᵀ e,   λ² = 10⁻² ‖e‖² + 10⁻¹⁴ s²   (s: the leg's span)

  clipped to the joint limits, until ``‖e‖ ≤ 10⁻¹³ s`` or the step stalls. All samples start
  from the seed; a sample whose solution is far from its predecessor's (a branch jump) or
  not reached is solved again warm-started from the previous sample. A foot is *reached*
  when the residual is at most :data:`REACH_TOL`; otherwise the residual is the distance of
  the best reachable point found to the target (the leg's ``excess``).
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..exceptions import ConfigurationError, ParameterError

__all__ = [
    "REACH_TOL",
    "FootSpec",
    "LegTree",
    "Tree",
    "axis_rotation",
    "find_legs",
    "leg_fk",
    "parse_feet",
    "solve_legs",
    "tree_poses",
]

#: A foot is reached when the numerical IK residual is at most this [m].
REACH_TOL = 1e-10

#: ``frame:x,y,z`` (the offset optional: ``frame`` alone is the frame's origin).
_SPEC = re.compile(r"^\s*([^:\s,]+)\s*(?::\s*([^:]+))?$")


# ============================================================================ foot specs
@dataclass(frozen=True)
class FootSpec:
    """A foot: a point ``offset`` [m] in the frame ``frame`` (the contact sphere's centre)."""

    frame: str
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)


def _numbers3(text: Any, where: str) -> tuple[float, float, float]:
    try:
        vals = [float(v) for v in (text.split(",") if isinstance(text, str) else text)]
    except (TypeError, ValueError):
        vals = []
    if len(vals) != 3 or not all(math.isfinite(v) for v in vals):
        raise ParameterError(
            f"foot {where}: offset {text!r} is not three finite numbers x,y,z [m]",
            parameter="feet",
            value=str(text),
            allowed="frame:x,y,z (metres, in the frame)",
        )
    return (vals[0], vals[1], vals[2])


def _split_specs(text: str) -> list[str]:
    """``a:1,2,3,b:4,5,6`` or ``a:1,2,3 b:...`` → one item per foot."""
    items: list[str] = []
    for part in re.split(r"[\s;]+", text.strip()):
        if not part:
            continue
        # a comma before a name with a colon starts a new foot
        items += [p for p in re.split(r",(?=[^,:\s]+:)", part) if p]
    return items


def _load_file(path: Path) -> Any:
    text = path.read_text(encoding="utf-8")
    suffix = path.suffix.lower()
    try:
        if suffix == ".json":
            return json.loads(text)
        if suffix == ".toml":
            import tomllib

            return tomllib.loads(text)
        import yaml

        return yaml.safe_load(text)
    except Exception as exc:  # the parsers' own error types differ
        raise ParameterError(
            f"feet file {str(path)!r}: cannot be read ({exc})", parameter="feet", value=str(path)
        ) from None


def parse_feet(spec: Any) -> tuple[FootSpec, ...] | None:
    """Foot specifications from any of the accepted forms (``None`` stays ``None``).

    Accepted: ``"tibia_lf:0,0.16,0.029"`` (several separated by spaces, ``;`` or commas), a
    list of such strings, a mapping ``{"tibia_lf": (x, y, z), ...}``, a sequence of
    :class:`FootSpec`, or a table file (``.yaml``/``.yml``/``.toml``/``.json``) holding either
    such a mapping or ``feet = [{frame = "...", offset = [x, y, z]}, ...]`` (optionally under
    a ``feet`` key). Offsets in [m], in the named frame.

    Raises:
        ParameterError: A malformed spec (named).

    """
    if spec is None:
        return None
    if isinstance(spec, Path) or (
        isinstance(spec, str) and Path(spec).suffix.lower() in (".yaml", ".yml", ".toml", ".json")
    ):
        path = Path(spec)
        if not path.is_file():
            raise ParameterError(
                f"feet file {str(path)!r} does not exist", parameter="feet", value=str(path)
            )
        data = _load_file(path)
        if isinstance(data, Mapping) and "feet" in data:
            data = data["feet"]
        return parse_feet(data)
    out: list[FootSpec] = []
    if isinstance(spec, str):
        items: list[Any] = _split_specs(spec)
    elif isinstance(spec, Mapping):
        items = [FootSpec(str(k), _numbers3(v, str(k))) for k, v in spec.items()]
    else:
        try:
            items = list(spec)
        except TypeError:
            raise ParameterError(
                f"feet={spec!r} is not a foot spec", parameter="feet", value=repr(spec)
            ) from None
    for item in items:
        if isinstance(item, FootSpec):
            out.append(item)
        elif isinstance(item, Mapping) and "frame" in item:
            out.append(FootSpec(str(item["frame"]), _numbers3(item.get("offset", (0, 0, 0)), "")))
        elif isinstance(item, str):
            for piece in _split_specs(item):
                m = _SPEC.match(piece)
                if m is None:
                    raise ParameterError(
                        f"foot spec {piece!r} is not 'frame:x,y,z'",
                        parameter="feet",
                        value=piece,
                        allowed="frame:x,y,z",
                    )
                off = (0.0, 0.0, 0.0) if m.group(2) is None else _numbers3(m.group(2), piece)
                out.append(FootSpec(m.group(1), off))
        else:
            raise ParameterError(
                f"foot spec {item!r} is not 'frame:x,y,z'", parameter="feet", value=repr(item)
            )
    if not out:
        raise ParameterError("feet: no foot given", parameter="feet", value=repr(spec))
    frames = [f.frame for f in out]
    if len(set(frames)) != len(frames):
        raise ParameterError(
            f"feet: a frame is named twice in {frames}", parameter="feet", value=frames
        )
    return tuple(out)


# ============================================================================ the tree
@dataclass(frozen=True)
class Tree:
    """The actuated joints of a floating-base tree as arrays (joint order = Pinocchio's q).

    Attributes:
        parents: (n,) index of each joint's parent joint (−1: the floating body).
        placements: (n, 4, 4) joint placements in the parent joint's frame at q = 0.
        axes: (n, 3) unit joint axes in the joint's own frame.
        prismatic: (n,) True for prismatic joints.

    """

    parents: np.ndarray
    placements: np.ndarray
    axes: np.ndarray
    prismatic: np.ndarray


def axis_rotation(axes: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Rotations (..., 3, 3) about unit ``axes`` (..., 3) by ``q`` (...) [rad] (Rodrigues)."""
    c, s = np.cos(q), np.sin(q)
    x, y, z = axes[..., 0], axes[..., 1], axes[..., 2]
    v = 1.0 - c
    R = np.empty(np.shape(q) + (3, 3))
    R[..., 0, 0] = c + v * x * x
    R[..., 0, 1] = v * x * y - s * z
    R[..., 0, 2] = v * x * z + s * y
    R[..., 1, 0] = v * x * y + s * z
    R[..., 1, 1] = c + v * y * y
    R[..., 1, 2] = v * y * z - s * x
    R[..., 2, 0] = v * x * z - s * y
    R[..., 2, 1] = v * y * z + s * x
    R[..., 2, 2] = c + v * z * z
    return R


def _local(P: np.ndarray, axis: np.ndarray, prismatic: Any, q: np.ndarray) -> np.ndarray:
    """``P · M(q)`` (N, 4, 4) for one joint (placement P (..., 4, 4), axis (..., 3))."""
    n = q.shape[0]
    out = np.empty((n, 4, 4))
    out[:, 3] = (0.0, 0.0, 0.0, 1.0)
    Pr = P[..., :3, :3]
    if np.ndim(prismatic) == 0 and not prismatic:
        out[:, :3, :3] = Pr @ axis_rotation(np.broadcast_to(axis, (n, 3)), q)
        out[:, :3, 3] = P[..., :3, 3]
        return out
    pr = np.broadcast_to(np.asarray(prismatic, dtype=bool), (n,))
    rot = axis_rotation(np.broadcast_to(axis, (n, 3)), np.where(pr, 0.0, q))
    out[:, :3, :3] = Pr @ rot
    shift = np.where(pr[:, None], np.broadcast_to(axis, (n, 3)) * q[:, None], 0.0)
    out[:, :3, 3] = P[..., :3, 3] + (Pr @ shift[..., None])[..., 0]
    return out


def tree_poses(tree: Tree, q: np.ndarray, base: np.ndarray) -> np.ndarray:
    """World poses (N, n, 4, 4) of the joints' frames at joints ``q`` (N, n), bodies ``base``."""
    n, nj = q.shape
    out = np.empty((n, nj, 4, 4))
    for j in range(nj):
        local = _local(tree.placements[j], tree.axes[j], bool(tree.prismatic[j]), q[:, j])
        par = int(tree.parents[j])
        out[:, j] = (base if par < 0 else out[:, par]) @ local
    return out


def leg_fk(
    placements: np.ndarray, axes: np.ndarray, prismatic: np.ndarray, foot: np.ndarray, q: Any
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Body-frame kinematics of E leg instances (one serial chain each, m joints).

    Args:
        placements: (E, m, 4, 4) each joint's placement in the previous joint's frame (the
            first in the body frame).
        axes: (E, m, 3) unit axes; prismatic: (E, m) booleans.
        foot: (E, 3) the foot in the last joint's frame.
        q: (E, m) joint values.

    Returns:
        ``(origins, world_axes, feet)``: (E, m, 3) joint origins, (E, m, 3) joint axes in the
        body frame, (E, 3) feet.

    """
    q = np.asarray(q, dtype=float)
    e, m = q.shape
    T = np.broadcast_to(np.eye(4), (e, 4, 4))
    origins = np.empty((e, m, 3))
    waxes = np.empty((e, m, 3))
    any_p = bool(np.any(prismatic))
    for k in range(m):
        T = T @ placements[:, k]
        origins[:, k] = T[:, :3, 3]
        waxes[:, k] = (T[:, :3, :3] @ axes[:, k, :, None])[..., 0]
        R = axis_rotation(axes[:, k], np.where(prismatic[:, k], 0.0, q[:, k]) if any_p else q[:, k])
        Tn = np.empty((e, 4, 4))
        Tn[:, :3, :3] = T[:, :3, :3] @ R
        Tn[:, :3, 3] = T[:, :3, 3]
        if any_p:
            Tn[:, :3, 3] += np.where(prismatic[:, k, None], waxes[:, k] * q[:, k, None], 0.0)
        Tn[:, 3] = (0.0, 0.0, 0.0, 1.0)
        T = Tn
    feet = (T[:, :3, :3] @ foot[..., None])[..., 0] + T[:, :3, 3]
    return origins, waxes, feet


# ============================================================================ legs in a tree
@dataclass(frozen=True)
class LegTree:
    """One leg found in the tree: its joints (indices into q) and its foot.

    Attributes:
        name: The leg's name.
        joints: Indices of the leg's joints in q, from the body outward.
        foot_frame: The frame the foot is given on (a leaf link, or the user's frame).
        foot_joint: Index (in q) of the joint that moves the foot.
        foot_placement: (4, 4) the foot frame in that joint's frame (offset included).

    """

    name: str
    joints: tuple[int, ...]
    foot_frame: str
    foot_joint: int
    foot_placement: np.ndarray


def _strip_common(names: list[str]) -> list[str]:
    """Names with a common prefix/suffix (ending/starting at ``_``/``-``) removed, if unique."""
    if len(names) < 2:
        return names
    pre = 0
    while all(len(n) > pre and n[pre] == names[0][pre] for n in names):
        pre += 1
    pre = max((i + 1 for i in range(pre) if names[0][i] in "_-"), default=0)
    suf = 0
    while all(len(n) > suf and n[-1 - suf] == names[0][-1 - suf] for n in names):
        suf += 1
    suf = max((i + 1 for i in range(suf) if names[0][-1 - i] in "_-"), default=0)
    out = [n[pre : len(n) - suf] for n in names]
    return out if all(out) and len(set(out)) == len(out) else names


def _frame_depth(model: Any, fid: int) -> int:
    depth = 0
    f = model.frames[fid]
    parent = getattr(f, "parentFrame", getattr(f, "previousFrame", 0))
    while fid != 0 and parent != fid and depth < 10_000:
        depth += 1
        fid = int(parent)
        f = model.frames[fid]
        parent = getattr(f, "parentFrame", getattr(f, "previousFrame", 0))
    return depth


def find_legs(
    model: Any, feet: tuple[FootSpec, ...] | None, *, ccw: bool = True
) -> tuple[list[LegTree], list[int]]:
    """The legs of a Pinocchio model with a free-flyer root (joint 1), and the other joints.

    Legs: with ``feet``, one per foot (the joints from the root to the foot's frame); without,
    one per leaf of the joint tree whose deepest frame is away from its joint (the foot), the
    branches shorter than half the longest one left out (a head, a sensor). Legs are ordered
    counter-clockwise seen from above starting at the front-left (the order of the built-in
    hexapod: ``atan2(y, x)`` of the first joint in [0, 2π)); ``ccw=False`` keeps the order of
    ``feet``.

    Returns:
        ``(legs, others)``: the legs (joint indices are model joint ids minus 2, i.e. indices
        into q[7:]) and the ids of the joints that belong to no leg.

    Raises:
        ConfigurationError: A frame that does not exist, a foot on the floating body, legs
            sharing joints, no leg found.

    """
    import pinocchio as pin

    nj = model.njoints
    children: dict[int, list[int]] = {j: [] for j in range(nj)}
    for j in range(2, nj):
        children[int(model.parents[j])].append(j)
    data = model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model))
    found: list[tuple[str, int, np.ndarray]] = []  # (frame name, joint id, foot in joint)
    if feet is not None:
        names = [f.name for f in model.frames]
        for spec in feet:
            if not model.existFrame(spec.frame):
                close = [n for n in names if spec.frame.lower() in n.lower()][:8]
                raise ConfigurationError(
                    f"foot frame {spec.frame!r} is not a frame of the robot"
                    + (f"; similar: {close}" if close else f"; frames: {names[:40]}"),
                    parameter="feet",
                    value=spec.frame,
                    allowed=names,
                )
            fr = model.frames[model.getFrameId(spec.frame)]
            off = np.eye(4)
            off[:3, 3] = spec.offset
            found.append((spec.frame, int(fr.parentJoint), fr.placement.homogeneous @ off))
    else:
        for j in range(2, nj):
            if children[j]:
                continue
            cands = [i for i, f in enumerate(model.frames) if int(f.parentJoint) == j]
            if not cands:
                continue

            def key(i: int) -> tuple[int, float]:
                return (
                    _frame_depth(model, i),
                    float(np.linalg.norm(model.frames[i].placement.translation)),
                )

            best = max(cands, key=key)
            fr = model.frames[best]
            if np.linalg.norm(fr.placement.translation) <= 1e-9:
                raise ConfigurationError(
                    f"the branch ending at joint {model.names[j]!r} has no foot link (its "
                    f"deepest frame {fr.name!r} is on the joint axis); name the foot as a frame "
                    f"plus an offset, e.g. --foot {fr.name}:0,0,-0.1 (feet={{'{fr.name}': "
                    "(x, y, z)}) for every leg",
                    parameter="feet",
                    value=str(fr.name),
                    allowed="frame:x,y,z",
                )
            found.append((str(fr.name), j, fr.placement.homogeneous.copy()))
    legs_raw = []
    for frame, j, place in found:
        if j <= 1:
            raise ConfigurationError(
                f"foot frame {frame!r} is on the floating body, not on a leg",
                parameter="feet",
                value=frame,
            )
        path = []
        k = j
        while k > 1:
            path.append(k)
            k = int(model.parents[k])
        path.reverse()
        foot_w = data.oMi[j].homogeneous @ place
        span = 0.0
        pts = [data.oMi[p].translation for p in path] + [foot_w[:3, 3]]
        for a, b in zip(pts[:-1], pts[1:]):
            span += float(np.linalg.norm(np.asarray(b) - np.asarray(a)))
        legs_raw.append((frame, path, place, span, np.asarray(data.oMi[path[0]].translation)))
    if feet is None and legs_raw:
        longest = max(r[3] for r in legs_raw)
        legs_raw = [r for r in legs_raw if r[3] >= 0.5 * longest]
    if not legs_raw:
        raise ConfigurationError(
            "no leg found: the robot has no branch of actuated joints from its root to a foot",
            parameter="feet",
        )
    used: dict[int, str] = {}
    for frame, path, *_ in legs_raw:
        for p in path:
            if p in used:
                raise ConfigurationError(
                    f"feet {used[p]!r} and {frame!r} share the joint {model.names[p]!r}: "
                    "a leg is the chain from the body to one foot",
                    parameter="feet",
                    value=[used[p], frame],
                )
            used[p] = frame
    if ccw:
        yaw = [math.atan2(r[4][1], r[4][0]) % (2 * math.pi) for r in legs_raw]
        order = sorted(range(len(legs_raw)), key=lambda i: (round(yaw[i], 9), legs_raw[i][0]))
        legs_raw = [legs_raw[i] for i in order]
    names = _strip_common([r[0] for r in legs_raw])
    legs = [
        LegTree(name, tuple(p - 2 for p in path), frame, path[-1] - 2, place)
        for name, (frame, path, place, _s, _o) in zip(names, legs_raw)
    ]
    others = sorted(set(range(2, nj)) - set(used))
    return legs, others


# ============================================================================ numerical IK
def solve_legs(
    placements: np.ndarray,
    axes: np.ndarray,
    prismatic: np.ndarray,
    foot: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    targets: np.ndarray,
    seed: np.ndarray,
    *,
    span: float,
    iterations: int = 60,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Damped least squares for G legs of m joints at N samples (see the module doc).

    Args:
        placements, axes, prismatic, foot: The legs' constants ((G, m, 4, 4), (G, m, 3),
            (G, m), (G, 3); see :func:`leg_fk`).
        lower, upper: (G, m) joint limits.
        targets: (N, G, 3) body-frame foot targets [m].
        seed: (G, m) the joints before the first sample.
        span: The legs' length scale [m] (tolerances).
        iterations: Cap on the steps per solve.

    Returns:
        ``(q, residual, reached)``: (N, G, m), (N, G) [m], (N, G).

    """
    n, g, _ = targets.shape
    m = placements.shape[1]
    q = np.broadcast_to(seed, (n, g, m)).reshape(n * g, m).copy()
    gi = np.tile(np.arange(g), n)
    tgt = targets.reshape(n * g, 3)
    res = _dls(placements, axes, prismatic, foot, lower, upper, tgt, q, gi, span, iterations)
    q = q.reshape(n, g, m)
    res = res.reshape(n, g)
    # continuity: re-solve, warm-started from the previous sample, where a branch jumped
    prev = np.asarray(seed, dtype=float)
    for i in range(n):
        jump = np.abs(q[i] - prev).max(axis=1) > 0.5
        bad = jump | (res[i] > REACH_TOL)
        if bad.any():
            idx = np.flatnonzero(bad)
            qi = prev[idx].copy()
            ri = _dls(
                placements, axes, prismatic, foot, lower, upper,
                targets[i, idx], qi, idx, span, iterations,
            )  # fmt: skip
            better = (ri <= np.maximum(res[i, idx], REACH_TOL)) | (ri <= REACH_TOL)
            q[i, idx] = np.where(better[:, None], qi, q[i, idx])
            res[i, idx] = np.where(better, ri, res[i, idx])
        prev = q[i]
    return q, res, res <= REACH_TOL


def _dls(
    placements: np.ndarray,
    axes: np.ndarray,
    prismatic: np.ndarray,
    foot: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    tgt: np.ndarray,
    q: np.ndarray,
    gi: np.ndarray,
    span: float,
    iterations: int,
) -> np.ndarray:
    """Iterate DLS in place on ``q`` (E, m) for leg indices ``gi`` (E,); residuals (E,)."""
    e_n, m = q.shape
    res = np.full(e_n, np.inf)
    active = np.arange(e_n)
    lam_floor = 1e-14 * span * span
    done_tol = 1e-13 * span
    eye = np.eye(m)
    for _ in range(iterations):
        g = gi[active]
        o, w, p = leg_fk(placements[g], axes[g], prismatic[g], foot[g], q[active])
        err = tgt[active] - p
        norm = np.linalg.norm(err, axis=1)
        res[active] = norm
        keep = norm > done_tol
        if not keep.any():
            break
        active, g, o, w, p, err, norm = (
            a[keep] for a in (active, g, o, w, p, err, norm)
        )  # fmt: skip
        J = np.where(prismatic[g][:, None, :], np.swapaxes(w, 1, 2), 0.0)
        rev = np.cross(w, p[:, None, :] - o)  # (E, m, 3)
        J = np.where(prismatic[g][:, None, :], J, np.swapaxes(rev, 1, 2))  # (E, 3, m)
        Jt = np.swapaxes(J, 1, 2)
        lam2 = 1e-2 * norm * norm + lam_floor
        A = Jt @ J + lam2[:, None, None] * eye
        dq = np.linalg.solve(A, (Jt @ err[..., None]))[..., 0]
        big = np.abs(dq).max(axis=1)
        dq *= np.minimum(1.0, 0.5 / np.maximum(big, 1e-300))[:, None]
        new = np.clip(q[active] + dq, lower[g], upper[g])
        moved = np.abs(new - q[active]).max(axis=1) > 1e-15
        q[active] = new
        active = active[moved]
        if active.size == 0:
            break
    if active.size:  # the last step's residual
        g = gi[active]
        _o, _w, p = leg_fk(placements[g], axes[g], prismatic[g], foot[g], q[active])
        res[active] = np.linalg.norm(tgt[active] - p, axis=1)
    return res
