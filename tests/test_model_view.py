"""``Model.view``: a chain of a loaded robot, built from its parse (issue 30, "one model").

A view must be the model ``load(source, base=, tip=)`` gives (Pinocchio's FK and the recovered
Khalil table compared number for number), without running the loader gate or Pinocchio's
parser again; the gait's legs use views for their closed forms.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import hexapod_kin as hk
from hexapod_kin import model as model_module
from hexapod_kin._fromurdf import chain_from_urdf


@pytest.mark.parametrize("source", ["erd:solo12", "hexapod"])
def test_a_view_is_the_chain_load_gives_without_a_second_parse(source, monkeypatch):
    robot = hk.load(source)
    tip = "FL_FOOT" if source == "erd:solo12" else robot.params.foot_frames[1]
    ref = hk.load(source, tip=tip)
    calls: list[str] = []
    gate = model_module.check_urdf

    def counted(*args, **kwargs):
        calls.append("gate")
        return gate(*args, **kwargs)

    monkeypatch.setattr(model_module, "check_urdf", counted)
    view = robot.view(tip=tip)
    assert calls == [] and view is robot.view(tip=tip)  # no gate run; cached on the robot
    assert view.full_model is robot.full_model and view.urdf == robot.urdf
    assert (view.base, view.tip, view.joint_names) == (ref.base, ref.tip, ref.joint_names)
    assert view.locked_joints == ref.locked_joints and view.nq < robot.full_model.nv
    for q in ref.random_q(25, seed=3):
        assert np.array_equal(view.fk(q), ref.fk(q))
        assert np.array_equal(view.jacobian(q), ref.jacobian(q))
    a, b = chain_from_urdf(view), chain_from_urdf(ref)
    assert a.rows == b.rows and np.array_equal(a.tool_matrix, b.tool_matrix)
    assert dataclasses.replace(a, description="") == dataclasses.replace(b, description="")


def test_the_gait_legs_closed_forms_come_from_views_of_the_loaded_robot(monkeypatch):
    from hexapod_kin.gait import as_whole_body

    robot = hk.load("erd:solo12")
    calls: list[str] = []
    gate = model_module.check_urdf
    monkeypatch.setattr(
        model_module, "check_urdf", lambda *a, **k: calls.append("gate") or gate(*a, **k)
    )
    wb = as_whole_body(robot)
    assert calls == [] and wb.ik_kind == ("closed",) * 4  # four tables, no second parse
    for closed in wb._closed:  # recovered from the robot as loaded, not from URDF text
        assert closed is not None and f"'{robot.name}'" in closed[0].description
