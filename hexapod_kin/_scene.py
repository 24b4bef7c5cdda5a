"""Scene building for the viewer: meshcat commands, animation data and the HTML page.

Everything here is computed from a model and a trajectory, with no server: the meshcat
commands (dicts, packed with msgpack) that draw the scene and animate it, shared by
:func:`export_html` (a self-contained page) and the live :class:`hexapod_kin.viewer.Viewer`.
The public names are re-exported by :mod:`hexapod_kin.viewer`; import them from there.

The scene layout (meshcat paths under ``/meshcat``) and the pose convention (Pinocchio's
``oMx``, 4×4; ``base_poses`` move the whole model by ``worldMroot``) are described in
:mod:`hexapod_kin.viewer`.
"""

from __future__ import annotations

import base64
import importlib.util
import json
import math
import os
import uuid
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ._io import atomic_write
from .exceptions import (
    ConfigurationError,
    OptionalDependencyError,
    ParameterError,
    ViewerError,
)
from .gait.stand import frame_poses

if TYPE_CHECKING:  # pragma: no cover
    from .model import Model

__all__ = [
    "MAX_SAMPLES",
    "PARTS",
    "export_html",
    "iframe",
    "khalil_frames",
    "scene_commands",
]

#: Parts of the scene that can be shown or hidden (``Viewer.set_visible``).
PARTS = ("robot", "trace", "frames", "singular", "ground")
#: Above this many samples (and with ``fps=None``) an animation is resampled at 60 frames/s.
MAX_SAMPLES = 3000

_INSTALL_HINT = "install the viewer extra: pip install 'hexapod-kin[viewer]' (meshcat==0.3.2)"
_NS = uuid.UUID("6f1d3c9a-2b1e-4f55-9a59-0c8c2f7d1e42")
_TRACE_COLORS = (0x1F77B4, 0xD62728, 0x2CA02C, 0x9467BD, 0x8C564B, 0xE377C2, 0x17BECF)


# ====================================================================== optional dependencies
def _umsgpack() -> Any:
    try:
        import umsgpack
    except ImportError:
        raise OptionalDependencyError(
            f"the viewer needs u-msgpack-python; {_INSTALL_HINT}"
        ) from None
    return umsgpack


def _meshcat_dir() -> Path:
    """Directory of the meshcat package (found without importing it: its __init__ is slow)."""
    spec = importlib.util.find_spec("meshcat")
    if spec is None or not spec.submodule_search_locations:
        raise OptionalDependencyError(f"meshcat is not installed; {_INSTALL_HINT}")
    return Path(next(iter(spec.submodule_search_locations)))


def _bundle() -> str:
    """Meshcat's JavaScript bundle (three.js, msgpack, dat.GUI and the viewer), as text."""
    path = _meshcat_dir() / "viewer" / "dist" / "main.min.js"
    if not path.is_file():
        raise OptionalDependencyError(f"meshcat's viewer bundle {path} is missing; {_INSTALL_HINT}")
    text = path.read_text(encoding="utf-8")
    return text.replace("</script", "<\\/script")


# ====================================================================== low-level: JSON objects
def _uuid(*parts: object) -> str:
    """Deterministic UUID (meshcat's own ``uuid1`` would embed the host's MAC address)."""
    return str(uuid.uuid5(_NS, "/".join(str(p) for p in parts)))


def _f32(array: Any) -> Any:
    """A float32 typed array for meshcat's msgpack decoder (extension 0x17)."""
    arr = np.ascontiguousarray(np.asarray(array, dtype=np.float32).ravel())
    return _umsgpack().Ext(0x17, arr.tobytes())


def _u32(array: Any) -> Any:
    arr = np.ascontiguousarray(np.asarray(array, dtype=np.uint32).ravel())
    return _umsgpack().Ext(0x16, arr.tobytes())


def _attr(array: np.ndarray, item_size: int) -> dict[str, Any]:
    typename = "Uint32Array" if array.dtype.kind == "u" else "Float32Array"
    packed = _u32(array) if array.dtype.kind == "u" else _f32(array)
    return {"itemSize": item_size, "type": typename, "array": packed, "normalized": False}


def _matrix(T: np.ndarray) -> list[float]:
    """Column-major list of a 4×4 (three.js ``Matrix4.fromArray``)."""
    return [float(v) for v in np.asarray(T, dtype=float).T.ravel()]


def _color(rgb: Sequence[float]) -> int:
    r, g, b = (int(round(255 * min(max(float(c), 0.0), 1.0))) for c in rgb[:3])
    return (r << 16) | (g << 8) | b


