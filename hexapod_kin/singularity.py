"""Singularity measures, fast scans of joint space, singular families, workspace.

Measures of a Jacobian ``J`` (k selected rows of the ``local_world_aligned`` tip Jacobian
``[v; ω]`` in the base frame, n joints; ``m = min(k, n)`` singular values ``σ1 ≥ … ≥ σm``):

* ``det`` — ``det J`` when ``k == n``, else NaN;
* ``manipulability`` — Yoshikawa's ``sqrt(det(J Jᵀ))`` (``sqrt(det(Jᵀ J))`` when ``k > n``),
  the product of the singular values (``|det J|`` when square);
* ``condition`` — ``σ1 / σm`` (``inf`` at a singularity);
* ``sigma_min`` — ``σm``, in [m] for position rows of revolute joints.

A configuration is flagged ``singular`` when ``sigma_min < threshold`` (default
``rtol × reach``, with ``reach`` the sum of the chain's link offsets).

Rows are chosen by name (``rows=("x", "y", "z", "wz")``); by default the position rows, plus
the angular rows that are not identically zero when that makes a square ``J`` — so the SCARA
gets ``x, y, z, wz`` and the 3-DOF leg ``x, y, z`` (see :func:`default_rows`).

The batched kernel is generic over any loaded 1-DOF serial chain (catalogue or URDF): FK,
the selected rows of ``J`` and the measures in one compiled pass (numba ``prange``), without
storing the Jacobians. Configurations are processed in structure-of-arrays blocks, joint by
joint, so the inner loops vectorise (SIMD): sin / cos by a polynomial (fdlibm kernels, no libm
calls), and, when the selected rows are invariant under the first revolute joint (see
:func:`_first_joint_invariant`), that joint is not evaluated at all. Every shape with
``m = min(k, n) ≤ 4`` is reduced over the whole block (:func:`_reduce_block`): the Gram
matrix ``G`` (``J Jᵀ`` or ``Jᵀ J``, split into diagonal blocks where the chain's structure
makes it block diagonal, see :func:`_gram_plan`; the split is re-checked on every block)
gives the largest eigenvalues — closed forms for blocks of size ≤ 2, cyclic Jacobi over the
block for 3 and 4 (backward stable for clustered eigenvalues) — and ``det G`` comes from
``J``'s own minors (``det(J)²`` when square, Cauchy–Binet otherwise), so that
``σm = sqrt(det G / Π_{i<m} λi)`` keeps full accuracy near a singularity. Larger ``m`` goes
through a per-configuration reduction.
"""

from __future__ import annotations

import math
import sys
import threading
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np

from . import _kernels
from .exceptions import ConfigurationError, ParameterError, choices
from .symbolic import ROW_NAMES, SingularFamily, row_indices

__all__ = [
    "ROW_NAMES",
    "Measures",
    "ScanResult",
    "WorkspaceResult",
    "default_rows",
    "measures",
    "measures_batch",
    "scan",
    "plot_joints",
    "reach",
    "workspace",
    "cross_section",
]

njit = _kernels.njit
prange = _kernels.prange


# ------------------------------------------------------------------------ compiled reductions
@njit(cache=True, nogil=True)
def _eig2(a: float, b: float, d: float) -> tuple[float, float]:  # pragma: no cover - compiled
    """Eigenvalues (descending) of the symmetric [[a, b], [b, d]]."""
    half = 0.5 * (a + d)
    diff = 0.5 * (a - d)
    rad = math.sqrt(diff * diff + b * b)
    lmax = half + rad
    det = a * d - b * b
    lmin = det / lmax if lmax > 0.0 else 0.0
    return lmax, lmin


@njit(cache=True, nogil=True)
def _eig3_top2(g: np.ndarray) -> tuple[float, float]:  # pragma: no cover - compiled
    """The two largest eigenvalues of a symmetric PSD 3×3 ``g`` (closed form, descending)."""
    a00, a11, a22 = g[0, 0], g[1, 1], g[2, 2]
    a01, a02, a12 = g[0, 1], g[0, 2], g[1, 2]
    p1 = a01 * a01 + a02 * a02 + a12 * a12
    qm = (a00 + a11 + a22) / 3.0
    b00, b11, b22 = a00 - qm, a11 - qm, a22 - qm
    p2 = b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * p1
    if p2 <= 0.0:
        return qm, qm
    p = math.sqrt(p2 / 6.0)
    inv = 1.0 / p
    c00, c11, c22 = b00 * inv, b11 * inv, b22 * inv
    c01, c02, c12 = a01 * inv, a02 * inv, a12 * inv
    r = 0.5 * (
        c00 * (c11 * c22 - c12 * c12)
        - c01 * (c01 * c22 - c12 * c02)
        + c02 * (c01 * c12 - c11 * c02)
    )
    if r <= -1.0:
        phi = math.pi / 3.0
    elif r >= 1.0:
        phi = 0.0
    else:
        phi = math.acos(r) / 3.0
    l1 = qm + 2.0 * p * math.cos(phi)
    l3 = qm + 2.0 * p * math.cos(phi + 2.0 * math.pi / 3.0)
    l2 = 3.0 * qm - l1 - l3
    return l1, l2


@njit(cache=True, nogil=True)
def _jacobi_eig(g: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover - compiled
    """Eigenvalues of the symmetric ``g`` (destroyed) by cyclic Jacobi, into ``out`` (desc)."""
    m = g.shape[0]
    for _sweep in range(60):
        off = 0.0
        diag = 0.0
        for i in range(m):
            diag += g[i, i] * g[i, i]
            for j in range(i + 1, m):
                off += g[i, j] * g[i, j]
        if off <= 1e-34 * diag or off == 0.0:
            break
        for p in range(m - 1):
            for q in range(p + 1, m):
                apq = g[p, q]
                if apq == 0.0:
                    continue
                theta = (g[q, q] - g[p, p]) / (2.0 * apq)
                t = (1.0 if theta >= 0 else -1.0) / (abs(theta) + math.sqrt(theta * theta + 1.0))
                c = 1.0 / math.sqrt(t * t + 1.0)
                s = t * c
                for k in range(m):
                    gkp, gkq = g[k, p], g[k, q]
                    g[k, p] = c * gkp - s * gkq
                    g[k, q] = s * gkp + c * gkq
                for k in range(m):
                    gpk, gqk = g[p, k], g[q, k]
                    g[p, k] = c * gpk - s * gqk
                    g[q, k] = s * gpk + c * gqk
    for i in range(m):
        out[i] = g[i, i]
    # insertion sort, descending
    for i in range(1, m):
        v = out[i]
        j = i - 1
        while j >= 0 and out[j] < v:
            out[j + 1] = out[j]
            j -= 1
        out[j + 1] = v


@njit(cache=True, nogil=True)
def _det_lu(a: np.ndarray) -> float:  # pragma: no cover - compiled
    """Determinant of the square ``a`` (destroyed) by LU with partial pivoting."""
    n = a.shape[0]
    det = 1.0
    for k in range(n):
        piv = k
        best = abs(a[k, k])
        for i in range(k + 1, n):
            if abs(a[i, k]) > best:
                best = abs(a[i, k])
                piv = i
        if best == 0.0:
            return 0.0
        if piv != k:
            for j in range(n):
                a[k, j], a[piv, j] = a[piv, j], a[k, j]
            det = -det
        det *= a[k, k]
        for i in range(k + 1, n):
            f = a[i, k] / a[k, k]
            for j in range(k + 1, n):
                a[i, j] -= f * a[k, j]
    return det


@njit(cache=True, nogil=True, inline="always")
def _det3(a: np.ndarray) -> float:  # pragma: no cover - compiled
    """Determinant of the leading 3×3 block of ``a`` (cofactor expansion)."""
    return (
        a[0, 0] * (a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1])
        - a[0, 1] * (a[1, 0] * a[2, 2] - a[1, 2] * a[2, 0])
        + a[0, 2] * (a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0])
    )


@njit(cache=True, nogil=True)
def _det_small(a: np.ndarray, n: int, work: np.ndarray) -> float:  # pragma: no cover - compiled
    """Determinant of the leading n×n block of ``a``: closed forms up to 3, else LU on a copy."""
    if n == 1:
        return a[0, 0]
    if n == 2:
        return a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]
    if n == 3:
        return _det3(a)
    for i in range(n):
        for j in range(n):
            work[i, j] = a[i, j]
    return _det_lu(work[:n, :n])


