"""The cockpit without a browser: its laws, its server's hygiene, the command's lifetime.

Numbers are held to independent references: ``model.fk`` / the legged robot's vectorised FK,
the body pose's own rotation, the planner's commanded twist; the resolved-rate follow's error
must shrink step by step.
"""

from __future__ import annotations

import asyncio
import json
import math
import os
import re
import signal
import socket
import subprocess
import sys
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest

import hexapod_kin as hk
from hexapod_kin.drive import Cockpit, drive
from hexapod_kin.drive.reach import TOLERANCE
from hexapod_kin.drive.server import handle
from hexapod_kin.exceptions import FrameNotFoundError, ParameterError

ROBOTS = ("hexabot_leg", "hexapod", "erd:solo12")
ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module", params=ROBOTS)
def model(request):
    return hk.load(request.param)


def _reachable(c: Cockpit) -> np.ndarray:
    """A target the selected limb reaches: FK of its joints moved by 0.15 rad (in limits)."""
    limb = c.limbs[c.limb]
    q = c._limb_q().copy()
    q[limb.columns] = np.clip(
        q[limb.columns] + 0.15, limb.lower[limb.columns], limb.upper[limb.columns]
    )
    return limb.point(q, c.base)


def test_joint_sets_fk_exactly(model):
    c = Cockpit(model)
    j = model.nq - 1
    v = float(np.clip(0.37, model.lower[j], model.upper[j]))
    q0 = c.q.copy()
    c.set_joint(model.joint_names[j], v)
    np.testing.assert_array_equal(np.delete(c.q, j), np.delete(q0, j))  # only joint j moved
    np.testing.assert_allclose(c.readout()["fk"], model.fk(c.q), atol=1e-12, rtol=0)
    assert c.q[j] == v
    with pytest.raises(ParameterError, match="limits"):
        c.set_joint(model.joint_names[j], float(model.upper[j]) + 0.5)
    with pytest.raises(FrameNotFoundError, match="use one of"):
        c.set_joint("no_such_joint", 0.0)


def test_target_converges_step_by_step(model):
    c = Cockpit(model)
    target = _reachable(c)
    c.set_target(target)
    limb = c.limbs[c.limb]
    errors = [float(np.linalg.norm(limb.point(c._limb_q(), c.base) - target))]
    for _ in range(400):
        if c.status != "moving":
            break
        c.advance(0.02)
        errors.append(float(np.linalg.norm(limb.point(c._limb_q(), c.base) - target)))
    assert c.status == "reached", c.message
    assert errors[-1] < 1e-3 and errors[-1] <= TOLERANCE
    assert all(b <= a + 1e-12 for a, b in zip(errors, errors[1:]))  # never moves away
    # the foot point is the independent FK's: model.fk for a chain, the feet's tree FK else
    if not c.legged:
        np.testing.assert_allclose(model.fk(c.q)[:3, 3], limb.point(c.q, c.base), atol=1e-12)


def test_unreachable_target_stops_with_reason(model):
    c = Cockpit(model)
    limb = c.limbs[c.limb]
    far = limb.hip(c._limb_q(), c.base) + np.array([0.0, 0.0, 2.0 * limb.max_reach])
    q0 = c.q.copy()
    c.set_target(far)
    c.advance(0.02)
    assert c.status == "out of reach"
    assert "out of reach" in c.message and "too far" in c.message
    np.testing.assert_array_equal(c.q, q0)  # refused before any step


def test_limit_or_singularity_reason():
    """A target straight above the hip at 0.9 reach: the leg stops and says why."""
    c = Cockpit(hk.load("hexabot_leg"))
    limb = c.limbs[0]
    c.set_target(limb.hip(c.q, c.base) + np.array([0.0, 0.0, 0.9 * limb.max_reach]))
    for _ in range(400):
        if c.status != "moving":
            break
        c.advance(0.02)
    assert c.status in ("joint limit", "singularity"), (c.status, c.message)
    assert c.message.startswith(c.status)
    assert np.all(c.q >= c.model.lower - 1e-12) and np.all(c.q <= c.model.upper + 1e-12)


