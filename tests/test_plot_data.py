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


# ---------------------------------------------------------------- limits, legends, units
def test_fit_limits_keep_the_data_and_a_margin_only():
    from hexapod_kin.plots import fit_limits, pyplot

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(11, 4))  # a wide panel: datalim would widen x
    x = np.array([-0.25, 0.6, 0.1])
    y = np.array([-0.3, 0.28, 0.0])
    ax.plot(x, y)
    fit_limits(ax, x, y, margin=0.05)
    fig.canvas.draw()
    pad = 0.05 * 0.85  # 5 % of the larger span (x: 0.85 m)
    assert np.allclose(ax.get_xlim(), (-0.25 - pad, 0.6 + pad))
    assert np.allclose(ax.get_ylim(), (-0.3 - pad, 0.28 + pad))
    # one scale on both axes: the box, not the limits, took the aspect
    bb = ax.get_window_extent()
    sx = bb.width / np.ptp(ax.get_xlim())
    sy = bb.height / np.ptp(ax.get_ylim())
    assert abs(sx - sy) / sx < 0.02
    plt.close(fig)


@pytest.fixture
def captured(monkeypatch):
    """The figures the report draws, kept open instead of written."""
    from hexapod_kin import plots

    figs = []

    def keep(fig, path, dpi=120, *, crop=True):
        figs.append(fig)
        return path

    monkeypatch.setattr(plots, "save_figure", keep)
    yield figs
    for f in figs:
        plots.pyplot().close(f)


def _overlap(a, b) -> bool:
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


def test_leg2_figure_legends_beside_the_curves_and_no_metres(captured, tmp_path):
    from hexapod_kin.report import figures
    from hexapod_kin.report.checks import Context

    figures.leg2_figure(Context(quick=True, claims=None), tmp_path)
    (fig,) = captured
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        leg = ax.get_legend()
        assert leg is not None
        assert not _overlap(leg.get_window_extent(renderer), ax.get_window_extent(renderer))
    # seed 002 gives l1 = 10, l2 = 5 without a unit: Fig. 12 must not say metres
    assert "[m]" not in fig.axes[1].get_ylabel() and "unit" in fig.axes[1].get_ylabel()


def test_walk_foot_paths_fitted_to_the_data(captured, tmp_path):
    from hexapod_kin.gait import walk
    from hexapod_kin.report import figures

    run = walk(duration=1.5)
    figures._walk_png(run, tmp_path / "walk.png")
    (fig,) = captured
    ax = fig.axes[2]
    xs = np.concatenate([run.feet[..., 0].ravel(), run.base_poses[:, 0, 3], run.com[:, 0]])
    ys = np.concatenate([run.feet[..., 1].ravel(), run.base_poses[:, 1, 3], run.com[:, 1]])
    span = max(np.ptp(xs), np.ptp(ys))
    for (lo, hi), v in ((ax.get_xlim(), xs), (ax.get_ylim(), ys)):
        assert lo <= v.min() and hi >= v.max()  # every point drawn is inside
        assert v.min() - lo <= 0.1 * span and hi - v.max() <= 0.1 * span  # and no more than 10 %
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    assert not _overlap(ax.get_legend().get_window_extent(r), ax.get_window_extent(r))
