"""``simulate --robust``: the bumpy members walk under the closed-loop controller (issue 31).

Independent references: the closed loop's own recorded body positions and the plan's
planned body poses (the travel along the plan recomputed from them), the controller's own
settings (what it was asked to walk on), the ensemble's definition.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco")
pytest.importorskip("proxsuite")

from hexapod_kin.exceptions import ParameterError  # noqa: E402
from hexapod_kin.robust import (  # noqa: E402
    CONTROL_LIMITS,
    ENSEMBLE,
    ControlledRun,
    Member,
    simulate_robust,
)
from hexapod_kin.robust.controlled import (  # noqa: E402
    RAMP_STEP,
    mean_twist,
    plan_command,
    plan_motion,
    ramped_motion,
)
from hexapod_kin.simulate import SimRun  # noqa: E402
from hexapod_kin.simulate.replay import LIMITS  # noqa: E402


def test_the_ensemble_controls_exactly_its_bumpy_members() -> None:
    assert [m.mode for m in ENSEMBLE] == ["replay"] * 8 + ["controlled"] * 3
    assert all((m.bumps == 0.003) == m.controlled for m in ENSEMBLE)
    assert [m.seed for m in ENSEMBLE if m.controlled] == [0, 1, 2]
    assert CONTROL_LIMITS["travel"] == LIMITS["travel"]  # 1 % of the plan's distance


@pytest.fixture(scope="module")
def mixed() -> object:
    """The built-in hexapod's 1.5 s tripod: a controlled bumpy member first, then a replay."""
    members = (dataclasses.replace(ENSEMBLE[9], name="bumpy"), ENSEMBLE[0])
    return simulate_robust(
        pattern="tripod", velocity=(0.05, 0.0, 0.0), duration=1.5, members=members, stand=False
    )


@pytest.mark.slow
def test_a_controlled_member_walks_the_plans_twist_on_its_bumps(mixed) -> None:
    walked, replay = mixed.runs
    assert isinstance(walked, ControlledRun) and isinstance(replay, SimRun)
    assert mixed.nominal is replay and mixed.worst_replay is replay
    c = walked.control
    m = mixed.members[0]
    assert (c.settings["bumps"], c.settings["seed"], c.settings["friction"]) == (0.003, 1, 0.8)
    assert c.pattern == replay.plan["pattern"]["name"] == "tripod"
    cmd = c.settings["commands"][0]
    motion = plan_motion(replay.planned, replay.turn_planned)
    assert (cmd["vx"], cmd["vy"], cmd["wz"]) == plan_command(motion, replay.plan["duration"])
    # the tripod moves at its twist: the mean twist is the nominal one, raised by the ramp
    vx = replay.plan["velocity"][0]
    assert vx < cmd["vx"] < 1.02 * vx and cmd["vy"] == cmd["wz"] == 0.0
    assert c.simulated == pytest.approx(0.5 + replay.plan["duration"])
    assert m.controlled and walked.mode == "controlled"


def test_a_controlled_members_travel_is_along_the_plan(mixed) -> None:
    walked, replay = mixed.runs
    planned = np.asarray(replay.planned)[[0, -1], :2, 3]
    u = (planned[1] - planned[0]) / np.linalg.norm(planned[1] - planned[0])
    c = walked.control
    p, path = np.asarray(c.position), np.asarray(c.path)
    n = round(c.settings["period"] * c.settings["rate"])  # samples of the last gait cycle
    end = path[-1, :2] + (p[-n:, :2] - path[-n:, :2]).mean(axis=0)  # surge and sway left out
    assert np.asarray(c.end) == pytest.approx(end, abs=1e-12)
    along = float((end - p[0, :2]) @ u)  # the start heading is 0 in both
    assert abs(float(np.asarray(walked.control.rpy)[0, 2])) < 0.01
    expect = (along - replay.distance_planned) / replay.distance_planned
    assert walked.distance_error == pytest.approx(expect, abs=1e-4)
    assert walked.distance_planned == replay.distance_planned > 0.05
    assert walked.turn_error is None  # a straight plan
    c = walked.checks()
    assert set(c) == {"travel", "heading", "fell", "contacts"}
    assert c["travel"]["value"] == pytest.approx(abs(expect), abs=1e-4)
    assert c["heading"]["value"] == walked.control.heading_error
    assert mixed.to_dict()["members"][0]["mode"] == "controlled"


def test_a_fall_or_a_contact_fails_a_controlled_member(mixed) -> None:
    walked = mixed.runs[0]
    fell = dataclasses.replace(walked, control=dataclasses.replace(walked.control, fell=True))
    assert not fell.checks()["fell"]["ok"] and not fell.ok
    touch = dataclasses.replace(
        walked,
        control=dataclasses.replace(walked.control, non_foot_contacts=(("a", "b", 0.1),)),
    )
    assert not touch.checks()["contacts"]["ok"]
    for ratio, ok in ((0.95, False), (1.005, True), (1.015, False)):  # along / planned
        other = dataclasses.replace(walked, distance_planned=walked.distance_along / ratio)
        assert other.distance_error == pytest.approx(ratio - 1.0)
        assert other.checks()["travel"]["ok"] == ok
    back = dataclasses.replace(walked, direction_planned=math.pi)
    assert "backwards" in back.direction and back.distance_error < -1.0