@njit(cache=True, nogil=True)
def _reduce_one(
    js: np.ndarray, g: np.ndarray, work: np.ndarray, lam: np.ndarray
) -> tuple[float, float, float, float]:  # pragma: no cover - compiled
    """Measures ``(det, manipulability, condition, sigma_min)`` of one k×n Jacobian ``js``."""
    k, n = js.shape
    square = k == n
    m = k if k <= n else n
    # Gram matrix
    if k <= n:
        for a in range(m):
            for b in range(a, m):
                s = 0.0
                for c in range(n):
                    s += js[a, c] * js[b, c]
                g[a, b] = s
                g[b, a] = s
    else:
        for a in range(m):
            for b in range(a, m):
                s = 0.0
                for c in range(k):
                    s += js[c, a] * js[c, b]
                g[a, b] = s
                g[b, a] = s
    # determinant (square) and det G
    det = np.nan
    if square:
        det = _det_small(js, n, work)
        det_g = det * det
    else:
        det_g = _det_small(g, m, work)
    if det_g < 0.0:
        det_g = 0.0
    # the m-1 largest eigenvalues of G
    if m == 1:
        lmax = g[0, 0]
        prod_top = 1.0
    elif m == 2:
        lmax, _ = _eig2(g[0, 0], g[0, 1], g[1, 1])
        prod_top = lmax
    elif m == 3:
        lmax, l2 = _eig3_top2(g)
        prod_top = lmax * l2
    else:
        for a in range(m):
            for b in range(m):
                work[a, b] = g[a, b]
        _jacobi_eig(work[:m, :m], lam)
        lmax = lam[0]
        prod_top = 1.0
        for a in range(m - 1):
            prod_top *= lam[a]
    if m == 1:
        lmin = g[0, 0]
    elif prod_top > 0.0:
        lmin = det_g / prod_top
    else:
        lmin = 0.0
    if lmin < 0.0:
        lmin = 0.0
    smin = math.sqrt(lmin)
    smax = math.sqrt(lmax) if lmax > 0.0 else 0.0
    if square:
        manip = abs(det)
    else:
        manip = math.sqrt(det_g)
    cond = smax / smin if smin > 0.0 else np.inf
    return det, manip, cond, smin


# Cody–Waite split of π/2 (two 33-bit pieces and a tail) and the fdlibm minimax kernels of
# sin / cos on [−π/4, π/4]: |error| ≤ 1 ulp for |x| ≤ _POLY_TRIG_MAX, no calls, so the
# per-joint loops below vectorise (SIMD); larger angles use libm.
_PIO2_1 = 1.57079632673412561417e00
_PIO2_2 = 6.07710050630396597660e-11
_PIO2_2T = 2.02226624879595063154e-21
_INVPIO2 = 6.36619772367581382433e-01
_POLY_TRIG_MAX = 1.0e5
_S1, _S2, _S3 = -1.66666666666666324348e-01, 8.33333333332248946124e-03, -1.98412698298579493134e-04
_S4, _S5, _S6 = 2.75573137070700676789e-06, -2.50507602534068634195e-08, 1.58969099521155010221e-10
_C1, _C2, _C3 = 4.16666666666666019037e-02, -1.38888888888741095749e-03, 2.48015872894767294178e-05
_C4, _C5, _C6 = -2.75573143513906633035e-07, 2.08757232129817482790e-09, -1.13596475577881948265e-11
#: Jacobi sweeps stop when every off-diagonal sum of a block is below this × its trace.
_JACOBI_TOL = 1e-15
_JACOBI_MAX_SWEEPS = 12
#: Sweeps run over the whole block (SIMD, no gather) until at most 1/this of it is unconverged.
_JACOBI_GATHER = 4


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _sincos(x: float) -> tuple[float, float]:  # pragma: no cover - compiled
    """``(sin x, cos x)`` without libm calls (branch-free quadrant selection)."""
    n = math.floor(x * _INVPIO2 + 0.5)
    r = ((x - n * _PIO2_1) - n * _PIO2_2) - n * _PIO2_2T
    z = r * r
    s = r + (z * r) * (_S1 + z * (_S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))))
    cr = z * (_C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * (_C5 + z * _C6)))))
    hz = 0.5 * z
    w = 1.0 - hz
    c = w + (((1.0 - w) - hz) + z * cr)
    quad = int(n) & 3
    swap = quad & 1
    sgn_s = 1.0 - 2.0 * ((quad >> 1) & 1)
    sgn_c = 1.0 - 2.0 * (((quad + 1) >> 1) & 1)
    ss = c if swap else s
    cc = s if swap else c
    return ss * sgn_s, cc * sgn_c


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _jacobi_rot(
    app: float, aqq: float, apq: float, arp: float, arq: float
) -> tuple[float, float, float, float]:  # pragma: no cover - compiled
    """One symmetric Jacobi rotation zeroing ``a_pq``: new ``(a_pp, a_qq, a_rp, a_rq)``.

    Golub & Van Loan's ``t = sign(τ) a_pq / (|τ| + ρ)``, ``ρ = hypot(τ, a_pq)``, written with
    ``D = τ + sign(τ) ρ``: ``c = |D| / Q``, ``s = sign(D) a_pq / Q``, ``Q = sqrt(2 ρ |D|)``
    (the half-angle form ``c² = (1 + |τ|/ρ) / 2``, no cancellation), so one division
    ``W = 1 / (D Q)`` gives ``1/Q = D W`` and ``t = a_pq Q W``: two square roots, one division.
    """
    tau = 0.5 * (aqq - app)
    rad = math.sqrt(tau * tau + apq * apq)
    den = tau + rad if tau >= 0.0 else tau - rad
    zero = den == 0.0  # a_pq = 0 and equal diagonal: the identity rotation
    den = 1.0 if zero else den
    rad = 0.5 if zero else rad
    qq = math.sqrt(2.0 * rad * abs(den))
    wi = 1.0 / (den * qq)
    inv_q = den * wi
    c = abs(den) * inv_q
    s = apq * inv_q if den > 0.0 else -apq * inv_q
    t = apq * qq * wi
    return app - t * apq, aqq + t * apq, c * arp - s * arq, s * arp + c * arq


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
    return abs(a01) + abs(a02) - _JACOBI_TOL * (a00 + a11 + a22)


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _rot_cs(
    app: float, aqq: float, apq: float
) -> tuple[float, float, float, float]:  # pragma: no cover - compiled
    """Jacobi rotation zeroing ``a_pq``: new ``(a_pp, a_qq)``, ``(c, s)`` (as :func:`_jacobi_rot`).

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


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _jacobi_open(gb: np.ndarray, i: int, m: int) -> bool:  # pragma: no cover - compiled
    """Whether matrix ``i`` (packed 3×3 or 4×4, diagonal ``d``, off-diagonal ``E``) needs sweeps.

    With ``o = Σ_{a<b} |e_ab|`` (≥ every off-diagonal row sum, ≥ ``‖E‖₂``) and ``g`` the
    smallest gap ``|d_a − d_b|``, the diagonal holds the eigenvalues to ``tol = _JACOBI_TOL ·
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
    else:
        d0, d1, d2, d3 = gb[0, i], gb[4, i], gb[7, i], gb[9, i]
        off = abs(gb[1, i]) + abs(gb[2, i]) + abs(gb[3, i])
        off += abs(gb[5, i]) + abs(gb[6, i]) + abs(gb[8, i])
        tr = d0 + d1 + d2 + d3
        gap = min(min(abs(d0 - d1), abs(d0 - d2)), min(abs(d0 - d3), abs(d1 - d2)))
        gap = min(gap, min(abs(d1 - d3), abs(d2 - d3)))
    tol = _JACOBI_TOL * tr
    weyl = off <= tol
    quad = (gap > 3.0 * off) & (2.0 * off * off <= tol * (gap - off))
    return not (weyl | quad)  # branch-free: the block loops that count these vectorise


