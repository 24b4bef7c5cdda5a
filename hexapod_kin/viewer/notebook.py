"""The viewer inside Jupyter: the self-contained page shown inline, no server.

:func:`show` (a model, a pose or a trajectory) and :func:`show_walk` (a
:class:`~hexapod_kin.gait.walk.GaitRun`) return a :class:`NotebookView` whose
``_repr_html_`` is a sandboxed ``<iframe srcdoc="...">`` (``allow-scripts`` only) holding the
page of :func:`~hexapod_kin.viewer.render_html`: a saved notebook replays offline.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .._io import atomic_write
from .._page import check_height, frame
from .page import render_html
from .walk import walk_page

__all__ = ["NotebookView", "show", "show_walk"]


@dataclass(frozen=True)
class NotebookView:
    """A self-contained viewer ``page`` (the whole HTML), shown inline by Jupyter ``height`` px."""

    page: str
    height: int = 480

    def __post_init__(self) -> None:
        check_height(self.height)

    def _repr_html_(self) -> str:
        """The page in a sandboxed ``<iframe srcdoc>`` (HTML-escaped, quotes included)."""
        return frame(self.page, height=self.height)

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the page to ``path`` (atomically); it opens from disk with no server."""
        return atomic_write(path, self.page)


def show(
    model: Any, times: Any = None, qs: Any = None, *, height: int = 480, **options: Any
) -> NotebookView:
    """A model, a pose or a trajectory, inline in a notebook (its ``_repr_html_``).

    Args:
        model: A loaded model, or anything :func:`hexapod_kin.load` takes (a preset name, a
            table file, a URDF path, ``erd:NAME``).
        times: (N,) sample times [s] of a trajectory (None: a still pose).
        qs: (N, nq) joint values [rad]/[m], or one (nq,) pose (default: the neutral pose).
        height: Frame height [px].
        **options: Passed to :func:`~hexapod_kin.viewer.render_html` (``trace_frame``,
            ``frame_triads``, ``fps``, ``speed``, ``title``...).

    Raises:
        OptionalDependencyError: meshcat (the ``viewer`` extra) is missing.
        ConfigurationError: Bad ``times``/``qs``.

    """
    from ..kinematics import KinematicModel, load

    mdl = model if isinstance(model, KinematicModel) else load(model)
    if qs is None:
        qs = mdl.neutral()
    q = np.asarray(qs, dtype=float)
    if times is None:
        times = np.zeros(1) if q.ndim == 1 else np.arange(len(q)) / 30.0
    return NotebookView(render_html(mdl, times, q, **options), height=height)


def show_walk(run: Any, *, model: Any = None, height: int = 480, **options: Any) -> NotebookView:
    """A walk (a :class:`~hexapod_kin.gait.walk.GaitRun`) animated inline, as ``walk_html``.

    Args:
        run: The walk.
        model: The loaded robot (default: the hexapod preset).
        height: Frame height [px].
        **options: Passed to :func:`~hexapod_kin.viewer.render_html` (``fps``, ``speed``...).

    Raises:
        OptionalDependencyError: meshcat (the ``viewer`` extra) is missing.

    """
    return NotebookView(walk_page(run, model=model, **options), height=height)
