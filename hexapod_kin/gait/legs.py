"""Legs of any floating-base robot: found in the kinematic tree, feet, closed forms.

* **Legs from the tree**: every chain of actuated joints from the floating body to a foot:
  the deepest frame of a branch (a leaf link such as solo12's ``FL_FOOT``) or a point given
  on a frame (``frame:x,y,z`` [m], :func:`parse_feet`) when the URDF has no foot link.
* **Closed forms**: a leg's table (a view of the loaded robot, or a Hexapod's leg on its
  mount) where :mod:`hexapod_kin.ik.closed` recognises it and reproduces the leg's own
  kinematics (:func:`closed_leg`); other legs numerically (:func:`~.leg_ik.solve_legs`).
"""

from __future__ import annotations

import contextlib
import math
import os
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields, replace
from functools import partial
from itertools import pairwise
from pathlib import Path
from typing import Any

import numpy as np

from .._fields import fields_dict
from .._reader import FORMATS, check_keys, named, numbers, read_data, text
from .._tree import robot_size, tree_frames
from ..exceptions import ConfigurationError, HexapodKinError, ParameterError

__all__ = [
    "BodyIK",
    "check_offsets",
    "check_size",
    "FootSpec",
    "GaitError",
    "LegTree",
    "closed_leg",
    "finite_or_inf",
    "pick_branch",
    "sphere_radius",
    "find_legs",
    "leg_layout",
    "offset_of",
    "parse_feet",
]

#: A foot offset (and a foot radius) may be at most this many times the robot's size
#: (:func:`hexapod_kin._tree.robot_size`).
OFFSET_FACTOR = 2.0

#: ``frame:x,y,z`` (the offset optional: ``frame`` alone is the frame's origin).
_SPEC = re.compile(r"^\s*([^:\s,]+)\s*(?::\s*([^:]+))?$")


class GaitError(ConfigurationError):
    """A gait or body pose that the robot cannot perform (a check failed).

    Attributes:
        check: The failed check (``"reach"``, ``"joint limit"``, ``"terrain"``, ...: see
            :func:`~.walk.walk`).
        leg: The leg's name (``None`` when the check is about the whole robot).
        time: Time of the first failing sample in [s] (``None`` for a single pose).
        amount: By how much the check fails, in [m] or [rad] (≥ 0).

    """

    def __init__(
        self,
        message: str,
        *,
        check: str,
        leg: str | None = None,
        time: float | None = None,
        amount: float | None = None,
        parameter: str | None = None,
        value: Any = None,
        allowed: Any = None,
    ) -> None:
        super().__init__(message, parameter=parameter, value=value, allowed=allowed)
        self.check, self.leg, self.time, self.amount = check, leg, time, amount


@dataclass(frozen=True)
class BodyIK:
    """Joint angles of body poses with the feet fixed in the world (arrays read-only).

    Attributes:
        q: (N, nq) joint angles in [rad], legs in order, each leg's joints.
        reached: (N, L) True where the leg's closed form has a solution.
        excess: (N, L) distance by which each foot is out of the leg's reach in [m]
            (0 when reachable).
        limit_margin: (N, nq) distance of each joint to its nearest limit in [rad]
            (negative beyond a limit).
        leg_names: The legs' names.

    """

    q: np.ndarray
    reached: np.ndarray
    excess: np.ndarray
    limit_margin: np.ndarray
    leg_names: tuple[str, ...]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (arrays as nested lists, SI units)."""
        return fields_dict(self, *(f.name for f in fields(self)))

    @property
    def ok(self) -> np.ndarray:
        """(N, L) True where the leg is reached and inside its joint limits."""
        n_leg = len(self.leg_names)
        lim = self.limit_margin.reshape(len(self.q), n_leg, -1).min(axis=2)
        return np.asarray(self.reached & (lim >= 0))


# ============================================================================ foot specs
@dataclass(frozen=True)
class FootSpec:
    """A foot: a point ``offset`` [m] in the frame ``frame`` (the contact sphere's centre)."""

    frame: str
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)


