"""Plan and simulation side by side: one self-contained HTML page (viewer imported lazily)."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Any

__all__ = ["simulation_html"]


def _panel(title: str, frame: str, lines: list[str]) -> str:
    from html import escape

    rows = "".join(f"<li>{escape(line)}</li>" for line in lines)
    return f"<section><h2>{escape(title)}</h2>{frame}<ul>{rows}</ul></section>"


def simulation_html(sim: Any, path: str | os.PathLike[str], **options: Any) -> Path:
    """Write the plan (left) and its MuJoCo replay (right) as one self-contained page.

    Each side is the viewer's offline page (:func:`hexapod_kin.gait.show.walk_html` for the
    plan, with its support polygon and centre of mass; :func:`hexapod_kin.viewer.export_html`
    of the simulated body poses and joint angles), embedded with ``<iframe srcdoc>``; below
    each, the figures (planned vs simulated distance, heading, roll/pitch, slip, non-foot
    contacts).

    Args:
        sim: A :class:`~hexapod_kin.simulate.SimRun` (with its plan, ``sim.run``).
        path: Destination ``.html`` (written atomically).
        **options: Passed to both animations (``fps``, ``speed``...).

    Returns:
        The path written.

    Raises:
        OptionalDependencyError: The viewer extra (meshcat) is missing.
        ParameterError: ``sim`` carries no plan.

    """
    import math
    from html import escape

    from .._io import atomic_write
    from ..exceptions import ParameterError
    from ..gait.show import run_model, walk_html
    from ..viewer import export_html, iframe

    run = getattr(sim, "run", None)
    if run is None:
        raise ParameterError("the simulation carries no plan (sim.run)", parameter="sim")
    mdl = run_model(run)
    cols = [list(sim.scene.joint_names).index(j) for j in mdl.joint_names]
    d = sim.to_dict()
    with tempfile.TemporaryDirectory(prefix="hexapod_kin_sim_") as tmp:
        left = walk_html(run, Path(tmp) / "plan.html", model=mdl, title="plan", **options)
        right = export_html(
            mdl,
            sim.t,
            sim.q[:, cols],
            Path(tmp) / "sim.html",
            base_poses=sim.base_poses,
            title="MuJoCo",
            **options,
        )
        frames = [iframe(left, height=520), iframe(right, height=520)]
    err = d["distance_error"]
    turn = d["turn_error"]
    plan_lines = [
        f"pattern {run.table.name}, terrain {d['scene']['terrain']}, "
        f"{run.t[-1]:.4g} s at {run.settings.get('rate', float('nan')):.4g} Hz",
        f"distance {sim.distance_planned:.4f} m, turn {math.degrees(sim.turn_planned):.3f}°",
        f"min stability margin {1e3 * run.min_margin:.2f} mm",
    ]
    sim_lines = [
        f"distance {sim.distance:.4f} m"
        + ("" if err is None else f" ({100 * err:+.2f} % of the plan)"),
        f"turn {math.degrees(sim.turn):.3f}°" + ("" if turn is None else f" ({100 * turn:+.2f} %)"),
        f"heading error {d['heading_error_deg']:.3f}°, max roll {d['max_roll_deg']:.3f}°, "
        f"max pitch {d['max_pitch_deg']:.3f}°",
        f"body height error {1e3 * sim.height_error:.2f} mm, stance slip "
        f"{1e3 * sim.max_slip:.2f} mm per contact",
        "non-foot contacts: "
        + (", ".join(f"{a}–{b} at {w:.3f} s" for a, b, w in sim.non_foot_contacts) or "none"),
        "swing feet striking the ground: "
        + (", ".join(f"{leg} at {w:.3f} s" for leg, w in sim.swing_strikes) or "none"),
        "checks: " + ("pass" if sim.ok else "FAIL") + (" (stumbled)" if sim.stumbled else ""),
    ]
    title = f"hexapod_kin: {run.table.name} plan and MuJoCo replay"
    page = (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        f"<title>{escape(title)}</title><style>body{{font-family:sans-serif;margin:1em}}"
        "main{display:flex;gap:1em}section{flex:1;min-width:0}h2{font-size:1.1em}"
        "</style></head><body>"
        f'<h1 style="font-size:1.3em">{escape(title)}</h1><main>'
        + _panel("plan", frames[0], plan_lines)
        + _panel("simulation (MuJoCo, open loop)", frames[1], sim_lines)
        + "</main></body></html>\n"
    )
    return atomic_write(path, page)
