"""Browser 3D viewer (meshcat): a live server on 127.0.0.1, animations, self-contained HTML.

One scene description, two outputs:

* :func:`export_html` writes a single HTML file: meshcat's JavaScript bundle is inlined and
  the scene and its animation are meshcat commands (msgpack, base64) decoded by the page
  itself, so the file opens from disk (``file://``) with no server and no network (a
  Content-Security-Policy in the page forbids every fetch).
* :class:`Viewer` is the live viewer: a meshcat server subprocess whose web server and ZeroMQ
  socket listen on 127.0.0.1 only (meshcat 0.3.2's own server binds the web server to all
  interfaces; ours binds explicitly), with free ports, stopped with its process group on
  exit, on error and at interpreter exit, and a ZeroMQ client with timeouts so that no call
  hangs when the server is gone (:class:`~hexapod_kin.exceptions.ViewerError`).

Scene layout (meshcat paths, all under ``/meshcat``, which is shifted so that the centre of
the scene sits at the origin, the orbit camera's target)::

    /meshcat/robot/<geometry>   visual geometry of the URDF (boxes, cylinders, spheres, meshes)
    /meshcat/trace              the path of the traced frame(s) (feet), drawn as thin tubes
    /meshcat/frames/<k>         triads of the Khalil frames (x red, y green, z blue), each
                                labelled with its index j (frame 0 = base of the chain)
    /meshcat/singular           red spheres where the trajectory is near-singular
    /meshcat/ground             a grid at the lowest point of the scene

Poses are Pinocchio's ``oMx`` (pose of x in the world frame of the model), 4×4 arrays; with
``base_poses`` the whole model is moved by ``worldMroot`` (a floating body).

The work is split in three modules, imports pointing one way: :mod:`hexapod_kin._scene`
builds the scene (meshcat commands, animation data, the HTML page) from a model and a
trajectory; :mod:`hexapod_kin._meshcat_server` runs the loopback server and its ZeroMQ
client; this module is the public face (the live :class:`Viewer`, demo poses and motions,
the headless Chromium launcher shared by the tests and ``tools/screenshots.py``) and
re-exports the public names of the other two.
"""

from __future__ import annotations

import contextlib
import sys
from typing import TYPE_CHECKING, Any

import numpy as np

from ._meshcat_server import LOOPBACK, MeshcatServer, _Client
from ._scene import (
    MAX_SAMPLES,
    PARTS,
    _build_for,
    _bundle,  # noqa: F401 - re-exported for tools/bench_viewer.py
    _check_base_poses,
    _clip,  # noqa: F401 - re-exported for tools/bench_viewer.py
    _delete,
    _Scene,
    _set_property,
    _set_transform,
    _triad_frames,
    export_html,
    iframe,
    khalil_frames,
    scene_commands,
)
from .exceptions import (
    ParameterError,
    ViewerError,
    choices,
)
from .gait.stand import default_configuration, standing_base

if TYPE_CHECKING:  # pragma: no cover
    from .model import Model

__all__ = [
    "LOOPBACK",
    "MAX_SAMPLES",
    "PARTS",
    "MeshcatServer",
    "Viewer",
    "export_html",
    "iframe",
    "khalil_frames",
    "scene_commands",
]