def _numbers3(text: Any, where: str) -> tuple[float, float, float]:
    """Three finite numbers from ``"x,y,z"`` or a sequence of numbers (never texts, booleans)."""
    if not isinstance(text, str):  # a file's or a caller's list: '0' or true are typos
        with contextlib.suppress(TypeError):
            text = list(text)
        x, y, z = numbers(text, f"foot {where}: offset", 3, parameter="feet")
        return (x, y, z)
    try:
        vals = [float(v) for v in text.split(",")]
    except ValueError:
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
    """``a:1,2,3,b:4,5,6`` or ``a:1,2,3 b:...`` → one item per foot.

    A comma before a name with a colon starts a new foot.
    """
    parts = re.split(r"[\s;]+", text.strip())
    return [p for part in parts for p in re.split(r",(?=[^,:\s]+:)", part) if p]


def check_offsets(feet: tuple[FootSpec, ...], model: Any) -> None:
    """Refuse a foot offset larger than the robot (:data:`OFFSET_FACTOR` × its size).

    Raises:
        ParameterError: The first such foot, its offset and the allowed range.

    """
    limit = OFFSET_FACTOR * (size := robot_size(model))
    for f in feet:
        big = max(abs(v) for v in f.offset)
        if big > limit:
            raise ParameterError(
                f"foot {f.frame}: offset {','.join(f'{v:.6g}' for v in f.offset)} m is larger "
                f"than the robot; allowed |x|, |y|, |z| <= {limit:.4g} m ({OFFSET_FACTOR:g} x "
                f"the robot's size {size:.4g} m)",
                parameter="feet",
                value=f"{f.frame}:{','.join(repr(v) for v in f.offset)}",
                allowed=[-limit, limit],
            )


def check_size(value: float, model: Any, name: str = "foot_radius") -> float:
    """``value`` [m], refused when ``|value|`` is over :data:`OFFSET_FACTOR` × the robot's size.

    Raises:
        ParameterError: A length (a foot radius, a height, a reach) larger than the robot.

    """
    limit = OFFSET_FACTOR * (size := robot_size(model))
    if abs(value) > limit:
        raise ParameterError(
            f"{name}={value!r} m is larger than the robot; allowed up to {limit:.4g} m "
            f"({OFFSET_FACTOR:g} x the robot's size {size:.4g} m)",
            parameter=name,
            value=value,
            allowed=[0.0, limit],
        )
    return value


def parse_feet(spec: Any, model: Any = None) -> tuple[FootSpec, ...] | None:
    """Foot specifications from any of the accepted forms (``None`` stays ``None``).

    Accepted: ``"tibia_lf:0,0.16,0.029"`` (several separated by spaces, ``;`` or commas), a
    list of such strings, a mapping ``{"tibia_lf": (x, y, z), ...}``, a sequence of
    :class:`FootSpec`, or a table file (``.yaml``/``.yml``/``.toml``/``.json``) holding either
    such a mapping or ``feet = [{frame = "...", offset = [x, y, z]}, ...]`` (optionally under
    a ``feet`` key). Offsets in [m], in the named frame; with ``model`` (a Pinocchio model)
    each is checked against the robot's size (:func:`check_offsets`).

    Raises:
        ParameterError: A malformed spec (named), an offset larger than the robot.
        SourceError: A feet file refused by the strict reader (:mod:`hexapod_kin._reader`).

    """
    if spec is None:
        return None
    if isinstance(spec, Path) or (isinstance(spec, str) and Path(spec).suffix.lower() in FORMATS):
        data = read_data(spec, "feet")
        if isinstance(data, Mapping) and "feet" in data:
            data = data["feet"]
        with named(spec, "feet"):  # a text is a spec, not a file
            return parse_feet([data] if isinstance(data, str) else data, model)
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
            check_keys(item, ("frame", "offset"), "foot", parameter="feet")
            frame = text(item["frame"], "foot frame", parameter="feet")
            out.append(FootSpec(frame, _numbers3(item.get("offset", (0, 0, 0)), frame)))
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
    if model is not None:
        check_offsets(tuple(out), model)
    return tuple(out)


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
    pre, suf = (
        max((i + 1 for i, ch in enumerate(os.path.commonprefix(s)) if ch in "_-"), default=0)
        for s in (names, [n[::-1] for n in names])
    )
    out = [n[pre : len(n) - suf] for n in names]
    return out if all(out) and len(set(out)) == len(out) else names


