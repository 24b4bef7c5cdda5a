"""Dynamics: forward dynamics (ABA) and integrators, the seed pendulum, leg torques, standing.

* :mod:`.forward` — :func:`simulate`: Pinocchio ABA with the URDF's joint damping and (smoothed)
  Coulomb friction, optional springs; RK4 (default) or semi-implicit Euler; energies.
* :mod:`.pendulum` — seed 001 §1: :func:`pendulum_experiment` (undamped, damped, small-amplitude
  decay) measured against the exact period ``4 sqrt(I/(m g l_c)) K(sin(θ0/2))`` and ``b/(2I)``.
* :mod:`.statics` — :func:`leg_torques` (``g(q) + Jᵀ F``, cross-checked by RNEA with the foot
  force as external force), :func:`torques_along` a joint trajectory (the seeds' step:
  :func:`hexapod_kin.seeds.step_torques`).
* :mod:`.standing` — :func:`stand`: the hexapod standing, the stance feet's contact forces
  (minimum-norm or friction-cone) and every joint's torque.
* :mod:`.gait_loads` — :func:`gait_torques`: the same along a gait run (a
  ``hexapod_kin.gait.walk``), sample by sample; peak torque per joint.

Every entry point refuses a model whose moving bodies have implausible inertials
(:func:`check_inertials`, naming the link).
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

__all__ = [
    "CONTACT_METHODS",
    "ContactSolution",
    "GaitTorques",
    "LegTorques",
    "METHODS",
    "PassiveJoints",
    "PendulumExperiment",
    "PendulumRun",
    "PhysicalPendulum",
    "Simulation",
    "Stance",
    "StepTorques",
    "check_inertials",
    "contact_forces",
    "exact_period",
    "gait_torques",
    "hermite_crossings",
    "leg_torques",
    "passive_joints",
    "pendulum_experiment",
    "pendulum_run",
    "physical_pendulum",
    "robot_mass_com",
    "simulate",
    "stance_at",
    "stand",
    "standing_configuration",
    "torques_along",
]
