"""Walks sized by the robot's own limits: the default period, and each pattern's top speed.

At stride ``L`` a straight walk follows, to first order, the same joint path whatever the
period ``T``: joint speeds scale as ``1/T``, accelerations as ``1/T²``. With ``ρ`` the largest
ratio of a joint's speed to its URDF limit (or the square root of its acceleration's to an
acceleration limit), a plan at ``T₀`` fits at ``T = ρ·T₀``: :func:`fit_period` (the default
period, a multiple of :data:`PERIOD_STEP`) and :func:`top_speed` (``v = L / (β · ρ(L) · T₀)``
over the strides the legs can reach).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from ..exceptions import HexapodKinError

__all__ = ["PERIOD_STEP", "STRIDES", "fit_period", "speed_ratio", "top_speed"]

#: Periods chosen from the limits are multiples of this [s].
PERIOD_STEP = 0.05

#: The strides tried by :func:`top_speed`, as multiples of the default stride.
STRIDES = (0.25, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0)


def speed_ratio(run: Any) -> float:
    """The largest joint speed over its limit, or √(acceleration over its limit), of a run."""
    ratio = 0.0
    for value, limit, power in (
        (run.max_joint_speed, run.velocity_limit, 1.0),
        (run.max_joint_accel, run.accel_limit, 0.5),
    ):
        lim = np.broadcast_to(np.asarray(limit, dtype=float), np.shape(value))
        finite = np.isfinite(lim) & (lim > 0)
        if np.asarray(limit).size and finite.any():
            ratio = max(ratio, float(np.max(np.asarray(value)[finite] / lim[finite])) ** power)
    return ratio


def fit_period(plan: Callable[[float], Any], period: float = 1.0, passes: int = 4) -> float:
    """``period`` [s] if a plan at it keeps the joints within their limits, else a longer one.

    Args:
        plan: ``plan(T)`` → a :class:`~.run.GaitRun` of one cycle at period ``T``
            (``strict=False``).
        period: The period tried first [s].
        passes: Plans tried at most after the first.

    Returns:
        ``period``, or the multiple of :data:`PERIOD_STEP` at the speed ratio's scale that the
        last plan found within the limits (or the last one tried); ``period`` when a plan
        cannot be made or its feet are out of reach (the walk then reports why).

    """
    T = float(period)
    try:
        first = plan(T)
        if np.any(np.asarray(first.reach_excess) > 0.0):  # feet out of reach: not a plan
            return T
        ratio = speed_ratio(first)
        for _ in range(passes):
            if ratio <= 1.0:
                return T
            T = math.ceil(T * ratio * (1.0 + 1e-6) / PERIOD_STEP) * PERIOD_STEP
            ratio = speed_ratio(plan(T))
    except HexapodKinError:
        return float(period)
    return T


def top_speed(
    plan: Callable[[float, float], Any], stride: float, period: float = 1.0
) -> tuple[float, float, float]:
    """The highest straight speed of a pattern within the legs' reach and the joints' limits.

    Args:
        plan: ``plan(L, T)`` → a :class:`~.run.GaitRun` of one cycle, stride ``L`` [m],
            period ``T`` [s] (``strict=False``).
        stride: The default stride [m] (:data:`STRIDES` are multiples of it).
        period: The period the strides are planned at [s].

    Returns:
        ``(v, L, T)``: the speed [m/s], and the stride [m] and period [s] that give it
        (``(0, 0, inf)`` when no stride can be walked).

    """
    best = (0.0, 0.0, math.inf)
    for k in STRIDES:
        L = k * stride
        try:
            run = plan(L, period)
        except HexapodKinError:
            continue
        if not (np.all(run.ik_ok) and run.min_limit_margin >= 0):
            continue
        T = max(speed_ratio(run), 1e-9) * period
        v = L / (run.table.duty_factor * T)
        if v > best[0]:
            best = (v, L, T)
    return best