def test_every_member_controlled_is_refused() -> None:
    bumpy = Member("bumpy", 0.005, False, 0.8, 0.003, 0, True)
    with pytest.raises(ParameterError, match="at least one replays"):
        simulate_robust(pattern="tripod", duration=0.5, members=(bumpy,))


ERD_QUADRUPEDS = ("a1", "anymal", "b1", "go1", "go2", "hyq", "laikago", "solo12")


@pytest.mark.slow
@pytest.mark.parametrize("name", ERD_QUADRUPEDS)
def test_erd_quadrupeds_walk_their_crawl_over_bumps_under_the_controller(name: str) -> None:
    """Each example-robot-data quadruped's default crawl (10 s), its twist walked under the
    controller over one of the ensemble's ±3 mm floors (the seeds in turn): within 1 % of
    the plan's distance along its direction, heading within 3°, no fall, feet only (every
    replay of these floors failed its slip check: 5.5-25.5 mm in one stance)."""
    k = ERD_QUADRUPEDS.index(name)
    bumpy = [m for m in ENSEMBLE if m.controlled][k % 3]
    rr = simulate_robust(f"erd:{name}", members=(ENSEMBLE[0], bumpy), stand=False)
    walked = rr.runs[1]
    assert isinstance(walked, ControlledRun) and rr.nominal.plan["pattern"]["name"] == "crawl"
    assert abs(walked.distance_error) < 0.01, walked.to_dict()
    assert walked.ok, {c: v for c, v in walked.checks().items() if not v["ok"]}


def test_a_blown_up_walk_is_still_json(mixed) -> None:
    """A controlled walk whose figures are not finite (a robot through the floor) gives JSON
    nulls, not NaN (the CLI's JSON refuses NaN)."""
    import json

    walked = mixed.runs[0]
    nan = dataclasses.replace(
        walked, control=dataclasses.replace(walked.control, heading_error=math.nan)
    )
    assert not nan.checks()["heading"]["ok"]
    rr = dataclasses.replace(mixed, runs=(nan, mixed.runs[1]))
    row = json.loads(json.dumps(rr.to_dict(), allow_nan=False))["members"][0]
    assert row["heading_error"] is None and row["control"]["heading_error"] is None
    assert "heading" in row["failed"]


def test_the_mean_twist_is_the_log_of_the_plans_motion() -> None:
    """The twist held for T that makes (x, y, yaw): against Pinocchio's exponential of SE(3)
    (a body-frame twist held for T), straight, turning, backwards and sideways."""
    pin = pytest.importorskip("pinocchio")
    rng = np.random.default_rng(31)
    twists = [(0.1, 0.0, 0.0), (-0.05, 0.02, 0.0), (0.0, 0.0, 0.4)]
    twists += [tuple(rng.uniform(-0.3, 0.3, 2)) + (rng.uniform(-1.0, 1.0),) for _ in range(20)]
    for twist in twists:
        T = float(rng.uniform(0.5, 10.0))
        v = np.array([twist[0], twist[1], 0.0, 0.0, 0.0, twist[2]]) * T
        M = pin.exp6(pin.Motion(v))
        motion = (M.translation[0], M.translation[1], twist[2] * T)  # the yaw unwrapped
        assert mean_twist(motion, T) == pytest.approx(twist, abs=1e-12)


@pytest.mark.slow
def test_the_command_makes_the_motion_from_rest() -> None:
    """The controller's reference ramps from rest at ACCEL: held for T, a straight command v
    moves v T - v^2 / (2 a) (closed form); the command raised by it makes the plan's motion.
    A turning one against an ODE solution of the same ramped twist."""
    from scipy.integrate import solve_ivp

    from hexapod_kin.control.controller import ACCEL

    a = ACCEL[0]
    for v, T in ((0.3, 4.0), (-0.05, 10.0), (0.004, 3.0)):
        got = ramped_motion((v, 0.0, 0.0), T, ACCEL)
        assert got[0] == pytest.approx(v * T - math.copysign(v * v / (2 * a), v), abs=RAMP_STEP)
        assert got[1] == got[2] == 0.0
    cmd, T = (0.12, -0.03, 0.5), 6.0

    def rhs(t: float, s: np.ndarray) -> list[float]:
        tw = [math.copysign(min(abs(c), acc * t), c) for c, acc in zip(cmd, (a, a, ACCEL[1]))]
        c, sn = math.cos(s[2]), math.sin(s[2])
        return [c * tw[0] - sn * tw[1], sn * tw[0] + c * tw[1], tw[2]]

    ode = solve_ivp(rhs, (0.0, T), [0.0, 0.0, 0.0], rtol=1e-10, atol=1e-12, max_step=0.01)
    assert ramped_motion(cmd, T, ACCEL) == pytest.approx(ode.y[:, -1], abs=3 * RAMP_STEP * 0.12)
    for motion in ((0.6, 0.0, 0.0), (0.5, -0.1, 0.8), (-0.1, -0.06, 0.0)):
        c = plan_command(motion, 10.0)
        assert ramped_motion(c, 10.0, ACCEL) == pytest.approx(motion, abs=1e-12)
        assert np.linalg.norm(c) > np.linalg.norm(mean_twist(motion, 10.0))  # raised


