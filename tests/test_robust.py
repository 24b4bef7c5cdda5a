"""``simulate --robust``: the bumpy members walk under the closed-loop controller (issue 31).

Independent references: the closed loop's own recorded body positions and the plan's
planned body poses (the travel along the plan recomputed from them), the controller's own
settings (what it was asked to walk on), the ensemble's definition.
"""

from __future__ import annotations

import dataclasses
import math

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


def test_a_controlled_member_walks_the_plans_twist_on_its_bumps(mixed) -> None:
    walked, replay = mixed.runs
    assert isinstance(walked, ControlledRun) and isinstance(replay, SimRun)
    assert mixed.nominal is replay and mixed.worst_replay is replay
    c = walked.control
    m = mixed.members[0]
    assert (c.settings["bumps"], c.settings["seed"], c.settings["friction"]) == (0.003, 1, 0.8)
    assert c.pattern == replay.plan["pattern"]["name"] == "tripod"
    cmd = c.settings["commands"][0]
    assert (cmd["vx"], cmd["vy"], cmd["wz"]) == tuple(replay.plan["velocity"])
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
