"""The compiled layer of the singularity scans: FK + Jacobian rows + measures, in blocks.

Configurations go through the block FK + Jacobian core (:func:`hexapod_kin._kernels.fk_jac_block`)
in structure-of-arrays blocks, never storing the Jacobians. For ``m = min(k, n) ≤ 6``
(:func:`_reduce_block`) the Gram matrix ``G`` (``J Jᵀ`` or ``Jᵀ J``, split into diagonal blocks
where the chain makes it block diagonal) gives the largest eigenvalues (closed forms up to size
2, cyclic Jacobi for 3 to 6) and ``det G`` comes from ``J``'s own minors (``det(J)²`` or
Cauchy–Binet), so ``σm = sqrt(det G / Π_{i<m} λi)`` keeps full accuracy near a singularity.
Shapes with more than ``_plan._MAX_MINORS`` maximal minors (chains of 9 joints and more) are
not the kernel's: :func:`~.measure.measures_batch` serves them with Pinocchio and numpy. Every
decision is taken per configuration, so a value does not depend on its neighbours.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._kernels import POLY_TRIG_MAX, eig3_sym, fk_jac_block, njit, sincos
from ._blocks import JACOBI_TOL, eig_block, minor_big, minor_block

__all__ = ["JACOBI_TOL", "POLY_TRIG_MAX", "eig_block", "measures_kernel", "minor_big",
           "minor_block", "sincos"]  # fmt: skip


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _eigenvalues(
    gb: np.ndarray, hb: np.ndarray, wb: np.ndarray, ev: np.ndarray, idx: np.ndarray, nb: int,
    mm: int, pack: np.ndarray, perm: np.ndarray, csize: np.ndarray, split: bool, use_jacobi: bool,
) -> None:  # pragma: no cover - compiled  # fmt: skip
    """Eigenvalues of the packed Gram matrices ``gb`` into ``ev[0:mm]`` (any order).

    ``split``: each diagonal block of the plan (``perm``, ``csize``) apart, else ``G`` whole.
    """
    ncomp = csize.shape[0] if split else 1
    off = 0
    for comp in range(ncomp):
        s = csize[comp] if split else mm
        if s == 1:
            p = pack[perm[off], perm[off]] if split else 0
            for i in range(nb):
                ev[off, i] = gb[p, i]
        elif s == 2:
            a, b = (perm[off], perm[off + 1]) if split else (0, 1)
            paa, pab, pbb = pack[a, a], pack[a, b], pack[b, b]
            for i in range(nb):
                ga, gab, gbb = gb[paa, i], gb[pab, i], gb[pbb, i]
                half = 0.5 * (ga - gbb)
                lmax = 0.5 * (ga + gbb) + math.sqrt(half * half + gab * gab)
                ev[off, i] = lmax
                lo = (ga * gbb - gab * gab) / lmax if lmax > 0.0 else 0.0
                ev[off + 1, i] = max(lo, 0.0)
        else:
            for u in range(s):
                for v in range(u, s):
                    a = perm[off + u] if split else u
                    b = perm[off + v] if split else v
                    p = pack[a, b]
                    q = u * s - (u * (u - 1)) // 2 + (v - u)
                    for i in range(nb):
                        hb[q, i] = gb[p, i]
            if not use_jacobi:  # plans whose blocks are all <= 2 (legs)
                for i in range(nb):  # only if a split fails: the 3×3 closed form
                    l1, l2, l3 = eig3_sym(
                        hb[0, i], hb[3, i], hb[5, i], hb[1, i], hb[2, i], hb[4, i]
                    )
                    hb[0, i], hb[3, i], hb[5, i] = l1, l2, l3
            else:
                eig_block(hb[: s * (s + 1) // 2], nb, s, wb, idx)
            for u in range(s):
                q = u * s - (u * (u - 1)) // 2
                for i in range(nb):
                    ev[off + u, i] = hb[q, i]
        off += s


@njit(cache=True, nogil=True, error_model="numpy")
def _reduce_block(
    jb: np.ndarray, nb: int, plan: tuple[Any, ...], gb: np.ndarray, hb: np.ndarray, wb: np.ndarray,
    ev: np.ndarray, ev2: np.ndarray, flag: np.ndarray, idx: np.ndarray, dg: np.ndarray,
    mnr: np.ndarray, tmp: np.ndarray, use_jacobi: bool, start: int, out_det: np.ndarray,
    out_manip: np.ndarray, out_cond: np.ndarray, out_smin: np.ndarray,
) -> None:  # pragma: no cover - compiled  # fmt: skip
    """Measures of a block of ``nb`` k×n Jacobians ``jb`` (k, n, B), ``m = min(k, n) ≤ 6``.

    ``plan`` is :attr:`._plan.GramPlan.arrays`. Where the plan's ``drop`` entries of ``G``
    (packed upper triangle) are below ``JACOBI_TOL · trace`` (per configuration; Weyl bounds
    the effect) each diagonal block is solved alone, else ``G`` whole. ``det G`` is ``det(J)²``
    or the sum of the squared maximal minors (rows ``rsub[s]``, columns ``csub[s]``), so that
    ``λmin = det G / Π_{i<m} λi`` keeps relative accuracy. ``ev2`` and ``flag`` are scratch.
    """
    pack, rsub, csub, gram_t, perm, csize, drop = plan
    k, n = jb.shape[0], jb.shape[1]
    mm = k if k <= n else n
    square = k == n
    for a in range(mm):
        for b in range(a, mm):
            p = pack[a, b]
            for i in range(nb):
                gb[p, i] = 0.0
            if gram_t:
                for c in range(k):
                    for i in range(nb):
                        gb[p, i] += jb[c, a, i] * jb[c, b, i]
            else:
                for c in range(n):
                    for i in range(nb):
                        gb[p, i] += jb[a, c, i] * jb[b, c, i]
    if square:
        if mm <= 4:  # no Laplace expansion
            minor_block(jb, rsub[0], csub[0], mm, nb, mnr)
        else:
            minor_big(jb, rsub[0], csub[0], mm, nb, mnr, tmp)
        for i in range(nb):
            out_det[start + i] = mnr[i]
            dg[i] = mnr[i] * mnr[i]
    else:
        for i in range(nb):
            dg[i] = 0.0
            out_det[start + i] = np.nan
        for s in range(rsub.shape[0]):
            if mm <= 4:
                minor_block(jb, rsub[s], csub[s], mm, nb, mnr)
            else:
                minor_big(jb, rsub[s], csub[s], mm, nb, mnr, tmp)
            for i in range(nb):
                dg[i] += mnr[i] * mnr[i]
    # the structural zeros really negligible, configuration by configuration? (flag 1: no)
    split = drop.shape[0] > 0
    nbad = 0
    if split:
        for i in range(nb):
            mnr[i] = 0.0
        for a in range(mm):
            p = pack[a, a]
            for i in range(nb):
                mnr[i] += gb[p, i]
        for d in range(drop.shape[0]):
            p = drop[d]
            for i in range(nb):
                mnr[i] -= abs(gb[p, i]) / JACOBI_TOL
        for i in range(nb):
            flag[i] = mnr[i] < 0.0
            nbad += flag[i]
    apart = split and nbad < nb  # each diagonal block apart, then G whole where that fails
    last = 1 if not split or nbad > 0 else 0
    for whole in range(0 if apart else 1, last + 1):  # one inlined copy: compiles once
        dest = ev2 if whole and apart else ev
        _eigenvalues(gb, hb, wb, dest, idx, nb, mm, pack, perm, csize, whole == 0, use_jacobi)
        if whole and apart:
            for i in range(nb):
                if flag[i]:
                    for a in range(mm):
                        ev[a, i] = ev2[a, i]
    # λmax into mnr, the product of the m − 1 largest into hb[0] (one loop per m: SIMD)
    if mm == 1:
        for i in range(nb):
            mnr[i] = ev[0, i]
            hb[0, i] = 1.0
    elif mm == 2:
        for i in range(nb):
            lmax = max(ev[0, i], ev[1, i])
            mnr[i] = lmax
            hb[0, i] = lmax
    elif mm == 3:
        for i in range(nb):
            e0, e1, e2 = ev[0, i], ev[1, i], ev[2, i]
            lmax = max(e0, max(e1, e2))
            mnr[i] = lmax
            hb[0, i] = lmax * max(min(e0, e1), min(max(e0, e1), e2))
    elif mm >= 5:  # m = 5, 6
        for i in range(nb):
            lo = 0
            hi = 0
            for a in range(1, mm):
                if ev[a, i] < ev[lo, i]:
                    lo = a
                if ev[a, i] > ev[hi, i]:
                    hi = a
            prod = 1.0
            for a in range(mm):
                if a != lo:
                    prod *= ev[a, i]
            mnr[i] = ev[hi, i]
            hb[0, i] = prod  # the m − 1 largest
    else:
        for i in range(nb):
            e0, e1, e2, e3 = ev[0, i], ev[1, i], ev[2, i], ev[3, i]
            lo1, hi1 = min(e0, e1), max(e0, e1)
            lo2, hi2 = min(e2, e3), max(e2, e3)
            mnr[i] = max(hi1, hi2)
            hb[0, i] = hi1 * hi2 * max(lo1, lo2)  # the three largest
    for i in range(nb):
        prod = hb[0, i]
        d = dg[i]
        lmin = d / prod if prod > 0.0 else 0.0
        smin = math.sqrt(max(lmin, 0.0))
        out_smin[start + i] = smin
        out_cond[start + i] = math.sqrt(max(mnr[i], 0.0)) / smin if smin > 0.0 else np.inf
    if square:
        for i in range(nb):
            out_manip[start + i] = abs(out_det[start + i])
    else:
        for i in range(nb):
            out_manip[start + i] = math.sqrt(dg[i])


@njit(cache=True, nogil=True, error_model="numpy")
def measures_kernel(
    prot: np.ndarray, ptr: np.ndarray, flags: np.ndarray, kind: np.ndarray, col: np.ndarray,
    qs: np.ndarray, sel: np.ndarray, plan: tuple[Any, ...], use_jacobi: bool, tmp: np.ndarray,
    skip0: bool, first_block: int, last_block: int, block: int, out_det: np.ndarray,
    out_manip: np.ndarray, out_cond: np.ndarray, out_smin: np.ndarray,
) -> None:  # pragma: no cover - compiled  # fmt: skip
    """FK + selected-row Jacobian + measures for blocks ``first_block`` to ``last_block - 1``.

    The chain is an :class:`~hexapod_kin._chain.AlignedChain` (``prot`` … ``col``); ``qs``
    (N, nq) is cut into blocks of ``block`` configurations. ``skip0``: joint 0 is left at 0
    (:func:`._plan.first_joint_invariant`). ``use_jacobi`` False: every diagonal
    block has size ≤ 2 and m ≤ 3, so a failed split gets the 3×3 closed form. ``tmp``: this
    thread's (2, B) scratch of :func:`minor_big`. The flags are runtime values: one compiled
    signature serves every chain.
    """
    nconf, nq, k, bsz = qs.shape[0], qs.shape[1], sel.shape[0], block
    mm = k if k <= nq else nq
    npk = mm * (mm + 1) // 2
    rr, pp, trig = np.empty((9, bsz)), np.empty((3, bsz)), np.empty((2, bsz))
    qb = np.empty((max(nq, 1), bsz))
    jfull = np.zeros((6 * max(nq, 1), bsz))  # off-path columns stay zero
    jb = np.empty((k, nq, bsz))
    gb, hb, wb = np.empty((npk, bsz)), np.empty((npk, bsz)), np.empty((npk, bsz))
    ev, ev2 = np.empty((mm, bsz)), np.empty((mm, bsz))
    flag, open_idx = np.zeros(bsz, dtype=np.int64), np.empty(bsz, dtype=np.int64)
    dg, mnr = np.empty(bsz), np.empty(bsz)
    for blk in range(first_block, last_block):
        start = blk * bsz
        nb = min(nconf, start + bsz) - start
        for i in range(nb):  # the block's q, transposed: the per-joint loops read rows
            for c in range(nq):
                qb[c, i] = qs[start + i, c]
        fk_jac_block(
            prot, ptr, flags, kind, col, qb, nb, skip0, nb < 0, nb > 0, 1.0, rr, pp, trig, jfull
        )
        for a in range(k):  # the selected rows
            r = sel[a] * nq
            for b in range(nq):
                for i in range(nb):
                    jb[a, b, i] = jfull[r + b, i]
        _reduce_block(
            jb, nb, plan, gb, hb, wb, ev, ev2, flag, open_idx, dg, mnr, tmp, use_jacobi, start,
            out_det, out_manip, out_cond, out_smin,
        )  # fmt: skip
