"""The robot's own collision geometry, read through Pinocchio, for the MuJoCo scene.

:func:`foot_radius_of` (the feet's radius from the foot links' shapes),
:func:`collision_hulls` (mesh collisions of body and legs as convex hulls, the feet's own
shapes left to the scene's foot spheres) and :func:`foot_spheres` (feet at the round ends
of the meshes that carry them). All read the geometry Pinocchio built from the URDF
(:meth:`hexapod_kin.model.KinematicModel.geometry_model`), so meshes resolve as for the
viewer.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "MeshHull",
    "add_hulls",
    "collision_hulls",
    "foot_radius_of",
    "foot_spheres",
    "scene_robot",
    "mjcf_asset",
]


@dataclass(frozen=True)
class MeshHull:
    """A mesh collision as its convex hull's vertices.

    Attributes:
        link: The URDF link the shape belongs to (a MuJoCo body of the same name).
        name: The geometry's name.
        vertices: (V, 3) hull vertices in the link's frame [m].

    """

    link: str
    name: str
    vertices: np.ndarray


def _collision_model(wb: Any) -> tuple[Any, Any] | None:
    """``(full model, collision GeometryModel)`` of a robot built from a URDF, else None."""
    km = getattr(wb, "kinematic", None)
    if km is None or not hasattr(km, "geometry_model"):
        return None
    try:
        geom = km.geometry_model("collision")
    except Exception:  # noqa: BLE001 - a robot without readable collisions has none
        return None
    return km.full_model, geom


def _foot_links(wb: Any) -> list[tuple[str, str, np.ndarray]]:
    """Per leg: its foot link, the joint moving it and the foot point in that joint's frame."""
    model = wb.model
    out = []
    for fname in wb.foot_frames:
        frame = model.frames[model.getFrameId(fname)]
        link = model.frames[frame.parentFrame]
        joint = str(model.names[frame.parentJoint])
        out.append((str(link.name), joint, np.asarray(frame.placement.translation, dtype=float)))
    return out


def _vertices(shape: Any) -> np.ndarray | None:
    verts = getattr(shape, "vertices", None)
    if verts is None:
        return None
    v = np.asarray(verts(), dtype=float).reshape(-1, 3)
    return v if len(v) >= 4 else None


def _act(placement: Any, v: np.ndarray) -> np.ndarray:
    """Points ``v`` (V, 3) moved by the rigid transform ``placement`` (``pinocchio.SE3``)."""
    return v @ np.asarray(placement.rotation).T + np.asarray(placement.translation)


def foot_radius_of(wb: Any) -> float | None:
    """The feet's contact radius [m] from the foot links' collision shapes (None: not found).

    Every leg needs a shape centred on its foot point (within a quarter of its size): a
    sphere's, cylinder's or capsule's radius, or a mesh's mean of its two largest bounding-box
    half-extents (a ball or a wheel). The smallest over the legs.
    """
    found = _collision_model(wb)
    if found is None:
        return None
    full, geom = found
    radii = []
    for link, _, point in _foot_links(wb):
        best = None
        for obj in geom.geometryObjects:
            if str(full.frames[obj.parentFrame].name) != link:
                continue
            shape = obj.geometry
            centre_local = np.asarray(obj.placement.actInv(point), dtype=float)
            kind = type(shape).__name__
            if kind in ("Sphere", "Cylinder", "Capsule"):
                r = float(shape.radius)
                if np.linalg.norm(centre_local) <= 0.25 * r + 1e-9:
                    best = r
            else:
                v = _vertices(shape)
                if v is None:
                    continue
                lo, hi = v.min(axis=0), v.max(axis=0)
                half = np.sort(0.5 * (hi - lo))
                r = float(half[1:].mean())
                if r > 0 and np.linalg.norm(0.5 * (lo + hi) - centre_local) <= 0.25 * r:
                    best = r
            if best is not None:
                break
        if best is None:
            return None
        radii.append(best)
    return min(radii) if radii else None


