"""Closed-loop walking: a controller for any legged robot of the model, run in MuJoCo.

* :class:`Controller` (:mod:`.controller`): measured state in (IMU, joints, foot contacts,
  a base estimate), joint torques or servo targets out, at a fixed rate; stance forces by a
  convex model-predictive controller (:mod:`.mpc`) or a wrench QP (:mod:`.qp`), both solved
  by proxsuite; Raibert / capture-point foot placement, body posing for servos.
* :class:`Command`, :class:`Timeline` (:mod:`.commands`): velocity, gait and mode over time.
* :class:`StateEstimator` (:mod:`.estimator`): the base position and velocity from the
  IMU and the legs (a contact-aided linear Kalman filter).
* :func:`run` (:mod:`.sim`): the closed loop in MuJoCo with pushes and bumps, and its figures
  (:class:`ControlRun`); :func:`hardware_loop`: the same controller through user callbacks.
* :func:`compare` (:mod:`.compare`): the open-loop replay of a plan beside its closed-loop
  walk, and :func:`comparison_html`, the two side by side.

Needs the optional extras ``export`` (MuJoCo) and ``control`` (proxsuite).
"""

from __future__ import annotations

from .commands import MODES, Command, Timeline, read_timeline, timeline_of
from .compare import Comparison, compare, comparison_html
from .controller import BALANCES, KINDS, Controller, Measurement
from .estimator import StateEstimator
from .sim import ControlRun, Payload, Push, hardware_loop, run

__all__ = [
    "BALANCES",
    "KINDS",
    "MODES",
    "Command",
    "Comparison",
    "ControlRun",
    "Controller",
    "Measurement",
    "Payload",
    "Push",
    "StateEstimator",
    "Timeline",
    "compare",
    "comparison_html",
    "hardware_loop",
    "read_timeline",
    "run",
    "timeline_of",
]
