"""Batch FK and Jacobians of whole poses: ``Model.fk_batch`` / ``jacobian_batch``.

The same chain as :mod:`hexapod_kin._kernels` (:class:`~hexapod_kin._kernels.ChainArrays`,
extracted once per model through ``Model.arrays``), re-expressed with every joint axis along its
frame's z (:class:`AlignedPose`: a constant rotation ``A_j`` with ``A_j ez = u_j`` folded into
the placements; exact signed permutations for coordinate axes; the tip placement is the last
one), so that each result equals Pinocchio's ``fk`` / ``computeFrameJacobian`` of the same model
to rounding, in the three reference frames.

One kernel, :func:`pose_jacobian_kernel`, one compiled signature for every chain and every
request (pose, Jacobian in any frame, or both; ≈1.8 s to compile cold, cached on disk).
Configurations are processed in structure-of-arrays blocks of :data:`BLOCK`, joint by joint,
so the inner loops run over the block and vectorise (SIMD): sin / cos by the libm-free
polynomial :func:`hexapod_kin.singularity._kernel.sincos` (libm for a joint whose block holds an
``|q|`` above :data:`~hexapod_kin.singularity._kernel.POLY_TRIG_MAX`), the 3×3 products, the
Jacobian columns; each block is then written row by row into the (N, 4, 4) / (N, 6, nq)
outputs. The value check of ``q`` (finite, below :data:`Q_MAX`) rides along the transposition
of each block, so a big batch is read once. Big batches run on every core as plain threads
(the kernel releases the GIL; no ``parallel=True``, whose lowering doubles compile time) that
take chunks of blocks from a shared counter, each touching the pages of a fresh output it
writes. At 1e6 leg configurations the time is mostly memory: writing a fresh 128 MB array
with numpy alone takes ≈23 ms here, the batch FK ≈26 ms.

The tier (:mod:`hexapod_kin._tier`) is decided once per call: a small call on a cold process
runs the kernel's source interpreted on one thread (≈6 µs per configuration and joint), a big
one compiles it.
"""

from __future__ import annotations

import itertools
import threading
import time
from collections.abc import Callable
from typing import Any

import numba
import numpy as np

from ._kernels import ChainArrays
from ._numerics import POLY_TRIG_MAX, njit, sincos
from ._tier import compiled, interpreted

__all__ = ["BLOCK", "REF_CODES", "AlignedPose", "aligned", "pose_jacobian_batch"]

#: Reference frame name → kernel code.
REF_CODES = {"local_world_aligned": 0, "world": 1, "local": 2}

#: Configurations per structure-of-arrays block (temporaries stay in L1: 64 measured best).
BLOCK = 64
#: Fewest configurations per thread (below this, one thread: starting threads costs more).
MIN_PER_THREAD = 16_384
#: Chunks of blocks handed out per thread (dynamic: a thread sharing its core takes fewer).
CHUNKS_PER_THREAD = 8
#: Fewest blocks per chunk (each chunk is one kernel call, ~10 µs of dispatch).
MIN_CHUNK_BLOCKS = 64
#: Interpreted seconds per unit of :func:`_work` (measured: 5–10 µs, CPython 3.11).
_INTERP_S = 6e-6
#: Cold compile time of :func:`pose_jacobian_kernel` in [s] (its interpreted budget).
_COMPILE_S = 2.0
#: Joint values must be finite and below this in magnitude (as ``Model.check_q_batch``).
Q_MAX = 1e150


class AlignedPose:
    """A chain re-expressed with z joint axes (the kernel's arguments).

    Placement ``j`` (rotation ``prot[j]``, translation ``ptr[j]``) comes before joint ``j``'s
    motion ``Rz(q)`` / ``Tz(q)``; placement ``m`` is the tip's. With ``A_j ez = u_j`` (see
    :func:`_z_to`), placement ``j`` is ``A_{j-1}ᵀ (R_j, t_j) A_j`` (``A_{-1} = A_m = I``).

    Attributes:
        prot: (m + 1, 9) placement rotations, row-major; the last is the tip rotation.
        ptr: (m + 1, 3) placement translations; the last is the tip offset.
        flags: (m + 1,) int64, 1 where the placement rotation is exactly the identity.
        kind: (m,) 0 revolute, 1 prismatic.
        col: (m,) index of each joint's variable in ``q`` (distinct).
        nq: Length of ``q``.

    """

    def __init__(self, arrays: ChainArrays) -> None:
        m = arrays.rot.shape[0]
        prot = np.empty((m + 1, 9))
        ptr = np.empty((m + 1, 3))
        prev_t = np.eye(3)  # A_{j-1}^T
        for j in range(m + 1):
            a = _z_to(arrays.axis[j]) if j < m else np.eye(3)
            rot = prev_t @ (arrays.rot[j] if j < m else arrays.tip_rot) @ a
            prot[j] = rot.reshape(-1)
            ptr[j] = prev_t @ arrays.trans[j]
            prev_t = a.T
        self.prot = prot
        self.ptr = ptr
        self.flags = np.array([np.array_equal(r, np.eye(3).reshape(-1)) for r in prot], np.int64)
        self.kind = np.ascontiguousarray(arrays.kind, dtype=np.int64)
        self.col = np.ascontiguousarray(arrays.col, dtype=np.int64)
        self.nq = int(arrays.nq)
        if len(set(self.col.tolist())) != m:  # pragma: no cover - one variable per joint
            from .exceptions import SourceError

            raise SourceError(f"joint variables {self.col.tolist()} drive two joints of a chain")


