"""The report's figures and animations, drawn like the seeds' (same quantities, same axes).

Each function writes one PNG (or HTML animation) into the report folder and returns its path.
Each animation has a still frame (:func:`step_still`, the walk's in :func:`walk_figures`): the
same scene drawn by matplotlib, shown by the page where the browser has no WebGL.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["heat_maps", "leg2_figure", "plot_pendulum", "step_still", "walk_figures"]


def heat_maps(ctx: Any, out: Path, grid: int) -> tuple[list[Path], dict[str, Any]]:
    """Det J / σ_min over (knee, ankle) for the leg and (θ1, θ2) for the SCARA, with families."""
    from ..plots import plot_singularity_map
    from ..singularity import scan

    paths, counts = [], {}
    for key, name, joints in (
        ("leg", "hexabot_leg", ["knee", "ankle"]),
        ("scara", "scara", ["theta1", "theta2"]),
    ):
        res = scan(ctx.model(key), grid=grid, joints=joints, families=True)
        counts[name] = dict(res.family_counts)
        title = f"{name}: singularity map, families of det J"
        paths.append(plot_singularity_map(res, out / f"singularity_{name}.png", title=title))
    return paths, counts


def step_still(ctx: Any, out: Path) -> tuple[Path, str]:
    """The step animation's scene with the foot farthest along x: the PNG and ``"t = … s, …"``."""
    from ..plots import plot_still

    tr = ctx.step.trajectory
    k = int(np.argmax(tr.foot[:, 0]))
    mdl = ctx.model("leg")
    chain = np.array([T[:3, 3] for T in mdl.frame_placements(tr.q[k])])
    start = np.array([T[:3, 3] for T in mdl.frame_placements(tr.q[0])])
    when = f"t = {tr.t[k]:.2f} s, foot farthest along x"
    path = plot_still(
        [chain],
        out / "step_still.png",
        title=f"hexabot_leg, the seeds' x-only step: still frame at {when}\n"
        "(light grey: the leg at t = 0; grey line: the foot's path over the run)",
        traces=[tr.foot],
        ghosts=[start],
        view=(18.0, -75.0),
    )
    return path, when


def leg2_figure(ctx: Any, out: Path) -> Path:
    """Seed 002 Figs. 11-13: planned joint input, foot position, IK output (ours, the seed's)."""
    from ..plots import decimate, pyplot, save_figure

    plt = pyplot()
    s = ctx.schedule
    t = s["t"]
    margins = {"left": 0.08, "right": 0.78, "bottom": 0.065, "top": 0.96, "hspace": 0.171}
    fig, axes = plt.subplots(3, 1, figsize=(9.5, 9), sharex=True, gridspec_kw=margins)
    for k, lab in enumerate(("θ1 (coxa)", "θ2 (tibia)")):
        axes[0].plot(*decimate(t, np.degrees(s["q"][:, k])), label=lab)
    axes[0].set(ylabel="input angle [deg]", title="Fig. 11: planned input (Table I)")
    for k, lab in enumerate("xyz"):
        axes[1].plot(*decimate(t, s["feet"][:, k]), label=lab)
    axes[1].set_ylabel("foot position [unit of l1, l2]")
    axes[1].set_title("Fig. 12: foot position by FK (l1 = 10, l2 = 5: seed 002 gives no unit)")
    for k, lab in enumerate(("θ1", "θ2")):
        axes[2].plot(*decimate(t, np.degrees(s["ours"][:, k])), label=f"{lab} ik.analytic")
        axes[2].plot(*decimate(t, np.degrees(s["seed"][:, k])), "--", label=f"{lab} seed Eqs. 9-12")
    axes[2].set(ylabel="IK output [deg]", xlabel="time [s]")
    axes[2].set_title("Fig. 13: inverse kinematics of the foot positions")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        # beside the axes, never over a curve
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, borderaxespad=0.0)
    return save_figure(fig, out / "leg2.png", crop=False)


def plot_pendulum(experiment: Any, path: Any) -> Path:
    """Seed 001 Figs. 5-8: θ [rad] and ω [rad/s] vs time of a ``pendulum_experiment``'s runs."""
    from ..plots import decimate, pyplot, save_figure

    plt = pyplot()
    p = experiment
    margins = {"left": 0.071, "right": 0.986, "bottom": 0.084, "top": 0.902}
    fig, axes = plt.subplots(2, 2, figsize=(11, 7), sharex=True, gridspec_kw=margins)
    for col, (run, name) in enumerate(
        ((p.undamped, "without damping"), (p.damped, f"damping {p.damped.damping:g} N·m·s/rad"))
    ):
        t = run.simulation.t
        axes[0, col].plot(*decimate(t, run.theta))
        axes[0, col].set(title=f"rotation of the link {name}", ylabel="θ [rad] (from hanging)")
        axes[1, col].plot(*decimate(t, run.theta), label="θ [rad]")
        axes[1, col].plot(*decimate(t, run.omega), label="ω [rad/s]")
        axes[1, col].set(title=f"rotation and angular velocity {name}", xlabel="time [s]")
        axes[1, col].set_ylabel("θ [rad], ω [rad/s]")
        axes[1, col].legend(loc="upper right", fontsize=8)
        for ax in axes[:, col]:
            ax.grid(True, alpha=0.3)
    u = p.undamped
    fig.suptitle(
        f"pendulum from {math.degrees(u.theta0):.0f}°: period {u.period:.6f} s, "
        f"exact {u.period_exact:.6f} s"
    )
    fig.subplots_adjust(wspace=0.169, hspace=0.155)
    return save_figure(fig, path, crop=False)


