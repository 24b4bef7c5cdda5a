"""Compiled batch FK and Jacobians of whole poses: ``Model.fk_batch`` / ``jacobian_batch``.

The same chain arrays as :mod:`hexapod_kin._kernels` (:class:`~hexapod_kin._kernels.ChainArrays`,
extracted once per model through ``Model.arrays``), but carrying the full tip rotation and the
three Pinocchio reference frames, so that each result equals Pinocchio's ``fk``/
``computeFrameJacobian`` of the same model to rounding. Compiled with numba (``prange`` over
configurations, chunks of 4,096).
"""

from __future__ import annotations

import numpy as np

from ._kernels import ChainArrays
from ._numerics import njit, prange

__all__ = ["REF_CODES", "pose_jacobian_batch"]

#: Reference frame name → kernel code.
REF_CODES = {"local_world_aligned": 0, "world": 1, "local": 2}

_CHUNK = 4096


@njit(cache=True, nogil=True)
def _one(
    rot: np.ndarray,
    trans: np.ndarray,
    axis: np.ndarray,
    kind: np.ndarray,
    col: np.ndarray,
    plain: np.ndarray,
    tip_rot: np.ndarray,
    q: np.ndarray,
    out_t: np.ndarray,
    out_j: np.ndarray,
    want_pose: bool,
    ref: int,
    want_jac: bool,
    org: np.ndarray,
) -> None:  # pragma: no cover - compiled
    """Pose (4×4) into ``out_t`` and Jacobian (6×nq, ``ref``) into ``out_j`` for one ``q``.

    ``plain[k]`` is 1 when joint k's placement rotation is the identity (skipped) and 2 when
    moreover its axis is +z (the rotation by q is then a plane rotation). ``org`` is a (m, 6)
    work array: joint origins and world axes.
    """
    m = rot.shape[0]
    r00, r01, r02 = 1.0, 0.0, 0.0
    r10, r11, r12 = 0.0, 1.0, 0.0
    r20, r21, r22 = 0.0, 0.0, 1.0
    px, py, pz = 0.0, 0.0, 0.0
    for k in range(m):
        tx, ty, tz = trans[k, 0], trans[k, 1], trans[k, 2]
        px += r00 * tx + r01 * ty + r02 * tz
        py += r10 * tx + r11 * ty + r12 * tz
        pz += r20 * tx + r21 * ty + r22 * tz
        if plain[k] == 0:
            a00, a01, a02 = rot[k, 0, 0], rot[k, 0, 1], rot[k, 0, 2]
            a10, a11, a12 = rot[k, 1, 0], rot[k, 1, 1], rot[k, 1, 2]
            a20, a21, a22 = rot[k, 2, 0], rot[k, 2, 1], rot[k, 2, 2]
            r00, r01, r02 = (
                r00 * a00 + r01 * a10 + r02 * a20,
                r00 * a01 + r01 * a11 + r02 * a21,
                r00 * a02 + r01 * a12 + r02 * a22,
            )
            r10, r11, r12 = (
                r10 * a00 + r11 * a10 + r12 * a20,
                r10 * a01 + r11 * a11 + r12 * a21,
                r10 * a02 + r11 * a12 + r12 * a22,
            )
            r20, r21, r22 = (
                r20 * a00 + r21 * a10 + r22 * a20,
                r20 * a01 + r21 * a11 + r22 * a21,
                r20 * a02 + r21 * a12 + r22 * a22,
            )
        ux, uy, uz = axis[k, 0], axis[k, 1], axis[k, 2]
        wx = r00 * ux + r01 * uy + r02 * uz
        wy = r10 * ux + r11 * uy + r12 * uz
        wz = r20 * ux + r21 * uy + r22 * uz
        org[k, 0], org[k, 1], org[k, 2] = px, py, pz
        org[k, 3], org[k, 4], org[k, 5] = wx, wy, wz
        qk = q[col[k]]
        if kind[k] == 1:
            px += wx * qk
            py += wy * qk
            pz += wz * qk
            continue
        c = np.cos(qk)
        s = np.sin(qk)
        if plain[k] == 2 or (ux == 0.0 and uy == 0.0 and uz == 1.0):
            r00, r01 = c * r00 + s * r01, c * r01 - s * r00
            r10, r11 = c * r10 + s * r11, c * r11 - s * r10
            r20, r21 = c * r20 + s * r21, c * r21 - s * r20
            continue
        v = 1.0 - c
        e00 = c + v * ux * ux
        e01 = v * ux * uy - s * uz
        e02 = v * ux * uz + s * uy
        e10 = v * uy * ux + s * uz
        e11 = c + v * uy * uy
        e12 = v * uy * uz - s * ux
        e20 = v * uz * ux - s * uy
        e21 = v * uz * uy + s * ux
        e22 = c + v * uz * uz
        r00, r01, r02 = (
            r00 * e00 + r01 * e10 + r02 * e20,
            r00 * e01 + r01 * e11 + r02 * e21,
            r00 * e02 + r01 * e12 + r02 * e22,
        )
        r10, r11, r12 = (
            r10 * e00 + r11 * e10 + r12 * e20,
            r10 * e01 + r11 * e11 + r12 * e21,
            r10 * e02 + r11 * e12 + r12 * e22,
        )
        r20, r21, r22 = (
            r20 * e00 + r21 * e10 + r22 * e20,
            r20 * e01 + r21 * e11 + r22 * e21,
            r20 * e02 + r21 * e12 + r22 * e22,
        )
    tx, ty, tz = trans[m, 0], trans[m, 1], trans[m, 2]
    px += r00 * tx + r01 * ty + r02 * tz
    py += r10 * tx + r11 * ty + r12 * tz
    pz += r20 * tx + r21 * ty + r22 * tz
    a00, a01, a02 = tip_rot[0, 0], tip_rot[0, 1], tip_rot[0, 2]
    a10, a11, a12 = tip_rot[1, 0], tip_rot[1, 1], tip_rot[1, 2]
    a20, a21, a22 = tip_rot[2, 0], tip_rot[2, 1], tip_rot[2, 2]
    t00 = r00 * a00 + r01 * a10 + r02 * a20
    t01 = r00 * a01 + r01 * a11 + r02 * a21
    t02 = r00 * a02 + r01 * a12 + r02 * a22
    t10 = r10 * a00 + r11 * a10 + r12 * a20
    t11 = r10 * a01 + r11 * a11 + r12 * a21
    t12 = r10 * a02 + r11 * a12 + r12 * a22
    t20 = r20 * a00 + r21 * a10 + r22 * a20
    t21 = r20 * a01 + r21 * a11 + r22 * a21
    t22 = r20 * a02 + r21 * a12 + r22 * a22
    if want_pose:
        out_t[0, 0], out_t[0, 1], out_t[0, 2], out_t[0, 3] = t00, t01, t02, px
        out_t[1, 0], out_t[1, 1], out_t[1, 2], out_t[1, 3] = t10, t11, t12, py
        out_t[2, 0], out_t[2, 1], out_t[2, 2], out_t[2, 3] = t20, t21, t22, pz
        out_t[3, 0], out_t[3, 1], out_t[3, 2], out_t[3, 3] = 0.0, 0.0, 0.0, 1.0
    if not want_jac:
        return
    out_j[:, :] = 0.0
    for k in range(m):
        j = col[k]
        wx, wy, wz = org[k, 3], org[k, 4], org[k, 5]
        if kind[k] == 1:
            vx, vy, vz = wx, wy, wz
            ox = oy = oz = 0.0
        else:
            if ref == 1:  # WORLD: velocity of the point at the base origin, o × w
                qx, qy, qz = org[k, 0], org[k, 1], org[k, 2]
                vx = qy * wz - qz * wy
                vy = qz * wx - qx * wz
                vz = qx * wy - qy * wx
            else:
                dx, dy, dz = px - org[k, 0], py - org[k, 1], pz - org[k, 2]
                vx = wy * dz - wz * dy
                vy = wz * dx - wx * dz
                vz = wx * dy - wy * dx
            ox, oy, oz = wx, wy, wz
        if ref == 2:  # LOCAL: both parts in the tip axes (R^T)
            out_j[0, j] += t00 * vx + t10 * vy + t20 * vz
            out_j[1, j] += t01 * vx + t11 * vy + t21 * vz
            out_j[2, j] += t02 * vx + t12 * vy + t22 * vz
            out_j[3, j] += t00 * ox + t10 * oy + t20 * oz
            out_j[4, j] += t01 * ox + t11 * oy + t21 * oz
            out_j[5, j] += t02 * ox + t12 * oy + t22 * oz
        else:
            out_j[0, j] += vx
            out_j[1, j] += vy
            out_j[2, j] += vz
            out_j[3, j] += ox
            out_j[4, j] += oy
            out_j[5, j] += oz