@pytest.mark.parametrize("src", ROBOTS[1:])
def test_body_pitch_holds_every_foot(src):
    c = Cockpit(hk.load(src))
    feet0 = c.body.feet(c.qb[None], c.base[None])[0]
    c.set_body((0.0, 0.0, 0.0), (0.0, 0.1, 0.0))
    assert c.status == "held", c.message
    R = c.base[:3, :3]
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    assert abs(pitch - 0.1) < 1e-6
    feet = c.body.feet(c.qb[None], c.base[None])[0]  # FK of the IK's joints
    np.testing.assert_allclose(feet, feet0, atol=1e-6)
    # an impossible pose is refused with its reason; the body stays
    base = c.base.copy()
    c.set_body((0.0, 0.0, 1.0), (0.0, 0.0, 0.0))
    assert c.status == "refused" and "out of reach" in c.message
    np.testing.assert_array_equal(c.base, base)


@pytest.mark.parametrize("src", ROBOTS[1:])
def test_walk_forward_and_switch_pattern(src):
    c = Cockpit(hk.load(src))
    x0 = c.base[:3, 3].copy()
    c.set_drive((1.0, 0.0, 0.0))
    dt, hold = 0.02, 2.0
    for _ in range(int(hold / dt)):
        c.advance(dt)
    walked = float(c.base[0, 3] - x0[0])
    assert walked >= 0.8 * c.speed[0] * hold
    stable = [p for p in c.patterns if c.walker.plan(p, c.drive).table.statically_stable]
    assert stable == list(c.patterns)  # kinematic mode offers the open-loop planner's patterns
    others = [p for p in stable if p != c.pattern]
    if not others:  # a quadruped: crawl only; trot is refused with the allowed ones named
        with pytest.raises(hk.ParameterError, match="crawl"):
            c.set_pattern("trot")
    other = others[0] if others else c.pattern
    c.set_pattern(other)
    for _ in range(int(2.5 / dt)):
        c.advance(dt)
    assert c.walker.cycle is not None and c.walker.cycle.pattern == other
    c.set_drive((0.0, 0.0, 0.0))
    for _ in range(int(1.5 / dt)):
        c.advance(dt)
    assert c.status == "standing" and c.walker.cycle is None
    assert c.min_margin > 0 and min(c.margins) > 0
    ro = c.readout()
    assert ro["command"] == [0.0, 0.0, 0.0] and ro["pattern"] == other


#: PWM servos for the timelines: 1500 µs at the centre, 450 µs/rad, 500..2500 µs (±2.22 rad).
SERVOS = {"defaults": {"units": "us", "centre": 1500, "us_per_rad": 450.0, "limits": [500, 2500]}}


def test_session_downloads_a_calibrated_servo_timeline(tmp_path):
    """The download is `timeline`'s: read back by its reader, every command in the servo range."""
    from hexapod_kin.drive.server import session_reply
    from hexapod_kin.export.servos import Calibration
    from hexapod_kin.export.timeline import read_timeline

    c = Cockpit(hk.load("hexapod"), calibration=Calibration.from_dict(SERVOS))
    c.set_drive((1.0, 0.0, 0.0))  # from standing: the joints blend into the walk
    for i in range(150):
        if i == 30:
            c.set_pattern(next(p for p in c.patterns if p != c.pattern))  # blended at 1 s
        c.advance(0.02)
    s = c.session()
    assert len(s["t"]) == len(s["q"]) == len(s["base_poses"]) == 151
    step = np.abs(np.diff(np.asarray(s["q"]), axis=0)).max()
    assert step < 0.1  # the swing's own fastest: 0.065 rad per tick; unblended: 0.30
    json.dumps(s)  # JSON-ready
    reply = session_reply(c)
    assert reply["refused"] is None
    path = tmp_path / "timeline.csv"
    path.write_text(reply["timeline"])
    tl = read_timeline(path)
    assert tl.joint_names == tuple(c.model.joint_names)
    assert np.all((tl.command >= 500) & (tl.command <= 2500))
    assert tl.t[-1] == pytest.approx(3.0, abs=1e-9)
    # the commands are the recorded angles through the calibration, to half a µs
    rec_q = np.asarray(s["q"])
    np.testing.assert_allclose(tl.command[-1], np.round(1500 + 450.0 * rec_q[-1]), atol=0.5)
    np.testing.assert_allclose(tl.q[-1], rec_q[-1], atol=0.5 / 450.0 + 1e-12)