def _walk_png(run: Any, path: Path) -> Path:
    """Gait diagram, margin and foot paths (:mod:`hexapod_kin.gait.plots`'s panels), fitted."""
    from ..gait.plots import draw_foot_paths, draw_gait_diagram, draw_margin
    from ..plots import fit_limits, pyplot, save_figure

    plt = pyplot()
    fig = plt.figure(figsize=(11, 8))
    grid = fig.add_gridspec(2, 2, height_ratios=(1, 1.4), left=0.07, right=0.86, hspace=0.3)
    draw_gait_diagram(fig.add_subplot(grid[0, 0]), run)
    draw_margin(fig.add_subplot(grid[0, 1]), run)
    ax = fig.add_subplot(grid[1, :])
    draw_foot_paths(ax, run)
    xs = [run.feet[..., 0], run.base_poses[:, 0, 3], run.com[:, 0]]
    ys = [run.feet[..., 1], run.base_poses[:, 1, 3], run.com[:, 1]]
    fit_limits(
        ax, np.concatenate([np.ravel(x) for x in xs]), np.concatenate([np.ravel(y) for y in ys])
    )
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    fig.suptitle("tripod walk: gait, margin, foot paths")
    return save_figure(fig, path, crop=False)


def _walk_still(run: Any, out: Path) -> tuple[Path, str]:
    """The walk animation's scene at mid-run: legs, body outline, support polygon, foot paths."""
    from ..gait.robot import whole_body
    from ..plots import plot_still

    wb = getattr(run, "robot", None) or whole_body()
    k = len(run.t) // 2
    pts, com = wb.points_and_com(run.q[k : k + 1], run.base_poses[k : k + 1])
    legs = pts[0]  # (L, K, 3)
    hips = legs[:, 0]
    centre = hips.mean(axis=0)
    order = np.argsort(np.arctan2(hips[:, 1] - centre[1], hips[:, 0] - centre[0]))
    stance = np.flatnonzero(run.support[k])
    feet = legs[stance, -1]
    fc = feet.mean(axis=0)
    feet = feet[np.argsort(np.arctan2(feet[:, 1] - fc[1], feet[:, 0] - fc[0]))]
    when = f"t = {run.t[k]:.2f} s"
    path = plot_still(
        list(legs),
        out / "walk_still.png",
        title=f"tripod walk, still frame at {when}: body (green, top), support polygon "
        "(green, ground),\nfoot paths over the run (grey)",
        traces=[run.feet[:, j] for j in range(run.feet.shape[1])],
        outlines=[hips[order], feet] if len(feet) >= 3 else [hips[order]],
        view=(28.0, -62.0),
        size=(8.0, 5.6),
    )
    return path, when


def walk_figures(
    out: Path, duration: float, animation: bool = True, html_dir: Path | None = None
) -> tuple[list[Path], dict[str, Any], tuple[Path, str] | None]:
    """The hexapod standing and walking: figure and animation paths, facts, still frame.

    The figures go into ``out``, ``walk.html`` into ``html_dir`` (default ``out``): written
    where it stays. The still frame (path, what it shows) is None without ``animation``.
    """
    from ..dynamics import stand
    from ..gait import walk

    st = stand()
    run = walk(duration=duration)
    paths = [_walk_png(run, out / "walk.png")]
    facts: dict[str, Any] = {
        "stand_height_m": st.height,
        "stand_mass_kg": st.mass,
        "stand_forces_z_N": [round(float(f), 4) for f in st.forces[:, 2]],
        "stand_force_residual_N": float(st.force_residual),
        "stand_peak_torque_Nm": float(np.max(np.abs(st.torque))),
        "walk_duration_s": float(run.t[-1]),
        "walk_min_margin_m": float(run.margin.min()),
        "walk_max_slip_m": float(run.slip.max()),
        "walk_ik_ok": bool(run.ik_ok.all()),
    }
    if not animation:
        return paths, facts, None
    still = _walk_still(run, out)
    try:
        from ..viewer import walk_html

        paths.append(walk_html(run, (html_dir or out) / "walk.html", fps=30))
    except Exception as exc:  # the viewer extra missing: said in the report
        facts["walk_animation"] = f"not written: {exc}"
    return paths, facts, still
