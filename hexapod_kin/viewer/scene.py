"""The model's scene: its visual geometry as meshcat objects, and every command of a trajectory.

:class:`Scene` turns a model's visual geometry into meshcat objects placed along q;
:func:`build` makes every command of one trajectory; :func:`scene_commands` is its public face.
Layout, under ``/meshcat`` (shifted so that the scene's centre is the camera target):
``robot/<geometry>``, ``trace`` (traced frames' paths), ``frames/<k>`` (Khalil triads, x red,
y green, z blue), ``singular`` (red spheres), ``overlays/<name>``, ``ground``. Poses are
Pinocchio's ``oMx`` (4×4); ``base_poses`` moves the whole model by ``worldMroot``.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..exceptions import ParameterError, ViewerError
from ..gait.stand import frame_poses
from .meshes import add_sticks, mesh_geometry
from .objects import (
    ObjectJSON,
    cylinder,
    grid,
    nice_step,
    rotation,
    set_object,
    set_property,
    set_transform,
    sphere,
    trace_rgba,
    translation,
    tube,
)
from .overlays import check_overlays, overlay_parts
from .trajectory import Motion, check_mask, check_motion, clip, resample

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model


#: Parts of the scene that can be shown or hidden (``Viewer.set_visible``).
PARTS = ("robot", "trace", "frames", "singular", "ground")


@dataclass(frozen=True)
class Visual:
    """One drawn geometry: its meshcat path, three.js object and bounding radius [m]."""

    path: str
    obj: dict[str, Any]
    radius: float


#: Drawn link radius as a fraction of the chain's length scale (PUMA 560: about 2.4 cm).
LINK_RADIUS_FRACTION = 0.02


def thickening(model: Model, objects: Sequence[Any]) -> tuple[float, float]:
    """``(factor, rod radius [m])`` thin primitives grow by so that links stay visible.

    The rod radius is the largest cylinder radius, drawn at least :data:`LINK_RADIUS_FRACTION`
    of the chain's length scale; cylinders up to 1, spheres up to 3 and boxes up to 6 rod radii
    grow by the factor (1 to 20). ``(1.0, 0.0)`` without a cylinder.
    """
    from .._numerics import chain_length

    kinds = ("Cylinder", "Capsule")
    rods = [float(go.geometry.radius) for go in objects if type(go.geometry).__name__ in kinds]
    if not rods or max(rods) <= 0:
        return 1.0, 0.0
    rod = max(rods)
    try:
        length = chain_length(model.arrays.trans)
    except (AttributeError, TypeError, ValueError):
        return 1.0, rod
    target = LINK_RADIUS_FRACTION * length
    return float(min(max(target / rod, 1.0), 20.0)), rod


class Scene:
    """The visual geometry of a model as meshcat objects, and their placements along q."""

    def __init__(self, model: Model, *, normals: bool = True) -> None:
        import pinocchio as pin

        self.model = model
        self.normals = bool(normals)
        try:
            self.geom = model.geometry_model("visual")
        except (ValueError, RuntimeError, OSError) as exc:
            raise ViewerError(
                f"could not build the visual geometry of {model.name!r}: {exc} (meshes resolve "
                f"against package_dirs={list(model.source.package_dirs)} and "
                f"mesh_root={model.source.mesh_root!r})"
            ) from exc
        if getattr(model, "missing_meshes", ()) or not self.geom.ngeoms:
            add_sticks(model.model, self.geom)  # meshes missing: a stick figure where they were
        self.gdata = pin.GeometryData(self.geom)
        self.data = model.model.createData()
        self.visuals: list[Visual] = []
        self.kept: list[int] = []
        used: set[str] = set()
        self.thickening = thickening(model, self.geom.geometryObjects)
        for k, go in enumerate(self.geom.geometryObjects):
            item = self._visual(go, used)
            if item is not None:
                self.visuals.append(item)
                self.kept.append(k)

    def _visual(self, go: Any, used: set[str]) -> Visual | None:
        name = "".join(c if c.isalnum() or c in "_-." else "_" for c in str(go.name)) or "geom"
        while name in used:
            name += "_"
        used.add(name)
        path = f"/meshcat/robot/{name}"
        rgba = [float(c) for c in np.asarray(go.meshColor).ravel()[:4]]
        if len(rgba) < 4 or not all(math.isfinite(c) for c in rgba):
            rgba = [0.7, 0.7, 0.7, 1.0]
        obj = ObjectJSON(path)
        mat = obj.material(rgba)
        g = go.geometry
        kind = type(g).__name__
        mesh_path = str(getattr(go, "meshPath", "") or "")
        grow, rod = self.thickening
        if kind == "Box":
            size = 2.0 * np.asarray(g.halfSide, dtype=float)
            if np.max(size) <= 6.0 * rod:
                size = size * grow
            gid = obj.geometry(
                {"type": "BoxGeometry", "width": size[0], "height": size[1], "depth": size[2]}
            )
            radius = float(np.linalg.norm(size) / 2)
            intrinsic = np.eye(4)
        elif kind in ("Cylinder", "Capsule"):  # a capsule drawn as a cylinder over its caps
            r = g.radius * (grow if g.radius <= rod else 1.0)
            cap = r if kind == "Capsule" else 0.0
            gid = obj.geometry(cylinder(r, 2.0 * g.halfLength + 2.0 * cap))
            radius = float(g.halfLength + r) if cap else float(math.hypot(r, g.halfLength))
            intrinsic = rotation("x", math.pi / 2)
        elif kind == "Sphere":
            r = g.radius * (grow if g.radius <= 3.0 * rod else 1.0)
            gid = obj.geometry(sphere(r))
            radius = float(r)
            intrinsic = np.eye(4)
        elif kind == "Ellipsoid":
            gid = obj.geometry(sphere(1.0))
            radii = np.asarray(g.radii, dtype=float)
            radius = float(radii.max())
            intrinsic = np.diag(np.append(radii, 1.0))
        elif mesh_path and (mesh := mesh_geometry(g, normals=self.normals)) is not None:
            gid = obj.geometry(mesh.data)
            try:  # the BVH has the mesh scale applied
                g.computeLocalAABB()
                radius = float(g.aabb_radius + np.linalg.norm(np.asarray(g.aabb_center)))
            except (AttributeError, RuntimeError):
                radius = 0.05
            intrinsic = mesh.matrix
        else:
            warnings.warn(f"viewer: geometry {go.name!r} of type {kind} is not drawn", stacklevel=3)
            return None
        root = obj.node("Mesh", geometry=gid, material=mat, matrix=intrinsic, name=name)
        return Visual(path, obj.lower(root), radius)

    def placements(self, qs: np.ndarray, base_poses: np.ndarray | None) -> np.ndarray:
        """World poses (N, G, 4, 4) of the drawn geometries."""
        import pinocchio as pin

        m, d = self.model.model, self.data
        out = np.empty((len(qs), len(self.kept), 4, 4))
        for i, q in enumerate(qs):
            pin.forwardKinematics(m, d, self.model.pinocchio_q(q))  # continuous: (cos, sin)
            pin.updateGeometryPlacements(m, d, self.geom, self.gdata)
            for j, k in enumerate(self.kept):
                out[i, j] = self.gdata.oMg[k].homogeneous
        if base_poses is not None:
            out = np.einsum("nab,ngbc->ngac", base_poses, out)
        return out


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


def _resolve_trace_frames(model: Model, trace_frame: Any) -> tuple[str, ...]:
    """The frames whose path is drawn (``None``/``True``: the tip, or every foot)."""
    from ..params import Hexapod

    if trace_frame is False or trace_frame == ():
        return ()
    if trace_frame is None or trace_frame is True:
        params = model.params
        return tuple(params.foot_frames) if isinstance(params, Hexapod) else (model.tip,)
    return _frame_names(model, trace_frame)


def resolve_triad_frames(model: Model, frame_triads: Any) -> tuple[str, ...]:
    """The frames drawn as triads (``True``: the Khalil frames 0..n)."""
    if frame_triads is False or frame_triads is None:
        return ()
    if frame_triads is True:
        return khalil_frames(model)
    return _frame_names(model, frame_triads)


def _frame_names(model: Model, frames: str | Sequence[str]) -> tuple[str, ...]:
    """``frames`` (one name or several) as a tuple, each checked (``FrameNotFoundError``)."""
    names = (frames,) if isinstance(frames, str) else tuple(frames)
    for name in names:
        model.frame_id(name)
    return names


@dataclass(frozen=True)
class Built:
    """Every command of one trajectory: static scene, animation, extent and timing [s]."""

    static: list[dict[str, Any]]
    animation: dict[str, Any] | None
    center: np.ndarray
    radius: float
    duration: float
    t0: float


def build(
    scene: Scene,
    motion: Motion,
    *,
    trace_frames: tuple[str, ...],
    triad_frames: tuple[str, ...],
    singular_mask: np.ndarray | None,
    play: bool,
    loop: bool,
    overlays: dict[str, np.ndarray] | None = None,
) -> Built:
    """All commands for one model and trajectory: static scene, first pose, animation."""
    poses = scene.placements(motion.qs, motion.base_poses)  # (N, G, 4, 4)
    radii = np.array([v.radius for v in scene.visuals])
    tracked = tuple(dict.fromkeys(trace_frames + triad_frames))
    fposes = None
    if tracked:
        fposes = frame_poses(scene.model, scene.data, motion.qs, motion.base_poses, tracked)
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
    # -- view: light background, no default grid/axes (metres-scale), camera framing the scene
    cmds = [
        set_property("/Background", "top_color", [0.97, 0.97, 0.99]),
        set_property("/Background", "bottom_color", [0.72, 0.76, 0.82]),
        set_property("/Grid", "visible", False),
        set_property("/Axes", "visible", False),
        set_transform("/meshcat", translation(list(-center))),
    ]
    # Camera: three.js y-up inside /Cameras/default/rotated; world offset (dx, dy, dz) is the
    # local position (dx, dz, -dy).
    d = _camera_offset(pts - center, rad, fov_deg=40.0, min_aspect=4 / 3)
    cam = "/Cameras/default/rotated/<object>"
    cmds.append(set_property(cam, "position", [float(d[0]), float(d[2]), float(-d[1])]))
    cmds.append(set_property(cam, "fov", 40.0))
    cmds.append(set_property(cam, "near", max(radius * 0.01, 1e-4)))
    cmds.append(set_property(cam, "far", radius * 100.0))
    # -- ground grid at the lowest point of the scene
    cell = nice_step(radius / 4)
    half = cell * max(2, math.ceil(1.6 * radius / cell))
    ground_z = float(lo[2])
    g = ObjectJSON("/meshcat/ground")
    root = g.node(
        "LineSegments",
        geometry=g.geometry(grid(half, cell)),
        material=g.material([0.45, 0.47, 0.52, 0.6], "LineBasicMaterial"),
        matrix=translation([center[0], center[1], ground_z]),
    )
    cmds.append(set_object("/meshcat/ground", g.lower(root)))
    # -- robot
    for j, vis in enumerate(scene.visuals):
        cmds.append(set_object(vis.path, vis.obj))
        cmds.append(set_transform(vis.path, poses[0, j]))
    # -- traces
    tube_r = max(size * 0.006, 1e-4)
    if trace_frames and fposes is not None:
        t = ObjectJSON("/meshcat/trace")
        kids = []
        for k, name in enumerate(trace_frames):
            geom = tube(fposes[:, tracked.index(name), :3, 3], tube_r)
            if geom is None:
                continue
            gid = t.geometry(geom)  # before the material: the UUIDs count in order
            kids.append(t.node("Mesh", geometry=gid, material=t.material(trace_rgba(k)), name=name))
        if kids:
            cmds.append(set_object("/meshcat/trace", t.lower(t.node("Group", children=kids))))
    # -- singular markers (on the first traced frame, or the tip)
    if singular_mask is not None and singular_mask.any():
        if trace_frames and fposes is not None:
            where = fposes[singular_mask, tracked.index(trace_frames[0]), :3, 3]
        else:
            base = None if motion.base_poses is None else motion.base_poses[singular_mask]
            qs, tip = motion.qs[singular_mask], (scene.model.tip,)
            where = frame_poses(scene.model, scene.data, qs, base, tip)[:, 0, :3, 3]
        s = ObjectJSON("/meshcat/singular")
        sg = s.geometry(sphere(max(size * 0.02, 1e-4)))
        sm = s.material([0.9, 0.05, 0.35, 1.0])
        kids = [s.node("Mesh", geometry=sg, material=sm, matrix=translation(p)) for p in where]
        cmds.append(set_object("/meshcat/singular", s.lower(s.node("Group", children=kids))))
    # -- per-frame overlays (polylines and points given by the caller)
    o_cmds, o_clips = overlay_parts(overlays or {}, motion.times - motion.times[0], size)
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
        cmds.append(set_object(path, _triad(path, triad_len, str(k), stack)))
        cmds.append(set_transform(path, fposes[0, tracked.index(name)]))
    # -- animation
    animation = None
    duration = float(motion.times[-1] - motion.times[0])
    if len(motion.times) > 1:
        times = motion.times - motion.times[0]
        clips = [clip(vis.path, times, poses[:, j]) for j, vis in enumerate(scene.visuals)]
        for k, name in enumerate(triad_frames):
            assert fposes is not None
            clips.append(clip(f"/meshcat/frames/{k}", times, fposes[:, tracked.index(name)]))
        clips += o_clips
        animation = {
            "type": "set_animation",
            "path": "",
            "animations": clips,
            "options": {"play": bool(play), "repetitions": math.inf if loop else 1},
        }
    return Built(cmds, animation, center, radius, duration, float(motion.times[0]))


def _camera_offset(
    points: np.ndarray,
    radii: np.ndarray,
    *,
    fov_deg: float,
    min_aspect: float,
    margin: float = 0.92,
) -> np.ndarray:
    """Camera position (relative to the scene centre) that fits every ball in the view.

    From the direction (1, −1.25, 0.75), the nearest at which every ball (``points`` (M, 3),
    ``radii`` (M,)) is inside ``margin`` of the field of view (aspect at least ``min_aspect``).
    """
    direction = np.array([1.0, -1.25, 0.75])
    direction /= np.linalg.norm(direction)
    right = np.cross(-direction, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, -direction)
    tan_v = math.tan(math.radians(fov_deg) / 2) * margin
    tan_h = tan_v * min_aspect
    depth = points @ direction + radii
    fit = np.maximum(
        (np.abs(points @ up) + radii) / tan_v, (np.abs(points @ right) + radii) / tan_h
    )
    need = fit + depth
    extent = float(np.max(np.linalg.norm(points, axis=1) + radii))
    dist = max(float(need.max()), 1.2 * extent, 1e-3)
    return dist * direction


def _triad(key: str, length: float, label: str, stack: int = 0) -> dict[str, Any]:
    o = ObjectJSON(key)
    r = length * 0.05
    cyl = o.geometry(cylinder(r, length, 12))
    kids = []
    axes = (
        ("x", [0.85, 0.1, 0.1, 1.0], rotation("z", -math.pi / 2)),
        ("y", [0.1, 0.7, 0.1, 1.0], np.eye(4)),
        ("z", [0.1, 0.25, 0.9, 1.0], rotation("x", math.pi / 2)),
    )
    for i, (_axis, rgba, rot) in enumerate(axes):
        at = translation(np.eye(3)[i] * (length / 2)) @ rot
        kids.append(o.node("Mesh", geometry=cyl, material=o.material(rgba), matrix=at))
    tex = o.text_texture(label)
    mat = o.material([1, 1, 1, 1], "SpriteMaterial", map=tex, depthTest=False, transparent=True)
    scale = np.diag([length * 0.75, length * 0.75, length * 0.75, 1.0])
    at = translation([length * 0.25, length * 0.25, length * (0.55 + 0.5 * stack)]) @ scale
    kids.append(o.node("Sprite", material=mat, matrix=at))
    return o.lower(o.node("Group", children=kids))


def scene_commands(model: Model, times: Any, qs: Any, **options: Any) -> list[dict[str, Any]]:
    """The meshcat commands (dicts, before msgpack) that draw and animate a trajectory.

    As the offline page and :meth:`Viewer.animate` send them (the last: ``set_animation``,
    with more than one sample); ``options``: :func:`~hexapod_kin.viewer.page.render_html`'s
    keywords but ``title`` and ``speed``.

    Raises:
        ConfigurationError: Bad shapes or values of ``times``, ``qs``, ``base_poses``,
            ``singular_mask``, ``overlays``.
        FrameNotFoundError: A traced or triad frame does not exist.
        ViewerError: The visual geometry cannot be built.

    """
    built = build_for(model, times, qs, **options)
    return built.static + ([built.animation] if built.animation else [])


def build_for(
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
    scene: Scene | None = None,
) -> Built:
    """Check the inputs, resample, and :func:`build` (``scene`` reused if given)."""
    motion = check_motion(model, times, qs, base_poses)
    mask = check_mask(singular_mask, len(motion.times))
    extra = check_overlays(overlays, len(motion.times))
    if mask is not None and fps is not None:
        raise ParameterError("singular_mask cannot be combined with fps resampling; give fps=None")
    if mask is None:
        given = motion.times
        motion = resample(motion, fps)
        if extra and len(motion.times) != len(given):  # hold each sample's overlay
            idx = np.clip(
                np.searchsorted(given, motion.times + 1e-12, side="right") - 1, 0, len(given) - 1
            )
            extra = {k: v[idx] for k, v in extra.items()}
    return build(
        scene or Scene(model),
        motion,
        trace_frames=_resolve_trace_frames(model, trace_frame),
        triad_frames=resolve_triad_frames(model, frame_triads),
        singular_mask=mask,
        play=play,
        loop=loop,
        overlays=extra,
    )
