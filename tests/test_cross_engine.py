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
