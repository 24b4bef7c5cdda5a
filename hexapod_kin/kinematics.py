"""Forward kinematics, every intermediate transform and frame Jacobians (Pinocchio).

Poses are Pinocchio's ``aMb`` (frame ``b`` in frame ``a``) as 4×4 arrays; ``base`` is the
chain's frame 0, ``tip`` its last. Jacobians take their reference frame explicitly:

* ``"local"`` — the tip's twist in the tip frame;
* ``"world"`` — the spatial twist in the base frame (velocity of the point at the base origin);
* ``"local_world_aligned"`` — the tip's linear and angular velocity in the base axes (the
  seeds' textbook ``J``; rows 0–2 are ``∂p/∂q``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pinocchio as pin

from ._gate.repair import check_mode
from .exceptions import ParameterError, choices
from .frames import joint_kind
from .model import Model
from .sources import resolve_source

# Bound once for the hot paths (the fast path of Model.check_q inlined, Pinocchio's calls).
_F64, _ND, _hypot = np.dtype(np.float64), np.ndarray, math.hypot
_forward_kinematics = pin.forwardKinematics
_update_frame_placement = pin.updateFramePlacement
_compute_frame_jacobian = pin.computeFrameJacobian

__all__ = ["REFERENCES", "KinematicModel", "as_model", "load", "direct_jacobian",
           "indirect_jacobian"]  # fmt: skip

REFERENCES: dict[str, pin.ReferenceFrame] = {
    "local": pin.ReferenceFrame.LOCAL,
    "world": pin.ReferenceFrame.WORLD,
    "local_world_aligned": pin.ReferenceFrame.LOCAL_WORLD_ALIGNED,
}
_LOCAL = pin.ReferenceFrame.LOCAL
_WORLD = pin.ReferenceFrame.WORLD


def _reference(reference: str) -> pin.ReferenceFrame:
    key = reference.lower() if isinstance(reference, str) else None
    if key not in REFERENCES:
        raise ParameterError(
            f"reference={reference!r} is not allowed; use one of {choices(REFERENCES)}"
        )
    return REFERENCES[key]


class KinematicModel(Model):
    """:func:`load`'s :class:`~hexapod_kin.model.Model`, with FK and Jacobians (fresh arrays)."""

    # -------------------------------------------------------------- forward kinematics
    def fk(self, q: Any) -> np.ndarray:
        """Pose of the tip in the base frame, ``baseMtip`` (4×4), at ``q`` (nq,) in [rad] / [m].

        Raises:
            ConfigurationError: Wrong shape or non-finite values.

        """
        m, d, fid, nq, root = self._local.hot  # the hot call: one lookup, the q check inlined
        try:  # len + hypot of the flat list: a 0-d or 2-D array raises TypeError here
            ok = q.__class__ is _ND and q.dtype is _F64 and len(q) == nq
            ok = ok and _hypot(*q.tolist()) < 1e150
        except TypeError:
            ok = False
        if not ok:
            q = self.pinocchio_q(q)
        _forward_kinematics(m, d, q)
        omf = _update_frame_placement(m, d, fid)
        if root:
            return omf.homogeneous
        return (self.baseMo * omf).homogeneous

    def position(self, q: Any) -> np.ndarray:
        """Tip position in the base frame in [m] (3,)."""
        return self.fk(q)[:3, 3].copy()

    def placement(self, q: Any, frame: str) -> np.ndarray:
        """Pose of any frame in the base frame, ``baseMframe`` (4×4)."""
        fid, d = self.frame_id(frame), self.data
        pin.forwardKinematics(self.model, d, self.pinocchio_q(q))
        return (self.baseMo * pin.updateFramePlacement(self.model, d, fid)).homogeneous

    def frame_placements(self, q: Any) -> list[np.ndarray]:
        """``^0T_j`` for every frame on the base → tip path (``path_frames``), 4×4 each."""
        d = self.data
        pin.framesForwardKinematics(self.model, d, self.pinocchio_q(q))
        return [(self.baseMo * d.oMf[self.frame_id(name)]).homogeneous for name in self.path_frames]

    def transforms(self, q: Any) -> list[np.ndarray]:
        """Every ``^{j-1}T_j`` along the path (4×4; of a Khalil table: its row ``j``)."""
        world = self.frame_placements(q)
        return [np.linalg.solve(world[j - 1], world[j]) for j in range(1, len(world))]

    def cumulative_transforms(self, q: Any) -> list[np.ndarray]:
        """``^0T_j`` for j = 1..n (the products of :meth:`transforms`)."""
        return self.frame_placements(q)[1:]

    # -------------------------------------------------------------- Jacobians
    def jacobian(
        self, q: Any, reference: str = "local_world_aligned", frame: str | None = None
    ) -> np.ndarray:
        """Frame Jacobian (6×nq), rows ``[v; ω]``, in the chosen reference frame.

        ``reference``: ``"local"``, ``"world"`` or ``"local_world_aligned"`` (module
        docstring; world axes are the base frame's); ``frame``: default the tip.

        Raises:
            ParameterError: Unknown ``reference``.
            FrameNotFoundError: Unknown ``frame``.
            ConfigurationError: Bad ``q``.

        """
        m, d, fid, nq, root = self._local.hot
        ref = REFERENCES.get(reference) if reference.__class__ is str else None
        if ref is None:
            ref = _reference(reference)
        if frame is not None:
            fid = self.frame_id(frame)
        try:  # len + hypot of the flat list: a 0-d or 2-D array raises TypeError here
            ok = q.__class__ is _ND and q.dtype is _F64 and len(q) == nq
            ok = ok and _hypot(*q.tolist()) < 1e150
        except TypeError:
            ok = False
        if not ok:
            q = self.pinocchio_q(q)
        jac = _compute_frame_jacobian(m, d, q, fid, ref)
        if jac.ndim == 1:  # Eigen 6x1 comes back as a 1-D array
            jac = jac.reshape(6, 1)
        if root or ref == _LOCAL:
            return jac
        if ref == _WORLD:
            return self.baseMo.action @ jac
        r = self._rot_base
        out = np.empty_like(jac)
        out[:3] = r @ jac[:3]
        out[3:] = r @ jac[3:]
        return out

    # -------------------------------------------------------------- batch calls
    def _batch(
        self,
        qs: Any,
        pose: bool,
        reference: str | None,
        out_pose: np.ndarray | None = None,
        out_jacobian: np.ndarray | None = None,
    ) -> tuple[Any, Any]:
        """The batch kernel's poses and/or Jacobians (``reference`` None: no Jacobian).

        A C-contiguous float64 (N, nq) ``qs`` is checked by the kernel on the way.
        """
        from ._chain import aligned_chain
        from ._kernels import pose_jacobian_batch

        if reference is not None:
            _reference(reference)
        key = None if reference is None else reference.lower()
        q = qs
        ready = isinstance(q, np.ndarray) and q.dtype == np.float64 and q.ndim == 2
        if not (ready and q.shape[1] == self.nq and q.flags.c_contiguous and q.flags.writeable):
            # a read-only array would be another compiled signature (one compile, not two)
            q = np.require(self.check_q_batch(qs, "Q"), requirements=("C", "W"))
        chain = self.cached("batch.aligned", lambda: aligned_chain(self.arrays))
        return pose_jacobian_batch(
            chain, q, pose=pose, jacobian=key, out_pose=out_pose, out_jacobian=out_jacobian,
            check=lambda: self.check_q_batch(q, "Q"),
        )  # fmt: skip

    def fk_batch(self, qs: Any, *, out: np.ndarray | None = None) -> np.ndarray:
        """Tip poses ``baseMtip`` of many configurations, (N, 4, 4), in one kernel pass.

        ``qs`` (N, nq) in [rad] / [m] (one (nq,) row: N = 1); ``out``: an optional (N, 4, 4)
        float64 C-contiguous array to fill. Equal to :meth:`fk` of each row to rounding
        (≈1e-15), the same bits on any thread count.

        Raises:
            ConfigurationError: Wrong shape, non-finite values or ``|q| >= 1e150`` (``out``
                is then partly written).
            ParameterError: ``out`` of the wrong shape, dtype or layout.

        """
        poses: np.ndarray = self._batch(qs, True, None, out_pose=out)[0]
        return poses

    def jacobian_batch(
        self, qs: Any, reference: str = "local_world_aligned", *, out: np.ndarray | None = None
    ) -> np.ndarray:
        """Tip Jacobians of many configurations, (N, 6, nq), rows ``[v; ω]``, in one pass.

        Arguments as :meth:`fk_batch` (``out``: (N, 6, nq)) and :meth:`jacobian`; equal to
        :meth:`jacobian` of each row to rounding; columns off the base → tip path are zero.
        Raises as :meth:`fk_batch`, and ParameterError for an unknown ``reference``.
        """
        jac: np.ndarray = self._batch(qs, False, reference, out_jacobian=out)[1]
        return jac

    def fk_jacobian_batch(
        self, qs: Any, reference: str = "local_world_aligned"
    ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`fk_batch` and :meth:`jacobian_batch` in one pass (arguments and errors alike)."""
        return self._batch(qs, True, reference)

    def position_jacobian(self, q: Any, frame: str | None = None) -> np.ndarray:
        """3×nq Jacobian of the tip position in the base frame, ``∂p/∂q``."""
        return self.jacobian(q, "local_world_aligned", frame)[:3].copy()

    def fk_jacobian(
        self, q: Any, reference: str = "local_world_aligned"
    ) -> tuple[np.ndarray, np.ndarray]:
        """Tip pose and Jacobian in one pass (cheaper than calling both)."""
        jac = self.jacobian(q, reference)  # its joint placements are the pose's too
        omf = _update_frame_placement(self.model, self.data, self.tip_id)
        return (omf if self._base_is_root else self.baseMo * omf).homogeneous, jac


def direct_jacobian(model: KinematicModel, q: Any) -> np.ndarray:
    """The textbook *direct* 3×nq position Jacobian (base frame): ``z_j × (O_E − O_j)``.

    ``z_j`` for a prismatic joint; from the joint frames' placements alone (no Jacobian routine).
    """
    qv = model.pinocchio_q(q)
    m, d = model.model, model.data
    pin.forwardKinematics(m, d, qv)
    pose = model.baseMo * pin.updateFramePlacement(m, d, model.tip_id)
    cols = []
    for i in range(1, m.njoints):
        omj = model.baseMo * d.oMi[i]
        kind = joint_kind(m.joints[i])
        assert kind is not None  # the loader admits one-variable joints only
        z = omj.rotation @ kind[1]
        prismatic = model.is_prismatic[i - 1]
        cols.append(z if prismatic else np.cross(z, pose.translation - omj.translation))
    return np.column_stack(cols)


def indirect_jacobian(model: KinematicModel, q: Any) -> np.ndarray:
    """The textbook *indirect* 3×nq position Jacobian ``∂p/∂q`` (base frame), exact.

    ``∂p/∂q_j``: the product of transforms with joint ``j``'s replaced by its derivative
    (``E_j·G_j``, ``G_j`` its generator), of the Khalil table when the model is one
    (:func:`~hexapod_kin.params.table_position_jacobian`), else of Pinocchio's joint
    placements and axes. No Jacobian routine, no finite differences.
    """
    from ._table_kin import table_position_jacobian
    from .params import Chain

    qv = model.check_q(q)
    chain = model.params
    if isinstance(chain, Chain) and model.base == chain.base and model.tip == chain.tip:
        return table_position_jacobian(chain, qv)
    arrays = model.arrays
    mats, gens = [], []
    for k in range(arrays.rot.shape[0]):
        place = np.eye(4)
        place[:3, :3] = arrays.rot[k]
        place[:3, 3] = arrays.trans[k]
        axis = arrays.axis[k]
        val = qv[arrays.col[k]]
        motion = np.eye(4)
        gen = np.zeros((4, 4))
        if arrays.kind[k] == 1:
            motion[:3, 3] = axis * val
            gen[:3, 3] = axis
        else:
            motion[:3, :3] = pin.exp3(axis * val)
            gen[:3, :3] = pin.skew(axis)
        mats.append(place @ motion)
        gens.append(gen)
    tip = np.eye(4)
    tip[:3, 3] = arrays.trans[-1]
    mats.append(tip)
    jac = np.zeros((3, model.nq))
    prefix = np.eye(4)
    for k in range(len(gens)):
        prefix = prefix @ mats[k]
        suffix = np.eye(4)
        for m in mats[k + 1 :]:
            suffix = suffix @ m
        jac[:, arrays.col[k]] += (prefix @ gens[k] @ suffix)[:3, 3]
    return jac


def load(
    source: Any, base: str | None = None, tip: str | None = None, **kwargs: Any
) -> KinematicModel:
    """Load a model from a chain/robot, preset name, URDF path or text, or ``erd:NAME``.

    Args:
        source: A :class:`~hexapod_kin.params.Chain` or ``Hexapod``, a preset name
            (``"hexabot_leg"``), a URDF path, URDF text, or ``"erd:solo12"``.
        base: Base frame of the sub-chain (default: the chain's base / the root).
        tip: Tip frame (default: the chain's tip; the first foot of a hexapod; else the last
            body frame). Giving ``base`` or ``tip`` keeps only the joints between them, the
            others locked at ``q_ref`` (default neutral), unless ``reduce=False``.
        **kwargs: ``reduce``, ``q_ref``; ``tool`` (a rigid offset of the tip: 4×4, ``(xyz,
            rpy)`` or a 6-vector, in [m]/[rad]: the frame ``<tip>_tool``, the new tip);
            ``package_dirs`` (where ``package://`` meshes resolve first); ``strict_inertia``
            (refuse implausible inertials instead of warning); ``inertia``
            (:data:`~hexapod_kin.model.INERTIA_MODES`: the file's ``"urdf"``, or the repair
            ``"collision"`` or ``"point"``, :mod:`hexapod_kin._gate.repair`); or preset
            parameters (with a preset name).

    Raises:
        SourceError: The source cannot be resolved.
        UrdfError: The URDF fails the loader gate.
        FrameNotFoundError: Unknown base/tip (the message lists the frames).

    Warns:
        UrdfWarning: Meshes not found (their visuals dropped), implausible inertials.

    """
    options = {key: kwargs.pop(key) for key in _MODEL_OPTIONS if key in kwargs}
    check_mode(options.get("inertia", "urdf"))  # before the source (its errors come first)
    return KinematicModel(resolve_source(source, **kwargs), base, tip, **options)


#: The keywords of :func:`load` that go to the model (the others resolve the source).
_MODEL_OPTIONS = ("reduce", "q_ref", "tool", "strict_inertia", "inertia")


def as_model(model: Any, **params: Any) -> KinematicModel:
    """``model`` itself when it is a loaded model, else :func:`load` ``(model, **params)``."""
    if isinstance(model, Model) and not params:
        return model  # type: ignore[return-value]
    return load(model, **params)
