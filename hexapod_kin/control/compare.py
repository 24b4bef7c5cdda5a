"""Open loop beside closed loop: one walk replayed as planned and walked under the controller.

:func:`compare` runs :func:`hexapod_kin.simulate.simulate` (the plan's joint trajectory on
position servos) and :func:`~.sim.run` (the controller, tracking the plan's twist) on the
same robot, pattern, twist, duration, ground friction and bump amplitude and seed, with the
pushes acting on the closed loop; :func:`comparison_html` writes both side by side: their
figures and a top view of the body paths against the plan.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .sim import ControlRun, Payload, Push, run

__all__ = ["Comparison", "compare", "comparison_html"]


@dataclass(frozen=True)
class Comparison:
    """An open-loop replay and a closed-loop walk of the same plan.

    Attributes:
        open_loop: The replay (:class:`hexapod_kin.simulate.SimRun`).
        closed_loop: The controlled walk (:class:`~.sim.ControlRun`).

    """

    open_loop: Any
    closed_loop: ControlRun

    def rows(self) -> list[tuple[str, float | None, float | None]]:
        """The figures of both: ``(name, open loop, closed loop)``.

        Travel error [-], heading error, max roll and pitch [rad], non-foot contact pairs
        and swing strikes [count].
        """
        o, c = self.open_loop, self.closed_loop
        o_travel = (
            (o.distance - o.distance_planned) / o.distance_planned
            if o.distance_planned > 1e-9
            else None
        )
        return [
            ("travel error", o_travel, c.travel_error),
            ("heading error [rad]", float(o.heading_error), c.heading_error),
            ("max roll [rad]", float(o.max_roll), c.max_roll),
            ("max pitch [rad]", float(o.max_pitch), c.max_pitch),
            (
                "non-foot contact pairs",
                float(len(o.non_foot_contacts)),
                float(len(c.non_foot_contacts)),
            ),
            ("swing strikes", float(len(o.swing_strikes)), float(len(c.swing_strikes))),
        ]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: both runs' summaries."""
        return {"open_loop": self.open_loop.to_dict(), "closed_loop": self.closed_loop.to_dict()}


def compare(
    robot: Any = None,
    *,
    pattern: str | None = None,
    velocity: Sequence[float] | None = None,
    duration: float = 10.0,
    friction: float = 1.0,
    bumps: float = 0.0,
    seed: int = 0,
    pushes: Sequence[Push] = (),
    payload: Payload | None = None,
    **walk_options: Any,
) -> Comparison:
    """Replay the plan open-loop and walk it closed-loop (see the module docstring).

    Args:
        robot: The robot (None: the built-in hexapod).
        pattern: The gait (default: the planner's for the legs, as ``simulate`` chooses).
        velocity: The twist ``(vx, vy, wz)`` [m/s, m/s, rad/s] (default: the planner's;
            the closed loop is commanded the plan's twist).
        duration: Walking time [s].
        friction: Ground friction coefficient.
        bumps: Bump amplitude [m] of both grounds (0: flat).
        seed: The bumps' seed.
        pushes: Pushes on the closed loop (the open-loop replay has none).
        payload: A load fixed to the body of the closed loop (the replay has none).
        **walk_options: More keywords of the plan (:func:`hexapod_kin.simulate.simulate`).

    Returns:
        A :class:`Comparison`.

    """
    from ..gait import as_whole_body
    from ..gait.tables import default_pattern
    from ..simulate import simulate

    wb = as_whole_body(robot)
    pattern = pattern or default_pattern(wb.n_legs)
    opened = simulate(
        robot,
        pattern=pattern,
        velocity=None if velocity is None else tuple(float(v) for v in velocity),
        duration=duration,
        friction=friction,
        bumps=bumps,
        seed=seed,
        **walk_options,
    )
    vx, vy, wz = (float(v) for v in opened.plan["velocity"])
    closed = run(
        robot,
        pattern=pattern,
        command=(vx, vy, wz),
        duration=duration,
        friction=friction,
        bumps=bumps,
        seed=seed,
        pushes=pushes,
        payload=payload,
    )
    return Comparison(opened, closed)


def _svg(cmp: Comparison) -> str:
    """A top view: the plan (grey), the open-loop body (red), the closed-loop body (blue)."""
    o, c = cmp.open_loop, cmp.closed_loop
    lines = {
        "plan": (np.asarray(o.planned)[:, :2, 3] - np.asarray(o.planned)[0, :2, 3], "#999"),
        "open loop": (
            np.asarray(o.base_poses)[:, :2, 3] - np.asarray(o.base_poses)[0, :2, 3],
            "#c33",
        ),
        "closed loop": (c.position[:, :2] - c.position[0, :2], "#36c"),
    }
    pts = np.vstack([p for p, _ in lines.values()])
    lo, hi = pts.min(axis=0) - 0.05, pts.max(axis=0) + 0.05
    w, h = 640.0, 320.0
    scale = min(w / max(hi[0] - lo[0], 1e-3), h / max(hi[1] - lo[1], 1e-3))
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w:.0f}" height="{h:.0f}">']
    for k, (name, (p, color)) in enumerate(lines.items()):
        xy = " ".join(
            f"{(x - lo[0]) * scale:.1f},{h - (y - lo[1]) * scale:.1f}"
            for x, y in p[:: max(1, len(p) // 400)]
        )
        out.append(f'<polyline fill="none" stroke="{color}" stroke-width="2" points="{xy}"/>')
        out.append(f'<text x="8" y="{16 + 16 * k}" fill="{color}">{name}</text>')
    out.append("</svg>")
    return "".join(out)


def comparison_html(cmp: Comparison, path: str | os.PathLike[str]) -> Path:
    """Write the side-by-side page (self-contained HTML); its path."""
    from .._io import atomic_write
    from .._page import Html, escape, page

    def cell(v: float | None, name: str) -> str:
        if v is None:
            return "-"
        if name.endswith("[rad]"):
            return f"{math.degrees(v):.2f}°"
        if name == "travel error":
            return f"{100 * v:+.2f} %"
        return f"{v:.0f}"

    c = cmp.closed_loop
    rows = "".join(
        f"<tr><td>{escape(n)}</td><td>{escape(cell(a, n))}</td><td>{escape(cell(b, n))}</td></tr>"
        for n, a, b in cmp.rows()
    )
    settings = escape(", ".join(f"{k}={v}" for k, v in c.settings.items() if k != "commands"))
    body = Html(
        "<h1>Open loop vs closed loop</h1>"
        f"<p>{settings}; fell (closed loop): {escape(c.fell)}; recovery after pushes [s]: "
        f"{escape(c.recovery_time)}</p>"
        "<table><tr><th>figure</th><th>open loop (plan replayed)</th>"
        f"<th>closed loop (controller)</th></tr>{rows}</table>"
        f"<h2>Top view of the body</h2>{_svg(cmp)}"
    )
    style = "body{font-family:sans-serif} td,th{padding:2px 10px;text-align:right}"
    return Path(atomic_write(path, page("Open loop vs closed loop", body, style=style)))