def _rot(axis: str, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    T = np.eye(4)
    i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
    T[i, i], T[i, j], T[j, i], T[j, j] = c, -s, s, c
    return T


def _translate(xyz: Any) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = np.asarray(xyz, dtype=float)
    return T


class _ObjectJSON:
    """Builds one three.js JSON object (the ``object`` of a meshcat ``set_object``)."""

    def __init__(self, key: str) -> None:
        self.key = key
        self.geometries: list[dict[str, Any]] = []
        self.materials: list[dict[str, Any]] = []
        self.textures: list[dict[str, Any]] = []
        self._n = 0

    def _id(self, role: str) -> str:
        self._n += 1
        return _uuid(self.key, role, self._n)

    def geometry(self, data: dict[str, Any]) -> str:
        gid = self._id("geometry")
        self.geometries.append({"uuid": gid, **data})
        return gid

    def material(
        self, rgba: Sequence[float], kind: str = "MeshPhongMaterial", **extra: Any
    ) -> str:
        mid = self._id("material")
        alpha = float(rgba[3]) if len(rgba) > 3 else 1.0
        data: dict[str, Any] = {
            "uuid": mid,
            "type": kind,
            "color": _color(rgba),
            "side": 2,
            "transparent": alpha < 1.0,
            "opacity": alpha,
        }
        if kind == "MeshPhongMaterial":
            data.update(reflectivity=0.5, shininess=40)
        data.update(extra)
        self.materials.append(data)
        return mid

    def text_texture(self, text: str) -> str:
        tid = self._id("texture")
        # meshcat's "_text" texture: the text drawn on a 256×256 canvas by the page itself.
        self.textures.append(
            {"uuid": tid, "type": "_text", "text": text, "font_size": 110,
             "font_face": "sans-serif"}
        )
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
        out: dict[str, Any] = {"uuid": self._id("object"), "type": kind}
        if geometry is not None:
            out["geometry"] = geometry
        if material is not None:
            out["material"] = material
        out["matrix"] = _matrix(np.eye(4) if matrix is None else matrix)
        if children:
            out["children"] = children
        if name:
            out["name"] = name
        return out

    def lower(self, root: dict[str, Any]) -> dict[str, Any]:
        return {
            "metadata": {"version": 4.5, "type": "Object"},
            "geometries": self.geometries,
            "materials": self.materials,
            "textures": self.textures,
            "images": [],
            "object": root,
        }


def _cylinder(radius: float, length: float, segments: int = 32) -> dict[str, Any]:
    """three.js cylinder (axis y; rotate by Rx(π/2) for a URDF cylinder, axis z)."""
    return {
        "type": "CylinderGeometry",
        "radiusTop": float(radius),
        "radiusBottom": float(radius),
        "height": float(length),
        "radialSegments": segments,
    }


def _sphere(radius: float) -> dict[str, Any]:
    return {"type": "SphereGeometry", "radius": float(radius), "widthSegments": 24,
            "heightSegments": 16}


def _tube(points: np.ndarray, radius: float, sides: int = 10) -> dict[str, Any] | None:
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
                "position": _attr(verts.reshape(-1, 3).astype(np.float32), 3),
                "normal": _attr(radial.reshape(-1, 3).astype(np.float32), 3),
            },
            "index": _attr(np.asarray(idx, dtype=np.uint32), 1),
        },
    }


def _grid(half: float, cell: float) -> dict[str, Any]:
    n = int(round(half / cell))
    ticks = np.arange(-n, n + 1) * cell
    segs = []
    for t in ticks:
        segs += [(t, -half, 0.0), (t, half, 0.0), (-half, t, 0.0), (half, t, 0.0)]
    return {
        "type": "BufferGeometry",
        "data": {"attributes": {"position": _attr(np.asarray(segs, dtype=np.float32), 3)}},
    }


def _nice(x: float) -> float:
    """1, 2 or 5 × 10^k just above ``x``."""
    if x <= 0 or not math.isfinite(x):
        return 1.0
    k = math.floor(math.log10(x))
    for m in (1.0, 2.0, 5.0, 10.0):
        if m * 10**k >= x:
            return m * 10**k
    return 10.0 ** (k + 1)  # pragma: no cover


# ====================================================================== commands
def _set_object(path: str, obj: dict[str, Any]) -> dict[str, Any]:
    return {"type": "set_object", "path": path, "object": obj}


def _set_transform(path: str, T: np.ndarray) -> dict[str, Any]:
    return {"type": "set_transform", "path": path, "matrix": _matrix(T)}


def _set_property(path: str, prop: str, value: Any) -> dict[str, Any]:
    return {"type": "set_property", "path": path, "property": prop, "value": value}


def _delete(path: str) -> dict[str, Any]:
    return {"type": "delete", "path": path}


def _pack(cmd: dict[str, Any]) -> bytes:
    return bytes(_umsgpack().packb(cmd))


# ====================================================================== the model's scene
@dataclass(frozen=True)
class _Visual:
    path: str
    obj: dict[str, Any]
    radius: float


