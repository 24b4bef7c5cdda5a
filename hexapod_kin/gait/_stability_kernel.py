"""The compiled gait checks (numba): support margin and leg clearance over many samples.

Used by :mod:`hexapod_kin.gait.stability` above its size threshold (the batch side of the
size rule); the numpy side there is the per-command engine. Both compute the same quantities
(tests hold them equal to 1e-12 on random inputs).
"""

from __future__ import annotations

import math

import numpy as np

from .._kernels import njit

__all__: list[str] = []


@njit(cache=True, inline="always")
def _cross(ox: float, oy: float, ax: float, ay: float, bx: float, by: float) -> float:
    return (ax - ox) * (by - oy) - (ay - oy) * (bx - ox)  # pragma: no cover - compiled


@njit(cache=True, inline="always")
def _seg_point(ax: float, ay: float, bx: float, by: float, px: float, py: float) -> float:
    """Distance from p to the segment ab (2-D)."""
    dx, dy = bx - ax, by - ay  # pragma: no cover - compiled
    ll = dx * dx + dy * dy
    t = 0.0
    if ll > 0.0:
        t = ((px - ax) * dx + (py - ay) * dy) / ll
        t = min(max(t, 0.0), 1.0)
    ex, ey = ax + t * dx - px, ay + t * dy - py
    return math.sqrt(ex * ex + ey * ey)


@njit(cache=True)
def _margin_kernel(
    pts: np.ndarray, mask: np.ndarray, com: np.ndarray, out: np.ndarray
) -> None:  # pragma: no cover - compiled
    n, m = mask.shape
    xs = np.empty(m)
    ys = np.empty(m)
    hx = np.empty(2 * m + 1)
    hy = np.empty(2 * m + 1)
    for i in range(n):
        k = 0
        for j in range(m):  # gather, insertion-sorted by (x, y)
            if mask[i, j]:
                x, y = pts[i, j, 0], pts[i, j, 1]
                p = k
                while p > 0 and (xs[p - 1] > x or (xs[p - 1] == x and ys[p - 1] > y)):
                    xs[p] = xs[p - 1]
                    ys[p] = ys[p - 1]
                    p -= 1
                xs[p] = x
                ys[p] = y
                k += 1
        px, py = com[i, 0], com[i, 1]
        if k == 0:
            out[i] = -np.inf
            continue
        # Andrew's monotone chain, counter-clockwise, collinear points dropped
        h = 0
        for j in range(k):
            while h >= 2 and _cross(hx[h - 2], hy[h - 2], hx[h - 1], hy[h - 1], xs[j], ys[j]) <= 0:
                h -= 1
            hx[h] = xs[j]
            hy[h] = ys[j]
            h += 1
        lo = h + 1
        for j in range(k - 2, -1, -1):
            while h >= lo and _cross(hx[h - 2], hy[h - 2], hx[h - 1], hy[h - 1], xs[j], ys[j]) <= 0:
                h -= 1
            hx[h] = xs[j]
            hy[h] = ys[j]
            h += 1
        h -= 1  # the last point repeats the first
        if h <= 0:
            h = 1
        if h == 1:
            out[i] = -math.sqrt((hx[0] - px) ** 2 + (hy[0] - py) ** 2)
            continue
        if h == 2:
            out[i] = -_seg_point(hx[0], hy[0], hx[1], hy[1], px, py)
            continue
        inside = True
        dmin = np.inf
        for j in range(h):
            ax, ay = hx[j], hy[j]
            bx, by = hx[(j + 1) % h], hy[(j + 1) % h]
            ll = math.sqrt((bx - ax) ** 2 + (by - ay) ** 2)
            c = _cross(ax, ay, bx, by, px, py) / ll  # signed distance to the edge's line
            if c < 0:
                inside = False
            dmin = min(dmin, _seg_point(ax, ay, bx, by, px, py))
        out[i] = dmin if inside else -dmin


@njit(cache=True, inline="always")
def _seg_seg(
    px: float,
    py: float,
    pz: float,
    ux: float,
    uy: float,
    uz: float,
    qx: float,
    qy: float,
    qz: float,
    vx: float,
    vy: float,
    vz: float,
) -> float:  # pragma: no cover - compiled
    """Distance between segments p→p+u and q→q+v in 3-D.

    Ericson, Real-Time Collision Detection, 5.1.9 (closest points of two segments).
    """
    rx, ry, rz = px - qx, py - qy, pz - qz
    a = ux * ux + uy * uy + uz * uz
    e = vx * vx + vy * vy + vz * vz
    f = vx * rx + vy * ry + vz * rz
    eps = 1e-18
    if a <= eps and e <= eps:
        s = 0.0
        t = 0.0
    elif a <= eps:
        s = 0.0
        t = min(max(f / e, 0.0), 1.0)
    else:
        c = ux * rx + uy * ry + uz * rz
        if e <= eps:
            t = 0.0
            s = min(max(-c / a, 0.0), 1.0)
        else:
            b = ux * vx + uy * vy + uz * vz
            den = a * e - b * b
            s = min(max((b * f - c * e) / den, 0.0), 1.0) if den > 1e-12 * a * e else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = min(max(-c / a, 0.0), 1.0)
            elif t > 1.0:
                t = 1.0
                s = min(max((b - c) / a, 0.0), 1.0)
    dx = rx + ux * s - vx * t
    dy = ry + uy * s - vy * t
    dz = rz + uz * s - vz * t
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@njit(cache=True)
def _clearance_kernel(
    pts: np.ndarray, pairs: np.ndarray, out: np.ndarray
) -> None:  # pragma: no cover - compiled
    n, _, k, _ = pts.shape
    for i in range(n):
        for q in range(pairs.shape[0]):
            a, b = pairs[q, 0], pairs[q, 1]
            best = np.inf
            for u in range(k - 1):
                px, py, pz = pts[i, a, u, 0], pts[i, a, u, 1], pts[i, a, u, 2]
                ux, uy, uz = (
                    pts[i, a, u + 1, 0] - px,
                    pts[i, a, u + 1, 1] - py,
                    pts[i, a, u + 1, 2] - pz,
                )
                for v in range(k - 1):
                    qx, qy, qz = pts[i, b, v, 0], pts[i, b, v, 1], pts[i, b, v, 2]
                    d = _seg_seg(
                        px,
                        py,
                        pz,
                        ux,
                        uy,
                        uz,
                        qx,
                        qy,
                        qz,
                        pts[i, b, v + 1, 0] - qx,
                        pts[i, b, v + 1, 1] - qy,
                        pts[i, b, v + 1, 2] - qz,
                    )
                    if d < best:
                        best = d
            out[i, q] = best
