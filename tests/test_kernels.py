"""Compiled batch kernels against Pinocchio, for every catalogue chain and a URDF leg."""

from __future__ import annotations

import numpy as np
import pytest

import hexapod_kin as hk
from hexapod_kin import _kernels as K
from hexapod_kin.exceptions import ConfigurationError

SOURCES = [("hexabot_leg", {}), ("coxa_tibia_leg", {}), ("scara", {}), ("pendulum", {}),
           ("hexapod", {"tip": "leg5_foot"}), ("erd:solo12", {"tip": "HR_FOOT"})]


@pytest.mark.parametrize("source,kw", SOURCES)
def test_batch_kernels_equal_pinocchio(source, kw):
    model = hk.load(source, **kw)
    arrays = K.ChainArrays.from_model(model)
    qs = model.random_q(300, seed=3)
    pos = K.fk_batch(arrays, qs)
    jac = K.jacobian_batch(arrays, qs)
    for i, q in enumerate(qs):
        np.testing.assert_allclose(pos[i], model.fk(q)[:3, 3], atol=1e-12)
        np.testing.assert_allclose(jac[i], model.jacobian(q), atol=1e-12)
    np.testing.assert_allclose(K.position_jacobian(arrays, qs[0]), model.position_jacobian(qs[0]),
                               atol=1e-12)
    np.testing.assert_allclose(K.fk_position(arrays, qs[0]), model.position(qs[0]), atol=1e-12)
    np.testing.assert_allclose(K.position_jacobian_batch(arrays, qs[:5]), jac[:5, :3])


def test_whole_hexapod_kernel_has_zero_columns_for_other_legs():
    model = hk.load("hexapod")
    arrays = K.ChainArrays.from_model(model, frame="leg2_foot")
    q = model.random_q(seed=1)
    jac = K.jacobian_batch(arrays, q[None])[0]
    np.testing.assert_allclose(jac, model.jacobian(q, frame="leg2_foot"), atol=1e-12)
    assert np.all(jac[:, :3] == 0) and np.all(jac[:, 6:] == 0)


def test_kernel_input_checks():
    arrays = K.ChainArrays.from_model(hk.load("hexabot_leg"))
    with pytest.raises(ConfigurationError, match=r"\(N, 3\)"):
        K.fk_batch(arrays, np.zeros((4, 2)))
    with pytest.raises(ConfigurationError, match="non-finite"):
        K.jacobian_batch(arrays, np.full((2, 3), np.nan))
    assert not arrays.rot.flags.writeable
