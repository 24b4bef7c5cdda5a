"""Viewer: the exported HTML and the live meshcat server, checked in a real headless Chromium.

Independent references: foot positions from the numpy table (``table_fk``), geometry counts
from Pinocchio's parser, socket states from the kernel (/proc/net/tcp), pixels from the
browser.
"""

from __future__ import annotations

import base64
import gzip
import http.client
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from hexapod_kin import gait, load, robots, table_fk, viewer
from hexapod_kin.exceptions import (
    ConfigurationError,
    FrameNotFoundError,
    ParameterError,
    ViewerError,
)
from hexapod_kin.viewer.scene import Scene

umsgpack = pytest.importorskip("umsgpack")


# ====================================================================== helpers

#: Two animation frames of the page: what it drew before this call is on the canvas (a wait
#: counted in frames, never in milliseconds: a busy machine only makes it longer).
FRAMES = "() => new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))"


def _alive(pid: int) -> bool:
    """True if ``pid`` exists and is not a zombie (a zombie has exited)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except (FileNotFoundError, ProcessLookupError):
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


def _wait_gone(pid: int, timeout: float = 120.0) -> bool:
    """True once ``pid`` has ended. ``timeout`` [s] only guards a hang (an orphan that never
    ends): generous, so that a busy machine cannot fail the test."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if not _alive(pid):
            return True
        time.sleep(0.05)
    return not _alive(pid)


def _html_data(path: Path) -> dict:
    """The page's DATA, its gzipped scene unpacked: ``commands`` and ``animation`` (bytes)."""
    text = path.read_text(encoding="utf-8")
    m = re.search(r"var DATA = (\{.*?\});\n", text)
    assert m, "no DATA block in the page"
    data = json.loads(m.group(1))
    blob = gzip.decompress(base64.b64decode(data["scene"]))
    cmds, at = [], 0
    while at < len(blob):
        n = int.from_bytes(blob[at : at + 4], "little")
        cmds.append(blob[at + 4 : at + 4 + n])
        at += 4 + n
    data["animation"] = cmds.pop() if data["animation"] else None
    data["commands"] = cmds
    return data


def _decode(packed: bytes) -> dict:
    return umsgpack.unpackb(packed)


def _f32(ext) -> np.ndarray:
    assert ext.type == 0x17
    return np.frombuffer(ext.data, dtype=np.float32)


def _resolved_rate_step(model):
    """The seeds' step: foot velocity [A sin(2πt/T), 0, 0] by resolved rate (hexapod_kin.motion)."""
    try:
        from hexapod_kin import motion
    except ImportError:  # motion not available: a joint path of the same kind
        return _step_trajectory(model)

    def velocity(t):
        t = np.asarray(t, dtype=float)
        return np.stack([0.05 * np.sin(np.pi * t), 0 * t, 0 * t], axis=-1)

    tr = motion.resolved_rate(model, velocity, motion.SEED_Q0, 0.025, 1.5)
    return np.asarray(tr.t), np.asarray(tr.q)


def _step_trajectory(model, n: int = 61):
    """A foot step of a 3-DOF leg as a joint path: hip swings, knee lifts mid-way."""
    s = np.linspace(0.0, 1.0, n)
    q_a = np.array([-0.35, 0.35, 1.2])
    q_b = np.array([0.35, 0.35, 1.2])
    qs = q_a + (q_b - q_a) * s[:, None]
    qs[:, 1] -= 0.5 * np.sin(np.pi * s)
    return s * 1.5, qs


def _local_ipv4() -> list[str]:
    """This machine's non-loopback IPv4 addresses (its own interfaces only)."""
    found: set[str] = set()
    ip = shutil.which("ip")
    if ip:
        out = subprocess.run([ip, "-4", "-o", "addr", "show"], capture_output=True, text=True)
        found.update(re.findall(r"inet (\d+\.\d+\.\d+\.\d+)/", out.stdout))
    try:
        for info in socket.getaddrinfo(socket.gethostname(), None, socket.AF_INET):
            found.add(info[4][0])
    except socket.gaierror:
        pass
    return sorted(a for a in found if not a.startswith("127."))


def _listeners(port: int) -> list[tuple[str, str]]:
    """(file, local address hex) of LISTEN sockets on ``port`` from /proc/net/tcp{,6}."""
    out = []
    for name in ("tcp", "tcp6"):
        path = Path(f"/proc/net/{name}")
        if not path.exists():
            continue
        for line in path.read_text().splitlines()[1:]:
            fields = line.split()
            addr, hexport = fields[1].rsplit(":", 1)
            if fields[3] == "0A" and int(hexport, 16) == port:
                out.append((name, addr))
    return out