def test_timeline_refuses_what_a_servo_cannot_do():
    """A slider jump faster than the joint's speed limit, a servo range: refused by name."""
    from hexapod_kin.drive.server import session_reply
    from hexapod_kin.exceptions import LimitError
    from hexapod_kin.export.servos import Calibration

    m = hk.load("hexabot_leg")
    c = Cockpit(m)
    c.advance(0.02)
    j = m.nq - 1
    c.set_joint(m.joint_names[j], float(m.lower[j]))  # a jump within one 20 ms tick
    c.advance(0.02)
    assert abs(c.q[j] - c._home()[j]) / 0.02 > m.velocity_limit[j]  # the case tested
    with pytest.raises(LimitError, match=f"{m.joint_names[j]}.*speed"):
        c.timeline()
    assert m.joint_names[j] in session_reply(c)["refused"]
    # ±1/3 rad: a tenth of the joint's turn, the least a calibration may sweep
    narrow = {"defaults": {**SERVOS["defaults"], "limits": [1350, 1650]}}
    c2 = Cockpit(m, calibration=Calibration.from_dict(narrow))
    c2.advance(0.02)
    assert np.any(np.abs(c2.q) * 450 > 150)  # home is beyond it
    with pytest.raises(LimitError, match="servo's limits"):
        c2.timeline()


def test_handle_refuses_bad_messages():
    """Each bad message raises its own kind of error, whose text says what is wrong."""
    c = Cockpit(hk.load("hexabot_leg"))
    q = c.q.copy()
    for bad, kind, says in (
        ([], TypeError, "a JSON object with a string 'type'"),
        ({"type": 3}, TypeError, "a JSON object with a string 'type'"),
        ({"type": "nope"}, KeyError, "type='nope': use one of 'joint'"),
        ({"type": "joint"}, KeyError, "'name'"),
        ({"type": "joint", "name": "hip", "value": "x"}, ParameterError, "value='x'"),
        ({"type": "joint", "name": "hip", "value": float("nan")}, ParameterError, "value=nan"),
        ({"type": "target", "xyz": [1, 2]}, ParameterError, "give 3 finite number(s)"),
        ({"type": "mode", "mode": "walk"}, ParameterError, "mode='walk' is not allowed"),
        ({"type": "drive", "axes": [1, 0, 0]}, ParameterError, "has no legs to walk with"),
    ):
        with pytest.raises(kind) as err:
            handle(c, bad)
        assert says in str(err.value), (bad, str(err.value))
    np.testing.assert_array_equal(c.q, q)  # nothing moved
    assert handle(c, {"type": "ping", "t": 1}) == {"type": "pong", "t": 1}


# ======================================================================== the server
def _get(url: str, host: str | None = None) -> tuple[int, bytes]:
    req = urllib.request.Request(url, headers={"Host": host} if host else {})
    try:
        with urllib.request.urlopen(req, timeout=10) as r:
            return r.status, r.read()
    except urllib.error.HTTPError as e:
        return e.code, e.read()


async def _ws_exchange(url: str, origin: str, messages: list[str], n: int) -> list[dict]:
    from tornado.httpclient import HTTPRequest
    from tornado.websocket import websocket_connect

    conn = await websocket_connect(HTTPRequest(url, headers={"Origin": origin}))
    for m in messages:
        conn.write_message(m)
    out: list[dict] = []
    while len([m for m in out if m["type"] != "state"]) < n:
        msg = await asyncio.wait_for(conn.read_message(), 10)
        assert msg is not None
        out.append(json.loads(msg))
    conn.close()
    return out


