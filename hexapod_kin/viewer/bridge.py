"""The child process of :class:`~hexapod_kin.viewer.server.MeshcatServer` (internal).

``python -m hexapod_kin.viewer.bridge --serve`` runs meshcat's websocket bridge with its web
server and ZeroMQ socket bound to 127.0.0.1 only (meshcat 0.3.2's own server binds the web
server to all interfaces). A module of its own so that running it never re-imports the
module that starts it.
"""

from __future__ import annotations

import json
import os
import signal
import sys
from typing import Any

from .server import LOOPBACK


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
    import zmq
    from meshcat.servers.tree import SceneTree
    from meshcat.servers.zmqserver import ZMQWebSocketBridge

    class LoopbackBridge(ZMQWebSocketBridge):
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
            self.web_url = f"http://{LOOPBACK}:{self.fileserver_port}/static/"
            self.tree = SceneTree()

    bridge = LoopbackBridge()
    loop = bridge.ioloop

    def stop(*_: Any) -> None:
        loop.add_callback_from_signal(loop.stop)

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)

    def watch_parent() -> None:
        try:
            while sys.stdin.buffer.read(4096):
                pass
        except (OSError, ValueError):
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