@njit(cache=True, nogil=True, error_model="numpy")
def _eig_block(
    gb: np.ndarray, nb: int, m: int, wb: np.ndarray, idx: np.ndarray
) -> None:  # pragma: no cover - compiled
    """Diagonalise ``nb`` packed symmetric m×m matrices (m = 3 or 4) in place by cyclic Jacobi.

    ``gb`` is (m(m+1)/2, B), rows the packed upper triangle (m = 3: ``g00 g01 g02 g11 g12
    g22``; m = 4: ``g00 g01 g02 g03 g11 g12 g13 g22 g23 g33``); ``wb`` the same shape and
    ``idx`` (B,) int are scratch. The first sweep runs over the whole block (SIMD); the
    matrices whose off-diagonal sum still exceeds ``_JACOBI_TOL · trace`` are gathered
    (compacted) into ``wb`` and swept there, contiguously (SIMD again), the converged ones
    scattered back, until none is left (Weyl: the diagonal then holds the eigenvalues to that
    absolute accuracy). Jacobi is backward stable for any eigenvalue clustering, unlike the
    characteristic-polynomial / trigonometric closed forms.
    """
    npk = gb.shape[0]
    sweeps = 0
    while sweeps < _JACOBI_MAX_SWEEPS:
        if m == 3:
            for i in range(nb):
                _jacobi_sweep(gb, i)
        else:
            for i in range(nb):
                _jacobi_sweep4(gb, i)
        sweeps += 1
        n_open = 0
        for i in range(nb):
            n_open += _jacobi_open(gb, i, m)
        if n_open == 0:
            return
        if n_open * _JACOBI_GATHER <= nb:
            break
    n_open = 0
    for i in range(nb):
        if _jacobi_open(gb, i, m):
            idx[n_open] = i
            n_open += 1
    for jj in range(n_open):
        i = idx[jj]
        for p in range(npk):
            wb[p, jj] = gb[p, i]
    while sweeps < _JACOBI_MAX_SWEEPS:
        sweeps += 1
        if n_open == 0:
            return
        if m == 3:
            for jj in range(n_open):
                _jacobi_sweep(wb, jj)
        else:
            for jj in range(n_open):
                _jacobi_sweep4(wb, jj)
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
def _eig3_block(gb: np.ndarray, nb: int, idx: np.ndarray) -> None:  # pragma: no cover - compiled
    """:func:`_eig_block` for packed 3×3 matrices (``gb`` (6, B): ``g00 g01 g02 g11 g12 g22``)."""
    _eig_block(gb, nb, 3, np.empty_like(gb), idx)


