"""Browser 3D viewer (meshcat): a live server on 127.0.0.1, animations, self-contained HTML.

:func:`export_html` writes one HTML file that opens from disk with no server and no network
(meshcat's bundle and the scene inlined; its Content-Security-Policy forbids every fetch);
:class:`Viewer` is the live viewer (a loopback meshcat server, a client with timeouts).
Modules, imports pointing left to right: ``objects`` (three.js objects, msgpack), ``meshes``,
``trajectory`` (checks, resampling), ``overlays``, ``scene`` (geometry and commands), ``page``,
``walk``, ``server`` (+ its child ``bridge``), ``live``.
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