def _port(url: str) -> int:
    return int(re.search(r":(\d+)", url.split("//", 1)[1]).group(1))


# ====================================================================== browser fixtures
class _Page:
    """A page whose every request outside ``allow`` is blocked and recorded."""

    def __init__(self, browser, allow: tuple[str, ...]):
        self.page = browser.new_page(viewport={"width": 800, "height": 600})
        self.blocked: list[str] = []
        self.errors: list[str] = []
        self.page.on("pageerror", lambda e: self.errors.append(str(e)))
        self.page.on("console", lambda m: self.errors.append(m.text) if m.type == "error" else None)

        def route(r):
            if r.request.url.startswith(allow):
                r.continue_()
            else:
                self.blocked.append(r.request.url)
                r.abort()

        self.page.route("**/*", route)

    def pixels(self) -> np.ndarray:
        from io import BytesIO

        import matplotlib.image as mpimg

        png = self.page.locator("canvas").first.screenshot()
        return mpimg.imread(BytesIO(png), format="png")[..., :3]

    def close(self):
        self.page.close()


def _changed(a: np.ndarray, b: np.ndarray) -> float:
    """Fraction of pixels whose colour differs by more than 0.1 in some channel."""
    return float(np.mean(np.abs(a - b).max(axis=-1) > 0.1))


# ====================================================================== scene and HTML (no browser)
@pytest.fixture(scope="module")
def leg():
    return load("hexabot_leg")


@pytest.fixture(scope="module")
def step_html(leg, tmp_path_factory):
    times, qs = _resolved_rate_step(leg)
    assert len(times) == 61
    sing = np.zeros(len(times), bool)
    sing[[0, 30]] = True
    path = tmp_path_factory.mktemp("html") / "step.html"
    viewer.export_html(leg, times, qs, path, frame_triads=True, singular_mask=sing, play=False)
    return path, times, qs


def test_export_is_self_contained(step_html):
    path, times, _ = step_html
    text = path.read_text(encoding="utf-8")
    assert "default-src 'none'" in text  # CSP: the page may fetch nothing
    assert "<script src" not in text and "<link" not in text
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//""", text)
    data = _html_data(path)
    assert data["duration"] == pytest.approx(times[-1] - times[0])
    assert data["animation"] is not None


def test_robot_objects_match_pinocchio_geometry(leg, step_html):
    path, _, _ = step_html
    cmds = [_decode(c) for c in _html_data(path)["commands"]]
    robot = [
        c for c in cmds if c["type"] == "set_object" and c["path"].startswith("/meshcat/robot/")
    ]
    expected = leg.geometry_model("visual").ngeoms
    assert len(robot) == expected > 0
    kinds = {c["object"]["geometries"][0]["type"] for c in robot}
    assert kinds <= {"BoxGeometry", "CylinderGeometry", "SphereGeometry"}


def test_keyframes_follow_the_table_fk(leg, step_html):
    """The foot sphere's animated position equals the numpy table FK at every sample."""
    path, times, qs = step_html
    anim = _decode(_html_data(path)["animation"])
    foot = [a for a in anim["animations"] if a["path"].startswith("/meshcat/robot/foot")]
    assert len(foot) == 1
    tracks = {t["name"]: t for t in foot[0]["clip"]["tracks"]}
    key_t = _f32(tracks[".position"]["times"])
    pos = _f32(tracks[".position"]["values"]).reshape(-1, 3)
    np.testing.assert_allclose(key_t, times - times[0], atol=1e-6)
    chain = robots.hexabot_leg()
    ref = np.array([table_fk(chain, q)[:3, 3] for q in qs])
    np.testing.assert_allclose(pos, ref, atol=1e-6)
    quat = _f32(tracks[".quaternion"]["values"]).reshape(-1, 4)
    np.testing.assert_allclose(np.linalg.norm(quat, axis=1), 1.0, atol=1e-6)
    assert np.all(np.einsum("ij,ij->i", quat[1:], quat[:-1]) > 0)  # sign-continuous


