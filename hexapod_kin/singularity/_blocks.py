"""Block linear algebra of the singularity kernel: cyclic Jacobi eigenvalues and Laplace minors.

Structure of arrays: every routine works on a block of ``nb`` small matrices at once (entry
``p`` of matrix ``i`` at ``g[p, i]``), so the inner loops over ``i`` vectorise. numba's disk
cache checks only the caller's file: after editing this module, touch ``_kernel.py`` too.
"""

from __future__ import annotations

import math

import numpy as np

from .._kernels import njit

__all__ = ["JACOBI_TOL", "eig_block", "minor_big", "minor_block"]

#: Jacobi sweeps stop when every off-diagonal sum of a block is below this × its trace.
JACOBI_TOL = 1e-15
JACOBI_MAX_SWEEPS = 12
#: Sweeps of m ≥ 5 matrices before the first convergence test.
JACOBI_MIN_SWEEPS_BIG = 4


@njit(cache=True, nogil=True, error_model="numpy")
def _rot_cs(
    app: float, aqq: float, apq: float
) -> tuple[float, float, float, float]:  # pragma: no cover - compiled
    """Jacobi rotation zeroing ``a_pq``: new ``(a_pp, a_qq)`` and ``(c, s)``.

    Golub & Van Loan's ``t = sign(τ) a_pq / (|τ| + ρ)``, ``ρ = hypot(τ, a_pq)``, written with
    ``D = τ + sign(τ) ρ``: ``c = |D| / Q``, ``s = sign(D) a_pq / Q``, ``Q = sqrt(2 ρ |D|)``
    (the half-angle form ``c² = (1 + |τ|/ρ) / 2``, no cancellation), so one division
    ``W = 1 / (D Q)`` gives ``1/Q = D W`` and ``t = a_pq Q W``: two square roots, one division.
    The other entries transform as ``a_rp ← c a_rp − s a_rq``, ``a_rq ← s a_rp + c a_rq``.
    """
    tau = 0.5 * (aqq - app)
    rad = math.sqrt(tau * tau + apq * apq)
    den = tau + rad if tau >= 0.0 else tau - rad
    zero = den == 0.0
    den = 1.0 if zero else den
    rad = 0.5 if zero else rad
    qq = math.sqrt(2.0 * rad * abs(den))
    wi = 1.0 / (den * qq)
    inv_q = den * wi
    c = abs(den) * inv_q
    s = apq * inv_q if den > 0.0 else -apq * inv_q
    t = apq * qq * wi
    return app - t * apq, aqq + t * apq, c, s


@njit(cache=True, nogil=True, error_model="numpy")
def _jacobi_rot(
    app: float, aqq: float, apq: float, arp: float, arq: float
) -> tuple[float, float, float, float]:  # pragma: no cover - compiled
    """One symmetric Jacobi rotation zeroing ``a_pq``: new ``(a_pp, a_qq, a_rp, a_rq)``."""
    app, aqq, c, s = _rot_cs(app, aqq, apq)
    return app, aqq, c * arp - s * arq, s * arp + c * arq


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _jacobi_sweep(gb: np.ndarray, i: int) -> float:  # pragma: no cover - compiled
    """One cyclic sweep on matrix ``i`` of ``gb``; returns its off-diagonal excess (≤ 0: done)."""
    a00, a01, a02 = gb[0, i], gb[1, i], gb[2, i]
    a11, a12, a22 = gb[3, i], gb[4, i], gb[5, i]
    a00, a11, a02, a12 = _jacobi_rot(a00, a11, a01, a02, a12)
    a00, a22, a01, a12 = _jacobi_rot(a00, a22, a02, 0.0, a12)
    a11, a22, a01, a02 = _jacobi_rot(a11, a22, a12, a01, 0.0)
    gb[0, i], gb[1, i], gb[2, i] = a00, a01, a02
    gb[3, i], gb[4, i], gb[5, i] = a11, 0.0, a22
    return abs(a01) + abs(a02) - JACOBI_TOL * (a00 + a11 + a22)


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _jacobi_sweep4(gb: np.ndarray, i: int) -> None:  # pragma: no cover - compiled
    """One cyclic sweep (six rotations) on the packed symmetric 4×4 matrix ``i`` of ``gb``.

    ``gb`` rows: ``g00 g01 g02 g03 g11 g12 g13 g22 g23 g33``.
    """
    a00, a01, a02, a03 = gb[0, i], gb[1, i], gb[2, i], gb[3, i]
    a11, a12, a13 = gb[4, i], gb[5, i], gb[6, i]
    a22, a23, a33 = gb[7, i], gb[8, i], gb[9, i]
    a00, a11, c, s = _rot_cs(a00, a11, a01)  # (0, 1); r = 2, 3
    a02, a12 = c * a02 - s * a12, s * a02 + c * a12
    a03, a13 = c * a03 - s * a13, s * a03 + c * a13
    a00, a22, c, s = _rot_cs(a00, a22, a02)  # (0, 2); r = 1, 3
    a01, a12 = -s * a12, c * a12  # a01 = 0 here
    a03, a23 = c * a03 - s * a23, s * a03 + c * a23
    a00, a33, c, s = _rot_cs(a00, a33, a03)  # (0, 3); r = 1, 2
    a01, a13 = c * a01 - s * a13, s * a01 + c * a13
    a02, a23 = -s * a23, c * a23  # a02 = 0 here
    a11, a22, c, s = _rot_cs(a11, a22, a12)  # (1, 2); r = 0, 3
    a01, a02 = c * a01 - s * a02, s * a01 + c * a02
    a13, a23 = c * a13 - s * a23, s * a13 + c * a23
    a11, a33, c, s = _rot_cs(a11, a33, a13)  # (1, 3); r = 0, 2
    a01, a03 = c * a01, s * a01  # a03 = 0 here
    a12, a23 = -s * a23, c * a23  # a12 = 0 here
    a22, a33, c, s = _rot_cs(a22, a33, a23)  # (2, 3); r = 0, 1
    a02, a03 = c * a02 - s * a03, s * a02 + c * a03
    a12, a13 = c * a12, s * a12  # a13 = 0 here
    gb[0, i], gb[1, i], gb[2, i], gb[3, i] = a00, a01, a02, a03
    gb[4, i], gb[5, i], gb[6, i] = a11, a12, a13
    gb[7, i], gb[8, i], gb[9, i] = a22, 0.0, a33


