"""The report's figures and animations, drawn like the seeds' (same quantities, same axes).

Each function writes one PNG (or HTML animation) into the report folder and returns its path.

**Render cache**: a PNG is a pure function of the data drawn, the drawing code and matplotlib.
Each figure is keyed by a SHA-256 of its inputs (every array's bytes, shape and dtype, every
number and text of the result objects, walked through dataclasses (their compared fields),
tuples and dicts), the package's source (every ``.py`` file of ``hexapod_kin``), the package
and matplotlib versions; the PNG is kept under :func:`hexapod_kin._io.cache_root`
``("report")/figures``. The data is always recomputed; only drawing the same numbers again is
skipped. Inputs that cannot be walked (an object of another kind) are simply drawn, not cached.
A damaged cached PNG is ignored.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .._io import atomic_write, cache_root

__all__ = [
    "heat_maps",
    "leg2_figure",
    "pendulum_figure",
    "step_animation",
    "step_figure",
    "walk_figures",
]

_PNG_HEAD, _PNG_TAIL = b"\x89PNG\r\n\x1a\n", b"IEND\xaeB`\x82"


def _feed(h: Any, obj: Any, depth: int = 0) -> bool:
    """Hash ``obj`` into ``h``; False when some part of it cannot be hashed by value."""
    if depth > 12:
        return False
    if obj is None or isinstance(obj, (bool, int, float, complex, str, np.generic)):
        h.update(f"{type(obj).__name__}:{obj!r};".encode())
        return True
    if isinstance(obj, np.ndarray):
        if obj.dtype.hasobject:
            return False
        h.update(f"a{obj.dtype.str}{obj.shape};".encode())
        h.update(np.ascontiguousarray(obj).tobytes())
        return True
    if isinstance(obj, (list, tuple)):
        h.update(f"{type(obj).__name__}{len(obj)}(".encode())
        return all(_feed(h, x, depth + 1) for x in obj)
    if isinstance(obj, dict):
        h.update(f"dict{len(obj)}(".encode())
        return all(
            _feed(h, k, depth + 1) and _feed(h, v, depth + 1)
            for k, v in sorted(obj.items(), key=lambda kv: repr(kv[0]))
        )
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        h.update(f"{type(obj).__module__}.{type(obj).__qualname__}(".encode())
        return all(
            _feed(h, f.name, depth + 1) and _feed(h, getattr(obj, f.name), depth + 1)
            for f in dataclasses.fields(obj)
            if f.compare  # the value's own fields (not a derived cache such as compiled code)
        )
    return False


def _digest(name: str, inputs: Any) -> str | None:
    """The render key of figure ``name`` drawn from ``inputs`` (None: not hashable)."""
    try:
        import matplotlib

        from .. import __version__
        from .cache import package_digest

        h = hashlib.sha256()
        head = (name, __version__, matplotlib.__version__, package_digest())
        return h.hexdigest() if _feed(h, head) and _feed(h, inputs) else None
    except Exception:  # noqa: BLE001 - no key: the figure is drawn
        return None


def _rendered(
    name: str, inputs: Any, path: Path, draw: Callable[[Path], Path], cache: bool = True
) -> Path:
    """Write figure ``name`` to ``path``: the cached PNG of the same inputs, else ``draw(path)``."""
    digest = _digest(name, inputs) if cache else None
    cached = cache_root("report") / "figures" / f"{digest}.png" if digest else None
    if cached is not None:
        try:
            data = cached.read_bytes()
            if data.startswith(_PNG_HEAD) and data.endswith(_PNG_TAIL):
                return atomic_write(path, data)
        except OSError:
            pass
    out = draw(path)
    if cached is not None:
        try:
            cached.parent.mkdir(parents=True, exist_ok=True)
            atomic_write(cached, out.read_bytes())
        except Exception:  # noqa: BLE001 - a cache that cannot be written is only slower
            pass
    return out


def heat_maps(ctx: Any, out: Path, grid: int) -> tuple[list[Path], dict[str, Any]]:
    """Det J / σ_min over (knee, ankle) for the leg and (θ1, θ2) for the SCARA, with families."""
    from .. import load
    from ..singularity import scan

    paths, counts = [], {}
    for key, name, joints in (
        ("leg", "hexabot_leg", ["knee", "ankle"]),
        ("scara", "scara", ["theta1", "theta2"]),
    ):
        res = scan(load(ctx.chain(key)), grid=grid, joints=joints, families=True)
        counts[name] = dict(res.family_counts)
        title = f"{name}: singularity map, families of det J"

        def draw(path: Path, res: Any = res, title: str = title) -> Path:
            from ..plots import pyplot, save_figure, singularity_map_figure

            plt = pyplot()
            fig = singularity_map_figure(res, title=title)
            written = save_figure(fig, path)
            plt.close(fig)
            return written

        png = out / f"singularity_{name}.png"
        paths.append(_rendered("heat_map", (res, title), png, draw, ctx.cache))
    return paths, counts


def step_figure(ctx: Any, out: Path) -> Path:
    """Seeds 000/001/003 Figs.: foot position, velocity, joint angles vs time, drift."""
    title = "x-only step: v = [A sin(2πt/T), 0, 0] (seeds 000, 001, 003)"

    def draw(path: Path) -> Path:
        from ..plots import plot_motion

        return plot_motion(ctx.step, path, title=title)

    return _rendered("step", (ctx.step, title), out / "step.png", draw, ctx.cache)


def step_animation(ctx: Any, out: Path) -> Path:
    """The step, animated (self-contained HTML)."""
    from .. import load
    from ..viewer import export_html

    tr = ctx.step.trajectory
    return export_html(
        load("hexabot_leg"),
        tr.t,
        tr.q,
        out / "step.html",
        fps=30,
        title="hexabot_leg: the seeds' x-only step",
    )


def leg2_figure(ctx: Any, out: Path) -> Path:
    """Seed 002 Figs. 11-13: planned joint input, foot position, IK output (ours, the seed's)."""
    return _rendered(
        "leg2", ctx.schedule, out / "leg2.png", lambda path: _leg2(ctx.schedule, path), ctx.cache
    )


def _leg2(s: dict[str, np.ndarray], path: Path) -> Path:
    from ..plots import decimate, pyplot, save_figure

    plt = pyplot()
    t = s["t"]
    fig, axes = plt.subplots(3, 1, figsize=(8, 9), sharex=True)
    for k, lab in enumerate(("θ1 (coxa)", "θ2 (tibia)")):
        axes[0].plot(*decimate(t, np.degrees(s["q"][:, k])), label=lab)
    axes[0].set_ylabel("input angle [deg]")
    axes[0].set_title("Fig. 11: planned input (Table I)")
    for k, lab in enumerate("xyz"):
        axes[1].plot(*decimate(t, s["feet"][:, k]), label=lab)
    axes[1].set_ylabel("foot position [m] (l1 = 10, l2 = 5)")
    axes[1].set_title("Fig. 12: foot position by FK")
    for k, lab in enumerate(("θ1", "θ2")):
        axes[2].plot(*decimate(t, np.degrees(s["ours"][:, k])), label=f"{lab} ik.analytic")
        axes[2].plot(*decimate(t, np.degrees(s["seed"][:, k])), "--", label=f"{lab} seed Eqs. 9-12")
    axes[2].set_ylabel("IK output [deg]")
    axes[2].set_xlabel("time [s]")
    axes[2].set_title("Fig. 13: inverse kinematics of the foot positions")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    written = save_figure(fig, path, crop=False)
    plt.close(fig)
    return written


def pendulum_figure(ctx: Any, out: Path) -> Path:
    """Seed 001 Figs. 5-8: rotation (and angular velocity) of the link, undamped and damped."""
    return _rendered(
        "pendulum",
        ctx.pendulum,
        out / "pendulum.png",
        lambda path: _pendulum(ctx.pendulum, path),
        ctx.cache,
    )


def _pendulum(p: Any, path: Path) -> Path:
    from ..plots import decimate, pyplot, save_figure

    plt = pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(11, 7), sharex=True)
    for col, (run, name) in enumerate(
        ((p.undamped, "without damping"), (p.damped, f"damping {p.damped.damping:g} N·m·s/rad"))
    ):
        t = run.simulation.t
        axes[0, col].plot(*decimate(t, run.theta))
        axes[0, col].set_title(f"rotation of the link {name}")
        axes[0, col].set_ylabel("θ [rad] (from hanging)")
        axes[1, col].plot(*decimate(t, run.theta), label="θ [rad]")
        axes[1, col].plot(*decimate(t, run.omega), label="ω [rad/s]")
        axes[1, col].set_title(f"rotation and angular velocity {name}")
        axes[1, col].set_xlabel("time [s]")
        axes[1, col].set_ylabel("θ [rad], ω [rad/s]")
        axes[1, col].legend(loc="upper right", fontsize=8)
        for ax in axes[:, col]:
            ax.grid(True, alpha=0.3)
    u = p.undamped
    fig.suptitle(
        f"pendulum from {math.degrees(u.theta0):.0f}°: period {u.period:.6f} s, "
        f"exact {u.period_exact:.6f} s"
    )
    fig.tight_layout()
    written = save_figure(fig, path, crop=False)
    plt.close(fig)
    return written


def walk_figures(
    out: Path, duration: float, animation: bool = True, cache: bool = True
) -> tuple[list[Path], dict[str, Any]]:
    """The hexapod standing and walking: gait figure, walk animation, the figures of both."""
    from ..dynamics import stand
    from ..gait import walk

    st = stand()
    run = walk(duration=duration)
    title = "tripod walk: gait, margin, foot paths"

    def draw(path: Path) -> Path:
        from ..gait.plots import plot_gait

        return plot_gait(run, path, title=title)

    paths = [_rendered("walk", (run, title), out / "walk.png", draw, cache)]
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
        return paths, facts
    try:
        from ..gait.show import walk_html

        paths.append(walk_html(run, out / "walk.html", fps=30))
    except Exception as exc:  # the viewer extra missing: said in the report
        facts["walk_animation"] = f"not written: {exc}"
    return paths, facts