def test_trace_tube_and_markers_follow_the_foot(leg, step_html):
    path, times, qs = step_html
    cmds = {c["path"]: c for c in (_decode(x) for x in _html_data(path)["commands"])}
    chain = robots.hexabot_leg()
    ref = np.array([table_fk(chain, q)[:3, 3] for q in qs])
    tube = cmds["/meshcat/trace"]["object"]["geometries"][0]["data"]["attributes"]["position"]
    verts = _f32(tube["array"]).reshape(-1, 3)
    dist = np.min(np.linalg.norm(verts[:, None, :] - ref[None, :, :], axis=2), axis=1)
    radius = dist.max()
    assert 0 < radius < 0.005  # every vertex of the tube sits close to the foot path
    spheres = cmds["/meshcat/singular"]["object"]["object"]["children"]
    centres = np.array([np.array(s["matrix"]).reshape(4, 4).T[:3, 3] for s in spheres])
    np.testing.assert_allclose(centres, ref[[0, 30]], atol=1e-9)


def test_triads_are_the_khalil_frames(leg, step_html):
    assert viewer.khalil_frames(leg) == ("base", "coxa", "femur", "tibia", "foot")
    hexa = load("hexapod")
    assert viewer.khalil_frames(hexa) == tuple(
        f"leg1_{n}" for n in ("base", "coxa", "femur", "tibia", "foot")
    )
    path, _, qs = step_html
    cmds = [_decode(c) for c in _html_data(path)["commands"]]
    triads = [
        c for c in cmds if c["type"] == "set_object" and c["path"].startswith("/meshcat/frames/")
    ]
    assert [c["path"] for c in triads] == [f"/meshcat/frames/{k}" for k in range(5)]
    labels = [[t["text"] for t in c["object"]["textures"] if t["type"] == "_text"] for c in triads]
    assert labels == [["0"], ["1"], ["2"], ["3"], ["4"]]
    moves = [c for c in cmds if c["type"] == "set_transform" and c["path"] == "/meshcat/frames/4"]
    T = np.array(moves[0]["matrix"]).reshape(4, 4).T
    np.testing.assert_allclose(T[:3, 3], table_fk(robots.hexabot_leg(), qs[0])[:3, 3], atol=1e-12)


def test_base_poses_move_the_whole_robot(leg, tmp_path):
    times, qs = _step_trajectory(leg, 5)
    shift = np.eye(4)
    shift[:3, 3] = [0.3, -0.2, 0.1]
    plain = viewer.scene_commands(leg, times, qs, trace_frame=False)
    moved = viewer.scene_commands(leg, times, qs, base_poses=shift, trace_frame=False)
    a = {c["path"]: c for c in plain if c["type"] == "set_transform"}
    b = {c["path"]: c for c in moved if c["type"] == "set_transform"}
    for p in a:
        if p.startswith("/meshcat/robot/"):
            Ta = np.array(a[p]["matrix"]).reshape(4, 4).T
            Tb = np.array(b[p]["matrix"]).reshape(4, 4).T
            np.testing.assert_allclose(Tb, shift @ Ta, atol=1e-12)


def test_resampling_and_long_trajectories(leg):
    times, qs = _step_trajectory(leg, 31)  # 1.5 s
    cmds = viewer.scene_commands(leg, times, qs, fps=10)
    anim = cmds[-1]
    key_t = _f32(anim["animations"][0]["clip"]["tracks"][0]["times"])
    np.testing.assert_allclose(key_t, np.arange(16) / 10, atol=1e-6)


def test_bad_inputs_are_named(leg, tmp_path):
    times, qs = _step_trajectory(leg, 5)
    out = tmp_path / "x.html"
    with pytest.raises(ConfigurationError, match="increase"):
        viewer.export_html(leg, times[::-1], qs, out)
    with pytest.raises(ConfigurationError, match="times has shape"):
        viewer.export_html(leg, times[:3], qs, out)
    with pytest.raises(ConfigurationError, match="qs has shape"):
        viewer.export_html(leg, times, qs[:, :2], out)
    with pytest.raises(ConfigurationError, match="base_poses"):
        viewer.export_html(leg, times, qs, out, base_poses=np.ones((5, 4, 4)))
    with pytest.raises(ConfigurationError, match="singular_mask"):
        viewer.export_html(leg, times, qs, out, singular_mask=[True])
    with pytest.raises(FrameNotFoundError, match="nope"):
        viewer.export_html(leg, times, qs, out, trace_frame="nope")
    with pytest.raises(ParameterError, match="fps"):
        viewer.export_html(leg, times, qs, out, fps=-1)
    with pytest.raises(ParameterError, match="speed"):
        viewer.export_html(leg, times, qs, out, speed=0)
    assert not out.exists()