class _Scene:
    """The visual geometry of a model as meshcat objects, and their placements along q."""

    def __init__(self, model: Model) -> None:
        import pinocchio as pin

        self.model = model
        try:
            self.geom = model.geometry_model("visual")
        except (ValueError, RuntimeError, OSError) as exc:
            raise ViewerError(
                f"could not build the visual geometry of {model.name!r}: {exc} (meshes resolve "
                f"against package_dirs={list(model.source.package_dirs)} and "
                f"mesh_root={model.source.mesh_root!r})"
            ) from exc
        self.gdata = pin.GeometryData(self.geom)
        self.data = model.model.createData()
        self.visuals: list[_Visual] = []
        self.kept: list[int] = []
        used: set[str] = set()
        for k, go in enumerate(self.geom.geometryObjects):
            item = self._visual(go, used)
            if item is not None:
                self.visuals.append(item)
                self.kept.append(k)

    def _visual(self, go: Any, used: set[str]) -> _Visual | None:
        name = "".join(c if c.isalnum() or c in "_-." else "_" for c in str(go.name)) or "geom"
        while name in used:
            name += "_"
        used.add(name)
        path = f"/meshcat/robot/{name}"
        rgba = [float(c) for c in np.asarray(go.meshColor).ravel()[:4]]
        if len(rgba) < 4 or not all(math.isfinite(c) for c in rgba):
            rgba = [0.7, 0.7, 0.7, 1.0]
        obj = _ObjectJSON(path)
        mat = obj.material(rgba)
        g = go.geometry
        kind = type(g).__name__
        scale = np.diag(np.append(np.asarray(go.meshScale, dtype=float).ravel()[:3], 1.0))
        mesh_path = str(getattr(go, "meshPath", "") or "")
        if kind == "Box":
            size = 2.0 * np.asarray(g.halfSide, dtype=float)
            gid = obj.geometry({"type": "BoxGeometry", "width": size[0], "height": size[1],
                                "depth": size[2]})
            radius = float(np.linalg.norm(size) / 2)
            intrinsic = np.eye(4)
        elif kind == "Cylinder":
            gid = obj.geometry(_cylinder(g.radius, 2.0 * g.halfLength))
            radius = float(math.hypot(g.radius, g.halfLength))
            intrinsic = _rot("x", math.pi / 2)
        elif kind == "Capsule":
            gid = obj.geometry(_cylinder(g.radius, 2.0 * g.halfLength + 2.0 * g.radius))
            radius = float(g.halfLength + g.radius)
            intrinsic = _rot("x", math.pi / 2)
        elif kind == "Sphere":
            gid = obj.geometry(_sphere(g.radius))
            radius = float(g.radius)
            intrinsic = np.eye(4)
        elif kind == "Ellipsoid":
            gid = obj.geometry(_sphere(1.0))
            radii = np.asarray(g.radii, dtype=float)
            radius = float(radii.max())
            intrinsic = np.diag(np.append(radii, 1.0))
        elif mesh_path and Path(mesh_path).is_file():
            data = self._mesh_file(Path(mesh_path))
            if data is None:
                warnings.warn(f"viewer: mesh {mesh_path} has an unsupported format; skipped",
                              stacklevel=3)
                return None
            gid = obj.geometry(data)
            radius = self._mesh_radius(g) * float(np.max(np.abs(np.diag(scale)[:3])))
            intrinsic = scale
        else:
            warnings.warn(f"viewer: geometry {go.name!r} of type {kind} is not drawn", stacklevel=3)
            return None
        root = obj.node("Mesh", geometry=gid, material=mat, matrix=intrinsic, name=name)
        return _Visual(path, obj.lower(root), radius)

    @staticmethod
    def _mesh_file(path: Path) -> dict[str, Any] | None:
        suffix = path.suffix.lower()
        if suffix == ".stl":
            return {"type": "_meshfile_geometry", "format": "stl",
                    "data": _umsgpack().Ext(0x12, path.read_bytes())}
        if suffix in (".dae", ".obj"):
            return {"type": "_meshfile_geometry", "format": suffix[1:],
                    "data": path.read_text(encoding="utf-8", errors="replace")}
        return None

    @staticmethod
    def _mesh_radius(g: Any) -> float:
        try:
            g.computeLocalAABB()
            return float(g.aabb_radius + np.linalg.norm(np.asarray(g.aabb_center)))
        except (AttributeError, RuntimeError):
            return 0.05

    # -------------------------------------------------------------- placements
    def placements(self, qs: np.ndarray, base_poses: np.ndarray | None) -> np.ndarray:
        """World poses (N, G, 4, 4) of the drawn geometries."""
        import pinocchio as pin

        m, d = self.model.model, self.data
        out = np.empty((len(qs), len(self.kept), 4, 4))
        for i, q in enumerate(qs):
            pin.forwardKinematics(m, d, q)
            pin.updateGeometryPlacements(m, d, self.geom, self.gdata)
            for j, k in enumerate(self.kept):
                out[i, j] = self.gdata.oMg[k].homogeneous
        if base_poses is not None:
            out = np.einsum("nab,ngbc->ngac", base_poses, out)
        return out

    def frame_poses(
        self, qs: np.ndarray, base_poses: np.ndarray | None, frames: Sequence[str]
    ) -> np.ndarray:
        """World poses (N, F, 4, 4) of named frames."""
        return frame_poses(self.model, self.data, qs, base_poses, frames)


def khalil_frames(model: Model) -> tuple[str, ...]:
    """The Khalil frames 0..n of the model's chain (base → tip), by name.

    Frame 0 is the last frame of ``model.path_frames`` that is fixed to the base (the parent
    link of the first joint), so for a hexapod leg ``leg1_base`` is 0 and the foot is 4.
    """
    m = model.model
    names = list(model.path_frames)
    start = 0
    base_joint = m.frames[m.getFrameId(names[0])].parentJoint
    for i, name in enumerate(names):
        if m.frames[m.getFrameId(name)].parentJoint == base_joint:
            start = i
        else:
            break
    return tuple(names[start:])


# ====================================================================== trajectories
@dataclass(frozen=True)
class _Motion:
    times: np.ndarray
    qs: np.ndarray
    base_poses: np.ndarray | None


def _check_base_poses(poses: Any, n: int) -> np.ndarray | None:
    if poses is None:
        return None
    try:
        arr = np.asarray(poses, dtype=float)
    except (TypeError, ValueError):
        raise ConfigurationError("base_poses is not an array of numbers") from None
    if arr.shape == (4, 4):
        arr = np.broadcast_to(arr, (n, 4, 4)).copy()
    if arr.shape != (n, 4, 4):
        raise ConfigurationError(
            f"base_poses has shape {arr.shape}; expected ({n}, 4, 4) (one pose per sample) or "
            "(4, 4)"
        )
    if not np.all(np.isfinite(arr)):
        raise ConfigurationError("base_poses contains non-finite values")
    rot = arr[:, :3, :3]
    err = np.abs(np.einsum("nji,njk->nik", rot, rot) - np.eye(3)).max()
    bottom = np.abs(arr[:, 3, :] - [0.0, 0.0, 0.0, 1.0]).max()
    if err > 1e-6 or bottom > 1e-9 or np.any(np.linalg.det(rot) < 0):
        raise ConfigurationError(
            f"base_poses are not rigid transforms (|RᵀR − I| = {err:.2e}, last row off by "
            f"{bottom:.2e}); expected rotations with det +1 and a last row [0, 0, 0, 1]"
        )
    return arr


def _check_motion(model: Model, times: Any, qs: Any, base_poses: Any) -> _Motion:
    q = model.check_q_batch(qs, "qs")
    try:
        t = np.asarray(times, dtype=float)
    except (TypeError, ValueError):
        raise ConfigurationError("times is not an array of numbers") from None
    if t.ndim == 0:
        t = t[None]
    if t.ndim != 1 or len(t) != len(q):
        raise ConfigurationError(
            f"times has shape {t.shape}; expected ({len(q)},), one time per row of qs"
        )
    if not np.all(np.isfinite(t)):
        raise ConfigurationError("times contains non-finite values")
    if len(t) > 1 and np.any(np.diff(t) <= 0):
        bad = int(np.argmax(np.diff(t) <= 0))
        raise ConfigurationError(
            f"times must increase strictly; times[{bad}]={t[bad]} >= times[{bad + 1}]={t[bad + 1]}"
        )
    return _Motion(t, q, _check_base_poses(base_poses, len(q)))


