"""three.js objects and meshcat commands: the low level of the viewer's scene.

Deterministic JSON objects (UUIDs derived from the meshcat path, never from the host), typed
arrays for meshcat's msgpack decoder, primitive geometries (boxes, cylinders, spheres, tubes,
grids), the four meshcat commands and their msgpack packing, and the optional dependencies
(u-msgpack-python, meshcat's JavaScript bundle) with their install hint.
"""

from __future__ import annotations

import importlib.util
import math
import uuid
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..exceptions import OptionalDependencyError

INSTALL_HINT = "install the viewer extra: pip install 'hexapod-kin[viewer]' (meshcat==0.3.2)"
_NS = uuid.UUID("6f1d3c9a-2b1e-4f55-9a59-0c8c2f7d1e42")
TRACE_COLORS = (0x1F77B4, 0xD62728, 0x2CA02C, 0x9467BD, 0x8C564B, 0xE377C2, 0x17BECF)


def msgpack_lib() -> Any:
    """The u-msgpack-python module (an optional dependency)."""
    try:
        import umsgpack
    except ImportError:
        msg = f"the viewer needs u-msgpack-python; {INSTALL_HINT}"
        raise OptionalDependencyError(msg) from None
    return umsgpack


def meshcat_dir() -> Path:
    """Directory of the meshcat package (found without importing it: its __init__ is slow)."""
    spec = importlib.util.find_spec("meshcat")
    if spec is None or not spec.submodule_search_locations:
        raise OptionalDependencyError(f"meshcat is not installed; {INSTALL_HINT}")
    return Path(next(iter(spec.submodule_search_locations)))


def bundle() -> str:
    """Meshcat's JavaScript bundle (three.js, msgpack, dat.GUI and the viewer), as text."""
    path = meshcat_dir() / "viewer" / "dist" / "main.min.js"
    if not path.is_file():
        raise OptionalDependencyError(f"meshcat's viewer bundle {path} is missing; {INSTALL_HINT}")
    return path.read_text(encoding="utf-8").replace("</script", "<\\/script")


def f32(array: Any) -> Any:
    """A float32 typed array for meshcat's msgpack decoder (extension 0x17)."""
    arr = np.ascontiguousarray(np.asarray(array, dtype=np.float32).ravel())
    return msgpack_lib().Ext(0x17, arr.tobytes())


#: msgpack extension codes of meshcat's decoder and three.js type names, by numpy dtype.
TYPED_ARRAYS = {
    "int16": (0x13, "Int16Array"),
    "uint16": (0x14, "Uint16Array"),
    "uint32": (0x16, "Uint32Array"),
    "float32": (0x17, "Float32Array"),
}


def attribute(array: np.ndarray, item_size: int) -> dict[str, Any]:
    """A three.js BufferGeometry attribute of ``array`` (other ints as uint32, floats float32)."""
    kind = array.dtype.name
    if kind not in TYPED_ARRAYS:
        kind = "uint32" if array.dtype.kind == "u" else "float32"
    code, typename = TYPED_ARRAYS[kind]
    arr = np.ascontiguousarray(np.asarray(array, dtype=kind).ravel())
    packed = msgpack_lib().Ext(code, arr.tobytes())
    return {"itemSize": item_size, "type": typename, "array": packed, "normalized": False}


def column_major(T: np.ndarray) -> list[float]:
    """Column-major list of a 4×4 (three.js ``Matrix4.fromArray``)."""
    return [float(v) for v in np.asarray(T, dtype=float).T.ravel()]


def trace_rgba(k: int) -> list[float]:
    """The RGBA in [0, 1] of trace colour ``k`` (cycling through :data:`TRACE_COLORS`)."""
    col = TRACE_COLORS[k % len(TRACE_COLORS)]
    return [((col >> 16) & 255) / 255, ((col >> 8) & 255) / 255, (col & 255) / 255, 1.0]


