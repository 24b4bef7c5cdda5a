"""What the figures draw: thinned line data keeps every extreme, crop choices keep the format."""

from __future__ import annotations

import numpy as np
import pytest

from hexapod_kin.plots import decimate


def test_short_series_pass_unchanged():
    x = np.arange(100.0)
    y = np.sin(x)
    dx, dy = decimate(x, y, max_points=200)
    assert dx is x or np.array_equal(dx, x)
    assert np.array_equal(dy, y)


@pytest.mark.parametrize("n", [10_001, 20_001, 99_999])
def test_every_bucket_keeps_its_extremes(n):
    rng = np.random.default_rng(n)
    x = np.linspace(0.0, 10.0, n)
    y = np.sin(3 * x) + 1e-3 * rng.standard_normal(n)
    y[rng.integers(0, n, 5)] = [5.0, -4.0, 3.0, 1e-12, np.nan]  # spikes, a tiny value, a gap
    dx, dy = decimate(x, y, max_points=3000)
    assert dx.shape == dy.shape and dx.shape[0] <= 3000 + 3
    assert np.all(np.diff(dx) > 0)  # the kept samples in their order, none twice
    kept = set(np.searchsorted(x, dx).tolist())
    assert {0, n - 1} <= kept
    # brute force: the smallest and largest sample of every bucket of the same size is kept
    b = -(-n // 1500)
    for start in range(0, n // b * b, b):
        block = y[start : start + b]
        assert start + int(np.argmax(block)) in kept
        assert start + int(np.argmin(block)) in kept
    assert np.nanmax(dy) == np.nanmax(y) and np.nanmin(dy) == np.nanmin(y)
    assert np.isnan(dy).any()  # the gap stays a gap
    tail = y[n // b * b :]
    if tail.size:
        assert (
            n // b * b + int(np.argmax(tail)) in kept and n // b * b + int(np.argmin(tail)) in kept
        )
