"""What a drawing of a walk needs from the gait: the support polygons and the robot's model.

:func:`support_polygons` gives, per sample, the support polygon (the convex hull of the stance
feet, on the ground under them) and the centre of mass projected on it; :func:`run_model` the
loaded model of the robot that walks. The pages and the live viewer that draw them are in
:mod:`hexapod_kin.viewer.walk` (the viewer imports the gait, never the other way round).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["run_model", "support_polygons"]


def _turn(o: tuple[float, ...], a: tuple[float, ...], p: tuple[float, ...]) -> float:
    """The cross product ``(a − o) × (p − o)`` (> 0: ``p`` on the left of ``o → a``)."""
    return (a[0] - o[0]) * (p[1] - o[1]) - (a[1] - o[1]) * (p[0] - o[0])


def _hull(points: np.ndarray) -> np.ndarray:
    """Counter-clockwise convex hull (K, 2) of 2-D points (Andrew's monotone chain)."""
    pts = sorted(map(tuple, points))
    if len(pts) <= 2:
        return np.array(pts, dtype=float).reshape(-1, 2)

    def half(seq: list[tuple[float, ...]]) -> list[tuple[float, ...]]:
        out: list[tuple[float, ...]] = []
        for p in seq:
            while len(out) >= 2 and _turn(out[-2], out[-1], p) <= 0:
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1], dtype=float)


def support_polygons(run: Any, lift: float = 0.002) -> tuple[np.ndarray, np.ndarray]:
    """Per sample: the closed support polygon (N, L + 1, 3) and the projected CoM (N, 1, 3).

    The polygon's vertices are the stance feet on the hull, counter-clockwise, at the feet's
    heights plus ``lift`` [m]; it is padded by repeating its last vertex and closed on the
    first (fixed shape for the animation). The CoM is drawn at the mean stance-foot height.
    """
    n, nl = run.support.shape
    poly = np.empty((n, nl + 1, 3))
    com = np.empty((n, 1, 3))
    for i in range(n):
        feet = run.feet[i, run.support[i]]
        if len(feet) == 0:
            feet = run.feet[i]
        hull = _hull(feet[:, :2])
        z = np.array([feet[np.argmin(np.hypot(*(feet[:, :2] - v).T)), 2] for v in hull]) + lift
        verts = np.column_stack([hull, z])
        k = len(verts)
        poly[i, :k] = verts
        poly[i, k:nl] = verts[-1]
        poly[i, nl] = verts[0]
        com[i, 0] = [run.com[i, 0], run.com[i, 1], float(feet[:, 2].mean()) + lift]
    return poly, com


def run_model(run: Any) -> Any:
    """The loaded model (:func:`hexapod_kin.load`) of the robot that walks ``run``.

    The run's own robot as loaded (``run.robot.kinematic``: the one model its description is
    a view of) when it has one; otherwise the built-in ``hexapod``.
    """
    robot = getattr(run, "robot", None)
    if robot is None:
        from .. import load

        return load("hexapod")
    return robot.kinematic