def _resample(motion: _Motion, fps: float | None) -> _Motion:
    """Resample at ``fps`` [frames/s] (linear in q; SE(3) geodesic for the base)."""
    n = len(motion.times)
    if fps is None:
        if n <= MAX_SAMPLES:
            return motion
        fps = 60.0
    if not (isinstance(fps, (int, float)) and math.isfinite(fps) and 0 < fps <= 1000):
        raise ParameterError(f"fps={fps!r} is not allowed; give a number in (0, 1000] frames/s")
    t0, t1 = float(motion.times[0]), float(motion.times[-1])
    if n < 2 or t1 <= t0:
        return motion
    count = max(2, int(math.floor((t1 - t0) * fps + 1e-9)) + 1)
    times = t0 + np.arange(count) / fps
    times[-1] = min(times[-1], t1)
    if times[-1] < t1 - 1e-12:
        times = np.append(times, t1)
    qs = np.column_stack([np.interp(times, motion.times, col) for col in motion.qs.T])
    poses = None
    if motion.base_poses is not None:
        import pinocchio as pin

        idx = np.clip(np.searchsorted(motion.times, times, side="right") - 1, 0, n - 2)
        poses = np.empty((len(times), 4, 4))
        for k, (i, t) in enumerate(zip(idx, times)):
            a, b = motion.times[i], motion.times[i + 1]
            alpha = min(max((t - a) / (b - a), 0.0), 1.0)
            A, B = pin.SE3(motion.base_poses[i]), pin.SE3(motion.base_poses[i + 1])
            poses[k] = (A * pin.exp6(alpha * pin.log6(A.inverse() * B))).homogeneous
    return _Motion(times, qs, poses)


def _quaternions(T: np.ndarray) -> np.ndarray:
    """(N, 4) quaternions x, y, z, w of (N, 4, 4) poses, sign-continuous along N."""
    import pinocchio as pin

    out = np.array([pin.Quaternion(np.ascontiguousarray(m[:3, :3])).coeffs() for m in T])
    for i in range(1, len(out)):
        if np.dot(out[i], out[i - 1]) < 0:
            out[i] = -out[i]
    return out


# ====================================================================== scene + animation
def _trace_frames(model: Model, trace_frame: Any) -> tuple[str, ...]:
    from .params import Hexapod

    if trace_frame is False or trace_frame == ():
        return ()
    if trace_frame is None or trace_frame is True:
        params = model.params
        if isinstance(params, Hexapod):
            return tuple(params.foot_frames)
        return (model.tip,)
    names = (trace_frame,) if isinstance(trace_frame, str) else tuple(trace_frame)
    for name in names:
        model.frame_id(name)
    return names


def _triad_frames(model: Model, frame_triads: Any) -> tuple[str, ...]:
    if frame_triads is False or frame_triads is None:
        return ()
    if frame_triads is True:
        return khalil_frames(model)
    names = (frame_triads,) if isinstance(frame_triads, str) else tuple(frame_triads)
    for name in names:
        model.frame_id(name)
    return names


def _check_mask(mask: Any, n: int) -> np.ndarray | None:
    if mask is None:
        return None
    arr = np.asarray(mask)
    if arr.shape != (n,) or arr.dtype.kind not in "bi":
        raise ConfigurationError(
            f"singular_mask has shape {arr.shape} and dtype {arr.dtype}; expected ({n},) booleans"
        )
    return arr.astype(bool)


@dataclass(frozen=True)
class _Built:
    static: list[dict[str, Any]]
    animation: dict[str, Any] | None
    center: np.ndarray
    radius: float
    duration: float
    t0: float