def test_demo_trajectories_respect_limits_and_keep_hexapod_feet_down():
    for name in ("hexabot_leg", "scara", "pendulum", "coxa_tibia_leg"):
        m = load(name)
        times, qs, base = gait.demo_trajectory(m, 2.0, 21)
        assert base is None and qs.shape == (21, m.nq)
        assert np.all(qs >= m.lower - 1e-12) and np.all(qs <= m.upper + 1e-12)
        assert np.ptp(qs, axis=0).min() > 0  # every joint moves
    hexa = load("hexapod")
    times, qs, base = gait.demo_trajectory(hexa, 2.0, 21)
    assert base.shape == (21, 4, 4) and np.ptp(base[:, 2, 3]) > 0  # the body moves
    feet = gait.frame_poses(hexa, hexa.model.createData(), qs, base, hexa.params.foot_frames)
    feet = feet[:, :, :3, 3]
    np.testing.assert_allclose(feet, np.broadcast_to(feet[0], feet.shape), atol=1e-9)
    assert feet[0, :, 2].min() > -1e-9  # standing on z = 0


def _stl_triangles(path: str) -> np.ndarray:
    """Triangles (T, 3, 3) of a binary STL file, read with numpy alone."""
    raw = Path(path).read_bytes()
    n = int.from_bytes(raw[80:84], "little")
    assert len(raw) == 84 + 50 * n, "not a binary STL"
    rec = np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    return np.frombuffer(raw[84:], dtype=rec)["v"].astype(float)


def _area(tris: np.ndarray) -> float:
    cross = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    return float(np.linalg.norm(cross, axis=1).sum() / 2)


def _mesh_triangles(obj: dict) -> tuple[np.ndarray, np.ndarray | None]:
    """World-free triangles (T, 3, 3) [m] of a drawn mesh object, and its normals if sent."""
    geom = obj["geometries"][0]
    assert geom["type"] == "BufferGeometry"
    attrs = geom["data"]["attributes"]
    assert attrs["position"]["array"].type == 0x13  # int16
    pos = np.frombuffer(attrs["position"]["array"].data, dtype=np.int16).reshape(-1, 3)
    index = geom["data"]["index"]
    dtype = {0x14: np.uint16, 0x16: np.uint32}[index["array"].type]
    idx = np.frombuffer(index["array"].data, dtype=dtype).reshape(-1, 3)
    M = np.array(obj["object"]["matrix"]).reshape(4, 4).T
    verts = pos @ M[:3, :3].T + M[:3, 3]
    normals = None
    if "normal" in attrs:
        normals = np.frombuffer(attrs["normal"]["array"].data, dtype=np.float32).reshape(-1, 3)
    return verts[idx], normals


def test_erd_meshes_are_embedded_compactly():
    """Mesh objects hold the STL's own triangles (int16 positions within one step)."""
    solo = load("erd:solo12", tip="FL_FOOT")
    cmds = viewer.scene_commands(solo, [0.0], solo.neutral()[None, :])
    meshes = [
        c for c in cmds if c["type"] == "set_object" and c["path"].startswith("/meshcat/robot/")
    ]
    gm = solo.geometry_model("visual")
    assert len(meshes) == gm.ngeoms
    for cmd, go in zip(meshes, gm.geometryObjects):
        tris, normals = _mesh_triangles(cmd["object"])
        stl = _stl_triangles(go.meshPath) * np.asarray(go.meshScale)
        step = np.ptp(stl.reshape(-1, 3), axis=0).max() / 65534
        np.testing.assert_allclose(tris.reshape(-1, 3).min(0), stl.reshape(-1, 3).min(0), atol=step)
        np.testing.assert_allclose(tris.reshape(-1, 3).max(0), stl.reshape(-1, 3).max(0), atol=step)
        assert _area(tris) == pytest.approx(_area(stl), rel=1e-3)
        assert normals is not None  # the live viewer gets normals (the page computes them)
        np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-5)


def test_mesh_page_is_much_smaller_than_the_mesh_files(tmp_path):
    """Panda: the page is under 40 % of its bundle plus mesh files (what it embedded before)."""
    from hexapod_kin.viewer.objects import bundle

    panda = load("erd:panda")
    q = panda.neutral()
    path = viewer.export_html(panda, [0.0], q[None, :], tmp_path / "panda.html")
    gm = panda.geometry_model("visual")
    files = sum(Path(go.meshPath).stat().st_size for go in gm.geometryObjects)
    before = len(bundle().encode("utf-8")) + files
    assert files > 5e6  # the bound is about the meshes
    assert path.stat().st_size < 0.4 * before
    data = _html_data(path)
    robot = [
        _decode(c)
        for c in data["commands"]
        if _decode(c)["path"].startswith("/meshcat/robot/") and _decode(c)["type"] == "set_object"
    ]
    assert len(robot) == gm.ngeoms
    for c in robot:  # the page computes the normals itself
        assert "normal" not in c["object"]["geometries"][0]["data"]["attributes"]