def _frame_key(model: Any, i: int) -> tuple[int, float]:
    """The deepest frame first, then the farthest from its joint."""
    depth, fid = 0, i
    while fid != 0 and (parent := model.frames[fid].parentFrame) != fid and depth < 10_000:
        depth, fid = depth + 1, int(parent)
    return (depth, float(np.linalg.norm(model.frames[i].placement.translation)))


def find_legs(
    model: Any, feet: tuple[FootSpec, ...] | None, *, ccw: bool = True
) -> tuple[list[LegTree], list[int]]:
    """The legs of a Pinocchio model with a free-flyer root (joint 1), and the other joints.

    With ``feet``, one leg per foot; without, one per leaf of the joint tree whose deepest
    frame is off its joint, dropping branches shorter than half the longest (a head, a
    sensor). Ordered counter-clockwise from above from the front-left (``atan2(y, x)`` of the
    first joint in [0, 2π)); ``ccw=False`` keeps the order of ``feet``.

    Returns:
        ``(legs, others)``: the legs (joint indices into q[7:]) and the ids of the joints of
        no leg.

    Raises:
        ParameterError: A foot offset larger than the robot (:func:`check_offsets`).
        ConfigurationError: A frame that does not exist, a foot on the floating body, legs
            sharing joints, no leg found.

    """
    import pinocchio as pin

    nj = model.njoints
    parents = {int(model.parents[j]) for j in range(2, nj)}
    data = model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model))
    found: list[tuple[str, int, np.ndarray]] = []  # (frame name, joint id, foot in joint)
    if feet is not None:
        check_offsets(feet, model)
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
            if j in parents:
                continue
            cands = [i for i, f in enumerate(model.frames) if int(f.parentJoint) == j]
            if not cands:
                continue
            fr = model.frames[max(cands, key=partial(_frame_key, model))]
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
        pts = [data.oMi[p].translation for p in path] + [foot_w[:3, 3]]
        span = sum(float(np.linalg.norm(np.asarray(b) - np.asarray(a))) for a, b in pairwise(pts))
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
        legs_raw.sort(key=lambda r: (round(math.atan2(r[4][1], r[4][0]) % (2 * math.pi), 9), r[0]))
    names = _strip_common([r[0] for r in legs_raw])
    legs = [
        LegTree(name, tuple(p - 2 for p in path), frame, path[-1] - 2, place)
        for name, (frame, path, place, _s, _o) in zip(names, legs_raw)
    ]
    others = sorted(set(range(2, nj)) - set(used))
    return legs, others


# ============================================================================ build helpers


def sphere_radius(text: str, link: str) -> float | None:
    """The radius of the first sphere collision of ``link`` in URDF ``text`` (if any)."""
    import xml.etree.ElementTree as ET

    try:
        root = ET.fromstring(text)
    except ET.ParseError:  # pragma: no cover - the gate parsed it already
        return None
    for el in root.iter("link"):
        if el.get("name") != link:
            continue
        for col in el.iter("collision"):
            sph = col.find("geometry/sphere")
            if sph is not None and sph.get("radius") is not None:
                try:
                    return float(sph.get("radius", ""))
                except ValueError:
                    return None
    return None


