"""A walk in the browser: the self-contained page and the live viewer, with its overlays.

:func:`walk_page` animates a :class:`~hexapod_kin.gait.walk.GaitRun` with a trace per foot, the
support polygon and the projected centre of mass at every frame
(:func:`hexapod_kin.gait.show.support_polygons`); :func:`walk_html` writes it;
:func:`walk_live` plays it live. The viewer imports the gait, never the other way round.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from .._io import atomic_write
from ..exceptions import ConfigurationError, FrameNotFoundError
from ..gait.show import run_model, support_polygons
from .page import render_html

__all__ = ["walk_html", "walk_live", "walk_page"]


def _joint_columns(run: Any, mdl: Any) -> list[int]:
    """The run's column of each of the model's joints (matched by name)."""
    try:
        return [run.joint_names.index(name) for name in mdl.joint_names]
    except ValueError:
        raise ConfigurationError(
            f"model joints {list(mdl.joint_names)} are not the run's {list(run.joint_names)}",
            parameter="model",
        ) from None


def _foot_frames(run: Any, mdl: Any) -> Any:
    """The frame each foot of the run's robot is on (its origin traced), or None: the default."""
    wb = getattr(run, "robot", None)
    if wb is None:
        return None
    frames = wb.model.frames
    names = [str(frames[frames[wb.model.getFrameId(c)].parentFrame].name) for c in wb.foot_frames]
    try:
        for name in names:
            mdl.frame_id(name)
    except FrameNotFoundError:  # a model without these frames: the page's default
        return None
    return tuple(dict.fromkeys(names))


def walk_live(run: Any, viewer: Any, **options: Any) -> None:
    """Play a walk in a live :class:`hexapod_kin.viewer.Viewer` (support polygon and CoM drawn).

    Args:
        run: A :class:`~hexapod_kin.gait.walk.GaitRun`.
        viewer: A live viewer of the walking robot.
        **options: Passed to ``Viewer.animate`` (``fps``, ``loop``, ``play``).

    Raises:
        ViewerError: The server is gone.
        ConfigurationError: The viewer's model joints are not the run's.

    """
    q = run.q[:, _joint_columns(run, viewer.model)]
    poly, com = support_polygons(run)
    overlays = {"support_polygon": poly, "com": com}
    viewer.animate(run.t, q, base_poses=run.base_poses, overlays=overlays, **options)


def walk_page(run: Any, *, model: Any = None, title: str | None = None, **options: Any) -> str:
    """The self-contained animation page of a walk (opens from disk, no network).

    Args:
        run: A :class:`~hexapod_kin.gait.walk.GaitRun`.
        model: The loaded robot, joints matched to the run's by name (default
            :func:`~hexapod_kin.gait.show.run_model`: ``run.robot`` or the built-in hexapod).
        title: Page title (default: pattern, terrain and the minimum margin).
        **options: Passed to :func:`~hexapod_kin.viewer.page.render_html` (``fps``...).

    Raises:
        OptionalDependencyError: The viewer extra (meshcat) is missing.
        ConfigurationError: The model's joints are not the run's.

    """
    mdl = run_model(run) if model is None else model
    cols = _joint_columns(run, mdl)
    if options.get("trace_frame") is None:  # a trace per foot
        options["trace_frame"] = _foot_frames(run, mdl)
    poly, com = support_polygons(run)
    label = title or (
        f"hexapod_kin: {run.table.name} gait on {run.settings.get('terrain', '?')} terrain "
        f"(min margin {1e3 * run.min_margin:.1f} mm)"
    )
    return render_html(
        mdl,
        run.t,
        run.q[:, cols],
        base_poses=run.base_poses,
        title=label,
        overlays={"support_polygon": poly, "com": com},
        **options,
    )


def walk_html(run: Any, path: str | os.PathLike[str], **options: Any) -> Path:
    """Write :func:`walk_page` (``options``: its keywords) to ``path`` atomically; return it."""
    return atomic_write(path, walk_page(run, **options))
