"""Matplotlib figures of computed results, written atomically; never imported by the core."""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Any

from ._io import atomic_write
from .exceptions import OptionalDependencyError

__all__ = ["FORMATS", "decimate", "fit_limits", "plot_motion", "plot_singularity_map",
           "plot_step", "plot_still", "plot_workspace", "pyplot", "save_figure",
           "singularity_map_figure"]  # fmt: skip


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


#: Output formats by file suffix (matplotlib writes each without extra dependencies).
FORMATS = {".png": "png", ".jpg": "jpeg", ".jpeg": "jpeg", ".svg": "svg", ".pdf": "pdf"}


def _figure_format(path: str | os.PathLike[str]) -> str:
    """The image format of ``path``'s suffix (else ParameterError listing :data:`FORMATS`)."""
    from .exceptions import ParameterError, choices

    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise ParameterError(
            f"plot path {str(path)!r}: suffix {suffix or '(none)'!r} is not allowed; use one of "
            f"{choices(FORMATS)}",
            parameter="path",
            value=str(path),
            allowed=list(FORMATS),
        )
    return FORMATS[suffix]


def decimate(x: Any, y: Any, max_points: int = 3000) -> tuple[Any, Any]:
    """``(x, y)`` thinned for a line plot: each bucket keeps its smallest and largest sample.

    The same picture (every peak, dip and NaN gap) from at most ``max_points + 3`` samples;
    a shorter series passes unchanged (views of the input).
    """
    import numpy as np

    x = np.asarray(x)
    y = np.asarray(y)
    n = y.shape[0]
    half = max(int(max_points) // 2, 2)
    if n <= 2 * half:
        return x, y
    b = -(-n // half)
    m = n // b * b
    blocks = y[:m].reshape(-1, b)
    start = np.arange(0, m, b)
    keep = np.concatenate([[0], start + blocks.argmin(axis=1), start + blocks.argmax(axis=1)])
    if m < n:  # the last, shorter bucket
        tail = y[m:]
        keep = np.concatenate([keep, [m + tail.argmin(), m + tail.argmax()]])
    keep = np.unique(np.concatenate([keep, [n - 1]]))
    return x[keep], y[keep]


def save_figure(
    fig: Any, path: str | os.PathLike[str], dpi: int = 120, *, crop: bool = True
) -> Path:
    """Render ``fig`` in memory in the format of ``path``'s suffix, write it atomically, close it.

    ``dpi``: resolution of raster formats; ``crop``: crop to what is drawn
    (``bbox_inches="tight"``, one more layout pass; False for a figure already fitted).

    Raises:
        ParameterError: An unknown suffix (see :data:`FORMATS`).

    """
    plt = pyplot()
    buf = io.BytesIO()
    try:
        fmt = _figure_format(path)
        fig.savefig(buf, format=fmt, dpi=dpi, bbox_inches="tight" if crop else None)
    finally:
        plt.close(fig)
    return atomic_write(path, buf.getvalue())


def fit_limits(ax: Any, x: Any, y: Any, margin: float = 0.06, equal: bool = True) -> None:
    """Set ``ax``'s limits to the extent of ``x``, ``y`` (NaN ignored) plus ``margin``.

    ``margin``: a fraction of the larger span; ``equal``: one scale for x and y by shrinking
    the box, never by widening the limits.
    """
    import numpy as np

    x = np.asarray(x, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    x0, x1 = float(np.nanmin(x)), float(np.nanmax(x))
    y0, y1 = float(np.nanmin(y)), float(np.nanmax(y))
    pad = margin * max(x1 - x0, y1 - y0, 1e-9)
    ax.set_xlim(x0 - pad, x1 + pad)
    ax.set_ylim(y0 - pad, y1 + pad)
    if equal:
        ax.set_aspect("equal", adjustable="box")


def plot_still(
    chains: Any,
    path: str | os.PathLike[str],
    *,
    title: str,
    traces: Any = (),
    outlines: Any = (),
    ghosts: Any = (),
    view: tuple[float, float] = (22.0, -60.0),
    size: tuple[float, float] = (7.0, 5.2),
) -> Path:
    """One frame of a 3-D scene as a stick figure (the still frame of an animation).

    ``chains``: point lists (K, 3) [m] drawn as links with joint markers (legs); ``traces``:
    paths (N, 3) as thin lines; ``outlines``: closed polygons (a body, a support polygon);
    ``ghosts``: point lists drawn faint behind (the pose at t = 0); ``view``: elevation and
    azimuth [deg]; ``size`` in inches. Returns the written path.
    """
    import numpy as np

    plt = pyplot()
    fig = plt.figure(figsize=size)
    ax = fig.add_subplot(projection="3d")
    pts = []
    for group, closed, fmt, style in (
        (traces, False, "-", {"lw": 0.8, "color": "0.55"}),
        (outlines, True, "-", {"lw": 1.6, "color": "tab:green"}),
        (chains, False, "-o", {"lw": 3.0, "ms": 4, "color": "tab:blue"}),
        (ghosts, False, "-o", {"lw": 2.0, "ms": 3, "color": "0.75"}),
    ):
        for line in group:
            line = np.asarray(line, dtype=float)
            drawn = np.vstack([line, line[:1]]) if closed else line
            ax.plot(drawn[:, 0], drawn[:, 1], drawn[:, 2], fmt, **style)
            if group is chains:
                ax.plot(*line[-1:].T, "o", ms=6, color="crimson")
            pts.append(line)
    allp = np.vstack(pts)
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    # one scale on every axis; a flat scene keeps a box at least a third as tall as wide
    span = max(float((hi - lo).max()), 1e-3)
    half = np.maximum((hi - lo) / 2, span / 6) * 1.08
    mid = (lo + hi) / 2
    for k, set_lim in enumerate((ax.set_xlim, ax.set_ylim, ax.set_zlim)):
        set_lim(mid[k] - half[k], mid[k] + half[k])
    ax.set_box_aspect(tuple(half / half.max()))
    for axis, h in zip((ax.xaxis, ax.yaxis, ax.zaxis), half / half.max()):
        axis.get_major_locator().set_params(nbins=max(2, int(round(6 * h))))
    ax.view_init(*view)
    ax.set(xlabel="x [m]", ylabel="y [m]")
    ax.set_zlabel("z [m]")
    ax.set_title(title, fontsize=10)
    fig.subplots_adjust(left=0.0, right=1.0, bottom=0.02, top=0.93)
    return save_figure(fig, path, crop=False)


# ---------------------------------------------------------------- singularity pictures
#: Longest family name in a legend (longer ones are cut): the figure keeps its size.
_LEGEND_CHARS = 80

_MEASURE_LABELS = {
    "det": "det J",
    "manipulability": "manipulability sqrt(det(J J^T))",
    "sigma_min": "smallest singular value sigma_min",
    "condition": "log10 condition number",
}


def _joint_axis(result: Any, joint: int, values: Any) -> tuple[Any, str]:
    """``(values, "name (qk) [unit]")`` of a scan's ``joint``: [deg], [m] or [mm] (< 0.1 m)."""
    import numpy as np

    vals = np.asarray(values, dtype=float)
    name = f"{result.joint_names[joint]} (q{joint + 1})"
    if not result.prismatic[joint]:
        return np.degrees(vals), f"{name} [deg]"
    span = float(np.ptp(result.q[:, joint])) if result.q.size else 0.0
    if span < 0.1:
        return vals * 1000.0, f"{name} [mm]"
    return vals, f"{name} [m]"


def singularity_map_figure(
    result: Any, measure: str | None = None, title: str | None = None
) -> Any:
    """The figure of :func:`plot_singularity_map` (not written; close it when done)."""
    import numpy as np

    from .exceptions import ParameterError, choices

    if result.grid_shape is None or len(result.joints) != 2:
        raise ParameterError(
            "plot_singularity_map: a grid scan over exactly two joints is required "
            f"(got joints {[result.joint_names[j] for j in result.joints]}, "
            f"grid {result.grid_shape})",
            parameter="result",
            value=result.grid_shape,
            allowed="a grid scan over two joints",
        )
    square = bool(np.isfinite(result.det).any())
    measure = measure or ("det" if square else "manipulability")
    if measure not in _MEASURE_LABELS or (measure == "det" and not square):
        allowed = [k for k in _MEASURE_LABELS if square or k != "det"]
        raise ParameterError(
            f"measure={measure!r} is not allowed here; use one of {choices(allowed)}",
            parameter="measure",
            value=measure,
            allowed=allowed,
        )
    plt = pyplot()
    from matplotlib.colors import TwoSlopeNorm
    from matplotlib.lines import Line2D

    ja, jb = result.joints
    qa = result.q[:, ja].reshape(result.grid_shape)
    qb = result.q[:, jb].reshape(result.grid_shape)
    val = np.asarray(getattr(result, measure), float).reshape(result.grid_shape)
    xa, label_a = _joint_axis(result, ja, qa[:, 0])
    xb, label_b = _joint_axis(result, jb, qb[0, :])
    fig, ax = plt.subplots(figsize=(8.0, 6.4))
    unit = " [m]" if measure == "sigma_min" and set(result.rows) <= {"x", "y", "z"} else ""
    if measure == "det":
        lim = float(np.nanmax(np.abs(val))) or 1.0
        norm = TwoSlopeNorm(0.0, -lim, lim)
        mesh = ax.pcolormesh(xa, xb, val.T, cmap="RdBu_r", norm=norm, shading="nearest")
    elif measure == "condition":
        with np.errstate(divide="ignore"):
            shown = np.log10(np.where(np.isfinite(val), val, np.nan))
        cap = np.nanpercentile(shown, 99) if np.isfinite(shown).any() else 1.0
        mesh = ax.pcolormesh(xa, xb, np.minimum(shown, cap).T, cmap="magma_r", shading="nearest")
    else:
        mesh = ax.pcolormesh(xa, xb, val.T, cmap="viridis", shading="nearest")
    cbar = fig.colorbar(mesh, ax=ax)
    cbar.set_label(_MEASURE_LABELS[measure] + unit)
    handles = []
    styles = ["-", "--", ":", "-."]
    colours = ["black", "magenta", "darkorange", "cyan", "lime"]
    fine_a = np.linspace(qa.min(), qa.max(), 721)
    fine_b = np.linspace(qb.min(), qb.max(), 721)
    ga, gb = np.meshgrid(fine_a, fine_b, indexing="ij")
    for f, fam in enumerate(result.families):
        colour = colours[f % len(colours)]
        style = styles[f % len(styles)]
        if fam.joint is not None and fam.joint in (ja, jb) and fam.value is not None:
            lo, hi = (qa.min(), qa.max()) if fam.joint == ja else (qb.min(), qb.max())
            vals = [fam.value + k * 2 * np.pi for k in (-1, 0, 1)] if fam.periodic else [fam.value]
            inside = [v for v in vals if lo - 1e-9 <= v <= hi + 1e-9]
            if not inside:
                continue
            line = ax.axvline if fam.joint == ja else ax.axhline
            for v in inside:
                line(float(_joint_axis(result, fam.joint, v)[0]), color=colour, ls=style, lw=2.2)
        elif fam.joint is None:
            qq = np.empty(ga.shape + (len(result.joint_names),))
            qq[:] = result.q_fixed
            qq[..., ja] = ga
            qq[..., jb] = gb
            res = result.family_residual(qq, f)
            if not (np.nanmin(res) <= 0 <= np.nanmax(res)):
                continue
            xs, ys = _joint_axis(result, ja, fine_a)[0], _joint_axis(result, jb, fine_b)[0]
            ax.contour(
                xs, ys, res.T, levels=[0.0], colors=[colour], linestyles=[style], linewidths=2.2
            )
        else:
            continue
        name = fam.name if len(fam.name) <= _LEGEND_CHARS else fam.name[: _LEGEND_CHARS - 1] + "…"
        handles.append(Line2D([], [], color=colour, ls=style, lw=2.2, label=name))
    flagged = result.singular.reshape(result.grid_shape)
    if flagged.any() and not result.families:
        ax.contourf(
            xa, xb, flagged.T.astype(float), levels=[0.5, 1.5], colors="none", hatches=["////"]
        )
        label = f"sigma_min < {result.threshold:.3g}"
        handles.append(Line2D([], [], color="black", lw=0, marker="s", mfc="none", label=label))
    if handles:  # below the axes: never over the data
        ax.legend(
            handles=handles,
            title="singular families",
            loc="upper center",
            bbox_to_anchor=(0.5, -0.12),
            ncol=min(len(handles), 2),
            fontsize=8,
            title_fontsize=9,
            frameon=False,
        )
    ax.set(xlabel=label_a, ylabel=label_b)
    others = [
        f"{name} = {result.q_fixed[j]:.3g} m"
        if result.prismatic[j]
        else f"{name} = {np.degrees(result.q_fixed[j]):.0f} deg"
        for j, name in enumerate(result.joint_names)
        if j not in (ja, jb)
    ]
    ax.set_title(
        title
        or f"{result.source}: {_MEASURE_LABELS[measure]} (rows {', '.join(result.rows)})"
        + (f"\n{'; '.join(others)}" if others else "")
    )
    return fig


def plot_singularity_map(
    result: Any, path: str | os.PathLike[str], measure: str | None = None, title: str | None = None
) -> Path:
    """Heat map of a measure over two scanned joints, with the singular families drawn.

    Revolute axes in degrees, prismatic axes in metres (millimetres under 0.1 m); the legend
    sits below the axes (never over the data); flagged points are hatched when no family is
    known.

    ``result``: a :class:`~hexapod_kin.singularity.ScanResult` of a *grid* scan over two
    joints; ``path``: a :data:`FORMATS` file, written atomically; ``measure``: ``"det"``
    (default when J is square), ``"manipulability"`` (else), ``"sigma_min"`` or
    ``"condition"``; ``title``: default source, measure and the fixed joints.

    Raises:
        ParameterError: Not a 2-joint grid scan, an unknown measure or file suffix.

    """
    _figure_format(path)
    return save_figure(singularity_map_figure(result, measure, title), path)


def plot_workspace(
    ws: Any,
    path: str | os.PathLike[str],
    plane: str = "xz",
    singular_points: Any = None,
    title: str | None = None,
) -> Path:
    """A :class:`~hexapod_kin.workspace.WorkspaceResult`'s section around ``plane`` (xz, yz, xy).

    ``singular_points``: (M, 3) tips of singular configurations, overlaid. Returns the path.
    """
    import numpy as np

    from .workspace import cross_section

    plt = pyplot()
    sec = cross_section(ws.points, plane)
    fig, ax = plt.subplots(figsize=(7.0, 6.4))
    ax.scatter(sec[:, 0], sec[:, 1], s=1, c="tab:blue", alpha=0.4, label="reachable tip points")
    if singular_points is not None and len(singular_points):
        sp_sec = cross_section(np.asarray(singular_points, float), plane)
        ax.scatter(sp_sec[:, 0], sp_sec[:, 1], s=2, c="tab:red", label="singular configurations")
    ax.set_aspect("equal")
    ax.set(xlabel=f"{plane[0]} [m]", ylabel=f"{plane[1]} [m]")
    ax.legend(loc="upper right", markerscale=6)
    ax.set_title(
        title or f"{ws.source}: workspace section ({plane} plane); volume ~ {ws.volume:.3g} m^3"
    )
    return save_figure(fig, path)


# ---------------------------------------------------------------- motion pictures
def plot_motion(run: Any, path: str | os.PathLike[str], title: str | None = None) -> Path:
    """The seeds' figures of a resolved-rate run in one 2×2 figure; returns the written path.

    ``run``: a :class:`~hexapod_kin.seeds.SeedRun` or :class:`~hexapod_kin.motion.Trajectory`.
    Foot position; commanded vs actual foot velocity; joint angles; deviation from the
    reference path (log scale, with the plain Euler baseline when the run has one).
    """
    import numpy as np

    plt = pyplot()
    tr = getattr(run, "trajectory", run)
    t = tr.t
    fig, axes = plt.subplots(2, 2, figsize=(12, 8), sharex=True)
    ax = axes[0, 0]
    for k, name in enumerate("xyz"):
        ax.plot(*decimate(t, tr.foot[:, k]), label=name)
    ax.set(ylabel="foot position [m]", title="foot position (base frame)")
    ax.legend(loc="center right")
    ax.grid(True, alpha=0.3)
    ax = axes[0, 1]
    for k, name in enumerate("xyz"):
        (line,) = ax.plot(*decimate(t, tr.foot_velocity[:, k]), label=f"actual v{name}")
        command = decimate(t, tr.command[:, k])
        ax.plot(*command, "--", color=line.get_color(), alpha=0.8, label=f"commanded v{name}")
    ax.set(ylabel="foot velocity [m/s]", title="commanded vs actual foot velocity")
    ax.legend(loc="best", fontsize=8, ncol=2)
    ax.grid(True, alpha=0.3)
    ax = axes[1, 0]
    for j in range(tr.q.shape[1]):
        ax.plot(*decimate(t, tr.q[:, j]), label=f"q{j + 1}")
    ax.set(ylabel="joint value [rad]", xlabel="t [s]", title="joint angles")
    ax.legend(loc="best")
    ax.grid(True, alpha=0.3)
    ax = axes[1, 1]
    dev = np.abs(tr.foot - tr.reference)
    floor = 1e-18
    for k, name in enumerate("xyz"):
        deviation = decimate(t, np.maximum(dev[:, k], floor))
        ax.semilogy(*deviation, label=f"|{name} − {name}_ref| {tr.method}")
    base_dev = getattr(run, "baseline_deviation", None)
    if base_dev is not None:
        base_z, base_x = (decimate(t, np.maximum(base_dev[:, k], floor)) for k in (2, 0))
        ax.semilogy(*base_z, "k:", label="|z − z0| Euler + solve")
        ax.semilogy(*base_x, "k--", lw=0.8, label="|x − x_ref| Euler + solve")
    ax.set(ylabel="deviation from the reference path [m]", xlabel="t [s]", title="drift")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    if title is None:
        title = f"resolved-rate run: {tr.method}, dt = {tr.dt:g} s, gain {tr.gain:g} 1/s"
        if getattr(run, "drift_z", None) is not None:  # a SeedRun
            title += (
                f" — drift y {run.drift_y:.1e} m, z {run.drift_z:.1e} m, "
                f"x error {run.error_x:.1e} m"
            )
    fig.suptitle(title)
    # the margins tight_layout finds for these panels, set directly (it costs a layout pass)
    fig.subplots_adjust(left=0.075, right=0.985, bottom=0.075, top=0.91, wspace=0.18, hspace=0.14)
    return save_figure(fig, path, crop=False)


def plot_step(step: Any, path: str | os.PathLike[str], title: str | None = None) -> Path:
    """A :class:`~hexapod_kin.gait.FootStep`: its path from the side and its joints vs time."""
    import numpy as np

    plt = pyplot()
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.5))
    foot, act = step.foot, step.foot_actual
    st = np.asarray(step.stance)
    a1.plot(foot[:, 0], foot[:, 2], "-", color="0.7", lw=4, label="planned")
    a1.plot(act[st, 0], act[st, 2], ".", ms=3, label="stance (FK of IK)")
    a1.plot(act[~st, 0], act[~st, 2], ".", ms=3, label="swing (FK of IK)")
    a1.set(xlabel="x [m]", ylabel="z [m]", title="foot path (side view)")
    a1.set_aspect("equal", adjustable="datalim")
    a1.legend(loc="best", fontsize=8)
    a1.grid(True, alpha=0.3)
    for j in range(step.q.shape[1]):
        a2.plot(step.t, step.q[:, j], label=f"q{j + 1}")
    a2.set(xlabel="t [s]", ylabel="joint value [rad]", title="joint trajectories by IK")
    a2.legend(loc="best")
    a2.grid(True, alpha=0.3)
    fig.suptitle(title or f"foot step: max IK error {step.max_error:.1e} m")
    fig.tight_layout()
    return save_figure(fig, path, crop=False)