def test_server_hygiene():
    with drive("hexabot_leg", families=False) as s:
        port = s.server.port
        assert s.url == f"http://127.0.0.1:{port}/"
        status, body = _get(s.url)
        assert status == 200 and b"hexapod_kin drive" in body and b"cdn" not in body.lower()
        assert _get(s.url + "meshcat.js")[0] == 200
        assert _get(s.url, host=f"evil.example:{port}")[0] == 403
        assert _get(s.url + "meshcat.js", host=f"localhost.evil:{port}")[0] == 403
        # not listening on other interfaces
        with socket.socket() as sock:
            sock.settimeout(1)
            others = [a for a in socket.gethostbyname_ex(socket.gethostname())[2]]
            others = [a for a in others if not a.startswith("127.")]
            for addr in others:
                assert sock.connect_ex((addr, port)) != 0
        ws = f"ws://127.0.0.1:{port}/ws"
        from tornado.httpclient import HTTPClientError
        from tornado.websocket import WebSocketError

        with pytest.raises((WebSocketError, HTTPClientError)):  # a foreign Origin: refused
            asyncio.run(_ws_exchange(ws, "http://evil.example", [], 1))
        bad = ["{not json", json.dumps({"type": "joint", "name": "hip", "value": 99, "id": 7})]
        good = json.dumps({"type": "joint", "name": "hip", "value": 0.2, "id": 8})
        got = asyncio.run(_ws_exchange(ws, f"http://127.0.0.1:{port}", [*bad, good], 3))
        replies = [m for m in got if m["type"] != "state"]
        assert replies[0]["type"] == "error" and replies[0]["id"] is None
        assert replies[1]["type"] == "error" and replies[1]["id"] == 7
        assert "limits" in replies[1]["error"]
        assert replies[2] == {"type": "ack", "id": 8}
        assert s.state()["q"][0] == 0.2  # the good one applied, the bad ones dropped
        # a second page on the same server works
        got = asyncio.run(
            _ws_exchange(ws, f"http://localhost:{port}", [json.dumps({"type": "ping", "t": 5})], 1)
        )
        assert {"type": "pong", "t": 5} in got
        assert s.server.pages_seen == 2  # the foreign Origin never opened
    assert not s.running
    with socket.socket() as sock:
        assert sock.connect_ex(("127.0.0.1", port)) != 0


def _start_cli(*extra: str) -> tuple[subprocess.Popen, str]:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen(
        [sys.executable, "-m", "hexapod_kin", "drive", "hexabot_leg", "--no-open", *extra],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=env,
        text=True,
    )
    line = proc.stdout.readline()
    m = re.search(r"(http://127\.0\.0\.1:\d+/)", line)
    assert m, (line, proc.stderr.read() if proc.poll() is not None else "")
    return proc, m.group(1)


def test_cli_ctrl_c_leaves_nothing():
    proc, url = _start_cli()
    try:
        assert _get(url)[0] == 200
        proc.send_signal(signal.SIGINT)
        rc = proc.wait(30)
        assert (130 if rc == -signal.SIGINT else rc) == 130  # a shell's $? for both
        assert proc.stderr.read().strip().endswith("hexapod-kin: interrupted")
    finally:
        if proc.poll() is None:
            proc.kill()
    port = int(url.rsplit(":", 1)[1].strip("/"))
    with socket.socket() as sock:
        assert sock.connect_ex(("127.0.0.1", port)) != 0


def test_cli_stops_when_the_page_closes():
    proc, url = _start_cli("--until-closed")
    try:
        ws = url.replace("http", "ws") + "ws"
        asyncio.run(_ws_exchange(ws, url.rstrip("/"), [json.dumps({"type": "ping"})], 1))
        assert proc.wait(30) == 0
    finally:
        if proc.poll() is None:
            proc.kill()


def test_drive_refuses_bad_port():
    with pytest.raises(ParameterError, match="port"):
        drive("hexabot_leg", port=-1)


def test_cli_refuses_bad_input(capsys):
    """Status 2 and one error line naming the value (before any server starts)."""
    from hexapod_kin.cli import main

    for argv, says in (
        (["hexabot_leg", "--no-open", "--port", "70000"], "--port 70000 is not allowed"),
        (["no_such_robot", "--no-open"], "source='no_such_robot' is not a preset"),
    ):
        assert main(["drive", *argv]) == 2
        err = capsys.readouterr().err.splitlines()
        assert len(err) == 1 and err[0].startswith("hexapod-kin: error: ") and says in err[0], err


@pytest.mark.parametrize("src", ROBOTS[1:])
def test_stance_width_puts_the_feet_at_the_reach(src):
    c = Cockpit(hk.load(src))
    wb = c.body
    c.set_stance(1.2)
    assert c.status == "held", c.message
    feet = wb.feet(c.qb[None], c.base[None])[0]  # FK of the IK's joints
    expect = (c.stand[:3, :3] @ wb.neutral_feet(1.2 * wb.foot_reach).T + c.stand[:3, 3:4]).T
    np.testing.assert_allclose(feet[:, :2], expect[:, :2], atol=1e-6)
    np.testing.assert_allclose(feet[:, 2], wb.foot_radius, atol=1e-6)
    with pytest.raises(ParameterError, match=r"\[0.6, 1.4\]"):
        c.set_stance(3.0)