#: A sphere fitted to a mesh's end is the foot when its vertices are within this fraction of
#: the radius of it (or :data:`FIT_TOLERANCE`, the larger) and the foot point is as close.
FIT_RELATIVE = 0.05
FIT_TOLERANCE = 5e-4
#: The depths of the mesh's end tried for the fit, as fractions of the foot point's distance
#: from its joint (the deepest that fits a sphere is taken).
_CAP_DEPTHS = (0.1, 0.05, 0.025)


def _fit_sphere(v: np.ndarray) -> tuple[np.ndarray, float, float]:
    """Least-squares sphere through points ``v`` (V, 3): ``(centre, radius, worst residual)``.

    Kåsa's algebraic fit: ``|x|² = 2 c·x + k`` is linear in the centre ``c`` and
    ``k = r² − |c|²``; the residual is the largest ``| |x − c| − r |``.
    """
    a = np.c_[2.0 * v, np.ones(len(v))]
    sol, *_ = np.linalg.lstsq(a, (v * v).sum(axis=1), rcond=None)
    centre = sol[:3]
    r = float(np.sqrt(max(float(sol[3] + centre @ centre), 0.0)))
    return centre, r, float(np.abs(np.linalg.norm(v - centre, axis=1) - r).max())


def _end_sphere(v: np.ndarray, point: np.ndarray) -> tuple[np.ndarray, float] | None:
    """The sphere of a mesh's round end at the foot point (joint frame), else None.

    The end: the vertices within :data:`_CAP_DEPTHS` × ``|point|`` of the deepest along the
    joint-to-foot direction; found when they and the foot point lie on a sphere
    (:data:`FIT_RELATIVE`, :data:`FIT_TOLERANCE`).
    """
    reach = float(np.linalg.norm(point))
    if reach <= 0 or len(v) < 4:
        return None
    depth = v @ (point / reach)
    for frac in _CAP_DEPTHS:
        cap = v[depth >= depth.max() - frac * reach]
        if len(cap) < 10:
            continue
        centre, r, worst = _fit_sphere(cap)
        tol = max(FIT_RELATIVE * r, FIT_TOLERANCE)
        on = abs(float(np.linalg.norm(point - centre)) - r)
        if 0 < r < 0.5 * reach and worst <= tol and on <= tol:
            return centre, r
    return None


#: Per leg, a frame and a point in it [m] (a foot as ``as_whole_body(feet=...)`` takes it).
FootEnds = tuple[tuple[str, tuple[float, float, float]], ...]


def foot_spheres(wb: Any) -> tuple[FootEnds, float] | None:
    """The feet as the round ends of the meshes that carry them.

    For a robot with no foot radius and no shape centred on its foot points
    (:func:`foot_radius_of`): per leg, the sphere fitted to the round end of a mesh moved by
    the foot's joint that ends at the foot point (:func:`_end_sphere`). The radius is the
    smallest (a larger end's centre moves along the leg by the difference, its lowest point
    kept).

    Returns:
        ``(feet, radius)``: per leg the foot frame's parent frame and the sphere's centre in it
        [m], as :func:`hexapod_kin.gait.as_whole_body` takes ``feet``, and the radius [m]; None
        when the robot has a foot radius, a centred foot shape, or a leg without such an end.

    """
    if float(wb.foot_radius) > 0 or foot_radius_of(wb) is not None:
        return None
    found = _collision_model(wb)
    if found is None:
        return None
    full, geom = found
    model = wb.model
    ends = []
    for fname, (_, joint, point) in zip(wb.foot_frames, _foot_links(wb)):
        best = None
        for obj in geom.geometryObjects:
            if str(full.names[obj.parentJoint]) != joint:
                continue
            v = _vertices(obj.geometry)
            fit = None if v is None else _end_sphere(_act(obj.placement, v), point)
            if fit is not None and (best is None or fit[1] < best[1]):
                best = fit
        if best is None:
            return None
        frame = model.frames[model.getFrameId(fname)]
        ends.append((model.frames[frame.parentFrame], point, best))
    radius = min(r for _, _, (_, r) in ends)
    feet = []
    for parent, point, (centre, r) in ends:
        centre = centre + (r - radius) * point / np.linalg.norm(point)
        local = parent.placement.actInv(centre)
        feet.append((str(parent.name), (float(local[0]), float(local[1]), float(local[2]))))
    return tuple(feet), radius


