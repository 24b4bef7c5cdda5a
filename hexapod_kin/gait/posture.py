"""The default standing posture of a robot whose geometric default leaves no joint range.

:meth:`~.robot.WholeBody.neutral_feet` puts each foot at a fixed fraction of its leg's span
(0.64 out, 0.32 down). That is a good stance for most legs, but not for every real robot: a
leg whose tibia is bent upwards, or whose knee range is narrow, reaches that point only at
the edge of a joint range, and the first step leaves it. Here the stance is checked over the
box a default step sweeps around each neutral foot (± half the stride along x and y, the step
height up), and when some joint keeps less than :data:`MIN_ROOM` of its range there, the
stance (one body height, one reach for every leg) that keeps the most range is searched on a
grid of reaches and depths.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

#: Fraction of every joint's range a default stance keeps free over the default step box.
MIN_ROOM = 0.1

#: The box a default step sweeps around a neutral foot (the CLI's default stride 0.05 m and
#: step height 0.03 m), in the body frame [m].
_STRIDE, _LIFT = 0.05, 0.03


def _box(stride: float, lift: float) -> np.ndarray:
    h = stride / 2
    return np.array([[0, 0, 0], [h, 0, 0], [-h, 0, 0], [0, h, 0], [0, -h, 0], [0, 0, lift]])


def room(wb: Any, body_height: float, reach: Any = None) -> float:
    """Smallest free fraction of a leg joint's range over the default step box (−1: unreachable).

    Args:
        wb: The :class:`~.robot.WholeBody`.
        body_height: Body above flat ground [m].
        reach: Mount-to-foot horizontal distance [m] (``None``: the robot's own).

    """
    span = wb.upper - wb.lower
    finite = np.isfinite(span) & (span > 0)
    if not finite.any():
        return math.inf
    feet = wb.neutral_feet(reach)
    feet[:, 2] = wb.foot_radius - body_height
    box = _box(_STRIDE, _LIFT)
    base = np.repeat(np.eye(4)[None], len(box), axis=0)
    base[:, 2, 3] = body_height
    targets = feet[None] + box[:, None, :]
    targets[:, :, 2] += body_height
    ik = wb.body_ik(base, targets, strict=False)
    if not bool(np.all(ik.reached)):
        return -1.0
    q = np.asarray(ik.q)
    free = np.minimum(q - wb.lower, wb.upper - q)[:, finite] / span[finite]
    return float(free.min()) if np.all(np.isfinite(free)) else -1.0


def roomiest_stance(wb: Any) -> tuple[float, float] | None:
    """``(body_height, reach)`` [m] keeping the most joint range, or ``None`` to keep the default.

    ``None`` when the robot's geometric default already keeps :data:`MIN_ROOM` of every
    joint's range over the default step box, or when no grid stance does better than it.
    The grid: reaches 0.2–0.9 and depths 0.1–0.85 of the legs' mean span, 12 × 12, within
    0.92 of the span from the mount; ties go to the stance nearest the default.
    """
    here = room(wb, wb.body_height)
    if here >= MIN_ROOM:
        return None
    span = wb.leg_span
    mount_z = float(np.min(wb.mounts[:, 2, 3]))
    best_score, best_dist, choice = here, math.inf, None
    for r in np.linspace(0.2, 0.9, 12) * span:
        for d in np.linspace(0.1, 0.85, 12) * span:
            if math.hypot(r, d) > 0.92 * span:
                continue
            height = float(d - mount_z)
            score = room(wb, height, r)
            dist = math.hypot(r - wb.foot_reach, height - wb.body_height)
            if score > best_score or (score == best_score and choice and dist < best_dist):
                best_score, best_dist, choice = score, dist, (height, float(r))
    return choice