def closed_leg(
    table: Any,
    T0: np.ndarray,
    feet_of: Callable[[np.ndarray], np.ndarray],
    lower: Any,
    upper: Any,
    span: float,
) -> bool:
    """True when the closed form of ``table`` (frame 0 at ``T0`` in the body) solves the leg.

    At 6 seeded configurations inside the limits a valid slot must put the foot (``feet_of``:
    (N, m) joints → (N, 3) body-frame feet) on target within 1e-9 × max(span, 1 m): a table
    that only approximates the leg (axes snapped by :func:`hexapod_kin.chain_from_urdf`) is
    refused.
    """
    from ..ik import analytic_batch

    lo = np.where(np.isfinite(lower), lower, -np.pi)
    hi = np.where(np.isfinite(upper), upper, np.pi)
    rng = np.random.default_rng(7)
    qs = lo + (hi - lo) * rng.uniform(0.05, 0.95, size=(6, len(lo)))
    e = len(qs)
    p = feet_of(qs)
    p0 = (p - T0[:3, 3]) @ T0[:3, :3]
    try:
        batch = analytic_batch(table, p0)
    except HexapodKinError:
        return False
    k = batch.q.shape[1]
    cand = np.nan_to_num(np.asarray(batch.q).reshape(e * k, -1))
    if cand.shape[1] != len(lo):
        return False
    pk = feet_of(cand)
    err = np.linalg.norm(pk.reshape(e, k, 3) - p[:, None, :], axis=2)
    err = np.where(np.asarray(batch.valid), err, np.inf)
    return bool(np.all(err.min(axis=1) <= 1e-9 * max(span, 1.0)))


def finite_or_inf(v: Any) -> np.ndarray:
    """``v`` as floats with absent limits (±inf, ±1e300 and beyond) as inf."""
    a = np.array(v, dtype=float)
    a[~np.isfinite(a) | (np.abs(a) >= 1e300)] = np.inf
    return a


def _nearest(cand: np.ndarray, refs: np.ndarray, usable: np.ndarray) -> np.ndarray:
    """For each reference, the valid slot nearest to it (the first on a tie), (A, G, N).

    ``cand`` (m, K, G, N), ``refs`` (m, A, G, N), ``usable`` (K, G, N); distance
    ``Σ_j |wrap(cand_j − ref_j)|`` (all-invalid samples give slot 0).
    """
    m, k = cand.shape[:2]
    shape = (refs.shape[1], k) + np.broadcast_shapes(cand.shape[2:], refs.shape[2:])
    d = np.zeros(shape)
    x = np.empty(shape)
    y = np.empty(shape)
    two_pi = 2.0 * np.pi
    for j in range(m):
        np.subtract(cand[j, None], refs[j][:, None], out=x)
        np.multiply(x, 1.0 / two_pi, out=y)
        np.rint(y, out=y)
        y *= two_pi
        x -= y
        np.abs(x, out=x)
        d += x
    np.copyto(d, np.inf, where=~usable[None])
    out = np.zeros((shape[0],) + shape[2:], dtype=np.intp)
    best = d[:, 0].copy()
    for b in range(1, k):
        nearer = d[:, b] < best
        out[nearer] = b
        np.copyto(best, d[:, b], where=nearer)
    return out