def _rod_radii(model) -> list[float]:
    cmds = viewer.scene_commands(model, [0.0], model.neutral()[None, :])
    return [
        g["radiusTop"]
        for c in cmds
        if c["type"] == "set_object" and c["path"].startswith("/meshcat/robot/")
        for g in c["object"]["geometries"]
        if g["type"] == "CylinderGeometry"
    ]


def test_link_radius_scales_with_the_robot():
    """PUMA 560's rods are at least 2.5 % of its reach; a small leg keeps its URDF radius."""
    puma = load(str(Path(__file__).resolve().parent.parent / "examples" / "puma560.toml"))
    q = np.zeros(puma.nq)
    tip = np.asarray(puma.fk(q))[:3, 3]
    reach = float(np.linalg.norm(tip))  # base at the origin: straight-line distance to the flange
    assert reach > 0.5
    radii = _rod_radii(puma)
    assert max(radii) >= 0.025 * reach > puma.params.link_radius  # the URDF's rods: too thin
    leg = load("hexabot_leg")
    geoms = [go.geometry for go in leg.geometry_model("visual").geometryObjects]
    urdf = sorted(g.radius for g in geoms if type(g).__name__ == "Cylinder")
    assert sorted(_rod_radii(leg)) == pytest.approx(urdf)  # already visible: drawn as it is


# ====================================================================== browser: exported HTML
@pytest.mark.slow
def test_exported_step_renders_and_moves_offline(browser, step_html):
    path, times, _ = step_html
    page = _Page(browser, allow=("file://",))
    try:
        page.page.goto(path.as_uri())
        page.page.wait_for_function(
            "() => window.hexapodKin && window.hexapodKin.ready", timeout=60000
        )
        page.page.evaluate(f"hexapodKin.seek({times[0]})")
        page.page.evaluate(FRAMES)
        start = page.pixels()
        page.page.evaluate(f"hexapodKin.seek({times[len(times) // 2]})")
        page.page.evaluate(FRAMES)
        middle = page.pixels()
        for part in ("robot", "trace", "frames", "singular"):
            page.page.evaluate(f"hexapodKin.setVisible('{part}', false)")
        page.page.evaluate(FRAMES)
        empty = page.pixels()
        page.page.evaluate("hexapodKin.setVisible('robot', true)")
        page.page.evaluate(FRAMES)
        robot_only = page.pixels()
    finally:
        page.close()
    assert page.blocked == []  # nothing but the file itself was requested
    assert page.errors == []
    assert _changed(robot_only, empty) > 0.01  # the robot is drawn
    assert _changed(start, middle) > 0.005  # the animation moves


def test_mesh_page_unpacks_and_computes_normals(browser, tmp_path):
    """A mesh robot's page unpacks its gzipped scene offline and shades every mesh."""
    solo = load("erd:solo12", tip="FL_FOOT")
    path = viewer.export_html(solo, [0.0], solo.neutral()[None, :], tmp_path / "solo.html")
    page = _Page(browser, allow=("file://",))
    try:
        page.page.goto(path.as_uri())
        page.page.wait_for_function(
            "() => window.hexapodKin && window.hexapodKin.ready", timeout=60000
        )
        counts = page.page.evaluate(
            """() => { var n = 0, shaded = 0;
              hexapodKin.viewer.scene.traverse(function (o) {
                if (o.isMesh && o.geometry.index && o.geometry.getAttribute("position").array
                    instanceof Int16Array) {
                  n += 1; if (o.geometry.getAttribute("normal")) { shaded += 1; } } });
              return [n, shaded]; }"""
        )
        page.page.evaluate(FRAMES)
        with_robot = page.pixels()
        page.page.evaluate("hexapodKin.setVisible('robot', false)")
        page.page.evaluate(FRAMES)
        without = page.pixels()
    finally:
        page.close()
    assert page.blocked == [] and page.errors == []
    assert counts == [solo.geometry_model("visual").ngeoms] * 2
    assert _changed(with_robot, without) > 0.01