@njit(cache=True, nogil=True, inline="always", error_model="numpy")
def _minor_block(
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
def _reduce_block(
    jb: np.ndarray,
    nb: int,
    plan: tuple[Any, ...],
    gb: np.ndarray,
    hb: np.ndarray,
    wb: np.ndarray,
    ev: np.ndarray,
    idx: np.ndarray,
    dg: np.ndarray,
    mnr: np.ndarray,
    start: int,
    out_det: np.ndarray,
    out_manip: np.ndarray,
    out_cond: np.ndarray,
    out_smin: np.ndarray,
) -> None:  # pragma: no cover - compiled
    """Measures of a block of ``nb`` k×n Jacobians ``jb`` (k, n, B), ``m = min(k, n) ≤ 4``.

    ``plan`` is :attr:`_GramPlan.arrays`. ``G`` (``J Jᵀ`` or ``Jᵀ J``, m×m, packed upper
    triangle) gives the largest eigenvalues. When the plan found ``G`` block diagonal (entries
    ``drop`` zero at random samples, e.g. the leg's ``{q1} ⊕ {q2, q3}``) and they are below
    ``_JACOBI_TOL · trace`` over the whole block (checked; Weyl bounds the effect), each
    diagonal block is solved alone: closed forms for sizes 1 and 2, :func:`_eig_block` for 3
    and 4; otherwise ``G`` as a whole. ``det G`` comes from the Jacobian itself — ``det(J)²``
    when square, else Cauchy–Binet, the sum of the squared maximal minors of ``J`` (rows
    ``rsub[s]``, columns ``csub[s]``) — so that ``λmin = det G / Π_{i<m} λi`` keeps relative
    accuracy near a singularity (forming ``det G`` from ``G`` would lose it: its error is
    ``ε λmax^m``).
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
        _minor_block(jb, rsub[0], csub[0], mm, nb, mnr)
        for i in range(nb):
            out_det[start + i] = mnr[i]
            dg[i] = mnr[i] * mnr[i]
    else:
        for i in range(nb):
            dg[i] = 0.0
            out_det[start + i] = np.nan
        for s in range(rsub.shape[0]):
            _minor_block(jb, rsub[s], csub[s], mm, nb, mnr)
            for i in range(nb):
                dg[i] += mnr[i] * mnr[i]
    # the structural zeros really are negligible over this block?
    split = drop.shape[0] > 0
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
                mnr[i] -= abs(gb[p, i]) / _JACOBI_TOL
        bad = 0
        for i in range(nb):
            bad += mnr[i] < 0.0
        split = bad == 0
    # eigenvalues of each diagonal block into ev[0:mm]
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
            _eig_block(hb[: s * (s + 1) // 2], nb, s, wb, idx)
            for u in range(s):
                q = u * s - (u * (u - 1)) // 2
                for i in range(nb):
                    ev[off + u, i] = hb[q, i]
        off += s
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


@njit(cache=True, parallel=True, nogil=True, error_model="numpy")
def _measures_kernel(
    prot: np.ndarray,
    ptr: np.ndarray,
    pident: np.ndarray,
    kind: np.ndarray,
    col: np.ndarray,
    qs: np.ndarray,
    sel: np.ndarray,
    use_block: bool,
    plan: tuple[Any, ...],
    skip0: bool,
    poly: bool,
    nwork: int,
    block: int,
    out_det: np.ndarray,
    out_manip: np.ndarray,
    out_cond: np.ndarray,
    out_smin: np.ndarray,
) -> None:  # pragma: no cover - compiled
    """Fused FK + selected-row Jacobian + measures for every row of ``qs``.

    The chain is given with every joint axis aligned to its frame's z (see
    :func:`_aligned_chain`): fixed placements ``(prot[j], ptr[j])`` then ``Rz(q)`` or ``Tz(q)``;
    ``ptr[m]`` is the tip offset. Work is split into ``nwork`` contiguous ranges (one per
    thread, scratch allocated once each), processed in blocks of ``block`` configurations
    stored structure-of-arrays, joint by joint, so that every inner loop runs over the block
    and vectorises. ``skip0``: joint 0 is left at ``q = 0`` (the measures do not depend on it,
    see :func:`_first_joint_invariant`). ``poly``: sin / cos by :func:`_sincos` (all
    ``|q| ≤ _POLY_TRIG_MAX``) rather than libm. ``use_block`` (``min(k, n) ≤ 4``, see
    :func:`_block_plan` for ``pack`` / ``rsub`` / ``csub``): the measures of the whole block by
    :func:`_reduce_block`; otherwise :func:`_reduce_one` per configuration.
    """
    nconf = qs.shape[0]
    nq = qs.shape[1]
    m = kind.shape[0]
    k = sel.shape[0]
    mm = k if k <= nq else nq
    big = k if k > nq else nq
    npk = mm * (mm + 1) // 2 if use_block else 1
    nev = mm if use_block else 1
    bsz = block
    nblocks = (nconf + bsz - 1) // bsz
    per = (nblocks + nwork - 1) // nwork
    for w in prange(nwork):
        rr = np.empty((9, bsz))
        pp = np.empty((3, bsz))
        frames = np.empty((max(m, 1), 6, bsz))
        trig = np.empty((2, bsz))
        qb = np.empty((nq, bsz))
        jb = np.empty((k, nq, bsz))
        gb = np.empty((npk, bsz))
        hb = np.empty((npk, bsz))
        wb = np.empty((npk, bsz))
        ev = np.empty((nev, bsz))
        open_idx = np.empty(bsz, dtype=np.int64)
        dg = np.empty(bsz)
        mnr = np.empty(bsz)
        js = np.empty((k, nq))
        g = np.empty((mm, mm))
        work = np.empty((big, big))
        lam = np.empty(mm)
        for blk in range(w * per, min(nblocks, (w + 1) * per)):
            start = blk * bsz
            nb = min(nconf, start + bsz) - start
            for i in range(nb):  # the block's q, transposed: the per-joint loops read rows
                for c in range(nq):
                    qb[c, i] = qs[start + i, c]
            for j in range(m):
                t0, t1, t2 = ptr[j, 0], ptr[j, 1], ptr[j, 2]
                if j == 0:
                    for i in range(nb):
                        pp[0, i] = t0
                        pp[1, i] = t1
                        pp[2, i] = t2
                    for a in range(9):
                        v = prot[0, a]
                        for i in range(nb):
                            rr[a, i] = v
                else:
                    for i in range(nb):
                        pp[0, i] += rr[0, i] * t0 + rr[1, i] * t1 + rr[2, i] * t2
                        pp[1, i] += rr[3, i] * t0 + rr[4, i] * t1 + rr[5, i] * t2
                        pp[2, i] += rr[6, i] * t0 + rr[7, i] * t1 + rr[8, i] * t2
                    if pident[j] == 0:
                        a00, a01, a02 = prot[j, 0], prot[j, 1], prot[j, 2]
                        a10, a11, a12 = prot[j, 3], prot[j, 4], prot[j, 5]
                        a20, a21, a22 = prot[j, 6], prot[j, 7], prot[j, 8]
                        for row in range(3):
                            b = 3 * row
                            for i in range(nb):
                                x0, x1, x2 = rr[b, i], rr[b + 1, i], rr[b + 2, i]
                                rr[b, i] = x0 * a00 + x1 * a10 + x2 * a20
                                rr[b + 1, i] = x0 * a01 + x1 * a11 + x2 * a21
                                rr[b + 2, i] = x0 * a02 + x1 * a12 + x2 * a22
                for i in range(nb):
                    frames[j, 0, i] = pp[0, i]
                    frames[j, 1, i] = pp[1, i]
                    frames[j, 2, i] = pp[2, i]
                    frames[j, 3, i] = rr[2, i]
                    frames[j, 4, i] = rr[5, i]
                    frames[j, 5, i] = rr[8, i]
                cj = col[j]
                if kind[j] == 1:
                    for i in range(nb):
                        qv = qb[cj, i]
                        pp[0, i] += rr[2, i] * qv
                        pp[1, i] += rr[5, i] * qv
                        pp[2, i] += rr[8, i] * qv
                elif not (j == 0 and skip0):
                    if poly:
                        for i in range(nb):
                            trig[0, i], trig[1, i] = _sincos(qb[cj, i])
                    else:
                        for i in range(nb):
                            qv = qb[cj, i]
                            trig[0, i] = math.sin(qv)
                            trig[1, i] = math.cos(qv)
                    for row in range(3):
                        b = 3 * row
                        for i in range(nb):
                            sq, cq = trig[0, i], trig[1, i]
                            x0, x1 = rr[b, i], rr[b + 1, i]
                            rr[b, i] = cq * x0 + sq * x1
                            rr[b + 1, i] = cq * x1 - sq * x0
            t0, t1, t2 = ptr[m, 0], ptr[m, 1], ptr[m, 2]
            for i in range(nb):
                pp[0, i] += rr[0, i] * t0 + rr[1, i] * t1 + rr[2, i] * t2
                pp[1, i] += rr[3, i] * t0 + rr[4, i] * t1 + rr[5, i] * t2
                pp[2, i] += rr[6, i] * t0 + rr[7, i] * t1 + rr[8, i] * t2
            # selected rows of J, column by column: [z × (p − o); z] or [z; 0]
            for a in range(k):
                for b in range(nq):
                    for i in range(nb):
                        jb[a, b, i] = 0.0
            for j in range(m):
                cj = col[j]
                for a in range(k):
                    r = sel[a]
                    if kind[j] == 1:
                        if r < 3:
                            for i in range(nb):
                                jb[a, cj, i] += frames[j, 3 + r, i]
                    elif r >= 3:
                        for i in range(nb):
                            jb[a, cj, i] += frames[j, r, i]
                    else:
                        u = (r + 1) % 3
                        v = (r + 2) % 3
                        for i in range(nb):
                            jb[a, cj, i] += frames[j, 3 + u, i] * (
                                pp[v, i] - frames[j, v, i]
                            ) - frames[j, 3 + v, i] * (pp[u, i] - frames[j, u, i])
            if use_block:
                _reduce_block(
                    jb,
                    nb,
                    plan,
                    gb,
                    hb,
                    wb,
                    ev,
                    open_idx,
                    dg,
                    mnr,
                    start,
                    out_det,
                    out_manip,
                    out_cond,
                    out_smin,
                )
            else:
                for i in range(nb):
                    for a in range(k):
                        for b in range(nq):
                            js[a, b] = jb[a, b, i]
                    d, mp, cn, sm = _reduce_one(js, g, work, lam)
                    out_det[start + i] = d
                    out_manip[start + i] = mp
                    out_cond[start + i] = cn
                    out_smin[start + i] = sm


def _rotation_z_to(u: np.ndarray) -> np.ndarray:
    """A rotation ``A`` with ``A @ ez = u`` (identity when ``u`` is ``ez``)."""
    u = np.asarray(u, float) / np.linalg.norm(u)
    ez = np.array([0.0, 0.0, 1.0])
    if np.allclose(u, ez, rtol=0, atol=1e-15):
        return np.eye(3)
    if np.allclose(u, -ez, rtol=0, atol=1e-15):
        return np.diag([1.0, -1.0, -1.0])
    v = np.cross(ez, u)
    s = np.linalg.norm(v)
    c = float(u @ ez)
    vx = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + vx + vx @ vx * ((1 - c) / s**2)


@dataclass(frozen=True)
class _AlignedChain:
    prot: np.ndarray
    ptr: np.ndarray
    pident: np.ndarray
    kind: np.ndarray
    col: np.ndarray
    nq: int


def _aligned_chain(arrays: _kernels.ChainArrays) -> _AlignedChain:
    """Re-express the shared :class:`~hexapod_kin._kernels.ChainArrays` with z joint axes.

    Joint ``j`` rotates about its local axis ``u_j``; with ``A_j ez = u_j`` the rotation is
    ``A_j Rz(q) A_jᵀ``, so ``A_j`` is folded into placement ``j`` and ``A_jᵀ`` into placement
    ``j + 1`` (or the tip offset). The kernel then only applies ``Rz(q)`` / ``Tz(q)``.
    """
    m = arrays.rot.shape[0]
    prot = np.empty((m, 9))
    ptr = np.empty((m + 1, 3))
    pident = np.zeros(m, dtype=np.int64)
    prev_t = np.eye(3)  # A_{j-1}^T
    for j in range(m):
        a = _rotation_z_to(arrays.axis[j])
        rot = prev_t @ arrays.rot[j] @ a
        rot[np.abs(rot) < 1e-15] = 0.0
        prot[j] = rot.reshape(-1)
        ptr[j] = prev_t @ arrays.trans[j]
        pident[j] = int(np.array_equal(rot, np.eye(3)))
        prev_t = a.T
    ptr[m] = prev_t @ arrays.trans[m]
    return _AlignedChain(prot, ptr, pident, arrays.kind.copy(), arrays.col.copy(), arrays.nq)


#: Configurations per structure-of-arrays block of :func:`_measures_kernel`.
_BLOCK = 256
#: Largest number of maximal minors (Cauchy–Binet terms) the block path accepts.
_MAX_MINORS = 70


@lru_cache(maxsize=64)
def _block_plan(k: int, n: int) -> tuple[bool, np.ndarray, np.ndarray, np.ndarray]:
    """Block-path tables for k×n Jacobians: ``(use_block, pack, rsub, csub)``.

    ``pack[a, b]``: row of ``G[a, b]`` in the packed upper triangle (m×m, ``m = min(k, n)``);
    ``rsub[s]`` / ``csub[s]``: rows / columns of the s-th maximal minor of ``J`` (the one
    square minor when ``k == n``; all ``C(max(k, n), m)`` of them otherwise, for Cauchy–Binet
    ``det G = Σ_s minor_s²``). ``use_block`` is false when ``m > 4`` or there are more than
    ``_MAX_MINORS`` minors (the per-configuration path then serves).
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
    use = 1 <= m <= 4 and len(subs) <= _MAX_MINORS
    if not use:
        subs = subs[:1] or [full]
    if k <= n:
        rsub, csub = [full] * len(subs), subs
    else:
        rsub, csub = subs, [full] * len(subs)
    as_arr = lambda x: np.array(x, dtype=np.int64).reshape(len(subs), max(m, 1))  # noqa: E731
    return use, pack, as_arr(rsub), as_arr(csub)


