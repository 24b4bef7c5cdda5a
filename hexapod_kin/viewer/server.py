"""The live meshcat server of the viewer: a loopback-only subprocess and its client.

:class:`MeshcatServer` runs :mod:`.bridge` (web server and ZeroMQ socket on 127.0.0.1 only,
free ports, stopped with its process group); :class:`Client` is a ZeroMQ client with
timeouts (:class:`~hexapod_kin.exceptions.ViewerError`).
"""

from __future__ import annotations

import atexit
import contextlib
import importlib.util
import json
import os
import selectors
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from ..exceptions import OptionalDependencyError, ViewerError
from .objects import INSTALL_HINT, meshcat_dir, pack

__all__ = ["LOOPBACK", "MeshcatServer"]

#: The only address the live server listens on.
LOOPBACK = "127.0.0.1"


class MeshcatServer:
    """A meshcat server subprocess listening on 127.0.0.1 only, with free ports.

    A context manager; :meth:`close` (also at interpreter exit) terminates the child's process
    group and reaps it; the child exits by itself when its parent dies (its stdin closes).

    Attributes:
        web_url: ``http://127.0.0.1:PORT/static/`` (the page to open).
        zmq_url: ``tcp://127.0.0.1:PORT`` (the command socket).
        pid: Process id of the server.

    Raises:
        ViewerError: The server did not start within ``start_timeout`` seconds.
        OptionalDependencyError: meshcat (or pyzmq, tornado) is not installed.

    """

    def __init__(self, start_timeout: float = 30.0) -> None:
        for mod in ("zmq", "tornado"):
            if importlib.util.find_spec(mod) is None:
                raise OptionalDependencyError(f"the live viewer needs {mod}; {INSTALL_HINT}")
        meshcat_dir()
        self._stderr = tempfile.TemporaryFile()
        env = dict(os.environ)
        pkg_root = str(Path(__file__).resolve().parents[2])
        env["PYTHONPATH"] = os.pathsep.join(p for p in (pkg_root, env.get("PYTHONPATH", "")) if p)
        self._proc: subprocess.Popen[bytes] | None = subprocess.Popen(
            [sys.executable, "-u", "-m", "hexapod_kin.viewer.bridge", "--serve"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self._stderr,
            env=env,
            start_new_session=True,
        )
        self.pid: int = self._proc.pid
        atexit.register(self.close)
        try:
            info = self._handshake(start_timeout)
        except BaseException:
            self.close()
            raise
        self.web_url: str = info["web_url"]
        self.zmq_url: str = info["zmq_url"]
        if not (
            self.web_url.startswith(f"http://{LOOPBACK}:")
            and self.zmq_url.startswith(f"tcp://{LOOPBACK}:")
        ):
            self.close()
            raise ViewerError(f"meshcat server reported non-loopback URLs {info}")

    def _handshake(self, timeout: float) -> dict[str, Any]:
        assert self._proc is not None and self._proc.stdout is not None
        deadline = time.monotonic() + timeout
        buf = b""
        with selectors.DefaultSelector() as sel:
            sel.register(self._proc.stdout, selectors.EVENT_READ)
            while b"\n" not in buf:
                left = deadline - time.monotonic()
                if left <= 0:
                    msg = f"the meshcat server did not start within start_timeout={timeout} s"
                    raise ViewerError(f"{msg}; its stderr: {self.stderr_tail()!r}")
                if sel.select(min(left, 0.2)):
                    chunk = os.read(self._proc.stdout.fileno(), 4096)
                    if not chunk:
                        msg = f"the meshcat server exited with status {self._proc.wait(5)} before"
                        raise ViewerError(f"{msg} starting; its stderr: {self.stderr_tail()!r}")
                    buf += chunk
        try:
            info = json.loads(buf.split(b"\n", 1)[0])
        except json.JSONDecodeError:
            raise ViewerError(f"unexpected meshcat server greeting {buf[:200]!r}") from None
        return dict(info)

    @property
    def running(self) -> bool:
        """Whether the server process is alive."""
        return self._proc is not None and self._proc.poll() is None

    def stderr_tail(self, size: int = 2000) -> str:
        """Last ``size`` bytes of the server's stderr (for error messages)."""
        try:
            self._stderr.seek(0, os.SEEK_END)
            end = self._stderr.tell()
            self._stderr.seek(max(0, end - size))
            return self._stderr.read().decode("utf-8", "replace")
        except (OSError, ValueError):
            return ""

    def close(self) -> None:
        """Stop the server and its process group; idempotent, never raises."""
        proc, self._proc = self._proc, None
        with contextlib.suppress(Exception):
            atexit.unregister(self.close)
        if proc is None:
            return
        if proc.poll() is None:
            for sig in (signal.SIGTERM, signal.SIGCONT):
                with contextlib.suppress(ProcessLookupError, PermissionError):
                    os.killpg(proc.pid, sig)
            try:
                proc.wait(timeout=3.0)
            except subprocess.TimeoutExpired:
                with contextlib.suppress(ProcessLookupError, PermissionError):
                    os.killpg(proc.pid, signal.SIGKILL)
                with contextlib.suppress(subprocess.TimeoutExpired):
                    proc.wait(timeout=5.0)
        else:  # the leader is gone; make sure nothing of its group is left
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(proc.pid, signal.SIGKILL)
        for stream in (proc.stdin, proc.stdout, self._stderr):
            with contextlib.suppress(OSError):
                if stream is not None:
                    stream.close()

    def __enter__(self) -> MeshcatServer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __del__(self) -> None:  # pragma: no cover - best effort
        with contextlib.suppress(Exception):
            self.close()


class Client:
    """A ZeroMQ REQ client of the meshcat server whose calls time out (never hang)."""

    def __init__(self, server: MeshcatServer, timeout: float) -> None:
        import zmq

        self._zmq = zmq
        self.server = server
        self.timeout = float(timeout)
        self._ctx = zmq.Context()
        self._sock: Any = None
        self._connect()

    def _connect(self) -> None:
        zmq = self._zmq
        sock = self._ctx.socket(zmq.REQ)
        ms = max(1, int(self.timeout * 1000))
        for option, value in ((zmq.LINGER, 0), (zmq.RCVTIMEO, ms), (zmq.SNDTIMEO, ms)):
            sock.setsockopt(option, value)
        sock.connect(self.server.zmq_url)
        self._sock = sock

    def request(self, frames: list[bytes]) -> bytes:
        if self._sock is None:
            raise ViewerError("the viewer is closed; open a new Viewer")
        if not self.server.running:
            msg = f"the meshcat server (pid {self.server.pid}) is not running; stderr: "
            raise ViewerError(msg + repr(self.server.stderr_tail(500)))
        try:
            self._sock.send_multipart(frames)
            return bytes(self._sock.recv())
        except self._zmq.ZMQError as exc:
            self._sock.close(0)  # a REQ socket that missed its reply cannot be reused
            self._connect()
            raise ViewerError(
                f"the meshcat server at {self.server.zmq_url} (pid {self.server.pid}) did not "
                f"answer within timeout={self.timeout} s ({exc}); is it still running?"
            ) from None

    def send(self, cmd: dict[str, Any]) -> None:
        reply = self.request(
            [cmd["type"].encode("utf-8"), cmd.get("path", "").encode("utf-8"), pack(cmd)]
        )
        if reply != b"ok":
            raise ViewerError(f"the meshcat server refused {cmd['type']!r}: {reply[:200]!r}")

    def close(self) -> None:
        if self._sock is not None:
            self._sock.close(0)
            self._sock = None
        self._ctx.term()