def test_notebook_iframe_renders(browser, step_html, tmp_path):
    """The srcdoc iframe (Jupyter/Colab) runs the page; two on one page do not clash."""
    path, _, _ = step_html
    snippet = viewer.iframe(path, height=300)
    host = tmp_path / "notebook.html"
    host.write_text(f"<!DOCTYPE html><html><body>{snippet}{snippet}</body></html>")
    page = _Page(browser, allow=("file://",))
    try:
        page.page.goto(host.as_uri())
        frames = [f for f in page.page.frames if f != page.page.main_frame]
        assert len(frames) == 2
        for frame in frames:
            frame.wait_for_function(
                "() => window.hexapodKin && window.hexapodKin.ready", timeout=60000
            )
            assert frame.evaluate("hexapodKin.duration") == pytest.approx(1.5)
    finally:
        page.close()
    assert page.blocked == [] and page.errors == []
    with pytest.raises(ParameterError, match="height"):
        viewer.iframe(path, height=5)


# ====================================================================== live server
def test_server_listens_on_loopback_only():
    with viewer.MeshcatServer() as server:
        ports = [_port(server.web_url), _port(server.zmq_url)]
        for port in ports:
            listening = _listeners(port)
            assert listening == [("tcp", "0100007F")], listening  # 127.0.0.1, no IPv6
            with socket.create_connection(("127.0.0.1", port), timeout=5):
                pass
            for addr in _local_ipv4():  # this machine's own other addresses only
                with pytest.raises(ConnectionRefusedError):
                    socket.create_connection((addr, port), timeout=5).close()
        conn = http.client.HTTPConnection("127.0.0.1", ports[0], timeout=10)
        conn.request("GET", "/static/")
        resp = conn.getresponse()
        assert resp.status == 200 and b"MeshCat" in resp.read()
        conn.close()


def test_live_page_shows_the_hexapod(browser):
    hexa = load("hexapod")
    with viewer.Viewer(hexa) as v:
        page = _Page(browser, allow=(v.url.split("/static/")[0],))
        try:
            page.page.goto(v.url)
            n = len(Scene(hexa).visuals)
            page.page.wait_for_function(
                "() => window.viewer && Object.keys(viewer.scene_tree.find(['meshcat','robot'])"
                f".children).length >= {n}",
                timeout=60000,
            )
            page.page.evaluate(FRAMES)
            shown = page.pixels()
            v.set_visible("robot", False)
            page.page.wait_for_function(  # the message arrived (however long that took)
                "() => viewer.scene_tree.find(['meshcat','robot']).object.visible === false",
                timeout=60000,
            )
            page.page.evaluate(FRAMES)
            hidden = page.pixels()
        finally:
            page.close()
    assert page.blocked == []
    assert _changed(shown, hidden) > 0.01


def test_no_orphan_after_exit_and_after_an_error():
    leg = load("hexabot_leg")
    with viewer.Viewer(leg) as v:
        pid = v.pid
        assert _alive(pid)
    assert _wait_gone(pid)
    with pytest.raises(RuntimeError, match="boom"):
        with viewer.Viewer(leg) as v:
            pid = v.pid
            raise RuntimeError("boom")
    assert _wait_gone(pid)


