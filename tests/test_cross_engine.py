"""Second engine: yourdfpy's FK of the very same URDF text agrees with Pinocchio."""

from __future__ import annotations

import numpy as np
import pytest

from hexapod_kin import robots


@pytest.mark.parametrize("name", robots.names())
def test_yourdfpy_agrees_with_pinocchio(name, preset_models):
    model = preset_models[name]
    urdf = model.yourdfpy()
    frames = [model.tip]
    if name == "hexapod":
        frames = list(model.params.foot_frames)
    rng = np.random.default_rng(11)
    for q in rng.uniform(model.lower, model.upper, (200, model.nq)):
        urdf.update_cfg(dict(zip(model.joint_names, q)))
        for frame in frames:
            ref = urdf.get_transform(frame_to=frame, frame_from=model.base)
            np.testing.assert_allclose(model.placement(q, frame), ref, atol=1e-9)


def test_yourdfpy_on_solo12_leg():
    import hexapod_kin as hk

    model = hk.load("erd:solo12", tip="FL_FOOT")
    urdf = model.yourdfpy()
    for q in np.random.default_rng(12).uniform(-2, 2, (50, 3)):
        urdf.update_cfg(dict(zip(model.joint_names, q)))
        ref = urdf.get_transform(frame_to="FL_FOOT", frame_from="base_link")
        np.testing.assert_allclose(model.fk(q), ref, atol=1e-9)


@pytest.mark.parametrize("file", ["leg4.toml", "leg_prismatic.yaml", "puma560.toml", "ur5.toml"])
def test_yourdfpy_agrees_on_table_files_and_batches(file):
    """Table-file robots (with a tool) and the compiled batch calls, against yourdfpy."""
    from pathlib import Path

    import hexapod_kin as hk

    model = hk.load(Path(__file__).resolve().parent.parent / "examples" / file)
    urdf = model.yourdfpy()
    qs = model.random_q(100, seed=13)
    poses = model.fk_batch(qs)
    for q, pose in zip(qs, poses):
        urdf.update_cfg(dict(zip(model.joint_names, q)))
        ref = urdf.get_transform(frame_to=model.tip, frame_from=model.base)
        np.testing.assert_allclose(pose, ref, atol=1e-9)


def test_yourdfpy_agrees_on_a_continuous_joint_robot():
    import hexapod_kin as hk
    from hexapod_kin.sources import erd_path

    model = hk.load(erd_path("double_pendulum_continuous"))
    urdf = model.yourdfpy()
    for q in model.random_q(50, seed=14):
        urdf.update_cfg(dict(zip(model.joint_names, q)))
        ref = urdf.get_transform(frame_to=model.tip, frame_from=model.base)
        np.testing.assert_allclose(model.fk(q), ref, atol=1e-9)
