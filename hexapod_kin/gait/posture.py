"""The default standing posture of a robot whose geometric default leaves no joint range.

:meth:`~.robot.WholeBody.neutral_feet` puts each foot at a fixed fraction of its leg's span
(0.64 out, 0.32 down); a leg with an upturned tibia or a narrow knee range may reach it only
at the edge of a joint range. The stance is checked over the box a default step sweeps
around each neutral foot; when a joint keeps less than :data:`MIN_ROOM` of its range there,
the stance (one body height, one reach for all legs) keeping the most range is searched on a
grid of reaches and depths. Bounded: a grid stance is tried by IK only when every target is
within each leg's reach (:func:`max_reach`) and every numerical leg reaches its neutral foot
from the seed (one batched solve); with a numerical leg, at most :data:`MAX_TRIES` stances.
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

#: At most this many grid stances are checked by numerical IK (those past the cheap tests, in
#: grid order) when a leg has no closed form; closed-form legs are checked at every one.
MAX_TRIES = 6


def _box(stride: float, lift: float) -> np.ndarray:
    h = stride / 2
    return np.array([[0, 0, 0], [h, 0, 0], [-h, 0, 0], [0, h, 0], [0, -h, 0], [0, 0, lift]])


def max_reach(wb: Any) -> np.ndarray:
    """(L,) an upper bound of the distance from each leg's first joint to its foot [m].

    The leg's span at q = 0 (:attr:`~.robot.WholeBody.leg_span` per leg: the lengths from
    joint to joint to the foot) plus the travel (upper − lower) of its prismatic joints: a
    revolute joint turns about its own origin (the next length is kept), a prismatic one
    lengthens the next by at most its travel (``inf`` when unbounded).
    """
    tr = wb._tree
    out = np.array(wb._span, dtype=float)
    for i, cols in enumerate(wb._leg_cols):
        c = list(cols)
        pr = np.asarray(tr.prismatic[c], dtype=bool)
        if pr.any():
            out[i] += float(np.sum((wb.upper[c] - wb.lower[c])[pr]))
    return out


def _stance_feet(wb: Any, heights: np.ndarray, reaches: np.ndarray) -> np.ndarray:
    """(K, L, 3) body-frame neutral feet of K stances (body heights, reaches) [m]."""
    feet = np.empty((len(heights), wb.n_legs, 3))
    feet[:, :, :2] = wb.mounts[None, :, :2, 3] + reaches[:, None, None] * wb._reach_dir[None]
    feet[:, :, 2] = (wb.foot_radius - heights)[:, None]
    return feet


def _beyond_reach(wb: Any, targets_body: np.ndarray) -> np.ndarray:
    """(..., ) True where a body-frame target (..., L, 3) is out of its leg's reach by geometry."""
    first = np.array([wb._tree.placements[c[0]][:3, 3] for c in wb._leg_cols])
    dist = np.linalg.norm(targets_body - first, axis=-1)
    return np.asarray(np.any(dist > max_reach(wb) * (1 + 1e-9) + 1e-12, axis=-1))


def _centre_reached(wb: Any, heights: np.ndarray, reaches: np.ndarray) -> np.ndarray:
    """(K,) False where a numerically solved leg misses its neutral foot (stance k) from the seed.

    The same first solve :meth:`~.robot.WholeBody.body_ik` runs for the box's centre (its
    first sample), for all K stances in one batch: a miss there makes :func:`room` −1.
    """
    k = len(heights)
    ok = np.ones(k, dtype=bool)
    groups: dict[int, list[int]] = {}
    for leg, closed in enumerate(wb._closed):
        if closed is None:
            groups.setdefault(len(wb._leg_cols[leg]), []).append(leg)
    if not groups or not k:
        return ok
    seed = wb.neutral_q()
    for legs in groups.values():
        g = len(legs)
        tgt = _stance_feet(wb, heights, reaches)[:, legs]
        # every stance's legs in one solve (stance-major, as the targets)
        _q, _res, reached = wb._numeric(legs * k, tgt.reshape(1, k * g, 3), seed)
        ok &= reached.reshape(k, g).all(axis=1)
    return ok


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
    if bool(np.any(_beyond_reach(wb, targets))):  # body frame: z below the body
        return -1.0
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
    0.92 of the span from the mount; ties go to the stance nearest the default. Bounded (see
    the module doc).
    """
    here = room(wb, wb.body_height)
    if here >= MIN_ROOM:
        return None
    span = wb.leg_span
    mount_z = float(np.min(wb.mounts[:, 2, 3]))
    grid = [
        (float(d - mount_z), float(r))
        for r in np.linspace(0.2, 0.9, 12) * span
        for d in np.linspace(0.1, 0.85, 12) * span
        if math.hypot(r, d) <= 0.92 * span
    ]
    if not grid:
        return None
    heights, reaches = np.array(grid).T
    feet = _stance_feet(wb, heights, reaches)
    box = _box(_STRIDE, _LIFT)
    far = _beyond_reach(wb, feet[:, None] + box[None, :, None, :]).any(axis=1)
    live = np.flatnonzero(~far)
    live = live[_centre_reached(wb, heights[live], reaches[live])]
    if any(c is None for c in wb._closed):  # numerical legs: a bounded number of tries
        live = live[:MAX_TRIES]
    best_score, best_dist, choice = here, math.inf, None
    for height, r in (grid[i] for i in live):
        score = room(wb, height, r)
        dist = math.hypot(r - wb.foot_reach, height - wb.body_height)
        if score > best_score or (score == best_score and choice and dist < best_dist):
            best_score, best_dist, choice = score, dist, (height, r)
    return choice
