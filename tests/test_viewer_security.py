"""The viewer's server: loopback Host/Origin only, and malformed messages never wedge it.

* A DNS-rebinding page reaches the server with Host and Origin both ``evil.example:PORT``:
  the page and the websocket are refused (403), while ``127.0.0.1:PORT``, ``localhost:PORT``
  and ``[::1]:PORT`` are served; another port or any other name is refused.
* 1,000 random ZeroMQ messages (random frame counts, bytes, commands, bad UTF-8) each get a
  reply, and a normal scene command still works afterwards.
"""

from __future__ import annotations

import asyncio
import random
import urllib.error
import urllib.request

import pytest

pytest.importorskip("meshcat")
zmq = pytest.importorskip("zmq")
tornado_ws = pytest.importorskip("tornado.websocket")
from tornado.httpclient import HTTPRequest  # noqa: E402

from hexapod_kin.viewer.server import Client, MeshcatServer  # noqa: E402


@pytest.fixture(scope="module")
def server():
    with MeshcatServer() as srv:
        yield srv


def _port(srv: MeshcatServer) -> int:
    return int(srv.web_url.split(":")[2].split("/")[0])


def _get(url: str, host: str) -> int:
    req = urllib.request.Request(url, headers={"Host": host})
    try:
        with urllib.request.urlopen(req, timeout=10) as res:
            return int(res.status)
    except urllib.error.HTTPError as exc:
        return int(exc.code)


def _ws(port: int, host: str, origin: str) -> str:
    async def go() -> str:
        req = HTTPRequest(
            f"ws://127.0.0.1:{port}/", headers={"Host": host, "Origin": origin}, request_timeout=10
        )
        try:
            conn = await tornado_ws.websocket_connect(req)
        except Exception as exc:  # noqa: BLE001 - the refusal (an HTTP 403 on the handshake)
            return f"refused: {exc}"
        conn.close()
        return "open"

    return asyncio.run(go())


def test_dns_rebinding_request_refused(server: MeshcatServer) -> None:
    port = _port(server)
    own, evil = f"127.0.0.1:{port}", f"evil.example:{port}"
    assert _get(server.web_url, own) == 200
    assert _get(server.web_url, evil) == 403
    assert _ws(port, own, f"http://{own}") == "open"
    assert _ws(port, evil, f"http://{evil}").startswith("refused")
    assert _ws(port, own, f"http://{evil}").startswith("refused")  # a foreign page
    assert _ws(port, evil, f"http://{own}").startswith("refused")


@pytest.mark.parametrize("name", ["localhost", "LOCALHOST", "[::1]"])
def test_loopback_names_of_its_own_port_are_served(server: MeshcatServer, name: str) -> None:
    port = _port(server)
    own = f"{name}:{port}"
    assert _get(server.web_url, own) == 200
    assert _ws(port, own, f"http://{own}") == "open"
    assert _ws(port, own, f"http://127.0.0.1:{port}") == "open"  # either loopback name


@pytest.mark.parametrize(
    "host",
    [
        "localhost",  # no port: not this server's own address
        "localhost:{other}",
        "127.0.0.1:{other}",
        "[::1]:{other}",
        "localhost.evil.example:{port}",
        "127.0.0.2:{port}",
        "0.0.0.0:{port}",
        "[::ffff:127.0.0.1]:{port}",
        "localhost:{port}.evil.example",
    ],
)
def test_other_hosts_and_ports_refused(server: MeshcatServer, host: str) -> None:
    port = _port(server)
    name = host.format(port=port, other=port + 1 if port < 65535 else port - 1)
    assert _get(server.web_url, name) == 403
    assert _ws(port, name, f"http://{name}").startswith("refused")
    assert _ws(port, f"localhost:{port}", f"http://{name}").startswith("refused")


def test_random_frames_never_wedge_the_server(server: MeshcatServer) -> None:
    rng = random.Random(25)
    ctx = zmq.Context()
    sock = ctx.socket(zmq.REQ)
    sock.setsockopt(zmq.LINGER, 0)
    sock.setsockopt(zmq.RCVTIMEO, 5000)
    sock.connect(server.zmq_url)
    words = [b"set_object", b"set_transform", b"delete", b"capture_image", b"wait", b"url", b""]
    try:
        for _ in range(1000):
            n = rng.randint(1, 4)
            frames = [
                rng.choice(words) if rng.random() < 0.4 else rng.randbytes(rng.randint(0, 40))
                for _ in range(n)
            ]
            sock.send_multipart(frames)
            sock.recv()  # every message gets an answer (a timeout here is a wedged server)
    finally:
        sock.close()
        ctx.term()
    client = Client(server, timeout=10.0)
    try:  # a normal command afterwards
        client.send({"type": "delete", "path": "/meshcat/robot"})
    finally:
        client.close()