def test_nearest_family_and_sigma_min_at_a_singular_pose():
    """ankle = 0 stretches the seeds' leg: family q3 = 0 at distance 0, σ_min = 0 (SVD)."""
    from hexapod_kin.singularity import default_rows, families_for

    m = hk.load("hexabot_leg")
    fams = families_for(m, default_rows(m), derive=False)
    c = Cockpit(m, families=fams)
    c.set_joint("ankle", 0.0)
    r = c.readout()
    assert r["sigma_min"] < 1e-12
    s = np.linalg.svd(m.jacobian(c.q)[:3], compute_uv=False)
    assert r["manipulability"] == pytest.approx(float(np.prod(s)), abs=1e-15)
    if not fams.families:
        pytest.skip("the leg's families are not derived on this machine (hexapod-kin derive)")
    assert r["family"]["name"].startswith("q3 = 0") and r["family"]["distance"] < 1e-12
    c.set_joint("ankle", 0.3)
    assert c.readout()["family"]["distance"] == pytest.approx(0.3, abs=1e-9)


def test_family_project_lands_on_the_family():
    """Family.project (the drawn chain on a family): ``q_k = v`` moves ``q_k`` onto ``v``
    (wrapped: the nearest copy), the rest kept; an implicit family's projection has a zero
    factor (closed form, 1e-12) and is no nearer than the family's closest distance."""
    from hexapod_kin.singularity import Family

    q = np.array([0.3, 0.4, 6.0])
    fixed = Family("q3 = 0", "Eq(q3, 0)", (2,), 2, 0.0, True, "q3")
    np.testing.assert_array_equal(fixed.project(q)[:2], q[:2])
    assert fixed.project(q)[2] == pytest.approx(2 * math.pi, abs=1e-12)
    knee = Family("knee", "knee", (1, 2), None, None, False, "0.16*cos(q2) + 0.16*cos(q2 + q3)")
    p = knee.project(q)
    assert p[0] == q[0]
    assert 0.16 * math.cos(p[1]) + 0.16 * math.cos(p[1] + p[2]) == pytest.approx(0, abs=1e-12)
    assert float(np.linalg.norm(p - q)) >= float(knee.distance(q)) - 1e-12


#: solo12 (the torque kind) in the slow step: test_drive_browser's physics test asserts the
#: same walk and push figures on it in the default run.
@pytest.mark.parametrize("source", ["hexapod", pytest.param("erd:solo12", marks=pytest.mark.slow)])
def test_physics_mode_walks_and_a_push_moves_the_base(source):
    """MuJoCo under the closed-loop controller (servo kind for the hexapod, torque kind for the
    quadruped): W walks the base forward (≥ half the commanded distance; the controller's own
    tests hold its accuracy), the readout's actual velocity is the base's (its displacement
    over the last second), and a push's impulse changes the base velocity along it (at least
    a quarter of F·Δt/m: the feet's friction takes the rest)."""
    from hexapod_kin.drive.physics import PUSH_TIME

    pytest.importorskip("mujoco")
    pytest.importorskip("proxsuite")
    c = Cockpit(hk.load(source))
    c.set_mode("physics")
    assert c.physics.kind == ("servo" if source == "hexapod" else "torque")
    for _ in range(25):  # settle 0.5 s
        c.advance(0.02)
    sup = c.support()  # standing: every foot in MuJoCo's contact, the CoM inside
    assert sup["stance"] == c.physics.contacts().tolist() == [True] * c.body.n_legs, sup
    assert sup["margin"] > 0.05, sup
    x0 = c.base[:3, 3].copy()
    c.set_drive((1.0, 0.0, 0.0))
    assert c.readout()["mode"] == "physics"
    for _ in range(100):  # 3 s at 0.05 m/s
        c.advance(0.02)
    x2 = c.base[:3, 3].copy()
    for _ in range(50):
        c.advance(0.02)
    moved = c.base[:3, 3] - x0
    assert moved[0] >= 0.5 * 0.05 * 3.0 and abs(moved[1]) < 0.3 * moved[0], moved
    r = c.readout()
    assert r["command"] == pytest.approx([0.05, 0.0, 0.0], abs=1e-15)
    v_last = (c.base[:3, 3] - x2)[0] / 1.0  # heading ≈ +x (|y| small, above)
    assert r["actual"][0] == pytest.approx(v_last, abs=0.3 * 0.05), (r["actual"], v_last)
    c.set_drive((0.0, 0.0, 0.0))
    for _ in range(50):
        c.advance(0.02)
    v0 = c.physics.state()[2]
    force = (0.0, c.physics.push_force)  # the page's push
    c.push(force)
    for _ in range(5):  # the push's 0.1 s
        c.advance(0.02)
    v1 = c.physics.state()[2]
    dv = v1 - v0
    assert dv[1] >= 0.25 * force[1] * PUSH_TIME / c.physics.mass, dv
    pv = c.physics.push_velocities  # recorded in simulated time at the push's start and end
    assert pv is not None and np.array_equal(pv[0], v0) and np.array_equal(pv[1], v1), pv
    assert abs(dv[0]) < 0.2 * dv[1], dv  # along the push
    for _ in range(50):  # it stays up (the push's size per kind)
        c.advance(0.02)
    assert c.base[2, 2] > 0.9 and c.base[2, 3] > 0.8 * x0[2], c.base
    assert any(e["type"] == "push" for e in c.session()["events"])
    with pytest.raises(ParameterError, match="force"):
        c.push((1.0, float("nan")))
    c.set_mode("walk")  # leaving physics: standing again
    with pytest.raises(ParameterError, match="physics"):
        c.push(force)


