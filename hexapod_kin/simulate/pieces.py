"""Convex pieces of a concave collision mesh, for a simulator that collides convex hulls.

MuJoCo collides a mesh geom as the convex hull of its vertices. For a concave part that hull
fills the hollows: CHAMP's base is an "H" (plates 290 mm wide at its ends and middle, a 30 mm
spine between them where the hips sit), and its hull, a 290 mm box, meets the upper legs
wherever a hip swings them in by a few degrees, where the real base has no material.

:func:`convex_pieces` cuts such a mesh into :data:`SLABS` slabs along each of its frame's
axes (each triangle clipped exactly: its vertices between the two planes and its edges'
crossings of them), keeps the axis whose slabs' hulls have the least volume, and merges
neighbouring slabs while their joint hull exceeds the two by at most :data:`MERGE_TOL` of the
smaller one (a thin spine does not merge into the plate beside it: the wedge between them is
hollow).
A mesh whose slabs' hulls fill :data:`CONVEX_FILL` of its hull or more is convex enough: it
stays one hull (its vertices' as before). Every piece lies inside the mesh's hull, so a
contact of the pieces is one of the hull.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["CONVEX_FILL", "MERGE_TOL", "SLABS", "convex_pieces", "triangles"]

#: Slabs per axis.
SLABS = 16
#: A mesh whose slabs' hulls fill less than this share of its hull's volume is cut.
CONVEX_FILL = 0.9
#: Neighbouring pieces merge while their hull exceeds the two by at most this share of the
#: smaller one's volume.
MERGE_TOL = 0.05


def triangles(shape: Any) -> np.ndarray | None:
    """(T, 3, 3) the triangles of a Coal BVH mesh (its frame) [m], else None."""
    n = int(getattr(shape, "num_tris", 0) or 0)
    if n == 0 or not hasattr(shape, "tri_indices"):
        return None
    v = np.asarray(shape.vertices(), dtype=float).reshape(-1, 3)
    idx = np.array([[t[0], t[1], t[2]] for t in map(shape.tri_indices, range(n))], dtype=int)
    return v[idx]


def _volume(p: np.ndarray) -> float:
    from scipy.spatial import ConvexHull, QhullError

    if len(p) < 4:
        return 0.0
    try:
        return float(ConvexHull(p).volume)
    except QhullError:  # flat: no volume
        return 0.0


def _slabs(tris: np.ndarray, axis: int, cuts: np.ndarray) -> list[np.ndarray]:
    """The points of each slab ``cuts[k] <= x[axis] <= cuts[k + 1]`` of the clipped triangles."""
    start, end = tris, np.roll(tris, -1, axis=1)  # the edges (T, 3, 3)
    a, b = start[..., axis], end[..., axis]
    crossings = []
    for c in cuts:
        hit = (a - c) * (b - c) < 0
        s = ((c - a[hit]) / (b[hit] - a[hit]))[:, None]
        crossings.append(start[hit] + s * (end[hit] - start[hit]))
    verts = tris.reshape(-1, 3)
    out = []
    for k in range(len(cuts) - 1):
        inside = verts[(verts[:, axis] >= cuts[k]) & (verts[:, axis] <= cuts[k + 1])]
        out.append(np.vstack([inside, crossings[k], crossings[k + 1]]))
    return out


def convex_pieces(tris: np.ndarray) -> list[np.ndarray] | None:
    """The points of each convex piece of a concave mesh (see the module's docstring).

    Args:
        tris: (T, 3, 3) the mesh's triangles [m].

    Returns:
        One (P, 3) array per piece, or None when the mesh is convex enough for one hull.

    """
    whole = _volume(tris.reshape(-1, 3))
    if not whole > 0:
        return None
    best: tuple[float, list[np.ndarray], list[float]] | None = None
    for axis in range(3):
        lo, hi = float(tris[..., axis].min()), float(tris[..., axis].max())
        if not hi > lo:
            continue
        slabs = _slabs(tris, axis, np.linspace(lo, hi, SLABS + 1))
        vols = [_volume(p) for p in slabs]
        if best is None or sum(vols) < best[0]:
            best = (sum(vols), slabs, vols)
    if best is None or best[0] >= CONVEX_FILL * whole:
        return None
    _, pieces, vols = best
    while len(pieces) > 1:
        joined = [np.vstack([pieces[i], pieces[i + 1]]) for i in range(len(pieces) - 1)]
        grown = [_volume(p) - vols[i] - vols[i + 1] for i, p in enumerate(joined)]
        share = [g / max(min(vols[i], vols[i + 1]), 1e-300) for i, g in enumerate(grown)]
        i = int(np.argmin(share))
        if grown[i] > MERGE_TOL * min(vols[i], vols[i + 1]):
            break
        pieces[i : i + 2] = [joined[i]]
        vols[i : i + 2] = [vols[i] + vols[i + 1] + grown[i]]
    return pieces
