"""Joint timelines: servo maps checked by hand, round trips, refusals naming joint and time."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest
import yaml

import hexapod_kin as hk
from hexapod_kin.exceptions import ConfigurationError, HexapodKinError, ParameterError
from hexapod_kin.export.timeline import (
    Calibration,
    Servo,
    read_calibration,
    read_plan,
    read_timeline,
    timeline,
)

# AX-12-like: 1024 ticks over 300 degrees, centre 512, speed ~114 rpm.
TICKS_PER_REV = 1024 * 360 / 300
HALF_TICK = 0.5 * 2 * math.pi / TICKS_PER_REV
AX12 = {
    "units": "ticks",
    "ticks_per_revolution": TICKS_PER_REV,
    "centre": 512,
    "limits": [0, 1023],
    "velocity_limit": 114 * 2 * math.pi / 60,
}


@pytest.fixture(scope="module")
def walk():
    return hk.gait.walk(pattern="tripod", duration=10)


def ax12_calibration(**joints):
    return Calibration.from_dict({"defaults": AX12, "joints": joints})


def plan_at(run, t):
    return np.column_stack([np.interp(t, run.t, run.q[:, j]) for j in range(run.q.shape[1])])


def test_tripod_walk_ax12_read_back_within_half_a_tick(walk, tmp_path):
    cal = ax12_calibration(leg1_knee={"direction": -1, "offset": -0.3}, leg2_ankle={"offset": 1.6})
    tl = timeline(walk, rate=50, calibration=cal)
    assert tl.t[0] == 0 and tl.t[-1] == pytest.approx(10.0)
    np.testing.assert_allclose(np.diff(tl.t), 0.02, atol=1e-12)
    plan = plan_at(walk, tl.t)
    # the servo map by hand: ticks = 512 + d (q - q0) 1024 / (300 deg)
    names = list(walk.joint_names)
    d = np.ones(18)
    q0 = np.zeros(18)
    d[names.index("leg1_knee")] = -1
    q0[names.index("leg1_knee")] = -0.3
    q0[names.index("leg2_ankle")] = 1.6
    by_hand = np.round(512 + d * (plan - q0) * 1024 / math.radians(300))
    np.testing.assert_array_equal(tl.command, by_hand)
    for suffix in (".csv", ".json", ".yaml"):
        back = read_timeline(tl.write(tmp_path / f"walk{suffix}"))
        assert back.joint_names == walk.joint_names
        np.testing.assert_allclose(back.t, tl.t, atol=1e-9)
        assert np.abs(back.q - plan).max() <= HALF_TICK + 1e-12
        assert np.abs(back.q - plan).max() > 0  # rounded to ticks, not a copy of the plan
        np.testing.assert_allclose(back.qdot, tl.qdot, rtol=1e-12, atol=1e-12)


def test_sample_past_servo_limit_refused_by_name(walk):
    names = list(walk.joint_names)
    j = names.index("leg3_ankle")
    # first sample whose ticks (by hand) pass 760
    t = np.arange(501) / 50
    ticks = np.round(512 + plan_at(walk, t)[:, j] * 1024 / math.radians(300))
    k = int(np.flatnonzero(ticks > 760)[0])
    cal = ax12_calibration(leg3_ankle={"limits": [0, 760]})
    with pytest.raises(ConfigurationError) as err:
        timeline(walk, rate=50, calibration=cal)
    assert err.value.parameter == "leg3_ankle"
    assert f"t={t[k]:.4f} s" in str(err.value)
    assert err.value.value == pytest.approx(512 + plan_at(walk, t)[k, j] * 1024 / math.radians(300))
    assert err.value.allowed == (0.0, 760.0)


def test_speed_limit_refused_by_name(walk):
    j = list(walk.joint_names).index("leg1_ankle")
    peak = np.abs(walk.qdot[:, j]).max()
    cal = ax12_calibration(leg1_ankle={"velocity_limit": 0.9 * peak})
    with pytest.raises(ConfigurationError, match=r"joint leg1_ankle at t=\d+\.\d+ s: speed"):
        timeline(walk, rate=100, calibration=cal)
    # the model's limits apply when the calibration has none
    with pytest.raises(ConfigurationError, match="speed"):
        timeline(walk, rate=100, velocity_limit=0.5)


def test_units_deg_and_pwm_by_hand(tmp_path):
    t = np.linspace(0, 1, 11)
    q = np.column_stack([0.3 * np.sin(t), -0.2 * t])
    cal = Calibration(
        servos={
            "a": Servo("a", units="deg", direction=-1, offset=0.1),
            "b": Servo("b", units="us", us_per_rad=600 / (math.pi / 2), centre=1500,
                       limits=(900, 2100)),
        }
    )  # fmt: skip
    tl = timeline((t, q), rate=10, calibration=cal, joint_names=["a", "b"])
    np.testing.assert_allclose(tl.command[:, 0], -np.degrees(q[:, 0] - 0.1), atol=1e-12)
    np.testing.assert_array_equal(tl.command[:, 1], np.round(1500 + q[:, 1] * 1200 / math.pi))
    back = read_timeline(tl.write(tmp_path / "x.json"))
    np.testing.assert_allclose(back.q[:, 0], q[:, 0], atol=1e-12)
    assert np.abs(back.q[:, 1] - q[:, 1]).max() <= 0.5 * math.pi / 1200 + 1e-12


def test_cubic_is_exact_on_a_cubic_and_its_derivative():
    t = np.linspace(0, 2, 9)
    q = (t**3 - t)[:, None]
    tl = timeline((t, q), rate=37, interpolation="cubic")
    np.testing.assert_allclose(tl.q[:, 0], tl.t**3 - tl.t, atol=1e-12)
    np.testing.assert_allclose(tl.qdot[:, 0], 3 * tl.t**2 - 1, atol=1e-12)


def test_ros2_yaml_times_strictly_increase_and_match(walk, tmp_path):
    tl = timeline(walk, rate=50, calibration=ax12_calibration())
    doc = yaml.safe_load(tl.write(tmp_path / "walk.yaml").read_text())
    assert set(doc) == {"header", "joint_names", "points"}
    assert doc["joint_names"] == list(walk.joint_names)
    stamps = [(p["time_from_start"]["sec"], p["time_from_start"]["nanosec"]) for p in doc["points"]]
    assert all(0 <= ns < 1_000_000_000 for _, ns in stamps)
    assert all(a < b for a, b in zip(stamps, stamps[1:]))
    assert stamps[1] == (0, 20_000_000) and stamps[-1] == (10, 0)
    assert all(len(p["positions"]) == 18 == len(p["velocities"]) for p in doc["points"])


def test_calibration_files_yaml_toml_json_agree(tmp_path):
    (tmp_path / "c.yaml").write_text(
        "defaults: {units: ticks, ticks_per_revolution: 1228.8, centre: 512, limits: [0, 1023]}\n"
        "joints:\n  j2: {direction: -1, offset: 0.5}\n"
    )
    (tmp_path / "c.toml").write_text(
        "[defaults]\nunits = 'ticks'\nticks_per_revolution = 1228.8\ncentre = 512\n"
        "limits = [0, 1023]\n[joints.j2]\ndirection = -1\noffset = 0.5\n"
    )
    data = {
        "defaults": {
            "units": "ticks",
            "ticks_per_revolution": 1228.8,
            "centre": 512,
            "limits": [0, 1023],
        },
        "joints": {"j2": {"direction": -1, "offset": 0.5}},
    }
    (tmp_path / "c.json").write_text(json.dumps(data))  # fmt: skip
    cals = [read_calibration(tmp_path / f"c.{s}") for s in ("yaml", "toml", "json")]
    assert cals[0] == cals[1] == cals[2]
    assert cals[0].servo("j2").direction == -1 and cals[0].servo("j1").offset == 0


def test_bad_calibrations_refused():
    with pytest.raises(ParameterError, match="units 'steps' unknown"):
        Calibration.from_dict({"joints": {"j1": {"units": "steps"}}})
    with pytest.raises(ParameterError, match="ticks_per_revolution"):
        Calibration.from_dict({"joints": {"j1": {"units": "ticks"}}})
    with pytest.raises(ParameterError, match="unknown key 'ofset'"):
        Calibration.from_dict({"joints": {"j1": {"ofset": 1}}})
    t = np.linspace(0, 1, 3)
    with pytest.raises(ParameterError, match="no servo for joint 'j2'"):
        timeline((t, np.zeros((3, 2))), rate=5, joint_names=["j1", "j2"],
                 calibration=Calibration.from_dict({"joints": {"j1": {}}}))  # fmt: skip
    with pytest.raises(ParameterError, match="'j9' is not in the plan"):
        timeline((t, np.zeros((3, 1))), rate=5, joint_names=["j1"],
                 calibration=Calibration.from_dict({"joints": {"j9": {}}}))  # fmt: skip
    with pytest.raises(HexapodKinError, match="rate"):
        timeline((t, np.zeros((3, 1))), rate=0)


def test_cli_gait_and_path(tmp_path):
    cal = tmp_path / "cal.yaml"
    cal.write_text(
        "defaults: {units: ticks, ticks_per_revolution: 1228.8, centre: 512, "
        "limits: [0, 1023], velocity_limit: 11.9}\n"
    )
    cmd = [sys.executable, "-m", "hexapod_kin", "timeline", "gait", "--pattern", "tripod",
           "--duration", "2", "--rate", "50", "--calibration", str(cal)]  # fmt: skip
    done = subprocess.run([*cmd, "-o", str(tmp_path / "w.csv")], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    tl = read_timeline(tmp_path / "w.csv")
    ref = timeline(hk.gait.walk(pattern="tripod", duration=2), rate=50, calibration=cal)
    np.testing.assert_array_equal(tl.command, ref.command)
    cal.write_text(cal.read_text() + "joints:\n  leg1_ankle: {limits: [0, 700]}\n")
    done = subprocess.run([*cmd, "-o", str(tmp_path / "x.csv")], capture_output=True, text=True)
    assert done.returncode == 1  # a servo limit reached: answered, not achieved
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "not achieved: joint leg1_ankle at t=" in lines[0]
    assert not (tmp_path / "x.csv").exists()
    # an IK path from a file
    plan = tmp_path / "path.csv"
    plan.write_text("t,j1,j2\n0,0,0\n0.5,0.25,-0.5\n1,1,-1\n")
    t, q, names = read_plan(plan)
    assert names == ("j1", "j2") and q.shape == (3, 2)
    out = tmp_path / "path.yaml"
    done = subprocess.run(
        [sys.executable, "-m", "hexapod_kin", "timeline", "path", str(plan), "--rate", "10",
         "-o", str(out)], capture_output=True, text=True,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    back = read_timeline(out)
    np.testing.assert_allclose(back.q[:, 1], np.interp(back.t, t, q[:, 1]), atol=1e-15)


def test_step_timeline_cli_matches_the_api(tmp_path):
    from hexapod_kin.cli import main
    from hexapod_kin.seeds import seed_experiment

    model = hk.load("hexabot_leg")
    run = seed_experiment(model, duration=2.0, baseline=False)
    ref = timeline(run.trajectory, rate=100, joint_names=model.joint_names)
    # the step's own rates (q̇ of the control law) interpolated: equal to the plan's at knots
    k = np.searchsorted(run.trajectory.t, ref.t)
    np.testing.assert_allclose(ref.q, run.trajectory.q[k], atol=1e-12)
    np.testing.assert_allclose(ref.qdot, run.trajectory.qdot[k], atol=1e-12)
    out = tmp_path / "step.json"
    assert main(["timeline", "step", "--duration", "2", "--rate", "100", "-o", str(out)]) == 0
    back = read_timeline(out)
    assert back.joint_names == model.joint_names
    np.testing.assert_allclose(back.q, ref.q, atol=1e-15)


def test_a_path_for_a_robot_is_held_to_its_joint_limits_and_names(tmp_path):
    """`timeline path FILE SOURCE`: the plan's joints by name, inside the robot's limits."""
    import hexapod_kin as hk
    from hexapod_kin.cli import main
    from hexapod_kin.exceptions import LimitError
    from hexapod_kin.export.timeline import timeline

    leg = hk.load("hexabot_leg")
    hi = float(leg.upper[0])
    for q_end, status in ((1e308, 1), (hi + 0.01, 1), (hi - 0.01, 0)):
        plan = tmp_path / "p.csv"
        plan.write_text(f"t,hip,knee,ankle\n0,0,0,0\n1,{q_end!r},0,0\n")
        out = tmp_path / "o.json"
        assert main(["timeline", "path", str(plan), "hexabot_leg", "-o", str(out)]) == status
        assert out.exists() == (status == 0)
        if status == 0:
            import json

            data = json.loads(out.read_text())  # valid JSON, every angle inside the limits
            assert max(max(abs(v) for v in row) for row in data["command"]) <= hi  # rad units
        out.unlink(missing_ok=True)
    plan.write_text("t,q1,knee,ankle\n0,0,0,0\n1,0.1,0,0\n")
    assert main(["timeline", "path", str(plan), "hexabot_leg", "-o", str(out)]) == 2
    # the API: limits given, or the plan's robot's
    with pytest.raises(LimitError) as err:
        timeline(([0.0, 1.0], [[0.0], [2.0]]), rate=10, position_limit=([-1.0], [1.0]))
    assert err.value.parameter == "joint1" and "t=0.6000" in str(err.value)  # q = 2t > 1