def _centroidal_cop(phys, period):
    """Advance ``phys`` one control period; return (its CoP, the CoP from the momentum balance).

    The balance uses no contact force: over the period T, the ground's vertical impulse is
    Δ(m ċ_z) + m g T and its moment about the world origin ΔL_O − ∫ c × m g dt (L_O, c, ċ
    from MuJoCo's subtree momenta, ∫ c dt by the trapezoid), so on the plane z = 0
    x = −M_y / F_z and y = M_x / F_z (Newton–Euler of the whole robot).
    """
    import mujoco as mj

    def momentum():
        m, d = phys.model, phys.data
        mj.mj_kinematics(m, d)
        mj.mj_comPos(m, d)
        mj.mj_comVel(m, d)
        mj.mj_subtreeVel(m, d)
        b = phys.base_body
        c, v = np.array(d.subtree_com[b]), np.array(d.subtree_linvel[b])
        return c, v, np.array(d.subtree_angmom[b]) + np.cross(c, phys.mass * v)

    c0, v0, L0 = momentum()
    phys.advance(period)
    c1, v1, L1 = momentum()
    m, g = phys.mass, -float(phys.model.opt.gravity[2])
    fz = m * (v1[2] - v0[2]) + m * g * period
    my = (L1[1] - L0[1]) - m * g * period * (c0[0] + c1[0]) / 2
    mx = (L1[0] - L0[0]) + m * g * period * (c0[1] + c1[1]) / 2
    return phys.zmp(), np.array([-my / fz, mx / fz]), c1


def test_physics_zmp_is_the_centre_of_pressure():
    """Physics mode's ZMP is the centre of pressure of MuJoCo's contact forces: equal, period
    by period, to the one of the whole robot's momentum balance (no contact force in it) within
    0.5 mm (the trapezoid over a 2 ms period and the joints' armature, measured < 0.1 mm), while
    it is several mm away from the CoM's projection (what the page drew before); the readout's
    ZMP and ZMP margin are it and its margin in the contact feet's polygon."""
    pytest.importorskip("mujoco")
    pytest.importorskip("proxsuite")
    from hexapod_kin.gait.stability import support_margin

    c = Cockpit(hk.load("erd:solo12"))
    c.set_mode("physics")
    c.set_drive((1.0, 0.0, 0.0))
    for _ in range(50):  # 1 s of the trot
        c.advance(0.02)
    phys = c.physics
    period = 1.0 / phys.ctl.rate
    off = []
    for _ in range(30):
        cop, ref, com = _centroidal_cop(phys, period)
        assert cop is not None and cop[2] == phys.ground_z == 0.0
        np.testing.assert_allclose(cop[:2], ref, atol=5e-4, rtol=0)
        off.append(float(np.linalg.norm(cop[:2] - com[:2])))
    assert max(off) > 3e-3, off  # not the CoM's projection
    q, base, _ = phys.state()
    c._set_limb_q(q)
    c.base = base
    sup = c.support()
    np.testing.assert_array_equal(sup["zmp"], phys.zmp())
    feet = np.asarray(c.body.feet(c.qb[None], c.base[None])[0])
    margin = support_margin(feet, phys.contacts(), phys.zmp())
    assert sup["zmp_margin"] == pytest.approx(float(margin), abs=1e-12)


