"""The cockpit's loopback server: one page, its websocket, the clock (a thread of this process).

A tornado application on its own event loop in a thread: ``GET /`` the page, ``GET
/meshcat.js`` meshcat's bundle (offline, no CDN), ``/ws`` the websocket. It binds 127.0.0.1
only; every request's Host, and the websocket's Origin, must name this server's own port on a
loopback name (:data:`hexapod_kin.viewer.bridge.HOSTS`), the shape a DNS-rebinding page cannot
take. A periodic callback advances the :class:`~.state.Cockpit` in real time and sends the state
to every page. A message from a page is one JSON object; a bad one is answered with an
``error`` message naming what is wrong and otherwise dropped.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ..exceptions import HexapodKinError, OptionalDependencyError, ViewerError
from ..viewer.bridge import FORBIDDEN, HOSTS
from ..viewer.objects import INSTALL_HINT, bundle
from ..viewer.server import LOOPBACK
from .state import Cockpit

__all__ = ["DriveServer", "TICK"]

#: Clock period of the server [s] (the state is sent to the pages at this rate).
TICK = 0.02
#: Largest message a page may send [bytes].
MAX_MESSAGE = 16_384


def handle(cockpit: Cockpit, msg: Any) -> dict[str, Any] | None:
    """Apply one page message to the cockpit; return the direct answer (or None).

    Raises:
        HexapodKinError: A message with a bad type or bad values (the server answers it).
        KeyError, TypeError, ValueError: A malformed message (the server answers it).

    """
    if not isinstance(msg, dict) or not isinstance(msg.get("type"), str):
        raise TypeError("a message is a JSON object with a string 'type'")
    kind = msg["type"]
    if kind == "joint":
        cockpit.set_joint(str(msg["name"]), msg["value"])
    elif kind == "q":
        cockpit.set_q(msg["q"])
    elif kind == "mode":
        cockpit.set_mode(str(msg["mode"]))
    elif kind == "foot":
        cockpit.select(msg["foot"])
    elif kind == "target":
        cockpit.set_target(msg["xyz"])
    elif kind == "body":
        cockpit.set_body(msg.get("xyz", (0, 0, 0)), msg.get("rpy", (0, 0, 0)))
    elif kind == "stance":
        cockpit.set_stance(msg["scale"])
    elif kind == "drive":
        cockpit.set_drive(msg["axes"])
    elif kind == "pattern":
        cockpit.set_pattern(str(msg["pattern"]))
    elif kind == "push":
        cockpit.push(msg["force"])
    elif kind == "reset":
        cockpit.reset()
    elif kind == "session":
        return session_reply(cockpit)
    elif kind == "ping":
        return {"type": "pong", "t": msg.get("t")}
    else:
        raise KeyError(
            f"type={kind!r}: use one of 'joint', 'q', 'mode', 'foot', 'target', 'body', "
            "'stance', 'drive', 'pattern', 'push', 'reset', 'session', 'ping'"
        )
    return None


def session_reply(cockpit: Cockpit) -> dict[str, Any]:
    """The downloads: the session (JSON) and its servo timeline (CSV) or why it is refused."""
    csv, refused = None, None
    try:
        csv = cockpit.timeline().to_csv()
    except HexapodKinError as exc:  # a limit (LimitError), too short a session
        refused = f"timeline refused: {exc}"
    return {"type": "session", "session": cockpit.session(), "timeline": csv, "refused": refused}


class DriveServer:
    """The loopback server of one cockpit (a thread; :meth:`close` stops it and joins).

    Args:
        cockpit: The robot's :class:`~.state.Cockpit`.
        page: The page's HTML.
        frame: Callable returning the state message sent each tick (a JSON-ready dict).
        port: Port on 127.0.0.1 (0: a free one).

    Raises:
        OptionalDependencyError: tornado is missing.
        ViewerError: The port cannot be bound.

    """

    def __init__(
        self,
        cockpit: Cockpit,
        page: str,
        frame: Callable[[], dict[str, Any]],
        port: int = 0,
    ) -> None:
        try:
            import tornado.web  # noqa: F401
        except ImportError:  # pragma: no cover - tornado comes with meshcat
            raise OptionalDependencyError(f"the cockpit needs tornado; {INSTALL_HINT}") from None
        self.cockpit = cockpit
        self._page = page.encode("utf-8")
        self._script = bundle().encode("utf-8")
        self._frame = frame
        self._sockets: set[Any] = set()
        self.pages_seen = 0
        self._last = ""
        self.last_close = math.inf
        self._loop: Any = None
        self._error: BaseException | None = None
        self._ready = threading.Event()
        self._stopped = threading.Event()
        self.port = 0
        self._thread = threading.Thread(
            target=self._run, args=(int(port),), name="hexapod-kin-drive", daemon=True
        )
        self._thread.start()
        self._ready.wait(30)
        if self._error is not None:
            raise ViewerError(f"the cockpit server could not start: {self._error}")
        if not self.port:
            self.close()
            raise ViewerError("the cockpit server did not start within 30 s")

    @property
    def url(self) -> str:
        """The page: ``http://127.0.0.1:PORT/``."""
        return f"http://{LOOPBACK}:{self.port}/"

    @property
    def running(self) -> bool:
        """Whether the server thread is serving."""
        return self._thread.is_alive() and not self._stopped.is_set()

    @property
    def pages(self) -> int:
        """Pages connected now."""
        return len(self._sockets)

    # ------------------------------------------------------------------ the thread
    def _run(self, port: int) -> None:  # noqa: C901 - the handlers share the closure
        import tornado.httpserver
        import tornado.ioloop
        import tornado.netutil
        import tornado.web
        import tornado.websocket

        owner = self
        asyncio.set_event_loop(asyncio.new_event_loop())
        allowed: set[str] = set()

        def local(value: str | None) -> bool:
            if not value:
                return False
            return value.split("://", 1)[-1].rstrip("/").lower() in allowed

        class Guarded(tornado.web.RequestHandler):
            def prepare(self) -> None:
                if not local(self.request.headers.get("Host")):
                    self.set_status(403)
                    self.finish(FORBIDDEN)

            def set_default_headers(self) -> None:
                self.set_header("Cache-Control", "no-store")
                self.set_header("X-Content-Type-Options", "nosniff")

        class Page(Guarded):
            def get(self) -> None:
                self.set_header("Content-Type", "text/html; charset=utf-8")
                self.write(owner._page)

        class Script(Guarded):
            def get(self) -> None:
                self.set_header("Content-Type", "text/javascript; charset=utf-8")
                self.write(owner._script)

        class Socket(tornado.websocket.WebSocketHandler):
            def check_origin(self, origin: str) -> bool:
                return local(origin) and local(self.request.headers.get("Host"))

            def prepare(self) -> Any:
                if not local(self.request.headers.get("Host")):
                    self.set_status(403)
                    self.finish(FORBIDDEN)
                return None

            def open(self, *args: str, **kwargs: str) -> None:
                owner._last = ""  # the new page gets the state at the next tick
                owner._sockets.add(self)
                owner.pages_seen += 1
                owner.last_close = math.inf

            def on_close(self) -> None:
                owner._sockets.discard(self)
                if not owner._sockets:
                    owner.last_close = time.monotonic()

            def on_message(self, message: str | bytes) -> None:
                owner._on_message(self, message)

        try:
            app = tornado.web.Application(
                [(r"/", Page), (r"/meshcat\.js", Script), (r"/ws", Socket)],
                websocket_max_message_size=MAX_MESSAGE,
            )
            socks = tornado.netutil.bind_sockets(port, address=LOOPBACK)
            server = tornado.httpserver.HTTPServer(app, max_body_size=MAX_MESSAGE)
            server.add_sockets(socks)
            self.port = int(socks[0].getsockname()[1])
            allowed.update(f"{h}:{self.port}" for h in HOSTS)
            loop = tornado.ioloop.IOLoop.current()
            self._loop = loop
            last = [time.monotonic()]

            def tick() -> None:
                now = time.monotonic()
                try:
                    self.cockpit.advance(now - last[0])
                finally:
                    last[0] = now
                if self._sockets:
                    self._push()

            clock = tornado.ioloop.PeriodicCallback(tick, TICK * 1000)
            clock.start()
        except BaseException as exc:  # noqa: BLE001 - reported by the constructor
            self._error = exc
            self._ready.set()
            return
        self._ready.set()
        try:
            loop.start()
        finally:
            clock.stop()
            server.stop()
            for sock in list(self._sockets):
                with contextlib.suppress(Exception):
                    sock.close()
            for s in socks:
                s.close()
            with contextlib.suppress(Exception):
                loop.close(all_fds=True)
            self._stopped.set()

    def _on_message(self, sock: Any, message: str | bytes) -> None:
        """Answer one page message; a bad one gets an ``error`` reply and is dropped."""
        ident: Any = None
        try:
            msg = json.loads(message)
            ident = msg.get("id") if isinstance(msg, dict) else None
            reply = handle(self.cockpit, msg)
        except (HexapodKinError, KeyError, TypeError, ValueError) as exc:
            text = str(exc) if not isinstance(exc, KeyError) else f"missing or bad key {exc}"
            self._send(sock, {"type": "error", "id": ident, "error": text[:500]})
            return
        self._send(sock, reply or {"type": "ack", "id": ident})
        self._push()  # a command is shown at once, not at the next tick

    def _push(self) -> None:
        """Send the state to every page when it changed since the last one sent (one dump)."""
        frame = self._frame()
        readout = frame.get("readout", {})
        stamp = frame.pop("seq", None), readout.pop("time", None)
        text = json.dumps(frame, default=_plain)  # the state without its clock
        if text == self._last or not self._sockets:
            return
        self._last = text
        clock = json.dumps({"seq": stamp[0], "time": stamp[1]})
        text = text[:-1] + ", " + clock[1:]  # {..., "seq": n, "time": t}
        for sock in list(self._sockets):
            with contextlib.suppress(Exception):
                sock.write_message(text)

    def _send(self, sock: Any, msg: dict[str, Any]) -> None:
        with contextlib.suppress(Exception):
            sock.write_message(json.dumps(msg, default=_plain))

    def close(self) -> None:
        """Stop serving and join the thread (idempotent)."""
        loop = self._loop
        if loop is not None and self._thread.is_alive():
            with contextlib.suppress(RuntimeError):
                loop.add_callback(loop.stop)
        self._thread.join(10)


def _plain(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (np.floating, np.integer)):
        return obj.item()
    raise TypeError(f"{type(obj).__name__} is not JSON")
