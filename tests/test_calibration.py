"""A servo calibration read for a robot: each entry a joint of it, each servo fit for its limits."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

import hexapod_kin as hk
from hexapod_kin.cli import main
from hexapod_kin.exceptions import ParameterError
from hexapod_kin.export.servos import Calibration, Servo, read_calibration
from hexapod_kin.export.timeline import timeline

AX12 = "defaults: {units: ticks, ticks_per_revolution: 1228.8, centre: 512, limits: [0, 1023]}\n"

#: A 2-joint robot with narrow limits [rad] (duck-typed as a model).
ROBOT = SimpleNamespace(name="two", joint_names=("a", "b"), lower=[-0.5, 0.2], upper=[0.5, 1.0])


def write(tmp_path, text):
    path = tmp_path / "cal.yaml"
    path.write_text(text)
    return path


def test_unknown_joint_named_with_the_joints_allowed(tmp_path):
    path = write(tmp_path, AX12 + "joints:\n  c: {offset: 0.1}\n")
    read_calibration(path)  # without a robot nothing to hold it to
    with pytest.raises(ParameterError, match=r"cal.yaml': .*'c' is not in 'two'.*'a', 'b'") as exc:
        read_calibration(path, robot=ROBOT)
    assert exc.value.value == "c" and exc.value.allowed == ["a", "b"]


def test_offset_more_than_a_turn_outside_the_joint_limits(tmp_path):
    # offset given in degrees by mistake: 90 "rad" on a joint of [0.2, 1.0] rad
    path = write(tmp_path, AX12 + "joints:\n  b: {offset: 90}\n")
    with pytest.raises(ParameterError, match=r"calibration of b: offset 90 .*\[0.2, 1\]") as exc:
        read_calibration(path, robot=ROBOT)
    assert exc.value.parameter == "offset" and exc.value.value == 90
    assert exc.value.allowed == pytest.approx((0.2 - 2 * math.pi, 1.0 + 2 * math.pi))
    # just inside that turn, a servo without limits: accepted
    read_calibration(write(tmp_path, "joints:\n  b: {offset: 7.0}\n"), robot=ROBOT)


def test_servo_range_that_misses_the_joint_range(tmp_path):
    # 200..300 deg of servo angle (offset 0, direction +1) = 3.49..5.24 rad, beyond [-0.5, 0.5]
    text = "joints:\n  a: {units: deg, limits: [200, 300]}\n"
    with pytest.raises(ParameterError, match=r"calibration of a: limits \[200.0, 300.0\]") as exc:
        read_calibration(write(tmp_path, text), robot=ROBOT)
    assert exc.value.parameter == "limits"
    # allowed: the joint's limits in the servo's units, by the map u = (q - q0) 180/pi
    assert exc.value.allowed == pytest.approx((math.degrees(-0.5), math.degrees(0.5)))
    assert "[3.49066, 5.23599]" in str(exc.value)
    # reversed direction maps the same servo range to -5.24..-3.49 rad: refused too
    with pytest.raises(ParameterError, match="outside its limits"):
        Calibration.from_dict(
            {"joints": {"a": {"units": "deg", "limits": [200, 300], "direction": -1}}}
        ).check_joints(ROBOT.joint_names, ROBOT.lower, ROBOT.upper)
    # a range that reaches into the joint's: accepted (the samples are checked later)
    read_calibration(write(tmp_path, "joints:\n  a: {units: deg, limits: [20, 300]}\n"), ROBOT)


def test_defaults_checked_for_every_unlisted_joint():
    # the AX-12 centre 512 is q = 2 rad; its range [0, 1023] ticks is 2 -/+ 2.62 rad: b fits,
    # and so does a; a centre far outside both joints is refused for the first one
    cal = Calibration(default=Servo("*", "ticks", 2.0, 1, 1228.8, 512.0, limits=(0.0, 1023.0)))
    cal.check_joints(ROBOT.joint_names, ROBOT.lower, ROBOT.upper)
    far = Calibration(default=Servo("*", "ticks", -9.0, 1, 1228.8, 512.0, limits=(0.0, 1023.0)))
    with pytest.raises(ParameterError, match="calibration of a: offset -9"):
        far.check_joints(ROBOT.joint_names, ROBOT.lower, ROBOT.upper)
    # infinite limits (a continuous joint) check nothing
    far.check_joints(ROBOT.joint_names, [-np.inf, -np.inf], [np.inf, np.inf])


def test_timeline_refuses_before_any_sample(tmp_path):
    model = hk.load("hexabot_leg")
    t = np.linspace(0.0, 1.0, 11)
    q = np.zeros((11, 3))
    cal = write(tmp_path, "joints:\n  knee: {units: deg, limits: [200, 300]}\n")
    with pytest.raises(ParameterError, match="calibration of knee: limits"):
        timeline(
            (t, q),
            rate=10,
            calibration=cal,
            joint_names=model.joint_names,
            position_limit=(model.lower, model.upper),
        )
    with pytest.raises(ParameterError, match="'elbow' is not in 'hexabot_leg'"):
        read_calibration(write(tmp_path, "joints:\n  elbow: {}\n"), robot=model)


def test_cli_one_line_exit_2(tmp_path, capsys):
    cal = write(tmp_path, "joints:\n  knee: {units: deg, limits: [200, 300]}\n")
    out = tmp_path / "t.csv"
    argv = ["timeline", "step", "hexabot_leg", "--duration", "0.5", "--calibration", str(cal)]
    assert main([*argv, "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "knee" in err[0] and "limits" in err[0]
    assert not out.exists()
