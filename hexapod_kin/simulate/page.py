"""Plan and simulation side by side: one self-contained HTML page (the viewer imported lazily)."""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

from .._io import atomic_write
from .._page import Html, fill, frame, page
from ..exceptions import ParameterError

__all__ = ["simulation_html"]


#: The page's style sheet.
_STYLE = (
    "body{font-family:sans-serif;margin:1em}main{display:flex;gap:1em}"
    "section{flex:1;min-width:0}h2{font-size:1.1em}h1{font-size:1.3em}"
)


#: The two animations in step: the plan's frame leads (its time, playing or not), the
#: simulation's follows (it seeks when it is more than 0.1 s apart).
_SYNC = (
    'window.addEventListener("message",function(e){var f=document.querySelectorAll("iframe");'
    'if(f.length<2||!e.data||e.data.hk!=="time"||e.source!==f[0].contentWindow){return;}'
    'f[1].contentWindow.postMessage({hk:"follow",t:e.data.t,on:e.data.on},"*");});'
)


def _panel(title: str, doc: str, lines: list[str]) -> Html:
    """A side of the page: its heading, its animation (``doc``, framed) and its figures."""
    items = Html("".join(fill("<li>$line</li>", line=line) for line in lines))
    return fill(
        "<section><h2>$title</h2>$frame<ul>$items</ul></section>",
        title=title,
        frame=frame(doc, height=520),
        items=items,
    )


def simulation_html(sim: Any, path: str | os.PathLike[str], **options: Any) -> Path:
    """Write the plan (left) and its MuJoCo replay (right) as one self-contained page.

    Each side is the viewer's offline page (:func:`hexapod_kin.viewer.walk_page` for the
    plan, with its support polygon and centre of mass; :func:`hexapod_kin.viewer.render_html`
    of the simulated body poses and joint angles), embedded with ``<iframe srcdoc>``; below
    each, the figures (planned vs simulated distance, heading, roll/pitch, slip, non-foot
    contacts). The two play in step: the simulation follows the plan's play, pause and
    time (the frames' messages, relayed by the page).

    ``sim``: a :class:`~hexapod_kin.simulate.SimRun` with its plan (``sim.run``); ``path``:
    the ``.html`` (written atomically, returned); ``**options`` go to both animations
    (``fps``, ``speed``...).

    Raises:
        OptionalDependencyError: The viewer extra (meshcat) is missing.
        ParameterError: ``sim`` carries no plan.

    """
    from ..gait.show import run_model
    from ..viewer import render_html, walk_page

    run = getattr(sim, "run", None)
    if run is None:
        raise ParameterError("the simulation carries no plan (sim.run)", parameter="sim")
    mdl = run_model(run)
    cols = [list(sim.scene.joint_names).index(j) for j in mdl.joint_names]
    d = sim.to_dict()
    left = walk_page(run, model=mdl, title="plan", **options)
    right = render_html(
        mdl, sim.t, sim.q[:, cols], base_poses=sim.base_poses, title="MuJoCo", **options
    )
    err, turn = d["distance_error"], d["turn_error"]
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
        f"{1e3 * sim.max_slip:.2f} mm per stance",
        "non-foot contacts: "
        + (", ".join(f"{a}–{b} at {w:.3f} s" for a, b, w in sim.non_foot_contacts) or "none"),
        "swing feet striking the ground: "
        + (", ".join(f"{leg} at {w:.3f} s" for leg, w in sim.swing_strikes) or "none"),
        "checks: " + ("pass" if sim.ok else "FAIL") + (" (stumbled)" if sim.stumbled else ""),
    ]
    title = f"hexapod_kin: {run.table.name} plan and MuJoCo replay"
    body = fill(
        "<h1>$title</h1><main>$plan$sim</main><script>$sync</script>",
        sync=Html(_SYNC),
        title=title,
        plan=_panel("plan", left, plan_lines),
        sim=_panel("simulation (MuJoCo, open loop)", right, sim_lines),
    )
    return atomic_write(path, page(title, body, style=_STYLE))