class Viewer:
    """Live meshcat viewer of a model, served on 127.0.0.1 (context manager).

    Example:
        >>> with Viewer(load("hexapod")) as v:          # doctest: +SKIP
        ...     print(v.url)                            # open it in a browser
        ...     v.display(default_configuration(v.model))
        ...     v.animate(*gait.demo_trajectory(v.model))

    Args:
        model: A loaded model.
        q: Initial configuration (default :func:`default_configuration`).
        base_pose: Initial world pose (4, 4) of the root (default: a hexapod stands on z = 0).
        timeout: Seconds every call waits for the server before raising ViewerError.
        start_timeout: Seconds to wait for the server to start.

    Raises:
        ViewerError: The server did not start or does not answer.
        OptionalDependencyError: meshcat is not installed.

    """

    def __init__(
        self,
        model: Model,
        *,
        q: Any = None,
        base_pose: Any = None,
        timeout: float = 5.0,
        start_timeout: float = 30.0,
    ) -> None:
        if not (isinstance(timeout, (int, float)) and 0 < timeout <= 3600):
            raise ParameterError(f"timeout={timeout!r} is not allowed; give seconds in (0, 3600]")
        self.model = model
        self._server = MeshcatServer(start_timeout)
        self._client: _Client | None = None
        self._animated = False
        self._triads: tuple[str, ...] = ()
        try:
            self._client = _Client(self._server, timeout)
            self._scene = _Scene(model)
            q0 = default_configuration(model) if q is None else model.check_q(q)
            pose = standing_base(model, q0) if base_pose is None else base_pose
            self._show(np.asarray(q0)[None, :], pose, animate=False)
        except BaseException:
            self.close()
            raise

    # -------------------------------------------------------------- properties
    @property
    def url(self) -> str:
        """The page to open in a browser (``http://127.0.0.1:PORT/static/``)."""
        return self._server.web_url

    @property
    def zmq_url(self) -> str:
        """The server's command socket (``tcp://127.0.0.1:PORT``)."""
        return self._server.zmq_url

    @property
    def pid(self) -> int:
        """Process id of the server subprocess."""
        return self._server.pid

    @property
    def server(self) -> MeshcatServer:
        """The server process handle."""
        return self._server

    # -------------------------------------------------------------- drawing
    def send(self, cmd: dict[str, Any]) -> None:
        """Send one raw meshcat command (a dict as in :func:`scene_commands`).

        Raises:
            ViewerError: The server is gone or did not answer within the timeout.

        """
        if self._client is None:
            raise ViewerError("the viewer is closed; open a new Viewer")
        self._client.send(cmd)

    def _show(self, qs: np.ndarray, base: Any, *, animate: bool, times: Any = None,
              **kwargs: Any) -> None:
        if times is None:
            times = np.arange(len(qs), dtype=float)
        triads = kwargs.get("frame_triads", False)
        built = _build_for(self.model, times, qs, base, kwargs.get("trace_frame", False),
                           triads, kwargs.get("singular_mask"), kwargs.get("fps"),
                           kwargs.get("play", True), kwargs.get("loop", True), scene=self._scene)
        for part in ("trace", "frames", "singular"):  # after the checks: a bad call keeps them
            self.send(_delete(f"/meshcat/{part}"))
        for cmd in built.static:
            self.send(cmd)
        self._triads = _triad_frames(self.model, triads)
        if animate and built.animation is not None:
            self.send(built.animation)
            self._animated = True

    def display(self, q: Any, base_pose: Any = None) -> None:
        """Show the model at configuration ``q`` (nq,) (and root pose ``base_pose`` (4, 4)).

        A running animation is stopped; the frame triads, if shown, follow the pose.

        Raises:
            ConfigurationError: Bad ``q`` or ``base_pose``.
            ViewerError: The server is gone or did not answer within the timeout.

        """
        qv = self.model.check_q(q)
        base = _check_base_poses(base_pose, 1)
        poses = self._scene.placements(qv[None, :], base)
        if self._animated:  # an empty animation clears meshcat's player
            self.send({"type": "set_animation", "path": "", "animations": [],
                       "options": {"play": False}})
            self._animated = False
        for j, vis in enumerate(self._scene.visuals):
            self.send(_set_transform(vis.path, poses[0, j]))
        if self._triads:
            frames = self._scene.frame_poses(qv[None, :], base, self._triads)
            for k in range(len(self._triads)):
                self.send(_set_transform(f"/meshcat/frames/{k}", frames[0, k]))

    def animate(
        self,
        times: Any,
        qs: Any,
        *,
        base_poses: Any = None,
        trace_frame: Any = None,
        frame_triads: Any = False,
        singular_mask: Any = None,
        fps: float | None = None,
        loop: bool = True,
        play: bool = True,
    ) -> None:
        """Animate a trajectory in the browser (meshcat's player: play, pause, time, speed).

        Arguments as in :func:`export_html`.

        Raises:
            ConfigurationError: Bad shapes or values.
            ViewerError: The server is gone or did not answer within the timeout.

        """
        self._show(np.asarray(qs), base_poses, animate=True, times=times,
                   trace_frame=trace_frame, frame_triads=frame_triads,
                   singular_mask=singular_mask, fps=fps, loop=loop, play=play)

    def set_visible(self, part: str, visible: bool) -> None:
        """Show or hide a part of the scene (one of :data:`PARTS`).

        Raises:
            ParameterError: Unknown part.
            ViewerError: The server is gone or did not answer within the timeout.

        """
        if part not in PARTS:
            raise ParameterError(f"part={part!r} is not allowed; use one of {choices(PARTS)}")
        self.send(_set_property(f"/meshcat/{part}", "visible", bool(visible)))

    # -------------------------------------------------------------- lifetime
    def close(self) -> None:
        """Disconnect and stop the server (idempotent)."""
        client, self._client = self._client, None
        if client is not None:
            with contextlib.suppress(Exception):
                client.close()
        self._server.close()

    def __enter__(self) -> Viewer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "running" if self._server.running else "closed"
        url = self._server.__dict__.get("web_url")
        return f"<hexapod_kin Viewer of {self.model.name!r} at {url} ({state})>"



if __name__ == "__main__":  # pragma: no cover - the server runs from hexapod_kin._meshcat_server
    from ._meshcat_server import _serve

    if sys.argv[1:] == ["--serve"]:
        _serve()
    else:
        sys.exit("usage: python -m hexapod_kin.viewer --serve  (internal: the live server)")
