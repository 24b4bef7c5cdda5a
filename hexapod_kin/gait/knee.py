"""Which way a leg's knee points: the branch of its closed-form IK, chosen and reported.

A leg's *knee* is its last joint's origin; its direction is the knee's offset from the line
hip → foot (the hip: the joint before the knee), perpendicular to it, in the body frame,
named by its largest component along the body's axes and the leg's outward horizontal
direction: ``up`` (+z), ``down`` (−z), ``forward`` (+x), ``backward`` (−x), ``out``, ``in``;
``straight`` for a knee on the line. :func:`knee_seed` picks for every closed-form leg the
first sample's branch whose knee points most along the direction asked (among those inside
the joint limits, when any); the walk then continues each leg on its nearest branch.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..exceptions import ParameterError, choices

__all__ = ["KNEES", "knee_directions", "knee_seed"]

#: The directions a knee can be asked to point (see the module docstring).
KNEES = ("up", "down", "forward", "backward", "out", "in")


def _axes(wb: Any) -> np.ndarray:
    """(L, 6, 3) per leg, the unit directions of :data:`KNEES` in the body frame."""
    out = np.zeros((wb.n_legs, 6, 3))
    out[:, 0, 2], out[:, 1, 2], out[:, 2, 0], out[:, 3, 0] = 1.0, -1.0, 1.0, -1.0
    radial = np.array(wb.mounts[:, :2, 3], dtype=float)
    norm = np.hypot(radial[:, 0], radial[:, 1])
    radial = np.where(norm[:, None] > 0, radial / np.maximum(norm, 1e-300)[:, None], [0.0, 1.0])
    out[:, 4, :2], out[:, 5, :2] = radial, -radial
    return out


def _offsets(wb: Any, q: np.ndarray) -> np.ndarray:
    """(N, L, 3) each leg's knee offset from its hip-foot line, body frame, at q (N, nq)."""
    pts = wb.leg_points(q, np.broadcast_to(np.eye(4), (len(q), 4, 4)))  # (N, L, K, 3)
    hips, knees, feet = pts[:, :, max(0, pts.shape[2] - 3)], pts[:, :, -2], pts[:, :, -1]
    line = feet - hips
    u = line / np.maximum(np.linalg.norm(line, axis=-1, keepdims=True), 1e-300)
    rel = knees - hips
    return np.asarray(rel - np.sum(rel * u, axis=-1, keepdims=True) * u)


def knee_directions(wb: Any, q: Any) -> tuple[str, ...]:
    """Per leg, where its knee points at the configuration ``q`` (nq,) (see the module doc)."""
    off = _offsets(wb, np.asarray(q, dtype=float).reshape(1, -1))[0]  # (L, 3)
    score = np.einsum("lkd,ld->lk", _axes(wb), off)
    size = np.linalg.norm(off, axis=-1)
    return tuple(
        "straight" if size[i] <= 1e-9 * max(float(wb.leg_span), 1e-3) else KNEES[int(k)]
        for i, k in enumerate(np.argmax(score, axis=1))
    )


def knee_seed(wb: Any, knee: str, base: np.ndarray, feet: np.ndarray, q: Any = None) -> np.ndarray:
    """Joints (nq,) whose closed-form legs take the branch with the knee most along ``knee``.

    Args:
        wb: The :class:`~.robot.WholeBody`.
        knee: One of :data:`KNEES`.
        base: (4, 4) body pose ``worldMbody`` of the first sample.
        feet: (L, 3) its foot points in the world [m].
        q: (nq,) the joints of the legs solved numerically (default the robot's neutral q).

    Raises:
        ParameterError: ``knee`` is not one of :data:`KNEES`.

    """
    from ..ik import analytic_batch

    if knee not in KNEES:
        raise ParameterError(
            f"knee={knee!r} is not allowed; use one of {choices(KNEES)}",
            parameter="knee",
            value=repr(knee),
            allowed=list(KNEES),
        )
    out = np.array(wb.neutral_q() if q is None else q, dtype=float)
    p_body = (np.asarray(feet, dtype=float) - base[:3, 3]) @ base[:3, :3]  # (L, 3)
    want = _axes(wb)[:, KNEES.index(knee)]
    for leg, closed in enumerate(wb._closed):
        if closed is None:
            continue
        cols = np.array(wb._leg_cols[leg])
        table, T0 = closed
        target = (p_body[leg] - T0[:3, 3]) @ T0[:3, :3]
        batch = analytic_batch(table, target[None])
        cand, valid = np.asarray(batch.q[0]), np.asarray(batch.valid[0], dtype=bool)
        if not valid.any():
            continue
        inside = wb._within_limits(cand[None, None], valid[None, None], cols[None])[0, 0]
        keys = np.flatnonzero(inside)
        qs = np.broadcast_to(out, (len(keys), len(out))).copy()
        qs[:, cols] = cand[keys]
        score = _offsets(wb, qs)[:, leg] @ want[leg]
        out[cols] = cand[keys[int(np.argmax(score))]]
    return out
