"""One model shared by 8 threads gives the same numbers as one thread.

Pinocchio writes every result into its ``Data``; a model keeps one ``Data`` per thread. The
thread switch interval is set to 1 µs (as on a busy server) so that threads interleave
between the Pinocchio calls of one ``fk``; each thread's results are compared bit for bit
with the same calls made on one thread beforehand.
"""

from __future__ import annotations

import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
import pytest

import hexapod_kin as hk

N_THREADS = 8


@contextmanager
def _busy_switching() -> Iterator[None]:
    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    try:
        yield
    finally:
        sys.setswitchinterval(old)


def _run_threads(work: Callable[[int], Any]) -> list[Any]:
    """Run ``work(i)`` for i in 0..7 on 8 threads started together; re-raise any error."""
    results: list[Any] = [None] * N_THREADS
    errors: list[BaseException] = []
    barrier = threading.Barrier(N_THREADS)

    def body(i: int) -> None:
        try:
            barrier.wait()
            results[i] = work(i)
        except BaseException as exc:  # noqa: BLE001 - reported below
            errors.append(exc)

    threads = [threading.Thread(target=body, args=(i,)) for i in range(N_THREADS)]
    with _busy_switching():
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    if errors:
        raise errors[0]
    return results


@pytest.fixture(scope="module")
def leg() -> Any:
    return hk.load("hexapod", tip="leg2_foot")  # base != root: exercises the base transform


@pytest.mark.parametrize("source", ["hexabot_leg", "scara"])
def test_fk_and_jacobian_from_8_threads_equal_one_thread(source: str) -> None:
    model = hk.load(source)
    qs = [model.random_q(600, seed=10 + i) for i in range(N_THREADS)]
    expect = [
        (
            np.array([model.fk(q) for q in block]),
            np.array([model.jacobian(q) for q in block]),
            np.array([model.jacobian(q, "world") for q in block]),
        )
        for block in qs
    ]

    def work(i: int) -> tuple[np.ndarray, ...]:
        block = qs[i]
        return (
            np.array([model.fk(q) for q in block]),
            np.array([model.jacobian(q) for q in block]),
            np.array([model.jacobian(q, "world") for q in block]),
        )

    got = _run_threads(work)
    for i in range(N_THREADS):
        for a, b in zip(got[i], expect[i]):
            np.testing.assert_array_equal(a, b)


def test_sub_chain_fk_jacobian_placements_from_threads(leg: Any) -> None:
    qs = [leg.random_q(300, seed=30 + i) for i in range(N_THREADS)]

    def compute(block: np.ndarray) -> tuple[np.ndarray, ...]:
        return (
            np.array([leg.fk(q) for q in block]),
            np.array([leg.jacobian(q, "local_world_aligned") for q in block]),
            np.array([leg.fk_jacobian(q)[1] for q in block]),
            np.array([leg.frame_placements(q)[-1] for q in block[:50]]),
        )

    expect = [compute(b) for b in qs]
    got = _run_threads(lambda i: compute(qs[i]))
    for g, e in zip(got, expect):
        for a, b in zip(g, e):
            np.testing.assert_array_equal(a, b)


def test_each_thread_has_its_own_data() -> None:
    model = hk.load("hexabot_leg")
    ids = _run_threads(lambda i: id(model.data))
    assert len(set(ids)) == N_THREADS and id(model.data) not in ids
    assert model.data.__class__.__name__ == "Data"


def test_ik_solve_from_threads() -> None:
    from hexapod_kin import ik

    model = hk.load("hexabot_leg")
    targets = [model.fk(q)[:3, 3] for q in model.random_q(8 * 40, seed=5)]
    blocks = [targets[i::N_THREADS] for i in range(N_THREADS)]
    expect = [[ik.solve(model, t).q for t in b] for b in blocks]
    got = _run_threads(lambda i: [ik.solve(model, t).q for t in blocks[i]])
    for g, e in zip(got, expect):
        np.testing.assert_array_equal(np.array(g), np.array(e))
    for b, g in zip(blocks, got):  # and they are solutions (independent of threading)
        for t, q in zip(b, g):
            assert np.linalg.norm(model.fk(q)[:3, 3] - t) < 1e-9


def test_singularity_scan_and_measures_batch_from_threads() -> None:
    from hexapod_kin import singularity

    model = hk.load("hexabot_leg")
    qs = [model.random_q(2000, seed=50 + i) for i in range(N_THREADS)]
    expect_m = [singularity.measures_batch(model, q) for q in qs]
    expect_s = singularity.scan(model, grid=15, families=False)

    def work(i: int) -> tuple[Any, Any]:
        return singularity.measures_batch(model, qs[i]), singularity.scan(
            model, grid=15, families=False
        )

    got = _run_threads(work)
    for (m_i, s_i), e_m in zip(got, expect_m):
        for a, b in zip(_as_arrays(m_i), _as_arrays(e_m)):
            np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(np.asarray(s_i.singular), np.asarray(expect_s.singular))
        np.testing.assert_array_equal(np.asarray(s_i.q), np.asarray(expect_s.q))


def _as_arrays(result: Any) -> list[np.ndarray]:
    """The arrays of a measures_batch result (a tuple today, a dataclass soon)."""
    if isinstance(result, tuple):
        return [np.asarray(a) for a in result]
    if hasattr(result, "to_dict"):
        return [np.asarray(v) for v in vars(result).values() if isinstance(v, np.ndarray)]
    return [np.asarray(result)]


def test_data_stays_paired_with_model() -> None:
    from hexapod_kin.exceptions import ParameterError

    model = hk.load("hexabot_leg")
    with pytest.raises(ParameterError, match="read-only"):
        model.data = model.model.createData()
    with pytest.raises(ParameterError, match="read-only"):
        model.model = model.full_model


def test_batch_calls_from_threads() -> None:
    model = hk.load("erd:ur5_robot")
    qs = [model.random_q(3000, seed=70 + i) for i in range(N_THREADS)]
    expect = [(model.fk_batch(q), model.jacobian_batch(q, "world")) for q in qs]
    got = _run_threads(lambda i: (model.fk_batch(qs[i]), model.jacobian_batch(qs[i], "world")))
    for g, e in zip(got, expect):
        np.testing.assert_array_equal(g[0], e[0])
        np.testing.assert_array_equal(g[1], e[1])