@njit(cache=True, parallel=True, nogil=True)
def _run(
    rot: np.ndarray,
    trans: np.ndarray,
    axis: np.ndarray,
    kind: np.ndarray,
    col: np.ndarray,
    plain: np.ndarray,
    tip_rot: np.ndarray,
    qs: np.ndarray,
    out_t: np.ndarray,
    out_j: np.ndarray,
    want_pose: bool,
    ref: int,
    want_jac: bool,
) -> None:  # pragma: no cover - compiled
    n = qs.shape[0]
    m = max(rot.shape[0], 1)
    nchunks = (n + _CHUNK - 1) // _CHUNK
    for c in prange(nchunks):
        org = np.empty((m, 6))
        for i in range(c * _CHUNK, min(n, (c + 1) * _CHUNK)):
            _one(
                rot, trans, axis, kind, col, plain, tip_rot, qs[i],
                out_t[i if want_pose else 0], out_j[i if want_jac else 0],
                want_pose, ref, want_jac, org,
            )  # fmt: skip


def plain_flags(arrays: ChainArrays) -> np.ndarray:
    """Per joint: 1 if its placement rotation is exactly the identity, 2 if its axis is also +z."""
    ident = np.all(arrays.rot == np.eye(3), axis=(1, 2))
    zaxis = np.all(arrays.axis == np.array([0.0, 0.0, 1.0]), axis=1)
    return (ident.astype(np.int64) * (1 + zaxis.astype(np.int64))).astype(np.int64)