@pytest.mark.slow
def test_a_controlled_member_is_asked_the_plans_displacement() -> None:
    """Mini Pupper's 3 s crawl is 0.41 of its 7.3 s cycle: its body surges and sways by
    +-25 mm, and at 3 s its CoM stands 4.7 mm behind and aside of where it started, while
    its nominal twist held for 3 s asks 16.6 mm forwards. The controller's path (its own
    record) moves by the plan's own displacement of the point the controller tracks (torque
    control: the CoM; the plan's first and last CoM), and the walk is judged against it."""
    data = Path(__file__).parent / "data" / "mini_pupper" / "mini_pupper_description"
    src = data / "urdf" / "mini_pupper" / "mini_pupper_description.urdf.xacro"
    with pytest.warns(UserWarning, match="meshes"):
        rr = simulate_robust(
            str(src), members=(ENSEMBLE[0], ENSEMBLE[8]), duration=3.0, stand=False
        )
    replay, walked = rr.runs
    plan = replay.plan
    cycles = plan["duration"] / plan["period"]
    assert 0.1 < cycles % 1.0 < 0.9  # not a whole number of cycles
    poses, com = np.asarray(replay.planned), np.asarray(replay.run.com)
    d = com[-1, :2] - com[0, :2]  # the plan's start heading is 0
    assert abs(math.atan2(poses[0, 1, 0], poses[0, 0, 0])) < 1e-9
    assert walked.control.kind == "torque"
    nominal = np.asarray(plan["velocity"][:2]) * plan["duration"]
    assert np.linalg.norm(nominal - d) > 0.015  # the nominal twist asks another walk
    c = walked.control
    path = np.asarray(c.path)
    v = float(np.hypot(*d)) / plan["duration"]
    dt = 1.0 / c.settings["rate"]
    # the path's first record is after one tick; the ramp is integrated at RAMP_STEP
    tol = v * max(dt, RAMP_STEP) + 1.0 * dt * dt
    assert path[-1, :2] - path[0, :2] == pytest.approx(d, abs=tol)
    assert path[-1, 2] - path[0, 2] == pytest.approx(0.0, abs=1e-9)
    assert walked.distance_planned == pytest.approx(float(np.hypot(*d)), abs=1e-15)
    assert walked.direction_planned == pytest.approx(math.atan2(d[1], d[0]), abs=1e-12)


def test_a_turning_plan_is_asked_its_arc() -> None:
    """The built-in hexapod's turning tripod (servos: the base is tracked): the controller's
    path ends at the plan's own end pose in its start frame (its first and last planned
    poses, the planned turn), and the walk is judged against that displacement. The ramp's
    shortfall left uncorrected would miss by 1.25 mm and 0.0225 rad."""
    rr = simulate_robust(
        pattern="tripod",
        velocity=(0.05, 0.0, 0.3),
        duration=1.5,
        members=(ENSEMBLE[0], ENSEMBLE[8]),
        stand=False,
    )
    replay, walked = rr.runs
    poses = np.asarray(replay.planned)
    rel = np.linalg.inv(poses[0]) @ poses[-1]  # the plan's end in its start frame
    c = walked.control
    assert c.kind == "servo"
    path = np.asarray(c.path)
    y0 = path[0, 2]
    d = path[-1, :2] - path[0, :2]
    got = [math.cos(y0) * d[0] + math.sin(y0) * d[1], -math.sin(y0) * d[0] + math.cos(y0) * d[1]]
    # the ramp integrated at RAMP_STEP, the controller's at its own tick (100 Hz here); the
    # path's first record is after one tick
    assert got == pytest.approx(rel[:2, 3], abs=2e-4)
    assert path[-1, 2] - y0 == pytest.approx(replay.turn_planned, abs=2e-3)
    assert replay.turn_planned == pytest.approx(math.atan2(rel[1, 0], rel[0, 0]), abs=1e-12)
    assert walked.turn_error is not None and walked.turn_planned == replay.turn_planned
    assert walked.distance_planned == pytest.approx(float(np.hypot(*rel[:2, 3])), abs=1e-12)