def scene_robot(robot: Any, feet: Any = None) -> Any:
    """The robot as the simulation plans and builds it: feet at its meshes' round ends.

    :func:`hexapod_kin.gait.as_whole_body` of ``robot`` (and ``feet``), rebuilt with the
    feet and radius of :func:`foot_spheres` when it finds them (the plan then rolls the
    same spheres the scene collides); else that robot unchanged.
    """
    from ..gait import as_whole_body
    from ..gait.legs import FootSpec

    wb = as_whole_body(robot, feet=feet)
    found = foot_spheres(wb)
    if found is None:
        return wb
    ends, radius = found
    specs = tuple(FootSpec(frame, offset) for frame, offset in ends)
    return as_whole_body(wb.kinematic, feet=specs, foot_radius=radius)


def collision_hulls(wb: Any, foot_radius: float) -> list[MeshHull]:
    """The mesh collisions of the body and the legs as convex hull vertices (link frames).

    The foot links' shapes are left out, and so are the vertices within ``2 × foot_radius``
    (at least 5 mm) of a foot point (the scene's foot sphere stands for them).
    """
    found = _collision_model(wb)
    if found is None:
        return []
    full, geom = found
    feet = _foot_links(wb)
    foot_links = {link for link, _, _ in feet}
    keep_out = max(2.0 * foot_radius, 0.005)
    out = []
    for obj in geom.geometryObjects:
        frame = full.frames[obj.parentFrame]
        link, joint = str(frame.name), str(full.names[obj.parentJoint])
        if link in foot_links:
            continue
        v = _vertices(obj.geometry)
        if v is None:
            continue
        v = _act(obj.placement, v)  # in the joint's frame
        for _, fjoint, point in feet:
            if fjoint == joint:
                v = v[np.linalg.norm(v - point, axis=1) > keep_out]
        v = _act(frame.placement.inverse(), v)  # in the link's frame
        if len(v) < 4:
            continue
        from scipy.spatial import ConvexHull, QhullError  # here: robots without meshes skip it

        try:
            hull = ConvexHull(v)
        except QhullError:  # flat or degenerate: no volume to collide
            continue
        out.append(MeshHull(link=link, name=str(obj.name), vertices=v[hull.vertices]))
    return out


def add_hulls(root: Any, bodies: dict[str, Any], wb: Any, r: float) -> None:
    """Add the robot's mesh collisions to an MJCF tree as convex mesh geoms.

    ``root`` the MJCF's root element, ``bodies`` its bodies by name, ``r`` the foot radius
    [m] (:func:`collision_hulls`); each hull a ``<mesh>`` asset of its vertices (MuJoCo
    takes their convex hull) and a massless geom in its link's body.
    """
    from lxml import etree

    from ..export._common import num

    hulls = [h for h in collision_hulls(wb, r) if h.link in bodies]
    if not hulls:
        return
    asset = mjcf_asset(root)
    for k, hull in enumerate(hulls):
        name = f"hk_hull_{k}"
        verts = " ".join(num(float(v)) for v in hull.vertices.ravel())
        etree.SubElement(asset, "mesh", name=name, vertex=verts, inertia="shell")
        etree.SubElement(
            bodies[hull.link],
            "geom",
            name=f"{hull.link}/{hull.name}",
            type="mesh",
            mesh=name,
            mass="0",
            rgba="0.5 0.5 0.6 1",
        )


def mjcf_asset(root: Any) -> Any:
    """The ``<asset>`` element of an MJCF tree (made after ``<compiler>`` if it has none)."""
    from lxml import etree

    asset = root.find("asset")
    if asset is None:
        asset = etree.Element("asset")
        root.find("compiler").addnext(asset)
    return asset