@dataclass(frozen=True)
class _GramPlan:
    """How :func:`_reduce_block` treats one chain and row selection (see :func:`_gram_plan`).

    Attributes:
        use_block: Whether the block path applies (``m = min(k, n) ≤ 4``, few minors).
        gram_t: ``G = Jᵀ J`` (else ``J Jᵀ``).
        perm: (m,) indices of ``G`` ordered by diagonal block.
        csize: (c,) sizes of the diagonal blocks (one block of size m: no split).
        drop: Packed positions of the entries between blocks (zero at random samples).
        arrays: The tuple the kernel takes: ``(pack, rsub, csub, gram_t, perm, csize, drop)``.

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
    seen = [False] * m
    comps = []
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


def _gram_plan(model: Any, sel: tuple[int, ...], skip0: bool) -> _GramPlan:
    """Plan the block reduction for ``model``'s rows ``sel`` (cached on the model).

    ``G`` is ``J Jᵀ`` when k < n, ``Jᵀ J`` when k > n, and, when square, whichever splits
    into smaller diagonal blocks: the entries of both are evaluated at 16 random
    configurations (the first joint at 0 when ``skip0``, as in the kernel) and those below
    ``1e-14 · max |G|`` at all of them are taken as structural zeros. The kernel re-checks them
    on every block (a block where one is not negligible is solved whole), so a wrong guess
    only costs time. A 3-DOF leg's ``Jᵀ J`` is ``{q1} ⊕ {q2, q3}`` (the hip column is
    orthogonal to the leg plane), the SCARA's (x, y, z, wz) ``{θ1, θ2, θ3} ⊕ {d4}``.
    """
    cache = getattr(model, "_hk_gram_plans", None)
    if cache is None:
        cache = {}
        try:
            model._hk_gram_plans = cache
        except AttributeError:  # pragma: no cover
            pass
    key = (sel, skip0)
    if key in cache:
        return cache[key]
    arrays = _arrays(model)
    k, n = len(sel), arrays.nq
    use_block, pack, rsub, csub = _block_plan(k, n)
    m = min(k, n)
    best: tuple[int, int, bool, list[list[int]], np.ndarray] | None = None
    if use_block and m >= 2:
        q = model.random_q(16, seed=2024)
        if skip0:
            q[:, arrays.col[0]] = 0.0
        jac = _kernels.jacobian_batch(arrays, q, rows=6)[:, list(sel), :]
        for gram_t in (False, True) if k == n else (k > n,):
            g = np.swapaxes(jac, 1, 2) @ jac if gram_t else jac @ np.swapaxes(jac, 1, 2)
            zero = (np.abs(g) <= 1e-14 * max(float(np.abs(g).max()), 1e-300)).all(axis=0)
            comps = _components(zero)
            score = (max(len(c) for c in comps), -len(comps))
            if best is None or score < best[:2]:
                best = (*score, gram_t, comps, zero)
    if best is None:
        gram_t, comps = k > n, [list(range(m))]
    else:
        gram_t, comps = best[2], best[3]
    perm = np.array([a for c in comps for a in c] or [0], dtype=np.int64)
    csize = np.array([len(c) for c in comps] or [1], dtype=np.int64)
    where = {a: ci for ci, c in enumerate(comps) for a in c}
    drop = np.array(
        sorted(
            int(pack[a, b]) for a in range(m) for b in range(a + 1, m) if where[a] != where[b]
        ),
        dtype=np.int64,
    )
    if len(comps) == 1:
        perm = np.arange(max(m, 1), dtype=np.int64)
    plan = _GramPlan(
        use_block, gram_t, perm, csize, drop, (pack, rsub, csub, gram_t, perm, csize, drop)
    )
    cache[key] = plan
    return plan


def _axis_rotation(u: np.ndarray, angle: float) -> np.ndarray:
    """Rotation by ``angle`` [rad] about the unit axis ``u`` (Rodrigues)."""
    ux = np.array([[0.0, -u[2], u[1]], [u[2], 0.0, -u[0]], [-u[1], u[0], 0.0]])
    return np.eye(3) + math.sin(angle) * ux + (1.0 - math.cos(angle)) * (ux @ ux)


def _first_joint_invariant(al: _AlignedChain, sel: tuple[int, ...]) -> bool:
    """Whether the measures of the ``sel`` rows of ``J`` do not depend on the first joint.

    Turning revolute joint 0 (axis ``u`` in the base frame) by ``θ`` rotates everything after it
    rigidly, so ``J(q) = B J(q with q0 = 0)`` with ``B = blockdiag(R, R)``, ``R = Rot(u, θ)``
    (linear velocities and axes both rotate; the origin of the rotation does not matter for
    differences of points). With ``S`` the k×6 row selection, ``S J(q) = Q S J(q0 = 0)`` and
    ``Q = S B Sᵀ`` holds exactly when ``Q`` is orthogonal (the selected rows span a subspace
    invariant under ``B``); then the singular values are the same, and ``det Q = +1``
    (``Q(θ)`` is continuous with ``Q(0) = I``) keeps ``det J``. Checked at two generic angles.
    Also requires ``q0`` to drive joint 0 only.
    """
    if al.kind.shape[0] == 0 or al.kind[0] != 0 or np.count_nonzero(al.col == al.col[0]) != 1:
        return False
    u = al.prot[0].reshape(3, 3)[:, 2]
    u = u / np.linalg.norm(u)
    rows = np.eye(6)[list(sel)]
    for angle in (0.7, 2.3):
        rot = _axis_rotation(u, angle)
        b = np.zeros((6, 6))
        b[:3, :3] = rot
        b[3:, 3:] = rot
        qmat = rows @ b @ rows.T
        if np.abs(qmat.T @ qmat - np.eye(len(sel))).max() > 1e-12:
            return False
        if np.linalg.det(qmat) <= 0:
            return False
    return True


#: The last output buffer of :func:`measures_batch`, kept for reuse (see :func:`_output_arrays`).
_OUT_POOL: list[np.ndarray] = []
_OUT_LOCK = threading.Lock()
_OUT_POOL_MAX_BYTES = 128 * 2**20


def _output_arrays(n: int) -> tuple[np.ndarray, ...]:
    """Four (n,) float64 arrays for :func:`measures_batch`: the rows of one (4, n) buffer.

    Touching fresh memory is slow on the 2-core VM (first-touch page faults, ~1.3 ms per MB:
    ~40 ms for the 32 MB of 1e6 configurations, as long as the kernel itself), so the last
    buffer (up to ``_OUT_POOL_MAX_BYTES``) is kept and handed out again — only when nothing
    references it any more: the rows returned hold it through ``.base``, so while any result
    array (or a view of one) is alive its reference count stays above the pool's own.
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


def _measures_numpy(jac: np.ndarray) -> tuple[np.ndarray, ...]:
    """Reference / fallback: measures of a stack of Jacobians (N, k, n) with numpy SVD."""
    n_conf, k, n = jac.shape
    sv = np.linalg.svd(jac, compute_uv=False)
    smax = sv[:, 0]
    smin = sv[:, -1]
    det = np.linalg.det(jac) if k == n else np.full(n_conf, np.nan)
    manip = np.abs(det) if k == n else np.prod(sv, axis=1)
    with np.errstate(divide="ignore"):
        cond = np.where(smin > 0, smax / np.where(smin > 0, smin, 1.0), np.inf)
    return det, manip, cond, smin


# ------------------------------------------------------------------------ single configuration
@dataclass(frozen=True)
class Measures:
    """Singularity measures of one configuration.

    Attributes:
        det: ``det J`` (NaN when J is not square).
        manipulability: ``sqrt(det(J Jᵀ))`` (product of the singular values).
        condition: ``σmax / σmin`` (``inf`` when singular).
        sigma_min: Smallest singular value.
        singular_values: All ``min(k, n)`` singular values, descending (read-only).
        rows: Row names of ``J`` used.

    """

    det: float
    manipulability: float
    condition: float
    sigma_min: float
    singular_values: np.ndarray
    rows: tuple[str, ...]


def _model(model: Any) -> Any:
    from .kinematics import KinematicModel, load

    if isinstance(model, KinematicModel):
        return model
    return load(model)


def default_rows(model: Any) -> tuple[str, ...]:
    """Default row selection for ``model``: ``x, y, z`` plus the non-zero angular rows if square.

    Angular rows are tested at a few random configurations (a row is "zero" when it is below
    1e-12 everywhere). SCARA → ``("x", "y", "z", "wz")``; 3-DOF leg → ``("x", "y", "z")``.

    Args:
        model: A loaded :class:`~hexapod_kin.kinematics.KinematicModel` (or a source).

    """
    from .symbolic import default_rows as _dr

    mdl = _model(model)
    arrays = _arrays(mdl)
    qs = mdl.random_q(8, seed=12345)
    jac = _kernels.jacobian_batch(arrays, qs, rows=6)
    flags = np.abs(jac).max(axis=(0, 2)) > 1e-12
    return _dr(flags, mdl.nq)


def _arrays(model: Any) -> _kernels.ChainArrays:
    cached = getattr(model, "_hk_chain_arrays", None)
    if cached is None:
        cached = _kernels.ChainArrays.from_model(model)
        try:
            model._hk_chain_arrays = cached
        except AttributeError:  # pragma: no cover
            pass
    return cached


