"""The stated inertia repairs: ``load(..., inertia="collision" | "point")``.

Real files carry inertias no body can have (PhantomX: ``I1 + I2 < I3``); a repair rewrites
every ``<inertial>``, keeping each link's **mass** and **centre of mass**:

* ``"collision"``: the link's collision shapes filled uniformly (the mass shared by volume):
  box ``m (b² + c²) / 12``, cylinder (axis z) ``m (3 r² + l²) / 12`` and ``m r² / 2``, sphere
  ``2 m r² / 5``, a mesh as its scaled bounding box; moved to the centre of mass (parallel
  axes) into the inertial frame. Without a usable shape: the point repair.
* ``"point"``: a solid sphere's of radius :data:`POINT_RADIUS` at the centre of mass.

Both give physical tensors on every link and merged body; massless links get a zero inertia
(a massless moving body stays a defect: mass is not invented).
"""

from __future__ import annotations

import os
import struct
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from lxml import etree

from ..exceptions import UrdfError, one_of
from .meshes import resolve_mesh
from .messages import first_names
from .parse import numbers_of, origin_of, parse_urdf

#: The ``inertia=`` choices: the file's own inertias, or one of the two repairs.
INERTIA_MODES = ("urdf", "collision", "point")
#: Radius [m] of the solid sphere whose inertia ``"point"`` gives each link (1 cm).
POINT_RADIUS = 0.01
#: Largest mesh read for its bounding box by ``"collision"`` (bytes).
MAX_BBOX_MESH_BYTES = 64 * 1024 * 1024


@dataclass
class InertiaRepair:
    """What a repair did: the new document and which links were repaired how."""

    text: str
    mode: str
    from_collision: list[str] = field(default_factory=list)
    as_point: list[str] = field(default_factory=list)
    #: ``(link, why)`` of links that ``"collision"`` could not use (they got the point repair).
    fallbacks: list[tuple[str, str]] = field(default_factory=list)

    def summary(self) -> str:
        """One line: counts and the first few link names of each kind."""
        parts = []
        if self.from_collision:
            parts.append(
                f"{len(self.from_collision)} link(s) from their collision geometry "
                f"({first_names(self.from_collision)})"
            )
        if self.as_point:
            what = "point masses" if self.mode == "point" else "point masses (no usable collision)"
            parts.append(f"{len(self.as_point)} link(s) as {what} ({first_names(self.as_point)})")
        body = "; ".join(parts) if parts else "no link has mass"
        return f"inertia={self.mode!r}: masses and centres of mass kept; {body}"


def check_mode(mode: object) -> str:
    """Return ``mode`` if it is one of :data:`INERTIA_MODES`, else raise ParameterError."""
    return str(one_of("inertia", mode, INERTIA_MODES))


def _stl_vertices(data: bytes) -> np.ndarray:
    """Vertices (N, 3) of a binary or ASCII STL file."""
    if len(data) >= 84:
        (count,) = struct.unpack_from("<I", data, 80)
        if 84 + 50 * count == len(data) and count > 0:
            rec = np.frombuffer(data, np.uint8, 50 * count, 84).reshape(count, 50)
            tri = rec[:, 12:48].copy().view("<f4").reshape(count * 3, 3)
            return tri.astype(np.float64)
    text = data.decode("ascii", errors="replace")
    rows = [ln.split()[1:4] for ln in text.splitlines() if ln.strip().startswith("vertex")]
    return np.array(rows, dtype=np.float64).reshape(-1, 3)