def rotation(axis: str, angle: float) -> np.ndarray:
    """The 4×4 rotation by ``angle`` [rad] about ``axis`` (``"x"``, ``"y"`` or ``"z"``)."""
    c, s = math.cos(angle), math.sin(angle)
    T = np.eye(4)
    i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
    T[i, i], T[i, j], T[j, i], T[j, j] = c, -s, s, c
    return T


def translation(xyz: Any) -> np.ndarray:
    """The 4×4 translation by ``xyz`` [m]."""
    T = np.eye(4)
    T[:3, 3] = np.asarray(xyz, dtype=float)
    return T


class ObjectJSON:
    """Builds one three.js JSON object (the ``object`` of a meshcat ``set_object``)."""

    def __init__(self, key: str) -> None:
        self.key = key
        self.geometries: list[dict[str, Any]] = []
        self.materials: list[dict[str, Any]] = []
        self.textures: list[dict[str, Any]] = []
        self._n = 0

    def _id(self, role: str) -> str:
        """A deterministic UUID (meshcat's ``uuid1`` would embed the host's MAC address)."""
        self._n += 1
        return str(uuid.uuid5(_NS, f"{self.key}/{role}/{self._n}"))

    def geometry(self, data: dict[str, Any]) -> str:
        """Add a geometry; return its UUID."""
        gid = self._id("geometry")
        self.geometries.append({"uuid": gid, **data})
        return gid

    def material(self, rgba: Sequence[float], kind: str = "MeshPhongMaterial", **extra: Any) -> str:
        """Add a material of colour ``rgba``; return its UUID."""
        mid = self._id("material")
        alpha = float(rgba[3]) if len(rgba) > 3 else 1.0
        r, g, b = (int(round(255 * min(max(float(c), 0.0), 1.0))) for c in rgba[:3])
        data: dict[str, Any] = dict(uuid=mid, type=kind, color=(r << 16) | (g << 8) | b, side=2)
        data.update(transparent=alpha < 1.0, opacity=alpha)
        if kind == "MeshPhongMaterial":
            data.update(reflectivity=0.5, shininess=40)
        data.update(extra)
        self.materials.append(data)
        return mid

    def text_texture(self, text: str) -> str:
        """Add a texture with ``text`` drawn by the page; return its UUID."""
        tid = self._id("texture")
        # meshcat's "_text" texture: the text drawn on a 256×256 canvas by the page itself.
        face = dict(font_size=110, font_face="sans-serif")
        self.textures.append({"uuid": tid, "type": "_text", "text": text, **face})
        return tid

    def node(
        self,
        kind: str,
        *,
        geometry: str | None = None,
        material: str | None = None,
        matrix: np.ndarray | None = None,
        children: list[dict[str, Any]] | None = None,
        name: str | None = None,
    ) -> dict[str, Any]:
        """One object node (Mesh, Group, Sprite, LineSegments) with its 4×4 ``matrix``."""
        out: dict[str, Any] = {"uuid": self._id("object"), "type": kind}
        parts = (("geometry", geometry), ("material", material))
        out.update({k: v for k, v in parts if v is not None})
        out["matrix"] = column_major(np.eye(4) if matrix is None else matrix)
        if children:
            out["children"] = children
        if name:
            out["name"] = name
        return out

    def lower(self, root: dict[str, Any]) -> dict[str, Any]:
        """The whole JSON object (geometries, materials, textures) with ``root`` as its object."""
        return {
            "metadata": {"version": 4.5, "type": "Object"},
            "geometries": self.geometries,
            "materials": self.materials,
            "textures": self.textures,
            "images": [],
            "object": root,
        }


def cylinder(radius: float, length: float, segments: int = 32) -> dict[str, Any]:
    """three.js cylinder (axis y; rotate by Rx(π/2) for a URDF cylinder, axis z)."""
    r = float(radius)
    kw = dict(radiusTop=r, radiusBottom=r, height=float(length), radialSegments=segments)
    return {"type": "CylinderGeometry", **kw}


def sphere(radius: float) -> dict[str, Any]:
    """A three.js sphere of ``radius`` [m]."""
    return dict(type="SphereGeometry", radius=float(radius), widthSegments=24, heightSegments=16)


