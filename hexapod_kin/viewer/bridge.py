"""The child process of :class:`~hexapod_kin.viewer.server.MeshcatServer` (internal).

``python -m hexapod_kin.viewer.bridge --serve`` runs meshcat's websocket bridge with its web
server and ZeroMQ socket bound to 127.0.0.1 only (meshcat 0.3.2's own server binds the web
server to all interfaces). A module of its own so that running it never re-imports the
module that starts it.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import sys
from typing import Any

from .server import LOOPBACK

#: The names a browser may use for the server in its Host and Origin headers, with its port:
#: the loopback address it listens on and the loopback names that resolve to it. Nothing else
#: (a DNS name, even one resolving to 127.0.0.1, is what a DNS-rebinding page sends).
HOSTS = (LOOPBACK, "localhost", "[::1]")
FORBIDDEN = "forbidden: this viewer answers to 127.0.0.1, localhost and [::1] on its port only"


def serve() -> None:  # pragma: no cover - runs in the server subprocess
    """Run meshcat's websocket bridge bound to 127.0.0.1 (the child of :class:`MeshcatServer`).

    Prints one JSON line ``{"zmq_url", "web_url", "pid"}`` and serves until stdin closes (the
    parent went away), SIGTERM or SIGINT.
    """
    import socket
    import threading

    import tornado.httpserver
    import tornado.ioloop
    import tornado.netutil
    import tornado.web
    import zmq
    from meshcat.servers.tree import SceneTree
    from meshcat.servers.zmqserver import (
        VIEWER_HTML,
        VIEWER_ROOT,
        StaticFileHandlerNoCache,
        WebSocketHandler,
        ZMQWebSocketBridge,
    )

    def refused(handler: Any) -> bool:
        """Answer 403 to a request whose Host is not this server's own (True: refused)."""
        if local(handler.request.headers.get("Host")):
            return False
        handler.set_status(403)
        handler.finish(FORBIDDEN)
        return True

    class LoopbackStatic(StaticFileHandlerNoCache):
        """The viewer's files, for a request whose Host names this server's own port."""

        def prepare(self) -> Any:
            return None if refused(self) else super().prepare()

    allowed_hosts: set[str] = set()  # "127.0.0.1:PORT", "localhost:PORT", "[::1]:PORT"

    def local(value: str | None) -> bool:
        """A Host or Origin naming this server's own port on a loopback name (:data:`HOSTS`)."""
        if not value:
            return False
        host = value.split("://", 1)[-1].rstrip("/").lower()
        return host in allowed_hosts

    class LoopbackSocket(WebSocketHandler):
        """Meshcat's websocket, for this server's own Host and Origin only.

        A request whose Host or Origin is not one of :data:`HOSTS` with this server's port (the
        shape of a DNS-rebinding page: Host and Origin both ``evil.example:PORT``) is refused.
        """

        def check_origin(self, origin: str) -> bool:
            return local(origin) and local(self.request.headers.get("Host"))

        def prepare(self) -> Any:
            return None if refused(self) else super().prepare()

    class LoopbackBridge(ZMQWebSocketBridge):
        COMMANDS = frozenset(("set_object", "set_transform", "set_property", "set_animation",
                              "delete", "get_scene", "url"))  # fmt: skip

        def make_app(self) -> Any:
            return tornado.web.Application(
                [
                    (r"/static/(.*)", LoopbackStatic,
                     {"path": VIEWER_ROOT, "default_filename": VIEWER_HTML}),
                    (r"/", LoopbackSocket, {"bridge": self}),
                ]
            )  # fmt: skip

        def handle_zmq(self, frames: list[bytes]) -> None:
            """Meshcat's handler, refusing what it cannot answer.

            A malformed or unknown message gets an error reply and is dropped: it never
            leaves the REP socket waiting (a wedged server).
            """
            try:
                cmd = frames[0].decode("utf-8") if frames else ""
                if (
                    cmd not in self.COMMANDS
                    or (cmd.startswith("set_") or cmd == "delete")
                    and (len(frames) != 3)
                ):
                    raise ValueError(f"unknown or malformed command {cmd[:40]!r}")
                if len(frames) == 3:
                    frames[1].decode("utf-8")
                super().handle_zmq(frames)
            except Exception as exc:  # noqa: BLE001 - any bad message: reply, drop, go on
                with contextlib.suppress(zmq.ZMQError):
                    self.zmq_socket.send(f"error: {type(exc).__name__}".encode())

        def __init__(self) -> None:  # noqa: D401 - not super().__init__: it binds 0.0.0.0
            self.host = LOOPBACK
            self.websocket_pool: set[Any] = set()
            self.app = self.make_app()
            self.ioloop = tornado.ioloop.IOLoop.current()
            self.zmq_socket, self.zmq_stream, _ = self.setup_zmq(f"tcp://{LOOPBACK}:*")
            self.zmq_url = self.zmq_socket.getsockopt_string(zmq.LAST_ENDPOINT)
            socks = tornado.netutil.bind_sockets(0, address=LOOPBACK, family=socket.AF_INET)
            self.http_server = tornado.httpserver.HTTPServer(self.app)
            self.http_server.add_sockets(socks)
            self.fileserver_port = socks[0].getsockname()[1]
            allowed_hosts.update(f"{host}:{self.fileserver_port}" for host in HOSTS)
            self.web_url = f"http://{LOOPBACK}:{self.fileserver_port}/static/"
            self.tree = SceneTree()

    bridge = LoopbackBridge()
    loop = bridge.ioloop

    def stop(*_: Any) -> None:
        loop.add_callback_from_signal(loop.stop)

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)

    def watch_parent() -> None:
        with contextlib.suppress(OSError, ValueError):
            while sys.stdin.buffer.read(4096):
                pass
        loop.add_callback(loop.stop)

    threading.Thread(target=watch_parent, daemon=True).start()
    print(
        json.dumps({"zmq_url": bridge.zmq_url, "web_url": bridge.web_url, "pid": os.getpid()}),
        flush=True,
    )
    loop.start()
    os._exit(0)


if __name__ == "__main__":  # pragma: no cover
    if sys.argv[1:] == ["--serve"]:
        serve()
    else:
        sys.exit("usage: python -m hexapod_kin.viewer.bridge --serve  (internal)")
