"""Collision primitives and STL visuals (trimesh) for URDF text as ``to_urdf`` writes it.

:func:`add_collisions` gives every primitive visual but the joint markers a ``<collision>``
twin; :func:`mesh_visuals` replaces each link's visuals by one STL per material. Kinematics
and inertials are untouched.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..exceptions import UrdfError
from ..params import rpy_to_matrix
from ._common import held_interrupt, need

__all__ = ["add_collisions", "mesh_visuals", "MeshedUrdf", "COLLIDING_MATERIALS"]

#: Visual materials whose primitives get a collision twin (joint markers stay visual only).
COLLIDING_MATERIALS = ("link", "foot", "body", "base")


def _parse(text: str) -> Any:
    from lxml import etree

    parser = etree.XMLParser(remove_blank_text=False)
    try:
        return etree.fromstring(text.encode("utf-8"), parser).getroottree()
    except etree.XMLSyntaxError as exc:
        raise UrdfError(f"URDF text is not well-formed XML: {exc}") from None


def _serialize(tree: Any) -> str:
    from lxml import etree

    root = tree.getroot()
    prolog = [
        etree.tostring(c, encoding="unicode").strip() for c in root.itersiblings(preceding=True)
    ]
    root_text = etree.tostring(root, encoding="unicode", with_tail=False)
    lines = ['<?xml version="1.0" encoding="utf-8"?>', *reversed(prolog), root_text]
    return "\n".join(lines) + "\n"


def _material(visual: Any) -> str:
    mat = visual.find("material")
    return "" if mat is None else str(mat.get("name", ""))


def add_collisions(urdf_text: str) -> str:
    """``urdf_text`` with a primitive ``<collision>`` per colliding visual (deterministic).

    Links with collision elements are left as they are; a body box holding leg mounts
    collides trimmed to leave them outside (:func:`_clip_box`).

    Raises:
        UrdfError: If the text is not XML.

    """
    from lxml import etree

    tree = _parse(urdf_text)
    root = tree.getroot()
    for link in root.iter("link"):
        if link.find("collision") is not None:
            continue
        mounts = [
            _origin_matrix(j)[:3, 3]
            for j in root.iter("joint")
            if j.find("parent") is not None and j.find("parent").get("link") == link.get("name")
        ]
        for visual in link.findall("visual"):
            geom = visual.find("geometry")
            if geom is None or _material(visual) not in COLLIDING_MATERIALS:
                continue
            if geom.find("mesh") is not None:  # a mesh visual has no primitive twin
                continue
            coll = etree.Element("collision")
            origin = visual.find("origin")
            if origin is not None:
                coll.append(copy.deepcopy(origin))
            coll.append(copy.deepcopy(geom))
            box = coll.find("geometry/box")
            if box is not None and mounts and _material(visual) == "body":
                inv = np.linalg.inv(_origin_matrix(visual))
                local = [inv[:3, :3] @ p + inv[:3, 3] for p in mounts]
                trimmed = _clip_box(_floats(box.get("size"), 3), local)
                if trimmed is not None:
                    box.set("size", trimmed)
            coll.tail = visual.tail
            link.append(coll)
    return _serialize(tree)


def _clip_box(size: np.ndarray, points: list[np.ndarray]) -> str | None:
    """The box ``size`` trimmed along x or y (the larger) to leave ``points`` out (or None)."""
    half = 0.5 * np.asarray(size, dtype=float)
    inside = [p for p in points if np.all(np.abs(p) < half - 1e-12)]
    if not inside:
        return None
    best = half
    for axis in (0, 1):
        trimmed = half.copy()
        trimmed[axis] = min(abs(float(p[axis])) for p in inside)
        if trimmed[axis] > 0 and (best is half or np.prod(trimmed) > np.prod(best)):
            best = trimmed
    return None if best is half else " ".join(f"{v:.6g}" for v in 2.0 * best)


def _floats(text: str | None, n: int, default: float = 0.0) -> np.ndarray:
    if text is None:
        return np.full(n, default)
    vals = np.array([float(v) for v in text.split()], dtype=float)
    if vals.shape != (n,):
        raise UrdfError(f"expected {n} numbers, got {text!r}")
    return vals


def _origin_matrix(elem: Any) -> np.ndarray:
    t = np.eye(4)
    origin = elem.find("origin")
    if origin is not None:
        t[:3, :3] = rpy_to_matrix(*_floats(origin.get("rpy"), 3))
        t[:3, 3] = _floats(origin.get("xyz"), 3)
    return t


def _primitive(geom: Any, material: str) -> Any:
    """A trimesh of one URDF primitive (about its own origin), or ``None`` for a mesh."""
    trimesh = need("trimesh")
    sphere, cyl, box = geom.find("sphere"), geom.find("cylinder"), geom.find("box")
    if sphere is not None:
        return trimesh.creation.icosphere(subdivisions=2, radius=float(sphere.get("radius")))
    if cyl is not None:
        radius, length = float(cyl.get("radius")), float(cyl.get("length"))
        if material == "link":
            # A capsule: the segment with rounded ends (height = distance between the caps).
            return trimesh.creation.capsule(height=length, radius=radius, count=[24, 12])
        return trimesh.creation.cylinder(radius=radius, height=length, sections=24)
    if box is not None:
        return trimesh.creation.box(extents=_floats(box.get("size"), 3))
    return None


@dataclass(frozen=True)
class MeshedUrdf:
    """A URDF whose visuals are STL meshes, and ``files``: name (no prefix) → STL bytes, sorted."""

    urdf: str
    files: dict[str, bytes]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary: the mesh file names and sizes in [bytes]."""
        return {"files": {k: len(v) for k, v in self.files.items()}}