def _out(out: np.ndarray | None, shape: tuple[int, ...], name: str) -> np.ndarray:
    """``out`` checked (float64, C-contiguous, writeable, ``shape``), or a new array."""
    if out is None:
        return np.empty(shape)
    if not (
        isinstance(out, np.ndarray)
        and out.dtype == np.float64
        and out.shape == shape
        and out.flags.c_contiguous
        and out.flags.writeable
    ):
        from .exceptions import ParameterError

        raise ParameterError(
            f"{name}: an array of shape {np.shape(out)} and dtype "
            f"{getattr(out, 'dtype', type(out).__name__)} is not allowed; a writeable "
            f"C-contiguous float64 array of shape {shape} is required",
            parameter=name,
            allowed=f"float64 {shape}",
        )
    return out


def pose_jacobian_batch(
    arrays: ChainArrays,
    qs: np.ndarray,
    *,
    pose: bool,
    jacobian: str | None,
    out_pose: np.ndarray | None = None,
    out_jacobian: np.ndarray | None = None,
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Poses (N, 4, 4) and/or Jacobians (N, 6, nq) of checked configurations ``qs`` (N, nq).

    Args:
        arrays: The chain (``Model.arrays``).
        qs: C-contiguous float64 (N, nq), already checked by the caller.
        pose: Whether to compute the poses.
        jacobian: A key of :data:`REF_CODES`, or ``None`` for no Jacobian.
        out_pose: Optional (N, 4, 4) float64 array to write the poses into (reused buffers
            skip the page faults of a fresh array: about 40 ms per 1e6 poses here).
        out_jacobian: Optional (N, 6, nq) float64 array for the Jacobians.

    Returns:
        ``(poses or None, jacobians or None)``.

    Raises:
        ParameterError: An ``out_*`` array of the wrong shape, dtype or layout.

    """
    n = qs.shape[0]
    out_t = _out(out_pose, (n, 4, 4), "out") if pose else np.empty((1, 4, 4))
    want_jac = jacobian is not None
    out_j = (
        _out(out_jacobian, (n, 6, arrays.nq), "out") if want_jac else np.empty((1, 6, arrays.nq))
    )
    ref = REF_CODES[jacobian] if jacobian is not None else 0
    _run(
        arrays.rot, arrays.trans, arrays.axis, arrays.kind, arrays.col, plain_flags(arrays),
        arrays.tip_rot, qs, out_t, out_j, pose, ref, want_jac,
    )  # fmt: skip
    return (out_t if pose else None), (out_j if want_jac else None)