def test_no_orphan_when_the_parent_dies():
    code = (
        "import os, sys; from hexapod_kin.viewer import MeshcatServer; "
        "s = MeshcatServer(); print(s.pid, flush=True); os._exit(3)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert out.returncode == 3
    pid = int(out.stdout.split()[0])
    assert _wait_gone(pid), f"server {pid} survived its parent"


def _call_in_thread(fn, limit: float = 60.0):
    box: dict = {}

    def run():
        try:
            fn()
        except BaseException as exc:  # noqa: BLE001
            box["exc"] = exc

    t = threading.Thread(target=run, daemon=True)
    t.start()
    t.join(limit)
    assert not t.is_alive(), "the call hung"
    return box.get("exc")


def test_no_hang_when_the_server_stops_answering():
    leg = load("hexabot_leg")
    q = np.zeros(3)
    with viewer.Viewer(leg, timeout=1.0) as v:
        pid = v.pid
        os.kill(pid, signal.SIGSTOP)  # alive but silent: the zmq timeout must fire
        exc = _call_in_thread(lambda: v.display(q))
        assert isinstance(exc, ViewerError) and "did not answer" in str(exc)
    assert _wait_gone(pid)  # close() also ends a stopped server


def test_no_hang_when_the_server_is_killed():
    leg = load("hexabot_leg")
    with viewer.Viewer(leg, timeout=1.0) as v:
        os.kill(v.pid, signal.SIGKILL)
        assert _wait_gone(v.pid)
        exc = _call_in_thread(lambda: v.display(np.zeros(3)))
        assert isinstance(exc, ViewerError)
        exc = _call_in_thread(lambda: v.set_visible("robot", True))
        assert isinstance(exc, ViewerError)


def test_viewer_rejects_bad_arguments():
    leg = load("hexabot_leg")
    with pytest.raises(ParameterError, match="timeout"):
        viewer.Viewer(leg, timeout=0)
    with viewer.Viewer(leg) as v:
        with pytest.raises(ParameterError, match="part"):
            v.set_visible("wheels", False)
        with pytest.raises(ConfigurationError):
            v.display([0.0, 0.0])
        v.animate(*_step_trajectory(leg, 11), frame_triads=True)  # accepted by the server
        with pytest.raises(ConfigurationError, match="increase"):
            v.animate([1.0, 0.0], np.zeros((2, 3)))


def test_live_display_reaches_the_server_tree():
    """The server's scene tree (meshcat's get_scene) holds the pose of the table FK."""
    leg = load("hexabot_leg")
    q = np.array([0.4, 0.2, 1.1])
    with viewer.Viewer(leg) as v:
        v.animate(*_step_trajectory(leg, 11), frame_triads=True)
        v.display(q)
        page = v._client.request([b"get_scene"]).decode("utf-8")
    blobs = re.findall(r"octet-binary;base64,([A-Za-z0-9+/=]+)", page)
    cmds = [umsgpack.unpackb(base64.b64decode(b)) for b in blobs]
    last = {}
    for c in cmds:
        if c["type"] in ("set_transform", "set_animation"):
            last[(c["type"], c["path"])] = c
    ref = table_fk(robots.hexabot_leg(), q)
    foot = [k for k in last if k[0] == "set_transform" and k[1].startswith("/meshcat/robot/foot")]
    assert len(foot) == 1
    T = np.array(last[foot[0]]["matrix"]).reshape(4, 4).T
    np.testing.assert_allclose(T[:3, 3], ref[:3, 3], atol=1e-12)
    T4 = np.array(last[("set_transform", "/meshcat/frames/4")]["matrix"]).reshape(4, 4).T
    np.testing.assert_allclose(T4, ref, atol=1e-12)  # the foot triad follows display()
    assert last[("set_animation", "")]["animations"] == []  # display() stopped the animation


# ====================================================================== command line
def test_cli_view_prints_a_loopback_url_and_stops(capsys):
    from hexapod_kin.cli import main

    assert main(["view", "hexabot_leg", "--no-wait"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"http://127\.0\.0\.1:\d+/static/", out)
    port = _port(re.search(r"http://\S+", out).group(0))
    with pytest.raises(OSError):
        socket.create_connection(("127.0.0.1", port), timeout=2).close()  # stopped


def test_cli_animate_writes_html(tmp_path, capsys):
    from hexapod_kin.cli import main

    out = tmp_path / "anim.html"
    rc = main(
        [
            "animate",
            "hexabot_leg",
            "--html",
            str(out),
            "--samples",
            "11",
            "--triads",
            "--sigma-min",
            "10",
            "--json",
        ]
    )
    assert rc == 0
    info = json.loads(capsys.readouterr().out)
    assert info["samples"] == 11 and info["singular_samples"] == 11
    data = _html_data(out)
    assert data["animation"] and data["duration"] == pytest.approx(4.0)


@pytest.mark.slow
def test_screenshot_tool_runs(browser, tmp_path):
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tools"))
    try:
        import screenshots
    finally:
        sys.path.pop(0)
    assert screenshots.main(["--out", str(tmp_path)], browser=browser) == 0
    import matplotlib.image as mpimg

    for name in ("hexapod.png", "leg_step.png"):
        img = mpimg.imread(tmp_path / name)[..., :3]
        assert img.shape[:2] == (700, 1000)
        # robot colours present: orange links and red feet, absent from the grey background
        r, g, b = img[..., 0], img[..., 1], img[..., 2]
        orange = (r > 0.75) & (g > 0.4) & (g < 0.7) & (b < 0.35)
        assert orange.mean() > 0.005, name


# ====================================================================== meshes of a real workspace
def _box_stl(path: Path, size: tuple[float, float, float]) -> None:
    """A binary STL of the box [0, size] (12 triangles)."""
    import struct

    xs, ys, zs = zip((0.0, 0.0, 0.0), size, strict=True)
    c = [(x, y, z) for x in xs for y in ys for z in zs]
    faces = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
             (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]  # fmt: skip
    out = bytearray(b"\0" * 80 + struct.pack("<I", len(faces)))
    for f in faces:
        out += (
            struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *c[i]) for i in f) + b"\0\0"
        )
    path.write_bytes(bytes(out))