@njit(cache=True, nogil=True, error_model="numpy")
def _jacobi_open(gb: np.ndarray, i: int, m: int) -> bool:  # pragma: no cover - compiled
    """Whether matrix ``i`` (packed m×m, diagonal ``d``, off-diagonal ``E``) needs sweeps.

    With ``o = Σ_{a<b} |e_ab|`` (≥ every off-diagonal row sum, ≥ ``‖E‖₂``) and ``g`` the
    smallest gap ``|d_a − d_b|``, the diagonal holds the eigenvalues to ``tol = JACOBI_TOL ·
    trace`` when ``o ≤ tol`` (Weyl), or when ``g > 3 o`` and ``2 o² / (g − o) ≤ tol`` (the
    quadratic bound for isolated eigenvalues: scale row / column ``a`` of ``D + E`` by
    ``1/α`` / ``α``; Gershgorin disc ``a``, radius ``≤ o/α``, is disjoint from the others,
    radius ``≤ o + α o``, for ``α = (g − o) / (2 o)`` when ``(g − o)² > 4 o²``, and holds
    exactly one eigenvalue, within ``2 o² / (g − o)`` of ``d_a``).
    """
    if m == 3:
        d0, d1, d2 = gb[0, i], gb[3, i], gb[5, i]
        off = abs(gb[1, i]) + abs(gb[2, i]) + abs(gb[4, i])
        tr = d0 + d1 + d2
        gap = min(abs(d0 - d1), min(abs(d0 - d2), abs(d1 - d2)))
    elif m > 4:
        off = 0.0
        tr = 0.0
        gap = np.inf
        for a in range(m):
            da = gb[a * m - (a * (a - 1)) // 2, i]
            tr += da
            for b in range(a + 1, m):
                off += abs(gb[a * m - (a * (a - 1)) // 2 + (b - a), i])
                gap = min(gap, abs(da - gb[b * m - (b * (b - 1)) // 2, i]))
    else:
        d0, d1, d2, d3 = gb[0, i], gb[4, i], gb[7, i], gb[9, i]
        off = abs(gb[1, i]) + abs(gb[2, i]) + abs(gb[3, i])
        off += abs(gb[5, i]) + abs(gb[6, i]) + abs(gb[8, i])
        tr = d0 + d1 + d2 + d3
        gap = min(min(abs(d0 - d1), abs(d0 - d2)), min(abs(d0 - d3), abs(d1 - d2)))
        gap = min(gap, min(abs(d1 - d3), abs(d2 - d3)))
    tol = JACOBI_TOL * tr
    weyl = off <= tol
    quad = (gap > 3.0 * off) & (2.0 * off * off <= tol * (gap - off))
    return not (weyl | quad)  # branch-free: the block loops that count these vectorise


@njit(cache=True, nogil=True, error_model="numpy")
def _sweep_many(g: np.ndarray, count: int, m: int) -> None:  # pragma: no cover - compiled
    """One sweep on matrices ``0 .. count - 1`` of ``g`` (m = 3 or 4; the one inlined copy)."""
    if m == 3:
        for i in range(count):
            _jacobi_sweep(g, i)
    else:
        for i in range(count):
            _jacobi_sweep4(g, i)


@njit(cache=True, nogil=True, error_model="numpy")
def _pack_table(m: int) -> np.ndarray:  # pragma: no cover - compiled
    """``pack[a, b]``: row of ``G[a, b]`` in the packed upper triangle (row-major) of m×m."""
    pack = np.empty((m, m), dtype=np.int64)
    p = 0
    for a in range(m):
        for b in range(a, m):
            pack[a, b] = p
            pack[b, a] = p
            p += 1
    return pack


@njit(cache=True, nogil=True, error_model="numpy")
def _sweep_gen(
    gb: np.ndarray, nb: int, m: int, pack: np.ndarray, cs: np.ndarray
) -> None:  # pragma: no cover - compiled
    """One cyclic Jacobi sweep over every matrix of the block, any m, pair by pair."""
    for p in range(m - 1):
        for q in range(p + 1, m):
            ppp, pqq, ppq = pack[p, p], pack[q, q], pack[p, q]
            for i in range(nb):
                app, aqq, c, sn = _rot_cs(gb[ppp, i], gb[pqq, i], gb[ppq, i])
                gb[ppp, i] = app
                gb[pqq, i] = aqq
                gb[ppq, i] = 0.0
                cs[0, i] = c
                cs[1, i] = sn
            for r in range(m):
                if r == p or r == q:
                    continue
                prp, prq = pack[r, p], pack[r, q]
                for i in range(nb):
                    arp, arq = gb[prp, i], gb[prq, i]
                    c, sn = cs[0, i], cs[1, i]
                    gb[prp, i] = c * arp - sn * arq
                    gb[prq, i] = sn * arp + c * arq


@njit(cache=True, nogil=True, error_model="numpy")
def eig_block(
    gb: np.ndarray, nb: int, m: int, wb: np.ndarray, idx: np.ndarray
) -> None:  # pragma: no cover - compiled
    """Diagonalise ``nb`` packed symmetric m×m matrices in place by cyclic Jacobi.

    m = 3 and 4 have unrolled sweeps; m = 5, 6 sweep pair by pair (:func:`_sweep_gen`),
    ``JACOBI_MIN_SWEEPS_BIG`` times before the first test. ``gb`` is (m(m+1)/2, B), rows the
    packed upper triangle; ``wb`` (same shape) and ``idx`` (B,) are scratch. The matrices
    still open (:func:`_jacobi_open`) are gathered into ``wb`` and swept there until each
    converges: every matrix gets the sweeps its own test asks for, whatever its neighbours.
    """
    npk = gb.shape[0]
    sweeps = 0
    big = m > 4
    pack = _pack_table(m if big else 1)
    cs = np.empty((2, nb if big else 1))
    if big:  # arms: ~4 of the ~5 sweeps a 6×6 needs, before any test
        for _ in range(JACOBI_MIN_SWEEPS_BIG):
            _sweep_gen(gb, nb, m, pack, cs)
        sweeps = JACOBI_MIN_SWEEPS_BIG
    else:
        _sweep_many(gb, nb, m)
        sweeps = 1
    n_open = np.int64(0)  # not the literal 0: numba would compile the sweeps once more for it
    for i in range(nb):
        if _jacobi_open(gb, i, m):
            idx[n_open] = i
            n_open += 1
    for jj in range(n_open):
        i = idx[jj]
        for p in range(npk):
            wb[p, jj] = gb[p, i]
    while sweeps < JACOBI_MAX_SWEEPS:
        sweeps += 1
        if n_open == 0:
            return
        if big:
            _sweep_gen(wb, n_open, m, pack, cs)
        else:
            _sweep_many(wb, n_open, m)
        kept = 0
        for jj in range(n_open):
            i = idx[jj]
            if _jacobi_open(wb, jj, m):
                if kept != jj:
                    for p in range(npk):
                        wb[p, kept] = wb[p, jj]
                    idx[kept] = i
                kept += 1
            else:
                for p in range(npk):
                    gb[p, i] = wb[p, jj]
        n_open = kept
    for jj in range(n_open):  # not converged within the sweep limit: keep the last iterate
        i = idx[jj]
        for p in range(npk):
            gb[p, i] = wb[p, jj]


@njit(cache=True, nogil=True, error_model="numpy")
def minor_block(
    jb: np.ndarray, r: np.ndarray, c: np.ndarray, m: int, nb: int, dst: np.ndarray
) -> None:  # pragma: no cover - compiled
    """``dst[i] = det(jb[r][:, c][:, :, i])`` for the m×m (m ≤ 4) minor on rows ``r``, cols ``c``.

    Explicit formulas (cofactors; for m = 4 the Laplace expansion by the 2×2 minors of the
    first two and the last two rows), vectorised over the block.
    """
    if m == 1:
        r0, c0 = r[0], c[0]
        for i in range(nb):
            dst[i] = jb[r0, c0, i]
    elif m == 2:
        r0, r1, c0, c1 = r[0], r[1], c[0], c[1]
        for i in range(nb):
            dst[i] = jb[r0, c0, i] * jb[r1, c1, i] - jb[r0, c1, i] * jb[r1, c0, i]
    elif m == 3:
        r0, r1, r2, c0, c1, c2 = r[0], r[1], r[2], c[0], c[1], c[2]
        for i in range(nb):
            a00, a01, a02 = jb[r0, c0, i], jb[r0, c1, i], jb[r0, c2, i]
            a10, a11, a12 = jb[r1, c0, i], jb[r1, c1, i], jb[r1, c2, i]
            a20, a21, a22 = jb[r2, c0, i], jb[r2, c1, i], jb[r2, c2, i]
            dst[i] = (
                a00 * (a11 * a22 - a12 * a21)
                - a01 * (a10 * a22 - a12 * a20)
                + a02 * (a10 * a21 - a11 * a20)
            )
    else:
        r0, r1, r2, r3 = r[0], r[1], r[2], r[3]
        c0, c1, c2, c3 = c[0], c[1], c[2], c[3]
        for i in range(nb):
            a0, a1, a2, a3 = jb[r0, c0, i], jb[r0, c1, i], jb[r0, c2, i], jb[r0, c3, i]
            b0, b1, b2, b3 = jb[r1, c0, i], jb[r1, c1, i], jb[r1, c2, i], jb[r1, c3, i]
            e0, e1, e2, e3 = jb[r2, c0, i], jb[r2, c1, i], jb[r2, c2, i], jb[r2, c3, i]
            f0, f1, f2, f3 = jb[r3, c0, i], jb[r3, c1, i], jb[r3, c2, i], jb[r3, c3, i]
            s01, s02, s03 = a0 * b1 - a1 * b0, a0 * b2 - a2 * b0, a0 * b3 - a3 * b0
            s12, s13, s23 = a1 * b2 - a2 * b1, a1 * b3 - a3 * b1, a2 * b3 - a3 * b2
            t01, t02, t03 = e0 * f1 - e1 * f0, e0 * f2 - e2 * f0, e0 * f3 - e3 * f0
            t12, t13, t23 = e1 * f2 - e2 * f1, e1 * f3 - e3 * f1, e2 * f3 - e3 * f2
            dst[i] = s01 * t23 - s02 * t13 + s03 * t12 + s12 * t03 - s13 * t02 + s23 * t01


@njit(cache=True, nogil=True, error_model="numpy")
def minor_big(
    jb: np.ndarray, r: np.ndarray, c: np.ndarray, m: int, nb: int, dst: np.ndarray, tmp: np.ndarray,
) -> None:  # pragma: no cover - compiled  # fmt: skip
    """:func:`minor_block` for any m ≤ 8: Laplace expansion along the first ``h = m // 2`` rows.

    ``det = Σ_S ε(S) det(J[top, S]) det(J[bottom, S̄])`` over the h-subsets ``S`` of the
    columns (20 pairs of 3×3 minors for m = 6), each from :func:`minor_block`; ``tmp`` is
    (2, B) scratch.
    """
    if m <= 4:
        minor_block(jb, r, c, m, nb, dst)
        return
    h = m // 2
    rt = r[:h].copy()
    rb = r[h:m].copy()
    cs = np.empty(h, dtype=np.int64)
    cc = np.empty(m - h, dtype=np.int64)
    for i in range(nb):
        dst[i] = 0.0
    base = h * (h - 1) // 2
    for mask in range(1 << m):
        cnt = 0
        tot = 0
        for b in range(m):
            if (mask >> b) & 1:
                cnt += 1
        if cnt != h:
            continue
        a1 = 0
        a2 = 0
        for b in range(m):
            if (mask >> b) & 1:
                cs[a1] = c[b]
                tot += b
                a1 += 1
            else:
                cc[a2] = c[b]
                a2 += 1
        sign = 1.0 if (tot + base) % 2 == 0 else -1.0
        minor_block(jb, rt, cs, h, nb, tmp[0])
        minor_block(jb, rb, cc, m - h, nb, tmp[1])
        for i in range(nb):
            dst[i] += sign * tmp[0, i] * tmp[1, i]
