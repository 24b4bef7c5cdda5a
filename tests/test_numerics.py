"""The small maths (numpy :mod:`_numerics`, compiled :mod:`_kernels`) vs numpy/LAPACK."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hexapod_kin import _kernels as K
from hexapod_kin import _numerics as N

RNG = np.random.default_rng(7)


def _sym(n: int) -> np.ndarray:
    a = RNG.normal(size=(n, n))
    return a @ a.T


def test_eig3_sym_equals_lapack_including_diagonal_and_degenerate() -> None:
    mats = [_sym(3) for _ in range(200)]
    mats += [np.diag([3.0, -1.0, 2.0]), np.eye(3) * 2.5, np.diag([1.0, 1.0, 0.0])]
    for g in mats:
        got = K.eig3_sym(g[0, 0], g[1, 1], g[2, 2], g[0, 1], g[0, 2], g[1, 2])
        ref = np.sort(np.linalg.eigvalsh(g))[::-1]
        assert np.allclose(got, ref, atol=1e-12 * max(1.0, abs(ref).max()))


def test_solve_spd_and_non_spd() -> None:
    a = _sym(5) + 0.1 * np.eye(5)
    b = RNG.normal(size=5)
    out = np.empty(5)
    assert K.solve_spd(a.copy(), b, out, len(b))
    assert np.allclose(a @ out, b, atol=1e-10)
    assert not K.solve_spd(-np.eye(2), np.ones(2), np.empty(2), 2)


@pytest.mark.parametrize("shape", [(3, 2), (3, 3), (3, 7), (6, 6), (6, 7), (2, 5)])
def test_dls_step_is_the_damped_least_squares_solution(shape: tuple[int, int]) -> None:
    m, n = shape
    j = RNG.normal(size=shape)
    e = RNG.normal(size=m)
    lam2 = 0.03
    # the minimiser of ‖J dq − e‖² + λ²‖dq‖², from the stacked least-squares problem
    stacked = np.vstack([j, math.sqrt(lam2) * np.eye(n)])
    ref = np.linalg.lstsq(stacked, np.concatenate([e, np.zeros(n)]), rcond=None)[0]
    assert np.allclose(N.dls_step(j, e, lam2), ref, atol=1e-10)
    free = np.arange(n) != 1  # a frozen joint gets no step; the others solve without it
    dq = N.dls_step(j, e, lam2, free)
    assert dq[1] == 0.0
    ref = np.linalg.lstsq(stacked[:, free], np.concatenate([e, np.zeros(n)]), rcond=None)[0]
    assert np.allclose(dq[free], ref, atol=1e-12)


def test_wrapping() -> None:
    a = np.array([-7.0, -math.pi, 0.0, math.pi, 3.5, 100.0, 1e4])
    w = N.wrap_angles(a)
    assert np.all(w > -math.pi) and np.all(w <= math.pi)
    assert np.allclose(np.sin(w), np.sin(a)) and np.allclose(np.cos(w), np.cos(a))
    assert w[1] == math.pi
    for x in a:
        assert K.wrap_angle(float(x)) == pytest.approx(w[list(a).index(x)], abs=1e-9)


def test_chain_scale_one_formula() -> None:
    t = np.array([[0.1, 0.0, 0.0], [0.0, 0.3, 0.4], [0.0, 0.0, 0.0]])
    assert N.chain_length(t) == pytest.approx(0.6)
    assert N.chain_scale(t) == pytest.approx(0.6)
    assert N.chain_scale(np.zeros((2, 3))) == 1.0


def test_rpy_to_matrix_is_rz_ry_rx() -> None:
    from hexapod_kin.params import rpy_to_matrix  # the one home (pure numpy)

    def rot(axis: int, a: float) -> np.ndarray:
        c, s = math.cos(a), math.sin(a)
        i, j = [(1, 2), (2, 0), (0, 1)][axis]
        r = np.eye(3)
        r[i, i] = r[j, j] = c
        r[i, j], r[j, i] = -s, s
        return r

    for _ in range(20):
        r, p, y = RNG.uniform(-3, 3, size=3)
        ref = rot(2, y) @ rot(1, p) @ rot(0, r)
        assert np.allclose(rpy_to_matrix(r, p, y), ref, atol=1e-15)


def test_rotation_angle_equals_pinocchio_log3():
    """‖log(R_a R_bᵀ)‖ at random, tiny and near-π angles, against Pinocchio's log3."""
    import pinocchio as pin

    from hexapod_kin._pose import rotation_angle

    rng = np.random.default_rng(5)
    ra, rb = [], []
    for angle in np.concatenate([rng.uniform(0, np.pi, 40), [1e-15, 3e-9, 1e-5, np.pi - 1e-7]]):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        base = pin.exp3(rng.normal(size=3))
        rb.append(base)
        ra.append(pin.exp3(angle * axis) @ base)
    got = rotation_angle(np.array(ra), np.array(rb))
    ref = np.array([np.linalg.norm(pin.log3(a @ b.T)) for a, b in zip(ra, rb)])
    assert np.allclose(got, ref, rtol=1e-9, atol=1e-15)
    assert got[-4] < 1e-14 and abs(got[-3] - 3e-9) < 1e-16  # tiny angles keep their digits


def test_numerics_never_imports_numba() -> None:
    import subprocess
    import sys

    code = "import sys, hexapod_kin._numerics; assert 'numba' not in sys.modules"
    subprocess.run([sys.executable, "-c", code], check=True)


@pytest.mark.parametrize("shape", [(3, 2), (3, 3), (6, 7), (2, 5)])
def test_compiled_dls_into_is_the_damped_least_squares_solution(shape: tuple[int, int]) -> None:
    m, n = shape
    j = RNG.normal(size=shape)
    e = RNG.normal(size=m)
    lam2 = 0.03
    free = np.arange(n) != 1
    big = max(m, n)
    dq = np.empty(n)
    assert K.dls_into(j, e, m, lam2, free, dq, np.empty((big, big)), np.empty(big), np.empty(big))
    stacked = np.vstack([j[:, free], math.sqrt(lam2) * np.eye(n)[:, free]])
    ref = np.linalg.lstsq(stacked, np.concatenate([e, np.zeros(n)]), rcond=None)[0]
    assert dq[1] == 0.0
    assert np.allclose(dq[free], ref, atol=1e-12)


def test_the_step_per_call_is_the_compiled_step() -> None:
    """dls_step3 (Python floats) is dls_into's arithmetic: the same bits; dls_step to rounding."""
    rng = np.random.default_rng(11)
    free = np.ones(3, dtype=bool)
    for _ in range(200):
        j, e, lam2 = rng.normal(size=(3, 3)), rng.normal(size=3), 10.0 ** rng.uniform(-12, -1)
        dq = np.empty(3)
        assert K.dls_into(j, e, 3, lam2, free, dq, np.empty((3, 3)), np.empty(3), np.empty(3))
        assert N.dls_step3(j.tolist(), e.tolist(), lam2) == dq.tolist()
        cond = np.linalg.cond(j.T @ j + lam2 * np.eye(3))
        assert np.allclose(N.dls_step(j, e, lam2), dq, rtol=0, atol=1e-14 * cond * np.abs(dq).max())
    stack = rng.normal(size=(5, 4, 3))
    errs = rng.normal(size=(5, 4))
    one_by_one = [N.dls_step(a, b, 0.01) for a, b in zip(stack, errs)]
    np.testing.assert_allclose(N.dls_step(stack, errs, 0.01), one_by_one, atol=1e-13)