def _build(
    scene: _Scene,
    motion: _Motion,
    *,
    trace_frames: tuple[str, ...],
    triad_frames: tuple[str, ...],
    singular_mask: np.ndarray | None,
    play: bool,
    loop: bool,
    overlays: dict[str, np.ndarray] | None = None,
) -> _Built:
    """All commands for one model and trajectory: static scene, first pose, animation."""
    poses = scene.placements(motion.qs, motion.base_poses)  # (N, G, 4, 4)
    radii = np.array([v.radius for v in scene.visuals])
    tracked = tuple(dict.fromkeys(trace_frames + triad_frames))
    fposes = scene.frame_poses(motion.qs, motion.base_poses, tracked) if tracked else None
    # -- extent of the scene over the whole motion
    pts = poses[:, :, :3, 3].reshape(-1, 3) if len(radii) else np.zeros((1, 3))
    rad = np.tile(radii, len(poses)) if len(radii) else np.zeros(1)
    if fposes is not None:
        pts = np.vstack([pts, fposes[:, :, :3, 3].reshape(-1, 3)])
        rad = np.concatenate([rad, np.zeros(fposes.shape[0] * fposes.shape[1])])
    lo = (pts - rad[:, None]).min(axis=0)
    hi = (pts + rad[:, None]).max(axis=0)
    center = (lo + hi) / 2
    radius = max(float(np.linalg.norm(hi - lo)) / 2, 1e-3)
    size = radius
    cmds: list[dict[str, Any]] = []
    # -- view: light background, no default grid/axes (metres-scale), camera framing the scene
    cmds.append(_set_property("/Background", "top_color", [0.97, 0.97, 0.99]))
    cmds.append(_set_property("/Background", "bottom_color", [0.72, 0.76, 0.82]))
    cmds.append(_set_property("/Grid", "visible", False))
    cmds.append(_set_property("/Axes", "visible", False))
    cmds.append(_set_transform("/meshcat", _translate(list(-center))))
    # Camera: three.js y-up inside /Cameras/default/rotated; world offset (dx, dy, dz) is the
    # local position (dx, dz, -dy).
    d = _camera_offset(pts - center, rad, fov_deg=40.0, min_aspect=4 / 3)
    cam = "/Cameras/default/rotated/<object>"
    cmds.append(_set_property(cam, "position", [float(d[0]), float(d[2]), float(-d[1])]))
    cmds.append(_set_property(cam, "fov", 40.0))
    cmds.append(_set_property(cam, "near", max(radius * 0.01, 1e-4)))
    cmds.append(_set_property(cam, "far", radius * 100.0))
    # -- ground grid at the lowest point of the scene
    cell = _nice(radius / 4)
    half = cell * max(2, math.ceil(1.6 * radius / cell))
    ground_z = float(lo[2])
    g = _ObjectJSON("/meshcat/ground")
    root = g.node(
        "LineSegments",
        geometry=g.geometry(_grid(half, cell)),
        material=g.material([0.45, 0.47, 0.52, 0.6], "LineBasicMaterial"),
        matrix=_translate([center[0], center[1], ground_z]),
    )
    cmds.append(_set_object("/meshcat/ground", g.lower(root)))
    # -- robot
    for j, vis in enumerate(scene.visuals):
        cmds.append(_set_object(vis.path, vis.obj))
        cmds.append(_set_transform(vis.path, poses[0, j]))
    # -- traces
    tube_r = max(size * 0.006, 1e-4)
    if trace_frames and fposes is not None:
        t = _ObjectJSON("/meshcat/trace")
        kids = []
        for k, name in enumerate(trace_frames):
            geom = _tube(fposes[:, tracked.index(name), :3, 3], tube_r)
            if geom is None:
                continue
            col = _TRACE_COLORS[k % len(_TRACE_COLORS)]
            rgb = [((col >> 16) & 255) / 255, ((col >> 8) & 255) / 255, (col & 255) / 255, 1.0]
            kids.append(t.node("Mesh", geometry=t.geometry(geom), material=t.material(rgb),
                               name=name))
        if kids:
            cmds.append(_set_object("/meshcat/trace", t.lower(t.node("Group", children=kids))))
    # -- singular markers (on the first traced frame, or the tip)
    if singular_mask is not None and singular_mask.any():
        if trace_frames and fposes is not None:
            where = fposes[singular_mask, tracked.index(trace_frames[0]), :3, 3]
        else:
            where = scene.frame_poses(
                motion.qs[singular_mask],
                None if motion.base_poses is None else motion.base_poses[singular_mask],
                (scene.model.tip,),
            )[:, 0, :3, 3]
        s = _ObjectJSON("/meshcat/singular")
        sg = s.geometry(_sphere(max(size * 0.02, 1e-4)))
        sm = s.material([0.9, 0.05, 0.35, 1.0])
        kids = [s.node("Mesh", geometry=sg, material=sm, matrix=_translate(p)) for p in where]
        cmds.append(_set_object("/meshcat/singular", s.lower(s.node("Group", children=kids))))
    # -- per-frame overlays (polylines and points given by the caller)
    o_cmds, o_clips = _overlay_parts(overlays or {}, motion.times - motion.times[0], size)
    cmds += o_cmds
    # -- triads with labels
    triad_len = max(size * 0.16, 1e-3)
    origins: list[np.ndarray] = []
    for k, name in enumerate(triad_frames):
        path = f"/meshcat/frames/{k}"
        assert fposes is not None
        origin = fposes[0, tracked.index(name), :3, 3]
        stack = sum(1 for o in origins if np.linalg.norm(o - origin) < 1e-3 * triad_len)
        origins.append(origin)  # coincident frames (e.g. 0 and 1): labels stacked upwards
        cmds.append(_set_object(path, _triad(path, triad_len, str(k), stack)))
        cmds.append(_set_transform(path, fposes[0, tracked.index(name)]))
    # -- animation
    animation = None
    duration = float(motion.times[-1] - motion.times[0])
    if len(motion.times) > 1:
        times = motion.times - motion.times[0]
        clips = []
        for j, vis in enumerate(scene.visuals):
            clips.append(_clip(vis.path, times, poses[:, j]))
        for k, name in enumerate(triad_frames):
            assert fposes is not None
            clips.append(_clip(f"/meshcat/frames/{k}", times, fposes[:, tracked.index(name)]))
        clips += o_clips
        animation = {
            "type": "set_animation",
            "path": "",
            "animations": clips,
            "options": {"play": bool(play), "repetitions": math.inf if loop else 1},
        }
    return _Built(cmds, animation, center, radius, duration, float(motion.times[0]))


def _camera_offset(
    points: np.ndarray, radii: np.ndarray, *, fov_deg: float, min_aspect: float,
    margin: float = 0.92,
) -> np.ndarray:
    """Camera position (relative to the scene centre) that fits every ball in the view.

    The camera looks at the centre from the direction (1, −1.25, 0.75) (front-right, above);
    its distance is the smallest one for which every ball (``points`` (M, 3) relative to the
    centre, ``radii`` (M,)) projects inside ``margin`` of the vertical field of view
    ``fov_deg`` and of the horizontal one for an aspect ratio of at least ``min_aspect``.
    """
    direction = np.array([1.0, -1.25, 0.75])
    direction /= np.linalg.norm(direction)
    right = np.cross(-direction, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, -direction)
    tan_v = math.tan(math.radians(fov_deg) / 2) * margin
    tan_h = tan_v * min_aspect
    depth = points @ direction + radii
    need = np.maximum((np.abs(points @ up) + radii) / tan_v,
                      (np.abs(points @ right) + radii) / tan_h) + depth
    extent = float(np.max(np.linalg.norm(points, axis=1) + radii))
    dist = max(float(need.max()), 1.2 * extent, 1e-3)
    return dist * direction


