"""Browser 3D viewer (meshcat): a live server on 127.0.0.1, animations, self-contained HTML.

One scene description, two outputs:

* :func:`export_html` writes a single HTML file: meshcat's JavaScript bundle is inlined and
  the scene and its animation are meshcat commands (msgpack) decoded by the page itself, so
  the file opens from disk (``file://``) with no server and no network (a
  Content-Security-Policy in the page forbids every fetch).
* :class:`Viewer` is the live viewer: a meshcat server subprocess whose web server and ZeroMQ
  socket listen on 127.0.0.1 only, with free ports, stopped with its process group on exit,
  on error and at interpreter exit, and a ZeroMQ client with timeouts so that no call hangs
  when the server is gone (:class:`~hexapod_kin.exceptions.ViewerError`).

The package, imports pointing one way (left to right)::

    objects     three.js JSON objects, primitive geometries, meshcat commands, msgpack
    meshes      mesh files -> compact indexed geometry (float32 vertices, deduplicated)
    trajectory  times/q/root poses checked and resampled; keyframe clips
    overlays    caller-given per-frame polylines
    scene       the model's visual geometry and every command of a trajectory
    page        the offline page (render_html, export_html, iframe), on hexapod_kin._page
    walk        a walk's page and live playback, with its support polygon and CoM
    server      the loopback meshcat server and its ZeroMQ client (bridge: its child)
    live        the live Viewer

The scene layout and the pose convention are described in :mod:`hexapod_kin.viewer.scene`.
"""

from __future__ import annotations

from .live import Viewer
from .page import export_html, iframe, render_html
from .scene import PARTS, khalil_frames, scene_commands
from .server import LOOPBACK, MeshcatServer
from .trajectory import MAX_SAMPLES
from .walk import walk_html, walk_live, walk_page

__all__ = [
    "LOOPBACK",
    "MAX_SAMPLES",
    "PARTS",
    "MeshcatServer",
    "Viewer",
    "export_html",
    "iframe",
    "khalil_frames",
    "render_html",
    "scene_commands",
    "walk_html",
    "walk_live",
    "walk_page",
]
