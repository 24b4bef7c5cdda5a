"""The walk in the browser: a self-contained HTML animation (viewer imported lazily).

:func:`walk_html` animates a :class:`~hexapod_kin.gait.walk.GaitRun` with
:func:`hexapod_kin.viewer.export_html`: the body and legs, the foot traces, and at every frame
the support polygon (the convex hull of the stance feet, drawn on the ground under them) and
the centre of mass projected on it (the ``overlays`` of the page); :func:`walk_live` plays
the same in the live viewer.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["run_model", "support_polygons", "walk_html", "walk_live"]


def _hull(points: np.ndarray) -> np.ndarray:
    """Counter-clockwise convex hull (K, 2) of 2-D points (Andrew's monotone chain)."""
    pts = sorted(map(tuple, points))
    if len(pts) <= 2:
        return np.array(pts, dtype=float).reshape(-1, 2)

    def half(seq: list[tuple[float, ...]]) -> list[tuple[float, ...]]:
        out: list[tuple[float, ...]] = []
        for p in seq:
            while (
                len(out) >= 2
                and (
                    (out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                    - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])
                )
                <= 0
            ):
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1], dtype=float)


def support_polygons(run: Any, lift: float = 0.002) -> tuple[np.ndarray, np.ndarray]:
    """Per sample: the closed support polygon (N, L + 1, 3) and the projected CoM (N, 1, 3).

    The polygon's vertices are the stance feet on the hull, counter-clockwise, at the feet's
    heights plus ``lift`` [m]; it is padded by repeating its last vertex and closed on the
    first (fixed shape for the animation). The CoM is drawn at the mean stance-foot height.
    """
    n, nl = run.support.shape
    poly = np.empty((n, nl + 1, 3))
    com = np.empty((n, 1, 3))
    for i in range(n):
        feet = run.feet[i, run.support[i]]
        if len(feet) == 0:
            feet = run.feet[i]
        hull = _hull(feet[:, :2])
        z = np.array([feet[np.argmin(np.hypot(*(feet[:, :2] - v).T)), 2] for v in hull]) + lift
        verts = np.column_stack([hull, z])
        k = len(verts)
        poly[i, :k] = verts
        poly[i, k:nl] = verts[-1]
        poly[i, nl] = verts[0]
        com[i, 0] = [run.com[i, 0], run.com[i, 1], float(feet[:, 2].mean()) + lift]
    return poly, com


def _joint_columns(run: Any, mdl: Any) -> list[int]:
    from ..exceptions import ConfigurationError

    try:
        return [run.joint_names.index(name) for name in mdl.joint_names]
    except ValueError:
        raise ConfigurationError(
            f"model joints {list(mdl.joint_names)} are not the run's {list(run.joint_names)}",
            parameter="model",
        ) from None


def run_model(run: Any) -> Any:
    """The loaded model (:func:`hexapod_kin.load`) of the robot that walks ``run``.

    The run's own robot (``run.robot``, a whole-body model) when it has one: its Hexapod
    table, else its source or URDF text; otherwise the built-in ``hexapod``.

    Raises:
        ConfigurationError: The run's robot cannot be loaded as a model.

    """
    from .. import load
    from ..exceptions import ConfigurationError
    from ..params import Hexapod

    robot = getattr(run, "robot", None)
    if robot is None:
        return load("hexapod")
    params = getattr(robot, "params", None)
    if isinstance(params, Hexapod):
        return load(params)
    if getattr(robot, "kinematic", None) is not None:  # the robot that walked, as loaded
        return robot.kinematic
    for attr in ("urdf", "source"):
        src = getattr(robot, attr, None)
        if src is not None:
            return load(src)
    raise ConfigurationError(
        f"the run's robot {robot!r} has no table, source or URDF to draw; pass model=",
        parameter="model",
    )


def walk_live(run: Any, viewer: Any, **options: Any) -> None:
    """Play a walk in a live :class:`hexapod_kin.viewer.Viewer` of the hexapod (with overlays).

    The viewer animates the robot and the foot traces (``Viewer.animate``); the support
    polygon and the projected centre of mass are then added to the same animation.

    Args:
        run: A :class:`~hexapod_kin.gait.walk.GaitRun`.
        viewer: A live viewer of the hexapod model.
        **options: Passed to ``Viewer.animate`` (``fps``, ``loop``, ``play``).

    Raises:
        ViewerError: The server is gone.
        ConfigurationError: The viewer's model joints are not the run's.

    """
    from ..viewer import scene_commands

    q = run.q[:, _joint_columns(run, viewer.model)]
    viewer.animate(run.t, q, base_poses=run.base_poses, **options)
    poly, com = support_polygons(run)
    cmds = scene_commands(
        viewer.model,
        run.t,
        q,
        base_poses=run.base_poses,
        overlays={"support_polygon": poly, "com": com},
        **options,
    )
    viewer.send({"type": "delete", "path": "/meshcat/overlays"})
    for cmd in cmds:
        if cmd["type"] == "set_animation" or str(cmd.get("path", "")).startswith(
            "/meshcat/overlays/"
        ):
            viewer.send(cmd)


def walk_html(
    run: Any,
    path: str | os.PathLike[str],
    *,
    model: Any = None,
    title: str | None = None,
    **options: Any,
) -> Path:
    """Write the self-contained animation of a walk (opens from disk, no network).

    Args:
        run: A :class:`~hexapod_kin.gait.walk.GaitRun`.
        path: Destination ``.html`` (written atomically).
        model: The loaded robot (default :func:`run_model`: the run's own robot,
            ``run.robot``, or the built-in hexapod); its joints are matched to the run's by
            name.
        title: Page title (default: pattern, terrain and the minimum margin).
        **options: Passed to :func:`hexapod_kin.viewer.export_html` (``fps``, ``speed``...).

    Returns:
        The path written.

    Raises:
        OptionalDependencyError: The viewer extra (meshcat) is missing.
        ConfigurationError: The model's joints are not the run's.

    """
    from ..viewer import export_html

    mdl = run_model(run) if model is None else model
    cols = _joint_columns(run, mdl)
    poly, com = support_polygons(run)
    label = title or (
        f"hexapod_kin: {run.table.name} gait on {run.settings.get('terrain', '?')} terrain "
        f"(min margin {1e3 * run.min_margin:.1f} mm)"
    )
    return export_html(
        mdl,
        run.t,
        run.q[:, cols],
        path,
        base_poses=run.base_poses,
        title=label,
        overlays={"support_polygon": poly, "com": com},
        **options,
    )