def _aligned(model: Any) -> _AlignedChain:
    cached = getattr(model, "_hk_aligned_chain", None)
    if cached is None:
        cached = _aligned_chain(_arrays(model))
        try:
            model._hk_aligned_chain = cached
        except AttributeError:  # pragma: no cover
            pass
    return cached


def _rows(model: Any, rows: Any) -> tuple[str, ...]:
    if rows is None:
        return default_rows(model)
    return tuple(ROW_NAMES[i] for i in row_indices(rows))


def measures(model: Any, q: Any, rows: str | Sequence[str] | None = None) -> Measures:
    """Singularity measures of one configuration (Pinocchio Jacobian, numpy SVD).

    Args:
        model: A loaded model (or a source for :func:`~hexapod_kin.kinematics.load`).
        q: Joint values (nq,) in [rad] / [m].
        rows: Row selection (see module doc); default :func:`default_rows`.

    Returns:
        The :class:`Measures`.

    Raises:
        ConfigurationError: Bad ``q``.
        ParameterError: Bad ``rows``.

    """
    mdl = _model(model)
    names = _rows(mdl, rows)
    idx = [ROW_NAMES.index(r) for r in names]
    jac = mdl.jacobian(q, "local_world_aligned")[idx]
    det, manip, cond, smin = _measures_numpy(jac[None])
    sv = np.linalg.svd(jac, compute_uv=False)
    sv.setflags(write=False)
    return Measures(float(det[0]), float(manip[0]), float(cond[0]), float(smin[0]), sv, names)


def measures_batch(
    model: Any,
    qs: Any,
    rows: str | Sequence[str] | None = None,
    *,
    engine: str = "kernel",
    out: tuple[np.ndarray, ...] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Measures of many configurations: ``(det, manipulability, condition, sigma_min)``.

    Args:
        model: A loaded model (or a source).
        qs: Configurations (N, nq).
        rows: Row selection; default :func:`default_rows`.
        engine: ``"kernel"`` (compiled, fused; numpy fallback without numba) or ``"numpy"``
            (batched Jacobians from the kernel, numpy SVD per configuration).
        out: Optional four preallocated float64 arrays of shape (N,) to fill.

    Returns:
        Four (N,) arrays.

    Raises:
        ConfigurationError: ``qs`` has the wrong shape or non-finite values.
        ParameterError: Bad ``rows`` or ``engine``.

    """
    mdl = _model(model)
    names = _rows(mdl, rows)
    arrays = _arrays(mdl)
    q = _kernels._check_batch(arrays, qs)
    sel = np.array([ROW_NAMES.index(r) for r in names], dtype=np.int64)
    full = 6 if sel.max() >= 3 else 3
    if engine not in ("kernel", "numpy"):
        raise ParameterError(f"engine={engine!r} is not allowed; use 'kernel' or 'numpy'")
    if engine == "numpy" or not _kernels.HAVE_NUMBA:
        jac = _kernels.jacobian_batch(arrays, q, rows=full)[:, sel, :]
        res = _measures_numpy(jac)
        if out is not None:
            for o, r in zip(out, res):
                o[...] = r
            return out  # type: ignore[return-value]
        return res  # type: ignore[return-value]
    n = q.shape[0]
    if out is None:
        out = _output_arrays(n)
    elif len(out) != 4 or any(o.shape != (n,) or o.dtype != np.float64 for o in out):
        raise ConfigurationError(f"out: four float64 arrays of shape ({n},) are required")
    al = _aligned(mdl)
    skip0 = _first_joint_invariant(al, tuple(int(r) for r in sel))
    poly = bool(n == 0 or max(float(q.max()), -float(q.min())) <= _POLY_TRIG_MAX)
    nwork = max(1, min(_kernels.numba.get_num_threads(), -(-n // _BLOCK)))
    plan = _gram_plan(mdl, tuple(int(r) for r in sel), skip0)
    _measures_kernel(
        al.prot, al.ptr, al.pident, al.kind, al.col, q, sel, plan.use_block, plan.arrays,
        skip0, poly, nwork, _BLOCK, *out,
    )
    return out  # type: ignore[return-value]


# ------------------------------------------------------------------------ families
@lru_cache(maxsize=16)
def _derivation(chain: Any, rows: tuple[str, ...]) -> Any:
    from .symbolic import derive

    return derive(chain, rows=rows)


def _derivation_for(model: Any, rows: tuple[str, ...]) -> Any:
    from .params import Chain

    params = model.params
    if isinstance(params, Chain) and model.nq == params.nq:
        try:
            return _derivation(params, rows)
        except Exception:  # noqa: BLE001 - sympy failures only cost the family equations
            return None
    return None


@dataclass(frozen=True)
class _FamilyFunctions:
    """Numeric residuals of the singular families: value ~ 0 on the family."""

    families: tuple[SingularFamily, ...]
    funcs: tuple[Any, ...]
    grads: tuple[Any, ...]

    def distance(self, q: np.ndarray) -> np.ndarray:
        """First-order joint-space distance (N, F) of configurations to each family."""
        q = np.atleast_2d(q)
        out = np.empty((q.shape[0], len(self.families)))
        for f, fam in enumerate(self.families):
            if fam.joint is not None and fam.value is not None:
                d = q[:, fam.joint] - fam.value
                if fam.periodic:
                    d = (d + np.pi) % (2 * np.pi) - np.pi
                out[:, f] = np.abs(d)
            else:
                val = self.funcs[f](q)
                grad = self.grads[f](q)
                norm = np.sqrt(np.sum(grad**2, axis=-1).reshape(q.shape[0]))
                with np.errstate(divide="ignore", invalid="ignore"):
                    out[:, f] = np.where(norm > 0, np.abs(val) / norm, np.inf)
        return out

    def residual(self, q: np.ndarray, f: int) -> np.ndarray:
        """Signed residual of family ``f`` (its factor; wrapped joint offset for joint ones)."""
        fam = self.families[f]
        if fam.joint is not None and fam.value is not None:
            d = q[..., fam.joint] - fam.value
            return (d + np.pi) % (2 * np.pi) - np.pi if fam.periodic else d
        return self.funcs[f](q)


_FAMILY_CACHE: dict[int, tuple[Any, _FamilyFunctions]] = {}


def _family_functions(deriv: Any) -> _FamilyFunctions:
    """Lambdified residuals of ``deriv``'s families (cached: derivations are cached too)."""
    hit = _FAMILY_CACHE.get(id(deriv))
    if hit is not None and hit[0] is deriv:
        return hit[1]
    import sympy as sp

    funcs, grads = [], []
    for fam in deriv.families:
        funcs.append(deriv.function(fam.factor))
        grads.append(deriv.function(sp.Matrix([[sp.diff(fam.factor, s) for s in deriv.q]])))
    result = _FamilyFunctions(tuple(deriv.families), tuple(funcs), tuple(grads))
    if len(_FAMILY_CACHE) > 32:
        _FAMILY_CACHE.clear()
    _FAMILY_CACHE[id(deriv)] = (deriv, result)
    return result


# ------------------------------------------------------------------------ scans
def _ro(arr: np.ndarray) -> np.ndarray:
    arr = np.ascontiguousarray(arr)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True)