@pytest.mark.slow  # 250 simulated control ticks, ~10 s; physics mode walks in the default run too
def test_physics_offers_every_pattern_control_walks():
    """A quadruped's physics mode offers the controller's patterns (trot included, which the
    kinematic walk does not: not statically stable), starts in ``hexapod-kin control``'s trot,
    walks ≥ 0.8 of the commanded distance without falling, and switches pattern while
    walking (the controller takes it at its next cycle) still walking upright."""
    pytest.importorskip("mujoco")
    pytest.importorskip("proxsuite")
    from hexapod_kin.gait.tables import pattern_names

    c = Cockpit(hk.load("erd:solo12"))
    xy = c.body.mounts[:, :2, 3]
    assert c.patterns == ("crawl",)
    assert c.physics_patterns == pattern_names(4, xy) and "trot" in c.physics_patterns
    with pytest.raises(ParameterError, match="walk mode|joints mode"):
        c.set_pattern("trot")  # the kinematic walk: statically stable patterns only
    c.set_mode("physics")
    assert c.pattern == "trot" and c.physics.ctl.pattern == "trot"
    z0 = c.base[2, 3]
    x0 = c.base[:3, 3].copy()
    c.set_drive((1.0, 0.0, 0.0))
    for _ in range(150):  # 3 s at 0.05 m/s
        c.advance(0.02)
    walked = c.base[:3, 3] - x0
    assert walked[0] >= 0.8 * 0.05 * 3.0 and abs(walked[1]) < 0.2 * walked[0], walked
    assert c.base[2, 2] > 0.95 and c.base[2, 3] > 0.8 * z0, c.base
    c.set_pattern("crawl")
    x1 = c.base[:3, 3].copy()
    for _ in range(100):
        c.advance(0.02)
    assert c.physics.ctl.pattern == "crawl" and c.readout()["pattern"] == "crawl"
    assert (c.base[:3, 3] - x1)[0] > 0.5 * 0.05 * 2.0
    assert c.base[2, 2] > 0.95 and c.base[2, 3] > 0.8 * z0, c.base
    with pytest.raises(ParameterError, match="physics mode"):
        c.set_pattern("tripod")
    c.set_mode("joints")  # back to the kinematic walk's patterns
    assert c.pattern in c.patterns


@pytest.mark.parametrize("source", ["hexapod", "erd:solo12"])
def test_legged_joints_mode_shows_the_moved_legs_family(source):
    """A legged robot's joints mode: the moved leg's chain (``Model.view(root, foot)``) and its
    families; the knee-straight family q3 = 0 at the distance of the ankle/knee angle, and the
    ghost drawn in the world equals the full robot's frames (Pinocchio on the whole model, not
    the view) at that angle to 1e-9."""
    import pinocchio as pin

    from hexapod_kin.singularity import default_rows, families_for

    m = hk.load(source)
    probe = Cockpit(m)
    fams = tuple(families_for(v, default_rows(v), derive=True) for v in probe.leg_views)
    if not all(f.families for f in fams):
        pytest.skip("the legs' families could not be derived here")
    c = Cockpit(m, families=fams)
    leg = 1
    view = c.leg_views[leg]
    assert view.nq == 3 and view.joint_names[0] in m.joint_names
    j = m.joint_names.index(view.joint_names[2])  # the knee/ankle: q3 of the view
    lo, hi = float(m.lower[j]), float(m.upper[j])
    v = 0.1 if lo <= 0.1 <= hi else -0.1
    c.set_joint(view.joint_names[2], v)
    r = c.readout()
    assert r["foot"] == f"foot of {c.body.leg_names[leg]}"
    fam = r["family"]
    assert fam["name"].startswith("q3 = 0") and fam["near"]
    assert fam["distance"] == pytest.approx(abs(v), abs=1e-12)
    q = np.array(r["q"])
    q[j] = 0.0
    d = m.model.createData()
    pin.framesForwardKinematics(m.model, d, m.pinocchio_q(q))
    ref = [
        (c.base @ (m.baseMo * d.oMf[m.model.getFrameId(f)]).homogeneous)[:3, 3]
        for f in view.path_frames
    ]
    np.testing.assert_allclose(fam["ghost"], ref, atol=1e-9, rtol=0)
    c.set_mode("walk")
    assert c.readout()["family"] is None  # joints mode only