def pick_branch(qk: np.ndarray, valid: np.ndarray, q0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per leg and sample, the valid IK slot nearest the previous sample (angles unwrapped).

    Sequentially: the slot with the smallest ``Σ|wrap(q_k − q_prev)|`` (the first on a tie) is
    taken and continued, ``q = q_prev + wrap(q_k − q_prev)``; samples without a valid slot keep
    ``q_prev``. Evaluated for all samples at once: the choice at sample i depends only on the
    slot chosen at the last sample with one, so each sample is a map ``F_i`` between slots and
    the chosen slots are the prefix compositions ``F_i ∘ … ∘ F_0`` (by doubling, log₂ N
    rounds); the unwrapped value is the candidate plus 2π times an integer count of turns (no
    rounding accumulates). When every leg keeps its first sample's slot the composition is
    skipped.

    Args:
        qk: (G, N, K, m) candidate solutions of G legs at N samples.
        valid: (G, N, K) which candidates exist.
        q0: (G, m) the configuration before the first sample.

    Returns:
        ``(q, ok)``: (G, N, m) the continued joint angles (the previous value kept where no
        slot is valid) and (G, N) whether a slot was found.

    """
    g, n, k, m = qk.shape
    usable = np.moveaxis(np.asarray(valid, dtype=bool), 2, 0)  # (K, G, N)
    ok = np.asarray(usable.any(axis=0))  # (G, N)
    q0 = np.asarray(q0, dtype=float)
    two_pi = 2.0 * np.pi
    # the last sample with a slot at or before each sample (−1: none yet, q0 is the reference)
    last = np.maximum.accumulate(np.where(ok, np.arange(n), -1), axis=1)
    ref = np.empty_like(last)
    ref[:, 0] = -1
    ref[:, 1:] = last[:, :-1]
    # components first, samples last; q0 as a sample −1 in every slot; missing slots at 0
    cand = np.empty((m, k, g, n + 1))
    cand[..., 0] = q0.T[:, None, :]
    cand[..., 1:] = np.transpose(qk, (3, 2, 0, 1))
    np.copyto(cand[..., 1:], 0.0, where=~usable[None])
    rows = np.arange(g)[:, None]
    cur = cand[..., 1:]
    # the usual case first: every leg keeps the slot it takes at its first sample with one
    first = np.argmax(ok, axis=1)
    at_first = cur[:, :, np.arange(g), first][..., None]  # (m, K, G, 1)
    s0 = _nearest(at_first, q0.T[:, None, :, None], usable[:, np.arange(g), first][..., None])
    s0 = s0[0, :, 0]  # (G,)
    kept = _nearest(cur, cand[:, s0[:, None], rows, ref + 1][:, None], usable)[0]
    if np.all((kept == s0[:, None]) | ~ok):
        slot = np.broadcast_to(s0[:, None], (g, n))
    else:  # slot maps F_i (reference slot → slot), composed: F_i ∘ … ∘ F_0 by doubling
        F = _nearest(cur, cand[:, :, rows, ref + 1], usable)  # (K, G, N)
        np.copyto(F, np.arange(k)[:, None, None], where=~ok[None])  # no slot: the same
        off = np.arange(g * n).reshape(g, n)
        span = 1
        while span < n:  # F_i <- F_i ∘ F_{i − span}
            nxt = F.copy()
            nxt[..., span:] = np.take(F.ravel(), F[..., :-span] * (g * n) + off[:, span:])
            F = nxt
            span *= 2
        slot = F[0]  # q0 stands in every slot of sample −1
    chosen = np.take_along_axis(cand[..., 1:], slot[None, None], axis=1)[:, 0]  # (m, G, N)
    # unwrapped: q_i = c_i + 2π M_i, M_i = M_ref + round((c_ref + wrap(c_i − c_ref) − c_i) / 2π)
    idx = np.broadcast_to(np.maximum(ref, 0), chosen.shape)
    c_ref = np.where(ref >= 0, np.take_along_axis(chosen, idx, axis=2), q0.T[:, :, None])
    step = np.mod(chosen - c_ref + np.pi, two_pi) - np.pi
    turns = np.where(ok, np.rint((c_ref + step - chosen) / two_pi), 0.0)
    turns = np.cumsum(turns, axis=2)
    at = np.broadcast_to(np.maximum(last, 0), chosen.shape)
    out = np.where(
        last >= 0, np.take_along_axis(chosen, at, axis=2) + two_pi * turns, q0.T[:, :, None]
    )
    return np.moveaxis(out, 0, 2), ok


def leg_layout(
    model: Any,
    tree: Any,
    legs: list[LegTree],
    cols: tuple[tuple[int, ...], ...],
    q_zero: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    params: Any,
    robot: Any,
) -> dict[str, Any]:
    """The legs' spans, mounts, default stance geometry and closed forms, as a dict.

    ``span`` (L,) [m], ``mounts`` (L, 4, 4), ``direction`` (L, 2), ``reach`` (L,) [m],
    ``body_height`` [m] (the rules of :meth:`~.robot.WholeBody.neutral_feet`) and ``closed``
    (per leg ``(table, T_body_frame0)`` or ``None``; tables from views of the loaded ``robot``).
    """
    from .._fromurdf import chain_from_urdf
    from ..params import Pose

    hexa = params is not None

    def leg_fk(leg: int, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Leg ``leg``'s joint origins (N, m, 3) and feet (N, 3), body frame, at its q (N, m)."""
        c, foot = list(cols[leg]), legs[leg].foot_placement[:3, 3]
        Q = np.tile(q_zero, (len(q), 1))
        Q[:, c] = q
        R, p = tree_frames(tree, Q, np.broadcast_to(np.eye(4), (len(Q), 4, 4)))
        j = c[-1]
        feet = R[:, 0, j] * foot[0] + R[:, 1, j] * foot[1] + R[:, 2, j] * foot[2] + p[:, j]
        return p[:, c].transpose(2, 1, 0), feet.T

    # the geometry at q = 0 (clipped into the limits)
    spans, feet0 = [], []
    for i, c in enumerate(cols):
        o, p = leg_fk(i, q_zero[list(c)][None])
        pts = np.vstack([o[0], p])
        spans.append(float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum()))
        feet0.append(p[0])
    span = np.array(spans)
    mounts = np.array(
        [x.transform() for x in params.legs] if hexa else [tree.placements[c[0]] for c in cols]
    )
    d0 = np.array(feet0)[:, :2] - mounts[:, :2, 3]
    if hexa:
        direction = mounts[:, :2, 0].copy()
    else:
        # an offset every foot shares (Unitree's knees, clipped into their range at q = 0,
        # put every foot 0.16 m forward of its hip) is a joint-zero convention, not a stance
        d0 -= d0.mean(axis=0)
        direction = np.zeros((len(cols), 2))
        for i, d in enumerate(d0):
            out = mounts[i, :2, 3]
            for v in (d, out, np.array([1.0, 0.0])):
                if np.linalg.norm(v) > 1e-6 * span[i]:
                    direction[i] = v / np.linalg.norm(v)
                    break
    d_horiz = np.einsum("li,li->l", d0, direction)
    reach = np.minimum(np.maximum(d_horiz, 0.0), 0.64 * span)
    rho = span * math.hypot(0.64, 0.32)
    depth = np.sqrt(np.maximum(rho**2 - reach**2, 0.0))
    body_height = float(np.min(depth - mounts[:, 2, 3]))
    # closed forms
    closed: list[tuple[Any, np.ndarray] | None] = []
    for i, leg in enumerate(legs):
        cand: tuple[Any, np.ndarray] | None = None
        try:
            if hexa:
                ch = params.legs[i].chain
                T0 = mounts[i] @ ch.base_matrix
                table = ch if ch.base_pose is None else replace(ch, base_pose=None)
            else:
                ch = chain_from_urdf(robot.view(tip=leg.foot_frame))  # a view: no parse
                off = np.eye(4)
                off[:3, 3] = offset_of(model, leg)
                if np.any(off[:3, 3] != 0):
                    ch = replace(ch, tool=Pose.of(ch.tool_matrix @ off))
                T0 = ch.base_matrix
                table = replace(ch, base_pose=None)
            sel = list(cols[i])
            feet_of = partial(lambda leg, q: leg_fk(leg, q)[1], i)  # leg i's feet
            if closed_leg(table, T0, feet_of, lower[sel], upper[sel], float(span[i])):
                cand = (table, T0)
        except HexapodKinError:
            cand = None
        closed.append(cand)
    if hexa:  # legs sharing one table share one closed-form call
        by_id: dict[int, Any] = {}
        for i, found in enumerate(closed):
            if found is not None:
                shared = by_id.setdefault(id(params.legs[i].chain), found[0])
                closed[i] = (shared, found[1])
    return {
        "span": span,
        "mounts": mounts,
        "direction": direction,
        "reach": reach,
        "body_height": body_height,
        "closed": closed,
    }


def offset_of(model: Any, leg: LegTree) -> np.ndarray:
    """The foot in its frame (the user's offset; 0 for a leaf frame) [m]."""
    fr = model.frames[model.getFrameId(leg.foot_frame)]
    rel = np.linalg.solve(fr.placement.homogeneous, leg.foot_placement)
    return np.asarray(rel[:3, 3])
