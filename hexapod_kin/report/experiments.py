"""The report's models and numeric experiments, without sympy (:class:`Experiments`).

:class:`~hexapod_kin.report.checks.Context` adds the derivations and the checks to them; a
build's numeric half (:mod:`._worker`) runs them in a process of its own.
"""

from __future__ import annotations

import math
from functools import cached_property
from typing import Any

__all__ = ["MODELS", "Experiments"]

#: Claim ``model`` → the hexapod_kin preset and its parameters.
MODELS: dict[str, tuple[str, dict[str, float]]] = {
    "leg": ("hexabot_leg", {"alpha2": -math.pi / 2}),
    "leg+": ("hexabot_leg", {"alpha2": math.pi / 2}),
    "scara": ("scara", {}),
    "coxa": ("coxa_tibia_leg", {}),
}


class Experiments:
    """The claims' models and the seeds' experiments, computed once (``quick``: shorter runs)."""

    def __init__(self, quick: bool = False) -> None:
        self.quick = quick
        self.pendulum_duration = 12.0 if quick else 20.0
        self._models: dict[str, Any] = {}

    def chain(self, key: str) -> Any:
        """The preset chain of a claim's ``model``."""
        from .. import robots

        name, params = MODELS[key]
        return robots.get(name, **params)

    def model(self, key: str) -> Any:
        """The loaded (Pinocchio) model of a claim's ``model`` (loaded once)."""
        from .. import load

        if key not in self._models:
            self._models[key] = load(self.chain(key))
        return self._models[key]

    @cached_property
    def step(self) -> Any:
        """The seeds' x-only step (:func:`hexapod_kin.seeds.seed_experiment`)."""
        from ..seeds import seed_experiment

        return seed_experiment(duration=4.0 if self.quick else 10.0)

    @cached_property
    def pendulum(self) -> Any:
        """Seed 001's pendulum, undamped and damped (:func:`pendulum_experiment`)."""
        from ..dynamics import pendulum_experiment

        return pendulum_experiment(duration=self.pendulum_duration)
