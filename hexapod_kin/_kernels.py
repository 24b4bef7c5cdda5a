"""Compiled batch kernels for serial chains: foot position and Jacobian of many configurations.

A :class:`ChainArrays` is extracted from a loaded model's *Pinocchio* model (joint placements,
axes, tip offset), so the kernels serve any 1-DOF serial chain — catalogue presets and URDFs
alike — and agree with Pinocchio to rounding. They are numba-compiled (``prange`` over
configurations; numba is a core dependency, ``njit`` comes from :mod:`hexapod_kin._numerics`).

Inner ``@njit`` functions (``fk_jac_into``) can be called from other numba code (IK loops,
scans) without Python overhead.

Jacobians here are LOCAL_WORLD_ALIGNED in the model's base frame: rows ``[v; ω]``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numba
import numpy as np

from ._numerics import njit, prange
from .exceptions import ConfigurationError, SourceError

__all__ = [
    "ChainArrays",
    "fk_batch",
    "jacobian_batch",
    "position_jacobian_batch",
    "fk_position",
    "position_jacobian",
    "fk_jac_into",
    "check_batch",
    "set_threads",
]


@dataclass(frozen=True)
class ChainArrays:
    """A serial chain as flat arrays (read-only), in the model's base frame.

    Attributes:
        rot: (m, 3, 3) rotation of each joint placement (parent joint → joint at q = 0); the
            first one includes the base → root transform.
        trans: (m + 1, 3) translations of the placements; the last row is the tip offset in
            the frame of the tip's parent joint.
        tip_rot: (3, 3) rotation of the tip frame in its parent joint frame.
        axis: (m, 3) unit joint axes in their joint frames.
        kind: (m,) 0 revolute, 1 prismatic.
        col: (m,) index of each joint's variable in ``q``.
        nq: Length of ``q``.

    """

    rot: np.ndarray
    trans: np.ndarray
    tip_rot: np.ndarray
    axis: np.ndarray
    kind: np.ndarray
    col: np.ndarray
    nq: int

    @classmethod
    def from_model(cls, model: Any, frame: str | None = None) -> ChainArrays:
        """Extract the chain from root to ``frame`` (default: the tip) of a loaded model.

        Args:
            model: A :class:`~hexapod_kin.model.Model` (1-DOF revolute/prismatic joints).
            frame: Tip frame name (checked).

        Raises:
            SourceError: If a joint on the path is not a 1-DOF revolute/prismatic joint.

        """
        import pinocchio as pin

        m = model.model
        fid = model.tip_id if frame is None else model.frame_id(frame)
        fr = m.frames[fid]
        path = [int(i) for i in m.supports[fr.parentJoint]][1:]
        rots, trans, axes, kinds, cols = [], [], [], [], []
        for k, i in enumerate(path):
            placement = m.jointPlacements[i]
            if k == 0:
                placement = model.baseMo * placement
            name = m.joints[i].shortname()
            if name.startswith("JointModelR"):
                kinds.append(0)
            elif name.startswith("JointModelP"):
                kinds.append(1)
            else:
                raise SourceError(f"joint {m.names[i]!r} of kind {name} is not 1-DOF rev/prism")
            if name[-1] in "XYZ":
                ax = np.zeros(3)
                ax["XYZ".index(name[-1])] = 1.0
            else:
                ax = np.asarray(m.joints[i].extract().axis, dtype=float)
                ax = ax / np.linalg.norm(ax)
            rots.append(np.array(placement.rotation))
            trans.append(np.array(placement.translation))
            axes.append(ax)
            cols.append(int(m.joints[i].idx_v))
        if not path:
            tip_pl = model.baseMo * fr.placement
        else:
            tip_pl = fr.placement
        trans.append(np.array(tip_pl.translation))
        arrays = cls(
            rot=np.ascontiguousarray(np.array(rots, dtype=float).reshape(-1, 3, 3)),
            trans=np.ascontiguousarray(np.array(trans, dtype=float).reshape(-1, 3)),
            tip_rot=np.ascontiguousarray(np.array(tip_pl.rotation, dtype=float)),
            axis=np.ascontiguousarray(np.array(axes, dtype=float).reshape(-1, 3)),
            kind=np.array(kinds, dtype=np.int64),
            col=np.array(cols, dtype=np.int64),
            nq=int(m.nv),
        )
        for arr in (arrays.rot, arrays.trans, arrays.tip_rot, arrays.axis, arrays.kind, arrays.col):
            arr.setflags(write=False)
        del pin
        return arrays

    def scratch(self) -> np.ndarray:
        """A fresh (6, m) work array for :func:`fk_jac_into`."""
        return np.empty((6, max(self.rot.shape[0], 1)))

    @property
    def packed(self) -> tuple[np.ndarray, ...]:
        """The arrays in the argument order of the compiled kernels."""
        return (self.rot, self.trans, self.axis, self.kind, self.col)


@njit(cache=True, fastmath=False, nogil=True)
def fk_jac_into(
    rot: np.ndarray,
    trans: np.ndarray,
    axis: np.ndarray,
    kind: np.ndarray,
    col: np.ndarray,
    q: np.ndarray,
    out_p: np.ndarray,
    out_j: np.ndarray,
    scratch: np.ndarray,
    want_jac: bool,
) -> None:  # pragma: no cover - compiled
    """Tip position into ``out_p`` (3,) and LWA Jacobian into ``out_j`` (3 or 6, nq).

    ``scratch`` is a (6, m) work array (joint origins and axes); nothing is allocated.
    Callers in compiled code pass ``want_jac`` as a runtime value (``n >= 0``, an argument),
    never a literal ``True``/``False``: numba would compile one copy per literal.
    """
    m = rot.shape[0]
    r00, r01, r02 = 1.0, 0.0, 0.0
    r10, r11, r12 = 0.0, 1.0, 0.0
    r20, r21, r22 = 0.0, 0.0, 1.0
    px, py, pz = 0.0, 0.0, 0.0
    for k in range(m):
        tx, ty, tz = trans[k, 0], trans[k, 1], trans[k, 2]
        px, py, pz = (
            px + r00 * tx + r01 * ty + r02 * tz,
            py + r10 * tx + r11 * ty + r12 * tz,
            pz + r20 * tx + r21 * ty + r22 * tz,
        )
        if not (
            rot[k, 0, 0] == 1.0
            and rot[k, 1, 1] == 1.0
            and rot[k, 2, 2] == 1.0
            and rot[k, 0, 1] == 0.0
            and rot[k, 0, 2] == 0.0
            and rot[k, 1, 0] == 0.0
            and rot[k, 1, 2] == 0.0
            and rot[k, 2, 0] == 0.0
            and rot[k, 2, 1] == 0.0
        ):
            n00 = r00 * rot[k, 0, 0] + r01 * rot[k, 1, 0] + r02 * rot[k, 2, 0]
            n01 = r00 * rot[k, 0, 1] + r01 * rot[k, 1, 1] + r02 * rot[k, 2, 1]
            n02 = r00 * rot[k, 0, 2] + r01 * rot[k, 1, 2] + r02 * rot[k, 2, 2]
            n10 = r10 * rot[k, 0, 0] + r11 * rot[k, 1, 0] + r12 * rot[k, 2, 0]
            n11 = r10 * rot[k, 0, 1] + r11 * rot[k, 1, 1] + r12 * rot[k, 2, 1]
            n12 = r10 * rot[k, 0, 2] + r11 * rot[k, 1, 2] + r12 * rot[k, 2, 2]
            n20 = r20 * rot[k, 0, 0] + r21 * rot[k, 1, 0] + r22 * rot[k, 2, 0]
            n21 = r20 * rot[k, 0, 1] + r21 * rot[k, 1, 1] + r22 * rot[k, 2, 1]
            n22 = r20 * rot[k, 0, 2] + r21 * rot[k, 1, 2] + r22 * rot[k, 2, 2]
            r00, r01, r02, r10, r11, r12 = n00, n01, n02, n10, n11, n12
            r20, r21, r22 = n20, n21, n22
        ux, uy, uz = axis[k, 0], axis[k, 1], axis[k, 2]
        wx = r00 * ux + r01 * uy + r02 * uz
        wy = r10 * ux + r11 * uy + r12 * uz
        wz = r20 * ux + r21 * uy + r22 * uz
        scratch[0, k] = px
        scratch[1, k] = py
        scratch[2, k] = pz
        scratch[3, k] = wx
        scratch[4, k] = wy
        scratch[5, k] = wz
        qk = q[col[k]]
        if kind[k] == 1:
            px, py, pz = px + wx * qk, py + wy * qk, pz + wz * qk
        elif ux == 0.0 and uy == 0.0 and uz == 1.0:
            c = np.cos(qk)
            s = np.sin(qk)
            r00, r01 = c * r00 + s * r01, c * r01 - s * r00
            r10, r11 = c * r10 + s * r11, c * r11 - s * r10
            r20, r21 = c * r20 + s * r21, c * r21 - s * r20
        else:
            c = np.cos(qk)
            s = np.sin(qk)
            v = 1.0 - c
            # Rodrigues rotation about the local axis u by qk: E = c I + s [u]x + v u u^T
            e00 = c + v * ux * ux
            e01 = v * ux * uy - s * uz
            e02 = v * ux * uz + s * uy
            e10 = v * uy * ux + s * uz
            e11 = c + v * uy * uy
            e12 = v * uy * uz - s * ux
            e20 = v * uz * ux - s * uy
            e21 = v * uz * uy + s * ux
            e22 = c + v * uz * uz
            n00 = r00 * e00 + r01 * e10 + r02 * e20
            n01 = r00 * e01 + r01 * e11 + r02 * e21
            n02 = r00 * e02 + r01 * e12 + r02 * e22
            n10 = r10 * e00 + r11 * e10 + r12 * e20
            n11 = r10 * e01 + r11 * e11 + r12 * e21
            n12 = r10 * e02 + r11 * e12 + r12 * e22
            n20 = r20 * e00 + r21 * e10 + r22 * e20
            n21 = r20 * e01 + r21 * e11 + r22 * e21
            n22 = r20 * e02 + r21 * e12 + r22 * e22
            r00, r01, r02, r10, r11, r12 = n00, n01, n02, n10, n11, n12
            r20, r21, r22 = n20, n21, n22
    tx, ty, tz = trans[m, 0], trans[m, 1], trans[m, 2]
    px, py, pz = (
        px + r00 * tx + r01 * ty + r02 * tz,
        py + r10 * tx + r11 * ty + r12 * tz,
        pz + r20 * tx + r21 * ty + r22 * tz,
    )
    out_p[0], out_p[1], out_p[2] = px, py, pz
    if not want_jac:
        return
    out_j[:, :] = 0.0
    ang = out_j.shape[0] == 6
    for k in range(m):
        j = col[k]
        if kind[k] == 1:
            out_j[0, j] += scratch[3, k]
            out_j[1, j] += scratch[4, k]
            out_j[2, j] += scratch[5, k]
        else:
            dx, dy, dz = px - scratch[0, k], py - scratch[1, k], pz - scratch[2, k]
            out_j[0, j] += scratch[4, k] * dz - scratch[5, k] * dy
            out_j[1, j] += scratch[5, k] * dx - scratch[3, k] * dz
            out_j[2, j] += scratch[3, k] * dy - scratch[4, k] * dx
            if ang:
                out_j[3, j] += scratch[3, k]
                out_j[4, j] += scratch[4, k]
                out_j[5, j] += scratch[5, k]


@njit(cache=True, parallel=True, nogil=True)
def _batch(
    rot: np.ndarray,
    trans: np.ndarray,
    axis: np.ndarray,
    kind: np.ndarray,
    col: np.ndarray,
    qs: np.ndarray,
    out_p: np.ndarray,
    out_j: np.ndarray,
    want_jac: bool,
) -> None:  # pragma: no cover - compiled
    n = qs.shape[0]
    chunk = 2048
    nchunks = (n + chunk - 1) // chunk
    for c in prange(nchunks):
        scratch = np.empty((6, max(rot.shape[0], 1)))
        dummy = np.empty((3, qs.shape[1]))
        for i in range(c * chunk, min(n, (c + 1) * chunk)):
            if want_jac:
                fk_jac_into(
                    rot, trans, axis, kind, col, qs[i], out_p[i], out_j[i], scratch, want_jac
                )
            else:
                fk_jac_into(rot, trans, axis, kind, col, qs[i], out_p[i], dummy, scratch, want_jac)


def check_batch(arrays: ChainArrays, qs: Any) -> np.ndarray:
    """``qs`` as an (N, nq) float64 C-contiguous array (a single (nq,) becomes (1, nq)).

    Raises:
        ConfigurationError: Wrong shape or non-finite values.

    """
    q = np.ascontiguousarray(np.asarray(qs, dtype=np.float64))
    if q.ndim == 1:
        q = q[None, :]
    if q.ndim != 2 or q.shape[1] != arrays.nq:
        raise ConfigurationError(
            f"Q has shape {np.shape(qs)}; expected (N, {arrays.nq})",
            parameter="Q",
            value=np.shape(qs),
            allowed=f"shape (N, {arrays.nq})",
        )
    if not np.all(np.isfinite(q)):
        raise ConfigurationError(
            "Q contains non-finite values",
            parameter="Q",
            value="non-finite",
            allowed="finite numbers",
        )
    return q


def fk_batch(arrays: ChainArrays, qs: Any) -> np.ndarray:
    """Tip positions (N, 3) in [m] for configurations ``qs`` (N, nq)."""
    q = check_batch(arrays, qs)
    out_p = np.empty((q.shape[0], 3))
    dummy = np.empty((1, 3, arrays.nq))
    _batch(*arrays.packed, q, out_p, dummy, False)
    return out_p


def jacobian_batch(arrays: ChainArrays, qs: Any, rows: int = 6) -> np.ndarray:
    """LWA Jacobians (N, rows, nq) for ``qs`` (N, nq); ``rows=3`` keeps the position part."""
    q = check_batch(arrays, qs)
    if rows not in (3, 6):
        raise ConfigurationError(f"rows={rows!r}; use 3 (position) or 6 (position + rotation)")
    out_p = np.empty((q.shape[0], 3))
    out_j = np.empty((q.shape[0], rows, arrays.nq))
    _batch(*arrays.packed, q, out_p, out_j, True)
    return out_j


def position_jacobian_batch(arrays: ChainArrays, qs: Any) -> np.ndarray:
    """Position Jacobians (N, 3, nq) in the base frame."""
    return jacobian_batch(arrays, qs, rows=3)


def fk_position(arrays: ChainArrays, q: Any) -> np.ndarray:
    """Tip position (3,) for one configuration."""
    qv = np.array(q, dtype=np.float64)  # writable C array: the kernels' q type (one compile)
    out_p = np.empty(3)
    fk_jac_into(*arrays.packed, qv, out_p, np.empty((3, arrays.nq)), arrays.scratch(), False)
    return out_p


def position_jacobian(arrays: ChainArrays, q: Any) -> np.ndarray:
    """Position Jacobian (3, nq) for one configuration."""
    qv = np.array(q, dtype=np.float64)  # writable C array: the kernels' q type (one compile)
    out_j = np.empty((3, arrays.nq))
    fk_jac_into(*arrays.packed, qv, np.empty(3), out_j, arrays.scratch(), True)
    return out_j


def set_threads(n: int | None) -> None:
    """Set numba's thread count (``None``/0: unchanged)."""
    if n:
        numba.set_num_threads(int(n))


_check_batch = check_batch  # the old private name, for callers not yet switched
