"""Dynamics: forward dynamics (ABA) and integrators, the seed pendulum, leg torques, standing.

:mod:`.forward` (:func:`simulate`), :mod:`.pendulum` (seed 001 §1 against the exact period),
:mod:`.statics` (:func:`leg_torques`, :func:`torques_along`), :mod:`.standing` (:func:`stand`:
contact forces and torques), :mod:`.gait_loads` (:func:`gait_torques`). Every entry point
refuses implausible inertials (:func:`check_inertials`, naming the link).
"""

from __future__ import annotations

from ._common import check_inertials
from .forward import METHODS, PassiveJoints, Simulation, passive_joints, simulate
from .gait_loads import GaitTorques, gait_torques
from .pendulum import (
    PendulumExperiment,
    PendulumRun,
    PhysicalPendulum,
    exact_period,
    hermite_crossings,
    pendulum_experiment,
    pendulum_run,
    physical_pendulum,
)
from .standing import (
    CONTACT_METHODS,
    ContactSolution,
    Stance,
    contact_forces,
    robot_mass_com,
    stance_at,
    stand,
    standing_configuration,
)
from .statics import LegTorques, StepTorques, leg_torques, torques_along

__all__ = ["CONTACT_METHODS", "ContactSolution", "GaitTorques", "LegTorques", "METHODS",
           "PassiveJoints", "PendulumExperiment", "PendulumRun", "PhysicalPendulum", "Simulation",
           "Stance", "StepTorques", "check_inertials", "contact_forces", "exact_period",
           "gait_torques", "hermite_crossings", "leg_torques", "passive_joints",
           "pendulum_experiment", "pendulum_run", "physical_pendulum", "robot_mass_com", "simulate",
           "stance_at", "stand", "standing_configuration", "torques_along"]  # fmt: skip
