"""Pictures of a walk (matplotlib, imported lazily through :mod:`hexapod_kin.plots`).

:func:`plot_gait` writes one PNG with three panels: the gait diagram (stance bars per leg over
time), the static stability margin over time, and the foot paths seen from above (with the
body's path and the projected centre of mass).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["draw_foot_paths", "draw_gait_diagram", "draw_margin", "plot_gait"]


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Index ranges [start, stop) where ``mask`` is True."""
    m = np.concatenate(([False], np.asarray(mask, dtype=bool), [False]))
    edges = np.flatnonzero(np.diff(m.astype(np.int8)))
    return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2])]


def draw_gait_diagram(ax: Any, run: Any) -> None:
    """Stance (dark bars) and swing (gaps) of each leg over time on ``ax``."""
    t = run.t
    dt = float(t[1] - t[0]) if len(t) > 1 else 1.0
    for k in range(len(run.leg_names)):
        bars = [(t[a], t[b - 1] - t[a] + dt) for a, b in _runs(run.support[:, k])]
        ax.broken_barh(bars, (k - 0.4, 0.8), facecolors="0.25")
    ax.set_yticks(range(len(run.leg_names)), list(run.leg_names))
    ax.invert_yaxis()
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("time [s]")
    ax.set_title(f"gait diagram: {run.table.name} (dark = stance, β = {run.table.duty_factor:.3g})")


def draw_margin(ax: Any, run: Any) -> None:
    """Static stability margin over time on ``ax`` (mm)."""
    ax.plot(run.t, 1e3 * run.margin, lw=1.2)
    ax.axhline(0.0, color="crimson", lw=0.8)
    ax.set_xlim(run.t[0], run.t[-1])
    ax.set_xlabel("time [s]")
    ax.set_ylabel("margin [mm]")
    ax.set_title(f"static stability margin (min {1e3 * run.min_margin:.1f} mm)")


def draw_foot_paths(ax: Any, run: Any) -> None:
    """Feet, body and projected centre of mass seen from above on ``ax`` (x, y in m)."""
    for k, name in enumerate(run.leg_names):
        ax.plot(run.feet[:, k, 0], run.feet[:, k, 1], lw=0.9, label=name)
        st = run.support[:, k]
        ax.plot(run.feet[st, k, 0], run.feet[st, k, 1], ".", ms=2, color="0.2")
    ax.plot(run.base_poses[:, 0, 3], run.base_poses[:, 1, 3], "k--", lw=0.8, label="body")
    ax.plot(run.com[:, 0], run.com[:, 1], color="crimson", lw=0.8, label="CoM")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("foot paths from above (dots: stance)")
    ax.legend(fontsize=7, ncol=4, loc="best")


def plot_gait(run: Any, path: str | os.PathLike[str], title: str | None = None) -> Path:
    """Write the gait diagram, the margin over time and the foot paths to one PNG.

    Args:
        run: A :class:`~hexapod_kin.gait.walk.GaitRun`.
        path: Destination ``.png`` (written atomically).
        title: Figure title (default: pattern, terrain and the check figures).

    Returns:
        The path written.

    Raises:
        OptionalDependencyError: matplotlib is missing.

    """
    from ..plots import pyplot, save_figure

    plt = pyplot()
    fig = plt.figure(figsize=(11, 8))
    grid = fig.add_gridspec(2, 2, height_ratios=(1, 1.4))
    draw_gait_diagram(fig.add_subplot(grid[0, 0]), run)
    draw_margin(fig.add_subplot(grid[0, 1]), run)
    draw_foot_paths(fig.add_subplot(grid[1, :]), run)
    fig.suptitle(
        title
        or (
            f"{run.table.name} gait on {run.settings.get('terrain', '?')} terrain: "
            f"min margin {1e3 * run.min_margin:.1f} mm, max slip {run.max_slip:.1e} m, "
            f"min joint-limit margin {run.min_limit_margin:.3f} rad"
        )
    )
    fig.tight_layout()
    return save_figure(fig, path, crop=False)