def _triad(key: str, length: float, label: str, stack: int = 0) -> dict[str, Any]:
    o = _ObjectJSON(key)
    r = length * 0.05
    cyl = o.geometry(_cylinder(r, length, 12))
    kids = []
    axes = (
        ("x", [0.85, 0.1, 0.1, 1.0], _rot("z", -math.pi / 2)),
        ("y", [0.1, 0.7, 0.1, 1.0], np.eye(4)),
        ("z", [0.1, 0.25, 0.9, 1.0], _rot("x", math.pi / 2)),
    )
    for i, (_axis, rgba, rot) in enumerate(axes):
        offset = np.zeros(3)
        offset[i] = length / 2
        kids.append(o.node("Mesh", geometry=cyl, material=o.material(rgba),
                           matrix=_translate(offset) @ rot))
    tex = o.text_texture(label)
    mat = o.material([1, 1, 1, 1], "SpriteMaterial", map=tex, depthTest=False, transparent=True)
    scale = np.diag([length * 0.75, length * 0.75, length * 0.75, 1.0])
    kids.append(o.node("Sprite", material=mat,
                       matrix=_translate([length * 0.25, length * 0.25,
                                          length * (0.55 + 0.5 * stack)]) @ scale))
    return o.lower(o.node("Group", children=kids))


def _clip(path: str, times: np.ndarray, T: np.ndarray) -> dict[str, Any]:
    return {
        "path": path,
        "clip": {
            "fps": 1.0,  # key times are in seconds
            "name": "default",
            "tracks": [
                {"name": ".position", "type": "vector3", "times": _f32(times),
                 "values": _f32(T[:, :3, 3])},
                {"name": ".quaternion", "type": "quaternion", "times": _f32(times),
                 "values": _f32(_quaternions(T))},
            ],
        },
    }



# ====================================================================== per-frame overlays
def _check_overlays(overlays: Any, n: int) -> dict[str, np.ndarray]:
    """Validate ``overlays``: name -> (N, M, 3) polylines, one per sample (M = 1: a point)."""
    if overlays is None:
        return {}
    if not hasattr(overlays, "items"):
        raise ConfigurationError(
            f"overlays={type(overlays).__name__}: expected a mapping name -> (N, M, 3) array"
        )
    out: dict[str, np.ndarray] = {}
    for name, value in overlays.items():
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise ConfigurationError(f"overlays[{name!r}] is not an array of numbers") from None
        if arr.ndim != 3 or arr.shape[0] != n or arr.shape[2] != 3 or arr.shape[1] < 1:
            raise ConfigurationError(
                f"overlays[{name!r}] has shape {arr.shape}; expected ({n}, M, 3): one polyline "
                "of M points per sample (M = 1: a moving point)"
            )
        if not np.all(np.isfinite(arr)):
            raise ConfigurationError(f"overlays[{name!r}] contains non-finite values")
        out[str(name)] = arr
    return out


def _y_to(d: np.ndarray) -> np.ndarray:
    """(K, 4) quaternions x, y, z, w turning +y onto the unit directions ``d`` (K, 3)."""
    q = np.empty((len(d), 4))
    q[:, 0], q[:, 1], q[:, 2] = d[:, 2], np.zeros(len(d)), -d[:, 0]  # y × d
    q[:, 3] = 1.0 + d[:, 1]
    flip = q[:, 3] < 1e-9  # d = -y: half turn about x
    q[flip] = [1.0, 0.0, 0.0, 0.0]
    return np.asarray(q / np.linalg.norm(q, axis=1, keepdims=True))