class ScanResult:
    """Result of :func:`scan` (arrays are read-only).

    Attributes:
        q: Configurations (N, n) in [rad] / [m].
        det: ``det J`` (N,) (NaN where J is not square).
        manipulability: (N,) ``sqrt(det(J Jᵀ))``.
        condition: (N,) ``σmax/σmin`` (``inf`` where singular).
        sigma_min: (N,) smallest singular value.
        singular: (N,) boolean mask ``sigma_min < threshold``.
        family: (N,) index into :attr:`families` of the family each flagged configuration lies
            on (nearest, within ``family_tol``), −1 where not flagged or unexplained.
        families: The singular families (from :mod:`hexapod_kin.symbolic`; empty when the
            model has no Khalil table).
        joint_names: Names of the n joints.
        joints: Indices of the joints that were scanned (the others stay at ``q_fixed``).
        rows: Row names of ``J``.
        threshold: The ``sigma_min`` threshold used.
        grid_shape: Points per scanned joint for a grid scan (``q`` in C order), else ``None``.
        q_fixed: Values of the joints that were not scanned (n,).
        source: The model's name.

    """

    q: np.ndarray
    det: np.ndarray
    manipulability: np.ndarray
    condition: np.ndarray
    sigma_min: np.ndarray
    singular: np.ndarray
    family: np.ndarray
    families: tuple[SingularFamily, ...]
    joint_names: tuple[str, ...]
    joints: tuple[int, ...]
    rows: tuple[str, ...]
    threshold: float
    grid_shape: tuple[int, ...] | None
    q_fixed: np.ndarray
    source: str
    _family_funcs: Any = field(default=None, repr=False, compare=False)

    @property
    def unexplained(self) -> np.ndarray:
        """Flagged configurations on no known family (N,) — expected empty for catalogue chains."""
        return self.singular & (self.family < 0)

    def family_counts(self) -> dict[str, int]:
        """Number of flagged configurations on each family, by family name."""
        return {
            fam.name: int(np.count_nonzero(self.family == f))
            for f, fam in enumerate(self.families)
        }

    def family_residual(self, q: np.ndarray, f: int) -> np.ndarray:
        """Signed residual of family ``f`` at ``q`` (…, n) (zero on the family)."""
        if self._family_funcs is None:
            raise ParameterError("family_residual: this scan has no family equations")
        return self._family_funcs.residual(np.asarray(q, float), f)

    def grid(self, name: str) -> np.ndarray:
        """A measure reshaped to :attr:`grid_shape` (grid scans only)."""
        if self.grid_shape is None:
            raise ParameterError("grid(): this scan used random samples, not a grid")
        allowed = ("det", "manipulability", "condition", "sigma_min", "singular", "family")
        if name not in allowed:
            raise ParameterError(f"grid(name={name!r}): use one of {choices(allowed)}")
        return np.asarray(getattr(self, name)).reshape(self.grid_shape)

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready dict with the same names (NaN / inf become ``null``)."""

        def clean(a: np.ndarray) -> list[Any]:
            flat = a.astype(float).tolist()
            return [v if math.isfinite(v) else None for v in flat]

        return {
            "source": self.source,
            "joint_names": list(self.joint_names),
            "joints": [self.joint_names[j] for j in self.joints],
            "rows": list(self.rows),
            "threshold": self.threshold,
            "grid_shape": list(self.grid_shape) if self.grid_shape else None,
            "q_fixed": self.q_fixed.tolist(),
            "q": self.q.tolist(),
            "det": clean(self.det),
            "manipulability": clean(self.manipulability),
            "condition": clean(self.condition),
            "sigma_min": clean(self.sigma_min),
            "singular": self.singular.tolist(),
            "family": self.family.tolist(),
            "families": [
                {
                    "name": fam.name,
                    "equation": str(fam.equation),
                    "joint": None if fam.joint is None else self.joint_names[fam.joint],
                    "value": fam.value,
                    "count": int(np.count_nonzero(self.family == f)),
                }
                for f, fam in enumerate(self.families)
            ],
            "n_singular": int(np.count_nonzero(self.singular)),
            "n_unexplained": int(np.count_nonzero(self.unexplained)),
        }


def _joint_indices(model: Any, joints: Any) -> tuple[int, ...]:
    if joints is None:
        return tuple(range(model.nq))
    if isinstance(joints, (str, int)):
        joints = [joints]
    out = []
    for j in joints:
        if isinstance(j, (int, np.integer)) and not isinstance(j, bool):
            if not 0 <= int(j) < model.nq:
                raise ParameterError(
                    f"joints: index {j} is out of range 0..{model.nq - 1} "
                    f"(joints {choices(model.joint_names)})"
                )
            out.append(int(j))
        else:
            out.append(model.joint_index(str(j)))
    if len(set(out)) != len(out) or not out:
        raise ParameterError(f"joints={joints!r}: give distinct joint names or indices")
    return tuple(out)


def reach(model: Any) -> float:
    """Sum of the chain's link offsets in [m] (an upper bound of the base-to-tip distance)."""
    arrays = _arrays(model)
    return float(np.sum(np.linalg.norm(arrays.trans, axis=1)))


def plot_joints(model: Any, rows: Any = None) -> tuple[int, int]:
    """The two joints a 2-D heat map should show by default.

    Joints that appear in the singular families' equations first (most equations first),
    then the last joints of the chain (the first revolute joint of a leg only rotates ``J``).
    """
    mdl = _model(model)
    if mdl.nq < 2:
        raise ParameterError(f"plot_joints: {mdl.name!r} has {mdl.nq} joint; two are needed")
    deriv = _derivation_for(mdl, _rows(mdl, rows))
    score = np.zeros(mdl.nq)
    if deriv is not None:
        for fam in deriv.families:
            for v in fam.variables:
                score[v] += 1
    # Only joints that move the tip (a whole hexapod has 15 that do not move one foot).
    moving = sorted(set(int(c) for c in _arrays(mdl).col))
    candidates = moving if len(moving) >= 2 else list(range(mdl.nq))
    order = sorted(candidates, key=lambda j: (-score[j], -j))
    first = order[0]
    if score[first] > 0 and np.count_nonzero(score) == 1:
        rest = [j for j in candidates if j != first and not mdl.is_prismatic[j]]
        second = rest[0] if rest else order[1]
    else:
        second = order[1]
    a, b = sorted((first, second))
    return a, b


def _grid_points(
    model: Any, joints: tuple[int, ...], grid: Any, q_fixed: np.ndarray
) -> tuple[np.ndarray, tuple[int, ...]]:
    counts: list[Any] = [grid] * len(joints) if np.isscalar(grid) else list(grid)
    if len(counts) != len(joints):
        raise ParameterError(
            f"grid={grid!r}: one count or one per scanned joint ({len(joints)}) is required"
        )
    shape = []
    for c in counts:
        if isinstance(c, bool) or int(c) != c or int(c) < 2:
            raise ParameterError(f"grid={grid!r}: counts must be integers >= 2")
        shape.append(int(c))
    total = int(np.prod(shape))
    if total > 50_000_000:
        raise ParameterError(f"grid={grid!r} makes {total} configurations; at most 50,000,000")
    axes = [np.linspace(model.lower[j], model.upper[j], c) for j, c in zip(joints, shape)]
    q = np.empty((*shape, model.nq))
    q[...] = q_fixed
    for k, (j, ax) in enumerate(zip(joints, axes)):
        index: list[slice | None] = [None] * len(shape)
        index[k] = slice(None)
        q[..., j] = ax[tuple(index)]  # broadcast along the other grid axes, no meshgrid copies
    return q.reshape(total, model.nq), tuple(shape)