def tube(points: np.ndarray, radius: float, sides: int = 10) -> dict[str, Any] | None:
    """A tube of ``radius`` along a polyline (M, 3), as an indexed BufferGeometry with normals."""
    pts = np.asarray(points, dtype=float)
    if len(pts) > 1:
        keep = np.concatenate(([True], np.linalg.norm(np.diff(pts, axis=0), axis=1) > 1e-9))
        pts = pts[keep]
    if len(pts) < 2:
        return None
    tang = np.gradient(pts, axis=0)
    tang /= np.maximum(np.linalg.norm(tang, axis=1, keepdims=True), 1e-12)
    normals = np.empty_like(pts)
    ref = np.array([0.0, 0.0, 1.0]) if abs(tang[0, 2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    for i, t in enumerate(tang):  # parallel transport of the first normal
        n = ref - np.dot(ref, t) * t
        if np.linalg.norm(n) < 1e-6:
            n = np.cross(t, [1.0, 0.0, 0.0] if abs(t[0]) < 0.9 else [0.0, 1.0, 0.0])
        n /= np.linalg.norm(n)
        normals[i] = n
        ref = n
    binormals = np.cross(tang, normals)
    ang = 2 * np.pi * np.arange(sides) / sides
    radial = (
        np.cos(ang)[None, :, None] * normals[:, None, :]
        + np.sin(ang)[None, :, None] * binormals[:, None, :]
    )  # (M, sides, 3)
    verts = pts[:, None, :] + radius * radial
    m = len(pts)
    idx: list[int] = []
    for i in range(m - 1):
        for k in range(sides):
            a, b = i * sides + k, i * sides + (k + 1) % sides
            c, d = a + sides, b + sides
            idx.extend((a, c, b, b, c, d))
    return {
        "type": "BufferGeometry",
        "data": {
            "attributes": {
                "position": attribute(verts.reshape(-1, 3).astype(np.float32), 3),
                "normal": attribute(radial.reshape(-1, 3).astype(np.float32), 3),
            },
            "index": attribute(np.asarray(idx, dtype=np.uint32), 1),
        },
    }


def grid(half: float, cell: float) -> dict[str, Any]:
    """A square grid of lines of half-width ``half`` [m] and ``cell`` [m] in the z = 0 plane."""
    n = int(round(half / cell))
    ticks = np.arange(-n, n + 1) * cell
    segs = []
    for t in ticks:
        segs += [(t, -half, 0.0), (t, half, 0.0), (-half, t, 0.0), (half, t, 0.0)]
    return {
        "type": "BufferGeometry",
        "data": {"attributes": {"position": attribute(np.asarray(segs, dtype=np.float32), 3)}},
    }


def nice_step(x: float) -> float:
    """1, 2 or 5 × 10^k just above ``x``."""
    if x <= 0 or not math.isfinite(x):
        return 1.0
    k = math.floor(math.log10(x))
    for m in (1.0, 2.0, 5.0, 10.0):
        if m * 10**k >= x:
            return m * 10**k
    return 10.0 ** (k + 1)  # pragma: no cover


def set_object(path: str, obj: dict[str, Any]) -> dict[str, Any]:
    """The meshcat ``set_object`` command."""
    return {"type": "set_object", "path": path, "object": obj}


def set_transform(path: str, T: np.ndarray) -> dict[str, Any]:
    """The meshcat ``set_transform`` command (pose ``T`` 4×4)."""
    return {"type": "set_transform", "path": path, "matrix": column_major(T)}


def set_property(path: str, prop: str, value: Any) -> dict[str, Any]:
    """The meshcat ``set_property`` command."""
    return {"type": "set_property", "path": path, "property": prop, "value": value}


def delete(path: str) -> dict[str, Any]:
    """The meshcat ``delete`` command."""
    return {"type": "delete", "path": path}


def pack(cmd: dict[str, Any]) -> bytes:
    """A command as msgpack bytes (what meshcat's decoder reads)."""
    return bytes(msgpack_lib().packb(cmd))
