"""The one compiled layer (numba): the FK + Jacobian core and the batch kernels of chains.

Equal to Pinocchio to rounding: :func:`fk_jac_into`, one configuration of a
:class:`~hexapod_kin._chain.ChainArrays` (the IK loop), and :func:`fk_jac_block`, a block of an
:class:`~hexapod_kin._chain.AlignedChain` (every batch kernel; its loops vectorise).
**Same bits every time**: no ``fastmath``; each element depends on its own input only.

Kernels are ``cache=True`` (:func:`hexapod_kin._kmath.njit`, numba's files sealed); before an
area's first kernel call :func:`run_blocks` prints one notice unless the area's stamp
(:func:`mark_compiled`) says it is compiled; a cache that cannot be loaded or written is never
fatal (:func:`_first_call`). Jacobians ``[v; ω]`` are LOCAL_WORLD_ALIGNED, base frame.
"""

from __future__ import annotations

import contextlib
import errno
import functools
import gc
import itertools
import math
import sys
import threading
import time
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numba
import numpy as np

from ._chain import AlignedChain, ChainArrays, aligned_chain
from ._kmath import (
    POLY_TRIG_MAX,
    OnEnd,
    dls_into,
    eig3_sym,
    njit,
    seal_compiled,
    sincos,
    solve_spd,
    wrap_angle,
)
from .exceptions import CacheWarning, ConfigurationError, ParameterError

__all__ = ["BLOCK", "COMPILE_SECONDS", "POLY_TRIG_MAX", "Q_MAX", "REF_CODES", "AlignedChain",
           "ChainArrays", "aligned_chain", "dls_into", "eig3_sym", "fk_jac_block", "fk_jac_into",
           "mark_compiled", "njit", "pose_jacobian_batch", "pose_jacobian_kernel", "run_blocks",
           "silence_notice", "sincos", "solve_spd", "threads", "wrap_angle"]  # fmt: skip

#: Reference frame name → kernel code.
REF_CODES = {"local_world_aligned": 0, "world": 1, "local": 2}
#: Configurations per structure-of-arrays block of :func:`pose_jacobian_kernel` (L1-sized).
BLOCK = 64
#: Fewest configurations per thread (below this, one thread: starting threads costs more).
MIN_PER_THREAD = 16_384
#: Chunks of blocks handed out per thread (dynamic: a thread sharing its core takes fewer).
CHUNKS_PER_THREAD = 8
#: Fewest blocks per chunk (each chunk is one kernel call, ~10 µs of dispatch).
MIN_CHUNK_BLOCKS = 64
#: Joint values must be finite and below this in magnitude (as ``Model.check_q_batch``).
Q_MAX = 1e150
#: Seconds of CPU each area's kernels take to compile from nothing (the notice's estimate;
#: measured on the project's 2-core machine: ``hexapod-kin precompile`` prints each area's).
COMPILE_SECONDS = {"batch": 4.0, "ik": 14.0, "singularity": 20.0}


# ------------------------------------------------------------------------ first use
_SEEN: set[str] = set()
_SEEN_LOCK = threading.Lock()
_NOTICE = [True]
#: Areas whose cache could not be written (said once per process: the next areas are alike).
_SAID: list[str] = []
#: Most first calls of an area: each failed save of numba's cache leaves one more kernel in memory.
_ATTEMPTS = 64


def silence_notice() -> None:
    """No first-use notice in this process (``precompile`` compiles on purpose)."""
    _NOTICE[0] = False


@functools.cache
def _stamp_key() -> str:
    """Package version, numba's, Python's and the CPU name: what numba's machine code depends on."""
    import importlib.metadata

    import llvmlite.binding

    try:
        version = importlib.metadata.version("hexapod-kin")
    except importlib.metadata.PackageNotFoundError:  # pragma: no cover - run from a checkout
        version = "dev"
    py = f"{sys.version_info[0]}{sys.version_info[1]}"
    return f"{version}-numba{numba.__version__}-py{py}-{llvmlite.binding.get_host_cpu_name()}"


