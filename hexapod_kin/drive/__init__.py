"""The browser cockpit: drive, pose and probe a robot live in the meshcat scene.

:func:`drive` serves one page on 127.0.0.1 (a thread of this process, :mod:`.server`) built on
the viewer's scene (:mod:`.page`), and returns a :class:`DriveSession`: the page's URL, the
state read and set from Python while the page runs, the page inline in a notebook. The robot's
state and its laws (joints, resolved-rate foot targets, body pose with the feet held, the
planner's walk) are :class:`~.state.Cockpit`, usable without any page.

The package, imports pointing one way::

    reach     the driven foot or tool: point, Jacobian, one resolved-rate step, the follow loop
    walking   the planner's walk played cycle by cycle for a live command
    state     the cockpit: state, commands, readouts, the recorded session
    page      the page (scene, panels, websocket) and each tick's state message
    server    the loopback server (Host/Origin checked) and its clock
"""

from __future__ import annotations

import contextlib
import threading
from typing import Any

from ..exceptions import ParameterError
from .state import MODES, Cockpit

__all__ = ["MODES", "Cockpit", "DriveSession", "drive"]


class DriveSession:
    """A running cockpit: its page's URL, the robot's state, :meth:`close` (context manager).

    The setters are the page's commands (:class:`~.state.Cockpit`); the page shows them at
    its next tick. ``_repr_html_`` shows the page inline in a notebook (an iframe of the
    loopback URL).
    """

    def __init__(self, cockpit: Cockpit, server: Any) -> None:
        self.cockpit = cockpit
        self.server = server

    @property
    def url(self) -> str:
        """The page (``http://127.0.0.1:PORT/``)."""
        return str(self.server.url)

    @property
    def running(self) -> bool:
        """Whether the server is serving."""
        return bool(self.server.running)

    def state(self) -> dict[str, Any]:
        """The readout the page prints (q, FK, σ_min, support, velocities...; SI units)."""
        return self.cockpit.readout()

    def set_joint(self, name: str | int, value: float) -> None:
        """Set one joint (see :meth:`Cockpit.set_joint`)."""
        self.cockpit.set_joint(name, value)

    def set_q(self, q: Any) -> None:
        """Set every joint (see :meth:`Cockpit.set_q`)."""
        self.cockpit.set_q(q)

    def set_target(self, xyz: Any, foot: int | str | None = None) -> None:
        """Send the (selected, or ``foot``) foot or tool towards ``xyz`` [m]."""
        if foot is not None:
            self.cockpit.select(foot)
        self.cockpit.set_target(xyz)

    def set_body(self, xyz: Any = (0.0, 0.0, 0.0), rpy: Any = (0.0, 0.0, 0.0)) -> None:
        """Body pose with the feet held (see :meth:`Cockpit.set_body`)."""
        self.cockpit.set_body(xyz, rpy)

    def set_stance(self, scale: float) -> None:
        """Stance width as a factor of the reach (see :meth:`Cockpit.set_stance`)."""
        self.cockpit.set_stance(scale)

    def set_drive(self, axes: Any) -> None:
        """Walk: (forward, left, turn) in [-1, 1] (see :meth:`Cockpit.set_drive`)."""
        self.cockpit.set_drive(axes)

    def set_pattern(self, name: str) -> None:
        """The walk's pattern (see :meth:`Cockpit.set_pattern`)."""
        self.cockpit.set_pattern(name)

    def reset(self) -> None:
        """Back to home / standing (see :meth:`Cockpit.reset`)."""
        self.cockpit.reset()

    def session(self) -> dict[str, Any]:
        """The recorded session (see :meth:`Cockpit.session`)."""
        return self.cockpit.session()

    def timeline(self, rate: float = 50.0) -> Any:
        """The session as a calibrated servo timeline (see :meth:`Cockpit.timeline`)."""
        return self.cockpit.timeline(rate)

    def close(self) -> None:
        """Stop the server (idempotent); the pages show "disconnected"."""
        self.server.close()

    def __enter__(self) -> DriveSession:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _repr_html_(self) -> str:
        return (
            f'<iframe src="{self.url}" width="100%" height="560" '
            'style="border:1px solid #ccc" title="hexapod_kin drive"></iframe>'
        )

    def __repr__(self) -> str:
        state = "running" if self.running else "closed"
        return f"<hexapod_kin drive of {self.cockpit.model.name!r} at {self.url} ({state})>"


def drive(
    robot: Any,
    *,
    feet: Any = None,
    port: int = 0,
    families: bool = True,
    title: str | None = None,
    calibration: Any = None,
) -> DriveSession:
    """Serve the cockpit of ``robot`` on 127.0.0.1 and return its running session.

    Args:
        robot: A loaded model or any source :func:`hexapod_kin.load` takes (a preset such as
            ``hexabot_leg`` or ``hexapod``, a URDF, ``erd:NAME``).
        feet: Feet of a legged URDF without foot links (``"FRAME:X,Y,Z ..."``).
        port: Port on 127.0.0.1 (0: a free one).
        families: Show the distance to the chain's (a legged robot: the moved leg's chain)
            nearest singular family when its families are already derived
            (``hexapod-kin derive SOURCE``; looked up in the background, never derived here:
            no child process).
        title: The page's title.
        calibration: The servos of the downloaded timeline (a
            :class:`~hexapod_kin.export.timeline.Calibration` or a calibration file; None:
            every joint in rad, unlimited).

    Returns:
        The :class:`DriveSession` (open :attr:`DriveSession.url`; ``close()`` when done).

    Raises:
        ParameterError: A bad ``port``.
        SourceError, UrdfError: The robot cannot be loaded.
        OptionalDependencyError: meshcat or tornado is missing.
        ViewerError: The server cannot start or the scene cannot be built.

    """
    from ..kinematics import KinematicModel, load
    from ..viewer.scene import Scene
    from .page import drive_page, state_frame
    from .server import DriveServer

    if not (isinstance(port, int) and not isinstance(port, bool) and 0 <= port <= 65535):
        raise ParameterError(
            f"port={port!r} is not allowed; give 0 (a free port) or a port in 1..65535",
            parameter="port",
            value=repr(port),
            allowed="0..65535",
        )
    model = robot if isinstance(robot, KinematicModel) else load(robot)
    cockpit = Cockpit(model, feet=feet, calibration=calibration)
    scene = Scene(model)
    html = drive_page(cockpit, scene, title=title)
    seq = [0]

    def frame() -> dict[str, Any]:
        seq[0] += 1
        return state_frame(cockpit, scene, seq[0])

    server = DriveServer(cockpit, html, frame, port=port)
    if families:
        threading.Thread(target=_families, args=(cockpit,), daemon=True).start()
    return DriveSession(cockpit, server)


def _families(cockpit: Cockpit) -> None:
    """Find the chain's (each leg's) singular families (a background thread; a failure: none)."""
    from ..singularity import default_rows, families_for

    with contextlib.suppress(Exception):
        if cockpit.legged:
            cockpit.families = tuple(
                families_for(v, default_rows(v), derive=False) for v in cockpit.leg_views
            )
        else:
            cockpit.families = families_for(
                cockpit.model, default_rows(cockpit.model), derive=False
            )
