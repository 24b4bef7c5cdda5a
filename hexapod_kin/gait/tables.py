"""Gait phase tables: which legs swing when (per-leg phase offset) and the duty factor.

A leg's phase is ``φ(t) = t / T + offset`` (in cycles, modulo 1); it is in stance for
``φ < β`` (the duty factor) and in swing for ``β ≤ φ < 1``, so it lifts off at
``t = (k + β − offset)·T`` and touches down ``(1 − β)·T`` later. Leg order is the robot's
(``hexapod``: leg1 front-left, leg2 middle-left, leg3 rear-left, leg4 rear-right, leg5
middle-right, leg6 front-right).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..exceptions import ParameterError, choices

__all__ = ["PATTERNS", "PhaseTable", "phase_table"]


@dataclass(frozen=True)
class PhaseTable:
    """A periodic gait: per-leg phase offsets and the duty factor.

    Attributes:
        name: Pattern name.
        offsets: Phase offset of each leg in cycles, in [0, 1).
        duty_factor: Fraction β of the cycle each leg spends in stance, in (0, 1).

    """

    name: str
    offsets: tuple[float, ...]
    duty_factor: float

    def __post_init__(self) -> None:
        offs = tuple(float(o) for o in self.offsets)
        if not offs or not all(math.isfinite(o) and 0.0 <= o < 1.0 for o in offs):
            raise ParameterError(
                f"offsets={self.offsets!r}: one phase offset per leg in [0, 1) cycles",
                parameter="offsets",
                value=list(self.offsets),
                allowed="values in [0, 1)",
            )
        object.__setattr__(self, "offsets", offs)
        beta = float(self.duty_factor)
        if not (math.isfinite(beta) and 0.0 < beta < 1.0):
            raise ParameterError(
                f"duty_factor={self.duty_factor!r} is not allowed; 0 < duty_factor < 1",
                parameter="duty_factor",
                value=self.duty_factor,
                allowed="(0, 1)",
            )
        object.__setattr__(self, "duty_factor", beta)

    @property
    def n_legs(self) -> int:
        """Number of legs."""
        return len(self.offsets)

    def with_duty_factor(self, duty_factor: float | None) -> PhaseTable:
        """The same offsets with another duty factor (``None``: unchanged)."""
        if duty_factor is None:
            return self
        return PhaseTable(self.name, self.offsets, duty_factor)

    def phase(self, t: Any, period: float) -> np.ndarray:
        """Phases (N, L) in cycles in [0, 1) at times ``t`` [s] for cycle ``period`` [s]."""
        tt = np.asarray(t, dtype=float).reshape(-1, 1)
        return np.asarray(np.remainder(tt / period + np.asarray(self.offsets)[None, :], 1.0))

    def stance(self, t: Any, period: float) -> np.ndarray:
        """(N, L) True where the leg is in stance."""
        return np.asarray(self.phase(t, period) < self.duty_factor)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: name, offsets [cycles], duty_factor."""
        return {"name": self.name, "offsets": list(self.offsets), "duty_factor": self.duty_factor}


def _snap(x: float) -> float:
    """``x`` modulo 1, with round-off next to a whole cycle snapped to 0."""
    v = float(np.remainder(x, 1.0))
    return 0.0 if v < 1e-12 or v > 1.0 - 1e-12 else v


def _lift_order(order: Sequence[int], beta: float, spacing: float) -> tuple[float, ...]:
    """Offsets so that leg ``order[k]`` lifts off at ``k·spacing`` cycles."""
    offs = [0.0] * len(order)
    for k, leg in enumerate(order):
        offs[leg] = _snap(beta - k * spacing)
    return tuple(offs)


def _tripod() -> PhaseTable:
    # legs 1, 3, 5 lift at t = 0; legs 2, 4, 6 half a cycle later
    return PhaseTable("tripod", (0.5, 0.0, 0.5, 0.0, 0.5, 0.0), 0.5)


def _wave() -> PhaseTable:
    # one leg at a time, rear to front: left side then right side
    beta = 5.0 / 6.0
    return PhaseTable("wave", _lift_order([2, 1, 0, 3, 4, 5], beta, 1.0 / 6.0), beta)


def _ripple() -> PhaseTable:
    # each side rear to front, a third of a cycle apart; the right side half a cycle later
    beta = 2.0 / 3.0
    offs = [0.0] * 6
    for leg, when in ((2, 0.0), (1, 1 / 3), (0, 2 / 3), (3, 0.5), (4, 5 / 6), (5, 1 / 6)):
        offs[leg] = _snap(beta - when)
    return PhaseTable("ripple", tuple(offs), beta)


#: The built-in patterns of the six-legged robot.
PATTERNS: dict[str, PhaseTable] = {p.name: p for p in (_tripod(), _wave(), _ripple())}


def phase_table(pattern: str | PhaseTable, n_legs: int = 6) -> PhaseTable:
    """A built-in pattern by name (``tripod``, ``wave``, ``ripple``) or a user's table.

    Raises:
        ParameterError: Unknown name (the message lists them), or a table whose number of
            offsets is not ``n_legs``.

    """
    if isinstance(pattern, PhaseTable):
        table = pattern
    elif isinstance(pattern, str) and pattern in PATTERNS:
        table = PATTERNS[pattern]
    else:
        raise ParameterError(
            f"pattern={pattern!r} is not allowed; use one of {choices(PATTERNS)} or a PhaseTable",
            parameter="pattern",
            value=repr(pattern),
            allowed=sorted(PATTERNS),
        )
    if table.n_legs != n_legs:
        raise ParameterError(
            f"pattern {table.name!r} has {table.n_legs} offsets; the robot has {n_legs} legs",
            parameter="pattern",
            value=table.n_legs,
            allowed=n_legs,
        )
    return table
