"""Pinocchio model surgery for :mod:`hexapod_kin.model`: joint kinds, frames, sub-chains, tips."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from .exceptions import ConfigurationError, FrameNotFoundError

__all__ = ["add_tool_frame", "floating_model", "frame_index", "joint_kind", "path_frames",
           "reduce_model", "reduced_model", "root_link_frame"]  # fmt: skip

_T = pin.FrameType
_FRAME_PREFERENCE = (_T.BODY, _T.OP_FRAME, _T.JOINT, _T.FIXED_JOINT, _T.SENSOR)


#: The one-variable joints Pinocchio builds from a URDF, by kind (``shortname()`` prefixes).
_JOINT_KINDS = (
    ("JointModelRUB", "continuous"),
    ("JointModelRevoluteUnboundedUnaligned", "continuous"),
    ("JointModelRevoluteUnaligned", "revolute"),
    ("JointModelPrismaticUnaligned", "prismatic"),
    ("JointModelR", "revolute"),
    ("JointModelP", "prismatic"),
)
_UNIT = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}


def joint_kind(joint: Any) -> tuple[str, np.ndarray] | None:
    """``(kind, axis in the joint's frame)`` of a one-variable Pinocchio joint, else ``None``.

    The one place joint kinds are told apart: ``"revolute"`` (``RX/RY/RZ``,
    ``RevoluteUnaligned``), ``"continuous"`` (``RUBX/Y/Z``, ``RevoluteUnboundedUnaligned``:
    ``(cos q, sin q)`` in Pinocchio's ``q``) and ``"prismatic"`` (``PX/PY/PZ``,
    ``PrismaticUnaligned``); the X/Y/Z kinds' axes are exact unit vectors.
    """
    name = str(joint.shortname())
    for prefix, kind in _JOINT_KINDS:
        if name == prefix and "Unaligned" in prefix:
            concrete = joint.extract() if hasattr(joint, "extract") else joint
            if hasattr(concrete, "axis"):
                return kind, np.asarray(concrete.axis, dtype=float)
            data = joint.createData()  # no axis in the binding: the motion subspace S
            joint.calc(data, np.r_[1.0, np.zeros(joint.nq - 1)])
            s = np.asarray(data.S, dtype=float).reshape(6)
            return kind, s[:3].copy() if kind == "prismatic" else s[3:].copy()
        if name[:-1] == prefix and name[-1] in _UNIT:
            return kind, np.array(_UNIT[name[-1]])
    return None


def frame_index(model: pin.Model, name: str) -> int:
    """Index of the frame ``name`` (which must exist): BODY first, then OP, JOINT, FIXED.

    Unlike ``getFrameId``, for a link and a joint named alike (anymal's ``RH_HAA``).
    """
    hits = [i for i, f in enumerate(model.frames) if f.name == name]
    if len(hits) == 1:
        return hits[0]
    for kind in _FRAME_PREFERENCE:
        for i in hits:
            if model.frames[i].type == kind:
                return i
    return hits[0]


def add_tool_frame(model: pin.Model, tip: str, tool: np.ndarray) -> tuple[pin.Model, str]:
    """A copy of ``model`` with a frame ``<tip>_tool`` at ``tip · tool``; returns its name."""
    out = pin.Model(model)
    tip_id = frame_index(out, tip)
    tip_frame = out.frames[tip_id]
    name = f"{tip}_tool"
    k = 1
    while out.existFrame(name):
        k += 1
        name = f"{tip}_tool{k}"
    placement = tip_frame.placement * pin.SE3(tool[:3, :3].copy(), tool[:3, 3].copy())
    out.addFrame(pin.Frame(name, tip_frame.parentJoint, tip_id, placement, pin.FrameType.OP_FRAME))
    return out, name


def floating_model(fixed: pin.Model) -> pin.Model:
    """``fixed`` (a URDF's model) with a free-flyer ``root_joint``, without a second parse.

    Equal (``==``) to ``pinocchio.buildModelFromXML(text, JointModelFreeFlyer())``: joints one
    index up, the root link's inertia on ``root_joint``, frames unchanged otherwise.
    """
    out = pin.Model()
    out.name = fixed.name
    root = out.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root_joint")
    if fixed.nframes > 1 and fixed.frames[1].inertia.mass > 0:  # the root link's <inertial>
        out.appendBodyToJoint(root, pin.Inertia.Zero(), pin.SE3.Identity())
    out.addJointFrame(root, 0)
    for j in range(1, fixed.njoints):
        jm = fixed.joints[j]
        iq, iv = slice(jm.idx_q, jm.idx_q + jm.nq), slice(jm.idx_v, jm.idx_v + jm.nv)
        k = out.addJoint(
            int(fixed.parents[j]) + 1,
            jm,
            fixed.jointPlacements[j],
            fixed.names[j],
            fixed.lowerEffortLimit[iv],
            fixed.upperEffortLimit[iv],
            fixed.lowerVelocityLimit[iv],
            fixed.upperVelocityLimit[iv],
            fixed.lowerPositionLimit[iq],
            fixed.upperPositionLimit[iq],
            fixed.positionLimitMargin[iq],
            fixed.lowerDryFrictionLimit[iv],
            fixed.upperDryFrictionLimit[iv],
            fixed.damping[iv],
        )
        out.appendBodyToJoint(k, pin.Inertia.Zero(), pin.SE3.Identity())
    for i in range(1, fixed.nframes):
        f = fixed.frames[i]
        inertia = pin.Inertia.Zero() if i == 1 else f.inertia
        frame = pin.Frame(
            f.name, int(f.parentJoint) + 1, int(f.parentFrame) + 1, f.placement, f.type, inertia
        )
        out.addFrame(frame, False)
    for j in range(fixed.njoints):  # assigned last: a frame added on a joint adds to it
        out.inertias[j + 1] = fixed.inertias[j]
    return out


def root_link_frame(model: pin.Model) -> str:
    """The URDF root link's frame (fixed at the origin of ``universe``), else ``universe``."""
    for frame in model.frames:
        if (
            frame.type == pin.FrameType.BODY
            and frame.parentJoint == 0
            and np.allclose(frame.placement.homogeneous, np.eye(4), atol=0.0)
        ):
            return str(frame.name)
    return str(model.frames[0].name)


def reduce_model(
    full: pin.Model, base: str, tip: str, do_reduce: bool, q_ref: Any
) -> tuple[pin.Model, tuple[int, ...], np.ndarray]:
    """``(model, locked joint ids, q_ref)``: only the joints between ``base`` and ``tip`` kept.

    The others are locked at ``q_ref`` (the full model when nothing is locked).

    Raises:
        FrameNotFoundError: ``base`` is not an ancestor of ``tip``.
        ConfigurationError: A malformed ``q_ref`` (Pinocchio layout of the full model).

    """
    if not do_reduce:
        return full, (), pin.neutral(full)
    base_joint = full.frames[frame_index(full, base)].parentJoint
    tip_joint = full.frames[frame_index(full, tip)].parentJoint
    tip_support = list(full.supports[tip_joint])
    base_support = set(full.supports[base_joint])
    if not base_support <= set(tip_support):
        raise FrameNotFoundError(
            f"base={base!r} is not on the path from the root to tip={tip!r}; pick a base that "
            f"is an ancestor of the tip (path joints: {[full.names[i] for i in tip_support]})"
        )
    keep = set(tip_support) - base_support
    lock = [i for i in range(1, full.njoints) if i not in keep]
    try:
        ref = pin.neutral(full) if q_ref is None else np.asarray(q_ref, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ConfigurationError(f"q_ref={q_ref!r} is not a sequence of numbers") from None
    if ref.shape != (full.nq,) or not np.all(np.isfinite(ref)):
        raise ConfigurationError(
            f"q_ref has shape {np.shape(q_ref)}; expected ({full.nq},) finite values"
        )
    if not lock:
        return full, (), ref
    return reduced_model(full, lock, ref), tuple(lock), ref


def reduced_model(full: pin.Model, lock: list[int], ref: np.ndarray) -> pin.Model:
    """``pin.buildReducedModel``, also for a link and a joint named alike (anymal_c's LF_HAA).

    Pinocchio raises on such a pair: their non-joint frames are renamed for the reduction.
    """
    names = [f.name for f in full.frames]
    shared = {n for n in names if names.count(n) > 1}
    if not shared:
        return pin.buildReducedModel(full, lock, ref)
    work = pin.Model(full)
    renamed: dict[str, str] = {}
    for i, frame in enumerate(work.frames):
        if frame.name in shared and frame.type != pin.FrameType.JOINT:
            tag = f"{frame.name}\x00{i}"  # NUL never occurs in a URDF name
            renamed[tag] = frame.name
            work.frames[i].name = tag
    reduced = pin.buildReducedModel(work, lock, ref)
    for i, frame in enumerate(reduced.frames):
        if frame.name in renamed:
            reduced.frames[i].name = renamed[frame.name]
    return reduced


def path_frames(model: pin.Model, base_id: int, tip_id: int) -> tuple[str, ...]:
    """Body frames from base to tip (one per link on the path), by walking parents."""
    names: list[str] = []
    fid = tip_id
    for _ in range(len(model.frames) + 2):
        frame = model.frames[fid]
        if frame.type == pin.FrameType.BODY or fid in (base_id, tip_id):
            names.append(frame.name)
        if fid == base_id or frame.parentFrame == fid:
            break
        fid = frame.parentFrame
    if names[-1] != model.frames[base_id].name:
        return (model.frames[base_id].name, model.frames[tip_id].name)
    names.reverse()
    return tuple(names)


@dataclass(frozen=True)
class DefaultTips:
    """The tip(s) a user would pick for a URDF with no ``tip`` given (:func:`default_tips`).

    ``kind``: ``"chain"``, ``"gripper"`` (the TCP or flange) or ``"limbs"`` (every limb's end);
    ``tips[0]`` is the model's tip; ``locked``: joints locked by this choice (a gripper's
    fingers); ``note``: one line saying what was chosen (empty for a plain chain).
    """

    kind: str
    tips: tuple[str, ...]
    locked: tuple[str, ...] = ()
    note: str = ""


def default_tips(model: pin.Model) -> DefaultTips:
    """The default tip(s) of a URDF model from its kinematic tree.

    End frames (BODY or fixed-joint frames nothing hangs from, moved by a joint) grouped by
    limb (their first joint from the root). Two or more limbs of two or more joints:
    ``"limbs"``, each one's deepest end (a legged robot's feet). One limb whose ends part with
    at most two joints of their own, one end needing none (a TCP): ``"gripper"``, those
    finger joints locked. Else ``"chain"``: the last of the deepest ends in frame order.
    """
    frames = list(model.frames)
    has_child = [False] * len(frames)
    for i, f in enumerate(frames):
        if i and f.parentFrame < len(frames) and f.parentFrame != i:
            has_child[f.parentFrame] = True
    kinds = (pin.FrameType.BODY, pin.FrameType.FIXED_JOINT)
    ends = []
    for i, f in enumerate(frames):
        path = list(model.supports[f.parentJoint])[1:]  # joints from the root, root excluded
        if not has_child[i] and f.type in kinds and path:
            ends.append((i, str(f.name), path))
    if not ends:  # nothing hangs from a joint: the last BODY frame, else the last frame
        bodies = [f for f in frames if f.type == pin.FrameType.BODY]
        return DefaultTips("chain", (str((bodies or frames)[-1].name),))
    limbs: dict[int, list[tuple[int, str, list[int]]]] = {}
    for end in ends:
        limbs.setdefault(end[2][0], []).append(end)
    long = [v for v in limbs.values() if max(len(p) for _, _, p in v) >= 2]
    if len(long) >= 2:
        tips = tuple(
            max(v, key=lambda e: (len(e[2]), "foot" in e[1].lower(), e[0]))[1] for v in long
        )
        note = f"{len(tips)} limbs from the root: every limb's end ({', '.join(tips)})"
        return DefaultTips("limbs", tips, note=note + "; --tip picks one")
    shared = list(ends[0][2])
    for _, _, p in ends[1:]:
        k = 0
        while k < min(len(shared), len(p)) and shared[k] == p[k]:
            k += 1
        shared = shared[:k]
    own = [(i, name, p[len(shared) :]) for i, name, p in ends]
    if len(own) >= 2 and all(len(extra) <= 2 for _, _, extra in own):
        bare = [(i, name) for i, name, extra in own if not extra]
        fingers = sorted({j for _, _, extra in own for j in extra})
        if bare:  # a TCP (or the hand) needs no finger joint
            hints = ("tcp", "tool", "ee")
            tip = max(bare, key=lambda e: (any(k in e[1].lower() for k in hints), e[0]))[1]
        else:  # only fingers: the flange, the link of the last joint the ends share
            tip = next(
                (str(f.name) for f in frames
                 if shared and f.parentJoint == shared[-1] and f.type == pin.FrameType.BODY),
                "",
            )  # fmt: skip
        if tip and fingers:
            names = tuple(str(model.names[j]) for j in fingers)
            note = (
                f"tip {tip} (gripper joints {', '.join(names)} locked); --tip picks another frame"
            )
            return DefaultTips("gripper", (tip,), names, note=note)
    depth = max(len(p) for _, _, p in ends)
    return DefaultTips("chain", (max((i, n) for i, n, p in ends if len(p) == depth)[1],))
