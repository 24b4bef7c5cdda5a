"""The Python side of the singularity kernel: block plans, output buffers, the threads.

:func:`compute` runs :func:`~._kernel.measures_kernel`; what it derives from the model (the
z-aligned chain, Gram plans) is kept in ``Model.cached``.
"""

from __future__ import annotations

import math
import sys
import threading
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from .._kernels import AlignedChain, aligned_chain, run_blocks
from .._pose import rodrigues
from ._kernel import measures_kernel

__all__ = ["GramPlan", "BLOCK", "aligned", "block_plan", "gram_plan", "first_joint_invariant",
           "output_arrays", "compute"]  # fmt: skip


#: Configurations per structure-of-arrays block of :func:`measures_kernel`.
BLOCK = 256
#: Fewest configurations per thread (below this, one thread: starting threads costs more).
MIN_PER_THREAD = 20_000
#: Largest number of maximal minors (Cauchy–Binet terms) the block path accepts.
_MAX_MINORS = 70


@lru_cache(maxsize=64)
def block_plan(k: int, n: int) -> tuple[bool, np.ndarray, np.ndarray, np.ndarray]:
    """Block-path tables for k×n Jacobians: ``(use_block, pack, rsub, csub)``.

    ``pack[a, b]``: row of ``G[a, b]`` in the packed upper triangle (m×m, ``m = min(k, n)``);
    ``rsub[s]`` / ``csub[s]``: rows / columns of the s-th maximal minor of ``J`` (the one
    square minor when ``k == n``; all ``C(max(k, n), m)`` of them otherwise, for Cauchy–Binet
    ``det G = Σ_s minor_s²``). ``use_block`` is false when ``m > 6`` or there are more than
    ``_MAX_MINORS`` minors (:func:`~.measure.measures_batch` then uses Pinocchio and numpy).
    """
    from itertools import combinations

    m = min(k, n)
    pack = np.zeros((max(m, 1), max(m, 1)), dtype=np.int64)
    p = 0
    for a in range(m):
        for b in range(a, m):
            pack[a, b] = pack[b, a] = p
            p += 1
    full = tuple(range(m))
    subs = list(combinations(range(max(k, n)), m)) if m else []
    use = 1 <= m <= 6 and len(subs) <= _MAX_MINORS
    if not use:
        subs = subs[:1] or [full]
    if k <= n:
        rsub, csub = [full] * len(subs), subs
    else:
        rsub, csub = subs, [full] * len(subs)
    as_arr = lambda x: np.array(x, dtype=np.int64).reshape(len(subs), max(m, 1))  # noqa: E731
    return use, pack, as_arr(rsub), as_arr(csub)


@dataclass(frozen=True)
class GramPlan:
    """How the kernel's ``_reduce_block`` treats one chain and row selection (:func:`gram_plan`).

    ``use_block``: the block path applies (``m = min(k, n) ≤ 6``, few minors); ``gram_t``:
    ``G = Jᵀ J`` (else ``J Jᵀ``); ``perm`` (m,): indices of ``G`` by diagonal block; ``csize``
    (c,): their sizes (one of size m: no split); ``drop``: packed positions of the entries
    between blocks (zero at random samples); ``arrays``: the kernel's tuple ``(pack, rsub,
    csub, gram_t, perm, csize, drop)``.
    """

    use_block: bool
    gram_t: bool
    perm: np.ndarray
    csize: np.ndarray
    drop: np.ndarray
    arrays: tuple[Any, ...]


def _components(zero: np.ndarray) -> list[list[int]]:
    """Connected components of the graph with an edge where ``zero[a, b]`` is false."""
    m = zero.shape[0]
    seen, comps = [False] * m, []
    for a in range(m):
        if seen[a]:
            continue
        stack, comp = [a], []
        seen[a] = True
        while stack:
            u = stack.pop()
            comp.append(u)
            for v in range(m):
                if not seen[v] and not zero[u, v]:
                    seen[v] = True
                    stack.append(v)
        comps.append(sorted(comp))
    return comps


def gram_plan(model: Any, sel: tuple[int, ...], skip0: bool) -> GramPlan:
    """Plan the block reduction for ``model``'s rows ``sel`` (kept in ``model.cached``).

    ``G`` is ``J Jᵀ`` (k < n), ``Jᵀ J`` (k > n), or whichever splits into smaller diagonal blocks:
    entries below ``1e-14 · max |G|`` at 16 random configurations are structural zeros (the
    kernel re-checks them per configuration).
    """
    key = f"singularity.gram_plan.{sel}.{skip0}"
    return model.cached(key, lambda: _build_gram_plan(model, sel, skip0))