def scan(
    model: Any,
    grid: int | Sequence[int] | None = None,
    samples: int | None = None,
    joints: Sequence[str | int] | str | None = None,
    *,
    rows: str | Sequence[str] | None = None,
    q_fixed: Any = None,
    threshold: float | None = None,
    rtol: float = 1e-2,
    family_tol: float | None = None,
    families: bool = True,
    seed: int | None = 0,
    progress: bool | None = None,
    chunk: int = 1_000_000,
) -> ScanResult:
    """Scan joint space (grid or random samples) for singularity measures and singular families.

    Args:
        model: A loaded model or any source for :func:`~hexapod_kin.kinematics.load` (a
            preset name, a Chain, a URDF path, ``erd:NAME`` ...).
        grid: Points per scanned joint (one count, or one per joint), spanning the joint
            limits (ends included). Default 41 when ``samples`` is not given either.
        samples: Number of uniform random configurations within the limits (instead of a grid).
        joints: Joints to scan (names or indices); default all. The others stay at ``q_fixed``.
        rows: Row selection of ``J`` (``("x", "y", "z", "wz")``, ``"position"``, ``"all"``);
            default :func:`default_rows`.
        q_fixed: Values of the joints not scanned (default neutral, i.e. zeros).
        threshold: ``sigma_min`` below which a configuration is flagged singular; default
            ``rtol × reach(model)``.
        rtol: Relative threshold (see ``threshold``).
        family_tol: Largest joint-space distance in [rad] from a flagged configuration to a
            family for it to count as lying on it; default ``15 × rtol``. (Near a family
            ``σmin ≈ s·d`` with ``s`` a lever arm in [m/rad]; with ``threshold = rtol·reach``
            flagged points lie within ``rtol·reach/s``, so the default allows ``s ≥ reach/15``.)
        families: Derive the families (sympy, cached per chain) and assign flagged points.
        seed: Random seed for ``samples``.
        progress: Show a tqdm bar on stderr (default: when N > 2,000,000 and stderr is a tty).
        chunk: Configurations per kernel call (progress granularity).

    Returns:
        The :class:`ScanResult`.

    Raises:
        ParameterError: Both or invalid ``grid``/``samples``, unknown joints or rows.
        ConfigurationError: Bad ``q_fixed``.

    """
    mdl = _model(model)
    names = _rows(mdl, rows)
    jidx = _joint_indices(mdl, joints)
    qf = mdl.neutral() if q_fixed is None else mdl.check_q(q_fixed, "q_fixed").copy()
    if grid is not None and samples is not None:
        raise ParameterError("scan: give grid= or samples=, not both")
    if samples is not None:
        if isinstance(samples, bool) or int(samples) != samples or not 1 <= samples <= 50_000_000:
            raise ParameterError(f"samples={samples!r}: an integer in 1..50,000,000 is required")
        rng = np.random.default_rng(seed)
        q = np.empty((int(samples), mdl.nq))
        q[:] = qf
        for j in jidx:
            q[:, j] = rng.uniform(mdl.lower[j], mdl.upper[j], int(samples))
        shape = None
    else:
        q, shape = _grid_points(mdl, jidx, 41 if grid is None else grid, qf)
    n = q.shape[0]
    out = tuple(np.empty(n) for _ in range(4))
    show = (n > 2_000_000 and sys.stderr.isatty()) if progress is None else bool(progress)
    bar = None
    if show:
        from tqdm import tqdm

        bar = tqdm(total=n, file=sys.stderr, unit="cfg", desc="scan", leave=False)
    try:
        for start in range(0, n, max(int(chunk), 1)):
            stop = min(n, start + max(int(chunk), 1))
            measures_batch(
                mdl, q[start:stop], names, out=tuple(o[start:stop] for o in out)
            )
            if bar is not None:
                bar.update(stop - start)
    finally:
        if bar is not None:
            bar.close()
    det, manip, cond, smin = out
    thr = float(rtol * reach(mdl)) if threshold is None else float(threshold)
    if not math.isfinite(thr) or thr < 0:
        raise ParameterError(f"threshold={threshold!r}: a finite value >= 0 is required")
    singular = smin < thr
    family = np.full(n, -1, dtype=np.int64)
    fams: tuple[SingularFamily, ...] = ()
    funcs = None
    if families:
        deriv = _derivation_for(mdl, names)
        if deriv is not None and deriv.families:
            funcs = _family_functions(deriv)
            fams = funcs.families
            idx = np.flatnonzero(singular)
            if idx.size:
                dist = funcs.distance(q[idx])
                best = np.argmin(dist, axis=1)
                tol = 15.0 * rtol if family_tol is None else float(family_tol)
                ok = dist[np.arange(idx.size), best] <= tol
                family[idx[ok]] = best[ok]
    return ScanResult(
        q=_ro(q),
        det=_ro(det),
        manipulability=_ro(manip),
        condition=_ro(cond),
        sigma_min=_ro(smin),
        singular=_ro(singular),
        family=_ro(family),
        families=fams,
        joint_names=tuple(mdl.joint_names),
        joints=jidx,
        rows=names,
        threshold=thr,
        grid_shape=shape,
        q_fixed=_ro(qf),
        source=mdl.name,
        _family_funcs=funcs,
    )


# ------------------------------------------------------------------------ workspace
@dataclass(frozen=True)
class WorkspaceResult:
    """Reachable tip points and a reachable-volume estimate (arrays read-only).

    The volume is a Monte Carlo voxel count: the tip positions of ``samples`` uniform random
    configurations are binned into cubic voxels of edge ``voxel``. Occupied voxels with all
    six face neighbours occupied count fully; boundary voxels (an empty neighbour) count
    half, since the boundary surface cuts them on average through the middle:
    ``volume = (interior + boundary / 2) · voxel³``; ``volume_occupied`` counts every occupied
    voxel (an over-estimate). Checked against closed forms (a spherical shell, the hexabot
    leg's solid of revolution) to about 4 % with the defaults. Meaningful for chains whose
    workspace is a solid (≥ 3 joints acting on the position).

    Attributes:
        q: The sampled configurations (N, n).
        points: Tip positions (N, 3) in [m], base frame.
        voxel: Voxel edge in [m].
        volume_occupied: Occupied voxels × voxel³ in [m³].
        volume: The boundary-corrected estimate in [m³].
        interior: Number of interior voxels.
        boundary: Number of boundary voxels.
        lower: Bounding-box corner (3,) in [m].
        upper: Bounding-box corner (3,) in [m].
        source: The model's name.

    """

    q: np.ndarray
    points: np.ndarray
    voxel: float
    volume_occupied: float
    volume: float
    interior: int
    boundary: int
    lower: np.ndarray
    upper: np.ndarray
    source: str


def _voxel_counts(points: np.ndarray, h: float) -> tuple[int, int]:
    lower = points.min(axis=0) - h
    idx = np.floor((points - lower) / h).astype(np.int64)
    dims = idx.max(axis=0) + 2
    occ = np.zeros(tuple(int(d) for d in dims), dtype=bool)
    occ[idx[:, 0], idx[:, 1], idx[:, 2]] = True
    pad = np.pad(occ, 1)
    inner = occ.copy()
    for ax in range(3):
        for shift in (1, -1):
            inner &= np.roll(pad, shift, axis=ax)[1:-1, 1:-1, 1:-1]
    n_inner = int(inner.sum())
    return n_inner, int(occ.sum()) - n_inner


def workspace(
    model: Any,
    samples: int = 2_000_000,
    voxel: float | None = None,
    seed: int | None = 0,
) -> WorkspaceResult:
    """Reachable tip points of random configurations and a reachable-volume estimate.

    Args:
        model: A loaded model or a source.
        samples: Number of uniform random configurations within the joint limits.
        voxel: Voxel edge in [m]; default ``reach / 25`` (finer voxels need more samples:
            empty voxels inside the workspace bias the estimate low).
        seed: Random seed.

    Returns:
        The :class:`WorkspaceResult` (see its docstring for how the volume is estimated).

    Raises:
        ParameterError: ``samples`` out of range or ``voxel`` not > 0.

    """
    mdl = _model(model)
    if isinstance(samples, bool) or int(samples) != samples or not 1 <= samples <= 50_000_000:
        raise ParameterError(f"samples={samples!r}: an integer in 1..50,000,000 is required")
    h = reach(mdl) / 25.0 if voxel is None else float(voxel)
    if not math.isfinite(h) or h <= 0:
        raise ParameterError(f"voxel={voxel!r}: a finite edge > 0 m is required")
    q = mdl.random_q(int(samples), seed=seed)
    pts = _kernels.fk_batch(_arrays(mdl), q)
    span = float(np.ptp(pts, axis=0).max())
    if span / h > 2000:
        raise ParameterError(f"voxel={h!r} m is too small for a workspace {span:.3g} m wide")
    n_in, n_b = _voxel_counts(pts, h)
    return WorkspaceResult(
        q=_ro(q),
        points=_ro(pts),
        voxel=h,
        volume_occupied=(n_in + n_b) * h**3,
        volume=(n_in + 0.5 * n_b) * h**3,
        interior=n_in,
        boundary=n_b,
        lower=_ro(pts.min(axis=0)),
        upper=_ro(pts.max(axis=0)),
        source=mdl.name,
    )


def cross_section(
    points: np.ndarray, plane: str = "xz", offset: float = 0.0, thickness: float | None = None
) -> np.ndarray:
    """Points of a workspace in a slab around a coordinate plane, as 2-D coordinates.

    Args:
        points: Tip positions (N, 3) in [m].
        plane: ``"xz"``, ``"yz"`` or ``"xy"`` (the two kept coordinates, in that order).
        offset: Position of the plane along the dropped axis in [m].
        thickness: Slab thickness in [m]; default 1 % of the points' extent.

    Returns:
        (M, 2) coordinates of the points with ``|coordinate − offset| ≤ thickness / 2``.

    Raises:
        ParameterError: Unknown plane or bad thickness.

    """
    planes = {"xz": (0, 2, 1), "yz": (1, 2, 0), "xy": (0, 1, 2)}
    if plane not in planes:
        raise ParameterError(f"plane={plane!r} is not allowed; use one of {choices(planes)}")
    a, b, c = planes[plane]
    pts = np.asarray(points, float)
    if thickness is None:
        thickness = 0.01 * float(np.ptp(pts, axis=0).max() or 1.0)
    if not math.isfinite(thickness) or thickness <= 0:
        raise ParameterError(f"thickness={thickness!r}: a finite value > 0 m is required")
    keep = np.abs(pts[:, c] - offset) <= thickness / 2
    return pts[keep][:, [a, b]].copy()
