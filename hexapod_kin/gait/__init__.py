"""Legged locomotion: foot paths, standing poses, and the whole hexapod walking.

* :mod:`.paths` — one leg's step cycle (:func:`foot_path`, :func:`foot_step`).
* :mod:`.stand` — standing poses and the hexapod's body sway (:func:`demo_trajectory`).
* :mod:`.robot` — the whole robot with a floating base (:func:`whole_body`), body-pose IK.
* :mod:`.tables` — phase tables (tripod, wave, ripple, custom).
* :mod:`.terrain` — the ground as a height function (flat, slope, a step, user callables).
* :mod:`.stability` — support-polygon margin and leg clearance.
* :mod:`.walk` — the walk and its checks (:func:`walk` → :class:`GaitRun`, in :mod:`.run`).
* :mod:`.limits` — the default period from the joints' limits; each pattern's top speed.
* :mod:`.knee` — which way the knees point: the IK branch asked (``knee=``) and reported.
* :mod:`.plots` — gait diagram, margin over time, foot paths from above (matplotlib).
* :mod:`.show` — what a drawing of a walk needs: support polygons, projected CoM, the robot's
  model (the pages are :mod:`hexapod_kin.viewer.walk`).
"""

from __future__ import annotations

from .paths import FootStep, foot_path, foot_step
from .robot import BodyIK, GaitError, WholeBody, as_whole_body, body_pose, whole_body
from .stability import segment_clearance, support_margin
from .stand import (
    StandingPose,
    default_configuration,
    demo_trajectory,
    frame_poses,
    standing_base,
    standing_pose,
)
from .tables import PATTERNS, PhaseTable, phase_table
from .terrain import TERRAINS, Terrain, flat, slope, step_terrain, terrain
from .walk import GaitRun, se2_pose, swing_profile, walk

__all__ = [
    "PATTERNS",
    "TERRAINS",
    "BodyIK",
    "FootStep",
    "GaitError",
    "GaitRun",
    "PhaseTable",
    "StandingPose",
    "Terrain",
    "WholeBody",
    "as_whole_body",
    "body_pose",
    "default_configuration",
    "demo_trajectory",
    "flat",
    "foot_path",
    "foot_step",
    "frame_poses",
    "phase_table",
    "se2_pose",
    "segment_clearance",
    "slope",
    "standing_base",
    "standing_pose",
    "step_terrain",
    "support_margin",
    "swing_profile",
    "terrain",
    "walk",
    "whole_body",
]
