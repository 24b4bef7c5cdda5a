"""Pinocchio model surgery for :mod:`hexapod_kin.model`: frames, sub-chains, tool frames.

Frame lookup that survives duplicate names, the reduction of a model to the joints between a
base and a tip, the tool frame added at the tip, the path of body frames, and the URDF text
without the visuals whose meshes are missing.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from .exceptions import ConfigurationError, FrameNotFoundError

__all__ = [
    "add_tool_frame",
    "drop_missing_meshes",
    "frame_index",
    "last_body_frame",
    "path_frames",
    "reduce_model",
    "root_link_frame",
]


_FRAME_PREFERENCE = (
    pin.FrameType.BODY,
    pin.FrameType.OP_FRAME,
    pin.FrameType.JOINT,
    pin.FrameType.FIXED_JOINT,
    pin.FrameType.SENSOR,
)


def frame_index(model: pin.Model, name: str) -> int:
    """Index of the frame ``name`` in a Pinocchio model (which must have it).

    URDFs may name a link and a joint alike (anymal: ``RH_HAA``); Pinocchio's ``getFrameId``
    then raises. The link's (BODY) frame wins, then operational, joint, fixed-joint frames.
    """
    hits = [i for i, f in enumerate(model.frames) if f.name == name]
    if len(hits) == 1:
        return hits[0]
    for kind in _FRAME_PREFERENCE:
        for i in hits:
            if model.frames[i].type == kind:
                return i
    return hits[0]


def drop_missing_meshes(text: str, missing: tuple[tuple[str, str], ...]) -> str:
    """``text`` without the visual/collision elements whose mesh file was not found."""
    if not missing:
        return text
    from ._gate import parse_urdf

    uris = {uri for uri, _ in missing}
    root = parse_urdf(text)
    for link in root.findall("link"):
        for part in [*link.findall("visual"), *link.findall("collision")]:
            if any(m.get("filename") in uris for m in part.iter("mesh", "texture")):
                link.remove(part)
    from lxml import etree

    return str(etree.tostring(root, encoding="unicode"))


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


def last_body_frame(model: pin.Model) -> str:
    """Name of the last BODY frame (the default tip of a URDF), else of the last frame."""
    for frame in reversed(model.frames):
        if frame.type == pin.FrameType.BODY:
            return str(frame.name)
    return str(model.frames[-1].name)


def reduce_model(
    full: pin.Model, base: str, tip: str, do_reduce: bool, q_ref: Any
) -> tuple[pin.Model, tuple[int, ...], np.ndarray]:
    """Keep only the joints between ``base`` and ``tip``, the others locked at ``q_ref``.

    Returns:
        ``(model, locked joint ids, q_ref)`` (the full model when nothing is locked).

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
    reduced = pin.buildReducedModel(full, lock, ref)
    return reduced, tuple(lock), ref


def path_frames(model: pin.Model, base_id: int, tip_id: int) -> tuple[str, ...]:
    """Body frames from base to tip (one per link on the path), by walking parents."""
    names: list[str] = []
    fid = tip_id
    seen = 0
    while True:
        frame = model.frames[fid]
        if frame.type == pin.FrameType.BODY or fid in (base_id, tip_id):
            names.append(frame.name)
        if fid == base_id or seen > len(model.frames):
            break
        parent = frame.parentFrame
        if parent == fid:
            break
        fid = parent
        seen += 1
    if names[-1] != model.frames[base_id].name:
        return (model.frames[base_id].name, model.frames[tip_id].name)
    names.reverse()
    return tuple(names)
