"""Matplotlib figures (PNG). Imported lazily; never imported by the core.

Every function takes computed results (no model building here), returns the written
:class:`~pathlib.Path`, and writes the PNG atomically. Sections: singularity pictures
(heat maps, workspace) and motion pictures (foot/joint time series).
"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Any

from ._io import atomic_write
from .exceptions import OptionalDependencyError

__all__ = ["plot_motion", "plot_step", "pyplot", "save_figure"]


def pyplot() -> Any:
    """Return ``matplotlib.pyplot`` with the non-interactive Agg backend.

    Raises:
        OptionalDependencyError: If matplotlib is missing (says what to install).
    """
    try:
        import matplotlib
    except ImportError:
        raise OptionalDependencyError(
            "plots need matplotlib: pip install 'hexapod-kin[plots]'"
        ) from None
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig: Any, path: str | os.PathLike[str], dpi: int = 120) -> Path:
    """Render ``fig`` to PNG in memory, write it atomically, close it; return the path."""
    plt = pyplot()
    buf = io.BytesIO()
    try:
        fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    finally:
        plt.close(fig)
    return atomic_write(path, buf.getvalue())


# ---------------------------------------------------------------- singularity pictures


# ---------------------------------------------------------------- motion pictures
def plot_motion(
    run: Any, path: str | os.PathLike[str], title: str | None = None
) -> Path:
    """The seeds' figures of a resolved-rate run, in one PNG (2×2 panels).

    Panels: foot position vs time (x, y, z); commanded vs actual foot velocity; joint angles
    vs time; deviation from the reference path (|y − y0|, |z − z0|, |x − x_ref|, log scale),
    with the plain Euler baseline when the run has one.

    Args:
        run: A :class:`~hexapod_kin.motion.SeedRun` or a
            :class:`~hexapod_kin.motion.Trajectory`.
        path: Destination PNG (written atomically).
        title: Figure title.

    Returns:
        The path written.
    """
    import numpy as np

    plt = pyplot()
    tr = getattr(run, "trajectory", run)
    t = tr.t
    fig, axes = plt.subplots(2, 2, figsize=(12, 8), sharex=True)
    ax = axes[0, 0]
    for k, name in enumerate("xyz"):
        ax.plot(t, tr.foot[:, k], label=name)
    ax.set_ylabel("foot position [m]")
    ax.set_title("foot position (base frame)")
    ax.legend(loc="center right")
    ax.grid(True, alpha=0.3)
    ax = axes[0, 1]
    for k, name in enumerate("xyz"):
        (line,) = ax.plot(t, tr.foot_velocity[:, k], label=f"actual v{name}")
        ax.plot(t, tr.command[:, k], "--", color=line.get_color(), alpha=0.8,
                label=f"commanded v{name}")
    ax.set_ylabel("foot velocity [m/s]")
    ax.set_title("commanded vs actual foot velocity")
    ax.legend(loc="best", fontsize=8, ncol=2)
    ax.grid(True, alpha=0.3)
    ax = axes[1, 0]
    for j in range(tr.q.shape[1]):
        ax.plot(t, tr.q[:, j], label=f"q{j + 1}")
    ax.set_ylabel("joint value [rad]")
    ax.set_xlabel("t [s]")
    ax.set_title("joint angles")
    ax.legend(loc="best")
    ax.grid(True, alpha=0.3)
    ax = axes[1, 1]
    dev = np.abs(tr.foot - tr.reference)
    floor = 1e-18
    for k, name in enumerate("xyz"):
        ax.semilogy(t, np.maximum(dev[:, k], floor), label=f"|{name} − {name}_ref| {tr.method}")
    base_dev = getattr(run, "baseline_deviation", None)
    if base_dev is not None:
        ax.semilogy(t, np.maximum(base_dev[:, 2], floor), "k:", label="|z − z0| Euler + solve")
        ax.semilogy(t, np.maximum(base_dev[:, 0], floor), "k--", lw=0.8,
                    label="|x − x_ref| Euler + solve")
    ax.set_ylabel("deviation from the reference path [m]")
    ax.set_xlabel("t [s]")
    ax.set_title("drift")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    if title is None:
        title = f"resolved-rate run: {tr.method}, dt = {tr.dt:g} s, gain {tr.gain:g} 1/s"
        drift = getattr(run, "drift_z", None)
        if drift is not None:
            title += (f" — drift y {run.drift_y:.1e} m, z {run.drift_z:.1e} m, "
                      f"x error {run.error_x:.1e} m")
    fig.suptitle(title)
    fig.tight_layout()
    return save_figure(fig, path)


def plot_step(step: Any, path: str | os.PathLike[str], title: str | None = None) -> Path:
    """A foot step: the path seen from the side (along travel vs height) and the joints vs time.

    Args:
        step: A :class:`~hexapod_kin.motion.FootStep`.
        path: Destination PNG.
        title: Figure title.

    Returns:
        The path written.
    """
    import numpy as np

    plt = pyplot()
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.5))
    foot, act = step.foot, step.foot_actual
    st = np.asarray(step.stance)
    a1.plot(foot[:, 0], foot[:, 2], "-", color="0.7", lw=4, label="planned")
    a1.plot(act[st, 0], act[st, 2], ".", ms=3, label="stance (FK of IK)")
    a1.plot(act[~st, 0], act[~st, 2], ".", ms=3, label="swing (FK of IK)")
    a1.set_xlabel("x [m]")
    a1.set_ylabel("z [m]")
    a1.set_aspect("equal", adjustable="datalim")
    a1.set_title("foot path (side view)")
    a1.legend(loc="best", fontsize=8)
    a1.grid(True, alpha=0.3)
    for j in range(step.q.shape[1]):
        a2.plot(step.t, step.q[:, j], label=f"q{j + 1}")
    a2.set_xlabel("t [s]")
    a2.set_ylabel("joint value [rad]")
    a2.set_title("joint trajectories by IK")
    a2.legend(loc="best")
    a2.grid(True, alpha=0.3)
    fig.suptitle(title or f"foot step: max IK error {step.max_error:.1e} m")
    fig.tight_layout()
    return save_figure(fig, path)