def _build_gram_plan(model: Any, sel: tuple[int, ...], skip0: bool) -> GramPlan:
    arrays = model.arrays
    k, n = len(sel), arrays.nq
    use_block, pack, rsub, csub = block_plan(k, n)
    m = min(k, n)
    best: tuple[int, int, bool, list[list[int]], np.ndarray] | None = None
    if use_block and m >= 2:
        q = model.random_q(16, seed=2024)
        if skip0:
            q[:, arrays.col[0]] = 0.0
        jac = np.array([model.jacobian(qi, "local_world_aligned") for qi in q])[:, list(sel), :]
        for gram_t in (False, True) if k == n else (k > n,):
            g = np.swapaxes(jac, 1, 2) @ jac if gram_t else jac @ np.swapaxes(jac, 1, 2)
            zero = (np.abs(g) <= 1e-14 * max(float(np.abs(g).max()), 1e-300)).all(axis=0)
            comps = _components(zero)
            score = (max(len(c) for c in comps), -len(comps))
            if best is None or score < best[:2]:
                best = (*score, gram_t, comps, zero)
    gram_t, comps = (k > n, [list(range(m))]) if best is None else (best[2], best[3])
    perm = np.array([a for c in comps for a in c] or [0], dtype=np.int64)
    csize = np.array([len(c) for c in comps] or [1], dtype=np.int64)
    where = {a: ci for ci, c in enumerate(comps) for a in c}
    between = [int(pack[a, b]) for a in range(m) for b in range(a + 1, m) if where[a] != where[b]]
    drop = np.array(sorted(between), dtype=np.int64)
    if len(comps) == 1:
        perm = np.arange(max(m, 1), dtype=np.int64)
    arrays = (pack, rsub, csub, gram_t, perm, csize, drop)
    return GramPlan(use_block, gram_t, perm, csize, drop, arrays)


def first_joint_invariant(al: AlignedChain, sel: tuple[int, ...]) -> bool:
    """Whether the measures of the ``sel`` rows of ``J`` do not depend on the first joint.

    Turning revolute joint 0 by ``θ`` gives ``J(q) = B J(q0 = 0)``, ``B = blockdiag(R, R)``; the
    measures are unchanged when ``Q = S B Sᵀ`` (``S`` the row selection) is orthogonal with
    ``det Q = +1``. Checked at two generic angles.
    """
    if al.kind.shape[0] == 0 or al.kind[0] != 0 or np.count_nonzero(al.col == al.col[0]) != 1:
        return False
    u = al.prot[0].reshape(3, 3)[:, 2]
    u, rows = u / np.linalg.norm(u), np.eye(6)[list(sel)]
    for angle in (0.7, 2.3):
        rot = rodrigues(u, math.sin(angle), math.cos(angle))
        b = np.zeros((6, 6))
        b[:3, :3] = b[3:, 3:] = rot
        qmat = rows @ b @ rows.T
        if np.abs(qmat.T @ qmat - np.eye(len(sel))).max() > 1e-12 or np.linalg.det(qmat) <= 0:
            return False
    return True


_OUT_POOL: list[np.ndarray] = []
_OUT_LOCK = threading.Lock()
_OUT_POOL_MAX_BYTES = 128 * 2**20


def output_arrays(n: int) -> tuple[np.ndarray, ...]:
    """Four (n,) float64 arrays for :func:`measures_batch`: the rows of one (4, n) buffer.

    The last buffer (up to ``_OUT_POOL_MAX_BYTES``) is reused once nothing references it.
    """
    with _OUT_LOCK:
        if _OUT_POOL:
            buf = _OUT_POOL[0]
            # references: the pool list, ``buf`` and getrefcount's argument
            if buf.shape[1] == n and sys.getrefcount(buf) == 3:
                return tuple(buf[i] for i in range(4))
            del buf
        buf = np.empty((4, n))
        if buf.nbytes <= _OUT_POOL_MAX_BYTES:
            _OUT_POOL[:] = [buf]
        return tuple(buf[i] for i in range(4))


def aligned(model: Any) -> AlignedChain:
    """The model's chain with z joint axes, kept in ``model.cached`` (shared with the batch)."""
    return model.cached("batch.aligned", lambda: aligned_chain(model.arrays))


def compute(
    model: Any, q: np.ndarray, sel: np.ndarray, out: tuple[np.ndarray, ...]
) -> tuple[np.ndarray, ...]:
    """Fill ``out`` = (det, manipulability, condition, sigma_min), four (N,) float64 arrays.

    ``q``: (N, nq) float64 C-contiguous configurations, checked by the caller; ``sel``: (k,)
    int64 indices of the rows ``[vx vy vz wx wy wz]`` of ``J``.
    """
    n, al = q.shape[0], aligned(model)
    key = tuple(int(r) for r in sel)
    skip0 = first_joint_invariant(al, key)
    plan, m = gram_plan(model, key, skip0), min(len(key), q.shape[1])
    use_jacobi = not (m <= 3 and int(plan.csize.max()) <= 2)
    args = (*al.packed, q, sel, plan.arrays, use_jacobi)

    def run(first: int, last: int) -> None:
        tmp = np.empty((2, BLOCK if m > 4 else 1))  # this thread's scratch (m = 5, 6)
        measures_kernel(*args, tmp, skip0, first, last, BLOCK, *out)

    run_blocks("singularity", run, -(-n // BLOCK), BLOCK, MIN_PER_THREAD)
    return out
