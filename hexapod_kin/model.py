"""The loader: a resolved source (:mod:`hexapod_kin.sources`) passes the gate, then Pinocchio.

A :class:`Model`: Pinocchio's ``Model``, one ``Data`` per thread, the URDF text, the base → tip
sub-chain, a tool frame, one per-model cache (:meth:`Model.cached`). What kinematics does not
need (unusable meshes, implausible inertials) loads with one
:class:`~hexapod_kin.exceptions.UrdfWarning` per kind; :func:`check_inertials` is dynamics'
strict check, ``inertia="collision"`` or ``"point"`` a stated repair.
"""

from __future__ import annotations

import dataclasses
import math
import os
import sys
import threading
import warnings
from collections.abc import Callable
from typing import Any, TypeVar

import numpy as np
import pinocchio as pin

from ._gate import check_urdf, parse_urdf
from ._gate.messages import defect_lines, first_names, mesh_lines
from ._gate.repair import INERTIA_MODES, InertiaRepair, check_mode, repair_inertials
from .exceptions import (
    ConfigurationError,
    FrameNotFoundError,
    SourceError,
    UrdfError,
    UrdfWarning,
    choices,
    one_of,
)
from .frames import (
    DefaultTips,
    add_tool_frame,
    default_tips,
    floating_model,
    frame_index,
    joint_kind,
    path_frames,
    reduce_model,
    root_link_frame,
)
from .params import Chain, Hexapod, Pose
from .sources import ResolvedSource, yourdfpy_load

_T = TypeVar("_T")

__all__ = ["INERTIA_MODES", "Model", "check_inertials"]

_F64, _ND, _hypot = np.dtype(np.float64), np.ndarray, math.hypot