def mesh_bounds(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Axis-aligned bounds ``(lo, hi)`` [mesh units] of a mesh file (STL, OBJ; else trimesh)."""
    size = path.stat().st_size
    if size > MAX_BBOX_MESH_BYTES:
        raise UrdfError(f"{path.name}: {size} bytes, over {MAX_BBOX_MESH_BYTES}")
    suffix = path.suffix.lower()
    data = path.read_bytes()
    try:
        if suffix == ".stl":
            pts = _stl_vertices(data)
        elif suffix == ".obj":
            lines = data.decode("utf-8", errors="replace").splitlines()
            rows = [ln.split()[1:4] for ln in lines if ln.startswith("v ")]
            pts = np.array(rows, dtype=np.float64).reshape(-1, 3)
        else:
            try:
                import trimesh  # optional
            except ImportError:
                raise UrdfError(f"{path.name}: no reader for {suffix} (install trimesh)") from None
            mesh = trimesh.load(str(path), force="mesh")
            pts = np.asarray(getattr(mesh, "vertices", ()), dtype=np.float64).reshape(-1, 3)
    except (ValueError, struct.error) as exc:
        raise UrdfError(f"{path.name}: unreadable mesh ({exc})") from None
    if pts.size == 0 or not np.all(np.isfinite(pts)):
        raise UrdfError(f"{path.name}: no (finite) vertices")
    return pts.min(axis=0), pts.max(axis=0)


def _box(m: float, size: Sequence[float]) -> np.ndarray:
    a, b, c = size
    return m / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])


def _shape(
    el: etree._Element, package_dirs: Sequence[str], mesh_root: str | None
) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    """``(volume, unit-mass inertia about the centroid, centroid, rotation)`` in link axes."""
    rot, xyz = origin_of(el)
    geometry = el.find("geometry")
    shape = next(c for c in geometry if isinstance(c.tag, str))
    centre = np.zeros(3)
    if shape.tag == "box":
        size = numbers_of(shape, "size", 3, 0.0)
        vol, inertia = float(np.prod(size)), _box(1.0, size)
    elif shape.tag == "cylinder":
        r, h = float(shape.get("radius")), float(shape.get("length"))
        vol = np.pi * r * r * h
        side = (3 * r * r + h * h) / 12.0
        inertia = np.diag([side, side, r * r / 2.0])
    elif shape.tag == "sphere":
        r = float(shape.get("radius"))
        vol, inertia = 4.0 / 3.0 * np.pi * r**3, np.eye(3) * (0.4 * r * r)
    else:  # mesh: its scaled bounding box
        path = resolve_mesh(shape.get("filename") or "", package_dirs=package_dirs,
                            mesh_root=mesh_root)  # fmt: skip
        scale = np.array(numbers_of(shape, "scale", 3, None) or (1.0, 1.0, 1.0))
        lo, hi = mesh_bounds(path)
        lo, hi = np.minimum(lo * scale, hi * scale), np.maximum(lo * scale, hi * scale)
        size = hi - lo
        vol, inertia, centre = float(np.prod(size)), _box(1.0, size), (lo + hi) / 2.0
    return vol, inertia, xyz + rot @ centre, rot


def _write(inertia_el: etree._Element, mat: np.ndarray) -> None:
    for key, (i, j) in {
        "ixx": (0, 0), "ixy": (0, 1), "ixz": (0, 2), "iyy": (1, 1), "iyz": (1, 2), "izz": (2, 2),
    }.items():  # fmt: skip
        inertia_el.set(key, repr(float(mat[i, j])))


def repair_inertials(
    text: str | bytes,
    mode: str,
    *,
    package_dirs: Sequence[str | os.PathLike[str]] = (),
    mesh_root: str | os.PathLike[str] | None = None,
) -> InertiaRepair:
    """Rewrite every ``<inertial>`` of a URDF that passed the gate by ``mode``.

    Collision meshes resolve as the gate's; the :class:`InertiaRepair`'s text keeps every line.
    """
    check_mode(mode)
    root = parse_urdf(text)
    dirs = [os.fspath(d) for d in package_dirs]
    mroot = None if mesh_root is None else os.fspath(mesh_root)
    rep = InertiaRepair(text="", mode=mode)
    for link in root.findall("link"):
        inertial = link.find("inertial")
        if inertial is None:
            continue
        mass_el, inertia_el = inertial.find("mass"), inertial.find("inertia")
        mass = float(mass_el.get("value"))
        name = str(link.get("name"))
        if mass <= 0.0:
            _write(inertia_el, np.zeros((3, 3)))
            continue
        rot_i, com = origin_of(inertial)
        mat_link = None
        if mode == "collision":
            try:  # the collision shapes' inertia about com in link axes, mass shared by volume
                shapes = [_shape(c, dirs, mroot) for c in link.findall("collision")]
                if not shapes:
                    raise UrdfError("no <collision>")
                total = sum(v for v, *_ in shapes)
                if not total > 0.0:
                    raise UrdfError("collision shapes of zero volume")
                out = np.zeros((3, 3))
                for vol, unit, centre, rot in shapes:
                    m, d = mass * vol / total, centre - com
                    out += m * (rot @ unit @ rot.T) + m * (
                        float(d @ d) * np.eye(3) - np.outer(d, d)
                    )
                mat_link = out
                rep.from_collision.append(name)
            except (UrdfError, OSError) as exc:
                rep.fallbacks.append((name, str(exc)))
        if mat_link is None:
            rep.as_point.append(name)
            mat_link = np.eye(3) * (0.4 * mass * POINT_RADIUS**2)
        _write(inertia_el, rot_i.T @ mat_link @ rot_i)  # into the inertial frame's axes
    rep.text = etree.tostring(root, encoding="unicode")
    return rep