def _stamp(area: str) -> Path | None:
    """The stamp file of ``area`` in numba's cache folder (``None``: numba caches nothing)."""
    folder = pose_jacobian_kernel.stats.cache_path
    return None if folder is None else Path(folder) / f"hexapod_kin-{area}-{_stamp_key()}.stamp"


def mark_compiled(area: str) -> None:
    """Record that numba's cache holds ``area``'s kernels (sealed first; stamp best effort)."""
    with _SEEN_LOCK:
        _SEEN.add(area)
    seal_compiled()
    path = _stamp(area)
    if path is not None:
        with contextlib.suppress(OSError):
            path.touch()


def _notice(area: str) -> bool:
    """Whether the first-use line was said (left open for :func:`_progress`'s dots)."""
    path = _stamp(area)
    said = _NOTICE[0] and (path is None or not path.exists())
    if said:
        seconds = COMPILE_SECONDS.get(area, 10.0)
        what = f"compiling {area} kernels for this machine, about {seconds:.0f} s"
        ahead = "(once; 'hexapod-kin precompile' does it ahead) "
        print(f"hexapod-kin: {what} {ahead}", end="", file=sys.stderr, flush=True)
    return said


@contextlib.contextmanager
def _progress(said: bool) -> Iterator[None]:
    """While numba compiles: a dot on stderr per function compiled, then the seconds taken."""
    if not said:
        yield
        return
    from numba.core import event

    dots = OnEnd(lambda ev: print(".", end="", file=sys.stderr, flush=True))
    t0 = time.perf_counter()
    try:
        with event.install_listener("numba:compile", dots):
            yield
    finally:
        print(f" {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)


@contextlib.contextmanager
def _gc_paused() -> Iterator[None]:
    """Python's cyclic garbage collector off while numba compiles, as it was after.

    A compile makes millions of short-lived objects; the collections they trigger took about a
    fifth of the compile's CPU time (measured: the ik and batch areas 22 s → 17 s, 66 MB more
    peak memory).
    """
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


def _dispatchers() -> list[Any]:
    """The package's compiled functions loaded in this process (numba dispatchers)."""
    return [
        obj
        for name, module in list(sys.modules.items())
        if name.startswith("hexapod_kin") and module is not None
        for obj in list(vars(module).values())
        if callable(getattr(obj, "recompile", None)) and hasattr(obj, "py_func")
    ]


def _unwritable(exc: BaseException) -> bool:
    """Whether ``exc`` (or what it wraps) is a failed write of numba's cache (disk full...)."""
    seen: BaseException | None = exc
    while seen is not None:
        if isinstance(seen, OSError):
            return True
        seen = seen.__cause__ or seen.__context__
    return any(f"[Errno {e}]" in str(exc) for e in (errno.ENOSPC, errno.EFBIG, errno.EACCES,
                                                   errno.EROFS, errno.EDQUOT))  # fmt: skip


def _first_call(area: str, run: Callable[[int, int], Any]) -> Any:
    """``run(0, 0)`` (no blocks: loads or compiles the kernel), never failing on the cache.

    A cache that cannot be written costs one :class:`~hexapod_kin.exceptions.CacheWarning`
    (the rest compiles in memory); one that cannot be loaded, one warning and its kernels
    reset (``Dispatcher.recompile()``). A Ctrl-C swallowed by numba's compile callback is
    raised as the ``KeyboardInterrupt`` it was.
    """
    if area in _SEEN:
        return run(0, 0)
    with _progress(_notice(area)), _gc_paused():
        try:
            return _first_run(area, run)
        finally:
            if area not in _SEEN:  # interrupted or failed: what numba wrote is sealed too
                seal_compiled()


def _first_run(area: str, run: Callable[[int, int], Any]) -> Any:
    """The body of :func:`_first_call`: ``run(0, 0)`` until the cache gives no more trouble."""
    swallowed: list[BaseException] = []
    hook = sys.unraisablehook

    def record(info: Any) -> None:
        if isinstance(info.exc_value, KeyboardInterrupt):
            swallowed.append(info.exc_value)
        hook(info)

    reloaded = False
    sys.unraisablehook = record
    try:
        for _ in range(_ATTEMPTS):
            before = {id(d): len(d.overloads) for d in _dispatchers()}
            try:
                out = run(0, 0)
                break
            except (ParameterError, ConfigurationError):
                raise
            except Exception as exc:  # noqa: BLE001 - the cache, never the answer
                if swallowed:  # Ctrl-C in numba's compile callback: not a cache problem
                    raise KeyboardInterrupt from exc
                full = _unwritable(exc)
                if not full and reloaded:  # compiled afresh and still failing: not the cache
                    raise
                if not (full and _SAID):
                    detail = " ".join(str(exc).split())[:120]
                    warnings.warn(
                        f"numba's compiled-code cache of the {area} kernels "
                        + ("cannot be written" if full else "could not be loaded")
                        + f" ({type(exc).__name__}: {detail}); compiling "
                        + ("in memory" if full else "them again"),
                        CacheWarning,
                        stacklevel=4,
                    )
                    if full:
                        _SAID.append(area)
                reloaded = reloaded or not full
                progress = any(len(d.overloads) != before.get(id(d), 0) for d in _dispatchers())
                if not full:
                    for obj in _dispatchers():
                        if not obj.overloads or len(obj.overloads) != before.get(id(obj), 0):
                            with contextlib.suppress(Exception):  # left empty: compiled on call
                                obj.recompile()
                elif not progress:
                    raise
        else:  # pragma: no cover - more kernels than attempts
            out = run(0, 0)
    finally:
        if sys.unraisablehook is record:
            sys.unraisablehook = hook
    mark_compiled(area)
    return out


# ------------------------------------------------------------------------ one configuration
@njit(cache=True, nogil=True)
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
    tip_rot: np.ndarray,
    out_r: np.ndarray,
) -> None:  # pragma: no cover - compiled
    """Tip position into ``out_p`` (3,), rotation into ``out_r`` (3, 3), LWA Jacobian ``out_j``.

    ``out_j``: (3 or 6, nq); ``scratch``: (6, m) work (nothing allocated); ``want_jac``: a
    runtime value, never a literal (one compiled copy).
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
        ones = rot[k, 0, 0] == 1.0 and rot[k, 1, 1] == 1.0 and rot[k, 2, 2] == 1.0
        upper = rot[k, 0, 1] == 0.0 and rot[k, 0, 2] == 0.0 and rot[k, 1, 2] == 0.0
        lower = rot[k, 1, 0] == 0.0 and rot[k, 2, 0] == 0.0 and rot[k, 2, 1] == 0.0
        if not (ones and upper and lower):  # a placement that turns
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
        scratch[0, k], scratch[1, k], scratch[2, k] = px, py, pz
        scratch[3, k], scratch[4, k], scratch[5, k] = wx, wy, wz
        qk = q[col[k]]
        if kind[k] == 1:
            px, py, pz = px + wx * qk, py + wy * qk, pz + wz * qk
        elif ux == 0.0 and uy == 0.0 and uz == 1.0:
            c = math.cos(qk)
            s = math.sin(qk)
            r00, r01 = c * r00 + s * r01, c * r01 - s * r00
            r10, r11 = c * r10 + s * r11, c * r11 - s * r10
            r20, r21 = c * r20 + s * r21, c * r21 - s * r20
        else:
            c = math.cos(qk)
            s = math.sin(qk)
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
    t = tip_rot  # the tip frame's rotation
    for j in range(3):
        out_r[0, j] = r00 * t[0, j] + r01 * t[1, j] + r02 * t[2, j]
        out_r[1, j] = r10 * t[0, j] + r11 * t[1, j] + r12 * t[2, j]
        out_r[2, j] = r20 * t[0, j] + r21 * t[1, j] + r22 * t[2, j]
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


# ------------------------------------------------------------------------ blocks of configurations
@njit(cache=True, nogil=True, error_model="numpy")
def fk_jac_block(
    prot: np.ndarray,
    ptr: np.ndarray,
    flags: np.ndarray,
    kind: np.ndarray,
    col: np.ndarray,
    qb: np.ndarray,
    nb: int,
    skip0: bool,
    tip_rot: bool,
    want_jac: bool,
    keep: float,
    rr: np.ndarray,
    pp: np.ndarray,
    trig: np.ndarray,
    jb: np.ndarray,
) -> None:  # pragma: no cover - compiled
    """The block FK + Jacobian core: ``nb`` configurations ``qb`` (nq, B), column-wise.

    Of an :class:`~hexapod_kin._chain.AlignedChain` (``prot`` ... ``col``): the tip rotation
    into ``rr`` (9, B, row-major; without the tip placement's own unless ``tip_rot``), its
    position into ``pp`` (3, B); with ``want_jac``, ``J[a, c]`` into row ``a·nq + c`` of ``jb``
    (6·nq, B): revolute ``[w × (keep·p − o); w]`` (``keep`` 1: LOCAL_WORLD_ALIGNED; 0: WORLD),
    prismatic ``[w; 0]``, columns off the path not written. ``skip0``: joint 0 stays at q = 0;
    ``trig``: (2, B) scratch. Flags are runtime values (one compiled copy for every caller).
    """
    nq = qb.shape[0]
    m = kind.shape[0]
    for a in range(9):  # the first placement, every configuration
        rr[a, :nb] = prot[0, a]
        if a < 3:
            pp[a, :nb] = ptr[0, a]
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
        elif not (j == 0 and skip0):
            for i in range(nb):
                trig[0, i], trig[1, i] = sincos(qb[cj, i])
            for i in range(nb):  # beyond the polynomial's range: libm, this element only
                qv = qb[cj, i]
                if abs(qv) > POLY_TRIG_MAX:
                    trig[0, i] = math.sin(qv)
                    trig[1, i] = math.cos(qv)
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
        if flags[j + 1] == 0 and (j + 1 < m or tip_rot):
            a00, a01, a02 = prot[j + 1, 0], prot[j + 1, 1], prot[j + 1, 2]
            a10, a11, a12 = prot[j + 1, 3], prot[j + 1, 4], prot[j + 1, 5]
            a20, a21, a22 = prot[j + 1, 6], prot[j + 1, 7], prot[j + 1, 8]
            for i in range(nb):
                for b in range(0, 9, 3):
                    x0, x1, x2 = rr[b, i], rr[b + 1, i], rr[b + 2, i]
                    rr[b, i] = x0 * a00 + x1 * a10 + x2 * a20
                    rr[b + 1, i] = x0 * a01 + x1 * a11 + x2 * a21
                    rr[b + 2, i] = x0 * a02 + x1 * a12 + x2 * a22
    if not want_jac:
        return
    for j in range(m):  # revolute: w × (keep·p − o)
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


@njit(cache=True, nogil=True, error_model="numpy")
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
    """Poses ``out_t`` (N, 16) and Jacobians ``out_j`` (N, 6·nq) of some blocks of ``qs``.

    Blocks ``first_block`` .. ``last_block - 1``; ``ref``: of :data:`REF_CODES`. Returns
    whether a ``q`` there is non-finite or ``|q| >= Q_MAX`` (the caller raises).
    """
    nconf = qs.shape[0]
    nq = qs.shape[1]
    bsz = block
    rr = np.empty((9, bsz))
    pp = np.empty((3, bsz))
    trig = np.empty((2, bsz))
    qb = np.empty((max(nq, 1), bsz))
    jb = np.empty((6 * max(nq, 1), bsz))
    npj = 6 * nq
    if want_jac:  # variables of joints off the path: zero columns
        jb[:, :] = 0.0
    tip_rot = want_pose or (want_jac and ref == 2)
    keep = 0.0 if ref == 1 else 1.0
    skip0 = nconf < 0  # False as a runtime value: one fk_jac_block for every caller
    ok = True
    for blk in range(first_block, last_block):
        start = blk * bsz
        nb = min(nconf, start + bsz) - start
        for c in range(nq):  # the block's q, transposed; the value check rides along
            for i in range(nb):
                qv = qs[start + i, c]
                qb[c, i] = qv
                ok &= abs(qv) < Q_MAX  # False for NaN too
        fk_jac_block(
            prot, ptr, flags, kind, col, qb, nb, skip0, tip_rot, want_jac, keep, rr, pp, trig, jb
        )
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


def threads() -> int:
    """``numba.get_num_threads()``, or ``NUMBA_NUM_THREADS`` before numba's pool started."""
    try:
        numba.threading_layer()
    except ValueError:  # not started: nothing set a count yet
        return int(numba.config.NUMBA_NUM_THREADS)
    return int(numba.get_num_threads())


def run_blocks(
    area: str, run: Callable[[int, int], Any], nblocks: int, block: int, min_per_thread: int
) -> list[Any]:
    """Run ``run(first_block, last_block)`` over ``nblocks`` blocks; return its results.

    The ``area``'s kernels are loaded first (:func:`_first_call`); then up to :func:`threads`
    plain threads (the kernels release the GIL) take chunks of blocks from a shared counter.
    """
    results = [_first_call(area, run)]
    nwork = max(1, min(threads(), nblocks * block // min_per_thread))
    if nwork == 1:
        return [*results, run(0, nblocks)]
    per = max(MIN_CHUNK_BLOCKS, -(-nblocks // (nwork * CHUNKS_PER_THREAD)))
    chunks = itertools.count()  # next() is atomic under the GIL

    def loop() -> None:
        while True:
            first = next(chunks) * per
            if first >= nblocks:
                return
            results.append(run(first, min(nblocks, first + per)))

    workers = [threading.Thread(target=loop) for _ in range(nwork - 1)]
    for t in workers:
        t.start()
    try:
        loop()
    finally:
        for t in workers:
            t.join()
    return results


def _out(out: np.ndarray | None, shape: tuple[int, ...], name: str) -> np.ndarray:
    """``out`` checked (float64, C-contiguous, writeable, ``shape``), or a new array."""
    if out is None:
        return np.empty(shape)
    good = isinstance(out, np.ndarray) and out.dtype == np.float64 and out.shape == shape
    if not (good and out.flags.c_contiguous and out.flags.writeable):
        raise ParameterError(
            f"{name}: an array of shape {np.shape(out)} and dtype "
            f"{getattr(out, 'dtype', type(out).__name__)} is not allowed; a writeable "
            f"C-contiguous float64 array of shape {shape} is required",
            parameter=name,
            allowed=f"float64 {shape}",
        )
    return out


def pose_jacobian_batch(
    chain: AlignedChain,
    qs: np.ndarray,
    *,
    pose: bool,
    jacobian: str | None,
    out_pose: np.ndarray | None = None,
    out_jacobian: np.ndarray | None = None,
    check: Callable[[], object] | None = None,
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """``(poses (N, 4, 4) or None, Jacobians (N, 6, nq) or None)`` of ``qs`` (N, nq).

    ``qs``: C-contiguous float64, checked by the kernel (finite, ``|q| < Q_MAX``; else
    ``check()`` raises the caller's error); ``jacobian``: a key of :data:`REF_CODES` or None.

    Raises:
        ParameterError: An ``out_*`` array of the wrong shape, dtype or layout.
        ConfigurationError: A non-finite or too large value in ``qs``.

    """
    n = qs.shape[0]
    nq = chain.nq
    out_t = _out(out_pose, (n, 4, 4), "out") if pose else np.empty((1, 4, 4))
    want_jac = jacobian is not None
    out_j = _out(out_jacobian, (n, 6, nq), "out") if want_jac else np.empty((1, 6, nq))
    ref = REF_CODES[jacobian] if jacobian is not None else 0
    flat_j = out_j.reshape(out_j.shape[0], 6 * nq)
    args = (*chain.packed, qs, out_t.reshape(-1, 16), flat_j, pose, ref)

    def run(first: int, last: int) -> bool:
        return bool(pose_jacobian_kernel(*args, want_jac, first, last, BLOCK))

    bad = run_blocks("batch", run, -(-n // BLOCK), BLOCK, MIN_PER_THREAD)
    if any(bad):
        if check is not None:
            check()
        raise ConfigurationError(f"Q contains non-finite values or values with |x| >= {Q_MAX:g}")
    return (out_t if pose else None), (out_j if want_jac else None)
