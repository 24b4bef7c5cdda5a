"""Mesh geometry for the viewer: a loaded mesh as a compact indexed three.js geometry.

The mesh as Pinocchio loaded it (its BVH: vertices in [m], scale applied), so every format
Pinocchio reads draws the same. Positions are quantised to int16 on the bounding box (the
dequantisation is the object's matrix); indices are uint16 below 65,536 vertices, else
uint32; normals are optional (the offline page computes them).
A robot whose meshes are missing gets a stick figure instead (:func:`add_sticks`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .objects import attribute, translation

__all__ = ["MeshGeometry", "add_sticks", "mesh_geometry"]

#: Stick radius as a fraction of the robot's longest joint-to-joint segment.
STICK_RADIUS_FRACTION = 0.05
#: Stick colour (RGBA).
STICK_RGBA = (0.35, 0.38, 0.45, 1.0)

#: Largest magnitude of a quantised coordinate.
QUANT_MAX = 32767


@dataclass(frozen=True)
class MeshGeometry:
    """A mesh as a BufferGeometry, its counts and ``matrix``: quantised → mesh coordinates [m]."""

    data: dict[str, Any]
    matrix: np.ndarray
    vertices: int
    triangles: int


def _corners(tri: Any) -> tuple[int, int, int]:
    return int(tri[0]), int(tri[1]), int(tri[2])  # a Coal Triangle has no len(): no tuple()


def _mesh_arrays(geometry: Any) -> tuple[np.ndarray, np.ndarray] | None:
    """Vertices (V, 3) [m] and triangles (T, 3) of a loaded mesh (a BVH), or None if empty."""
    try:
        verts = np.asarray(geometry.vertices(), dtype=np.float64).reshape(-1, 3)
        count = int(geometry.num_tris)
        corners = [_corners(geometry.tri_indices(i)) for i in range(count)]
        tris = np.array(corners, dtype=np.int64).reshape(-1, 3)
    except (AttributeError, RuntimeError, TypeError, ValueError):
        return None
    empty = not len(verts) or not len(tris) or not np.all(np.isfinite(verts))
    return None if empty or tris.min() < 0 or tris.max() >= len(verts) else (verts, tris)


def _quantise(verts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Int16 coordinates of ``verts`` (V, 3) and the 4×4 matrix back to [m]."""
    lo, hi = verts.min(axis=0), verts.max(axis=0)
    center = (lo + hi) / 2
    step = max(float(np.max(hi - lo)) / (2 * QUANT_MAX), 1e-12)
    q = np.clip(np.rint((verts - center) / step), -QUANT_MAX, QUANT_MAX).astype(np.int16)
    return q, translation(center) @ np.diag([step, step, step, 1.0])


def _vertex_normals(verts: np.ndarray, tris: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals (V, 3) (as three.js ``computeVertexNormals``)."""
    a, b, c = verts[tris[:, 0]], verts[tris[:, 1]], verts[tris[:, 2]]
    face = np.cross(b - a, c - a)
    out = np.zeros_like(verts)
    for k in range(3):
        np.add.at(out, tris[:, k], face)
    norm = np.linalg.norm(out, axis=1, keepdims=True)
    return np.asarray(np.where(norm > 0, out / np.maximum(norm, 1e-300), [0.0, 0.0, 1.0]))


def mesh_geometry(geometry: Any, *, normals: bool) -> MeshGeometry | None:
    """The compact geometry of a Pinocchio/Coal BVH (with float32 ``normals``), or None: empty."""
    arrays = _mesh_arrays(geometry)
    if arrays is None:
        return None
    verts, tris = arrays
    q, matrix = _quantise(verts)
    index = tris.astype(np.uint16 if len(verts) <= 65536 else np.uint32)
    attributes: dict[str, Any] = {"position": attribute(q, 3)}
    if normals:  # of the quantised mesh: what the browser would compute
        normal = _vertex_normals(q.astype(np.float64), tris).astype(np.float32)
        attributes["normal"] = attribute(normal, 3)
    data = {"attributes": attributes, "index": attribute(index, 1)}
    return MeshGeometry({"type": "BufferGeometry", "data": data}, matrix, len(verts), len(tris))


def add_sticks(model: Any, geom: Any) -> int:
    """Add sticks to the visual ``geom`` of the Pinocchio ``model`` where joints carry none.

    Per such joint (the base included), a cylinder from its origin to each child joint's
    origin and each body or fixed-joint frame on it, else to its centre of mass; in place.
    Returns the number of sticks added.
    """
    import coal
    import pinocchio as pin

    drawn = {int(go.parentJoint) for go in geom.geometryObjects}
    ends: dict[int, list[np.ndarray]] = {}
    for j in range(1, model.njoints):
        ends.setdefault(int(model.parents[j]), []).append(model.jointPlacements[j].translation)
    for f in model.frames:
        if f.type in (pin.FrameType.BODY, pin.FrameType.FIXED_JOINT):
            ends.setdefault(int(f.parentJoint), []).append(f.placement.translation)
    for j in range(1, model.njoints):  # nothing beyond the joint: to the centre of mass
        if not any(np.linalg.norm(p) > 1e-6 for p in ends.get(j, [])):
            ends.setdefault(j, []).append(model.inertias[j].lever)
    segments = [
        (j, np.array(p, dtype=float))
        for j, points in sorted(ends.items())
        if j not in drawn
        for p in points
        if np.linalg.norm(p) > 1e-6
    ]
    if not segments:
        return 0
    longest = max(float(np.linalg.norm(p)) for _, p in segments)
    radius = max(STICK_RADIUS_FRACTION * longest, 1e-4)
    for k, (j, p) in enumerate(segments):
        length = float(np.linalg.norm(p))
        z = p / length
        x = np.cross(z, [1.0, 0.0, 0.0] if abs(z[0]) < 0.9 else [0.0, 1.0, 0.0])
        x /= np.linalg.norm(x)
        rot = np.column_stack([x, np.cross(z, x), z])  # the cylinder's axis z along the stick
        go = pin.GeometryObject(
            f"stick_{model.names[j]}_{k}", j, pin.SE3(rot, p / 2), coal.Cylinder(radius, length)
        )
        go.meshColor = np.array(STICK_RGBA)
        geom.addGeometryObject(go)
    return len(segments)