def mesh_visuals(urdf_text: str, uri_prefix: str) -> MeshedUrdf:
    """Replace the primitive visuals of every link by STL meshes (one per link and material).

    Collision primitives are added first (:func:`add_collisions`); ``uri_prefix`` goes before
    each file name in ``<mesh filename=...>`` (e.g. ``"meshes/"``).

    Raises:
        OptionalDependencyError: If trimesh is not installed.
        UrdfError: If the text is not a URDF.

    """
    trimesh = need("trimesh")
    tree = _parse(add_collisions(urdf_text))
    files: dict[str, bytes] = {}
    with held_interrupt() as check:  # trimesh swallows a KeyboardInterrupt: checked per link
        for link in tree.getroot().iter("link"):
            check()
            _mesh_link(trimesh, link, uri_prefix, files)
    return MeshedUrdf(urdf=_serialize(tree), files=dict(sorted(files.items())))


def _mesh_link(trimesh: Any, link: Any, uri_prefix: str, files: dict[str, bytes]) -> None:
    """Replace the primitive visuals of ``link`` by STL meshes, added to ``files``."""
    from lxml import etree

    visuals = link.findall("visual")
    groups: dict[str, list[Any]] = {}
    for visual in visuals:
        geom = visual.find("geometry")
        mesh = None if geom is None else _primitive(geom, _material(visual))
        if mesh is None:
            continue
        mesh.apply_transform(_origin_matrix(visual))
        groups.setdefault(_material(visual), []).append(mesh)
        link.remove(visual)
    anchor = link.find("collision")
    for material in sorted(groups):
        combined = trimesh.util.concatenate(groups[material])
        fname = f"{link.get('name')}_{material or 'visual'}.stl"
        files[fname] = bytes(trimesh.exchange.stl.export_stl(combined))
        visual = etree.Element("visual")
        etree.SubElement(visual, "origin", xyz="0 0 0", rpy="0 0 0")
        geometry = etree.SubElement(visual, "geometry")
        etree.SubElement(geometry, "mesh", filename=f"{uri_prefix}{fname}")
        if material:
            etree.SubElement(visual, "material", name=material)
        visual.tail = "\n    "
        if anchor is not None:
            anchor.addprevious(visual)
        else:
            link.append(visual)