def _float_array(q: Any, message: str) -> np.ndarray:
    """``q`` as a float64 array; strings, booleans and non-numbers raise ``message``."""
    try:
        if np.asarray(q).dtype.kind in "USb":  # strings and booleans are not joint values
            raise TypeError
        return np.asarray(q, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise ConfigurationError(message) from None


def _check_values(arr: np.ndarray, label: str) -> None:
    """Refuse non-finite values and values with ``|x| >= 1e150`` (``label`` starts the message)."""
    if not np.all(np.isfinite(arr)):
        raise ConfigurationError(f"{label} contains non-finite values")
    if not np.all(np.abs(arr) < 1e150):
        raise ConfigurationError(f"{label} has values too large (|x| >= 1e150)")


# ------------------------------------------------------------------------ the model
class Model:
    """A Pinocchio model with its data, built from URDF text, restricted to base → tip.

    Attributes:
        model: The ``pinocchio.Model`` (reduced to the base → tip joints when asked);
            ``full_model``: before reduction; ``data``: the calling thread's ``pinocchio.Data``.
        urdf: The URDF text it was built from; ``source``: the resolved source.
        base: Name of the base frame; ``tip``: of the tip (``<flange>_tool`` with a ``tool``).
        flange: The frame the tool is mounted on; ``tool``: ``flangeMtip`` (4×4) or None.

    """

    #: The inertia repair applied (``inertia="collision"|"point"``), or ``None``.
    inertia_repair: InertiaRepair | None
    #: ``(uri, reason)`` of meshes that could not be found (their visuals are dropped).
    missing_meshes: tuple[tuple[str, str], ...]
    #: ``uri -> real path`` of the mesh and texture files the gate resolved and checked.
    mesh_files: dict[str, str]
    #: ``(link, defect)`` of physically implausible inertials (kinematics ignores them).
    inertia_defects: tuple[tuple[str, str], ...]

    def __init__(
        self,
        resolved: ResolvedSource,
        base: str | None = None,
        tip: str | None = None,
        *,
        reduce: bool | None = None,
        q_ref: Any = None,
        tool: Any = None,
        strict_inertia: bool = False,
        inertia: str = "urdf",
        parsed: Model | None = None,
    ) -> None:
        self._cache: dict[str, Any] = {}
        self._cache_lock = threading.RLock()
        if parsed is None:
            full, text = self._parse(resolved, strict_inertia, inertia)
        else:  # a view of a loaded robot: its gate verdict and its parse, shared
            for key in ("inertia_repair", "missing_meshes", "mesh_files", "inertia_defects"):
                setattr(self, key, getattr(parsed, key))
            full, text = parsed.full_model, parsed.urdf
        self.full_model: pin.Model = full
        self.urdf: str = text
        self.source = resolved
        full_frames = [f.name for f in full.frames]
        params = resolved.params
        #: the default tip(s) of a URDF given without ``tip`` (:func:`frames.default_tips`)
        self.default_tips: DefaultTips | None = None
        default_tip: str | None = None
        if isinstance(params, Chain):
            default_base, default_tip = params.base, params.tip
        elif isinstance(params, Hexapod):
            default_base, default_tip = params.body, params.foot_frames[0]
        else:
            default_base = root_link_frame(full)
        if tip is None and default_tip is None:
            self.default_tips = default_tips(full)
            default_tip = self.default_tips.tips[0]
        tip_name = default_tip if tip is None else tip
        assert tip_name is not None  # every source has a default tip
        base_name = default_base if base is None else base
        for label, name in (("base", base_name), ("tip", tip_name)):
            if not isinstance(name, str) or not full.existFrame(name):
                raise FrameNotFoundError(
                    f"{label}={name!r} is not a frame of {resolved.name!r}; frames are "
                    f"{choices(full_frames, limit=200)}"
                )
        do_reduce = (base is not None or tip is not None) if reduce is None else reduce
        if reduce is None and self.default_tips is not None and self.default_tips.locked:
            do_reduce = True  # the gripper's fingers are locked
        reduced, self._locked, self._q_ref = reduce_model(
            full, base_name, tip_name, do_reduce, q_ref
        )
        self.flange = tip_name
        self.tool: np.ndarray | None = None
        if tool is not None:
            tool_m = Pose.of(tool, "tool").matrix
            reduced, tip_name = add_tool_frame(reduced, tip_name, tool_m)
            tool_m.setflags(write=False)
            self.tool = tool_m
        self.model = m = reduced
        data = m.createData()
        self.base, self.tip = base_name, tip_name
        self.base_id, self.tip_id = frame_index(m, base_name), frame_index(m, tip_name)
        joints = range(1, m.njoints)
        self.joint_names: tuple[str, ...] = tuple(m.names[i] for i in joints)
        self.nq: int = int(m.nv)
        self._pin_nq: int = int(m.nq)
        kinds = [joint_kind(m.joints[i]) for i in joints]
        if None in kinds:
            bad = [f"joint {m.names[i]!r} is a {m.joints[i].shortname()}" for i in joints
                   if kinds[i - 1] is None]  # fmt: skip
            raise SourceError(
                f"{resolved.name!r}: joints of kind other than 1-DOF revolute/prismatic between "
                f"{base_name!r} and {tip_name!r} ({'; '.join(bad)}); pick a sub-chain with "
                "base=/tip="
            )
        self._shape = (self.nq,)
        names = [k[0] for k in kinds if k is not None]  # every joint's kind (all known here)
        # continuous joints: one angle in q, (cos, sin) in Pinocchio's (pinocchio_q)
        idx = [(int(m.joints[i].idx_q), int(m.joints[i].idx_v)) for i in joints]
        self._unbounded = tuple(p for p, kind in zip(idx, names) if kind == "continuous")
        plain = [p for p, kind in zip(idx, names) if kind != "continuous"]
        self._plain_idx = np.array(plain, dtype=np.int64).reshape(-1, 2)
        pin.framesForwardKinematics(m, data, pin.neutral(m))
        self._base_is_root = m.frames[self.base_id].parentJoint == 0 and np.allclose(
            data.oMf[self.base_id].homogeneous, np.eye(4), atol=0.0
        )
        # The base is fixed (no kept joint between the root and it), so its pose is constant.
        support = set(m.supports[m.frames[self.base_id].parentJoint])
        if support - {0}:
            raise FrameNotFoundError(
                f"base={base_name!r} moves with joints "
                f"{[m.names[i] for i in sorted(support - {0})]}; the base must be fixed "
                "relative to the root of the chain (choose a frame closer to the root)"
            )
        self.oMbase = pin.SE3(data.oMf[self.base_id])
        self.baseMo = self.oMbase.inverse()
        self._rot_base = np.ascontiguousarray(self.baseMo.rotation)
        self.lower, self.upper = np.empty(self.nq), np.empty(self.nq)  # per velocity index
        lower, upper = np.asarray(m.lowerPositionLimit), np.asarray(m.upperPositionLimit)
        for iq, iv in self._plain_idx:
            self.lower[iv], self.upper[iv] = lower[iq], upper[iq]
        for _, iv in self._unbounded:  # continuous joints
            self.lower[iv], self.upper[iv] = -math.pi, math.pi
        self.velocity_limit = np.array(m.velocityLimit, dtype=float)
        self.effort_limit = np.array(m.effortLimit, dtype=float)
        self.is_prismatic = np.array([kind == "prismatic" for kind in names], dtype=bool)
        for arr in (self.lower, self.upper, self.velocity_limit, self.effort_limit):
            arr.setflags(write=False)
        self.path_frames: tuple[str, ...] = path_frames(m, self.base_id, self.tip_id)
        # what the hot paths need (kinematics.fk), with one pinocchio.Data per thread
        self._local = _PerThread(self, data)

    def _parse(
        self, resolved: ResolvedSource, strict_inertia: bool, inertia: str
    ) -> tuple[pin.Model, str]:
        """The loader gate (and the inertia repair), then Pinocchio: ``(full model, URDF text)``."""
        check_mode(inertia)
        where: dict[str, Any] = {
            "package_dirs": resolved.package_dirs,
            "mesh_root": resolved.mesh_root,
        }
        gate = check_urdf(resolved.text, lenient=True, **where)
        self.inertia_repair = None
        if inertia != "urdf":
            text = resolved.text if gate.text is None else gate.text
            repaired = repair_inertials(text, inertia, **where)
            self.inertia_repair = repaired
            gate = check_urdf(repaired.text, lenient=True, **where)
            if gate.text is None:
                gate = dataclasses.replace(gate, text=repaired.text)
            _warn(f"{resolved.name!r}: {repaired.summary()}")
        self.missing_meshes = gate.missing_meshes
        self.mesh_files = {uri: str(path) for uri, path in gate.meshes}
        self.inertia_defects = gate.inertia_defects
        if strict_inertia:
            _raise_inertia_defects(resolved.name, gate.inertia_defects)
        for lines in (mesh_lines(gate.missing_meshes), defect_lines(gate.inertia_defects)):
            if lines:  # one warning for the meshes, one for the inertials
                _warn("\n".join(f"{resolved.name!r}: {line}" for line in lines))
        for repair in gate.repairs:
            _warn(f"{resolved.name!r}: {repair}")
        text = resolved.text if gate.text is None else gate.text
        try:
            full = pin.buildModelFromXML(text)
        except (RuntimeError, ValueError) as exc:  # the gate should have caught it; say so
            raise UrdfError(
                f"{resolved.name!r}: passed the loader gate but Pinocchio refused it: {exc}"
            ) from None
        return full, text

    def view(self, base: str | None = None, tip: str | None = None) -> Model:
        """The chain ``base`` → ``tip`` of this robot as a model of its own (cached).

        :func:`hexapod_kin.load` of the source with ``base``/``tip``, from this robot's parse.
        """
        return self.cached(
            f"model.view {base!r} {tip!r}",
            lambda: type(self)(self.source, base, tip, parsed=self),
        )

    def pinocchio_q(self, q: Any) -> np.ndarray:
        """``q`` checked (:meth:`check_q`) in Pinocchio's layout (continuous joints: cos, sin).

        Raises:
            ConfigurationError: Wrong shape or non-finite values.

        """
        qv = self.check_q(q)
        if not self._unbounded:
            return qv
        out = np.empty(self._pin_nq)
        out[self._plain_idx[:, 0]] = qv[self._plain_idx[:, 1]]
        for iq, iv in self._unbounded:
            out[iq] = math.cos(qv[iv])
            out[iq + 1] = math.sin(qv[iv])
        return out

    _FROZEN = frozenset(
        {"model", "data", "full_model", "urdf", "source", "base", "tip", "tip_id", "_local"}
    )

    @property
    def data(self) -> pin.Data:
        """The calling thread's ``pinocchio.Data`` of :attr:`model` (created on first use)."""
        return self._local.hot[1]

    def __setattr__(self, key: str, value: Any) -> None:
        # Model and Data are created together, never re-paired: these are read-only once set
        if key in self._FROZEN and (key in self.__dict__ or key == "data"):
            from .exceptions import ParameterError

            raise ParameterError(
                f"{key!r} of a hexapod_kin Model is read-only (the Pinocchio Model and Data are "
                "kept together); load a new model instead"
            )
        object.__setattr__(self, key, value)

    # -------------------------------------------------------------- the per-model cache
    def cached(self, key: str, factory: Callable[[], _T]) -> _T:
        """The value under ``key`` (``"singularity.gram_plans"``), built once by ``factory()``.

        The one per-model cache, thread-safe (a factory may call :meth:`cached` for another
        key; one that raises stores nothing). The value is shared: treat it as read-only.
        """
        cache = self._cache
        try:
            return cache[key]
        except KeyError:
            pass
        with self._cache_lock:
            if key not in cache:
                cache[key] = factory()
            return cache[key]

    @property
    def floating_model(self) -> pin.Model:
        """:attr:`full_model` with a free-flyer root, shared: treat it as read-only."""
        return self.cached("model.floating", lambda: floating_model(self.full_model))

    @property
    def arrays(self) -> Any:
        """The chain base → tip as :class:`hexapod_kin._chain.ChainArrays` (extracted once)."""
        from ._chain import ChainArrays

        return self.cached("model.arrays", lambda: ChainArrays.from_model(self))

    # -------------------------------------------------------------- names and checks
    @property
    def name(self) -> str:
        """A short label of the source."""
        return self.source.name

    @property
    def params(self) -> Chain | Hexapod | None:
        """The parameter table the model came from, if any."""
        return self.source.params

    @property
    def frame_names(self) -> list[str]:
        """All frame names of the (reduced) model."""
        return [f.name for f in self.model.frames]

    def frame_id(self, name: str) -> int:
        """Return the frame id of ``name``, checked.

        Raises:
            FrameNotFoundError: If no such frame exists (the message lists the frames).

        """
        if not isinstance(name, str) or not self.model.existFrame(name):
            raise FrameNotFoundError(
                f"frame={name!r} does not exist in {self.name!r}; frames are "
                f"{choices(self.frame_names, limit=200)}"
            )
        return frame_index(self.model, name)

    def joint_index(self, name: str) -> int:
        """Return the index (0-based, in ``q``) of joint ``name``, checked."""
        if name not in self.joint_names:
            raise FrameNotFoundError(
                f"joint={name!r} does not exist in {self.name!r}; joints are "
                f"{choices(self.joint_names)}"
            )
        return self.joint_names.index(name)

    def check_q(self, q: Any, name: str = "q") -> np.ndarray:
        """Return ``q`` as a float array of shape (nq,), checked for shape and finiteness.

        Raises:
            ConfigurationError: Wrong length, not numbers, or non-finite values.

        """
        # fast path: hypot of the values is NaN/inf for any NaN/inf and bounds every |q_i|
        if q.__class__ is _ND and q.dtype is _F64 and q.shape == self._shape:
            if _hypot(*q.tolist()) < 1e150:
                return q
        joints = list(self.joint_names)
        arr = _float_array(
            q, f"{name}={q!r} is not a sequence of {self.nq} numbers (joints {joints})"
        )
        if arr.shape != self._shape:
            raise ConfigurationError(
                f"{name} has shape {arr.shape}; expected ({self.nq},) for joints "
                f"{list(self.joint_names)}"
            )
        _check_values(arr, f"{name}={arr.tolist()}")
        return np.ascontiguousarray(arr)

    def check_q_batch(self, q: Any, name: str = "q") -> np.ndarray:
        """Return ``q`` as an (N, nq) float array, checked (a single (nq,) becomes (1, nq))."""
        arr = _float_array(q, f"{name} is not an array of numbers")
        if arr.ndim == 1:
            arr = arr[None, :]
        if arr.ndim != 2 or arr.shape[1] != self.nq:
            raise ConfigurationError(
                f"{name} has shape {arr.shape}; expected (N, {self.nq}) for joints "
                f"{list(self.joint_names)}"
            )
        _check_values(arr, name)
        return arr

    def neutral(self) -> np.ndarray:
        """Neutral configuration (zeros for revolute/prismatic joints), a fresh array."""
        return np.zeros(self.nq)

    def random_q(self, n: int | None = None, seed: int | None = None) -> np.ndarray:
        """Uniform random configurations within the joint limits ((nq,) or (n, nq))."""
        if n is not None and (isinstance(n, bool) or not isinstance(n, int) or n < 0):
            raise ConfigurationError(f"n={n!r} is not allowed; a count >= 0 (or None) required")
        size = (self.nq,) if n is None else (n, self.nq)
        return np.random.default_rng(seed).uniform(self.lower, self.upper, size=size)

    @property
    def locked_joints(self) -> tuple[str, ...]:
        """Names of the joints of the full model locked by the base/tip reduction."""
        return tuple(self.full_model.names[i] for i in self._locked)

    def geometry_model(self, kind: str = "visual") -> Any:
        """Pinocchio's ``GeometryModel`` of :attr:`model` (``kind``: visual or collision)."""
        from lxml import etree

        kinds = {"visual": pin.GeometryType.VISUAL, "collision": pin.GeometryType.COLLISION}
        one_of("kind", kind, kinds)
        dirs = list(self.source.package_dirs)
        if self.source.mesh_root:
            dirs.append(self.source.mesh_root)
        drop = {uri for uri, _ in self.missing_meshes}

        def build(dropped: set[str]) -> Any:
            """From the URDF without the elements of ``dropped``, every mesh by the gate's path."""
            text = self.urdf
            if dropped or self.mesh_files:
                root = parse_urdf(self.urdf)
                for link in root.findall("link"):
                    for part in [*link.findall("visual"), *link.findall("collision")]:
                        nodes = list(part.iter("mesh", "texture"))
                        if any(m.get("filename") in dropped for m in nodes):
                            link.remove(part)
                            continue
                        for m in nodes:
                            path = self.mesh_files.get(m.get("filename") or "")
                            if path is not None:
                                m.set("filename", path)
                text = str(etree.tostring(root, encoding="unicode"))
            return pin.buildGeomFromUrdfString(self.full_model, text, kinds[kind], None, dirs)

        try:
            geom = build(drop)
        except (RuntimeError, ValueError):  # a mesh Coal's loader cannot read: find and drop it
            import coal

            bad = set()
            for uri, path in self.mesh_files.items():
                if path.lower().endswith((".stl", ".dae", ".obj", ".ply", ".3ds", ".off")):
                    try:
                        coal.MeshLoader().load(path, np.ones(3))
                    except (RuntimeError, ValueError, TypeError):
                        bad.add(uri)
            if not bad:
                raise
            _warn(
                f"{self.name!r}: meshes: {len(bad)} file(s) unreadable by the mesh loader, "
                f"dropped with their visual/collision elements ({first_names(sorted(bad))})"
            )
            geom = build(drop | bad)
        if self._locked:
            _, geoms = pin.buildReducedModel(
                self.full_model, [geom], list(self._locked), self._q_ref
            )
            geom = geoms[0]
        return geom

    def yourdfpy(self) -> Any:
        """The same URDF text loaded by yourdfpy (a second engine; meshes not loaded)."""
        return yourdfpy_load(self.urdf)

    def __repr__(self) -> str:
        return (
            f"<hexapod_kin Model {self.name!r}: nq={self.nq} joints={list(self.joint_names)} "
            f"base={self.base!r} tip={self.tip!r}>"
        )


class _PerThread(threading.local):
    """Per-thread ``(model, data, tip_id, nq, base_is_root)`` (the load's data: its thread's)."""

    def __init__(self, owner: Model, data: Any = None) -> None:
        first = getattr(owner, "_owner_thread", None)
        mine = threading.get_ident()
        if first is None:
            object.__setattr__(owner, "_owner_thread", mine)
        if data is None or (first is not None and first != mine):
            data = owner.model.createData()
        # nq = -1 with continuous joints: their q always takes Model.pinocchio_q
        nq = -1 if owner._unbounded else owner.nq
        self.hot = (owner.model, data, owner.tip_id, nq, owner._base_is_root)


_PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__)) + os.sep


def _warn(message: str) -> None:
    """One :class:`UrdfWarning` attributed to the first caller outside hexapod_kin."""
    level, frame = 2, sys._getframe(1)
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(_PACKAGE_DIR):
        level, frame = level + 1, frame.f_back  # type: ignore[assignment]
    warnings.warn(message, UrdfWarning, stacklevel=level)


def _raise_inertia_defects(name: str, defects: tuple[tuple[str, str], ...]) -> None:
    if defects:
        link, why = defects[0]
        more = f" (and {len(defects) - 1} more link(s))" if len(defects) > 1 else ""
        raise UrdfError(
            f"{name!r}: link {link!r} has a physically implausible inertial{more}: {why}; "
            "repair with inertia='collision' or 'point' (CLI: --inertia)",
            parameter="inertial",
            value=link,
            allowed="mass > 0 and a positive-definite inertia obeying the triangle inequality",
        )


def check_inertials(model: Model) -> None:
    """Dynamics' first check: a UrdfError naming the first link with an implausible inertial."""
    _raise_inertia_defects(model.name, model.inertia_defects)