def _mesh_workspace(tmp_path: Path) -> tuple[Path, dict[str, tuple[float, float, float]]]:
    """ws/src/mypkg (package meshes: good, empty, garbage) + a file:// mesh elsewhere."""
    pkg = tmp_path / "ws" / "src" / "mypkg"
    (pkg / "urdf").mkdir(parents=True)
    (pkg / "meshes").mkdir()
    (pkg / "package.xml").write_text("<package><name>mypkg</name></package>")
    other = tmp_path / "elsewhere"  # outside every package: what xacro's $(find pkg) gives
    other.mkdir()
    sizes = {"good": (0.04, 0.02, 0.1), "abs": (0.03, 0.03, 0.08)}
    _box_stl(pkg / "meshes" / "good.stl", sizes["good"])
    _box_stl(other / "abs.stl", sizes["abs"])
    (pkg / "meshes" / "empty.stl").write_bytes(b"")
    (pkg / "meshes" / "garbage.stl").write_bytes(b"\x00not a mesh\xff" * 3)
    uris = {
        "good": "package://mypkg/meshes/good.stl",
        "empty": "package://mypkg/meshes/empty.stl",
        "garbage": "package://mypkg/meshes/garbage.stl",
        "abs": (other / "abs.stl").as_uri(),
        "missing": "package://mypkg/meshes/missing.stl",
    }
    parts = ['<robot name="ws"><link name="base"/>']
    for k, (name, uri) in enumerate(uris.items()):
        parts.append(
            f'<link name="{name}"><inertial><mass value="0.1"/><inertia ixx="1e-4" iyy="1e-4" '
            f'izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial><visual><geometry>'
            f'<mesh filename="{uri}"/></geometry></visual></link>'
            f'<joint name="j{k}" type="revolute"><parent link="base"/><child link="{name}"/>'
            f'<origin xyz="{0.1 * k} 0 0"/><axis xyz="0 0 1"/>'
            '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
        )
    path = pkg / "urdf" / "ws.urdf"
    path.write_text("".join(parts) + "</robot>")
    return path, sizes


def test_package_empty_garbage_and_file_uri_meshes(browser, tmp_path):
    """The good meshes are drawn; an empty, an unreadable and a missing one cost only themselves."""
    import warnings

    path, sizes = _mesh_workspace(tmp_path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = load(path)
        html = viewer.export_html(model, [0.0], model.neutral()[None, :], tmp_path / "ws.html")
    said = [str(w.message) for w in caught]
    assert any("1 file(s) empty" in s and "empty.stl" in s for s in said), said
    assert any("1 file(s) not found" in s and "missing.stl" in s for s in said), said
    assert any("1 file(s) unreadable" in s and "garbage.stl" in s for s in said), said
    assert all("\n" not in s for s in said if "meshes:" in s and "not found" not in s)
    cmds = [_decode(c) for c in _html_data(html)["commands"]]
    robot = [
        c for c in cmds if c["type"] == "set_object" and c["path"].startswith("/meshcat/robot/")
    ]
    sticks = [c for c in robot if c["path"].startswith("/meshcat/robot/stick_")]
    assert len(sticks) == 4  # meshes are missing: the base's joints as a stick figure
    robot = [c for c in robot if c not in sticks]
    assert len(robot) == 2
    extents = sorted(
        tuple(np.ptp(_mesh_triangles(c["object"])[0].reshape(-1, 3), axis=0)) for c in robot
    )  # the boxes' own sizes, within one int16 quantisation step (0.1 m / 65534)
    np.testing.assert_allclose(extents, sorted(sizes.values()), atol=2e-6)
    page = _Page(browser, allow=("file://",))
    try:
        page.page.goto(html.as_uri())
        page.page.wait_for_function(
            "() => window.hexapodKin && window.hexapodKin.ready", timeout=60000
        )
        n = page.page.evaluate(
            """() => { var n = 0; hexapodKin.viewer.scene.traverse(function (o) {
                 if (o.isMesh && o.geometry.index) { n += 1; } }); return n; }"""
        )
        page.page.evaluate(FRAMES)
        with_robot = page.pixels()
        page.page.evaluate("hexapodKin.setVisible('robot', false)")
        page.page.evaluate(FRAMES)
        without = page.pixels()
    finally:
        page.close()
    assert page.blocked == [] and page.errors == []
    assert n >= 2
    assert _changed(with_robot, without) > 0.002