def _z_to(u: np.ndarray) -> np.ndarray:
    """A rotation ``A`` with ``A ez = u`` (unit ``u``); a signed permutation for ±x, ±y, ±z.

    Exact for coordinate axes (no rounding enters the placements); otherwise the columns
    ``(e1, e2, u)`` of an orthonormal frame completed by Gram–Schmidt.
    """
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


def aligned(arrays: ChainArrays) -> AlignedPose:
    """The chain of ``arrays`` with z joint axes (:class:`AlignedPose`)."""
    return AlignedPose(arrays)


def _work(*args: Any) -> float:
    """Units of work of one :func:`pose_jacobian_kernel` call (its ``work=``).

    Configurations × (m + 1) × requested outputs; about :data:`_INTERP_S` interpreted seconds
    each.
    """
    kind, qs, want_pose, want_jac = args[3], args[5], args[8], args[10]
    first, last, block = int(args[11]), int(args[12]), int(args[13])
    n = max(min(int(qs.shape[0]), last * block) - first * block, 0)
    return float(n * (1 + int(kind.shape[0])) * (int(want_pose) + int(want_jac)))


@njit(
    cache=True,
    nogil=True,
    error_model="numpy",
    fastmath={"contract"},
    work=_work,
    per_unit_s=_INTERP_S,
    compile_s=_COMPILE_S,
)
def pose_jacobian_kernel(
    prot: np.ndarray,
    ptr: np.ndarray,
    flags: np.ndarray,
    kind: np.ndarray,
    col: np.ndarray,
    qs: np.ndarray,
    out_t: np.ndarray,
    out_j: np.ndarray,
    want_pose: bool,
    ref: int,
    want_jac: bool,
    first_block: int,
    last_block: int,
    block: int,
) -> bool:  # pragma: no cover - compiled
    """Poses into ``out_t`` (N, 16) and Jacobians into ``out_j`` (N, 6·nq) of some blocks.

    Blocks ``first_block`` to ``last_block - 1`` of ``block`` rows of ``qs`` (N, nq). The
    chain is an :class:`AlignedPose` (``prot``, ``ptr``, ``flags``, ``kind``, ``col``).
    ``ref``: 0 local world aligned, 1 world (velocity of the point at the base origin), 2
    local (tip axes). Only multiply-add contraction (FMA) is allowed to the compiler: no NaN /
    Inf assumptions.

    Returns:
        Whether a value of ``q`` in these blocks is non-finite or ``|q| >= 1e150`` (the
        caller raises; the outputs of such rows are meaningless but no memory outside them is
        written).

    """
    nconf = qs.shape[0]
    nq = qs.shape[1]
    m = kind.shape[0]
    bsz = block
    need_tip_rot = want_pose or (want_jac and ref == 2)
    keep = 0.0 if ref == 1 else 1.0  # world: velocity of the point at the base origin
    rr = np.empty((9, bsz))  # rotation of the current frame (z = joint axis), row-major
    pp = np.empty((3, bsz))  # its origin
    trig = np.empty((2, bsz))
    qb = np.empty((max(nq, 1), bsz))
    jb = np.empty((6 * max(nq, 1), bsz))  # row a * nq + c: J[a, c]
    npj = 6 * nq
    if want_jac and nq > m:  # variables of joints off the path: zero columns
        jb[:, :] = 0.0
    ok = True
    for blk in range(first_block, last_block):
        start = blk * bsz
        nb = min(nconf, start + bsz) - start
        for c in range(nq):  # the block's q, transposed: the per-joint loops read rows
            for i in range(nb):
                qv = qs[start + i, c]
                qb[c, i] = qv
                ok &= abs(qv) < Q_MAX  # False for NaN too
        for a in range(3):
            v = ptr[0, a]
            for i in range(nb):
                pp[a, i] = v
        for a in range(9):
            v = prot[0, a]
            for i in range(nb):
                rr[a, i] = v
        for j in range(m):
            cj = col[j]
            if want_jac:  # prismatic [w; 0]; revolute [o; w], its linear part finished below
                for a in range(3):
                    lin = a * nq + cj
                    ang = lin + 3 * nq
                    w = 3 * a + 2
                    if kind[j] == 1:
                        for i in range(nb):
                            jb[lin, i] = rr[w, i]
                            jb[ang, i] = 0.0
                    else:
                        for i in range(nb):
                            jb[lin, i] = pp[a, i]
                            jb[ang, i] = rr[w, i]
            if kind[j] == 1:
                for i in range(nb):
                    qv = qb[cj, i]
                    pp[0, i] += rr[2, i] * qv
                    pp[1, i] += rr[5, i] * qv
                    pp[2, i] += rr[8, i] * qv
            else:
                big = False
                for i in range(nb):
                    qv = qb[cj, i]
                    big |= abs(qv) > POLY_TRIG_MAX
                    trig[0, i], trig[1, i] = sincos(qv)
                if big:  # an angle beyond the polynomial's range: libm for this joint and block
                    for i in range(nb):
                        qv = qb[cj, i]
                        trig[0, i] = np.sin(qv)
                        trig[1, i] = np.cos(qv)
                for i in range(nb):
                    sq, cq = trig[0, i], trig[1, i]
                    for b in range(0, 9, 3):
                        x0, x1 = rr[b, i], rr[b + 1, i]
                        rr[b, i] = cq * x0 + sq * x1
                        rr[b + 1, i] = cq * x1 - sq * x0
            # placement j + 1 (the tip's after the last joint)
            t0, t1, t2 = ptr[j + 1, 0], ptr[j + 1, 1], ptr[j + 1, 2]
            if t0 != 0.0 or t1 != 0.0 or t2 != 0.0:
                for i in range(nb):
                    pp[0, i] += rr[0, i] * t0 + rr[1, i] * t1 + rr[2, i] * t2
                    pp[1, i] += rr[3, i] * t0 + rr[4, i] * t1 + rr[5, i] * t2
                    pp[2, i] += rr[6, i] * t0 + rr[7, i] * t1 + rr[8, i] * t2
            if flags[j + 1] == 0 and (j + 1 < m or need_tip_rot):
                a00, a01, a02 = prot[j + 1, 0], prot[j + 1, 1], prot[j + 1, 2]
                a10, a11, a12 = prot[j + 1, 3], prot[j + 1, 4], prot[j + 1, 5]
                a20, a21, a22 = prot[j + 1, 6], prot[j + 1, 7], prot[j + 1, 8]
                for i in range(nb):
                    for b in range(0, 9, 3):
                        x0, x1, x2 = rr[b, i], rr[b + 1, i], rr[b + 2, i]
                        rr[b, i] = x0 * a00 + x1 * a10 + x2 * a20
                        rr[b + 1, i] = x0 * a01 + x1 * a11 + x2 * a21
                        rr[b + 2, i] = x0 * a02 + x1 * a12 + x2 * a22
        if want_pose:
            for i in range(nb):
                r = start + i
                out_t[r, 0], out_t[r, 1], out_t[r, 2] = rr[0, i], rr[1, i], rr[2, i]
                out_t[r, 3] = pp[0, i]
                out_t[r, 4], out_t[r, 5], out_t[r, 6] = rr[3, i], rr[4, i], rr[5, i]
                out_t[r, 7] = pp[1, i]
                out_t[r, 8], out_t[r, 9], out_t[r, 10] = rr[6, i], rr[7, i], rr[8, i]
                out_t[r, 11] = pp[2, i]
                out_t[r, 12], out_t[r, 13], out_t[r, 14], out_t[r, 15] = 0.0, 0.0, 0.0, 1.0
        if not want_jac:
            continue
        for j in range(m):  # revolute: w × (p − o), or w × (0 − o) = o × w for world
            if kind[j] == 1:
                continue
            r0 = col[j]
            r1, r2, r3, r4, r5 = r0 + nq, r0 + 2 * nq, r0 + 3 * nq, r0 + 4 * nq, r0 + 5 * nq
            for i in range(nb):
                dx = keep * pp[0, i] - jb[r0, i]
                dy = keep * pp[1, i] - jb[r1, i]
                dz = keep * pp[2, i] - jb[r2, i]
                wx, wy, wz = jb[r3, i], jb[r4, i], jb[r5, i]
                jb[r0, i] = wy * dz - wz * dy
                jb[r1, i] = wz * dx - wx * dz
                jb[r2, i] = wx * dy - wy * dx
        if ref == 2:  # local: both parts in the tip axes (Rᵀ)
            for c in range(2 * nq):
                r0 = (c // nq) * 3 * nq + c % nq
                r1, r2 = r0 + nq, r0 + 2 * nq
                for i in range(nb):
                    vx, vy, vz = jb[r0, i], jb[r1, i], jb[r2, i]
                    jb[r0, i] = rr[0, i] * vx + rr[3, i] * vy + rr[6, i] * vz
                    jb[r1, i] = rr[1, i] * vx + rr[4, i] * vy + rr[7, i] * vz
                    jb[r2, i] = rr[2, i] * vx + rr[5, i] * vy + rr[8, i] * vz
        for i in range(nb):  # rows of 6·nq, one flat loop
            r = start + i
            for p in range(npj):
                out_j[r, p] = jb[p, i]
    return not ok


def _run_threads(
    fast: Callable[..., bool], args: tuple[Any, ...], nblocks: int, bad: list[bool]
) -> None:
    """Run the compiled kernel ``fast`` over ``nblocks`` blocks; its flags go to ``bad``.

    Up to ``numba.get_num_threads()`` threads (the kernel releases the GIL), each taking the
    next chunk of blocks when done with one, so that a thread sharing its core with another
    process does less of the work.
    """
    nwork = max(1, min(numba.get_num_threads(), nblocks * BLOCK // MIN_PER_THREAD))
    if nwork == 1:
        bad.append(fast(*args, 0, nblocks, BLOCK))
        return
    if not getattr(fast, "signatures", True):  # compile (or load) once, before the threads
        fast(*args, 0, 0, BLOCK)
    per = max(MIN_CHUNK_BLOCKS, -(-nblocks // (nwork * CHUNKS_PER_THREAD)))
    chunks = itertools.count()  # next() is atomic under the GIL

    def run() -> None:
        while True:
            first = next(chunks) * per
            if first >= nblocks:
                return
            bad.append(fast(*args, first, min(nblocks, first + per), BLOCK))

    workers = [threading.Thread(target=run) for _ in range(nwork - 1)]
    for t in workers:
        t.start()
    try:
        run()
    finally:
        for t in workers:
            t.join()


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
    chain: AlignedPose | None = None,
    check: Callable[[], object] | None = None,
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Poses (N, 4, 4) and/or Jacobians (N, 6, nq) of configurations ``qs`` (N, nq).

    Args:
        arrays: The chain (``Model.arrays``).
        qs: C-contiguous float64 (N, nq). Its values are checked by the kernel on the way
            (finite, ``|q| < 1e150``); when one is not, ``check()`` is called to raise.
        pose: Whether to compute the poses.
        jacobian: A key of :data:`REF_CODES`, or ``None`` for no Jacobian.
        out_pose: Optional (N, 4, 4) float64 array to write the poses into (a reused buffer
            skips the page faults of a fresh array).
        out_jacobian: Optional (N, 6, nq) float64 array for the Jacobians.
        chain: ``aligned(arrays)`` if the caller keeps it (else derived here, ~30 µs).
        check: Raises the caller's error for ``qs`` (e.g. ``Model.check_q_batch``); called
            only when a value is out of range.

    Returns:
        ``(poses or None, jacobians or None)``.

    Raises:
        ParameterError: An ``out_*`` array of the wrong shape, dtype or layout.
        ConfigurationError: A non-finite or too large value in ``qs`` (from ``check``, or
            this module's message when ``check`` is ``None`` or returns); the ``out_*``
            contents are then unspecified.

    """
    n = qs.shape[0]
    nq = arrays.nq
    out_t = _out(out_pose, (n, 4, 4), "out") if pose else np.empty((1, 4, 4))
    want_jac = jacobian is not None
    out_j = _out(out_jacobian, (n, 6, nq), "out") if want_jac else np.empty((1, 6, nq))
    ref = REF_CODES[jacobian] if jacobian is not None else 0
    al = aligned(arrays) if chain is None else chain
    flat_t = out_t.reshape(out_t.shape[0], 16)
    flat_j = out_j.reshape(out_j.shape[0], 6 * nq)
    nblocks = -(-n // BLOCK)
    args = (al.prot, al.ptr, al.flags, al.kind, al.col, qs, flat_t, flat_j, pose, ref, want_jac)
    kernel = pose_jacobian_kernel
    bad: list[bool] = []
    if kernel.prefer_interpreted(_INTERP_S * _work(*args, 0, nblocks, BLOCK)):
        t0 = time.perf_counter()  # small and cold: the source run by Python, one thread
        bad.append(interpreted(kernel)(*args, 0, nblocks, BLOCK))
        kernel.charge(time.perf_counter() - t0)
    else:
        _run_threads(compiled(kernel), args, nblocks, bad)
    if any(bad):
        if check is not None:
            check()
        from .exceptions import ConfigurationError

        raise ConfigurationError(f"Q contains non-finite values or values with |x| >= {Q_MAX:g}")
    return (out_t if pose else None), (out_j if want_jac else None)
