"""``-s NAME=VALUE`` from the command line: list values (comma-separated numbers), errors."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from hexapod_kin.cli import main

YAWS = "45,90,135,-135,-90,-45"


def _run(capsys, argv):
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("leg,yaw", [(1, 45.0), (3, 135.0), (5, -90.0)])
def test_list_value_sets_the_mount_yaws(capsys, leg, yaw):
    code, out, _ = _run(
        capsys,
        ["fk", "hexapod", "-s", f"mount_yaw_deg={YAWS}", "--tip", f"leg{leg}_foot", "--json"],
    )
    assert code == 0
    foot = np.array(json.loads(out)["T_tip"])[:3, 3]
    # hand calculation: at q = 0 the leg is stretched radially, body_radius + l1 + l2 + l3
    reach = 0.12 + 0.05 + 0.10 + 0.10
    expected = [reach * math.cos(math.radians(yaw)), reach * math.sin(math.radians(yaw)), 0.0]
    np.testing.assert_allclose(foot, expected, rtol=0, atol=1e-12)


def test_list_value_sets_the_leg_count(capsys):
    code, out, _ = _run(capsys, ["urdf", "hexapod", "-s", "mount_yaw_deg=0,90,180,-90"])
    assert code == 0
    assert 'name="leg4_hip"' in out and 'name="leg5_hip"' not in out
    code, out, _ = _run(capsys, ["urdf", "hexapod", "-s", "mount_yaw_deg=30,"])  # one item
    assert code == 0 and 'name="leg1_hip"' in out and 'name="leg2_hip"' not in out


@pytest.mark.parametrize(
    "value,words",
    [
        ("mount_yaw_deg=45,x,90", ["mount_yaw_deg", "item 2", "'x'"]),
        ("mount_yaw_deg=45,,90", ["mount_yaw_deg", "item 2"]),
        ("mount_yaw_deg=45,nan", ["mount_yaw_deg", "item 2", "finite"]),
        ("l1=0.05,0.06", ["'l1'", "one number", "list of 2"]),
        ("l1=[0.05, 0.06]", ["'l1'", "one number"]),
    ],
)
def test_bad_list_values_are_one_line_exit_2(capsys, value, words):
    code, out, err = _run(capsys, ["fk", "hexapod", "-s", value, "--tip", "leg1_foot"])
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith("hexapod-kin: error:")
    for w in words:
        assert w in err
