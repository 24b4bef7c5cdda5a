"""The live viewer: :class:`Viewer`, a model shown by a loopback meshcat server.

The server (:class:`~hexapod_kin.viewer.server.MeshcatServer`) listens on 127.0.0.1 only;
the ZeroMQ client times out so that no call hangs when the server is gone
(:class:`~hexapod_kin.exceptions.ViewerError`). The scene is the same as the offline page's
(:mod:`hexapod_kin.viewer.scene`).
"""

from __future__ import annotations

import contextlib
from typing import TYPE_CHECKING, Any

import numpy as np

from ..exceptions import ParameterError, ViewerError, choices, positive
from ..gait.stand import default_configuration, frame_poses, standing_base
from .objects import delete, set_property, set_transform
from .scene import PARTS, Scene, build_for, resolve_triad_frames
from .server import Client, MeshcatServer
from .trajectory import check_base_poses

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model

__all__ = ["Viewer"]


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
        ViewerError: The server did not start or does not answer (every method that draws
            raises it too when the server is gone or silent past ``timeout``).
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
        timeout = positive("timeout", timeout, at_most=3600.0)  # seconds
        self.model = model
        self._server = MeshcatServer(start_timeout)
        self._client: Client | None = None
        self._animated = False
        self._triads: tuple[str, ...] = ()
        try:
            self._client = Client(self._server, timeout)
            self._scene = Scene(model)
            q0 = default_configuration(model) if q is None else model.check_q(q)
            pose = standing_base(model, q0) if base_pose is None else base_pose
            q0 = np.asarray(q0)[None, :]
            self._show(np.zeros(1), q0, animate=False, base_poses=pose, trace_frame=False)
        except BaseException:
            self.close()
            raise

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

    def send(self, cmd: dict[str, Any]) -> None:
        """Send one raw meshcat command (a dict as in :func:`scene_commands`)."""
        if self._client is None:
            raise ViewerError("the viewer is closed; open a new Viewer")
        self._client.send(cmd)

    def _show(self, times: Any, qs: Any, *, animate: bool, **options: Any) -> None:
        built = build_for(self.model, times, qs, scene=self._scene, **options)
        # after the checks: a bad call keeps them
        for part in ("trace", "frames", "singular", "overlays"):
            self.send(delete(f"/meshcat/{part}"))
        for cmd in built.static:
            self.send(cmd)
        self._triads = resolve_triad_frames(self.model, options.get("frame_triads", False))
        if animate and built.animation is not None:
            self.send(built.animation)
            self._animated = True

    def display(self, q: Any, base_pose: Any = None) -> None:
        """Show the model at ``q`` (nq,) and root pose ``base_pose`` (4, 4); stops an animation.

        Raises:
            ConfigurationError: Bad ``q`` or ``base_pose``.

        """
        qv = self.model.check_q(q)
        base = check_base_poses(base_pose, 1)
        poses = self._scene.placements(qv[None, :], base)
        if self._animated:  # an empty animation clears meshcat's player
            off = {"play": False}
            self.send({"type": "set_animation", "path": "", "animations": [], "options": off})
            self._animated = False
        for j, vis in enumerate(self._scene.visuals):
            self.send(set_transform(vis.path, poses[0, j]))
        if self._triads:
            frames = frame_poses(self.model, self._scene.data, qv[None, :], base, self._triads)
            for k in range(len(self._triads)):
                self.send(set_transform(f"/meshcat/frames/{k}", frames[0, k]))

    def animate(self, times: Any, qs: Any, **options: Any) -> None:
        """Animate a trajectory in the browser (meshcat's player: play, pause, time, speed).

        ``options``: the keywords of :func:`~hexapod_kin.viewer.scene.scene_commands`
        (``base_poses``, ``trace_frame``, ``frame_triads``, ``singular_mask``, ``fps``,
        ``loop``, ``play``, ``overlays``; see :func:`~hexapod_kin.viewer.page.render_html`).

        Raises:
            ConfigurationError: Bad shapes or values.

        """
        self._show(times, qs, animate=True, **options)

    def set_visible(self, part: str, visible: bool) -> None:
        """Show or hide a part of the scene (one of :data:`PARTS`; else ParameterError)."""
        if part not in PARTS:
            raise ParameterError(f"part={part!r} is not allowed; use one of {choices(PARTS)}")
        self.send(set_property(f"/meshcat/{part}", "visible", bool(visible)))

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