def _overlay_parts(
    overlays: dict[str, np.ndarray], times: np.ndarray, size: float
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """Objects and animation clips of the overlays (segments: unit cylinders scaled along y)."""
    cmds: list[dict[str, Any]] = []
    clips: list[dict[str, Any]] = []
    r = max(size * 0.005, 1e-4)
    for k, (name, arr) in enumerate(overlays.items()):
        col = _TRACE_COLORS[(k + 3) % len(_TRACE_COLORS)]
        rgb = [((col >> 16) & 255) / 255, ((col >> 8) & 255) / 255, (col & 255) / 255, 1.0]
        pieces = [(0, 0)] if arr.shape[1] == 1 else [(j, j + 1) for j in range(arr.shape[1] - 1)]
        for j, (a, b) in enumerate(pieces):
            path = f"/meshcat/overlays/{name}/{j}"
            o = _ObjectJSON(path)
            geom = _sphere(3 * r) if a == b else _cylinder(r, 1.0, 8)
            cmds.append(_set_object(path, o.lower(o.node(
                "Mesh", geometry=o.geometry(geom), material=o.material(rgb)))))
            pa, pb = arr[:, a], arr[:, b]
            d = pb - pa
            length = np.linalg.norm(d, axis=1)
            unit = np.where(length[:, None] > 1e-12, d / np.maximum(length, 1e-12)[:, None],
                            [0.0, 1.0, 0.0])
            scale = np.ones((len(arr), 3))
            if a != b:
                scale[:, 1] = np.maximum(length, 1e-9)
                scale[length <= 1e-12] = 1e-9  # a repeated point: hidden
            T = np.tile(np.eye(4), (len(arr), 1, 1))
            T[:, :3, 3] = (pa + pb) / 2
            cmds.append(_set_transform(path, T[0]))
            cmds.append(_set_property(path, "scale", [float(v) for v in scale[0]]))
            if len(times) > 1:
                clip = _clip(path, times, T)
                clip["clip"]["tracks"][1]["values"] = _f32(_y_to(unit))
                clip["clip"]["tracks"].append(
                    {"name": ".scale", "type": "vector3", "times": _f32(times),
                     "values": _f32(scale)})
                clips.append(clip)
    return cmds, clips


def scene_commands(
    model: Model,
    times: Any,
    qs: Any,
    *,
    base_poses: Any = None,
    trace_frame: Any = None,
    frame_triads: Any = False,
    singular_mask: Any = None,
    fps: float | None = None,
    play: bool = True,
    loop: bool = True,
    overlays: Any = None,
) -> list[dict[str, Any]]:
    """The meshcat commands (dicts, before msgpack) that draw and animate a trajectory.

    The same commands feed :func:`export_html` and :meth:`Viewer.animate`; the last one is the
    ``set_animation`` when there is more than one sample. See :func:`export_html` for the
    arguments.

    Raises:
        ConfigurationError: Bad shapes or values of ``times``, ``qs``, ``base_poses``,
            ``singular_mask``.
        FrameNotFoundError: A traced or triad frame does not exist.
        ViewerError: The visual geometry cannot be built.

    """
    built = _build_for(model, times, qs, base_poses, trace_frame, frame_triads, singular_mask,
                       fps, play, loop, overlays=overlays)
    return built.static + ([built.animation] if built.animation else [])


def _build_for(
    model: Model,
    times: Any,
    qs: Any,
    base_poses: Any,
    trace_frame: Any,
    frame_triads: Any,
    singular_mask: Any,
    fps: float | None,
    play: bool,
    loop: bool,
    scene: _Scene | None = None,
    overlays: Any = None,
) -> _Built:
    motion = _check_motion(model, times, qs, base_poses)
    mask = _check_mask(singular_mask, len(motion.times))
    extra = _check_overlays(overlays, len(motion.times))
    if mask is not None and fps is not None:
        raise ParameterError("singular_mask cannot be combined with fps resampling; give fps=None")
    if mask is None:
        given = motion.times
        motion = _resample(motion, fps)
        if extra and len(motion.times) != len(given):  # hold each sample's overlay
            idx = np.clip(np.searchsorted(given, motion.times + 1e-12, side="right") - 1, 0,
                          len(given) - 1)
            extra = {k: v[idx] for k, v in extra.items()}
    return _build(
        scene or _Scene(model),
        motion,
        trace_frames=_trace_frames(model, trace_frame),
        triad_frames=_triad_frames(model, frame_triads),
        singular_mask=mask,
        play=play,
        loop=loop,
        overlays=extra,
    )


# ====================================================================== self-contained HTML
#: The page may run its own inline code and decode data: URIs, and fetch nothing else.
_CSP = (
    "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; "
    "img-src data: blob:; worker-src blob:"
)
_PAGE = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta http-equiv="Content-Security-Policy" content="__CSP__">
<meta name="generator" content="hexapod_kin __VERSION__ (meshcat 0.3.2 bundle)">
<title>__TITLE__</title>
<style>
body { margin: 0; overflow: hidden; font-family: sans-serif; }
#meshcat-pane { width: 100vw; height: 100vh; overflow: hidden; }
#hk-panel { position: absolute; left: 8px; top: 8px; padding: 6px 10px; border-radius: 6px;
  background: rgba(255,255,255,0.82); color: #222; font-size: 13px; line-height: 1.5; }
#hk-panel b { font-size: 14px; }
#hk-panel button, #hk-panel select { font-size: 12px; }
#hk-help { color: #555; font-size: 11px; }
</style>
</head>
<body>
<div id="meshcat-pane"></div>
<div id="hk-panel"><b id="hk-title"></b><br>
<span id="hk-controls"><button id="hk-play">pause</button>
<label><input type="checkbox" id="hk-loop"> loop</label>
speed <select id="hk-speed"><option>0.25</option><option>0.5</option><option>1</option>
<option>2</option><option>4</option></select>
t = <span id="hk-time">0.000</span> s</span><br>
<span id="hk-help">__HELP__</span></div>
<script>
__BUNDLE__
</script>
<script>
(function () {
  "use strict";
  var DATA = __DATA__;
  function bytes(b64) {
    var s = atob(b64), out = new Uint8Array(s.length);
    for (var i = 0; i < s.length; i++) { out[i] = s.charCodeAt(i); }
    return out;
  }
  var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
  DATA.commands.forEach(function (c) { viewer.handle_command_bytearray(bytes(c)); });
  var animator = viewer.animator;
  if (DATA.animation) {
    viewer.handle_command_bytearray(bytes(DATA.animation));
    animator.mixer.timeScale = DATA.speed;
  }
  document.getElementById("hk-title").textContent = DATA.title;
  var playBtn = document.getElementById("hk-play"), loopBox = document.getElementById("hk-loop");
  var speedSel = document.getElementById("hk-speed"), timeEl = document.getElementById("hk-time");
  if (!DATA.animation) { document.getElementById("hk-controls").style.display = "none"; }
  loopBox.checked = DATA.loop;
  speedSel.value = String(DATA.speed);
  function setLoop(on) {
    animator.actions.forEach(function (a) { a.repetitions = on ? Infinity : 1; });
  }
  function play() {
    if (animator.actions.length && animator.actions.every(function (a) { return a.paused; })) {
      animator.reset();
    }
    animator.play(); playBtn.textContent = "pause";
  }
  function pause() { animator.pause(); playBtn.textContent = "play"; }
  function seek(t) {
    animator.actions.forEach(function (a) { a.enabled = true; a.paused = false; a.play(); });
    animator.pause(); playBtn.textContent = "play";
    animator.seek(t - DATA.t0); animator.display_progress(t - DATA.t0);
    viewer.render();
  }
  playBtn.onclick = function () { if (animator.playing) { pause(); } else { play(); } };
  loopBox.onchange = function () { setLoop(loopBox.checked); };
  speedSel.onchange = function () { animator.mixer.timeScale = parseFloat(speedSel.value); };
  if (!DATA.play) { playBtn.textContent = "play"; }
  (function tick() {
    timeEl.textContent = (DATA.t0 + (animator.time || 0)).toFixed(3);
    if (DATA.animation && !animator.playing) { playBtn.textContent = "play"; }
    requestAnimationFrame(tick);
  })();
  window.hexapodKin = {
    viewer: viewer, duration: DATA.duration, t0: DATA.t0, parts: DATA.parts,
    play: play, pause: pause, seek: seek, setLoop: setLoop,
    setSpeed: function (s) { animator.mixer.timeScale = s; speedSel.value = String(s); },
    setVisible: function (part, on) {
      viewer.set_property(["meshcat", part], "visible", !!on); viewer.render();
    },
    render: function () { viewer.render(); },
    ready: true
  };
})();
</script>
</body>
</html>
"""


def _html_data(obj: Any) -> str:
    """JSON for an inline <script> (no ``</`` or ``<!--`` can close it)."""
    return (
        json.dumps(obj, allow_nan=False)
        .replace("<", "\\u003c")
        .replace(">", "\\u003e")
        .replace("&", "\\u0026")
    )


def _html_text(text: str) -> str:
    return (
        text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace('"', "&quot;")
    )


def export_html(
    model: Model,
    times: Any,
    qs: Any,
    path: str | os.PathLike[str],
    *,
    base_poses: Any = None,
    trace_frame: Any = None,
    frame_triads: Any = False,
    singular_mask: Any = None,
    title: str | None = None,
    fps: float | None = None,
    loop: bool = True,
    speed: float = 1.0,
    play: bool = True,
    overlays: Any = None,
) -> Path:
    """Write a self-contained animated HTML file of a trajectory (opens from disk, no network).

    The page inlines meshcat's JavaScript bundle and the scene as meshcat commands; it works
    from ``file://``, in an iframe (Colab, Binder, Jupyter) and offline. Controls: drag to
    orbit, right-drag to pan, wheel to zoom; a panel with play/pause, loop, speed and the time;
    meshcat's "Open Controls" menu (scene tree visibility, animation scrubber). For scripts and
    tests the page exposes ``window.hexapodKin`` (``seek(t)``, ``play()``, ``pause()``,
    ``setVisible(part, on)``, ``setLoop(on)``, ``setSpeed(s)``).

    Args:
        model: A loaded model (``hexapod_kin.load(...)``).
        times: Sample times (N,) in [s], strictly increasing.
        qs: Joint configurations (N, nq) in [rad] / [m]. A single (nq,) shows a still pose.
        path: Destination ``.html`` file (written atomically).
        base_poses: Optional world pose of the model's root per sample, (N, 4, 4) or one (4, 4)
            (a floating body, e.g. a walking hexapod).
        trace_frame: Frame(s) whose path is drawn: a name, a sequence of names, ``False`` for
            none; default the tip (every foot for a hexapod).
        frame_triads: ``True`` draws the Khalil frames 0..n of the chain (x red, y green,
            z blue, labelled with the index j); or a sequence of frame names (labelled with
            their position in the sequence).
        singular_mask: Optional (N,) booleans; a red sphere marks the traced point at each
            flagged (near-singular) sample.
        title: Page title (default: the model's name).
        fps: Resample the animation at this rate in [frames/s] (default: the given samples,
            or 60 frames/s above :data:`MAX_SAMPLES` samples).
        loop: Repeat the animation forever (else play once).
        speed: Playback speed factor (> 0).
        play: Start playing when the page opens.
        overlays: Optional mapping ``name -> (N, M, 3)`` array: a polyline of M world points
            [m] per sample, drawn as thin tubes and moved with the animation (close a polygon
            by repeating its first point; repeated points make hidden segments; M = 1 draws
            a moving sphere), under ``/meshcat/overlays/<name>`` (e.g. a walk's support
            polygon and projected centre of mass).

    Returns:
        The path written.

    Raises:
        ConfigurationError: Bad ``times``/``qs``/``base_poses``/``singular_mask``/``overlays``.
        FrameNotFoundError: A frame name does not exist.
        ParameterError: Bad ``fps``, ``speed`` or destination.
        OptionalDependencyError: meshcat is not installed.
        ViewerError: The visual geometry cannot be built.

    """
    if not (isinstance(speed, (int, float)) and math.isfinite(speed) and 0 < speed <= 100):
        raise ParameterError(f"speed={speed!r} is not allowed; give a factor in (0, 100]")
    bundle = _bundle()
    built = _build_for(model, times, qs, base_poses, trace_frame, frame_triads, singular_mask,
                       fps, play, loop, overlays=overlays)
    label = title if title is not None else f"hexapod_kin: {model.name}"
    data = {
        "title": label,
        "commands": [base64.b64encode(_pack(c)).decode("ascii") for c in built.static],
        "animation": (
            base64.b64encode(_pack(built.animation)).decode("ascii") if built.animation else None
        ),
        "duration": built.duration,
        "t0": built.t0,
        "loop": bool(loop),
        "speed": float(speed),
        "play": bool(play),
        "parts": list(PARTS),
    }
    from . import __version__

    help_text = "drag: orbit · right-drag: pan · wheel: zoom"
    if _triad_frames(model, frame_triads):
        help_text += " · triads x/y/z = red/green/blue, label = Khalil frame index"
    if data["commands"] and singular_mask is not None and np.any(singular_mask):
        help_text += " · red spheres: near-singular samples"
    page = (
        _PAGE.replace("__VERSION__", __version__)
        .replace("__CSP__", _CSP)
        .replace("__TITLE__", _html_text(label))
        .replace("__HELP__", _html_text(help_text))
        .replace("__DATA__", _html_data(data))
    )
    page = page.replace("__BUNDLE__", bundle)  # last: the bundle is never scanned for markers
    return atomic_write(path, page)


def iframe(html: str | os.PathLike[str], *, height: int = 480) -> str:
    """An ``<iframe srcdoc=...>`` embedding an exported page (Jupyter, Colab, Binder).

    ``IPython.display.HTML(viewer.iframe("step.html"))`` shows the animation inline; the page
    stays isolated in its frame (ids, scripts, its Content-Security-Policy), so several can be
    shown in one notebook.

    Args:
        html: Path of a file written by :func:`export_html`.
        height: Frame height in [px] (100..4000).

    Returns:
        The HTML snippet.

    Raises:
        ParameterError: Bad ``height`` or not a file.

    """
    if not (isinstance(height, int) and 100 <= height <= 4000):
        raise ParameterError(f"height={height!r} is not allowed; give pixels in [100, 4000]")
    path = Path(html)
    if not path.is_file():
        raise ParameterError(f"html={str(path)!r} is not a file written by export_html")
    doc = path.read_text(encoding="utf-8")
    return (
        f'<iframe srcdoc="{_html_text(doc)}" style="width: 100%; height: {height}px; '
        'border: 0;" sandbox="allow-scripts"></iframe>'
    )

