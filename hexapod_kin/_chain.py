"""A serial chain as flat arrays, the input of the compiled layer (numpy only, no numba).

:class:`ChainArrays`: joint placements, axes and tip offset of any chain of 1-DOF joints,
extracted once per model (``Model.arrays``); :class:`AlignedChain`: the same with every joint
axis along its frame's z (the block core :func:`hexapod_kin._kernels.fk_jac_block`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ._fields import read_only
from .exceptions import SourceError
from .frames import joint_kind

__all__ = ["AlignedChain", "ChainArrays", "aligned_chain"]


@dataclass(frozen=True)
class ChainArrays:
    """A serial chain as flat read-only arrays, in the model's base frame.

    ``rot`` (m, 3, 3) and ``trans`` (m + 1, 3) [m]: the joint placements at q = 0 (the first
    from the base, the last translation the tip offset); ``tip_rot`` (3, 3): the tip frame in
    its joint's; ``axis`` (m, 3): unit axes; ``kind`` (m,): 0 revolute, 1 prismatic; ``col``
    (m,): each joint's index in ``q`` (of length ``nq``).
    """

    rot: np.ndarray
    trans: np.ndarray
    tip_rot: np.ndarray
    axis: np.ndarray
    kind: np.ndarray
    col: np.ndarray
    nq: int

    @classmethod
    def serial(cls, rot: Any, trans: Any, axis: Any, kind: Any, tip_rot: Any = None) -> ChainArrays:
        """A chain of its own joints alone (``col = 0..m-1``, ``nq = m``; ``tip_rot`` default I)."""
        m = len(rot)
        return cls._frozen(
            rot, trans, np.eye(3) if tip_rot is None else tip_rot, axis, kind, np.arange(m), m
        )

    @classmethod
    def _frozen(
        cls, rot: Any, trans: Any, tip_rot: Any, axis: Any, kind: Any, col: Any, nq: int
    ) -> ChainArrays:
        """The arrays as C-contiguous float64 (int64 ``kind``, ``col``), made read-only."""
        arrays = cls(
            rot=np.ascontiguousarray(np.array(rot, dtype=float).reshape(-1, 3, 3)),
            trans=np.ascontiguousarray(np.array(trans, dtype=float).reshape(-1, 3)),
            tip_rot=np.ascontiguousarray(np.array(tip_rot, dtype=float)),
            axis=np.ascontiguousarray(np.array(axis, dtype=float).reshape(-1, 3)),
            kind=np.array(kind, dtype=np.int64),
            col=np.array(col, dtype=np.int64),
            nq=int(nq),
        )
        read_only(arrays.rot, arrays.trans, arrays.tip_rot, arrays.axis, arrays.kind, arrays.col)
        return arrays

    @classmethod
    def from_model(cls, model: Any, frame: str | None = None) -> ChainArrays:
        """Extract the chain from root to ``frame`` (default: the tip) of a loaded model."""
        m = model.model
        fid = model.tip_id if frame is None else model.frame_id(frame)
        fr = m.frames[fid]
        path = [int(i) for i in m.supports[fr.parentJoint]][1:]
        rots, trans, axes, kinds, cols = [], [], [], [], []
        for k, i in enumerate(path):
            placement = model.baseMo * m.jointPlacements[i] if k == 0 else m.jointPlacements[i]
            kind = joint_kind(m.joints[i])
            assert kind is not None  # the loader admits one-variable joints only
            kinds.append(1 if kind[0] == "prismatic" else 0)
            rots.append(np.array(placement.rotation))
            trans.append(np.array(placement.translation))
            axes.append(kind[1] / np.linalg.norm(kind[1]))
            cols.append(int(m.joints[i].idx_v))
        tip_pl = fr.placement if path else model.baseMo * fr.placement
        trans.append(np.array(tip_pl.translation))
        return cls._frozen(rots, trans, tip_pl.rotation, axes, kinds, cols, m.nv)

    def scratch(self) -> np.ndarray:
        """A fresh (6, m) work array for :func:`hexapod_kin._kernels.fk_jac_into`."""
        return np.empty((6, max(self.rot.shape[0], 1)))

    @property
    def packed(self) -> tuple[np.ndarray, ...]:
        """The arrays in the argument order of the compiled kernels."""
        return (self.rot, self.trans, self.axis, self.kind, self.col)


@dataclass(frozen=True)
class AlignedChain:
    """A chain re-expressed with z joint axes (the block FK core's arguments).

    Placement ``j`` (``prot[j]`` (9,) row-major, ``ptr[j]`` [m]) comes before joint ``j``'s
    ``Rz(q)`` / ``Tz(q)``; the last is the tip's. With ``A_j ez = u_j`` (:func:`_z_to`) it is
    ``A_{j-1}ᵀ (R_j, t_j) A_j`` (``A_{-1} = A_m = I``). ``flags``: 1 where ``prot[j]`` is
    exactly the identity; ``kind``, ``col`` (distinct), ``nq`` as :class:`ChainArrays`.
    """

    prot: np.ndarray
    ptr: np.ndarray
    flags: np.ndarray
    kind: np.ndarray
    col: np.ndarray
    nq: int

    @property
    def packed(self) -> tuple[np.ndarray, ...]:
        """``(prot, ptr, flags, kind, col)``: the block core's argument order."""
        return (self.prot, self.ptr, self.flags, self.kind, self.col)


def _z_to(u: np.ndarray) -> np.ndarray:
    """A rotation ``A`` with ``A ez = u``: exact for ±x, ±y, ±z, else Gram–Schmidt's."""
    u = np.asarray(u, dtype=float)
    for k in range(3):
        if abs(u[k]) == 1.0 and np.count_nonzero(u) == 1:
            s = float(u[k])
            ex, ey = np.zeros(3), np.zeros(3)
            ex[(k + 1) % 3] = 1.0
            ey[(k + 2) % 3] = s  # (ex, ey, u) right-handed: ex × ey = s·e_k = u
            return np.column_stack([ex, ey, u])
    u = u / np.linalg.norm(u)
    ref = np.eye(3)[int(np.argmin(np.abs(u)))]
    e1 = ref - (ref @ u) * u
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(u, e1)
    return np.column_stack([e1, e2, u])


def aligned_chain(arrays: ChainArrays) -> AlignedChain:
    """The chain of ``arrays`` with z joint axes (SourceError: a variable drives two joints)."""
    m = arrays.rot.shape[0]
    prot = np.empty((m + 1, 9))
    ptr = np.empty((m + 1, 3))
    prev_t = np.eye(3)  # A_{j-1}^T
    for j in range(m + 1):
        a = _z_to(arrays.axis[j]) if j < m else np.eye(3)
        prot[j] = (prev_t @ (arrays.rot[j] if j < m else arrays.tip_rot) @ a).reshape(-1)
        ptr[j] = prev_t @ arrays.trans[j]
        prev_t = a.T
    flags = np.array([np.array_equal(r, np.eye(3).reshape(-1)) for r in prot], np.int64)
    col = np.ascontiguousarray(arrays.col, dtype=np.int64)
    if len(set(col.tolist())) != m:
        raise SourceError(f"joint variables {col.tolist()} drive two joints of a chain")
    kind = np.ascontiguousarray(arrays.kind, dtype=np.int64)
    return AlignedChain(prot, ptr, flags, kind, col, int(arrays.nq))
